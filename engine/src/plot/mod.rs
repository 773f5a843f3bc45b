//! Pictures of runs, rendered headless to PNG: a field on the triangles of a slice
//! ([`FieldPlot`]), line charts ([`LineChart`], e.g. `history.png`), and `sdg plot` on a VTU file
//! ([`plot_vtu`]).
//!
//! Text is drawn by plotters with DejaVu Sans, shipped in `engine/assets` (license beside it) and
//! registered once from the bytes compiled in; nothing is read from the system.

mod canvas;
mod command;
mod crack;
mod field;
mod lefm;
mod line;
mod vtu;

pub use canvas::{Image, tick_label, tick_label_within};
pub use command::{
    FIELD_PNG_SIZE, HISTORY_PNG_SIZE, PlotRequest, history_chart, plot_vtu, write_history_png,
};
pub use crack::{
    CRACK_PNG_SIZE, Normalization, crack_charts, plot_tips, write_crack_png, write_tip_speed_png,
};
pub use field::{FieldLayout, FieldPlot, Values, viridis};
pub use lefm::{G_WINDOW, plot_lefm};
pub use line::{LineChart, LineStyle};
pub use vtu::VtuGrid;
