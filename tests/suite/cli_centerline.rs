//! The centreline commands end to end (issue 20): `centerline` to JSON and to VTP (read back by
//! VTK's own reader), `profile` (CSV and picture), `stenosis --json`; the bad inputs (an open
//! mesh with a hole: capped, with a notice; a mesh with no inside: exit 2, nothing written; a
//! sphere: a notice); and `repair` measuring the stenosis along the centreline, the same for
//! every region radius from 1.5 to 3 healthy radii, and sizing a picked point from the healthy
//! radius.

use crate::common;

use common::{assert_fails, vesselmsr, vesselmsr_json};
use nalgebra::Point3;
use std::path::Path;
use vesselmsr::io::{read_centerline_json, write_mesh};
use vesselmsr::mesh::primitives::{icosphere, open_tube};
use vesselmsr::TriMesh;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The stenosis phantom (damaged, truth) written into `d` by the CLI.
fn stenosis_phantom(d: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let (damaged, truth, _) = common::phantom("stenosis", d);
    (damaged, truth)
}

#[test]
fn centerline_json_and_vtp_of_the_aorta() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("cl.json");
    let vtp = dir.path().join("cl.vtp");
    let summary = vesselmsr_json(&["centerline", &common::aorta(), "-o", s(&json), "--json"]);
    assert_eq!(summary["branches"].as_array().unwrap().len(), 3);
    assert_eq!(summary["junctions"].as_array().unwrap().len(), 1);
    let cl = read_centerline_json(&json).unwrap();
    assert_eq!(cl.branches.len(), 3);
    assert_eq!(cl.endpoints.iter().filter(|e| e.open_end).count(), 3);
    let out = vesselmsr(&["centerline", &common::aorta(), "-o", s(&vtp), "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // VTK's reader: one polyline per branch, every point with its radius.
    let script = "import sys, vtk\n\
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(sys.argv[1]); r.Update()\n\
d = r.GetOutput(); pd = d.GetPointData()\n\
print([d.GetNumberOfLines(), d.GetNumberOfPoints(), pd.GetArray('Radius').GetNumberOfTuples(), pd.GetArray('BranchId').GetRange()[1], pd.GetArray('Radius').GetRange()[1]])";
    let v = common::run_python(script, &[&vtp]);
    println!("vtk reads: {v}");
    let f: Vec<f64> = serde_json::from_value(v).unwrap();
    let points: usize = cl.branches.iter().map(|b| b.points.len()).sum();
    let max_r = cl
        .branches
        .iter()
        .flat_map(|b| b.radius.iter())
        .cloned()
        .fold(0.0, f64::max);
    assert_eq!(f[0], 3.0);
    assert_eq!(f[1], points as f64);
    assert_eq!(f[2], points as f64);
    assert_eq!(f[3], 2.0);
    assert!((f[4] - max_r).abs() < 1e-9 * max_r);
}

#[test]
fn profile_and_stenosis_of_the_stenosis_phantom() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (damaged, truth) = stenosis_phantom(d);
    let csv = d.join("p.csv");
    let png = d.join("p.png");
    let out = vesselmsr(&[
        "profile",
        s(&damaged),
        "-o",
        s(&csv),
        "--picture",
        s(&png),
        "--units",
        "mm",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let eq: Vec<f64> = rows.iter().filter_map(|r| r[6].parse().ok()).collect();
    let min = eq.iter().cloned().fold(f64::INFINITY, f64::min);
    println!(
        "profile: {} rows, {} measured, narrowest equivalent diameter {min:.3} (healthy 6)",
        rows.len(),
        eq.len()
    );
    assert!((min - 3.0).abs() < 0.2);
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    let st = vesselmsr_json(&["stenosis", s(&damaged), "--json"]);
    let lesions = st["lesions"].as_array().unwrap();
    assert_eq!(lesions.len(), 1);
    let deg = lesions[0]["diameter_stenosis_pct"].as_f64().unwrap();
    println!("stenosis --json: {deg:.2}%");
    assert!((deg - 50.0).abs() <= 3.0);
    let st = vesselmsr_json(&["stenosis", s(&truth), "--json"]);
    assert!(st["lesions"].as_array().unwrap().is_empty());
}

#[test]
fn bad_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // An open tube with a hole in its wall: capped first, with a notice; one branch.
    let tube = open_tube(3.0, 40.0, 48, 61);
    let faces: Vec<[u32; 3]> = tube
        .faces
        .iter()
        .filter(|f| {
            let c = f
                .iter()
                .map(|&v| tube.vertices[v as usize])
                .fold(Point3::origin(), |a, p| a + p.coords / 3.0);
            !((c.z - 20.0).abs() < 2.0 && c.x > 2.0)
        })
        .copied()
        .collect();
    let holed = d.join("holed.stl");
    write_mesh(&holed, &TriMesh::new(tube.vertices.clone(), faces)).unwrap();
    let out_json = d.join("holed.json");
    let run = vesselmsr(&["centerline", s(&holed), "-o", s(&out_json)]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    println!("holed tube: {}", stderr.trim());
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("hole(s) in the wall capped"), "{stderr}");
    assert_eq!(read_centerline_json(&out_json).unwrap().branches.len(), 1);
    // A flat sheet has no inside: exit 2, nothing written.
    let sheet = d.join("sheet.stl");
    write_mesh(
        &sheet,
        &TriMesh::new(
            vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(10.0, 0.0, 0.0),
                Point3::new(10.0, 10.0, 0.0),
                Point3::new(0.0, 10.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        ),
    )
    .unwrap();
    let out = d.join("sheet.json");
    assert_fails(&["centerline", s(&sheet), "-o", s(&out)], "no inside", &out);
    assert_fails(
        &["centerline", s(&holed), "-o", s(&d.join("x.txt"))],
        "unknown centreline format",
        &d.join("x.txt"),
    );
    // A sphere is no vessel: a short stub and a notice.
    let ball = d.join("ball.stl");
    write_mesh(&ball, &icosphere(4, 5.0, Point3::origin())).unwrap();
    let run = vesselmsr(&["centerline", s(&ball), "-o", s(&d.join("ball.json"))]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    println!("sphere: {}", stderr.trim());
    assert!(run.status.success());
    assert!(stderr.contains("not tube-like"), "{stderr}");
}

#[test]
fn repair_measures_along_the_centerline() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (damaged, truth) = stenosis_phantom(d);
    let healthy_radius = 3.0;
    // Runs `repair ARGS -o out.stl --report rep.json` and returns the report.
    let repair = |args: &[&str]| -> serde_json::Value {
        let (out, report) = (d.join("out.stl"), d.join("rep.json"));
        let mut all = vec!["repair"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["-o", s(&out), "--report", s(&report), "--quiet"]);
        let run = vesselmsr(&all);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap()
    };
    let mut seen = Vec::new();
    for factor in [1.5, 2.0, 2.5, 3.0] {
        let region = format!("0,0,0,{}", factor * healthy_radius);
        let r = repair(&[s(&damaged), "--region", &region]);
        let g = &r["regions"][0];
        assert_eq!(g["stenosis_method"], "centerline");
        let (dia, nascet) = (
            g["diameter_stenosis_pct"].as_f64().unwrap(),
            g["nascet_stenosis_pct"].as_f64().unwrap(),
        );
        println!("region radius {factor} R: diameter {dia:.2}%, NASCET {nascet:.2}%");
        seen.push(nascet);
        assert!((dia - 50.0).abs() <= 5.0 && (nascet - 50.0).abs() <= 5.0);
    }
    let spread = seen.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - seen.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(
        spread <= 3.0,
        "NASCET moves by {spread} points with the region's radius"
    );
    // A healthy vessel reports under 5%.
    let r = repair(&[s(&truth), "--region", "0,3,0,4.5"]);
    let g = &r["regions"][0];
    println!(
        "healthy: diameter {}%, NASCET {}%",
        g["diameter_stenosis_pct"], g["nascet_stenosis_pct"]
    );
    assert!(g["diameter_stenosis_pct"].as_f64().unwrap().abs() < 5.0);
    // A point picked in the narrowing takes the narrowing's region: its width at half depth
    // plus a healthy radius (at least 1.5 healthy radii), on the centreline at its throat,
    // measured there.
    let picked = d.join("pick.json");
    std::fs::write(&picked, r#"{"points": [[0, 1.6, 0]]}"#).unwrap();
    let r = repair(&[s(&damaged), "--regions", s(&picked)]);
    let g = &r["regions"][0];
    let radius = g["radius"].as_f64().unwrap();
    let nascet = g["nascet_stenosis_pct"].as_f64().unwrap();
    println!(
        "picked point: {} region radius {radius:.3} (healthy {healthy_radius}), NASCET {nascet:.2}%",
        g["source"]
    );
    assert_eq!(g["source"], "picked stenosis");
    assert!(radius >= 1.5 * healthy_radius && radius <= 5.0 * healthy_radius);
    assert!((nascet - 50.0).abs() <= 5.0);
}
