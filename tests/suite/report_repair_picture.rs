//! The before/after picture of a repair (src/report/repair_picture.rs): a tube with a dent
//! (input) and the intact tube (repaired). The camera looks at the dent face on, perpendicular
//! to the tube, from the dent's side (also for a tube lying obliquely); the picture has its
//! size, two rows of three views with grey surface in every panel; red only where the repair
//! added (the filled dent: centred on the ball, smaller than D's disc; none at all when the
//! repaired mesh is the input); the figures and a scale bar in the caption; bad paths and sizes
//! fail and leave no file. Pictures of the phantoms of src/inpaint/phantom.rs (truth standing
//! in for the repair) and of the real ICA aneurysm (a ball on its widest point, the mesh as its
//! own repair: no red) are written to target/tmp/report_repair_picture/ for a person to look
//! at.

use crate::common;

use nalgebra::{Point3, Rotation3, Vector3};
use std::path::{Path, PathBuf};
use vesselmsr::inpaint::phantom::{make_phantom, PhantomKind, PhantomOptions};
use vesselmsr::inpaint::region::Ball;
use vesselmsr::mesh::primitives::open_tube;
use vesselmsr::report::*;
use vesselmsr::TriMesh;

const WHITE: [u8; 3] = [255, 255, 255];

/// Folder under target/ for the pictures a person looks at.
fn figure_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report_repair_picture");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A tube of radius 1 along z from 0 to 8 (64 × 81 vertices), the ball D of radius 0.8 centred
/// on its wall at (1, 0, 4), and the tube with a dent: the vertices in D pulled towards the axis
/// by up to 0.4 (smoothly to 0 at D's border). Returns (dented, intact, ball).
fn dented_tube() -> (TriMesh, TriMesh, Ball) {
    let intact = open_tube(1.0, 8.0, 64, 81);
    let ball = Ball {
        center: Point3::new(1.0, 0.0, 4.0),
        radius: 0.8,
    };
    let mut dented = intact.clone();
    for p in &mut dented.vertices {
        let t: f64 = (*p - ball.center).norm() / ball.radius;
        if t < 1.0 {
            let s = 1.0 - 0.4 * (1.0 - t * t).powi(2);
            p.x *= s;
            p.y *= s;
        }
    }
    (dented, intact, ball)
}

fn decode(path: &Path) -> RgbImage {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let pixels = buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    RgbImage {
        width: info.width,
        height: info.height,
        pixels,
    }
}

/// Red: at least half covered by the red of D (grey mixed half and half with it has r ≈ 1.75 g).
fn is_red(c: [u8; 3]) -> bool {
    c[0] as f64 > 1.8 * c[1] as f64 && c[0] as f64 > 1.8 * c[2] as f64 && c[0] > 40
}

/// Shaded grey: surface, not background, channels equal within 3.
fn is_grey(c: [u8; 3]) -> bool {
    c != WHITE && c[0].abs_diff(c[1]) <= 3 && c[1].abs_diff(c[2]) <= 3 && c[0] < 250
}

/// The pixels of one panel, as (x, y, colour) with x, y relative to the panel.
fn panel_pixels(image: &RgbImage, rect: [u32; 4]) -> Vec<(u32, u32, [u8; 3])> {
    let [x0, y0, w, h] = rect;
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            out.push((x, y, image.get(x0 + x, y0 + y).unwrap()));
        }
    }
    out
}

#[test]
fn view_is_perpendicular_to_the_tube_from_the_side_of_d() {
    let (dented, intact, ball) = dented_tube();
    // The dented tube's box holds one more ring at z = 6 than at z = 2, which tilts its
    // principal axes a little (the intact tube's stay exact by symmetry).
    for (mesh, tol) in [(&intact, 1e-9), (&dented, 1e-3)] {
        let v = repair_view(mesh, &[ball]);
        assert!(
            (v.view - Vector3::new(-1.0, 0.0, 0.0)).norm() < tol,
            "{v:?}"
        );
        assert!(
            v.right.z.abs() > 1.0 - tol,
            "tube axis not horizontal: {v:?}"
        );
        assert!(v.up.dot(&v.view).abs() < 1e-12 && (v.view.cross(&v.up) - v.right).norm() < 1e-12);
        // The context box is the ball's box grown ×2.5.
        assert!(
            (v.min - Point3::new(-1.0, -2.0, 2.0)).norm() < 1e-12,
            "{v:?}"
        );
        assert!((v.max - Point3::new(3.0, 2.0, 6.0)).norm() < 1e-12, "{v:?}");
    }
    // The same tube lying obliquely, D on another side: the view stays perpendicular to the
    // axis and looks at D's side of the wall.
    let rot = Rotation3::from_euler_angles(0.7, -0.4, 1.9);
    let moved = |m: &TriMesh| {
        let mut m = m.clone();
        for p in &mut m.vertices {
            *p = rot * *p;
        }
        m
    };
    let turned = Ball {
        center: rot * ball.center,
        radius: ball.radius,
    };
    let v = repair_view(&moved(&intact), &[turned]);
    let axis = rot * Vector3::z();
    let outward = rot * Vector3::x();
    println!(
        "oblique: view·axis {:.3e}, |view + outward| {:.3e}",
        v.view.dot(&axis),
        (v.view + outward).norm()
    );
    assert!(v.view.dot(&axis).abs() < 1e-9, "{v:?}");
    // The axis point comes from the triangles' normal lines, which pass the axis at a sixth of
    // an edge (the triangles' centroids are off their quads' middles); the box cuts the rings
    // unevenly here, so that no longer cancels exactly (measured 1.7e-6).
    assert!((v.view + outward).norm() < 1e-3, "{v:?} vs {outward}");
}

/// Red pixels of the panel `rect`.
fn red_in(image: &RgbImage, rect: [u32; 4]) -> Vec<(u32, u32, [u8; 3])> {
    panel_pixels(image, rect)
        .into_iter()
        .filter(|p| is_red(p.2))
        .collect()
}

#[test]
fn picture_paints_only_what_the_repair_added_in_three_views() {
    let (dented, intact, ball) = dented_tube();
    let opts = RepairPictureOptions {
        added_distance: 0.05,
        unit: "mm".into(),
        figures: vec!["input volume 24.1 mm³".into(), "watertight yes".into()],
        ..RepairPictureOptions::default()
    };
    let path = figure_dir().join("dented_tube.png");
    render_repair(&dented, &intact, &[ball], &path, &opts).unwrap();
    let image = decode(&path);
    assert_eq!((image.width, image.height), (1200, 800));
    assert_eq!(
        image,
        repair_picture(&dented, &intact, &[ball], &opts).unwrap()
    );
    let layout = picture_layout(&opts);
    // Lines of 24 px (3% of the height): the views' names over 36 px, the caption 3 lines
    // (2 figures, the scale bar) and a half; panels (1200 − 16) / 3 wide, 8 px apart.
    assert_eq!(layout.line, 24);
    assert_eq!(layout.panels[0][0], [0, 36, 394, 336]);
    assert_eq!(layout.panels[1][2], [804, 380, 394, 336]);
    assert_eq!(layout.caption, [0, 716, 1200, 84]);

    // Every panel shows grey surface; the input row no red but the balls' thin outlines.
    for (r, row) in layout.panels.iter().enumerate() {
        for (c, &rect) in row.iter().enumerate() {
            let grey = panel_pixels(&image, rect)
                .iter()
                .filter(|p| is_grey(p.2))
                .count();
            assert!(grey > 1_000, "row {r} view {c}: grey {grey}");
        }
    }
    // The repaired front view: red where the dent was filled out by more than 0.05 (the
    // intact tube's triangles within 0.05 of the dented one stay grey), centred on the ball.
    let red = red_in(&image, layout.panels[1][0]);
    let outline = red_in(&image, layout.panels[0][0]).len();
    assert!(
        red.len() > 3_000,
        "red pixels in the repaired front view: {}",
        red.len()
    );
    assert!(
        outline < red.len() / 2,
        "input {outline}, repaired {}",
        red.len()
    );
    let [_, _, w, h] = layout.panels[1][0];
    let cx = red.iter().map(|p| p.0 as f64 + 0.5).sum::<f64>() / red.len() as f64;
    let cy = red.iter().map(|p| p.1 as f64 + 0.5).sum::<f64>() / red.len() as f64;
    assert!(
        (cx - w as f64 / 2.0).abs() < 3.0 && (cy - h as f64 / 2.0).abs() < 3.0,
        "red centroid ({cx}, {cy}) in a {w}×{h} panel"
    );
    // The filled dent is narrower than D: the red covers less than D's disc (radius 0.8).
    let scale = {
        let [x0, y0, pw, ph] = layout.panels[1][0];
        let column = (0..ph)
            .filter(|&y| image.get(x0 + pw / 5, y0 + y).unwrap() != WHITE)
            .count();
        column as f64 / 2.0
    };
    let disc = std::f64::consts::PI * (0.8 * scale).powi(2);
    assert!(
        (red.len() as f64) < 0.8 * disc,
        "red {} vs D's disc {disc:.0}",
        red.len()
    );
    // The top and oblique views see the filled dent too.
    assert!(red_in(&image, layout.panels[1][1]).len() > 500);
    assert!(red_in(&image, layout.panels[1][2]).len() > 1_000);
    // Caption: dark text in the strip and the scale bar (a long black run).
    let [x0, y0, cw, ch] = layout.caption;
    let ink = (y0..y0 + ch)
        .flat_map(|y| (x0..x0 + cw).map(move |x| (x, y)))
        .filter(|&(x, y)| image.get(x, y).unwrap()[0] < 100)
        .count();
    assert!(ink > 500, "caption ink {ink}");
    let longest_run = (y0..y0 + ch)
        .map(|y| {
            let (mut best, mut run) = (0, 0);
            for x in x0..x0 + cw {
                run = if image.get(x, y).unwrap() == [0, 0, 0] {
                    run + 1
                } else {
                    0
                };
                best = best.max(run);
            }
            best
        })
        .max()
        .unwrap();
    // A quarter of a panel's width in world units, rounded down to 1, 2 or 5 × 10^k: at
    // `scale` px per unit the bar is between 0.1 and 0.25 of the panel's width.
    assert!(
        longest_run as f64 > 0.1 * w as f64 && longest_run as f64 <= 0.26 * w as f64,
        "scale bar {longest_run} px in a {w} px panel"
    );

    // A repair that added nothing: no red in the repaired row.
    let same = repair_picture(&intact, &intact, &[ball], &opts).unwrap();
    for rect in layout.panels[1] {
        assert_eq!(red_in(&same, rect).len(), 0);
    }
    println!(
        "red {} px in the front view ({scale:.1} px per unit, D's disc {disc:.0} px), scale bar \
         {longest_run} px",
        red.len()
    );
}

#[test]
fn without_regions_the_whole_mesh_is_grey() {
    let (dented, intact, _) = dented_tube();
    let opts = RepairPictureOptions {
        width: 400,
        height: 300,
        ..RepairPictureOptions::default()
    };
    let image = repair_picture(&dented, &intact, &[], &opts).unwrap();
    assert_eq!((image.width, image.height), (400, 300));
    let rrect = picture_layout(&opts).panels[1][0];
    let grey = panel_pixels(&image, rrect)
        .iter()
        .filter(|p| is_grey(p.2))
        .count();
    assert!(grey > 1_000, "grey {grey}");
    // Empty meshes give blank panels, not an error.
    let empty = TriMesh::new(vec![], vec![]);
    let blank = repair_picture(&empty, &empty, &[], &opts).unwrap();
    // (Below the row's name in the panel's corner.)
    let [x, y, w, h] = picture_layout(&opts).panels[0][0];
    let lower = [x, y + h / 2, w, h / 2];
    assert!(panel_pixels(&blank, lower).iter().all(|p| p.2 == WHITE));
}

#[test]
fn bad_path_or_size_fails_and_leaves_no_file() {
    let (dented, intact, ball) = dented_tube();
    let dir = figure_dir();
    let missing = dir.join("no_such_folder").join("picture.png");
    assert!(render_repair(
        &dented,
        &intact,
        &[ball],
        &missing,
        &RepairPictureOptions::default()
    )
    .is_err());
    assert!(!missing.exists());
    let path = dir.join("zero_width.png");
    let _ = std::fs::remove_file(&path);
    for (width, height) in [(0, 600), (1200, 0), (1_000_000, 600)] {
        let err = render_repair(
            &dented,
            &intact,
            &[ball],
            &path,
            &RepairPictureOptions {
                width,
                height,
                ..RepairPictureOptions::default()
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("zero_width.png"), "{err}");
        assert!(!path.exists());
    }
    // Unusable balls are ignored, not fatal.
    let odd = [
        Ball {
            center: Point3::new(f64::NAN, 0.0, 0.0),
            radius: 1.0,
        },
        Ball {
            center: Point3::new(1.0, 0.0, 4.0),
            radius: -1.0,
        },
    ];
    let opts = RepairPictureOptions {
        width: 200,
        height: 100,
        ..RepairPictureOptions::default()
    };
    assert!(repair_picture(&dented, &intact, &odd, &opts).is_ok());
}

#[test]
fn phantom_pictures_for_a_person() {
    // Each phantom's truth stands in for the repaired vessel.
    for kind in [
        PhantomKind::Tube,
        PhantomKind::Curved,
        PhantomKind::Bifurcation,
        PhantomKind::Stenosis,
    ] {
        let phantom = make_phantom(kind, &PhantomOptions::default()).unwrap();
        let opts = RepairPictureOptions {
            added_distance: 0.05,
            ..RepairPictureOptions::default()
        };
        let path = figure_dir().join(format!("{}_phantom.png", kind.as_str()));
        render_repair(
            &phantom.damaged,
            &phantom.truth,
            &phantom.regions,
            &path,
            &opts,
        )
        .unwrap();
        let image = decode(&path);
        let layout = picture_layout(&opts);
        let (lrect, rrect) = (layout.panels[0][0], layout.panels[1][0]);
        let count = |rect, f: &dyn Fn([u8; 3]) -> bool| {
            panel_pixels(&image, rect).iter().filter(|p| f(p.2)).count()
        };
        let red = count(rrect, &is_red);
        let grey = count(lrect, &is_grey);
        assert!(
            red > 1_000 && grey > 5_000,
            "{kind:?}: red {red}, grey {grey}"
        );
        let v = repair_view(&phantom.truth, &phantom.regions);
        println!(
            "{}: red {red} px, grey {grey} px, view {:.3?}, {}",
            phantom.description,
            v.view.as_slice(),
            path.display()
        );
    }
}

#[test]
fn real_aneurysm_picture_for_a_person() {
    let Some(dir) = common::real_dir() else {
        return;
    };
    let mesh = common::read_real(&dir, "ica_aneurysm_c0015.stl");
    // D: a ball at the widest point of the vessel (the aneurysm's sac), 1.5 × its local radius
    // as a picked point gets it; the mesh stands in for both input and repair.
    let bvh = vesselmsr::bvh::MeshBvh::new(&mesh);
    let (p, r) = mesh
        .vertices
        .iter()
        .step_by(3)
        .filter_map(|p| {
            vesselmsr::inpaint::region::local_vessel_radius(&mesh, &bvh, p).map(|r| (*p, r))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    let ball = Ball {
        center: p,
        radius: vesselmsr::inpaint::region::PICKED_RADIUS_FACTOR * r,
    };
    let path = figure_dir().join("ica_aneurysm.png");
    let opts = RepairPictureOptions::default();
    render_repair(&mesh, &mesh, &[ball], &path, &opts).unwrap();
    let image = decode(&path);
    let layout = picture_layout(&opts);
    let (lrect, rrect) = (layout.panels[0][0], layout.panels[1][0]);
    let red = panel_pixels(&image, rrect)
        .iter()
        .filter(|p| is_red(p.2))
        .count();
    let grey = panel_pixels(&image, lrect)
        .iter()
        .filter(|p| is_grey(p.2))
        .count();
    // The mesh stands in for both input and repair: nothing added, nothing red.
    assert!(red == 0 && grey > 5_000, "red {red}, grey {grey}");
    println!("{ball:?}: red {red} px, grey {grey} px, {}", path.display());
}
