//! The headless figures of src/report: the software rasteriser against the analytic picture of
//! a sphere (covered fraction π r²/area, centred silhouette, brightest where the normal meets
//! the light), the colour maps' exact stops, signed scalars coloured by side, strips sharing one
//! camera scale, the histogram grid's bars where the data put them, PNG round trip and atomic
//! failure, and figures of the real cortex written to target/ for a person to look at.

use crate::common;

use nalgebra::{Point3, Vector3};
use std::path::PathBuf;
use vesselmsr::mesh::primitives::icosphere;
use vesselmsr::report::colormap::{diverging, sequential, NAN_COLOR};
use vesselmsr::report::histogram::BAR_COLOR;
use vesselmsr::report::*;
use vesselmsr::TriMesh;

const WHITE: [u8; 3] = [255, 255, 255];

/// Options for exact pixel counting: no supersampling (every pixel is surface or background).
fn sharp(width: u32, height: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        margin: 0.1,
        supersample: false,
        ..RenderOptions::default()
    }
}

/// Covered pixels: count and centroid (pixel centres).
fn coverage(image: &RgbImage, background: [u8; 3]) -> (usize, f64, f64) {
    let (mut n, mut sx, mut sy) = (0usize, 0.0, 0.0);
    for y in 0..image.height {
        for x in 0..image.width {
            if image.get(x, y) != Some(background) {
                n += 1;
                sx += x as f64 + 0.5;
                sy += y as f64 + 0.5;
            }
        }
    }
    (n, sx / n.max(1) as f64, sy / n.max(1) as f64)
}

fn luminance(c: [u8; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// Folder under target/ for the figures a person looks at.
fn figure_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report_figures");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn sphere_covers_pi_r_squared_and_is_centred() {
    let center = Point3::new(3.0, -2.0, 7.0);
    let sphere = icosphere(5, 2.5, center);
    for (w, h) in [(400u32, 300u32), (300, 400)] {
        let opts = sharp(w, h);
        let image = render_mesh(&sphere, None, &opts).unwrap();
        assert_eq!((image.width, image.height), (w, h));
        // The diameter fills the shorter side less the two margins.
        let radius_px = 0.5 * w.min(h) as f64 * (1.0 - 2.0 * opts.margin);
        let expected = std::f64::consts::PI * radius_px * radius_px;
        let (n, cx, cy) = coverage(&image, opts.background);
        let rel = (n as f64 - expected) / expected;
        assert!(
            rel.abs() < 0.02,
            "{w}×{h}: covered {n} px, π r² = {expected:.0} ({rel:+.4})"
        );
        assert!((cx - w as f64 / 2.0).abs() < 0.5, "centroid x {cx} in {w}");
        assert!((cy - h as f64 / 2.0).abs() < 0.5, "centroid y {cy} in {h}");
        // The corners are background, the centre is surface.
        assert_eq!(image.get(0, 0), Some(opts.background));
        assert_eq!(image.get(w - 1, h - 1), Some(opts.background));
        assert_ne!(image.get(w / 2, h / 2), Some(opts.background));
    }
}

#[test]
fn shading_is_brightest_where_the_normal_meets_the_light() {
    let sphere = icosphere(5, 1.0, Point3::origin());
    let opts = sharp(301, 301);
    let image = render_mesh(&sphere, None, &opts).unwrap();
    let r = 0.5 * 301.0 * (1.0 - 2.0 * opts.margin);
    let l = opts.light.normalize();
    // On a sphere seen orthographically the normal at screen offset (dx, −dy)/r is (dx, dy, ·)/r,
    // so the lit pole is at offset (l.x, −l.y)·r from the centre.
    let (mut best, mut at) = (-1.0, (0u32, 0u32));
    for y in 0..301 {
        for x in 0..301 {
            let lum = luminance(image.get(x, y).unwrap());
            if image.get(x, y) != Some(opts.background) && lum > best {
                best = lum;
                at = (x, y);
            }
        }
    }
    let expect = (150.5 + l.x * r, 150.5 - l.y * r);
    let dist =
        ((at.0 as f64 + 0.5 - expect.0).powi(2) + (at.1 as f64 + 0.5 - expect.1).powi(2)).sqrt();
    assert!(
        dist < 0.08 * r,
        "brightest pixel {at:?}, light pole at {expect:?}"
    );
    // Full light there: the surface colour itself (ambient + diffuse = 1).
    assert!(
        (best - luminance(opts.surface_color)).abs() < 2.0,
        "peak luminance {best}"
    );
    // Everywhere inside the disc: ambient + (1 − ambient)·max(0, n·l) times the surface colour,
    // with n the sphere's normal under the pixel centre.
    let base = luminance(opts.surface_color);
    let mut worst: f64 = 0.0;
    let (mut brightest_away, mut darkest_facing) = (0.0f64, 255.0f64);
    for y in (0..301).step_by(3) {
        for x in (0..301).step_by(3) {
            let (u, v) = ((x as f64 + 0.5 - 150.5) / r, (150.5 - y as f64 - 0.5) / r);
            if u * u + v * v > 0.9 {
                continue;
            }
            let n = Vector3::new(u, v, (1.0 - u * u - v * v).sqrt());
            let lum = luminance(image.get(x, y).unwrap());
            let expected = base * (opts.ambient + (1.0 - opts.ambient) * n.dot(&l).max(0.0));
            worst = worst.max((lum - expected).abs());
            if n.dot(&l) > 0.9 {
                darkest_facing = darkest_facing.min(lum);
            } else if n.dot(&l) < 0.3 {
                brightest_away = brightest_away.max(lum);
            }
        }
    }
    assert!(
        worst < 3.0,
        "shading differs from Lambert + ambient by {worst}"
    );
    assert!(darkest_facing > brightest_away + 50.0);
}

#[test]
fn two_sided_lighting_shows_an_inward_facing_sphere_the_same() {
    let sphere = icosphere(4, 1.0, Point3::origin());
    let mut inward = sphere.clone();
    inward.flip_faces();
    let opts = sharp(160, 160);
    let a = render_mesh(&sphere, None, &opts).unwrap();
    let b = render_mesh(&inward, None, &opts).unwrap();
    let max_diff = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] as i32 - q[k] as i32).abs()))
        .max()
        .unwrap();
    assert!(
        max_diff <= 1,
        "flipped orientation changes pixels by {max_diff}"
    );
}

#[test]
fn colour_maps_have_exact_stops_and_clamp() {
    assert_eq!(diverging(-1.0), [33, 102, 172]);
    assert_eq!(diverging(0.0), [247, 247, 247]);
    assert_eq!(diverging(1.0), [178, 24, 43]);
    assert_eq!(diverging(-7.0), diverging(-1.0));
    assert_eq!(diverging(7.0), diverging(1.0));
    assert_eq!(diverging(f64::NAN), NAN_COLOR);
    assert_eq!(sequential(0.0), [68, 1, 84]);
    assert_eq!(sequential(0.5), [33, 145, 140]);
    assert_eq!(sequential(1.0), [253, 231, 37]);
    assert_eq!(sequential(-3.0), sequential(0.0));
    assert_eq!(sequential(3.0), sequential(1.0));
    // Between two stops: the linear mix, rounded.
    assert_eq!(diverging(-0.75), [90, 150, 197]);
    // On a range: lo → first stop, middle → midpoint, hi → last stop.
    let m = ColorMap::Diverging;
    assert_eq!(m.color(-0.2, (-0.2, 0.2)), diverging(-1.0));
    assert_eq!(m.color(0.0, (-0.2, 0.2)), diverging(0.0));
    assert_eq!(m.color(0.5, (-0.2, 0.2)), diverging(1.0));
    assert_eq!(
        ColorMap::Sequential.color(15.0, (10.0, 20.0)),
        sequential(0.5)
    );
    // Robust ranges ignore a few outliers and NaN.
    let mut v: Vec<f64> = (0..1000).map(|i| -1.0 + 2.0 * i as f64 / 999.0).collect();
    v.extend([100.0, -250.0, f64::NAN, f64::INFINITY]);
    let (lo, hi) = m.auto_range(&v);
    assert_eq!(lo, -hi);
    assert!((hi - 0.99).abs() < 0.01, "diverging range {hi}");
    let (lo, hi) = ColorMap::Sequential.auto_range(&v);
    assert!(
        (lo + 0.98).abs() < 0.01 && (hi - 0.98).abs() < 0.01,
        "{lo} {hi}"
    );
    // A constant field does not divide by zero.
    assert_eq!(m.auto_range(&[0.0; 10]), (-1.0, 1.0));
}

#[test]
fn signed_scalar_is_red_on_one_side_and_blue_on_the_other() {
    let sphere = icosphere(4, 1.0, Point3::origin());
    let s: Vec<f64> = sphere
        .vertices
        .iter()
        .map(|p| if p.x > 0.0 { 1.0 } else { -1.0 })
        .collect();
    let opts = RenderOptions {
        light: Vector3::new(0.0, 0.0, 1.0),
        ..sharp(200, 200)
    };
    let image = render_mesh(&sphere, Some(&s), &opts).unwrap();
    // Looking along −y with z up, +x is on the left of the picture.
    let left = image.get(60, 100).unwrap();
    let right = image.get(140, 100).unwrap();
    assert!(
        left[0] as i32 > left[2] as i32 + 80,
        "left should be red: {left:?}"
    );
    assert!(
        right[2] as i32 > right[0] as i32 + 80,
        "right should be blue: {right:?}"
    );
    // The map's ends, dimmed only by the light's cosine (here the light is the view direction).
    let red = diverging(1.0);
    let ratio = left[0] as f64 / red[0] as f64;
    assert!(ratio > 0.85 && ratio <= 1.0, "{left:?} vs {red:?}");
    // The explicit range is used: ±2 halves the saturation towards white.
    let opts2 = RenderOptions {
        range: Some((-2.0, 2.0)),
        ..opts.clone()
    };
    let image2 = render_mesh(&sphere, Some(&s), &opts2).unwrap();
    let pale = image2.get(100 - 5, 100).unwrap();
    assert!(
        pale[1] > left[1] + 40,
        "±2 range should be paler: {pale:?} vs {left:?}"
    );
    // The wrong number of values is an error, not a panic.
    assert!(render_mesh(&sphere, Some(&s[1..]), &opts).is_err());
}

#[test]
fn strip_panels_share_one_scale() {
    let small = icosphere(5, 1.0, Point3::new(10.0, 0.0, 0.0));
    let big = icosphere(5, 2.0, Point3::new(-4.0, 1.0, 3.0));
    let opts = StripOptions {
        panel: sharp(240, 240),
        gap: 10,
        title_height: 0,
        colorbar: None,
    };
    let panels = [
        Panel {
            mesh: &small,
            scalars: None,
            title: "",
        },
        Panel {
            mesh: &big,
            scalars: None,
            title: "",
        },
    ];
    let strip = render_strip(&panels, &opts).unwrap();
    assert_eq!((strip.width, strip.height), (490, 240));
    let count = |x0: u32, x1: u32| {
        (0..strip.height)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| strip.get(x, y) != Some(WHITE))
            .count() as f64
    };
    let (a, b) = (count(0, 240), count(250, 490));
    assert!((b / a - 4.0).abs() < 0.08, "area ratio {}", b / a);
    println!(
        "strip: spheres r = 2 / r = 1 silhouette area ratio {:.4}",
        b / a
    );
    // The big sphere fills its panel as it would alone; gap columns stay blank.
    let alone = render_mesh(&big, None, &opts.panel).unwrap();
    assert!((coverage(&alone, WHITE).0 as f64 - b).abs() < 0.01 * b);
    assert_eq!(count(240, 250), 0.0);
    // Titles and a colour bar add their bands and ink.
    let s: Vec<f64> = small.vertices.iter().map(|p| p.z).collect();
    let titled = render_strip(
        &[
            Panel {
                mesh: &small,
                scalars: Some(&s),
                title: "S_0",
            },
            panels[1],
        ],
        &StripOptions {
            title_height: 30,
            colorbar: Some("z".into()),
            ..opts.clone()
        },
    )
    .unwrap();
    assert!(titled.height > 270);
    let title_ink = (0..30)
        .flat_map(|y| (0..240).map(move |x| (x, y)))
        .filter(|&(x, y)| luminance(titled.get(x, y).unwrap()) < 100.0)
        .count();
    assert!(title_ink > 20, "title band has {title_ink} dark pixels");
    // The colour bar runs from the map's blue end (left) to its red end (right) on one row.
    let near = |p: [u8; 3], q: [u8; 3]| (0..3).all(|k| (p[k] as i32 - q[k] as i32).abs() <= 6);
    let bar_row = (270..titled.height).find(|&y| {
        let colourful: Vec<(u32, [u8; 3])> = (0..titled.width)
            .map(|x| (x, titled.get(x, y).unwrap()))
            .filter(|(_, p)| p.iter().max().unwrap() - p.iter().min().unwrap() > 30)
            .collect();
        match (colourful.first(), colourful.last()) {
            (Some(&(x0, first)), Some(&(x1, last))) => {
                near(first, diverging(-1.0)) && near(last, diverging(1.0)) && x1 - x0 > 200
            }
            _ => false,
        }
    });
    assert!(bar_row.is_some(), "no colour bar going from blue to red");
}

#[test]
fn empty_or_broken_meshes_render_blank() {
    let opts = sharp(50, 40);
    let empty = TriMesh::new(vec![], vec![]);
    let image = render_mesh(&empty, None, &opts).unwrap();
    assert_eq!(image.count_not(opts.background), 0);
    let bad = TriMesh::new(
        vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(f64::NAN, 0.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ],
        vec![[0, 1, 2], [0, 2, 9]],
    );
    let image = render_mesh(&bad, None, &opts).unwrap();
    assert_eq!(image.count_not(opts.background), 0);
    // A camera whose up is the view direction still gives a picture.
    let sphere = icosphere(3, 1.0, Point3::origin());
    let odd = RenderOptions {
        camera: Camera {
            view: Vector3::new(0.0, 0.0, -2.0),
            up: Vector3::new(0.0, 0.0, 5.0),
        },
        ..opts
    };
    assert!(render_mesh(&sphere, None, &odd).unwrap().count_not(WHITE) > 500);
}

#[test]
fn histogram_tallest_bar_is_where_the_values_are() {
    let h = 0.5; // world units per voxel
                 // Level 1: a spike at +0.3 h over a uniform spread on [−h, h]; level 2: spike at −0.55 h.
    let uniform: Vec<f64> = (0..420)
        .map(|i| h * (-1.0 + (i as f64 + 0.5) / 210.0))
        .collect();
    let mut l1 = uniform.clone();
    l1.extend(std::iter::repeat_n(0.3 * h, 300));
    let mut l2 = uniform.clone();
    l2.extend(std::iter::repeat_n(-0.55 * h, 150));
    l2.push(5.0 * h); // beyond the axis
    let opts = HistogramOptions {
        unit: h,
        half_range: Some(1.0),
        bins: 21,
        columns: 2,
        ..HistogramOptions::default()
    };
    let fig = histogram_grid(&[("level 1".into(), l1), ("level 2".into(), l2)], &opts).unwrap();
    assert_eq!(fig.panels.len(), 2);
    assert_eq!((fig.image.width, fig.image.height), (640, 280));
    for (panel, spike) in fig.panels.iter().zip([0.3, -0.55]) {
        let hist = &panel.histogram;
        let expected_bin = ((spike + 1.0) / 2.0 * 21.0) as usize;
        assert_eq!(hist.tallest(), Some(expected_bin), "{}", panel.label);
        // Every uniform value is counted: 20 per bin (420 / 21), the spike on top.
        assert_eq!(
            hist.counts.iter().sum::<u64>() as usize,
            420 + if spike > 0.0 { 300 } else { 150 }
        );
        // In the picture: the column with the most bar pixels is the spike's bin.
        let (x0, x1) = panel.x;
        let (y0, y1) = panel.y;
        let (mut best, mut best_x) = (0, 0);
        for x in x0..x1 {
            let n = (y0..y1)
                .filter(|&y| fig.image.get(x as u32, y as u32) == Some(BAR_COLOR))
                .count();
            if n > best {
                best = n;
                best_x = x;
            }
        }
        let value = hist.lo + (best_x as f64 + 0.5 - x0 as f64) / (x1 - x0) as f64 * 2.0;
        assert!(
            (value - hist.bin_center(expected_bin)).abs() <= 0.5 * hist.bin_width() + 0.02,
            "{}: tallest bar drawn at {value}, spike bin centre {}",
            panel.label,
            hist.bin_center(expected_bin)
        );
        // The notes in the top-right corner (3 or 4 lines of 16 px) stay clear of the bars.
        let lines = 3 + (panel.histogram.above + panel.histogram.below > 0) as i32;
        let bar_top = (y0..y1)
            .find(|&y| (x0..x1).any(|x| fig.image.get(x as u32, y as u32) == Some(BAR_COLOR)))
            .unwrap();
        assert!(
            bar_top >= y0 + 4 + 16 * lines,
            "bars reach row {bar_top}, notes end at {}",
            y0 + 4 + 16 * lines
        );
        // Its height is the count on the shared axis.
        let want = hist.counts[expected_bin] as f64 / panel.count_max * (y1 - y0) as f64;
        assert!(
            (best as f64 - want).abs() <= 2.0,
            "bar {best} px, expected {want:.1}"
        );
    }
    assert_eq!(fig.panels[1].histogram.above, 1);
    // Text was drawn (caption, ticks, labels): dark pixels outside the plotting areas.
    let ink = fig
        .image
        .pixels
        .iter()
        .filter(|p| luminance(**p) < 80.0)
        .count();
    assert!(ink > 500, "only {ink} dark pixels of text and axes");
    // No level, or a meaningless unit: an error.
    assert!(histogram_grid(&[], &opts).is_err());
    let zero_unit = HistogramOptions { unit: 0.0, ..opts };
    assert!(histogram_grid(&[("a".into(), vec![1.0])], &zero_unit).is_err());
}

#[test]
fn histogram_counts_edges_and_outliers() {
    let h = histogram(
        &[-1.0, -0.5, 0.0, 0.49, 1.0, 2.0, -3.0, f64::NAN],
        -1.0,
        1.0,
        4,
    );
    assert_eq!(h.counts, vec![1, 1, 2, 1]);
    assert_eq!((h.below, h.above, h.not_finite), (1, 1, 1));
    assert_eq!(h.bin_width(), 0.5);
    assert_eq!(h.bin_center(0), -0.75);
    let empty = histogram(&[], 0.0, 0.0, 0);
    assert_eq!(empty.counts.len(), 1);
    assert_eq!(empty.tallest(), None);
}

#[test]
fn png_round_trip_and_atomic_failure() {
    let dir = tempfile::tempdir().unwrap();
    let mut image = RgbImage::new(7, 5, [10, 20, 30]);
    image.set(0, 0, [255, 0, 0]);
    image.set(6, 4, [0, 255, 1]);
    image.set(3, 2, [1, 2, 3]);
    let path = dir.path().join("a.png");
    write_png(&path, &image).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (7, 5));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    assert_eq!(&buf[..info.buffer_size()], image.as_bytes());
    assert_eq!(&buf[0..3], &[255, 0, 0]);
    assert_eq!(&buf[(4 * 7 + 6) * 3..(4 * 7 + 6) * 3 + 3], &[0, 255, 1]);

    // Into a folder that does not exist: an error, and nothing is created.
    let missing = dir.path().join("no_such_folder").join("b.png");
    assert!(write_png(&missing, &image).is_err());
    assert!(!missing.exists() && !missing.parent().unwrap().exists());
    // An empty image or one whose pixel count disagrees: an error, no file.
    let empty = dir.path().join("empty.png");
    assert!(write_png(&empty, &RgbImage::new(0, 3, WHITE)).is_err());
    let mut broken = image.clone();
    broken.pixels.pop();
    assert!(write_png(&empty, &broken).is_err());
    assert!(!empty.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "only a.png is left"
    );
}

#[test]
fn cortex_figures_are_lit_and_readable() {
    let Some(real) = common::real_dir() else {
        return;
    };
    let mesh = vesselmsr::io::read_mesh(&real.join("cortex_rh_pial_fsaverage5.stl")).unwrap();
    let z: Vec<f64> = mesh.vertices.iter().map(|p| p.z).collect();
    let zmid = 0.5
        * (z.iter().cloned().fold(f64::INFINITY, f64::min)
            + z.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
    let signed: Vec<f64> = z.iter().map(|v| v - zmid).collect();
    let camera = Camera::along_shortest_axis(&mesh);
    // The cortex is thinnest along x: a lateral view, anterior (+y) to the right.
    assert_eq!(camera.view, Vector3::new(-1.0, 0.0, 0.0));
    let opts = RenderOptions {
        width: 640,
        height: 480,
        camera,
        ..RenderOptions::default()
    };
    let image = render_mesh(&mesh, Some(&signed), &opts).unwrap();
    let dir = figure_dir();
    write_png(&dir.join("cortex_z.png"), &image).unwrap();
    let (n, cx, cy) = coverage(&image, opts.background);
    let frac = n as f64 / (640.0 * 480.0);
    assert!(
        frac > 0.35 && frac < 0.85,
        "cortex covers {frac:.3} of the image"
    );
    assert!(
        (cx - 320.0).abs() < 40.0 && (cy - 240.0).abs() < 40.0,
        "centroid {cx} {cy}"
    );
    // Colour runs from blue (bottom) to red (top); shading gives many distinct tones.
    let top = (0..480)
        .find(|&y| (0..640).any(|x| image.get(x, y) != Some(WHITE)))
        .unwrap();
    let bottom = (0..480)
        .rev()
        .find(|&y| (0..640).any(|x| image.get(x, y) != Some(WHITE)))
        .unwrap();
    let row_mean = |y: u32| {
        let px: Vec<[u8; 3]> = (0..640)
            .filter_map(|x| image.get(x, y))
            .filter(|&p| p != WHITE)
            .collect();
        let r = px.iter().map(|p| p[0] as f64).sum::<f64>() / px.len() as f64;
        let b = px.iter().map(|p| p[2] as f64).sum::<f64>() / px.len() as f64;
        (r, b)
    };
    let (rt, bt) = row_mean(top + 8);
    let (rb, bb) = row_mean(bottom - 8);
    assert!(
        rt > bt + 40.0 && bb > rb + 40.0,
        "top {rt:.0}/{bt:.0}, bottom {rb:.0}/{bb:.0}"
    );
    let mut tones: Vec<[u8; 3]> = image.pixels.clone();
    tones.sort();
    tones.dedup();
    assert!(tones.len() > 2000, "only {} distinct colours", tones.len());
    println!(
        "cortex 640×480: covers {frac:.3}, centroid ({cx:.1}, {cy:.1}), {} colours, \
         top row red/blue {rt:.0}/{bt:.0}, bottom {rb:.0}/{bb:.0}",
        tones.len()
    );

    // A strip: the cortex and a half-size copy share the scale; a plain one for the shape.
    let half = TriMesh::new(
        mesh.vertices
            .iter()
            .map(|p| Point3::from(p.coords * 0.5))
            .collect(),
        mesh.faces.clone(),
    );
    let strip_opts = StripOptions {
        panel: RenderOptions {
            width: 360,
            height: 280,
            camera,
            ..RenderOptions::default()
        },
        colorbar: Some("z − z_mid (mm)".into()),
        ..StripOptions::default()
    };
    let half_signed: Vec<f64> = signed.iter().map(|v| 0.5 * v).collect();
    let strip = render_strip(
        &[
            Panel {
                mesh: &mesh,
                scalars: None,
                title: "S_0 (plain)",
            },
            Panel {
                mesh: &mesh,
                scalars: Some(&signed),
                title: "S_0",
            },
            Panel {
                mesh: &half,
                scalars: Some(&half_signed),
                title: "S_0 × 0.5",
            },
        ],
        &strip_opts,
    )
    .unwrap();
    write_png(&dir.join("cortex_strip.png"), &strip).unwrap();
    let t = strip_opts.title_height;
    let panel_cover = |i: u32| {
        let x0 = i * (360 + strip_opts.gap);
        (t..t + 280)
            .flat_map(|y| (x0..x0 + 360).map(move |x| (x, y)))
            .filter(|&(x, y)| strip.get(x, y) != Some(WHITE))
            .count() as f64
    };
    let ratio = panel_cover(1) / panel_cover(2);
    assert!(
        (ratio - 4.0).abs() < 0.1,
        "full / half-size cortex area ratio {ratio}"
    );
    println!("strip: full / half-size cortex silhouette area ratio {ratio:.3}");

    // Histograms of a synthetic "detail" per level, narrowing level by level.
    let levels: Vec<(String, Vec<f64>)> = (1..=5)
        .map(|i| {
            (
                format!("level {i}"),
                signed.iter().map(|v| v / (i * i) as f64).collect(),
            )
        })
        .collect();
    let fig = histogram_grid(
        &levels,
        &HistogramOptions {
            unit: 3.1,
            ..HistogramOptions::default()
        },
    )
    .unwrap();
    write_png(&dir.join("cortex_histograms.png"), &fig.image).unwrap();
    println!("figures written to {}", dir.display());
}
