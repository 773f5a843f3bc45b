//! What a run over ranks did before it (re)started: nothing for a new run, or the
//! bookkeeping of the checkpoint it restarted from (module `rank_checkpoint`), which the
//! outputs (module `rank_outputs`) and the next checkpoints continue.

use std::path::PathBuf;

use sdg_mesh::Front;
use sdg_solver::element::FrontSolution;
use sdg_solver::patch::PatchReport;

use crate::error::EngineError;
use crate::output::snapshot::Snapshots;
use crate::problem::Problem;
use crate::solve::CheckpointSummary;
use crate::solve::book::Records;
use crate::solve::checkpoint::{Folder, Restored};

/// What a run over ranks did before it (re)started: nothing for a new run, the checkpoint's
/// bookkeeping for a restarted one.
#[derive(Debug)]
pub(crate) struct Prior {
    /// Tents before, with their reports summed, elements, degrees of freedom and Newton counts.
    pub(crate) patches: u64,
    pub(crate) totals: PatchReport,
    pub(crate) elements: u64,
    pub(crate) dofs: u64,
    pub(crate) nonlinear: u64,
    pub(crate) newton: u64,
    pub(crate) newton_max: usize,
    /// The largest `c_max |grad t|` before.
    pub(crate) max_slope_ratio: f64,
    /// `history.csv` so far (header and rows), empty for a new run.
    pub(crate) history: String,
    /// The latest time of the checkpoint's front, s (0 for a new run): history rows at times
    /// up to it are in `history` or left out.
    pub(crate) reached: f64,
    /// Wall time of the solve before, s, and checkpoints numbered before.
    pub(crate) wall_time_s: f64,
    pub(crate) written: u64,
    /// The checkpoint (re)started from and its front's least time on the config's clock, s.
    pub(crate) restarted: Option<(PathBuf, f64)>,
    /// Its snapshots (schedule, files written, slices pending), for a restart.
    pub(crate) snapshots: Option<Snapshots>,
    /// Crack-tracking crossings and probe samples before.
    pub(crate) records: Records,
}

impl Prior {
    /// The prior of a new run.
    pub(crate) fn fresh() -> Self {
        Self {
            patches: 0,
            totals: PatchReport::default(),
            elements: 0,
            dofs: 0,
            nonlinear: 0,
            newton: 0,
            newton_max: 0,
            max_slope_ratio: 0.0,
            history: String::new(),
            reached: 0.0,
            wall_time_s: 0.0,
            written: 0,
            restarted: None,
            snapshots: None,
            records: Records::default(),
        }
    }

    /// The prior of a run restarted from `restored` (read from `file`) of `problem`, numbering
    /// its checkpoints after those in `folder`; returns it with the checkpoint's front and
    /// elements. A checkpoint with mesh-changing state, or a restart that moves the end time
    /// or the snapshot times, is refused (exit 2).
    pub(crate) fn restored(
        problem: &Problem,
        (file, restored): (PathBuf, Restored),
        folder: &Folder,
    ) -> Result<(Self, Front, FrontSolution), EngineError> {
        let config = &problem.loaded.config;
        let refuse = |reason: &str| {
            EngineError::Input(format!(
                "--restart {}: {reason}; restart it on threads (without --ranks or --mpi)",
                file.display()
            ))
        };
        if restored.frontier.mesh.vertices().len() != problem.mesh.vertices().len()
            || restored.frontier.mesh.triangles().len() != problem.mesh.triangles().len()
        {
            return Err(refuse("its mesh was changed by events"));
        }
        if crate::solve::checkpoint::extends(&restored.header.config, config) {
            return Err(refuse(
                "time.end or output.snapshot_times differ from the checkpoint's, which a run \
                 over ranks cannot move yet",
            ));
        }
        let book = restored.book;
        let front = restored.frontier.front;
        let reached = front.snapshot().into_iter().fold(0.0, f64::max);
        let prior = Self {
            patches: book.patches,
            totals: book.totals,
            elements: book.elements,
            dofs: book.dofs,
            nonlinear: book.nonlinear_patches,
            newton: book.newton_iterations,
            newton_max: book.newton_max,
            max_slope_ratio: book.max_slope_ratio,
            history: book.history,
            reached,
            wall_time_s: restored.counts.wall_time_s,
            written: folder.next_number(restored.counts.written),
            restarted: Some((file, config.time.clock(restored.header.time))),
            snapshots: Some(book.snapshots),
            records: Records {
                crossings: book.crossings,
                samples: book.samples,
            },
        };
        Ok((prior, front, restored.frontier.solution))
    }

    /// The checkpoint part of `summary.json` for `written` checkpoints written in
    /// `write_seconds`.
    pub(crate) fn summary(&self, written: u64, write_seconds: f64) -> CheckpointSummary {
        CheckpointSummary {
            written,
            restarted_from: self.restarted.as_ref().map(|r| r.0.clone()),
            restart_time: self.restarted.as_ref().map(|r| r.1),
            write_seconds,
        }
    }
}
