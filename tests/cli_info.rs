//! `info --json` on the six real meshes against the counts of ../shared/data/real/SOURCES.md and
//! against pymeshlab's volume and area (the Python oracle) for the closed ones.

mod common;
use common::*;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

#[test]
fn info_matches_sources_and_pymeshlab() {
    let Some(dir) = real_dir() else { return };
    let oracle = oracle();
    for (file, v, f, loops, closed) in REAL_MESHES {
        let path = dir.join(file);
        let info = vesselmsr_json(&["info", "--json", path.to_str().unwrap()]);
        println!("{file}: {info}");
        assert_eq!(info["vertices"], v, "{file} vertices");
        assert_eq!(info["faces"], f, "{file} faces");
        assert_eq!(info["boundary_loops"], loops, "{file} boundary loops");
        assert_eq!(info["watertight"], closed, "{file} watertight");
        assert_eq!(info["components"], 1, "{file} components");
        assert_eq!(info["non_manifold_edges"], 0, "{file} non-manifold edges");
        let reference = oracle.check(&path);
        let area = info["area"].as_f64().unwrap();
        let ref_area = reference["pymeshlab_area"].as_f64().unwrap();
        println!(
            "{file}: area {area} vs pymeshlab {ref_area} (rel {:.2e})",
            rel(area, ref_area)
        );
        assert!(
            rel(area, ref_area) < 1e-6,
            "{file}: area {area} vs pymeshlab {ref_area}"
        );
        if closed {
            let vol = info["volume"].as_f64().unwrap();
            let ref_vol = reference["pymeshlab_volume"].as_f64().unwrap();
            println!(
                "{file}: volume {vol} vs pymeshlab {ref_vol} (rel {:.2e})",
                rel(vol, ref_vol)
            );
            assert!(
                rel(vol, ref_vol) < 1e-6,
                "{file}: volume {vol} vs pymeshlab {ref_vol}"
            );
            assert_eq!(info["genus"], reference["manifold_genus"], "{file} genus");
            assert_eq!(
                reference["manifold_status"], "NoError",
                "{file}: manifold3d verdict"
            );
        } else {
            assert!(
                info["volume"].is_null() && info["genus"].is_null(),
                "{file}: open mesh volume"
            );
            assert_eq!(info["orientation"], "open", "{file} orientation");
        }
    }
}

#[test]
fn info_reports_orientation_of_closed_meshes() {
    let Some(dir) = real_dir() else { return };
    for (file, expected) in [
        ("aorta_abdominal_capped.stl", "inward"),
        ("cortex_rh_pial_fsaverage5.stl", "outward"),
    ] {
        let info = vesselmsr_json(&["info", "--json", dir.join(file).to_str().unwrap()]);
        assert_eq!(info["orientation"], expected, "{file}");
    }
}

#[test]
fn info_text_output_names_the_essentials() {
    let path = data_dir().join("aorta_abdominal_open_ends.stl");
    let out = vesselmsr(&["info", path.to_str().unwrap()]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap().to_lowercase();
    for word in [
        "6068",
        "11887",
        "boundary",
        "watertight",
        "orientation",
        "area",
    ] {
        assert!(text.contains(word), "text output lacks {word}:\n{text}");
    }
}
