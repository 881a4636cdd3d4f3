//! Vessel repair by surface inpainting (paper Section 4, Algorithm 4 with eq. 4.1 and 4.2):
//! the damaged regions D (`region`), synthetic damaged vessels with known truth (`phantom`), and
//! the inpainting loop itself (`repair`), and the whole repair of a vessel as the CLI and the
//! Python package run it (`pipeline`: regions, checks, repair, report).

pub mod adaptive;
pub mod axial;
pub mod axis;
pub mod checks;
pub(crate) mod groups;
pub mod guided;
pub mod harmonic;
pub mod holes;
pub mod junction;
pub mod known_wall;
pub mod mask;
pub mod msr_fill;
pub mod paper;
pub mod phantom;
pub mod pipeline;
pub mod region;
pub mod region_limits;
pub mod repair;
pub mod repair_budget;
pub mod shave;
pub mod stitch;
pub mod topology;
pub mod tunnel;
pub mod wall_chart;
pub mod widen;
