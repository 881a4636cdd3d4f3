//! The whole repair of a vessel mesh as `vesselmsr repair` runs it, between reading the mesh and
//! writing the outputs; the CLI (which reads the file, writes the mesh, the report and the
//! picture) and the Python package (numpy arrays in and out) both call [`repair_vessel`].
//!
//! 1. The regions D: the balls given, those of a regions (or 3D Slicer markups) file, with
//!    `holes` every boundary loop that is not an open vessel end, with `stenoses` every
//!    narrowing of the input's centreline of at least that degree; checked against the mesh,
//!    repeats dropped, at most [`MAX_REGIONS`].
//! 2. The memory check of the grids ([`super::repair_budget`]), then the repair
//!    ([`super::repair::repair_with_centerline`]); asked for holes or narrowings and none found,
//!    the input as it is (ends capped unless kept open, outward) with a notice. The input's
//!    centreline is traced first when the regions are read on it (a regions file, `stenoses`);
//!    otherwise on a thread of its own while the repair caps and voxelizes the input (the two
//!    grids are then held at once), and the fill waits for it.
//! 3. Optionally the quadric simplification within a fraction of the voxel, then the report
//!    ([`RepairReport`]): volumes, per region the inpainted volume and the stenosis, the loops,
//!    the parameters and timings. An output that is not watertight (ends not kept open) is an
//!    error.

use super::holes::{classify_loops, gap_regions, hole_balls, LoopInfo, LoopKind, LoopOptions};
use super::region::{read_regions, Ball, PickedSite};
use super::region_limits::check_regions;
pub use super::region_limits::MAX_REGIONS;
use super::repair::{repair_awaiting, Repair, RepairOptions};
use super::repair_budget;
use crate::centerline::healthy::HealthyVessel;
use crate::centerline::stenosis::StenosisFindOptions;
use crate::centerline::{compute_centerline, CenterlineOptions};
use crate::error::short_number;
use crate::mesh::cap::{cap_holes, CapOptions};
use crate::mesh::decimate::{decimate_mesh, DecimateOptions};
use crate::mesh::info::mesh_info;
use crate::mesh::measures::signed_volume;
use crate::mesh::orient::orient_outward;
use crate::mesh::topology::EdgeMap;
use crate::mesh::units::{check_vessel_scale, VesselScaleOptions};
use crate::report::repair_report::{
    discount_cap_outside, is_stenosis_source, modelled_junction, region_reports, stopped_vessel,
    surface_measures, unrestored_narrowing, LoopReport, MeshPart, RepairParameters, RepairReport,
    DETECTED_STENOSIS, PICKED_STENOSIS,
};
use crate::{Error, Result, TriMesh};
use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};
use std::thread::{Scope, ScopedJoinHandle};
use std::time::Instant;

/// A point picked on a narrowing of at least this stenosis (NASCET, %) chooses that narrowing's
/// region (`--stenoses`'s default threshold).
pub const PICKED_STENOSIS_MIN_PCT: f64 = 20.0;

/// What to repair and how: the regions' sources and the options of `vesselmsr repair`.
#[derive(Debug, Clone)]
pub struct VesselRepair {
    /// Regions D given as balls (`--region`).
    pub balls: Vec<Ball>,
    /// A regions file, JSON or 3D Slicer markups (`--regions`).
    pub regions_file: Option<PathBuf>,
    /// Every boundary loop that is not an open vessel end becomes a region (`--holes`).
    pub holes: bool,
    /// Every narrowing of at least this many percent becomes a region (`--stenoses`).
    pub stenoses: Option<f64>,
    /// Simplify the output within this many voxels (`--decimate`).
    pub decimate: Option<f64>,
    /// The name of the file's length unit, for the report and the scale check (`--units`).
    pub units: String,
    /// The repair itself: method, voxel, kept outside and open ends, c, T, ε, iterations.
    pub options: RepairOptions,
    /// The memory budget, bytes (`--max-memory`).
    pub max_memory: u64,
    /// The input's file, when it came from one: the report's `input.path`, and the name in
    /// messages (else "mesh").
    pub input_path: Option<String>,
    /// The output's file, when it goes to one: the report's `output.path`.
    pub output_path: Option<String>,
}

impl Default for VesselRepair {
    fn default() -> Self {
        VesselRepair {
            balls: Vec::new(),
            regions_file: None,
            holes: false,
            stenoses: None,
            decimate: None,
            units: "file units".into(),
            options: RepairOptions::default(),
            max_memory: crate::budget::default_max_memory(),
            input_path: None,
            output_path: None,
        }
    }
}

impl VesselRepair {
    /// The mesh's name in messages.
    pub fn name(&self) -> &str {
        self.input_path.as_deref().unwrap_or("mesh")
    }

    /// Whether the regions are read on the input's centreline (a regions file's picked points
    /// are sized by it, `stenoses` are found on it).
    fn regions_need_centreline(&self) -> bool {
        self.regions_file.is_some() || self.stenoses.is_some()
    }

    /// Checks the options ([`Error::BadOption`] naming the field: `speed`, `time`, `epsilon`,
    /// `decimate`, `voxel`, `stenoses`, or `regions` when there is nothing to repair).
    pub fn validate(&self) -> Result<()> {
        let bad = |option: &'static str, problem: String| Err(Error::BadOption { option, problem });
        let o = &self.options;
        for (name, v) in [("speed", o.speed), ("time", o.time), ("epsilon", o.epsilon)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return bad(name, format!("must be > 0, got {v}"));
                }
            }
        }
        if let Some(v) = self.decimate {
            if !(v.is_finite() && v > 0.0) {
                return bad(
                    "decimate",
                    format!("must be a positive number of voxels, got {v}"),
                );
            }
        }
        if let Some(v) = o.voxel {
            if !(v.is_finite() && v > 0.0) {
                return bad("voxel", format!("must be a positive length, got {v}"));
            }
        }
        if self.balls.is_empty()
            && self.regions_file.is_none()
            && !self.holes
            && self.stenoses.is_none()
        {
            return bad(
                "regions",
                "none given: nothing to repair (give regions, holes or stenoses)".into(),
            );
        }
        if let Some(p) = self.stenoses {
            if !(p.is_finite() && (0.0..100.0).contains(&p)) {
                return bad(
                    "stenoses",
                    format!("must be a percentage from 0 to below 100, got {p}"),
                );
            }
        }
        Ok(())
    }
}

/// What [`repair_vessel`] tells while it works.
#[derive(Debug, Clone, Copy)]
pub enum RepairEvent<'a> {
    /// A one-line notice (the CLI prints it on stderr).
    Notice(&'a str),
    /// The stage starting: "repairing", "decimating", "measuring".
    Stage(&'static str),
}

/// The repaired vessel and its report.
#[derive(Debug, Clone)]
pub struct RepairedVessel {
    /// The repaired mesh (closed unless the ends were kept open, outward).
    pub mesh: TriMesh,
    /// The report (`repair --report`); its timings have no `read`.
    pub report: RepairReport,
    /// The regions D repaired (empty when holes or narrowings were asked for and none found).
    pub balls: Vec<Ball>,
    /// The notices of the repair itself (also in the report's `notices`).
    pub repair_notices: Vec<String>,
}

/// Repairs `mesh` as `request` says (see the module doc). Errors name the mesh
/// ([`VesselRepair::name`]); notices and stages go to `events`.
pub fn repair_vessel(
    mesh: &TriMesh,
    request: &VesselRepair,
    events: &mut dyn FnMut(RepairEvent),
) -> Result<RepairedVessel> {
    request.validate()?;
    // The regions of a regions file (picked points) and of `stenoses` are read on the
    // centreline: it is traced first. Otherwise it is traced on a thread of its own while the
    // repair caps and voxelizes the input, and waited for when the fill needs it (one thread
    // asked for: in turn). The outputs are the same either way.
    let meanwhile = !request.regions_need_centreline() && rayon::current_num_threads() > 1;
    std::thread::scope(|scope| {
        let traced = TracedCentreline::start(scope, mesh, meanwhile);
        repair_traced(mesh, request, events, &traced)
    })
}

/// The input's centreline with its diameter profiles and healthy references (or why there is
/// none), and the seconds its tracing took.
type Traced = (Result<HealthyVessel>, f64);

fn trace(mesh: &TriMesh) -> Traced {
    let start = Instant::now();
    let healthy = compute_centerline(mesh, &CenterlineOptions::default())
        .map(|(cl, _)| HealthyVessel::new(mesh, cl, &StenosisFindOptions::default()));
    (healthy, start.elapsed().as_secs_f64())
}

/// The input's centreline, traced at once or on a scoped thread meanwhile.
struct TracedCentreline<'scope> {
    pending: Mutex<Option<ScopedJoinHandle<'scope, Traced>>>,
    done: OnceLock<Traced>,
}

impl<'scope> TracedCentreline<'scope> {
    fn start<'env>(
        scope: &'scope Scope<'scope, 'env>,
        mesh: &'env TriMesh,
        meanwhile: bool,
    ) -> Self {
        let done = OnceLock::new();
        let pending = if meanwhile {
            Some(scope.spawn(move || trace(mesh)))
        } else {
            let _ = done.set(trace(mesh));
            None
        };
        TracedCentreline {
            pending: Mutex::new(pending),
            done,
        }
    }

    /// The centreline, waited for if it is being traced.
    fn get(&self) -> &Traced {
        self.done.get_or_init(|| {
            let handle = self
                .pending
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take()
                .expect("a centreline neither traced nor pending");
            handle
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        })
    }

    fn healthy(&self) -> Option<&HealthyVessel> {
        self.get().0.as_ref().ok()
    }
}

fn repair_traced(
    mesh: &TriMesh,
    request: &VesselRepair,
    events: &mut dyn FnMut(RepairEvent),
    traced: &TracedCentreline,
) -> Result<RepairedVessel> {
    let name = request.name();
    let mut balls: Vec<Ball> = request.balls.clone();
    let mut sources: Vec<String> = vec!["region".to_string(); balls.len()];
    let mut notices = Vec::new();
    if let Some(n) = check_vessel_scale(mesh, &request.units, &VesselScaleOptions::default()) {
        notices.push(n);
    }
    // The input's centreline: healthy radii for picked points, detected narrowings, the fill,
    // and the stenosis measured along it in the report.
    // A centreline that failed is told once: before the regions read on it, else after the
    // repair that waited for it.
    let no_centreline = |events: &mut dyn FnMut(RepairEvent)| {
        if let Err(e) = &traced.get().0 {
            events(RepairEvent::Notice(&format!(
                "{name}: no centreline ({e}); regions are sized and measured without it"
            )));
        }
    };
    if request.regions_need_centreline() {
        no_centreline(events);
    }
    if let Some(path) = &request.regions_file {
        let site = |p: &nalgebra::Point3<f64>| {
            let h = traced.healthy()?;
            match h.lesion_region_at(p, PICKED_STENOSIS_MIN_PCT) {
                Some(ball) => Some(PickedSite::Narrowing(ball)),
                None => h.healthy_radius(p).map(PickedSite::Radius),
            }
        };
        for r in read_regions(path, mesh, &site)? {
            balls.push(r.ball);
            sources.push(if r.narrowing {
                PICKED_STENOSIS.to_string()
            } else {
                format!("regions file {}", path.display())
            });
        }
    }
    if let Some(p) = request.stenoses {
        let found = traced
            .healthy()
            .map(|h| h.lesion_regions(p))
            .unwrap_or_default();
        if found.is_empty() {
            notices.push(format!("no narrowing of {p}% or more found"));
        }
        for b in found {
            balls.push(b);
            sources.push(DETECTED_STENOSIS.into());
        }
    }
    let mut loops = Vec::new();
    if request.holes {
        let infos = classify_loops(mesh, &LoopOptions::default());
        let (gaps, gap_balls) = gap_regions(mesh, &infos, &LoopOptions::default());
        let in_gap = |i: usize| gaps.iter().any(|g| g.contains(&i));
        let at = |l: &LoopInfo| {
            let [x, y, z] = [l.center.x, l.center.y, l.center.z].map(short_number);
            format!("({x}, {y}, {z})")
        };
        for (i, l) in infos.iter().enumerate() {
            if l.is_rough_end() && !in_gap(i) {
                notices.push(format!(
                    "the loop at {} is taken for an open vessel end, yet lies {:.0}% of its \
                     radius off its plane (clipped ends: under 1%): if the damage cut the vessel \
                     there, what lay beyond is not restored",
                    at(l),
                    100.0 * l.planarity,
                ));
            }
        }
        for g in &gaps {
            let ends: Vec<String> = g.iter().map(|&i| at(&infos[i])).collect();
            notices.push(format!(
                "the loops at {} are not planar as clipped ends are, and face each other: taken \
                 for a vessel the damage cut through, its pieces kept, and bridged across the gap",
                ends.join(" and "),
            ));
        }
        // A hole that is one side of a gap is bridged with it, not filled on its own.
        let holes_alone: Vec<LoopInfo> = infos
            .iter()
            .enumerate()
            .filter(|&(i, l)| l.kind == LoopKind::Hole && !in_gap(i))
            .map(|(_, l)| l.clone())
            .collect();
        if !holes_alone.is_empty() {
            let holes = hole_balls(&holes_alone, &LoopOptions::default())
                .map_err(|e| e.context(format!("{name}: --holes")))?;
            for b in holes {
                balls.push(b);
                sources.push("hole".into());
            }
        } else if gap_balls.is_empty() {
            notices.push(if infos.is_empty() {
                "no holes found (the mesh is closed): nothing to inpaint".to_string()
            } else {
                format!(
                    "no holes found ({} boundary loop(s), all open vessel ends): nothing to inpaint{}",
                    infos.len(),
                    if request.options.open_ends { "" } else { "; the ends are capped" }
                )
            });
        }
        for b in gap_balls {
            balls.push(b);
            sources.push("gap".into());
        }
        loops = infos
            .iter()
            .enumerate()
            .map(|(i, l)| LoopReport {
                kind: match l.kind {
                    _ if in_gap(i) => "cut end",
                    LoopKind::End => "open vessel end",
                    LoopKind::Hole => "hole",
                },
                center: [l.center.x, l.center.y, l.center.z],
                radius: l.radius,
                planarity: l.planarity,
            })
            .collect();
    }
    // Asked to find holes or narrowings and none found: the mesh is given back as it is (ends
    // capped), with a report saying so (a script over a cohort goes on).
    let nothing_to_do = (request.holes || request.stenoses.is_some()) && balls.is_empty();
    if !nothing_to_do {
        check_regions(mesh, name, &mut balls, &mut sources, &mut |n| {
            events(RepairEvent::Notice(n))
        })?;
    }
    for n in &notices {
        events(RepairEvent::Notice(&format!("{name}: {n}")));
    }
    // The narrowings' regions hold an intact lumen: the fill may follow their centreline.
    let opts = &RepairOptions {
        intact_lumen: sources.iter().map(|s| is_stenosis_source(s)).collect(),
        max_memory: Some(request.max_memory),
        ..request.options.clone()
    };
    repair_budget::check(mesh, &balls, opts, request.max_memory).map_err(|e| e.context(name))?;
    events(RepairEvent::Stage("repairing"));
    let mut result = if nothing_to_do {
        unrepaired(mesh, opts)
    } else {
        repair_awaiting(mesh, &balls, opts, &|| traced.healthy())
    }
    .map_err(|e| e.context(format!("{name}: repair failed")))?;
    if !request.regions_need_centreline() {
        no_centreline(events);
    }
    let (healthy, centerline_secs) = (traced.healthy(), traced.get().1);
    let decimate = match request.decimate {
        Some(voxels) if result.voxel > 0.0 => {
            events(RepairEvent::Stage("decimating"));
            let (lean, done) = decimate_mesh(
                &result.mesh,
                &DecimateOptions {
                    max_distance: voxels * result.voxel,
                    ..DecimateOptions::default()
                },
            );
            result.mesh = lean;
            // The output's winding number and volumes were the undecimated mesh's.
            result.measured = None;
            Some(done)
        }
        _ => None,
    };
    events(RepairEvent::Stage("measuring"));
    let measure_start = Instant::now();
    let mut regions = region_reports(
        &result.closed_input,
        &result.mesh,
        &balls,
        &sources,
        healthy,
        result.measured.as_ref().map(|(i, o)| [i, o]),
    );
    for (region, &fill) in regions.iter_mut().zip(&result.region_fill) {
        region.fill = Some(fill);
    }
    // What only a hole's cap held outside the vessel is no volume of the input's.
    let output_volume = signed_volume(&result.mesh);
    for (k, (region, &outside)) in regions.iter_mut().zip(&result.cap_outside).enumerate() {
        if let Some(notice) = discount_cap_outside(k + 1, region, outside, output_volume) {
            result.notices.push(notice);
        }
    }
    // A narrowing left narrowed, a junction's shape estimated, a vessel that stops in D: no
    // silent failure.
    for (k, region) in regions.iter().enumerate() {
        let notices = [
            unrestored_narrowing(k + 1, region),
            modelled_junction(k + 1, region),
            stopped_vessel(k + 1, region),
        ];
        result.notices.extend(notices.into_iter().flatten());
    }
    let info = mesh_info(&result.mesh);
    let input_info = mesh_info(&result.closed_input);
    // A vessel left in pieces is told, not only counted (a gap no region bridged).
    if info.components > 1 {
        result.notices.push(format!(
            "the output is in {} pieces (the input in {}): pieces the damage cut apart stay \
             apart where no region bridges them",
            info.components, input_info.components
        ));
    }
    let measure_secs = measure_start.elapsed().as_secs_f64();
    let mut timings = serde_json::Map::new();
    timings.insert("centerline".into(), centerline_secs.into());
    for (phase, secs) in &result.timings {
        timings.insert(phase.clone(), (*secs).into());
    }
    timings.insert("report".into(), measure_secs.into());
    notices.extend(result.notices.iter().cloned());
    let report = RepairReport {
        units: request.units.clone(),
        notices,
        input: MeshPart {
            path: request.input_path.clone(),
            measures: surface_measures(&input_info),
        },
        input_capped: result.closed_input.num_faces() != mesh.num_faces(),
        output: MeshPart {
            path: request.output_path.clone(),
            measures: surface_measures(&info),
        },
        regions,
        loops,
        decimate,
        watertight: info.watertight,
        iterations: result.iterations,
        converged: result.converged,
        parameters: RepairParameters {
            method: opts.method.as_str(),
            voxel: result.voxel,
            grid_dims: result.grid_dims,
            patch_voxel: result.patch_voxel,
            radius_estimate: result.radius_estimate,
            c: result.speed,
            time: result.time,
            epsilon: result.epsilon,
            keep_outside: opts.keep_outside,
            open_ends: opts.open_ends,
            stitched: result.stitched,
            stitch_beyond: result.stitch_beyond,
            junctions: result.junctions,
            fallback: result.fallback.clone(),
            axes: result.axes.clone(),
            guides: result.guides.clone(),
        },
        timings,
    };
    if !(info.watertight || opts.open_ends) {
        return Err(Error::Geometry(format!(
            "{name}: the repaired mesh is not watertight ({}); no output",
            info.leaks().join(", ")
        )));
    }
    Ok(RepairedVessel {
        mesh: result.mesh,
        report,
        balls,
        repair_notices: result.notices,
    })
}

/// The outcome of `holes` or `stenoses` on a mesh without either: the input, its open ends
/// capped unless they are kept open, outward; nothing inpainted.
fn unrepaired(mesh: &TriMesh, opts: &RepairOptions) -> Result<Repair> {
    let start = Instant::now();
    let closed_input = if opts.open_ends || EdgeMap::new(mesh).boundary_edges() == 0 {
        mesh.clone()
    } else {
        cap_holes(mesh, &CapOptions::default())?.0
    };
    let mut output = closed_input.clone();
    if !opts.open_ends {
        orient_outward(&mut output);
    }
    Ok(Repair {
        mesh: output,
        closed_input,
        voxel: 0.0,
        grid_dims: [0; 3],
        patch_voxel: 0.0,
        radius_estimate: 0.0,
        speed: 0.0,
        time: 0.0,
        epsilon: 0.0,
        axes: Vec::new(),
        junctions: 0,
        iterations: 0,
        converged: true,
        stitched: false,
        stitch_beyond: 0.0,
        fallback: None,
        guides: Vec::new(),
        region_fill: Vec::new(),
        notices: Vec::new(),
        timings: vec![("cap".into(), start.elapsed().as_secs_f64())],
        measured: None,
        cap_outside: Vec::new(),
    })
}
