//! `info --json` on the six real meshes against the counts of ../shared/data/real/SOURCES.md and
//! against pymeshlab's volume and area (the Python oracle) for the closed ones.

use crate::common;
use common::*;

#[test]
fn info_matches_sources_and_pymeshlab() {
    let Some(dir) = real_dir() else { return };
    let oracle = oracle();
    for (file, v, f, loops, closed) in REAL_MESHES {
        let path = dir.join(file);
        let info = info_json(&path);
        println!("{file}: {info}");
        assert_eq!(info["vertices"], v, "{file} vertices");
        assert_eq!(info["faces"], f, "{file} faces");
        assert_eq!(info["boundary_loops"], loops, "{file} boundary loops");
        assert_eq!(info["watertight"], closed, "{file} watertight");
        assert_eq!(info["components"], 1, "{file} components");
        assert_eq!(info["non_manifold_edges"], 0, "{file} non-manifold edges");
        let reference = oracle.check(&path);
        assert_matches_pymeshlab(
            &format!("{file}: area"),
            info["area"].as_f64().unwrap(),
            reference["pymeshlab_area"].as_f64().unwrap(),
        );
        if closed {
            assert_matches_pymeshlab(
                &format!("{file}: volume"),
                info["volume"].as_f64().unwrap(),
                reference["pymeshlab_volume"].as_f64().unwrap(),
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
        let info = info_json(&dir.join(file));
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
