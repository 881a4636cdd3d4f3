//! The real aortas of issue 21 (both shipped in data/, BSD): a hole in the open-ended aorta
//! repaired with the defaults (once a watertight mesh with a slit across the lumen, 12 mm sliver
//! edges and 7× the inpainted volume, silently), and the capped aorta, stored inward (once left
//! inward, with negative volumes in the report). Each: a wall chop (every triangle with a vertex
//! in a ball of 1.5 local radii on the wall; the benchmark repair_real's chop#3 of that vessel),
//! repaired by the command a user runs (`repair --holes`), judged against the intact file
//! inside D (the chop ball × 1.3): watertight, outward, every face near D two-sided (no slit,
//! fin or pocket), stitched, positive volumes in the report, and the distance to the truth.
//!
//! Measured 2026-12-04: open aorta 1.23h / −1.4% in D (2.08h / +0.3% while the wall's offsets
//! over the hole were a harmonic fill, before `wall_chart`'s biharmonic one; 3.22h / +8.6%
//! before the intact wall around a hole was kept and read, `known_wall`); capped (inward) aorta
//! 0.84h / +0.0% (1.28h harmonic, 1.75h before). Issue 21 asks for 1.5h: met on both.
//! Measured 2026-12-05, the wall chart's rays going on past the hole's cap: open aorta 1.18h /
//! −1.4%, capped aorta 0.69h / +0.2%; the open aorta's hole beside its bifurcation 2.46h / +1.3%
//! (3.20h before the junction's balls were bounded by its inscribed sphere).

use crate::common;

use common::{
    chopped, cut_where, data_dir, hausdorff_in, loop_kinds, one_sided_faces_near, punch_hole,
    vesselmsr, volume_error_in,
};
use nalgebra::Point3;
use serde_json::Value;
use std::path::Path;
use vesselmsr::inpaint::region::Ball;
use vesselmsr::io::{read_mesh, write_mesh};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::measures::handles;
use vesselmsr::TriMesh;

/// `vesselmsr repair DAMAGED FLAGS -o … --report … -q` in `dir` (FLAGS whitespace-separated):
/// the repaired mesh and report.
fn repair_by_cli(damaged: &TriMesh, flags: &str, dir: &Path) -> (TriMesh, Value) {
    let input = dir.join("damaged.stl");
    write_mesh(&input, damaged).unwrap();
    let (output, report) = (dir.join("repaired.stl"), dir.join("report.json"));
    let p = |x: &Path| x.to_str().unwrap().to_string();
    let (input_s, output_s, report_s) = (p(&input), p(&output), p(&report));
    let mut args = vec!["repair", &input_s];
    args.extend(flags.split_whitespace());
    args.extend(["-o", &output_s, "--report", &report_s, "-q"]);
    let run = vesselmsr(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    // The summary names the patch's voxel where it is not the fill's (`patch_stride`).
    let p = &report["parameters"];
    let coarse = p["patch_voxel"].as_f64().unwrap() > p["voxel"].as_f64().unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert_eq!(
        stdout.contains("(the patch meshed at "),
        coarse,
        "{stdout}\n{p}"
    );
    (read_mesh(&output).unwrap(), report)
}

/// Chops `file` (data/) at `centre` with a ball of `radius`, repairs it with `repair FLAGS`
/// (whitespace-separated) and checks the output; returns (Hausdorff in D in voxels, volume
/// error in D, report).
fn chop_and_repair(
    file: &str,
    centre: [f64; 3],
    radius: f64,
    flags: &str,
    dir: &Path,
) -> (f64, f64, Value) {
    damage_and_repair(file, centre, radius, false, flags, dir)
}

/// [`chop_and_repair`] with every piece the ball leaves kept (it may cut the vessel through),
/// repaired with `--holes`.
fn cut_through_and_repair(file: &str, centre: [f64; 3], radius: f64) -> (f64, f64, Value) {
    let dir = tempfile::tempdir().unwrap();
    damage_and_repair(file, centre, radius, true, "--holes", dir.path())
}

/// `file` (data/) without the triangles the ball of `radius` at `centre` reaches (the largest
/// piece left, or every piece), repaired with `repair FLAGS` and checked; D is the ball grown
/// by 1.3, as the benchmark's.
fn damage_and_repair(
    file: &str,
    centre: [f64; 3],
    radius: f64,
    keep_pieces: bool,
    flags: &str,
    dir: &Path,
) -> (f64, f64, Value) {
    let truth = read_mesh(&data_dir().join(file)).unwrap();
    let chop = Ball {
        center: Point3::from(centre),
        radius,
    };
    let d = Ball {
        center: chop.center,
        radius: 1.3 * radius,
    };
    let damaged = if keep_pieces {
        punch_hole(&truth, chop.center, radius)
    } else {
        chopped(&truth, &chop)
    };
    assert!(
        damaged.num_faces() + 300 < truth.num_faces(),
        "the chop removed a wall"
    );
    repair_and_check(file, &truth, &damaged, d, flags, dir)
}

/// Repairs `damaged` (`file` with a hole in `d`) with `repair FLAGS` and checks the output as
/// [`chop_and_repair`] says; returns (Hausdorff in D in voxels, volume error in D, report).
fn repair_and_check(
    file: &str,
    truth: &TriMesh,
    damaged: &TriMesh,
    d: Ball,
    flags: &str,
    dir: &Path,
) -> (f64, f64, Value) {
    let (repaired, report) = repair_by_cli(damaged, flags, dir);
    let info = mesh_info(&repaired);
    assert!(info.watertight, "not watertight");
    assert!(
        info.signed_volume > 0.0,
        "not outward: {}",
        info.signed_volume
    );
    assert_eq!(report["parameters"]["stitched"], true, "{report}");
    // No handle the vessel does not have (a tunnel between the fill and the input's wall).
    assert_eq!(
        handles(&repaired),
        handles(truth),
        "the repair changed the genus"
    );
    // Every volume the report gives is positive.
    for part in ["input", "output"] {
        let v = report[part]["volume"].as_f64().unwrap();
        assert!(v > 0.0, "{part} volume {v}");
    }
    let h = report["parameters"]["voxel"].as_f64().unwrap();
    let mean_edge = vesselmsr::mesh::measures::mean_edge_length(damaged);
    // The faces near D and near the regions the repair drew round the holes (wider than D:
    // the stitch's seam lies on their edge).
    let mut probe = vec![d];
    for r in report["regions"].as_array().unwrap() {
        let added = r["inpainted_volume"].as_f64().unwrap();
        assert!(added > 0.0, "inpainted {added}");
        assert!(r["output_volume_in_region"].as_f64().unwrap() > 0.0);
        let c: Vec<f64> = serde_json::from_value(r["center"].clone()).unwrap();
        probe.push(Ball {
            center: Point3::new(c[0], c[1], c[2]),
            radius: r["radius"].as_f64().unwrap(),
        });
    }
    let (wrong, probed) = one_sided_faces_near(&repaired, &probe, 3.0 * h, 0.1 * mean_edge.min(h));
    assert_eq!(
        wrong, 0,
        "{wrong} of {probed} faces near D do not face out (a slit, or a triangle folded over)"
    );
    let hd = hausdorff_in(&repaired, truth, &[d]) / h;
    let ve = volume_error_in(&repaired, truth, &[d]);
    println!(
        "{file}: Hausdorff in D {hd:.2}h, volume error in D {:+.1}%, {wrong} of {probed} faces near D one-sided",
        100.0 * ve
    );
    (hd, ve, report)
}

/// [`chop_and_repair`] on one of the benchmark's chops, given as its region D (the chop is D
/// over 1.3), in a folder of its own; checks the region was filled as `fill` and that the
/// whole vessel was not re-meshed instead (no `fallback`).
fn bench_chop(file: &str, centre: [f64; 3], d_radius: f64, fill: &str) -> (f64, f64, Value) {
    bench_chop_with(file, centre, d_radius, fill, "--holes")
}

/// [`bench_chop`] repaired with `repair FLAGS` (whitespace-separated) instead of `--holes`.
fn bench_chop_with(
    file: &str,
    centre: [f64; 3],
    d_radius: f64,
    fill: &str,
    flags: &str,
) -> (f64, f64, Value) {
    let dir = tempfile::tempdir().unwrap();
    let (hd, ve, report) = chop_and_repair(file, centre, d_radius / 1.3, flags, dir.path());
    assert_eq!(report["regions"][0]["fill"], fill, "{report}");
    assert!(report["parameters"]["fallback"].is_null(), "{report}");
    (hd, ve, report)
}

#[test]
fn a_hole_in_the_open_aorta_is_filled_without_a_slit() {
    let dir = tempfile::tempdir().unwrap();
    let (hd, ve, report) = chop_and_repair(
        "aorta_abdominal_open_ends.stl",
        [210.9, 116.7, 24.33],
        6.647,
        "--holes",
        dir.path(),
    );
    // A wall on one vessel: continued through D, no junction notice.
    assert_eq!(report["regions"][0]["fill"], "through", "{report}");
    assert!(
        !report["notices"].to_string().contains("junction"),
        "{}",
        report["notices"]
    );
    // The aorta there is 14 voxels in radius: its patch is meshed at twice the voxel, about the
    // input's density, and still within 1.5h.
    let p = &report["parameters"];
    let (voxel, patch) = (
        p["voxel"].as_f64().unwrap(),
        p["patch_voxel"].as_f64().unwrap(),
    );
    assert!((patch - 2.0 * voxel).abs() < 1e-12 * voxel, "{p}");
    // Stitched at ∂D itself.
    assert_eq!(p["stitch_beyond"].as_f64(), Some(0.0), "{p}");
    // Issue 21 asks for 1.5h (0.82h measured since 2026-12-07, the recentred curve fading out at
    // its ends, 0.96h before; 1.20h with the wall chart's Laplacian isotropic,
    // 1.18h with the patch at the voxel too); the damaged input is 21.6h / −12.5%.
    assert!(hd <= 1.5, "{hd}h");
    assert!(ve.abs() <= 0.03, "{ve}");
}

/// A slit in the open aorta's wall (every triangle with a vertex within 0.35 local radii of a
/// line along the wall, 2 radii either side of a wall point; 168 triangles, 14 mm by 5 mm):
/// the fill's curve, moved onto the intact wall's centre around the hole, once kept its end at
/// the anchor while the sample beside it moved with its neighbours, so the last tangent turned
/// sideways and the tube, continued straight past its end, stood out of the wall as a fin
/// 7 mm long (22.6h / +4.6% in D; MeshLib's fillHoleNicely 0.67h). Measured 2026-12-07 with
/// the recentring fading out at the curve's ends: 1.45h / +0.0%.
#[test]
fn a_slit_in_the_open_aortas_wall_is_filled_without_a_fin() {
    let file = "aorta_abdominal_open_ends.stl";
    let truth = read_mesh(&data_dir().join(file)).unwrap();
    let p = Point3::new(229.38040161132812, 145.60545349121094, 21.098255793253582);
    let t = nalgebra::Vector3::new(0.19397666340627853, 0.28608394622585415, 0.9383650834113607);
    let r = 6.857025852405833;
    let damaged = cut_where(&truth, |x| {
        let v = x - p;
        let along = v.dot(&t);
        along.abs() < 2.0 * r && (v - t * along).norm() < 0.35 * r
    });
    assert_eq!(truth.num_faces() - damaged.num_faces(), 168);
    let d = Ball {
        center: p,
        radius: 1.3 * 2.0 * r,
    };
    let dir = tempfile::tempdir().unwrap();
    let (hd, ve, report) = repair_and_check(file, &truth, &damaged, d, "--holes", dir.path());
    assert_eq!(report["regions"][0]["fill"], "through", "{report}");
    assert!(hd <= 1.5, "{hd}h");
    assert!(ve.abs() <= 0.01, "{ve}");
}

/// A ball of 2.2 local radii on the open aorta's wall over its bifurcation cuts the aorta from
/// both iliacs, every piece kept (`benches/repair_real -- --shapes`, seed 21): three loops, none
/// planar as a clipped end is, facing each other. `--holes` took them for open vessel ends and
/// inpainted nothing (−68% in D, with a notice per loop; MeshLib's fillHoleNicely caps each loop,
/// 34.6h / −55%); they are now a gap, bridged as a junction: measured 2026-12-07 10.3h / −1.8%.
#[test]
fn a_bifurcation_cut_from_its_branches_is_bridged_with_holes() {
    let (hd, ve, report) = cut_through_and_repair(
        "aorta_abdominal_open_ends.stl",
        [218.62894019216657, 139.28650651820985, 17.915409997084918],
        19.079970169931972 / 1.3,
    );
    let kinds = loop_kinds(&report);
    assert_eq!(
        kinds.iter().filter(|k| **k == "cut end").count(),
        3,
        "{kinds:?}"
    );
    assert_eq!(report["regions"][0]["source"], "gap", "{report}");
    assert_eq!(report["regions"][0]["fill"], "junction", "{report}");
    assert!(ve.abs() <= 0.05, "{ve}");
    assert!(hd <= 12.0, "{hd}h");
}

/// The shapes study's big ball (2.2 radii) over the open aorta's bifurcation, seed 23, its
/// pieces kept: the aorta is cut 12 mm below its clipped top, a stub whose centreline the gap's
/// region swallows, and the two iliacs, side by side below, were the only ends left: bridged to
/// each other, a U-turn, with the stub left apart (44.3h / −64.8% in D, two pieces). Two ends
/// that do not face each other are now joined with the open end ahead of them as a junction.
#[test]
fn a_severed_bifurcation_with_a_short_stub_is_joined_as_a_junction() {
    let (hd, ve, report) = cut_through_and_repair(
        "aorta_abdominal_open_ends.stl",
        [228.02747269725148, 153.28951732873261, 26.33249918022866],
        21.457955795473833 / 1.3,
    );
    assert_eq!(report["regions"][0]["source"], "gap", "{report}");
    assert_eq!(report["regions"][0]["fill"], "junction", "{report}");
    assert_eq!(report["output"]["components"], 1, "{report}");
    assert!(ve.abs() <= 0.05, "{ve}");
    assert!(hd <= 5.0, "{hd}h");
}

/// The benchmark's chop#2 of the open aorta: a hole whose region D reaches over the aortic
/// bifurcation, so the fill is a junction of three tubes closed by balls at the junction point.
/// The aorta's ball (7.7 mm, its anchor's radius) stood 1.2 mm outside the intact wall beside
/// the hole (3.20h); bounded by the junction's inscribed sphere (5.7 mm) it is within 2.5h.
#[test]
fn a_hole_beside_the_aortic_bifurcation_stays_within_3h() {
    let (hd, ve, report) = bench_chop(
        "aorta_abdominal_open_ends.stl",
        [222.56062162145258, 149.9970286039105, 30.50383559546181],
        14.567503951015059,
        "junction",
    );
    assert_eq!(report["parameters"]["guides"][0], "junction", "{report}");
    // The report says the junction's shape there is estimated.
    assert!(
        report["notices"]
            .to_string()
            .contains(") spans a junction: its branches are continued"),
        "{}",
        report["notices"]
    );
    // Issue 21 asks every case within 3h (2.27h measured; 2.51h with the junction branches'
    // equal Hermite tangents, `guided::JUNCTION_TANGENTS`, 2.15h with the wall chart's Laplacian
    // isotropic too; 3.20h before).
    assert!(hd <= 3.0, "{hd}h");
    assert!(ve.abs() <= 0.05, "{ve}");
}

/// The benchmark's chop#2 of the open aorta in the draw of seed 25: a wall chop on one iliac
/// whose region D (sized from the hole) reaches less than half a voxel into the other iliac's
/// wall. That grazed piece was cut out too, the patch had no loop there to meet its
/// hole ("3 holes around D but 2 patch loops"), and the whole vessel was re-meshed; the grazed
/// wall is now kept and the patch stitched (`chop_and_repair` asserts it).
#[test]
fn a_region_that_grazes_the_other_iliac_is_still_stitched() {
    let (hd, ve, _) = bench_chop(
        "aorta_abdominal_open_ends.stl",
        [216.40718427143486, 115.91472005651814, 24.347107395788477],
        8.588039476176371,
        "through",
    );
    // 1.45h and +2.2% measured (1.55h and +2.3% with the wall chart's Laplacian isotropic; 1.57h
    // and +2.5% with the patch at the voxel too, as the whole-vessel re-mesh gave).
    assert!(hd <= 2.0, "{hd}h");
    assert!(ve.abs() <= 0.04, "{ve}");
}

/// The benchmark's chop#1 of the capped aorta in the draw of seed 26, over the bifurcation: the
/// crotch between the iliacs touches ∂D, so the input cut at D leaves the iliacs' holes joined at
/// a vertex while the patch, whose crotch lies a fraction of a voxel outside D, has one loop round
/// both ("3 holes around D but 2 patch loops" at every cut depth): the whole vessel was re-meshed
/// (2.3 s in the benchmark). The patch is now stitched 2 voxels beyond D, with a notice saying so
/// (`chop_and_repair` asserts it was stitched and that no face near D is one-sided).
#[test]
fn a_crotch_on_the_edge_of_d_is_stitched_beyond_it() {
    let (hd, ve, report) = bench_chop(
        "aorta_abdominal_capped.stl",
        [221.1882240218797, 143.03143962930866, 16.61964283543172],
        13.835545241097313,
        "junction",
    );
    let p = &report["parameters"];
    let (voxel, beyond) = (
        p["voxel"].as_f64().unwrap(),
        p["stitch_beyond"].as_f64().unwrap(),
    );
    assert!((beyond - 2.0 * voxel).abs() < 1e-9 * voxel, "{p}");
    assert!(
        report["notices"]
            .to_string()
            .contains("it was stitched 2 voxels beyond D"),
        "{}",
        report["notices"]
    );
    // 3.43h and +0.8% measured (3.94h and +1.1% with the junction branches' equal Hermite
    // tangents, 4.36h and +1.7% with the wall chart's Laplacian isotropic too; 4.38h re-meshed
    // whole): a modelled junction.
    assert!(hd <= 4.75, "{hd}h");
    assert!(ve.abs() <= 0.05, "{ve}");
}

/// The benchmark's chop#1 of the capped aorta in the draw of seed 22, over the bifurcation: the
/// hole's rim (125 vertices, round the junction) and the patch loop facing it (308) are of
/// unlike spacing and shape. The zipper that advanced along whichever loop gave the shorter next
/// edge lost step on them and left edges of 15–25 mm across the hole at every cut depth: the
/// self-check refused each, and the whole vessel was re-meshed. The strip whose new edges are
/// shortest in sum stitches it (`chop_and_repair` asserts it).
#[test]
fn a_junction_hole_of_the_capped_aorta_is_stitched() {
    let (hd, ve, _) = bench_chop(
        "aorta_abdominal_capped.stl",
        [215.3426687825042, 135.29525643582284, 29.618966774963265],
        11.154411028337723,
        "junction",
    );
    // 4.02h and −6.1% measured (4.39h and −6.6% with the junction branches' equal Hermite
    // tangents, 4.26h and −6.5% with the wall chart's Laplacian isotropic too, 4.23h with the
    // patch at the voxel too, as the whole-vessel re-mesh gave): the junction's shape is
    // modelled, not measured (issue 21's 3h not met here).
    assert!(hd <= 4.75, "{hd}h");
    assert!(ve.abs() <= 0.08, "{ve}");
}

/// The benchmark's chop#1 of the capped aorta in the draw of seed 27: a hole over the carina,
/// between the iliacs. The hole's cap spans the crotch, outside the vessel, and the union of the
/// fill with the capped input kept that web: the crotch closed 6.6 mm below the truth's carina
/// (12.32h, +15.1% in D). What only the cap holds outside the input's own wall is now left to the
/// fill (`known_wall::cap_only_nodes`), and the report says so and counts the input's volume in
/// D without it.
#[test]
fn a_hole_over_the_carina_does_not_keep_its_caps_web() {
    let (hd, ve, report) = bench_chop(
        "aorta_abdominal_capped.stl",
        [220.13698707094613, 128.56137329595356, 27.630710178247696],
        9.830062321977557,
        "junction",
    );
    let notices = report["notices"].to_string();
    assert!(
        notices.contains("the hole's cap crossed space outside the vessel"),
        "{notices}"
    );
    // 8.90h and +9.6% measured (9.66h and +9.8% with the junction branches' equal Hermite
    // tangents, 9.63h and +10.2% with the wall chart's Laplacian isotropic too): the iliacs'
    // tubes still part below the truth's carina (its junction's shape is modelled, not measured:
    // issue 21's 3h not met here).
    assert!(hd <= 10.5, "{hd}h");
    assert!(ve <= 0.12, "{ve}");
}

/// Region D (centre, radius) of the capped aorta's chop#1 in the benchmark's draw of seed 29,
/// over the whole front of the bifurcation: the two tests below repair it.
const SEED29_JUNCTION_CHOP: ([f64; 3], f64) = (
    [222.9602717458809, 131.77253662387804, 28.718339448262288],
    13.971884731559433,
);

/// The benchmark's chop#1 of the capped aorta in the draw of seed 29 (held out): a hole over the
/// whole front of the bifurcation. The hole's cap dents the lumen and the damaged skeleton
/// sprouts spurs, ten junctions in E; the one nearest the anchors, a spur's (inscribed radius
/// 1.24 where the iliacs' are 4.1), stood 11.7 mm from the truth's, and the trunk was led across
/// the right iliac's lumen to it: 15.79h, and the gap between that lumen and the strip of wall
/// the hole left ran through the vessel, a tunnel (the output's genus 1, the truth's 0), closed
/// by `inpaint::tunnel`. The junction is now the nearest one as wide as half the narrowest
/// anchor (`guided::JUNCTION_MIN_RADIUS`; 4.35, 7.0 mm from the truth's), and the fill leaves
/// no tunnel (`chop_and_repair` checks the genus).
#[test]
fn a_junction_chop_joins_the_branches_at_the_bifurcation_not_at_a_spur() {
    let (hd, ve, report) = bench_chop(
        "aorta_abdominal_capped.stl",
        SEED29_JUNCTION_CHOP.0,
        SEED29_JUNCTION_CHOP.1,
        "junction",
    );
    let notices = report["notices"].to_string();
    assert!(!notices.contains("tunnel"), "{notices}");
    // 8.69h / −9.3% measured (MeshLib 10.51h): the trunk's top wall still sags 3 mm over the
    // hole towards the junction, which lies 2.3 mm below the truth's (issue 21's 3h not met
    // here).
    assert!(hd <= 10.0, "{hd}h");
    assert!(ve.abs() <= 0.11, "{ve}");
}

/// The same chop filled along the axis (`--method axial`), which joins the two sides of D
/// across the bifurcation: the fill leaves a tunnel through the vessel (genus 1, the truth's 0),
/// and the field is closed in D by the smallest closing that removes it (`inpaint::tunnel`),
/// with a notice.
#[test]
fn a_tunnel_left_by_the_fill_is_closed() {
    let (_, _, report) = bench_chop_with(
        "aorta_abdominal_capped.stl",
        SEED29_JUNCTION_CHOP.0,
        SEED29_JUNCTION_CHOP.1,
        "axial",
        "--holes --method axial",
    );
    let notices = report["notices"].to_string();
    assert!(
        notices.contains("the fill left a tunnel through the vessel in D")
            && notices.contains("closed by a morphological closing"),
        "{notices}"
    );
}

/// The benchmark's chop#1 of the open aorta in the draw of seed 25: a hole in the aorta's top
/// wall over the bifurcation, filled as a junction. Towards the junction point the wall chart's
/// biharmonic fill carried the readings' slope on past the last of them and swelled one
/// iliac's section to 2.3 times its radius: a bulge 2 mm above the aorta's top wall (8.2h in the
/// benchmark's measure). Filled details are now held to 0.8 radii outward (`MAX_FILLED_BULGE`),
/// and the union of tubes has its bumps shaved (`inpaint::shave`); a junction branch's chart
/// is held taut beyond a radius (`guided::JUNCTION_CHART_TENSION`), so that the slope past the
/// last reading is not carried on.
#[test]
fn a_junction_fill_does_not_bulge_over_the_aortas_top_wall() {
    let (hd, ve, _) = bench_chop(
        "aorta_abdominal_open_ends.stl",
        [221.420188694023, 139.57846073912825, 30.69293311715652],
        13.495492507156944,
        "junction",
    );
    // 3.11h and +1.4% measured (3.53h and +1.9% with the junction branches' equal Hermite
    // tangents, 4.24h and +2.9% with the wall chart's Laplacian isotropic too; 4.82h and +3.9%
    // with a thin-plate chart, 6.26h and +4.8% unshaved too, 8.24h and +6.1% unbounded too).
    // Still beyond issue 21's 3h: the junction's shape is modelled, not measured.
    assert!(hd <= 4.75, "{hd}h");
    assert!(ve.abs() <= 0.035, "{ve}");
}

#[test]
fn the_inward_capped_aorta_is_repaired_outward() {
    let dir = tempfile::tempdir().unwrap();
    let input = read_mesh(&data_dir().join("aorta_abdominal_capped.stl")).unwrap();
    assert!(
        mesh_info(&input).signed_volume < 0.0,
        "the file is stored inward"
    );
    let (hd, ve, report) = chop_and_repair(
        "aorta_abdominal_capped.stl",
        [235.8, 115.4, 26.52],
        6.717,
        "--holes",
        dir.path(),
    );
    let notices = report["notices"].to_string();
    assert!(notices.contains("faced inward"), "{notices}");
    // Issue 21 asks for 1.5h (0.83h measured since 2026-12-07, the recentred curve fading out at
    // its ends (0.86h while the fade was half a radius whatever the offsets), 0.76h before; 0.69h with the wall chart's Laplacian isotropic, 0.84h while the
    // chart's rays stopped at the hole's cap, which hides intact wall beside a rim that is not
    // planar); the damaged input is 20.2h / −11.9%.
    assert!(hd <= 1.0, "{hd}h");
    assert!(ve.abs() <= 0.05, "{ve}");
}

#[test]
fn the_readme_first_command_repairs_the_shipped_hole() {
    // The README's first command, on data/aorta_abdominal_open_ends_hole.stl (the chop above,
    // shipped): the hole found and filled, the three ends capped, every output written.
    let readme = std::fs::read_to_string(data_dir().join("../README.md")).unwrap();
    let line = readme
        .lines()
        .find(|l| l.starts_with("cargo run --release -- repair "))
        .expect("the README's first command");
    let dir = tempfile::tempdir().unwrap();
    let args: Vec<String> = line
        .split_whitespace()
        .skip(4)
        .map(|a| match a {
            a if a.starts_with("data/") => data_dir().join(&a[5..]).to_string_lossy().into(),
            a if a.starts_with("aorta_") => dir.path().join(a).to_string_lossy().into(),
            a => a.to_string(),
        })
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let run = vesselmsr(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert_eq!(stdout.matches(": hole").count(), 1, "{stdout}");
    assert_eq!(stdout.matches("open vessel end").count(), 3, "{stdout}");
    for out in [
        "aorta_repaired.stl",
        "aorta_report.json",
        "aorta_repair.png",
    ] {
        assert!(dir.path().join(out).is_file(), "{out} not written");
    }
    let repaired = read_mesh(&dir.path().join("aorta_repaired.stl")).unwrap();
    let info = mesh_info(&repaired);
    assert!(info.watertight && info.signed_volume > 0.0);
}

#[test]
fn stenoses_on_a_vessel_without_a_narrowing_write_it_and_say_so() {
    // Like --holes on a mesh with no hole: exit 0, the mesh written (ends capped), a notice.
    let dir = tempfile::tempdir().unwrap();
    let (out, report) = (dir.path().join("out.stl"), dir.path().join("r.json"));
    let mesh = data_dir().join("aorta_abdominal_open_ends.stl");
    let run = vesselmsr(&[
        "repair",
        mesh.to_str().unwrap(),
        "--stenoses",
        "-o",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert!(
        report["notices"].to_string().contains("no narrowing"),
        "{report}"
    );
    assert!(mesh_info(&read_mesh(&out).unwrap()).watertight);
}

#[test]
fn a_narrowing_of_the_capped_aorta_is_widened_to_its_own_shape() {
    // The benchmark repair_real's 50% narrowing of this vessel (seed 21), repaired by `repair
    // --stenoses 30` and judged in D = the ball of 3σ: the fill keeps the narrowed wall's own
    // cross-section shape at the healthy size, along the narrowed lumen's own centreline
    // (4.40h / −1.9% with a circular section, 2.18h with a cubic between the shoulders, 0.83h /
    // −2.5% bridged between anchors at ∂D, 0.81h / −2.5% widened to the healthy reference: `widen`).
    let (truth, damaged, d) = narrowed("aorta_abdominal_capped.stl", [230.46, 118.04, 25.3]);
    let (before, hd, ve) = repair_in(
        &damaged,
        &truth,
        d,
        "--stenoses=30",
        "narrowed capped aorta",
    );
    assert!(before > 5.0, "the narrowing is {before}h deep");
    assert!(hd <= 1.5, "{hd}h");
    assert!(ve.abs() <= 0.05, "{ve}");
}

#[test]
fn a_narrowing_beside_a_junction_and_a_closed_end_is_widened_not_the_carina() {
    // The held-out case of repair_real (seed 23): the left iliac narrowed 4 radii from the
    // aortic bifurcation, its D (3σ) reaching the junction and the branch's closed end. Bridged
    // between anchors at ∂D, the far anchor lay on the closed end's taper and was dropped as a
    // spur: the fill webbed the carina and left the narrowing (11.35h / −21.3%, the output still
    // 46% narrowed). Widened to the healthy reference between its shoulders (`widen`): 1.71h.
    let (truth, damaged, d) = narrowed("aorta_abdominal_capped.stl", [214.19, 119.13, 27.74]);
    let dir = tempfile::tempdir().unwrap();
    let (_, report) = repair_by_cli(&damaged, "--stenoses=30", dir.path());
    assert_eq!(report["regions"][0]["fill"], "widened", "{report}");
    let residual = report["regions"][0]["residual_stenosis_pct"]
        .as_f64()
        .unwrap();
    assert!(residual.abs() < 5.0, "{residual}% left");
    assert!(
        !report["notices"].to_string().contains("not restored"),
        "{}",
        report["notices"]
    );
    let (before, hd, ve) = repair_in(
        &damaged,
        &truth,
        d,
        "--stenoses=30",
        "narrowed iliac beside the carina",
    );
    assert!(before > 5.0, "the narrowing is {before}h deep");
    assert!(hd <= 3.0, "{hd}h");
    assert!(ve.abs() <= 0.10, "{ve}");
}

/// The benchmark repair_real's 50% narrowing of `file` (data/) at the centreline point nearest
/// to `p0` (σ = 1.2 R, R the inscribed radius there): every vertex whose nearest branch is this
/// one, within 2.5 R of it and 4σ along it, moved towards its projection c(s) on the branch
/// polyline, v ← c + (v − c)·(1 − 0.5·exp(−(s − s₀)²/(2σ²))). The truth, the damaged mesh and
/// D = the ball of 3σ on the point.
fn narrowed(file: &str, p0: [f64; 3]) -> (TriMesh, TriMesh, Ball) {
    let (truth, cl, b, k) = centreline_site(file, p0);
    let pts = &cl.branches[b].points;
    let r = cl.branches[b].radius[k];
    let sigma = 1.2 * r;
    let mut arc = vec![0.0];
    for w in pts.windows(2) {
        arc.push(arc.last().unwrap() + (w[1] - w[0]).norm());
    }
    let s0 = arc[k];
    let mut damaged = truth.clone();
    for v in damaged.vertices.iter_mut() {
        // Nearest point of the branch polyline and its arc length.
        let (c, s) = pts
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                let e = w[1] - w[0];
                let u = ((*v - w[0]).dot(&e) / e.norm_squared().max(1e-300)).clamp(0.0, 1.0);
                (w[0] + e * u, arc[i] + u * e.norm())
            })
            .min_by(|x, y| (x.0 - *v).norm().total_cmp(&(y.0 - *v).norm()))
            .unwrap();
        // Only the vertices whose nearest branch is this one.
        let mine = (*v - c).norm();
        let other = cl
            .branches
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != b)
            .flat_map(|(_, br)| br.points.iter())
            .map(|q| (*v - q).norm())
            .fold(f64::INFINITY, f64::min);
        if mine < 2.5 * r && mine <= other && (s - s0).abs() < 4.0 * sigma {
            let g = (-(s - s0).powi(2) / (2.0 * sigma * sigma)).exp();
            *v = c + (*v - c) * (1.0 - 0.5 * g);
        }
    }
    let d = Ball {
        center: pts[k],
        radius: 3.0 * sigma,
    };
    (truth, damaged, d)
}

/// `file` (data/), its centreline, and the (branch, point index) of the centreline point
/// nearest to `p0`: where a damage of the benchmark repair_real is made.
fn centreline_site(
    file: &str,
    p0: [f64; 3],
) -> (TriMesh, vesselmsr::centerline::Centerline, usize, usize) {
    let truth = read_mesh(&data_dir().join(file)).unwrap();
    let (cl, _) = vesselmsr::centerline::compute_centerline(
        &truth,
        &vesselmsr::centerline::CenterlineOptions::default(),
    )
    .unwrap();
    let p0 = Point3::from(p0);
    let (b, k) = cl
        .branches
        .iter()
        .enumerate()
        .flat_map(|(b, br)| br.points.iter().enumerate().map(move |(k, p)| (b, k, p)))
        .min_by(|x, y| (x.2 - p0).norm().total_cmp(&(y.2 - p0).norm()))
        .map(|(b, k, _)| (b, k))
        .unwrap();
    (truth, cl, b, k)
}

/// `damaged` repaired by `repair FLAG` (watertight), judged in `d` against `truth`: the damaged
/// input's and the repair's Hausdorff distance in voxels and the repair's volume error.
fn repair_in(
    damaged: &TriMesh,
    truth: &TriMesh,
    d: Ball,
    flag: &str,
    what: &str,
) -> (f64, f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let (repaired, report) = repair_by_cli(damaged, flag, dir.path());
    assert!(mesh_info(&repaired).watertight);
    let h = report["parameters"]["voxel"].as_f64().unwrap();
    let before = hausdorff_in(damaged, truth, &[d]) / h;
    let hd = hausdorff_in(&repaired, truth, &[d]) / h;
    let ve = volume_error_in(&repaired, truth, &[d]);
    println!(
        "{what}: damaged {before:.2}h, repaired {hd:.2}h / {:+.1}% in D",
        100.0 * ve
    );
    (before, hd, ve)
}

#[test]
fn an_occlusion_of_the_open_aorta_carries_the_wall_across_the_gap() {
    // The benchmark repair_real's occlusion of this vessel: every triangle with a vertex in the
    // slab |(v − p)·t| < R/2, |v − p| < 2R across the lumen (p a centreline point of the intact
    // file, t its tangent, R its inscribed radius), repaired by `repair --region p,1.5R`. The
    // vessel is cut in two: its two ends are bridged, and the wall the tube reads inside D is on
    // either end's branch (3.85h / −3.2% in D while only the first end's wall was read: the
    // truth's lobe on both sides of the gap was lost, the section across the gap round; now
    // 2.33h / +1.6%, 1.94h / +0.2% with the harmonic fill of the wall's offsets).
    let (truth, cl, b, k) = centreline_site("aorta_abdominal_open_ends.stl", [214.5, 121.4, 27.16]);
    let (p, t, r) = (
        cl.branches[b].points[k],
        cl.branches[b].tangent[k].normalize(),
        cl.branches[b].radius[k],
    );
    let faces = truth
        .faces
        .iter()
        .filter(|f| {
            !f.iter().any(|&i| {
                let q = truth.vertices[i as usize] - p;
                q.dot(&t).abs() < 0.5 * r && q.norm() < 2.0 * r
            })
        })
        .copied()
        .collect();
    let damaged = TriMesh::new(truth.vertices.clone(), faces);
    let d = Ball {
        center: p,
        radius: 1.5 * r,
    };
    let region = format!("--region={},{},{},{}", p.x, p.y, p.z, d.radius);
    let (before, hd, ve) = repair_in(&damaged, &truth, d, &region, "occluded open aorta");
    assert!(before > 5.0, "the occlusion is {before}h deep");
    assert!(hd <= 2.5, "{hd}h");
    assert!(ve.abs() <= 0.02, "{ve}");
}
