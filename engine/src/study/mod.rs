//! Studies: ensembles of runs of one config over the product of axes of config values, with
//! statistics over the draws (`sdg study`, `docs/reference/study.md`).
//!
//! A study file names a base config, the `summary.json` keys to collect (metrics), the axes
//! (config keys and their values; a `{ draws = N, first = F }` axis is the draws) and overrides
//! for every case. [`Study::load`] reads and checks the file, [`Study::prepare`] loads every
//! case's config (so that a bad key or value is refused before anything runs),
//! [`run_cases`] runs what is not finished, and [`collect`] writes `study.csv`, `study.json`
//! and `study.png`.

mod cases;
mod error;
mod file;
mod metrics;
mod picture;
mod record;
mod runner;
mod slurm;
mod stats;
mod table;

pub use cases::{Axis, Case, case_dir, config_hash};
pub use error::StudyError;
pub use file::Study;
pub use metrics::{metric_keys, metric_value};
pub use record::{CaseStatus, Collected, case_status};
pub use runner::{CHECKPOINT_BYTE, RunPlan, STUDY_ENV, Stop, Tally, run_cases};
pub use slurm::write_slurm;
pub use stats::{Stats, t_975};
pub use table::collect;
