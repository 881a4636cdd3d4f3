//! Repair on real damage against peer tools, side by side in one run (issue 21).
//!
//! On each real vessel of ../shared/data/real but the cortex (skipped with a notice when the
//! folder is absent), five seeded cases of damage, each judged against the intact mesh (the
//! truth, as the file gives it: the capped aorta's inward winding and the carotid's metres
//! included; its open ends capped flat, as every watertight output closes them: an open end
//! inside D has no surface to judge a cap against):
//! - 3 wall chops: a wall point (splitmix64 on the seed: an area-weighted face, a uniform
//!   barycentric point), more than 3 local radii R (`local_vessel_radius`) from the open ends'
//!   vertices and from the centreline's endpoints (where capped ends lie), the points two sums
//!   of radii apart (one if too few are found); the first one within 2 inscribed radii of a
//!   centreline junction, or of the vessel's sharpest bend when it has no junction. Damaged =
//!   the mesh without every triangle that has a vertex inside the ball of 1.5R on the point (an
//!   open hole), its largest connected component kept; D = the ball of 1.5R·1.3.
//! - a 50% stenosis: a centreline point (seeded) more than 4R from the junctions and the
//!   endpoints (3R, then 2R, where no point is 4R away, with a note; the lesion then shorter
//!   in proportion, σ = 1.2R × 3/4 or × 2/4, so that it fits the vessel), 3σ of branch on both
//!   sides, the inscribed radius within 0.75–1.33 R over them (a healthy stretch; R its
//!   inscribed radius, σ = 1.2R), and level: R (averaged over one radius of arc) within 10%
//!   of each of those σ, 2σ, 3σ (the rim of D) and 4σ (the shoulders) away on either side,
//!   so that 50% of R is 50% of the healthy lumen, not of a natural dip or bulge under the lesion
//!   (where no site is level, a healthy one, with a note giving how far it is from level);
//!   every vertex whose closest
//!   centreline branch is this one, within 2.5R of it and 4σ along it, moved towards its
//!   projection c(s) on the branch polyline: v ← c + (v − c)·(1 − 0.5·exp(−(s − s₀)²/(2σ²))),
//!   s the arc length. D = the ball of 3σ on the point.
//! - an occlusion: a centreline point chosen as above (healthy over ±2R); every triangle with
//!   a vertex within R/2 of the plane through the point across the tangent and within 2R of the
//!   point removed (two open loops facing each other; every piece kept). D = the ball of 1.5R.
//!
//! Each case's damaged mesh, truth and D (a regions file) are written to a folder (a temporary
//! one, or `--keep DIR`), then repaired by
//! - ours: the whole command a user waits for, timed end to end: `vesselmsr repair DAMAGED -o
//!   OUT --report R.json --picture P.png` with `--holes` (chops), `--regions pick.json`
//!   (stenosis: the point picked at the narrowing's site, as a clinician points at the lesion,
//!   the paper's interactive strategy; the repair takes the narrowing's whole region) or
//!   `--region x,y,z,r` = D (occlusion); also with `--method paper` when $VESSELMSR_BENCH_PAPER
//!   is set; on the stenosis, `--stenoses` (every narrowing of 20% or more, the vessel's own
//!   included, which the truth keeps) is run beside it and printed, outside the tallies;
//! - the peers, by reference/peers.py on the same damaged mesh: MeshLib `fillHoleNicely` with
//!   curvature smoothing on every hole, pymeshfix `MeshFix.repair()`, pymeshlab
//!   `meshing_close_holes` (any hole size); their seconds are the filler call only. The peers'
//!   packages (reference/requirements-peers.txt) are installed into the oracle's venv on demand;
//!   without them (or without the venv) the peers are skipped with a notice;
//! - on the chops, MeshLib again as a user runs it, timed as a process like ours:
//!   reference/meshlib_fill.py (Python start-up, MeshLib's import, its own reader, the same fill,
//!   its own writer).
//!
//! Per output: the symmetric Hausdorff distance to the truth restricted to D (dense barycentric
//! samples, BVH closest point; benches/common/surface.rs) in units of h, h = the voxel our
//! default repair of that case used (its report; the project's default-voxel rule on the damaged
//! mesh when ours failed or inpainted nothing); the volume error in D against the truth, %;
//! watertight (closed, manifold, consistently wound: `mesh_info`); components; the faces within
//! 2 radii of D's centre that do not face out (winding number probed in front of and behind each:
//! `inpaint::checks::faces_not_facing_out`; a slit, or a triangle folded over, as the stitch's
//! shortest seam left 1–4 per output before; also a crease or sliver thinner than the probe's
//! offset, and an input's own folds that an output keeps); whether it has more handles than the
//! truth (`mesh::measures::handles`: a tunnel through the vessel; counted per tool under the
//! table); seconds. A failed output counts as
//! an infinite Hausdorff distance. For the stenosis, the NASCET and diameter stenosis our report
//! gives for the damaged input. Then per tool: the medians, the cases within 1.5h and 5% and
//! within 3h, and on how many cases ours beats each peer (smaller Hausdorff in D, as printed to
//! 2 decimals; ties by |volume error|); ours' cases by how our report says D was filled
//! (`fill`: through, bridge, junction, dead-end, stump, widened, axial: median and cases beyond
//! 3h); and our whole command's time against MeshLib's filler call, and against MeshLib's whole
//! run, on the chops.
//!
//! Measured 2026-12-04 (late night) after the speed work of that night (the guided fill sampled
//! adaptively, the winding numbers built once and by translated moments, the cap's polish rounds
//! local, no closest-point transform of the core for the centreline fill); 2 cores, load 1.5,
//! 25 cases in 56 s, `cargo bench --bench repair_real`: ours median 1.99h / 1.6% (10 of 25
//! within 1.5h and 5%, 19 within 3h; chops 1.99h, stenoses 2.41h, occlusions 1.04h); ours beats
//! MeshLib on 24 of 25 (chops 14/15, stenoses 5/5, occlusions 5/5; it loses the carotid's chop#2,
//! 1.54h against 1.25h), pymeshfix and pymeshlab on 25. Our whole command on a chop: median
//! 0.72 s (0.40–1.03 s; 0.85 s, 0.36–1.48 s before) against MeshLib's filler call 0.010 s (75×).
//! The figures are those of the night's earlier run but two (the aneurysm's neck −0.4% → −0.5%,
//! the coronary's chop#2 0.08h → 0.09h). Re-measured 2026-12-05 after the fill's islands were
//! labelled by runs (load 1.5, 25 cases in 54 s): the same figures (four outputs compared byte
//! for byte); a chop median 0.60 s (0.38–0.95 s, 72×), every case 0.38–1.24 s (the aneurysm's
//! narrowing 1.46 → 1.24 s). Our report's diameter stenosis for the 50% narrowings:
//! 48.9, 45.2, 44.8, 45.2, 56.5% (the narrowest input diameter is within 1.4% of half the truth's
//! at each site; the local reference is 9% below the truth's diameter there on three vessels,
//! whose truth bulges at the site or whose shoulder beside a junction has no measured section,
//! and 16% above it on the coronary, whose truth is narrower than its shoulders).
//!
//! Re-measured 2026-12-05 (morning) after the speed work of that morning (the checks' and the
//! report's winding numbers at order 2, the cap's polish stopping below 1e-3 a sweep, obvhs's
//! fast build), the section rays sized to the voxel around a hole, the rays going on past a
//! hole's cap and a junction's closing balls bounded by its inscribed sphere (load 1.5–1.7, 25
//! cases in 59 s): ours median 1.82h / 1.4% (10 of 25 within 1.5h and 5%, 22 within 3h; chops
//! 1.82h, stenoses 2.41h, occlusions 0.94h); ours beats MeshLib on 24 of 25 (it loses the
//! carotid's chop#2, 1.54h against 1.25h), pymeshfix and pymeshlab on 25. Our whole command:
//! every case 0.35–0.99 s (the aneurysm's narrowing the slowest: 0.91–1.01 s over four runs at
//! load 1.2–1.8); on a chop median 0.51 s (0.37–0.86 s) against MeshLib's filler call 0.011 s
//! (61×, 21–121×) and against MeshLib run whole as a user runs it (reference/meshlib_fill.py)
//! 0.43 s (1.28×, 0.91–2.00×). Still above 3h: the carotid's narrowing next to its external
//! carotid's origin (4.88h, +13.6%: the two narrowings' regions merge around the bifurcation,
//! each branch becomes a tube to the junction at its anchor's radius, and the internal
//! carotid's, 2.18 mm all along its 20 mm run, is wider than the vessel and reaches into the
//! crotch; the natural narrowing at the origin is widened too), the aneurysm's ICA narrowing
//! (4.10h, −13.3%: the truth widens across the lesion), the capped aorta's chop over the
//! carina (3.71h: the damaged centreline's junction lies 5 mm upstream of the true one).
//!
//! Re-measured 2026-12-05 (day) in a fresh clone after the narrowings' fill was made to follow
//! the narrowed lumen's own centreline and the stenosis case was repaired from the point picked
//! at its site (a regions file: the narrowing's whole region, as `--stenoses` gives it; before,
//! `--stenoses` also widened the vessels' own narrowings, which the truth keeps: the carotid's
//! external carotid origin, 36%, and the coronary's two, 49% and 37%); load 1.5, 25 cases in 62
//! s: ours median 1.40h / 1.7% (11 of 25 within 1.5h and 5%, 23 within 3h; chops 1.82h,
//! stenoses 1.35h, occlusions 0.94h); ours beats MeshLib on 24 of 25 (it loses the carotid's
//! chop#2, 1.54h against 1.25h), pymeshfix and pymeshlab on 25. With `--stenoses` instead of the
//! pick (printed beside each stenosis case): 0.83, 1.88, 4.88, 4.10, 1.04h. Our whole command:
//! every case 0.35–0.98 s; on a chop median 0.53 s (0.35–0.79 s) against MeshLib's filler call
//! 0.010 s (65×, 22–130×) and against MeshLib run whole 0.39 s (1.33×, 0.90–1.95×). Still above
//! 3h: the aneurysm's ICA narrowing (4.10h, −13.3%: the truth widens from 3.1 to 3.5 mm across
//! the lesion, under the narrowing, and the far anchor lies in the aneurysm's flare), the capped
//! aorta's chop over the carina (3.71h: the damaged centreline's junction lies 5 mm upstream of
//! the true one).
//!
//! Re-measured 2026-12-05 (late morning, load 1.3–1.8, 75 cases in 169 s) after a narrowing's
//! region was widened where it is (`inpaint::widen`: shoulder to shoulder along its own
//! centreline, nothing else in D touched), the truth judged with its open ends capped flat,
//! and the held-out draws (seeds 22, 23) added to every run. Seed 21: ours median 1.40h / 1.7%
//! (11 of 25 within 1.5h and 5%, 23 within 3h; chops 1.82h, stenoses 1.25h, occlusions 0.94h);
//! ours beats MeshLib on 24 of 25, pymeshfix and pymeshlab on 25; the narrowings 0.81, 2.20,
//! 1.25, 3.56, 1.14h (0.83, 1.88, 1.35, 4.10, 1.09h before); with `--stenoses` 0.81, 2.20, 2.55,
//! 3.56, 1.14h. Seed 22: 1.20h / 2.2%, 13 and 19 of 25, MeshLib beaten on 24. Seed 23: 1.04h /
//! 0.9%, 16 and 21 of 25, MeshLib beaten on 23 (19 and 19 of 25 within 3h before the widening;
//! the capped aorta's narrowing beside the carina 11.35h → 1.7h, the aneurysm's 14.6h → 2.8h).
//! All 75: 1.20h / 1.6%, 40 within 1.5h and 5%, 63 within 3h; MeshLib beaten on 71, pymeshfix
//! on 74, pymeshlab on 75. Above 3h: 8 of the 15 junction chops (3.7–9.9h; MeshLib better on
//! three of them: the carotid's of seed 22, 6.56h against 6.16h, the capped aorta's of seed 23,
//! 5.17h against 3.52h, the aneurysm's of seed 23, 9.97h against 9.05h), two wall chops (3.59h,
//! 3.65h) and the aneurysm's narrowing in two draws (3.56h, 4.01h). Our whole command on a chop:
//! median 0.49 s (0.35–1.20 s) over the 45, 55× MeshLib's filler call, 1.23× its whole run.
//!
//! Re-measured 2026-12-05 (evening, load 1.4–2.2) after a junction fill's bumps were shaved
//! (`inpaint::shave`): seed 21 1.40h / 1.4%, 11 and 23 of 25, MeshLib beaten on 24; seed 22
//! 1.20h / 1.7%, 13 and 19; seed 23 1.04h / 0.9%, 16 and 21; all 75: 1.20h / 1.5%, 40 and 63,
//! MeshLib beaten on 71, pymeshfix on 74, pymeshlab on 75; the 14 junction fills median 3.72h →
//! 3.35h, still 8 beyond 3h (3.1–10.2h). Seeds 24–27: 1.04, 1.64, 1.52, 1.64h; 46 and 79 of 100;
//! MeshLib beaten on 87, pymeshfix and pymeshlab on 97. Our whole command on a chop: median
//! 0.49 s (0.35–1.23 s), 59× MeshLib's filler call, 1.24× its whole run. The table below is
//! the late-morning run's.
//!
//! Re-measured 2026-12-05 (night, load 1.7–2.3) after the stenosis sites
//! were required to be level ([`UNIFORM`]): before, a site could lie on a narrowing or a bulge
//! of the vessel's own, and "50% of its radius" was not 50% of the healthy lumen (the carotid's
//! sites of seeds 25 and 26 fell on its external carotid's origin, 36% narrower than the artery
//! 6 mm on: the report's 67% there was right against the healthy lumen, and the fill, widened
//! to that lumen, overfilled the truth by 87–98% in D; the carotid's of seeds 21 and 23 and
//! the aneurysm's lay on bulges: 44–45%). The chops and occlusions are the same cases as
//! before, the same figures. Our report's diameter stenosis within 50 ± 5% on 29 of 35
//! narrowings (24 of 35 before): 14 of 15 on seeds 21–23; the six outside are the aneurysm's
//! three (its ICA has no level site: 15–16% from level; 43.6, 44.3, 43.6%), the carotid's of
//! seed 25 (55.6%) and the coronary's of seeds 25 and 26 (57.7, 57.0%: its shoulders, sought up
//! to 8 radii away, are wider than the vessel at the site). All 75 of seeds 21–23: 1.19h /
//! 1.5%, 40 within 1.5h and 5%, 64 within 3h; MeshLib beaten on 71, pymeshfix on 74, pymeshlab
//! on 75. Seeds 24–27: 1.04, 1.57, 1.51, 1.64h; 49 and 80 of 100 (46 and 79 before); MeshLib
//! beaten on 89 of 100 (24, 21, 21, 23; 87 before: the carotid's two narrowings are now won),
//! pymeshfix and pymeshlab on 97; MeshLib closer on 9 of the 16 junction chops of 24–27 and on
//! the coronary's chop#1 of seed 24. Seed 21's median moved with its new narrowings (the
//! capped aorta's 0.81h → 1.77h at its new site): 1.54h / 1.4%, above 1.5h.
//!
//! Re-measured the same night (load 1.3–3.0) after a junction branch's wall chart was held
//! taut beyond a radius (`guided::JUNCTION_CHART_TENSION`): seed 21 1.54h / 1.4%, 11 and 22 of
//! 25 (the aneurysm's junction chop 2.80h → 3.18h), MeshLib beaten on 24; seeds 21–23: 1.19h /
//! 1.4%, 40 and 64 of 75; the 14 junction fills median 3.35h → 3.09h, 8 beyond 3h as before;
//! MeshLib beaten on 72 of 75, pymeshfix on 74, pymeshlab on 75. Seeds 24–27: 1.04, 1.57, 1.51,
//! 1.64h; 49 and 82 of 100; MeshLib beaten on 92 of 100 (24, 21, 24, 23), pymeshfix and
//! pymeshlab on 99; MeshLib still closer on 7 of the 16 junction chops of 24–27. Our whole
//! command on a chop: median 0.57 s (0.39–1.49 s) over the 45 of seeds 21–23, 56× MeshLib's
//! filler call, 1.31× its whole run; seed 21's chops 0.39–1.10 s, its 25 cases 0.39–1.25 s (21
//! under 1 s; the machine then ran about 1.6× slower than earlier that day: the same chop's
//! unchanged centreline phase 0.35 s against 0.21 s).
//!
//! Re-measured 2026-12-06 (load 1.4–1.8) after the stenosis sites were made level on each side
//! at σ, 2σ, 3σ, 4σ (shorter lesions where the clearance is relaxed: [`stenosis_sigma`]), a
//! report's shoulder where the lumen levels off, and a narrowing's region over an open end
//! widened (it had been taken for a hole's): the chops and occlusions as before, case by case;
//! the narrowings at their new sites. Seeds 21–23: 1.16h / 1.4%, 43 and 65 of 75; per seed
//! 1.41, 1.20, 0.99h; MeshLib beaten on 70, pymeshfix on 72, pymeshlab on 73 (the carotid's
//! narrowings of seeds 21 and 23, 2–3 mm before its bulb's flare, overfilled by 53% in D, 2.79h,
//! are lost to all three). Seeds 24–27: 1.04, 1.36, 1.51, 1.64h; 49 and 83 of 100; MeshLib
//! beaten on 90, pymeshfix and pymeshlab on 97. The report's diameter stenosis within 50 ± 5%
//! on 32 of 35 (57.2–61.0% on the other three: the carotid's of seeds 24 and 27 by the flare,
//! the coronary's of seed 26 on a taper). Our whole command on a chop: median 0.79 s (0.41–1.64
//! s) over the 45 of seeds 21–23, 52× MeshLib's filler call, 1.25× its whole run; seed 21's
//! chops 0.70 s median, 9 of 15 under 1 s.
//!
//! Re-measured 2026-12-06, the next session, after a report's shoulder was also taken where the
//! rise slows and quickens again (a lesion's flank meeting a bulb's flare) and a widening no
//! longer takes a point whose shoulders lie on either side of a lesion already taken for a
//! lesion of its own: only the narrowings moved, the carotid's of every seed (2.33–3.20h, +53–70% in D before:
//! 0.21–0.50h, −2 to −10%) and the coronary's of seed 22 (1.34h / +21% → 0.48h / +0.9%). Seeds
//! 21–23: 1.07h / 1.3%, 44 and 65 of 75; per seed 1.40, 1.12, 0.90h; MeshLib beaten on 72,
//! pymeshfix on 74, pymeshlab on 75. Seeds 24–27: 1.00, 1.21, 1.47, 1.49h; 51 and 85 of 100;
//! MeshLib beaten on 92, pymeshfix and pymeshlab on 99. The report's diameter stenosis within
//! 50 ± 5% on 34 of 35 (the coronary's of seed 26, on a taper, 57.2%). The carotid sites of
//! seeds 24 and 27 were looked at to make the change: those two draws are no longer held out
//! for it. Our whole command on seed 21's chops: median 0.91 s (0.49–1.44 s), 9 of 15 under
//! 1 s, 60× MeshLib's filler call, 1.24× its whole run (the chops' path unchanged: the machine
//! ran slower, every phase alike). Re-measured 2026-12-06, the session after, once the input's
//! centreline was traced while the repair voxelizes (the outputs identical to the byte) and the
//! stitch's strip became the one whose new edges are shortest in sum (the greedy walk lost step
//! on loops of unlike spacing: seed 22's capped aorta fell back to the whole re-mesh on two
//! junction chops, with 15–25 mm edges across the hole, and seed 23's aneurysm occlusion on the
//! slit check): no fallback left in seeds 21–23 (3 before), 2 in 24–27 (4; both "3 holes around
//! D but 2 patch loops", a different failure). Moved: 10 of the 75 cases, none by more than
//! 0.01h farther, the coronary's narrowing of seed 21 1.16h → 0.55h and four occlusions closer
//! (0.92 → 0.37h, 0.86 → 0.62h, 0.29 → 0.19h; in 24–27 0.20 → 0.09h, 0.80 → 0.39h, 0.69 →
//! 0.36h); seeds 21–23 1.04h / 1.4%, 44 and 65 of 75, per seed 1.40, 1.12, 0.90h, MeshLib beaten
//! on 72, pymeshfix 74, pymeshlab 75; seeds 24–27 as before (1.00, 1.21, 1.47, 1.49h; 51 and 85
//! of 100; 92, 99, 99); the end bites unchanged. Our whole command on a chop: median 0.69 s
//! (0.46–1.33 s) over the 45 of seeds 21–23, 35 under 1 s; seed 21 median 0.73 s (0.47–1.18 s), 10
//! of 15 under 1 s (13 of 15 in the run just before with the old stitch at a quieter moment: the
//! count moves with the host's load); 44× MeshLib's filler call, 1.21× its whole run. The table
//! below is still the late-morning run's.
//!
//! Re-measured 2026-12-06, a session later (load about 1.5), once the patch was meshed at twice
//! the voxel where the vessel around D is 12 voxels or more in radius (`repair::patch_stride`;
//! the fill's own grid unchanged): the aneurysm's and the aortas' chops, the carotid's and the
//! coronary's not (8–10 and 4–7 voxels). Seeds 21–23: 1.05h / 1.2%, 44 and 66 of 75 (the open
//! aorta's junction chop of seed 22 3.00h → 2.87h); per seed 1.40, 1.07, 0.98h; MeshLib beaten
//! on 72, pymeshfix 74, pymeshlab 75; no fallback. Of the 75, 43 moved: closer by up to 0.13h
//! (that junction chop; the capped aorta's chop#2 of seed 22 1.12h → 1.02h), farther by up to
//! 0.08h (the capped aorta's narrowings, 0.90h → 0.98h), the volume in D 0.0–0.3% lower (chords
//! across the wall at 2h). Seeds 24–27: 0.97, 1.21, 1.44, 1.50h; 50 and 85 of
//! 100 (51 and 85: the capped aorta's occlusion of seed 24 1.46h → 1.52h); MeshLib beaten on 92,
//! pymeshfix and pymeshlab on 99, as before; the report's stenosis readings unchanged. End bites
//! 2.59h / 1.8%, 15 and 17 of 33, MeshLib beaten on 31; the phantoms as before (their vessels are
//! under 12 voxels). Our whole command on a chop: median 0.63 s (0.42–1.23 s) over the 45 of
//! seeds 21–23, 42 under 1 s (35 before); against MeshLib's filler call median 0.014 s, 49× at the
//! median of the per-chop ratios (their spread is MeshLib's: 0.005–0.02 s), 1.05× its whole run.
//!
//! Re-measured 2026-12-06, late afternoon (load 1.3–1.7), after changes that leave every output
//! as it was (what follows the fill run on the patch's nodes only, the report reading the volumes
//! the self-checks measured, the centreline's chamfer sweeping only the nodes it changes): every
//! accuracy figure above unchanged; our whole command on a chop median 0.55 s (0.35–0.91 s)
//! over the 45 of seeds 21–23, all 45 under 1 s, and 0.34–0.88 s over the 60 of seeds 24–27;
//! 44× MeshLib's filler call at the median, 0.98× its whole run.
//!
//! Re-measured 2026-12-06, evening (load 0.2–1.6), after a hole's cap that spans space outside
//! the vessel was no longer kept as the input's lumen (`known_wall::cap_only_nodes`: across a
//! hole over a crotch the cap closed the space between the iliacs): of the 100 cases of seeds
//! 21–27 and the 33 end bites, two moved, the capped aorta's carina chop of seed 27, 12.32h /
//! +15.1% → 9.63h / +10.2% (MeshLib 11.60h: now beaten on 93 of the 100), and the open aorta's
//! junction chop of seed 26 in volume only (+3.1% → +2.6%, 3.55h); every other figure
//! as above (seeds 21–23 1.05h / 1.2%, 44 and 66 of 75; seeds 24–27 0.97, 1.21, 1.44, 1.50h, 50
//! and 85 of 100; end bites 2.59h / 1.6%, 17 of 33). Our whole command on a chop: median 0.48 s
//! (0.34–0.77 s) over the 45 of seeds 21–23 (0.43 s, 0.32–0.71 s, in a run of the commit before
//! at load 0.2–1.4), 48× MeshLib's filler call, 0.94× its whole run.
//!
//! Re-measured 2026-12-07 (load 1.4–4.3: other work ran beside it), every seed from 21 to 33,
//! after the tunnel closing and the open-end anchor fixes of seeds 28 and 29 and with the
//! stenosis pick also run on the truth: seeds 21–23 1.05h / 1.2%, 44 and 66 of 75, MeshLib
//! beaten on 72, pymeshfix 74, pymeshlab 75, our whole command on a chop median 0.48 s
//! (0.36–0.77 s), 45× MeshLib's filler call, 0.93× its whole run; per seed from 24 to 33 the
//! medians 0.97, 1.20, 1.44, 1.50, 1.42, 1.28, 1.46, 1.06, 1.40, 1.46h. All 325 cases: median
//! 1.23h, 172 within 1.5h and 5%, 274 within 3h, MeshLib beaten on 304, pymeshfix on 319,
//! pymeshlab on 320; 64 of the 65 narrowings read within 50 ± 5%; no output with a handle the
//! truth lacks. Seeds 32 and 33 were new: the carotid severed at its junction again (seed 33,
//! as seed 31's: its cut end is now named in a notice) and an iliac taken whole beyond D (seed
//! 33's open aorta, 40.8h against MeshLib's 48.7h); seed 32's coronary printed its lesion's
//! centre ratio as NaN (no vertex within a quarter radius of the centre on its coarse wall: the
//! nearest one's ratio is printed now).
//!
//! Seed 34 (2026-12-07, new): median 1.86h / 1.8%, 10 of 25 within 1.5h and 5%, 18 within 3h,
//! MeshLib beaten on 22, pymeshfix 25, pymeshlab 24; our whole command on a chop median 0.59 s
//! (0.46–0.83 s), 48× MeshLib's filler call, 0.77× its whole run. Its capped aorta's junction
//! chop severed an iliac (99.1h; MeshLib 121.7h); its carotid bulb's wall chop 4.08h / −16.2%
//! led to the wall chart's bound applying only towards a junction point (3.10h / −4.8%).
//! Then a dead end towards a closed vessel end bridged to its intact section there (five chops
//! of seeds 22–34 move, 2.08–5.45h → 0.83–2.17h). Seed 35 (2026-12-07, new, drawn with it):
//! median 1.09h / 1.9%, 14 within 1.5h and 5%, 21 within 3h, MeshLib beaten on 23, pymeshfix
//! and pymeshlab 25. Then the wall chart's second difference around the vessel weighted 0.7;
//! seeds 21–35 re-run: all 375 median 1.09h / 1.3%, 205 within 1.5h and
//! 5%, 320 within 3h, MeshLib beaten on 350, pymeshfix and pymeshlab 369; per draw medians
//! 0.93–1.48h but seed 34's 1.91h; our whole command on a chop median 0.40–0.54 s per draw.
//! Then a junction counts only where it is half as wide as the narrowest branch (seed 29's
//! aorta junction chops had taken a spur's: 15.79h → 8.48h, 17.01h → 7.18h, and no tunnel), and
//! junction branches keep their anchors' direction longer (`guided::JUNCTION_TANGENTS`; the 61
//! junction fills' mean 4.14h → 3.78h); seeds 21–35 re-run: all 375 median 1.09h / 1.4%, 205
//! within 1.5h and 5%, 323 within 3h, MeshLib beaten on 359, pymeshfix and pymeshlab 371;
//! our whole command on a chop median 0.36–0.49 s per draw.
//! Then a round vessel's curve through a hole is moved onto the intact wall's centre from half
//! a section of wall, in five passes (`guided::ROUND_SECTION`; seed 34's coronary bend chop
//! 1.91h → 1.08h); seeds 21–35 re-run: all 375 median 1.08h / 1.3%, 206 within 1.5h and 5%,
//! 323 within 3h, every draw's median within 1.5h (seed 34 1.24h), MeshLib beaten on 361,
//! pymeshfix and pymeshlab 371; our whole command on a chop median 0.41–0.49 s per draw.
//!
//! Seed 21 per case (the run before):
//!
//! | vessel | case | ours h / vol | ours s | MeshLib | pymeshfix | pymeshlab |
//! |---|---|---|---|---|---|---|
//! | aorta_abdominal_capped | chop#1 (junction) | 3.71 / +4.4% | 0.788 | 10.47 / +6.9% | 12.66 / +15.7% | 12.85 / −9.3% (open) |
//! | aorta_abdominal_capped | chop#2 (wall) | 2.65 / +1.7% | 0.882 | 8.77 / −10.6% | 20.92 / −26.8% | 5.52 / −6.3% |
//! | aorta_abdominal_capped | chop#3 (wall) | 0.73 / −0.1% | 0.522 | 5.06 / −9.5% | 4.12 / −5.6% | 8.52 / −17.3% |
//! | aorta_abdominal_capped | stenosis 50% (diameter 48.9%) | 0.81 / −2.5% | 0.487 | 7.19 / −30.4% | 7.19 / −30.4% | 7.19 / −30.4% |
//! | aorta_abdominal_capped | occlusion | 0.94 / −0.2% | 0.381 | 12.84 / −23.6% | 21.61 / −69.9% | 13.18 / −42.0% |
//! | aorta_abdominal_open_ends | chop#1 (junction) | 2.34 / −2.2% | 0.558 | 4.60 / −7.3% | 3.75 / −1.2% | 9.56 / −14.7% (open) |
//! | aorta_abdominal_open_ends | chop#2 (wall) | 2.48 / +1.3% | 0.745 | 8.76 / −7.3% | 8.72 / −6.2% | 19.10 / −19.4% (open) |
//! | aorta_abdominal_open_ends | chop#3 (wall) | 1.18 / −1.4% | 0.493 | 5.20 / −9.9% | 1.90 / −3.3% | 12.60 / −25.4% (open) |
//! | aorta_abdominal_open_ends | stenosis 50% (diameter 45.2%) | 2.20 / −7.4% | 0.551 | 8.51 / −28.2% | 8.51 / −28.2% | 8.51 / −28.2% (open) |
//! | aorta_abdominal_open_ends | occlusion | 1.84 / +1.3% | 0.427 | 14.12 / −26.3% | 24.05 / −73.5% | 11.78 / −44.3% (open) |
//! | carotid_bifurcation | chop#1 (junction) | 2.23 / +8.4% | 0.418 | 4.62 / +21.5% | 4.88 / +29.6% | 3.65 / +1.7% |
//! | carotid_bifurcation | chop#2 (wall) | 1.54 / +4.0% | 0.383 | 1.25 / −3.1% | 4.74 / −10.9% | 6.78 / −23.9% |
//! | carotid_bifurcation | chop#3 (wall) | 0.18 / +0.4% | 0.353 | 1.98 / −12.2% | 4.83 / −28.8% | 5.69 / −40.6% |
//! | carotid_bifurcation | stenosis 50% (diameter 44.8%) | 1.25 / −12.1% | 0.381 | 4.96 / −33.7% | 4.96 / −33.7% | 4.96 / −33.7% |
//! | carotid_bifurcation | occlusion | 0.33 / −0.4% | 0.354 | 10.03 / −19.4% | 17.94 / −74.2% | 9.94 / −45.6% |
//! | ica_aneurysm_c0015 | chop#1 (junction) | 2.41 / +0.5% | 0.650 | 6.32 / +5.1% | 16.50 / +24.2% | 14.29 / −15.0% (open) |
//! | ica_aneurysm_c0015 | chop#2 (wall) | 1.82 / −1.1% | 0.723 | 11.42 / −11.3% | 28.30 / −32.4% | 22.51 / −23.3% (open) |
//! | ica_aneurysm_c0015 | chop#3 (wall) | 2.99 / +1.7% | 0.731 | 8.34 / −9.8% | 21.90 / −25.1% | 24.63 / −24.7% (open) |
//! | ica_aneurysm_c0015 | stenosis 50% (diameter 45.2%) | 3.56 / −10.7% | 0.921 | 14.86 / −35.3% | 14.86 / −35.3% | 14.86 / −35.3% (open) |
//! | ica_aneurysm_c0015 | occlusion | 1.40 / −0.3% | 0.613 | 27.66 / −19.9% | 48.58 / −69.9% | 25.52 / −40.5% (open) |
//! | coronary_stenosis_xray | chop#1 (bend 47°) | 0.58 / −2.7% | 0.353 | 3.55 / −24.5% | 6.03 / −42.3% | 2.04 / −17.5% |
//! | coronary_stenosis_xray | chop#2 (wall) | 0.09 / −0.1% | 0.351 | 2.36 / −16.7% | 4.08 / −27.4% | 1.20 / −4.9% |
//! | coronary_stenosis_xray | chop#3 (wall) | 0.66 / −3.0% | 0.396 | 3.81 / −22.0% | 7.25 / −42.2% | 4.46 / −24.0% |
//! | coronary_stenosis_xray | stenosis 50% (diameter 56.5%) | 1.14 / +20.9% | 0.366 | 3.16 / −33.1% | 3.16 / −33.1% | 3.16 / −33.1% |
//! | coronary_stenosis_xray | occlusion | 0.29 / −0.3% | 0.347 | 6.99 / −58.3% | 14.79 / −82.6% | 7.05 / −67.5% |
//!
//! Measured 2026-12-04 on src at b426dc2 (the old `axial` fill), 2 cores shared with another job
//! (load 5.9 at the start, 4.7 at the end), from a clean venv (the bench installed the peers
//! first); 25 cases in 223 s. `cargo bench --bench repair_real`. Cells: Hausdorff in D (h) /
//! volume error in D; "(open)": the output is not watertight (pymeshlab leaves the holes whose
//! patch would self-intersect); ours' seconds are the whole command, the peers' filler calls
//! took 0.000–0.08 s (MeshLib), 0.02–0.71 s (pymeshfix), 0.008–0.04 s (pymeshlab):
//!
//! | vessel | case | damaged | ours | ours s | MeshLib | pymeshfix | pymeshlab |
//! |---|---|---|---|---|---|---|---|
//! | aorta capped | chop#1 (junction) | 23.03 / −4.0% | 14.51 / +22.0% | 3.47 | 10.47 / +6.9% | 12.66 / +15.7% | 12.85 / −9.3% (open) |
//! | aorta capped | chop#2 (wall) | 35.10 / −10.1% | 4.42 / −0.2% | 3.36 | 8.77 / −10.6% | 20.92 / −26.8% | 5.52 / −6.3% |
//! | aorta capped | chop#3 (wall) | 20.23 / −11.9% | 1.91 / +3.9% | 1.54 | 5.06 / −9.5% | 4.12 / −5.6% | 8.52 / −17.3% |
//! | aorta capped | stenosis (NASCET 43.3%) | 7.19 / −30.4% | 13.00 / −84.3% | 1.30 | 7.19 / −30.4% | 7.19 / −30.4% | 7.19 / −30.4% |
//! | aorta capped | occlusion | 8.17 / −30.7% | 1.61 / +1.9% | 1.28 | 12.84 / −23.6% | 21.61 / −69.9% | 13.18 / −42.0% |
//! | aorta open | chop#1 (junction) | 22.70 / −8.7% | 16.59 / +20.5% | 3.94 | 4.60 / −7.3% | 3.75 / −1.2% | 9.56 / −14.7% (open) |
//! | aorta open | chop#2 (wall) | 36.53 / −8.6% | 5.52 / +1.0% | 5.00 | 8.76 / −7.3% | 8.72 / −6.2% | 19.10 / −19.4% (open) |
//! | aorta open | chop#3 (wall) | 21.59 / −12.5% | 2.18 / +2.0% | 2.68 | 5.20 / −9.9% | 1.90 / −3.3% | 12.60 / −25.4% (open) |
//! | aorta open | stenosis (NASCET 36.1%) | 8.51 / −28.2% | 6.32 / −17.5% | 1.99 | 8.51 / −28.2% | 8.51 / −28.2% | 8.51 / −28.2% (open) |
//! | aorta open | occlusion | 9.21 / −33.2% | 2.68 / −1.7% | 2.42 | 14.12 / −26.3% | 24.05 / −73.5% | 11.78 / −44.3% (open) |
//! | carotid | chop#1 (junction) | 8.11 / −1.0% | 5.18 / +26.3% | 1.34 | 4.62 / +21.5% | 4.88 / +29.6% | 3.65 / +1.7% |
//! | carotid | chop#2 (wall) | 14.38 / −9.1% | 2.55 / +5.7% | 1.31 | 1.25 / −3.1% | 4.74 / −10.9% | 6.78 / −23.9% |
//! | carotid | chop#3 (wall) | 7.60 / −12.3% | 0.13 / +0.0% | 0.93 | 1.98 / −12.2% | 4.83 / −28.8% | 5.69 / −40.6% |
//! | carotid | stenosis (NASCET 57.2%) | 4.96 / −33.7% | 13.99 / −16.5% | 2.40 | 4.96 / −33.7% | 4.96 / −33.7% | 4.96 / −33.7% |
//! | carotid | occlusion | 6.13 / −30.6% | 0.94 / −2.2% | 1.34 | 10.03 / −19.4% | 17.95 / −74.2% | 9.94 / −45.6% |
//! | ICA aneurysm | chop#1 (junction) | 26.09 / −2.8% | 22.17 / +67.1% | 2.73 | 6.32 / +5.1% | 16.50 / +24.2% | 14.29 / −15.0% (open) |
//! | ICA aneurysm | chop#2 (wall) | 42.72 / −11.2% | 14.63 / −3.8% | 3.59 | 11.42 / −11.3% | 28.30 / −32.4% | 22.51 / −23.3% (open) |
//! | ICA aneurysm | chop#3 (wall) | 41.80 / −11.3% | 12.85 / −2.7% | 3.27 | 8.34 / −9.8% | 21.90 / −25.1% | 24.63 / −24.7% (open) |
//! | ICA aneurysm | stenosis (NASCET 41.6%) | 14.86 / −35.3% | 14.54 / −21.4% | 2.59 | 14.86 / −35.3% | 14.86 / −35.3% | 14.86 / −35.3% (open) |
//! | ICA aneurysm | occlusion | 15.89 / −29.4% | 4.36 / +1.5% | 2.02 | 27.66 / −19.9% | 48.58 / −69.9% | 25.52 / −40.5% (open) |
//! | coronary | chop#1 (bend 47°) | 8.72 / −18.0% | 6.12 / −39.0% | 0.89 | 3.55 / −24.5% | 6.03 / −42.3% | 2.04 / −17.5% |
//! | coronary | chop#2 (wall) | 8.65 / −13.5% | 1.11 / +0.0% | 0.52 | 2.36 / −16.7% | 4.08 / −27.4% | 1.20 / −4.9% |
//! | coronary | chop#3 (wall) | 10.35 / −16.9% | 4.52 / −33.1% | 0.64 | 3.81 / −22.0% | 7.25 / −42.2% | 4.46 / −24.0% |
//! | coronary | stenosis (NASCET 55.8%) | 3.16 / −33.1% | 3.21 / −32.4% | 3.52 | 3.16 / −33.1% | 3.16 / −33.1% | 3.16 / −33.1% |
//! | coronary | occlusion | 7.07 / −45.2% | 0.58 / −2.6% | 0.63 | 6.99 / −58.3% | 14.79 / −82.6% | 7.05 / −67.5% |
//!
//! Summary (median Hausdorff h, median |volume error|, within 1.5h and 5%, within 3h):
//! ours 4.52 h, 3.9%, 4/25, 9/25 (chops 5.18 h, stenoses 13.00 h, occlusions 1.61 h);
//! MeshLib 6.99 h, 19.4%, 1/25, 3/25 (chops 5.06 h); pymeshfix 8.51 h, 29.6%, 0/25, 1/25;
//! pymeshlab 8.52 h, 24.7%, 1/25, 2/25. Ours beats MeshLib on 13 of 25 (chops 6/15, stenoses
//! 2/5, occlusions 5/5), pymeshfix and pymeshlab on 16 of 25 each (chops 9/15). Speed on the 15
//! chops: ours' whole command 0.52–5.00 s (median 2.68 s, of which the report 0.2–1.6 s and the
//! centreline 0.3–1.5 s), MeshLib's fillHoleNicely 0.004–0.086 s (median 0.028 s): ratio median
//! 85× (55–189×); peers.py's whole script (Python start-up, imports, all three) 1.0–2.8 s.
//! What stands out: ours overfills every junction chop (+20% to +67% volume; on the open aorta
//! its picture shows a web between the iliacs; MeshLib 4.6–10.5 h there) and makes the stenosis
//! worse than the damaged input on the capped aorta (13.0 h, −84%; that input is wound inward
//! and ours' report gives negative volumes in its region) and on the carotid (14.0 h);
//! the peers leave every stenosis as it is (no hole) and cap each side of every occlusion
//! (pymeshfix also drops the smaller piece: −70% to −83%), where ours is within 0.6–4.4 h and
//! 2.6%. Our report gives NASCET 36–57% for the 50% narrowings (never within 50 ± 5%).
//! The aneurysm's ICA has no centreline point 4 radii from its junction and ends: its stenosis
//! and occlusion are placed 3 radii away (the case note says so).
//! `--method paper` (VESSELMSR_BENCH_PAPER=1, the coronary only, load 6.5–8): chops 4.71 h /
//! −37.9%, 3.62 h / −29.4%, 5.04 h / −37.3% in 4.9–10.9 s; stenosis 3.20 h / −32.4% in 308 s
//! (five narrowings found); occlusion 6.97 h / −61.5% in 6.2 s: less volume in D than the
//! damaged input on the chops and the occlusion, the stenosis unchanged; the default beats it
//! on 3 of 5.
//!
//! Run: `cargo bench --bench repair_real`: the draw of seed 21 (the acceptance's), then the
//! held-out draws of seeds 22 and 23, each with its summary, and the summary of all 75 cases
//! (`-- --seed N` runs one draw; `-- SUBSTRING` runs the vessels whose file name holds it;
//! `-- --keep DIR` keeps every case's files in DIR/seedN/VESSEL/CASE, our pictures included;
//! `-- --end-bites` replaces each vessel's cases by chops that reach an open end's rim, a study
//! outside the acceptance's cases; `-- --shapes` by damage of five other shapes, another such
//! study, below; $VESSELMSR_BENCH_PAPER=1 adds `--method paper`).
//! The shapes study: on the chops' wall points (the first within 2 radii of a junction or
//! bend), a slit (every triangle with a vertex within 0.35R of a line along the wall, 2R either
//! side of the point), an ellipsoid (2.5R along a random direction, R across it), a pair of
//! balls of 0.9R 1.6R apart along the wall, a small ball of 0.6R (a hole in the wall alone) and
//! a big one of 2.2R with every piece kept (it may cut the vessel through); D = the ball on the
//! point of 1.3 × the shape's reach; repaired with `--holes` as the chops are. Seeds 21–23
//! (2026-12-07, 75 cases): ours median 0.88h (MeshLib 1.22h), 58 within 3h (53), MeshLib beaten
//! on 51: slits 3 of 15 (0.88h against 0.58h: the patch re-meshes the intact wall inside D's
//! ball, which a slit's thin hole leaves almost whole), ellipsoids 14, pairs 13, small balls 11,
//! big balls 10 (a vessel cut through is bridged where its cut ends face each other, `gap`, and
//! left as it is where the cut lies next to a clipped end). Run first by a script, the study
//! found a slit's fin 7 mm out of the wall (22.6h; now 1.45h) and the severed bifurcations left
//! unfilled (−68% in D; now 10.3h / −1.7% and 11.5h / −11.8%). Then (2026-12-07, evening) 10
//! of the 15 big balls' outputs in two pieces, 5 of them because cut loops 20–32% off their
//! planes were taken for holes and closed alone; as a gap's sides
//! (`holes::CUT_MAX_PLANARITY`): the coronary's three
//! 1.14h, 0.87h, 0.19h (10.01h, 5.02h, 7.16h before), the carotid's 3.92h and 6.55h (13.61h,
//! 10.74h), big balls' median 11.47h (13.61h), the 70 other cases unchanged, 62 within 3h
//! (MeshLib 53); and the open aorta's iliacs, bridged to each other under a severed
//! bifurcation, joined with the aorta's open end ahead of them as a junction
//! (`guided::BRIDGE_MIN_FACING`): 44.30h → 3.83h. 4 still in pieces (a cut 2 mm
//! from a clipped end), with a notice.
//! The end-bite study, seeds 21–23 (33 bites on the four open-ended vessels; 2026-12-05, late):
//! ours 2.57h / 1.7% at the median, 17 within 3h, better than MeshLib (13.35h / 29.8%, the
//! whole loop capped) on 31; before a dead end went on to the end the damage reached (the
//! fill closed round along the damaged centreline), 8.61h / 27.3%, none within 3h. With the
//! wall chart's second difference around the vessel weighted 0.7 (2026-12-07): 2.56h / 1.6%,
//! 15 within 1.5h and 5%, 17 within 3h, MeshLib beaten on 33 (isotropic, the same build:
//! 2.59h / 1.6%, 15 and 17).

mod common;

use common::surface::{hausdorff_in, median_all, sig, volume_in, AreaSampler};
use common::{load, Reference, REAL_VESSELS};
use nalgebra::{Point3, Vector3};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::centerline::{compute_centerline, Branch, Centerline, CenterlineOptions};
use vesselmsr::grid::spec::default_voxel;
use vesselmsr::inpaint::checks::faces_not_facing_out;
use vesselmsr::inpaint::phantom::SplitMix;
use vesselmsr::inpaint::region::{local_vessel_radius, write_regions, Ball};
use vesselmsr::io::{read_mesh, write_mesh};
use vesselmsr::mesh::cap::{cap_holes, CapOptions};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::measures::{bounding_box, handles, mean_edge_length};
use vesselmsr::mesh::topology::{boundary_loops, connected_components};
use vesselmsr::TriMesh;

/// Seed of every draw (one splitmix64 stream per kind of damage and vessel): the draw the
/// acceptance is judged on.
const SEED: u64 = 21;
/// Held-out draws, run after it by default (`--seed N` runs one draw alone): cases no change
/// was tuned on, so that the figures are not those of one draw.
const HELD_OUT: [u64; 2] = [22, 23];
/// Wall chops per vessel.
const CHOPS: usize = 3;
/// Chop ball and its region D, in local radii.
const CHOP: f64 = 1.5;
const CHOP_REGION: f64 = 1.5 * 1.3;
/// Wall points keep this many local radii from the open ends and the centreline's endpoints.
const END_CLEARANCE: f64 = 3.0;
/// The first chop lies within this many inscribed radii of a junction (or bend).
const NEAR_FEATURE: f64 = 2.0;
/// Random wall points tried per search.
const DRAWS: usize = 20_000;
/// Stenosis and occlusion points keep this many radii from junctions and endpoints (the
/// first; the next ones in turn where no point is that far, as on the aneurysm's short ICA,
/// whose middle is 3.8 radii from its ends).
const SITE_CLEARANCES: [f64; 3] = [4.0, 3.0, 2.0];
/// The bend of the first chop is sought this many radii away from the branch ends.
const BEND_CLEARANCE: f64 = 4.0;
/// The synthetic stenosis: radius × (1 − DEGREE·exp(−s²/(2σ²))), σ = SIGMA·R (shortened where
/// the site's clearance was relaxed: [`stenosis_sigma`]).
const DEGREE: f64 = 0.5;
const SIGMA: f64 = 1.2;
/// The stenosis's region D and its healthy stretch: this many σ on each side.
const STENOSIS_SIGMAS: f64 = 3.0;
/// Vertices moved for the stenosis: within this many σ along the branch and radii across it.
const MOVE_SIGMAS: f64 = 4.0;
const MOVE_RADII: f64 = 2.5;
/// A healthy stretch: inscribed radii within [R·HEALTHY, R/HEALTHY].
const HEALTHY: f64 = 0.75;
/// A stenosis site is as wide as the vessel around it: its inscribed radius (averaged over one
/// radius of arc) within this fraction of each of those [`LEVEL_SIGMAS`] σ away on either
/// side, out to the ends of the stretch the stenosis moves (MOVE_SIGMAS σ away, where the
/// shoulders lie). Otherwise the vessel is narrowed or bulged there of itself, and "50%" of its
/// radius is not 50% of the healthy lumen: on the carotid (seeds 25, 26) the site fell on the
/// external carotid's origin, 36% narrower than the artery 6 mm on (1.85 against 2.9 mm), and
/// the 50% stenosis was a 68% one. Checked at MOVE_SIGMAS σ alone, a dip under the lesion
/// passed where the vessel 4σ on happened to match it: the coronary of seed 26 (a 2.06 mm
/// lumen between 2.43 mm bulges 3 mm either side) and the external carotid of seed 25 (2.41
/// mm, 2.91 mm 3.5 mm before it) were 56–57% stenoses against the lumen beside them; and
/// against the mean of both sides, a bulge on one side passed (the coronary's, 14% wider 2 radii
/// on, the other side level: 55.5%).
const UNIFORM: f64 = 0.1;
/// The distances, in σ, at which a stenosis site's level is checked.
const LEVEL_SIGMAS: [f64; 4] = [1.0, 2.0, STENOSIS_SIGMAS, MOVE_SIGMAS];
/// The occlusion: the slab's half-thickness and reach, its healthy stretch and region, in R.
const SLAB_HALF: f64 = 0.5;
const SLAB_REACH: f64 = 2.0;
const OCCLUSION_WINDOW: f64 = 2.0;
const OCCLUSION_REGION: f64 = 1.5;
/// Each tool run is stopped after this long (and counted as failed).
const TIME_LIMIT: Duration = Duration::from_secs(300);
const PAPER_TIME_LIMIT: Duration = Duration::from_secs(900);
/// Peers, in peers.py's order and names.
const PEERS: [&str; 3] = ["meshlib", "pymeshfix", "pymeshlab"];

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    Chop,
    Stenosis,
    Occlusion,
}

impl Kind {
    const ALL: [Kind; 3] = [Kind::Chop, Kind::Stenosis, Kind::Occlusion];

    fn as_str(self) -> &'static str {
        match self {
            Kind::Chop => "chops",
            Kind::Stenosis => "stenosis",
            Kind::Occlusion => "occlusion",
        }
    }
}

/// One damaged vessel to repair.
struct Case {
    /// e.g. "chop#1 (junction)".
    label: String,
    /// Folder name.
    slug: String,
    kind: Kind,
    damaged: TriMesh,
    /// The region D of the metrics (and of ours for the occlusion).
    region: Ball,
    /// The vessel radius R the damage was sized on.
    radius: f64,
    /// How the damage came out (new loops, moved vertices, ...).
    note: String,
}

/// One output judged against the truth.
#[derive(Clone)]
struct Outcome {
    /// Symmetric Hausdorff in D, units of h (infinite: no output).
    hausdorff_h: f64,
    /// Volume error in D, % (NaN: no output).
    volume_pct: f64,
    watertight: bool,
    components: usize,
    /// Faces within 2 radii of D's centre that do not face out (a slit, fin or pocket, a
    /// triangle folded over, or a feature thinner than the probe's offset:
    /// `faces_not_facing_out`); None for a surface that is not closed.
    facing_in: Option<usize>,
    /// Handles the output has beyond the truth's (a tunnel through the vessel:
    /// `mesh::measures::handles`, open ends counted as capped); None when either cannot be told.
    extra_handles: Option<i64>,
    seconds: f64,
    /// Why there is no output.
    error: Option<String>,
}

impl Outcome {
    fn failed(why: String, seconds: f64) -> Outcome {
        Outcome {
            hausdorff_h: f64::INFINITY,
            volume_pct: f64::NAN,
            watertight: false,
            components: 0,
            facing_in: None,
            extra_handles: None,
            seconds,
            error: Some(why),
        }
    }

    /// The rule of the tally: smaller Hausdorff in D as printed (2 decimals), then smaller
    /// |volume error| as printed.
    fn beats(&self, other: &Outcome) -> bool {
        let key = |o: &Outcome| {
            let v = o.volume_pct.abs();
            (
                (o.hausdorff_h * 100.0).round(),
                if v.is_finite() {
                    (v * 100.0).round()
                } else {
                    f64::INFINITY
                },
            )
        };
        let (a, b) = (key(self), key(other));
        a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
    }
}

/// Everything measured on one case.
struct CaseResult {
    label: String,
    kind: Kind,
    h: f64,
    /// Why `h` is the default-voxel rule's, not our report's voxel: our default repair failed,
    /// or it inpainted nothing (a vessel severed by the chop, whose cut end is taken for an open
    /// end: a report without a voxel). None: the report's voxel.
    h_rule: Option<&'static str>,
    /// The damaged input itself against the truth (not a tool).
    input: Outcome,
    /// Per tool of `tool_names`; None: not run.
    outcomes: Vec<Option<Outcome>>,
    /// peers.py's wall time (all three peers, Python start-up and imports included).
    peers_script: Option<f64>,
    /// MeshLib run as a user runs it (reference/meshlib_fill.py: Python start-up, import, its
    /// own reader, the fill, its own writer), wall seconds; chops only.
    meshlib_run: Option<f64>,
    /// Our report's stenosis readings at the pick (stenosis case).
    stenosis: Option<StenosisReading>,
    /// Our report's timings, "name s" each.
    our_timings: String,
    /// How our default repair filled the case's regions (the report's `fill`, joined by "+";
    /// empty: no report).
    our_fill: String,
}

/// Our report's stenosis figures at the picked narrowing (percent; None: no reading).
struct StenosisReading {
    /// NASCET and diameter stenosis on the damaged input.
    nascet: Option<f64>,
    diameter: Option<f64>,
    /// Diameter stenosis on the truth at the same pick: the vessel's own narrowing there, if
    /// any, which the synthetic lesion (half the local diameter) deepens. Context, not an
    /// oracle: the coronary's of seed 26 read 15.7% (half its local diameter is then 57.9% of
    /// the healthy reference; our reading on the damaged input 57.2%), but on the truth the
    /// carotid's region (the narrowest section in it) read 29–36% on 7 of the 13 draws of seeds
    /// 21–33, where the damaged input read 46–48%.
    own: Option<f64>,
}

/// A real vessel, its centreline and where its ends are.
struct Vessel {
    name: String,
    mesh: TriMesh,
    /// The truth the outputs are judged against: the mesh with its open ends capped flat, as
    /// every watertight output closes them (an open end inside D has no surface to compare a
    /// cap with: the aneurysm's short ICA, whose narrowing's D holds its open end, 24.5h for a
    /// flat cap before).
    judged: TriMesh,
    /// The handles of `judged` (`mesh::measures::handles`), once.
    judged_handles: Option<i64>,
    bvh: MeshBvh,
    centerline: Option<Centerline>,
    /// Open-end loop vertices and centreline endpoints.
    ends: Vec<Point3<f64>>,
}

impl Vessel {
    fn near_end(&self, p: &Point3<f64>, r: f64) -> bool {
        self.ends.iter().any(|e| (e - p).norm() < END_CLEARANCE * r)
    }
}

/// A centreline point where a stenosis or occlusion is made.
struct Site {
    branch: usize,
    index: usize,
    point: Point3<f64>,
    radius: f64,
    tangent: Vector3<f64>,
}

/// Cumulative arc length along a polyline.
fn arc(points: &[Point3<f64>]) -> Vec<f64> {
    let mut cum = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            s += (p - points[i - 1]).norm();
        }
        cum.push(s);
    }
    cum
}

/// Closest point of the polyline to `v`: (its arc length, the point, the distance).
fn project(points: &[Point3<f64>], cum: &[f64], v: &Point3<f64>) -> (f64, Point3<f64>, f64) {
    let mut best = (0.0, points[0], (v - points[0]).norm());
    for i in 0..points.len().saturating_sub(1) {
        let (a, b) = (points[i], points[i + 1]);
        let ab = b - a;
        let len2 = ab.norm_squared();
        let t = if len2 > 0.0 {
            ((v - a).dot(&ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let c = a + ab * t;
        let d = (v - c).norm();
        if d < best.2 {
            best = (cum[i] + t * (cum[i + 1] - cum[i]), c, d);
        }
    }
    best
}

/// The point the first chop lies near: the first junction, else the sharpest bend (the largest
/// turn of the tangent over one radius on each side, away from the branch ends), with its
/// inscribed radius and what it is.
fn feature(cl: &Centerline) -> Option<(Point3<f64>, f64, String)> {
    if let Some(j) = cl.junctions.first() {
        return Some((j.position, j.radius, "junction".into()));
    }
    let mut best: Option<(f64, Point3<f64>, f64)> = None;
    for b in &cl.branches {
        let cum = arc(&b.points);
        let len = cum.last().copied().unwrap_or(0.0);
        for i in 0..b.points.len() {
            let r = b.radius[i];
            if cum[i] < BEND_CLEARANCE * r || len - cum[i] < BEND_CLEARANCE * r {
                continue;
            }
            let before = (0..i).rev().find(|&j| cum[i] - cum[j] >= r);
            let after = (i + 1..b.points.len()).find(|&j| cum[j] - cum[i] >= r);
            let (Some(j), Some(k)) = (before, after) else {
                continue;
            };
            let turn = b.tangent[j].angle(&b.tangent[k]);
            if best.is_none_or(|(t, _, _)| turn > t) {
                best = Some((turn, b.points[i], r));
            }
        }
    }
    best.map(|(turn, p, r)| (p, r, format!("bend {:.0}°", turn.to_degrees())))
}

/// `count` wall points for chops with their local radius and a tag (see the module docs).
fn chop_points(v: &Vessel, rng: &mut SplitMix, count: usize) -> Vec<(Point3<f64>, f64, String)> {
    let sampler = AreaSampler::new(&v.mesh);
    let mut found: Vec<(Point3<f64>, f64, String)> = Vec::new();
    if let Some((q, rq, what)) = v.centerline.as_ref().and_then(feature) {
        for _ in 0..DRAWS {
            let p = sampler.draw(&v.mesh, rng);
            if (p - q).norm() >= NEAR_FEATURE * rq {
                continue;
            }
            let Some(r) = local_vessel_radius(&v.mesh, &v.bvh, &p) else {
                continue;
            };
            if !v.near_end(&p, r) {
                found.push((p, r, what));
                break;
            }
        }
    }
    for apart in [2.0, 1.0] {
        for _ in 0..DRAWS {
            if found.len() == count {
                return found;
            }
            let p = sampler.draw(&v.mesh, rng);
            let Some(r) = local_vessel_radius(&v.mesh, &v.bvh, &p) else {
                continue;
            };
            let near_other = found
                .iter()
                .any(|(q, rq, _)| (q - p).norm() < apart * (r + rq));
            if !v.near_end(&p, r) && !near_other {
                found.push((p, r, "wall".into()));
            }
        }
    }
    found
}

/// With `--end-bites`, instead of the draw's cases: wall points whose chop reaches an open end's
/// rim (its nearest rim vertex between half and 1.2 local radii away, so the chop of
/// [`CHOP`] radii bites 0.3 to 1 radius into the end), up to [`CHOPS`] per vessel, apart as the
/// wall chops. A study of damage at a segmentation's cut end, outside the acceptance's cases.
fn end_bite_points(v: &Vessel, rng: &mut SplitMix) -> Vec<(Point3<f64>, f64, String)> {
    let rims: Vec<Point3<f64>> = boundary_loops(&v.mesh)
        .iter()
        .flatten()
        .map(|&i| v.mesh.vertices[i as usize])
        .collect();
    let mut found: Vec<(Point3<f64>, f64, String)> = Vec::new();
    if rims.is_empty() {
        return found;
    }
    let sampler = AreaSampler::new(&v.mesh);
    for _ in 0..DRAWS {
        if found.len() == CHOPS {
            break;
        }
        let p = sampler.draw(&v.mesh, rng);
        let Some(r) = local_vessel_radius(&v.mesh, &v.bvh, &p) else {
            continue;
        };
        let d = rims
            .iter()
            .map(|q| (q - p).norm())
            .fold(f64::INFINITY, f64::min);
        let apart = found
            .iter()
            .all(|(q, rq, _)| (q - p).norm() >= 2.0 * (r + rq));
        if (0.5 * r..=1.2 * r).contains(&d) && apart {
            found.push((p, r, "end".into()));
        }
    }
    found
}

/// Centreline points for a stenosis or occlusion: `window` radii of branch on both sides whose
/// inscribed radius stays within [R·HEALTHY, R/HEALTHY], more than `clearance` radii from
/// every junction and endpoint; and for each of `uniform` (radii), the site's radius within
/// [`UNIFORM`] of each of those that many radii of arc away on either side ([`level_ratio`]).
fn sites(cl: &Centerline, window: f64, clearance: f64, uniform: &[f64]) -> Vec<Site> {
    let mut out = Vec::new();
    for (bi, b) in cl.branches.iter().enumerate() {
        let cum = arc(&b.points);
        let len = cum.last().copied().unwrap_or(0.0);
        for i in 0..b.points.len() {
            let (p, r) = (b.points[i], b.radius[i]);
            let reach = window * r;
            if !(r > 0.0) || cum[i] < reach || len - cum[i] < reach {
                continue;
            }
            let clear = cl
                .junctions
                .iter()
                .map(|j| j.position)
                .chain(cl.endpoints.iter().map(|e| e.position))
                .all(|q| (q - p).norm() > clearance * r);
            let healthy = (0..b.points.len())
                .filter(|&j| (cum[j] - cum[i]).abs() <= reach)
                .all(|j| b.radius[j] >= HEALTHY * r && b.radius[j] <= r / HEALTHY);
            let level = uniform
                .iter()
                .all(|&w| level_ratio(b, &cum, i, w).is_some_and(|q| (q - 1.0).abs() <= UNIFORM));
            if clear && healthy && level {
                out.push(Site {
                    branch: bi,
                    index: i,
                    point: p,
                    radius: r,
                    tangent: b.tangent[i],
                });
            }
        }
    }
    out
}

/// The inscribed radius at point `i` of branch `b` (`cum`: its arc lengths) over that `w` radii
/// of arc away on the side where the two differ more (at the branch's ends where it is
/// shorter), each averaged over one radius of arc; None where a side has no point.
fn level_ratio(b: &Branch, cum: &[f64], i: usize, w: f64) -> Option<f64> {
    let r = b.radius[i];
    let len = cum.last().copied().unwrap_or(0.0);
    let mean_at = |at: f64| {
        let near: Vec<f64> = (0..b.points.len())
            .filter(|&j| (cum[j] - at).abs() <= r)
            .map(|j| b.radius[j])
            .collect();
        (!near.is_empty()).then(|| near.iter().sum::<f64>() / near.len() as f64)
    };
    let here = mean_at(cum[i])?;
    let (a, c) = (
        mean_at((cum[i] - w * r).max(0.0))?,
        mean_at((cum[i] + w * r).min(len))?,
    );
    // The side farther from level.
    Some(
        [here / a, here / c]
            .into_iter()
            .max_by(|p, q| (p - 1.0).abs().total_cmp(&(q - 1.0).abs()))?,
    )
}

/// A seeded site of [`sites`] at the first clearance of [`SITE_CLEARANCES`] that has one, with
/// that clearance; `window` and `uniform` (radii) as functions of the clearance.
fn pick(
    cl: &Centerline,
    window: impl Fn(f64) -> f64,
    uniform: impl Fn(f64) -> Vec<f64>,
    rng: &mut SplitMix,
) -> Option<(Site, f64)> {
    SITE_CLEARANCES.iter().find_map(|&clearance| {
        let found = sites(cl, window(clearance), clearance, &uniform(clearance));
        let k = (rng.uniform() * found.len() as f64) as usize;
        found.into_iter().nth(k).map(|site| (site, clearance))
    })
}

/// The stenosis's σ, in radii, at a site `clearance` radii from the junctions and ends:
/// [`SIGMA`], shortened in proportion where the clearance had to be relaxed, so that the lesion
/// and the healthy lumen beside it fit the vessel (on the aneurysm's short ICA a lesion of
/// σ = 1.2R reached both of its ends, and no lumen beside it was left unnarrowed to measure
/// it against).
fn stenosis_sigma(clearance: f64) -> f64 {
    SIGMA * clearance / SITE_CLEARANCES[0]
}

/// The note of a site whose clearance had to be relaxed.
fn relaxed(clearance: f64) -> String {
    if clearance < SITE_CLEARANCES[0] {
        format!(
            " (relaxed: {clearance} radii from junctions and ends, none is {} away)",
            SITE_CLEARANCES[0]
        )
    } else {
        String::new()
    }
}

/// `mesh` without the faces `remove` selects.
fn without(mesh: &TriMesh, remove: impl Fn(&[u32; 3]) -> bool) -> TriMesh {
    TriMesh::new(
        mesh.vertices.clone(),
        mesh.faces.iter().filter(|f| !remove(f)).copied().collect(),
    )
}

/// The faces of the largest connected component (by face count).
fn largest_component(mesh: &TriMesh) -> TriMesh {
    let (n, labels) = connected_components(mesh);
    let mut count = vec![0usize; n];
    for &l in &labels {
        count[l as usize] += 1;
    }
    let Some(big) = (0..n).max_by_key(|&c| count[c]) else {
        return mesh.clone();
    };
    TriMesh::new(
        mesh.vertices.clone(),
        mesh.faces
            .iter()
            .zip(&labels)
            .filter(|(_, &l)| l as usize == big)
            .map(|(f, _)| *f)
            .collect(),
    )
}

/// A case of wall damage: `v` without every triangle that has a vertex `inside` the damage, its
/// largest piece kept (every piece with `keep_pieces`), repaired with `--holes`; the note says
/// how many triangles were removed and how many more went with the pieces dropped.
fn cut_case(
    v: &Vessel,
    label: String,
    slug: String,
    region: Ball,
    r: f64,
    keep_pieces: bool,
    inside: impl Fn(&Point3<f64>) -> bool,
) -> Case {
    let holed = without(&v.mesh, |f| {
        f.iter().any(|&i| inside(&v.mesh.vertices[i as usize]))
    });
    let damaged = if keep_pieces {
        holed.clone()
    } else {
        largest_component(&holed)
    };
    let dropped = holed.num_faces() - damaged.num_faces();
    Case {
        label,
        slug,
        kind: Kind::Chop,
        note: format!(
            "{} triangles removed{}",
            v.mesh.num_faces() - holed.num_faces(),
            if dropped > 0 {
                format!(", {dropped} more in smaller pieces")
            } else {
                String::new()
            }
        ),
        damaged,
        region,
        radius: r,
    }
}

fn chop_case(v: &Vessel, n: usize, p: Point3<f64>, r: f64, tag: &str) -> Case {
    let cut = CHOP * r;
    cut_case(
        v,
        format!("chop#{n} ({tag})"),
        format!("chop{n}"),
        Ball {
            center: p,
            radius: CHOP_REGION * r,
        },
        r,
        false,
        |x| (x - p).norm() < cut,
    )
}

/// Which cases a run draws: the acceptance's, or a study's (`--end-bites`, `--shapes`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Study {
    Acceptance,
    EndBites,
    Shapes,
}

/// The damage of the `--shapes` study, one of each per vessel on the chops' wall points.
const SHAPES: [Shape; 5] = [
    Shape::Slit,
    Shape::Ellipsoid,
    Shape::Pair,
    Shape::Small,
    Shape::Big,
];

/// A shape of damage other than the acceptance's ball of 1.5R ([`shape_case`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    /// Within 0.35R of a line along the wall, 2R either side of the point: a slit.
    Slit,
    /// An ellipsoid of semi-axes 2.5R along a random direction and R across it.
    Ellipsoid,
    /// Two balls of 0.9R, 1.6R apart along the wall.
    Pair,
    /// A ball of 0.6R: a hole in the wall alone.
    Small,
    /// A ball of 2.2R, every piece kept: it may cut the vessel in two.
    Big,
}

impl Shape {
    fn as_str(self) -> &'static str {
        match self {
            Shape::Slit => "slit",
            Shape::Ellipsoid => "ellipsoid",
            Shape::Pair => "pair",
            Shape::Small => "small",
            Shape::Big => "big",
        }
    }
}

/// Whether a point lies in a shape of damage.
type InShape = Box<dyn Fn(&Point3<f64>) -> bool>;

/// A uniformly random unit vector.
fn random_direction(rng: &mut SplitMix) -> Vector3<f64> {
    let z = 2.0 * rng.uniform() - 1.0;
    let a = std::f64::consts::TAU * rng.uniform();
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vector3::new(s * a.cos(), s * a.sin(), z)
}

/// The `--shapes` study's case of `shape` on wall point `p` (local radius `r`): every triangle
/// with a vertex in the shape removed, the largest piece kept (every piece for [`Shape::Big`]),
/// as a chop; D = the ball on `p` of 1.3 × the shape's reach from `p`.
fn shape_case(
    v: &Vessel,
    n: usize,
    shape: Shape,
    p: Point3<f64>,
    r: f64,
    tag: &str,
    rng: &mut SplitMix,
) -> Case {
    let normal = v
        .mesh
        .face_normal_raw(v.bvh.closest_point(&p).face as usize)
        .try_normalize(1e-300)
        .unwrap_or_else(Vector3::z);
    // A random direction along the wall (its part along the normal taken off).
    let along_wall = {
        let d = random_direction(rng);
        (d - normal * d.dot(&normal))
            .try_normalize(1e-9)
            .unwrap_or_else(|| {
                normal
                    .cross(&Vector3::x())
                    .try_normalize(1e-9)
                    .unwrap_or_else(Vector3::y)
            })
    };
    let axis = random_direction(rng);
    let pair = p + along_wall * (1.6 * r);
    let (inside, reach): (InShape, f64) = match shape {
        Shape::Slit => (
            Box::new(move |x| {
                let d = x - p;
                let s = d.dot(&along_wall);
                s.abs() < 2.0 * r && (d - along_wall * s).norm() < 0.35 * r
            }),
            2.0 * r,
        ),
        Shape::Ellipsoid => (
            Box::new(move |x| {
                let d = x - p;
                let s = d.dot(&axis);
                (s / (2.5 * r)).powi(2) + ((d - axis * s).norm() / r).powi(2) < 1.0
            }),
            2.5 * r,
        ),
        Shape::Pair => (
            Box::new(move |x| (x - p).norm() < 0.9 * r || (x - pair).norm() < 0.9 * r),
            2.5 * r,
        ),
        Shape::Small => (Box::new(move |x| (x - p).norm() < 0.6 * r), 0.6 * r),
        Shape::Big => (Box::new(move |x| (x - p).norm() < 2.2 * r), 2.2 * r),
    };
    // A big ball may cut the vessel in two: both pieces are kept, a gap to bridge (as the
    // occlusion's); the other shapes leave the wall whole around them.
    cut_case(
        v,
        format!("{}#{n} ({tag})", shape.as_str()),
        shape.as_str().into(),
        Ball {
            center: p,
            radius: 1.3 * reach,
        },
        r,
        shape == Shape::Big,
        inside,
    )
}

fn stenosis_case(v: &Vessel, cl: &Centerline, site: &Site, sigma_radii: f64) -> Case {
    let b = &cl.branches[site.branch];
    let cum = arc(&b.points);
    let others: Vec<(&[Point3<f64>], Vec<f64>)> = cl
        .branches
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != site.branch)
        .map(|(_, o)| (o.points.as_slice(), arc(&o.points)))
        .collect();
    let (s0, r) = (cum[site.index], site.radius);
    let sigma = sigma_radii * r;
    let mut damaged = v.mesh.clone();
    let mut moved = 0;
    let mut centre_ratio = Vec::new();
    // The moved vertex nearest the centre along the axis: a coarse mesh (the coronary's wall
    // triangles are about a radius long) may have none within a quarter radius of it.
    let mut nearest_ratio = (f64::INFINITY, f64::NAN);
    for vertex in damaged.vertices.iter_mut() {
        let (s, c, d) = project(&b.points, &cum, vertex);
        if (s - s0).abs() > MOVE_SIGMAS * sigma || d > MOVE_RADII * r {
            continue;
        }
        if others
            .iter()
            .any(|(pts, cm)| project(pts, cm, vertex).2 < d)
        {
            continue;
        }
        let f = 1.0 - DEGREE * (-(s - s0).powi(2) / (2.0 * sigma * sigma)).exp();
        *vertex = c + (*vertex - c) * f;
        moved += 1;
        if (s - s0).abs() < 0.25 * r {
            centre_ratio.push(f);
        }
        if (s - s0).abs() < nearest_ratio.0 {
            nearest_ratio = ((s - s0).abs(), f);
        }
    }
    Case {
        label: "stenosis 50%".into(),
        slug: "stenosis".into(),
        kind: Kind::Stenosis,
        note: format!(
            "{moved} vertices moved, radius × {} (branch {}, s = {})",
            if centre_ratio.is_empty() {
                format!(
                    "{:.3} at the vertex nearest the centre, {} along the axis from it",
                    nearest_ratio.1,
                    sig(nearest_ratio.0)
                )
            } else {
                format!("{:.3} at the centre", common::surface::median(centre_ratio))
            },
            site.branch,
            sig(s0)
        ),
        damaged,
        region: Ball {
            center: site.point,
            radius: STENOSIS_SIGMAS * sigma,
        },
        radius: r,
    }
}

fn occlusion_case(v: &Vessel, site: &Site) -> Case {
    let (p, r) = (site.point, site.radius);
    let t = site.tangent.normalize();
    let damaged = without(&v.mesh, |f| {
        f.iter().any(|&i| {
            let q = v.mesh.vertices[i as usize] - p;
            q.dot(&t).abs() < SLAB_HALF * r && q.norm() < SLAB_REACH * r
        })
    });
    let loops = boundary_loops(&damaged).len() as i64 - boundary_loops(&v.mesh).len() as i64;
    let pieces = connected_components(&damaged).0;
    Case {
        label: "occlusion".into(),
        slug: "occlusion".into(),
        kind: Kind::Occlusion,
        note: format!(
            "{} triangles removed, {loops:+} boundary loop(s), {pieces} piece(s){}",
            v.mesh.num_faces() - damaged.num_faces(),
            if loops == 2 {
                ""
            } else {
                " (NOT two facing loops)"
            }
        ),
        damaged,
        region: Ball {
            center: p,
            radius: OCCLUSION_REGION * r,
        },
        radius: r,
    }
}

/// The five cases of a vessel (fewer when no place fits), or those of a study: its end bites
/// ([`end_bite_points`]) or its damage of other shapes ([`shape_case`]).
fn cases(v: &Vessel, index: u64, seed: u64, study: Study) -> Vec<Case> {
    let mut out = Vec::new();
    let mut rng = SplitMix(seed ^ (index << 32));
    if study == Study::Shapes {
        let points = chop_points(v, &mut rng, SHAPES.len());
        for (n, ((p, r, tag), shape)) in points.into_iter().zip(SHAPES).enumerate() {
            out.push(shape_case(v, n + 1, shape, p, r, &tag, &mut rng));
        }
        return out;
    }
    if study == Study::EndBites {
        let bites = end_bite_points(v, &mut rng);
        if bites.is_empty() {
            println!("  no open end: no end bite");
        }
        for (n, (p, r, tag)) in bites.into_iter().enumerate() {
            out.push(chop_case(v, n + 1, p, r, &tag));
        }
        return out;
    }
    let chops = chop_points(v, &mut rng, CHOPS);
    if chops.len() < CHOPS {
        println!("  only {} wall point(s) away from the ends", chops.len());
    }
    for (n, (p, r, tag)) in chops.into_iter().enumerate() {
        out.push(chop_case(v, n + 1, p, r, &tag));
    }
    let Some(cl) = &v.centerline else {
        println!("  no centreline: no stenosis or occlusion case");
        return out;
    };
    let mut rng = SplitMix(seed ^ (index << 32) ^ 1);
    // A level site, else (with a note) the vessel's healthy stretch as it is.
    let window = |c: f64| STENOSIS_SIGMAS * stenosis_sigma(c);
    let levels = |c: f64| {
        let sigma = stenosis_sigma(c);
        LEVEL_SIGMAS.iter().map(|k| k * sigma).collect::<Vec<f64>>()
    };
    let picked = pick(cl, window, levels, &mut rng)
        .map(|p| (p, true))
        .or_else(|| pick(cl, window, |_| Vec::new(), &mut rng).map(|p| (p, false)));
    match picked {
        Some(((site, clearance), is_level)) => {
            let sigma = stenosis_sigma(clearance);
            let mut case = stenosis_case(v, cl, &site, sigma);
            case.note += &relaxed(clearance);
            if clearance < SITE_CLEARANCES[0] {
                case.note += &format!(" (σ = {sigma:.2} R)");
            }
            if !is_level {
                let b = &cl.branches[site.branch];
                let cum = arc(&b.points);
                let off: Vec<String> = levels(clearance)
                    .iter()
                    .filter_map(|&w| {
                        let q = level_ratio(b, &cum, site.index, w)?;
                        Some(format!(
                            "{:+.0}% against {w:.1} radii on",
                            100.0 * (q - 1.0)
                        ))
                    })
                    .collect();
                case.note += &format!(
                    " (not level: no site's radius is within {:.0}% of the vessel's on either \
                     side; this one is {})",
                    100.0 * UNIFORM,
                    off.join(", ")
                );
            }
            out.push(case);
        }
        None => {
            println!("  no healthy stretch of 2×3σ away from junctions and ends: no stenosis case")
        }
    }
    let mut rng = SplitMix(seed ^ (index << 32) ^ 2);
    match pick(cl, |_| OCCLUSION_WINDOW, |_| Vec::new(), &mut rng) {
        Some((site, clearance)) => {
            let mut case = occlusion_case(v, &site);
            case.note += &relaxed(clearance);
            out.push(case);
        }
        None => println!("  no healthy stretch away from junctions and ends: no occlusion case"),
    }
    out
}

/// A command run with its output to LOG.out / LOG.err, stopped after `limit`: its wall seconds,
/// or why it failed (the exit status and the last line of stderr).
fn run_limited(cmd: &mut Command, log: &Path, limit: Duration) -> (Result<(), String>, f64) {
    let files = (
        std::fs::File::create(log.with_extension("out")),
        std::fs::File::create(log.with_extension("err")),
    );
    let (Ok(out), Ok(err)) = files else {
        return (Err(format!("cannot write {}", log.display())), 0.0);
    };
    let start = Instant::now();
    let mut child = match cmd.stdout(out).stderr(err).stdin(Stdio::null()).spawn() {
        Ok(c) => c,
        Err(e) => return (Err(format!("cannot start: {e}")), 0.0),
    };
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Ok(status),
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                break Err(format!("stopped after {} s", limit.as_secs()));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(1)),
            Err(e) => break Err(format!("{e}")),
        }
    };
    let secs = start.elapsed().as_secs_f64();
    let result = status.and_then(|s| {
        if s.success() {
            Ok(())
        } else {
            let text = std::fs::read_to_string(log.with_extension("err")).unwrap_or_default();
            Err(format!(
                "{s}: {}",
                text.lines()
                    .rev()
                    .find(|l| !l.trim().is_empty())
                    .unwrap_or("(no message)")
            ))
        }
    });
    (result, secs)
}

/// Judges `output` against the vessel's truth in D.
fn judge(output: &TriMesh, vessel: &Vessel, region: &Ball, h: f64, seconds: f64) -> Outcome {
    let truth = &vessel.judged;
    let balls = [*region];
    let v_truth = volume_in(truth, &balls);
    let info = mesh_info(output);
    Outcome {
        hausdorff_h: hausdorff_in(output, truth, &balls).map_or(f64::INFINITY, |d| d / h),
        volume_pct: 100.0 * (volume_in(output, &balls) - v_truth) / v_truth,
        watertight: info.watertight,
        components: info.components,
        facing_in: info
            .watertight
            .then(|| facing_in_near(output, region, info.signed_volume < 0.0, h)),
        extra_handles: handles(output)
            .zip(vessel.judged_handles)
            .map(|(o, t)| o - t),
        seconds,
        error: None,
    }
}

/// The faces of the closed `output` with a corner within 2 radii of `region`'s centre that do
/// not face out (`faces_not_facing_out`, probed 0.1 of the smaller of the mean edge and `h` off
/// their centroids; an `inward` surface is judged turned outward).
fn facing_in_near(output: &TriMesh, region: &Ball, inward: bool, h: f64) -> usize {
    let flipped;
    let mesh = if inward {
        let mut m = output.clone();
        m.faces.iter_mut().for_each(|f| f.swap(1, 2));
        flipped = m;
        &flipped
    } else {
        output
    };
    let near = Ball {
        center: region.center,
        radius: 2.0 * region.radius,
    };
    let faces: Vec<usize> = (0..mesh.faces.len())
        .filter(|&f| {
            mesh.faces[f]
                .iter()
                .any(|&v| near.contains(&mesh.vertices[v as usize]))
        })
        .collect();
    let winding = WindingNumber::new(mesh, WindingOptions::SIDES);
    let eps = 0.1 * mean_edge_length(mesh).min(h);
    faces_not_facing_out(mesh, &winding, &faces, eps)
}

/// How the user tells ours where D is on the case in `dir`: `--holes` (chop), the point picked
/// at the narrowing (a regions file, pick.json, written here) or `--region` = D (occlusion).
fn region_args(dir: &Path, case: &Case) -> Result<Vec<String>, String> {
    Ok(match case.kind {
        Kind::Chop => vec!["--holes".into()],
        Kind::Stenosis => {
            let c = case.region.center;
            let path = dir.join("pick.json");
            let text = format!("{{\"points\": [[{}, {}, {}]]}}\n", c.x, c.y, c.z);
            std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
            vec!["--regions".into(), path.display().to_string()]
        }
        Kind::Occlusion => {
            let (c, r) = (case.region.center, case.region.radius);
            vec![format!("--region={},{},{},{}", c.x, c.y, c.z, r)]
        }
    })
}

/// Our whole `repair` command on `input` in the case's `dir` with the region flags `regions`,
/// its files named by `tag`: the output and its report, or why not, and the wall seconds.
fn run_ours(
    dir: &Path,
    input: &str,
    tag: &str,
    regions: &[String],
    method: Option<&str>,
) -> (Result<(TriMesh, Value), String>, f64) {
    let out = dir.join(format!("{tag}.stl"));
    let report = dir.join(format!("{tag}.json"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_vesselmsr"));
    cmd.arg("repair")
        .arg(dir.join(input))
        .arg("-o")
        .arg(&out)
        .arg("--report")
        .arg(&report)
        .arg("--picture")
        .arg(dir.join(format!("{tag}.png")))
        .args(regions);
    let limit = if let Some(m) = method {
        cmd.arg("--method").arg(m);
        PAPER_TIME_LIMIT
    } else {
        TIME_LIMIT
    };
    let (status, secs) = run_limited(&mut cmd, &dir.join(tag), limit);
    let result = status.and_then(|()| {
        let mesh = read_mesh(&out).map_err(|e| format!("output: {e}"))?;
        let text = std::fs::read(&report).map_err(|e| format!("report: {e}"))?;
        let json = serde_json::from_slice(&text).map_err(|e| format!("report: {e}"))?;
        Ok((mesh, json))
    });
    (result, secs)
}

/// reference/peers.py on the case in `dir`: its peers.json (read even when the script died, to
/// keep the tools that finished) or why there is none, and the script's wall seconds.
fn run_peers(python: &Path, dir: &Path) -> (Result<Value, String>, f64) {
    let peers = dir.join("peers");
    let _ = std::fs::remove_dir_all(&peers);
    let mut cmd = Command::new(python);
    cmd.arg(common::root().join("reference/peers.py"))
        .arg(dir.join("damaged.stl"))
        .arg("--out-dir")
        .arg(&peers);
    let (status, secs) = run_limited(&mut cmd, &dir.join("peers"), TIME_LIMIT);
    let json = std::fs::read(peers.join("peers.json"))
        .ok()
        .and_then(|t| serde_json::from_slice::<Value>(&t).ok());
    match (json, status) {
        (Some(j), _) => (Ok(j), secs),
        (None, Err(e)) => (Err(e), secs),
        (None, Ok(())) => (Err("no peers.json".into()), secs),
    }
}

/// reference/meshlib_fill.py on the damaged mesh in `dir` (MeshLib as a user runs it, to set
/// beside our whole command): its wall seconds, or why it failed.
fn run_meshlib_whole(python: &Path, dir: &Path) -> Result<f64, String> {
    let mut cmd = Command::new(python);
    cmd.arg(common::root().join("reference/meshlib_fill.py"))
        .arg(dir.join("damaged.stl"))
        .arg(dir.join("meshlib_run.stl"));
    let (status, secs) = run_limited(&mut cmd, &dir.join("meshlib_run"), TIME_LIMIT);
    status.map(|()| secs)
}

/// The oracle's Python with the peers importable, installing reference/requirements-peers.txt
/// into it when they are missing; None (with a notice) when that fails.
fn peers_python() -> Option<PathBuf> {
    let reference = Reference::find_or_notice("the peers (MeshLib, pymeshfix, pymeshlab)")?;
    let python = reference.python().to_path_buf();
    let importable = || {
        Command::new(&python)
            .args(["-c", "import meshlib.mrmeshpy, pymeshfix, pymeshlab"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    if importable() {
        return Some(python);
    }
    let requirements = common::root().join("reference/requirements-peers.txt");
    println!(
        "peers missing: installing them: {} -m pip install -r {}",
        python.display(),
        requirements.display()
    );
    let installed = Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            "-q",
            "-r",
        ])
        .arg(&requirements)
        .status()
        .is_ok_and(|s| s.success());
    if installed && importable() {
        println!("peers installed");
        Some(python)
    } else {
        println!(
            "notice: the peers could not be installed: MeshLib, pymeshfix and pymeshlab skipped"
        );
        None
    }
}

/// Our report's stenosis figures for the damaged input at the region nearest `site`:
/// (NASCET %, diameter stenosis %), and how many narrowings it repaired.
fn report_stenosis(report: &Value, site: &Point3<f64>) -> (Option<f64>, Option<f64>, usize) {
    let regions = report["regions"].as_array().cloned().unwrap_or_default();
    let centre = |r: &Value| -> Option<Point3<f64>> {
        let c = r["center"].as_array()?;
        Some(Point3::new(c[0].as_f64()?, c[1].as_f64()?, c[2].as_f64()?))
    };
    let nearest = regions
        .iter()
        .filter_map(|r| Some((centre(r)?, r)))
        .min_by(|a, b| (a.0 - site).norm().total_cmp(&(b.0 - site).norm()));
    match nearest {
        Some((_, r)) => (
            r["nascet_stenosis_pct"].as_f64(),
            r["diameter_stenosis_pct"].as_f64(),
            regions.len(),
        ),
        None => (None, None, 0),
    }
}

/// The tools in table order.
fn tool_names(paper: bool) -> Vec<&'static str> {
    let mut t = vec!["ours"];
    if paper {
        t.push("ours-paper");
    }
    t.extend(PEERS);
    t
}

/// Runs every tool on `case` (files in `dir`) and judges the outputs.
fn run_case(
    vessel: &Vessel,
    case: &Case,
    dir: &Path,
    python: Option<&Path>,
    paper: bool,
) -> CaseResult {
    let regions = region_args(dir, case);
    let ours_run = |tag: &str, method: Option<&str>| match &regions {
        Ok(args) => run_ours(dir, "damaged.stl", tag, args, method),
        Err(e) => (Err(e.clone()), f64::NAN),
    };
    let mut ours = vec![ours_run("ours", None)];
    if paper {
        ours.push(ours_run("ours-paper", Some("paper")));
    }
    let report = ours[0].0.as_ref().ok().map(|(_, r)| r.clone());
    let voxel = report
        .as_ref()
        .and_then(|r| r["parameters"]["voxel"].as_f64())
        .filter(|h| *h > 0.0);
    let h = voxel.unwrap_or_else(|| {
        let (lo, hi) = bounding_box(&case.damaged);
        default_voxel(mean_edge_length(&case.damaged), (hi - lo).max())
    });
    let mut outcomes = Vec::new();
    for (result, secs) in &ours {
        outcomes.push(Some(match result {
            Ok((mesh, _)) => judge(mesh, vessel, &case.region, h, *secs),
            Err(e) => Outcome::failed(e.clone(), *secs),
        }));
    }
    let mut peers_script = None;
    let meshlib_run = python.filter(|_| case.kind == Kind::Chop).and_then(|py| {
        match run_meshlib_whole(py, dir) {
            Ok(s) => Some(s),
            Err(e) => {
                println!("    meshlib_fill.py: {e}");
                None
            }
        }
    });
    match python {
        None => outcomes.extend(PEERS.map(|_| None)),
        Some(py) => {
            let (json, secs) = run_peers(py, dir);
            peers_script = Some(secs);
            for peer in PEERS {
                let outcome = match &json {
                    Err(e) => Outcome::failed(format!("peers.py: {e}"), f64::NAN),
                    Ok(j) => {
                        let t = &j["tools"][peer];
                        let seconds = t["seconds"].as_f64().unwrap_or(f64::NAN);
                        match (t["output"].as_str(), t["error"].as_str()) {
                            (Some(path), None) => match read_mesh(Path::new(path)) {
                                Ok(m) => judge(&m, vessel, &case.region, h, seconds),
                                Err(e) => Outcome::failed(format!("output: {e}"), seconds),
                            },
                            (_, Some(e)) => Outcome::failed(e.to_string(), seconds),
                            (None, None) => Outcome::failed("not run".into(), seconds),
                        }
                    }
                };
                outcomes.push(Some(outcome));
            }
        }
    }
    let stenosis = (case.kind == Kind::Stenosis).then(|| {
        let (nascet, diameter) = match &report {
            Some(r) => {
                let (nascet, diameter, _) = report_stenosis(r, &case.region.center);
                (nascet, diameter)
            }
            None => (None, None),
        };
        // The same pick on the truth: the vessel's own narrowing there, if any, which the
        // synthetic lesion (a fraction of the local radius) narrows further.
        let own = match &regions {
            Ok(args) => run_ours(dir, "truth.stl", "truth-pick", args, None).0,
            Err(e) => Err(e.clone()),
        };
        let own = own
            .ok()
            .and_then(|(_, r)| report_stenosis(&r, &case.region.center).1);
        StenosisReading {
            nascet,
            diameter,
            own,
        }
    });
    let our_fill = report
        .as_ref()
        .and_then(|r| r["regions"].as_array().cloned())
        .map(|regions| {
            regions
                .iter()
                .map(|g| g["fill"].as_str().unwrap_or("?").to_string())
                .collect::<Vec<_>>()
                .join("+")
        })
        .unwrap_or_default();
    let our_timings = report
        .as_ref()
        .and_then(|r| r["timings"].as_object().cloned())
        .map(|t| {
            t.iter()
                .map(|(k, v)| format!("{k} {:.2}", v.as_f64().unwrap_or(f64::NAN)))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .unwrap_or_default();
    if let Some(r) = &report {
        if let Some(why) = r["parameters"]["fallback"].as_str() {
            println!("    ours: whole vessel re-meshed ({why})");
        }
    }
    if case.kind == Kind::Stenosis {
        // Beside the pick: every narrowing of 20% or more repaired, the vessel's own included
        // (the truth keeps those, so they count against it here).
        let (all, secs) = run_ours(
            dir,
            "damaged.stl",
            "ours-stenoses",
            &["--stenoses".to_string()],
            None,
        );
        match &all {
            Ok((mesh, r)) => {
                let o = judge(mesh, vessel, &case.region, h, secs);
                let (_, _, n) = report_stenosis(r, &case.region.center);
                println!(
                    "    ours with --stenoses instead of the pick: {} h, {} ({n} narrowing(s) \
                     repaired)",
                    fmt_h(o.hausdorff_h),
                    fmt_pct(o.volume_pct)
                );
            }
            Err(e) => println!("    ours with --stenoses instead of the pick: failed ({e})"),
        }
    }
    CaseResult {
        label: case.label.clone(),
        kind: case.kind,
        h,
        h_rule: match (voxel, &report) {
            (Some(_), _) => None,
            (None, Some(_)) => Some("ours inpainted nothing"),
            (None, None) => Some("ours failed"),
        },
        input: judge(&case.damaged, vessel, &case.region, h, f64::NAN),
        outcomes,
        peers_script,
        meshlib_run,
        stenosis,
        our_timings,
        our_fill,
    }
}

fn fmt_h(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2}")
    } else {
        "failed".into()
    }
}

fn fmt_pct(x: f64) -> String {
    if x.is_finite() {
        format!("{x:+.1}%")
    } else {
        "-".into()
    }
}

fn fmt_s(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "-".into()
    }
}

fn print_row(case: &str, tool: &str, o: &Outcome) {
    println!(
        "  {case:<22} {tool:<11} {:>8} {:>9} {:>10} {:>5} {:>9} {:>8}{}",
        fmt_h(o.hausdorff_h),
        fmt_pct(o.volume_pct),
        if o.error.is_some() {
            "-"
        } else if o.watertight {
            "yes"
        } else {
            "no"
        },
        if o.error.is_some() {
            "-".to_string()
        } else {
            o.components.to_string()
        },
        o.facing_in.map_or("-".to_string(), |n| n.to_string()),
        fmt_s(o.seconds),
        o.error
            .as_ref()
            .map_or(String::new(), |e| format!("  ({e})"))
    );
}

/// Per tool, "{tool} {shown}": `shown` of the values `field` gives on its outputs (those it has).
fn per_tool<T>(
    results: &[CaseResult],
    tools: &[&str],
    field: impl Fn(&Outcome) -> Option<T>,
    shown: impl Fn(&[T]) -> String,
) -> String {
    tools
        .iter()
        .enumerate()
        .map(|(t, tool)| {
            let values: Vec<T> = results
                .iter()
                .filter_map(|r| r.outcomes[t].as_ref().and_then(&field))
                .collect();
            format!("{tool} {}", shown(&values))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

fn print_vessel_table(results: &[CaseResult], tools: &[&str]) {
    println!(
        "  {:<22} {:<11} {:>8} {:>9} {:>10} {:>5} {:>9} {:>8}",
        "case", "tool", "H in D h", "vol in D", "watertight", "comp", "facing in", "seconds"
    );
    for r in results {
        print_row(&r.label, "(damaged)", &r.input);
        for (tool, o) in tools.iter().zip(&r.outcomes) {
            if let Some(o) = o {
                print_row("", tool, o);
            }
        }
        let mut notes = vec![format!(
            "h = {}{}",
            sig(r.h),
            r.h_rule.map_or(String::new(), |why| format!(
                " (the default-voxel rule: {why})"
            ))
        )];
        if let Some(st) = &r.stenosis {
            let pct = |p: Option<f64>| p.map_or("n/a".into(), |p| format!("{p:.1}%"));
            notes.push(format!(
                "our report on the damaged input: NASCET {}, diameter stenosis {} (on the truth \
                 at the same pick {})",
                pct(st.nascet),
                pct(st.diameter),
                pct(st.own)
            ));
        }
        if let Some(s) = r.peers_script {
            notes.push(format!("peers.py whole script {s:.2} s"));
        }
        if let Some(s) = r.meshlib_run {
            notes.push(format!("MeshLib as a user runs it {s:.2} s"));
        }
        println!("  {:<22} {}", "", notes.join("; "));
        if !r.our_timings.is_empty() {
            println!("  {:<22} ours' report timings (s): {}", "", r.our_timings);
        }
    }
}

fn print_summary(results: &[CaseResult], tools: &[&str]) {
    let n = results.len();
    println!(
        "\nsummary over {n} case(s) (a failed output counts as an infinite Hausdorff distance)"
    );
    println!(
        "  {:<11} {:>10} {:>12} {:>15} {:>10}   {}",
        "tool", "median H h", "median |vol|", "<= 1.5h & 5%", "<= 3h", "per kind: median H h"
    );
    for (t, tool) in tools.iter().enumerate() {
        let got: Vec<(&CaseResult, &Outcome)> = results
            .iter()
            .filter_map(|r| r.outcomes[t].as_ref().map(|o| (r, o)))
            .collect();
        if got.is_empty() {
            println!("  {tool:<11} not run");
            continue;
        }
        let hd: Vec<f64> = got.iter().map(|(_, o)| o.hausdorff_h).collect();
        let vol: Vec<f64> = got
            .iter()
            .map(|(_, o)| {
                let v = o.volume_pct.abs();
                if v.is_finite() {
                    v
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        let good = got
            .iter()
            .filter(|(_, o)| o.hausdorff_h <= 1.5 && o.volume_pct.abs() <= 5.0)
            .count();
        let within3 = got.iter().filter(|(_, o)| o.hausdorff_h <= 3.0).count();
        let per_kind: Vec<String> = Kind::ALL
            .iter()
            .filter_map(|k| {
                let v: Vec<f64> = got
                    .iter()
                    .filter(|(r, _)| r.kind == *k)
                    .map(|(_, o)| o.hausdorff_h)
                    .collect();
                (!v.is_empty()).then(|| format!("{} {}", k.as_str(), fmt_h(median_all(v))))
            })
            .collect();
        println!(
            "  {tool:<11} {:>10} {:>11.1}% {:>15} {:>10}   {}",
            fmt_h(median_all(hd)),
            median_all(vol),
            format!("{good}/{}", got.len()),
            format!("{within3}/{}", got.len()),
            per_kind.join(", ")
        );
    }
    // Faces near D that do not face out, per tool, over its closed outputs (a fold of the seam,
    // a slit; an input's own folds outside D count for every tool that keeps them).
    println!(
        "  faces within 2 radii of D that do not face out (closed outputs): {}",
        per_tool(
            results,
            tools,
            |o| o.facing_in,
            |counts| format!(
                "{} in {} of {}",
                counts.iter().sum::<usize>(),
                counts.iter().filter(|&&n| n > 0).count(),
                counts.len()
            )
        )
    );
    // Outputs with a handle the truth does not have: a tunnel through the vessel.
    println!(
        "  outputs with more handles than the truth (a tunnel through the vessel): {}",
        per_tool(
            results,
            tools,
            |o| o.extra_handles,
            |extra| format!(
                "{} of {}",
                extra.iter().filter(|&&n| n > 0).count(),
                extra.len()
            )
        )
    );
    // Ours by how the regions were filled (the report's `fill`): where the fill is least sure.
    let mut fills: Vec<&str> = results.iter().map(|r| r.our_fill.as_str()).collect();
    fills.sort_unstable();
    fills.dedup();
    let by_fill: Vec<String> = fills
        .iter()
        .filter(|f| !f.is_empty())
        .map(|f| {
            let hd: Vec<f64> = results
                .iter()
                .filter(|r| r.our_fill == *f)
                .filter_map(|r| r.outcomes[0].as_ref().map(|o| o.hausdorff_h))
                .collect();
            let beyond = hd.iter().filter(|&&h| h > 3.0).count();
            format!(
                "{f} {} (median {}, beyond 3h {beyond})",
                hd.len(),
                fmt_h(median_all(hd))
            )
        })
        .collect();
    if !by_fill.is_empty() {
        println!("  ours by fill: {}", by_fill.join(", "));
    }
    // The stenosis readings against the lesion made (half the truth's local diameter).
    let readings: Vec<&StenosisReading> =
        results.iter().filter_map(|r| r.stenosis.as_ref()).collect();
    if !readings.is_empty() {
        let within = readings
            .iter()
            .filter(|s| {
                s.diameter
                    .is_some_and(|d| (d - 100.0 * DEGREE).abs() <= 5.0)
            })
            .count();
        println!(
            "  our diameter stenosis at the pick within 50 ± 5% on {within} of {}",
            readings.len()
        );
    }
    // Ours (the default method) against each other tool, case by case.
    for (t, tool) in tools.iter().enumerate().skip(1) {
        let pairs: Vec<(&Outcome, &Outcome, Kind)> = results
            .iter()
            .filter_map(|r| Some((r.outcomes[0].as_ref()?, r.outcomes[t].as_ref()?, r.kind)))
            .collect();
        if pairs.is_empty() {
            continue;
        }
        let wins = pairs.iter().filter(|(a, b, _)| a.beats(b)).count();
        let per_kind: Vec<String> = Kind::ALL
            .iter()
            .filter_map(|k| {
                let of: Vec<_> = pairs.iter().filter(|p| p.2 == *k).collect();
                (!of.is_empty()).then(|| {
                    format!(
                        "{} {}/{}",
                        k.as_str(),
                        of.iter().filter(|(a, b, _)| a.beats(b)).count(),
                        of.len()
                    )
                })
            })
            .collect();
        println!(
            "  ours beats {tool} on {wins} of {} case(s) ({})",
            pairs.len(),
            per_kind.join(", ")
        );
    }
    // Speed on the chops: our whole command against MeshLib's fillHoleNicely call, and against
    // MeshLib run whole as a user runs it.
    if let Some(m) = tools.iter().position(|t| *t == "meshlib") {
        let rows: Vec<(f64, f64, f64, f64)> = results
            .iter()
            .filter(|r| r.kind == Kind::Chop)
            .filter_map(|r| {
                let ours = r.outcomes[0].as_ref()?;
                let ml = r.outcomes[m].as_ref()?;
                (ours.error.is_none() && ml.error.is_none()).then_some((
                    ours.seconds,
                    ml.seconds,
                    r.peers_script.unwrap_or(f64::NAN),
                    r.meshlib_run.unwrap_or(f64::NAN),
                ))
            })
            .collect();
        if !rows.is_empty() {
            let spread = |ratios: &[f64]| {
                let lo = ratios.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = ratios.iter().copied().fold(0.0, f64::max);
                (median_all(ratios.to_vec()), lo, hi)
            };
            let call: Vec<f64> = rows.iter().map(|r| r.0 / r.1).collect();
            let (call_med, call_lo, call_hi) = spread(&call);
            println!(
                "  speed on {} chop(s): ours' whole command median {:.2} s ({:.2}–{:.2} s), MeshLib fillHoleNicely median {:.3} s; ratio ours / MeshLib median {:.0}× ({:.0}–{:.0}×); peers.py's whole script (three peers, Python start-up) median {:.2} s",
                rows.len(),
                median_all(rows.iter().map(|r| r.0).collect()),
                rows.iter().map(|r| r.0).fold(f64::INFINITY, f64::min),
                rows.iter().map(|r| r.0).fold(0.0, f64::max),
                median_all(rows.iter().map(|r| r.1).collect()),
                call_med,
                call_lo,
                call_hi,
                median_all(rows.iter().map(|r| r.2).collect()),
            );
            let whole: Vec<f64> = rows
                .iter()
                .filter(|r| r.3.is_finite())
                .map(|r| r.0 / r.3)
                .collect();
            if !whole.is_empty() {
                let (med, lo, hi) = spread(&whole);
                println!(
                    "  MeshLib as a user runs it (reference/meshlib_fill.py: Python start-up, import, its own reader, the fill, its own writer) on {} chop(s): median {:.2} s; ratio ours' whole command / MeshLib's whole run, per chop: median {:.2}× ({:.2}–{:.2}×)",
                    whole.len(),
                    median_all(rows.iter().map(|r| r.3).filter(|s| s.is_finite()).collect()),
                    med,
                    lo,
                    hi,
                );
            }
        }
    }
}

/// The vessel read, its centreline traced, its ends listed; None (with a line) when unusable.
fn load_vessel(path: &Path) -> Option<Vessel> {
    let name = path.file_stem()?.to_string_lossy().to_string();
    let mesh = match read_mesh(path) {
        Ok(m) => m,
        Err(e) => {
            println!("  skipping {name}: {e}");
            return None;
        }
    };
    let centerline = match compute_centerline(&mesh, &CenterlineOptions::default()) {
        Ok((cl, _)) => Some(cl),
        Err(e) => {
            println!("  {name}: no centreline ({e})");
            None
        }
    };
    let mut ends: Vec<Point3<f64>> = boundary_loops(&mesh)
        .iter()
        .flatten()
        .map(|&v| mesh.vertices[v as usize])
        .collect();
    if let Some(cl) = &centerline {
        ends.extend(cl.endpoints.iter().map(|e| e.position));
    }
    let bvh = MeshBvh::new(&mesh);
    let judged = if boundary_loops(&mesh).is_empty() {
        mesh.clone()
    } else {
        let opts = CapOptions {
            orient_outward: false,
            ..CapOptions::default()
        };
        match cap_holes(&mesh, &opts) {
            Ok((closed, _)) => closed,
            Err(e) => {
                println!("  {name}: its open ends could not be capped ({e}): judged open");
                mesh.clone()
            }
        }
    };
    Some(Vessel {
        name,
        judged_handles: handles(&judged),
        judged,
        mesh,
        bvh,
        centerline,
        ends,
    })
}

fn main() {
    let start = Instant::now();
    println!(
        "vesselmsr repair on real damage against peers ({} rayon threads; load {}; the machine is shared: timings vary)",
        rayon::current_num_threads(),
        load()
    );
    let mut args = std::env::args().skip(1);
    let mut only = Vec::new();
    let mut keep: Option<PathBuf> = None;
    let mut study = Study::Acceptance;
    let mut seeds = vec![SEED];
    seeds.extend(HELD_OUT);
    while let Some(a) = args.next() {
        if a == "--seed" {
            match args.next().and_then(|s| s.parse().ok()) {
                Some(s) => seeds = vec![s],
                None => {
                    eprintln!("repair_real: --seed needs a whole number");
                    std::process::exit(2);
                }
            }
        } else if a == "--keep" {
            keep = args.next().map(PathBuf::from);
        } else if let Some(dir) = a.strip_prefix("--keep=") {
            keep = Some(PathBuf::from(dir));
        } else if a == "--end-bites" {
            study = Study::EndBites;
        } else if a == "--shapes" {
            study = Study::Shapes;
        } else if !a.starts_with("--") {
            only.push(a);
        }
    }
    if seeds.len() > 1 {
        println!("reproduce: cargo bench --bench repair_real (one draw: -- --seed N)");
    } else {
        println!(
            "reproduce: cargo bench --bench repair_real -- --seed {}",
            seeds[0]
        );
    }
    let data = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"));
    if !data.is_dir() {
        println!("notice: ../shared/data/real not found: repair_real benchmark skipped");
        return;
    }
    let paper = std::env::var_os("VESSELMSR_BENCH_PAPER").is_some();
    let python = peers_python();
    let tmp = tempfile::tempdir().expect("a temporary folder");
    let root = keep.clone().unwrap_or_else(|| tmp.path().to_path_buf());
    let tools = tool_names(paper);
    let mut vessels = Vec::new();
    for (index, file) in REAL_VESSELS.iter().enumerate() {
        if !only.is_empty() && !only.iter().any(|o| file.contains(o.as_str())) {
            continue;
        }
        let path = data.join(file);
        if !path.is_file() {
            println!("notice: {} not found: skipped", path.display());
            continue;
        }
        if let Some(vessel) = load_vessel(&path) {
            vessels.push((index as u64, vessel));
        }
    }
    let mut all = Vec::new();
    for &seed in &seeds {
        println!(
            "\n######## seed {seed}{}",
            if seed == SEED {
                " (the draw the acceptance is judged on)"
            } else {
                " (held out: no change was tuned on it)"
            }
        );
        let mut drawn = Vec::new();
        for (index, vessel) in &vessels {
            let cl = vessel.centerline.as_ref();
            println!(
                "\n== {}: {} vertices, {} triangles, {} boundary loop(s); centreline {} branch(es), {} junction(s)",
                vessel.name,
                vessel.mesh.num_vertices(),
                vessel.mesh.num_faces(),
                boundary_loops(&vessel.mesh).len(),
                cl.map_or(0, |c| c.branches.len()),
                cl.map_or(0, |c| c.junctions.len()),
            );
            let mut results = Vec::new();
            for case in cases(vessel, *index, seed, study) {
                let c = case.region.center;
                println!(
                    "  {}: R = {}, D = ball ({}, {}, {}) radius {}; {}",
                    case.label,
                    sig(case.radius),
                    sig(c.x),
                    sig(c.y),
                    sig(c.z),
                    sig(case.region.radius),
                    case.note
                );
                let dir = root
                    .join(format!("seed{seed}"))
                    .join(&vessel.name)
                    .join(&case.slug);
                let written = std::fs::create_dir_all(&dir)
                    .map_err(|e| e.to_string())
                    .and_then(|()| {
                        write_mesh(&dir.join("damaged.stl"), &case.damaged)
                            .map_err(|e| e.to_string())?;
                        write_mesh(&dir.join("truth.stl"), &vessel.mesh)
                            .map_err(|e| e.to_string())?;
                        write_regions(&dir.join("d.json"), &[case.region])
                            .map_err(|e| e.to_string())
                    });
                if let Err(e) = written {
                    println!("  skipping {}: cannot write its files: {e}", case.label);
                    continue;
                }
                results.push(run_case(vessel, &case, &dir, python.as_deref(), paper));
            }
            print_vessel_table(&results, &tools);
            drawn.extend(results);
        }
        println!("\nseed {seed}:");
        print_summary(&drawn, &tools);
        all.extend(drawn);
    }
    if seeds.len() > 1 {
        println!(
            "\nall {} draws (seeds {}):",
            seeds.len(),
            seeds
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
        print_summary(&all, &tools);
    }
    if let Some(dir) = &keep {
        println!("case files kept in {}", dir.display());
    }
    println!(
        "\nbenchmark took {:.1} s; load now {}",
        start.elapsed().as_secs_f64(),
        load()
    );
}
