//! The jobs of the command line and their options: `sdg mesh` here, `sdg run` in the solve.

mod mesh;
mod options;

pub use mesh::{MeshSummary, mesh_job, pitch_to_end};
pub use options::RunOptions;
