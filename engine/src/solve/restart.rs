//! Checkpoints written by a running solve, and a restart that moves the end time.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::EngineError;
use crate::frontier::Frontier;

use super::book::{Book, Milestones};
use super::checkpoint::{self, Counts};
use super::context::Solve;
use super::summary::*;

impl Solve<'_> {
    /// Writes a checkpoint of `state`, quiescent (no tent in flight, no event queued), once the
    /// snapshots it counts as written are on disk; counts it in `counts` and `summary`. A run
    /// that writes no files ([`Solve::writes`]) counts it and returns where rank 0 writes it.
    pub(crate) fn checkpoint(
        &self,
        folder: &checkpoint::Folder,
        state: &Frontier,
        counts: &mut Counts,
        summary: &mut CheckpointSummary,
    ) -> Result<PathBuf, EngineError> {
        let config = &self.problem.loaded.config;
        if !self.writes() {
            let path = folder.path(counts.written);
            counts.written += 1;
            summary.written += 1;
            return Ok(path);
        }
        let written = Instant::now();
        let mut book = self.book.lock();
        book.snapshots.finish()?;
        let path = folder.write(config, *counts, state, &book)?;
        drop(book);
        counts.written += 1;
        summary.written += 1;
        summary.write_seconds += written.elapsed().as_secs_f64();
        tracing::info!(
            checkpoint = %path.display(),
            time = config.time.clock(state.front.min_time()),
            seconds = written.elapsed().as_secs_f64(),
            "checkpoint written"
        );
        Ok(path)
    }
}

/// A resumed run whose `time.end` or `output.snapshot_times` differ from its checkpoint's: the
/// pitcher ends at the config's end (s, run clock `t_end`), the snapshots and milestones are
/// the config's after the checkpoint's front. `checkpoint` names the file in errors (exit 2).
pub(crate) fn extend(
    state: &mut Frontier,
    book: &mut Book,
    config: &crate::config::Config,
    t_end: f64,
    checkpoint: &Path,
) -> Result<(), EngineError> {
    let times = state.front.snapshot();
    let reached = times.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let clock = |t: f64| config.time.clock(t);
    let refuse = |reason: String| {
        EngineError::Input(format!(
            "{}: {reason}; a restart may only move the end and add snapshots after the \
             checkpoint's front, which reaches {:.6e} s in places",
            checkpoint.display(),
            clock(reached)
        ))
    };
    if t_end < reached {
        return Err(refuse(format!(
            "time.end = {:e} s is before the front",
            config.time.end
        )));
    }
    let start = config.time.start;
    (book.snapshots)
        .retime(&config.output.snapshot_times, start, reached)
        .map_err(|t| {
            refuse(format!(
                "output.snapshot_times: {t:e} s is not a snapshot of the run so far"
            ))
        })?;
    let snapshot_times: Vec<f64> = (config.output.snapshot_times.iter())
        .map(|&t| config.time.elapsed(t))
        .collect();
    book.milestones = Milestones::resumed(
        &times,
        t_end,
        &snapshot_times,
        config.checkpoint.every_sim_s,
    );
    state.pitcher.set_t_end(t_end);
    tracing::info!(
        end = config.time.end,
        "the run goes on to a new end time or snapshot times"
    );
    Ok(())
}
