//! The engine: configuration, problem setup, the run loop wiring mesh, solver and scheduler, and
//! the outputs of a run.

mod adaptivity;
pub mod config;
pub mod distributed_run;
pub mod error;
pub mod estimate;
mod exact_sum;
pub mod fracture;
mod frontier;
pub mod job;
pub mod lefm;
pub mod output;
pub mod plot;
pub mod problem;
pub mod progress;
mod rank_checkpoint;
mod rank_finish;
mod rank_outputs;
mod rank_prior;
mod rank_rounds;
mod rank_run;
mod rank_setup;
mod rank_tally;
pub mod solve;
pub mod study;
pub mod trace;

pub use config::{Config, ConfigError, LoadedConfig};
#[cfg(feature = "mpi")]
pub use distributed_run::solve_mpi;
pub use distributed_run::{
    PartitionKind, RankOptions, causality, partition_for, physics, solve_ranks,
};
pub use error::EngineError;
pub use estimate::Estimate;
pub use fracture::{CrackNetwork, CrackSummary, FractureSummary};
pub use job::{MeshSummary, RunOptions, mesh_job, pitch_to_end};
pub use output::spacetime::SpacetimeMesh;
pub use problem::Problem;
pub use solve::{Control, RunSummary, estimate_job, solve_job};
#[doc(hidden)]
pub use solve::{Live, solve_job_with};
pub use study::{Study, StudyError};
