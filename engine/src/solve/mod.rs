//! `sdg run`: the SDG solve, tents pitched and solved by the scheduler's workers.
//!
//! Each worker owns a patch solver (its scratch memory). A tent pitches on the shared front,
//! solves its patch and hands a report to the bookkeeping (`book`), which sums energy terms,
//! cuts snapshots and notices when the whole front has passed a milestone time: a snapshot is
//! then complete, or a history row is due. History rows integrate the energy over the whole
//! front, so they run as scheduler events over every vertex: with no tent in flight.
//!
//! `run` lists the stages of a solve; `start` builds the initial front, `context` holds what
//! every tent reads, `tent` solves one, `work` hands tents and their events to the scheduler,
//! `outputs` writes the files, `restart` the checkpoints.

pub(crate) mod book;
pub(crate) mod checkpoint;
pub(crate) mod context;
pub(crate) mod control;
pub(crate) mod finish;
pub(crate) mod history;
pub(crate) mod outputs;
pub(crate) mod restart;
pub(crate) mod run;
pub(crate) mod split;
pub(crate) mod start;
pub(crate) mod summary;
pub(crate) mod tent;
pub(crate) mod work;

pub use context::Live;
pub use control::Control;
pub use run::{solve_job, solve_job_with};
pub use start::estimate_job;
pub use summary::{
    CheckpointSummary, DistributedSummary, EnergySummary, ErrorSummary, InterfaceSummary,
    RankSummary, RunSummary, Timings,
};
