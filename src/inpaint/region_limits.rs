//! Limits on the regions D of a vessel repair: repeated balls (the same ball listed twice, or a ball
//! inside another) are dropped with a notice, and more than [`MAX_REGIONS`] distinct balls are
//! refused, naming where they came from (each ball costs a pass over the grid around D). Balls
//! are checked against the mesh per source, so a bad ball of a regions file is reported with the
//! JSON file's name.

use super::region::{validate_regions, Ball};
use crate::mesh::weld::weld_key;
use crate::{Error, Result, TriMesh};
use std::collections::HashSet;

/// Most distinct regions a repair takes.
pub const MAX_REGIONS: usize = 100;

/// Above this many distinct balls the containment test (quadratic) is not tried: the count is
/// refused anyway.
const MAX_COMPARED: usize = 20 * MAX_REGIONS;

/// Checks each source's balls against `mesh` (errors name the source: the regions file, or the
/// mesh for the others), then drops repeated balls in place (with their sources) and refuses
/// more than [`MAX_REGIONS`]; the notice of dropped balls goes to `notice`.
pub fn check_regions(
    mesh: &TriMesh,
    mesh_name: &str,
    balls: &mut Vec<Ball>,
    sources: &mut Vec<String>,
    notice: &mut dyn FnMut(&str),
) -> Result<()> {
    let mut names: Vec<&String> = Vec::new();
    for s in sources.iter() {
        if !names.contains(&s) {
            names.push(s);
        }
    }
    for name in names {
        let group: Vec<Ball> = balls
            .iter()
            .zip(sources.iter())
            .filter(|(_, s)| *s == name)
            .map(|(b, _)| *b)
            .collect();
        // "regions file X" names X; the others are about the mesh.
        let about = name.strip_prefix("regions file ").unwrap_or(mesh_name);
        validate_regions(mesh, &group).map_err(|e| e.context(about))?;
    }
    let before = balls.len();
    let mut seen = HashSet::new();
    let mut keep: Vec<bool> = balls
        .iter()
        .map(|b| seen.insert((weld_key(b.center.into()), b.radius.to_bits())))
        .collect();
    let distinct = keep.iter().filter(|&&k| k).count();
    if distinct <= MAX_COMPARED {
        for i in 0..balls.len() {
            if !keep[i] {
                continue;
            }
            let inside = |j: usize| {
                j != i
                    && keep[j]
                    && (balls[i].center - balls[j].center).norm() + balls[i].radius
                        <= balls[j].radius
                    // Of two equal balls the first is kept.
                    && (balls[i].radius < balls[j].radius || j < i)
            };
            if (0..balls.len()).any(inside) {
                keep[i] = false;
            }
        }
    }
    let mut k = keep.iter();
    balls.retain(|_| *k.next().unwrap_or(&true));
    let mut k = keep.iter();
    sources.retain(|_| *k.next().unwrap_or(&true));
    if balls.len() < before {
        notice(&format!(
            "{} of the {before} regions repeat another or lie inside another and were dropped",
            before - balls.len()
        ));
    }
    if balls.len() > MAX_REGIONS {
        let mut from: Vec<&str> = sources.iter().map(String::as_str).collect();
        from.dedup();
        return Err(Error::Refused(format!(
            "{} distinct regions ({}): at most {MAX_REGIONS} are repaired at once; merge them \
             into fewer, larger balls",
            balls.len(),
            from.join(", ")
        )));
    }
    Ok(())
}
