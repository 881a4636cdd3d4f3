//! `vesselmsr batch` (issue 23): a folder of small vessels (a closed phantom, an open tube, the
//! same tube with a hole punched in its wall) and one broken file through `repair`, two at a
//! time: one summary row each in summary.csv and summary.json, the broken one an error that
//! stops nothing, the holed one inpainted; a second run skips every finished row, a run whose
//! summary lost a row (a killed run) redoes that one only, `--retry-failed` redoes the error;
//! a manifest CSV drives `stenosis` and `remesh` with the single commands' figures.

use crate::common;

use common::{punch_hole, vesselmsr};
use nalgebra::Point3;
use serde_json::Value;
use std::path::Path;
use vesselmsr::io::{read_mesh, write_mesh};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::primitives::open_tube;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `batch ARGS`, returning (exit code, stderr) and the rows of summary.json in `out`.
fn batch(args: &[&str], out: &Path) -> (Option<i32>, String, Vec<Value>) {
    let mut all = vec!["batch"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["-o", s(out)]);
    let run = vesselmsr(&all);
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    println!("{all:?}\n{stderr}");
    let rows: Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    (run.status.code(), stderr, rows.as_array().unwrap().clone())
}

fn row<'a>(rows: &'a [Value], id: &str) -> &'a Value {
    rows.iter().find(|r| r["id"] == id).unwrap()
}

#[test]
fn batch_repairs_a_folder_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = (dir.path().join("in"), dir.path().join("out"));
    std::fs::create_dir(&input).unwrap();
    let (tube_phantom, _, _) = common::phantom("tube", dir.path());
    std::fs::rename(tube_phantom, input.join("phantom.stl")).unwrap();
    let tube = open_tube(2.0, 20.0, 32, 41);
    write_mesh(&input.join("tube.ply"), &tube).unwrap();
    write_mesh(
        &input.join("holed.vtp"),
        &punch_hole(&tube, Point3::new(2.0, 0.0, 10.0), 1.2),
    )
    .unwrap();
    std::fs::write(input.join("broken.stl"), "solid nothing\n").unwrap();
    std::fs::write(input.join("notes.txt"), "not a mesh").unwrap();

    let (code, _, rows) = batch(&[s(&input), "--jobs", "2", "-q"], &out);
    assert_eq!(code, Some(2), "one mesh failed");
    let ids: Vec<&str> = rows.iter().map(|r| r["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["broken", "holed", "phantom", "tube"]);
    let broken = row(&rows, "broken");
    assert_eq!(broken["status"], "error");
    assert!(broken["error"].as_str().unwrap().contains("broken.stl"));
    assert!(broken["output_volume"].is_null());
    for id in ["holed", "phantom", "tube"] {
        let r = row(&rows, id);
        assert_eq!(r["status"], "ok", "{r}");
        assert_eq!(r["watertight"], true, "{r}");
        let output = r["output"].as_str().unwrap();
        assert!(mesh_info(&read_mesh(Path::new(output)).unwrap()).watertight);
        // The row's figures are the report's.
        let report: Value =
            serde_json::from_slice(&std::fs::read(r["report"].as_str().unwrap()).unwrap()).unwrap();
        assert_eq!(r["output_volume"], report["output"]["volume"]);
    }
    let holed = row(&rows, "holed");
    assert!(holed["output"].as_str().unwrap().ends_with("holed.vtp"));
    assert_eq!(holed["regions"], 1);
    let added = holed["inpainted_volume"].as_f64().unwrap();
    assert!(added > 0.0, "{holed}");
    assert_eq!(row(&rows, "tube")["regions"], 0);
    assert!(row(&rows, "tube")["notices"]
        .as_str()
        .unwrap()
        .contains("no holes found"));
    // The holed tube comes back to the intact one's capped volume.
    let full = row(&rows, "tube")["output_volume"].as_f64().unwrap();
    let repaired = holed["output_volume"].as_f64().unwrap();
    println!("holed: +{added:.3}, {repaired:.3} against {full:.3} intact");
    assert!((repaired / full - 1.0).abs() < 0.01);
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5, "{csv}");
    assert!(csv.starts_with("id,mesh,command,status,output,report,input_volume,"));

    // Again: nothing redone (the outputs keep their times, the rows their seconds).
    let stamp = |id: &str| {
        std::fs::metadata(out.join(format!("{id}.report.json")))
            .unwrap()
            .modified()
            .unwrap()
    };
    let before = stamp("holed");
    let (code, stderr, again) = batch(&[s(&input)], &out);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("4 of 4 meshes already in"), "{stderr}");
    assert_eq!(again, rows);
    assert_eq!(stamp("holed"), before);

    // A killed run: the summary lacks the rows that had not finished; only those are run.
    let kept: Vec<&Value> = rows.iter().filter(|r| r["id"] != "tube").collect();
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string(&kept).unwrap(),
    )
    .unwrap();
    let (_, stderr, resumed) = batch(&[s(&input)], &out);
    assert!(stderr.contains("3 of 4 meshes already in"), "{stderr}");
    assert!(stderr.contains("[1/1] tube: ok"), "{stderr}");
    assert_eq!(resumed.len(), 4);
    assert_eq!(stamp("holed"), before);
    // --retry-failed runs the error again, nothing else.
    let (_, stderr, _) = batch(&[s(&input), "--retry-failed"], &out);
    assert!(stderr.contains("[1/1] broken: error"), "{stderr}");
}

#[test]
fn batch_manifest_runs_stenosis_and_remesh() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (sten, truth, _) = common::phantom("stenosis", d);
    std::fs::rename(sten, d.join("sten.stl")).unwrap();
    std::fs::rename(truth, d.join("truth.stl")).unwrap();
    std::fs::write(
        d.join("cohort.csv"),
        "# a comment\nid,mesh,age\nnarrow,sten.stl,61\n\"healthy, truth\",truth.stl,58\n",
    )
    .unwrap();
    let out = d.join("stenosis");
    let (code, _, rows) = batch(
        &[s(&d.join("cohort.csv")), "--command", "stenosis", "-q"],
        &out,
    );
    assert_eq!(code, Some(0));
    assert_eq!(rows.len(), 2);
    let single = common::vesselmsr_json(&["stenosis", s(&d.join("sten.stl")), "--json", "-q"]);
    let narrow = row(&rows, "narrow");
    assert_eq!(
        narrow["stenoses"],
        single["lesions"].as_array().unwrap().len()
    );
    assert_eq!(
        narrow["max_stenosis_pct"],
        single["lesions"][0]["diameter_stenosis_pct"]
    );
    let pct = narrow["max_stenosis_pct"].as_f64().unwrap();
    assert!((pct - 50.0).abs() < 5.0, "{pct}");
    assert_eq!(row(&rows, "healthy, truth")["stenoses"], 0);

    let out = d.join("remesh");
    let (code, _, rows) = batch(
        &[
            s(&d.join("cohort.csv")),
            "--command",
            "remesh",
            "--format",
            "vtk",
            "-q",
        ],
        &out,
    );
    assert_eq!(code, Some(0));
    let single = d.join("single.vtk");
    let info = common::vesselmsr_json(&[
        "remesh",
        s(&d.join("sten.stl")),
        "-o",
        s(&single),
        "--json",
        "-q",
    ]);
    let narrow = row(&rows, "narrow");
    assert_eq!(narrow["output_volume"], info["output"]["volume"]);
    assert_eq!(
        read_mesh(Path::new(narrow["output"].as_str().unwrap())).unwrap(),
        read_mesh(&single).unwrap()
    );
    // A manifest without a mesh column: exit 2 naming it, no summary.
    std::fs::write(d.join("bad.csv"), "path\nsten.stl\n").unwrap();
    let run = vesselmsr(&["batch", s(&d.join("bad.csv")), "-o", s(&d.join("bad"))]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2));
    assert!(
        stderr.contains("bad.csv") && stderr.contains("`mesh` column"),
        "{stderr}"
    );
    assert!(!d.join("bad").exists());
}
