//! Figures of the multiscale representation, drawn headless in Rust (no display, no GPU, no
//! system fonts): `render` rasterises surfaces coloured by a per-vertex scalar (the scales
//! S_0 … S_N coloured by the detail w_i, Figure 1 of Dong, Chien, Shen and Osher), `histogram`
//! draws the per-level detail histograms as small multiples (their Figure 2), `colormap` holds
//! the colour maps, and `image` the RGB raster and its atomic PNG writer.

pub mod centerline_plot;
pub mod colormap;
pub mod histogram;
pub mod image;
pub mod profile_plot;
mod raster;
pub mod render;
pub mod repair_picture;
pub mod repair_report;
pub mod stenosis;
pub(crate) mod text;

pub use colormap::ColorMap;
pub use histogram::{histogram, histogram_grid, Histogram, HistogramFigure, HistogramOptions};
pub use image::{write_png, RgbImage};
pub use render::{render_mesh, render_strip, Camera, Panel, RenderOptions, StripOptions};
pub use repair_picture::{
    picture_layout, render_repair, repair_picture, repair_view, PictureLayout,
    RepairPictureOptions, RepairView,
};
