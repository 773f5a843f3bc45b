//! `sdg run`: the stages of a solve from set-up to summary.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use sdg_scheduler::Options;
use sdg_solver::patch::PatchSolver;

use crate::error::{EngineError, scheduler_error};
use crate::estimate::Estimate;
use crate::frontier::Frontier;
use crate::job::RunOptions;
use crate::problem::Problem;
use crate::progress::Progress;

use super::checkpoint::{self, Counts, Folder, Restored};
use super::context::{Intervention, Live, Solve};
use super::restart::extend;
use super::split::Split;
use super::start::{Start, patch_solver};
use super::summary::{CheckpointSummary, RunSummary};

/// `sdg run`: solves the problem to the end time; writes `summary.json`, `history.csv` and the
/// configured snapshots. Returns the summary and the output folder.
pub fn solve_job(
    problem: &Problem,
    options: &RunOptions,
) -> Result<(RunSummary, PathBuf), EngineError> {
    run_job(problem, options, None, None)
}

/// [`solve_job`], with `intervention` (its time and change) applied once mid-run, and with
/// `split` as this rank's part of rounds split over ranks ([`super::split`]).
pub(crate) fn run_job(
    problem: &Problem,
    options: &RunOptions,
    intervention: Option<(f64, Intervention)>,
    split: Option<Split>,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let config = &problem.loaded.config;
    let scheduler = options.scheduler(problem);
    let Start {
        state,
        adapt,
        max_star,
    } = Start::new(problem)?;
    let estimate = state.estimate(problem, max_star, scheduler.threads, adapt.is_some());
    let restored = match &options.restart {
        Some(path) => Some(checkpoint::restore(path, config)?),
        None => None,
    };
    let estimate = announce(problem, options, estimate, restored.as_ref())?;
    // The ranks but 0 of split rounds hold copies of rank 0's state and write nothing.
    let (dir, folder) = match split.as_ref().is_none_or(Split::writes) {
        true => {
            let dir = options.output_dir(problem)?;
            let folder = prepare_folder(problem, options, &dir, restored.is_some())?;
            (dir, folder)
        }
        false => {
            let dir = options.output_folder(problem);
            (dir.clone(), Folder::new(config, &dir))
        }
    };
    let start = (&state, adapt, max_star);
    let intervention = intervention.unzip();
    let solve = Solve {
        split,
        ..Solve::new(
            problem,
            options,
            start,
            scheduler.threads,
            &dir,
            intervention,
        )
    };
    let (mut state, mut counts, mut checkpoints) =
        solve.resume(state, restored, &folder, &dir, options)?;
    let _span = tracing::info_span!("solve", config = %problem.loaded.file.display()).entered();
    tracing::info!(
        threads = scheduler.threads,
        deterministic = scheduler.deterministic,
        order = config.solver.order,
        vertices = state.mesh.vertices().len(),
        "solve started"
    );
    solve.advance(
        &mut state,
        &scheduler,
        (&folder, &dir),
        &mut counts,
        &mut checkpoints,
    )?;
    solve.finish(
        &state,
        options,
        &dir,
        counts,
        checkpoints,
        estimate,
        &scheduler,
    )
}

/// The estimate of the run ahead (what is left of it after a restart from `restored`), logged,
/// printed with `--progress` and checked against `[limits]` unless `--force`.
fn announce(
    problem: &Problem,
    options: &RunOptions,
    estimate: Estimate,
    restored: Option<&(PathBuf, Restored)>,
) -> Result<Estimate, EngineError> {
    let t_end = problem.loaded.config.time.span();
    // A restarted run has only the rest of the way before it.
    let estimate = match restored {
        Some((_, r)) => estimate.remaining(&r.frontier.front.snapshot(), t_end),
        None => estimate,
    };
    tracing::info!(
        tents = estimate.tents,
        lower_bound = estimate.lower_bound,
        wall_time_s = estimate.wall_time_s,
        memory_bytes = estimate.memory_bytes,
        "estimate"
    );
    if options.progress {
        crate::progress::note(format_args!("estimate: {}", estimate.describe()));
    }
    if !options.force {
        estimate.check(problem)?;
    }
    Ok(estimate)
}

/// The checkpoint folder of a run into `dir`, after checking that every folder it writes can
/// be written and that it mixes no other run's checkpoints; removes an earlier run's
/// `summary.json` and, unless `restarted`, its snapshot files.
fn prepare_folder(
    problem: &Problem,
    options: &RunOptions,
    dir: &Path,
    restarted: bool,
) -> Result<Folder, EngineError> {
    let config = &problem.loaded.config;
    let folder = Folder::new(config, dir);
    if config.checkpoint.dir.is_some() {
        let named = format!("checkpoint.dir {}", folder.dir.display());
        crate::output::check_writable(&folder.dir, &named)?;
        // The folder itself is made by the first checkpoint, in a parent that exists.
        if let Some(parent) = folder.dir.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|e| {
                EngineError::Input(format!("{named}: cannot make {}: {e}", parent.display()))
            })?;
        }
    }
    if let Some(trace) = &options.trace {
        crate::trace::check_path(trace)?;
    }
    folder.check_unmixed(options.restart.as_deref())?;
    // `summary.json` is written when a run finishes: an earlier run's must not stand for this
    // one should it fail or stop.
    match std::fs::remove_file(dir.join("summary.json")) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(EngineError::io(dir.join("summary.json"), e));
        }
        _ => {}
    }
    if !restarted {
        let removed = crate::output::snapshot::remove_earlier(dir)?;
        if removed > 0 {
            tracing::info!(removed, dir = %dir.display(), "snapshot files of an earlier run removed");
        }
    }
    Ok(folder)
}

impl Solve<'_> {
    /// The front to solve from and the counts so far: those of the checkpoint `restored` (its
    /// end and snapshots moved to the config's), or the initial `state` with its first history
    /// row.
    fn resume(
        &self,
        state: Frontier,
        restored: Option<(PathBuf, Restored)>,
        folder: &Folder,
        dir: &Path,
        options: &RunOptions,
    ) -> Result<(Frontier, Counts, CheckpointSummary), EngineError> {
        let config = &self.problem.loaded.config;
        let t_end = config.time.span();
        let Some((file, restored)) = restored else {
            self.history_row(&state, &mut self.book.lock());
            return Ok((state, Counts::default(), CheckpointSummary::default()));
        };
        tracing::info!(
            checkpoint = %file.display(),
            time = config.time.clock(restored.header.time),
            "restarting"
        );
        let mut counts = restored.counts;
        counts.written = folder.next_number(counts.written);
        let mut state = restored.frontier;
        let mut book = restored.book;
        let output = self.writes().then_some((dir, config.output.vtu));
        book.resume(output, self.basis.len(), self.width)?;
        if checkpoint::extends(&restored.header.config, config) {
            extend(&mut state, &mut book, config, t_end, &file)?;
        }
        let done: f64 = state.front.snapshot().iter().sum();
        book.progress = Progress::new(options.progress, state.mesh.vertices().len() as f64 * t_end);
        book.progress.advance(done, book.patches);
        self.energy_reference
            .store(book.energy_max.to_bits(), Ordering::Relaxed);
        *self.book.lock() = book;
        let checkpoints = CheckpointSummary {
            restarted_from: Some(file),
            restart_time: Some(config.time.clock(restored.header.time)),
            ..CheckpointSummary::default()
        };
        Ok((state, counts, checkpoints))
    }

    /// Runs the scheduler on `state` to the end time, pausing at each quiescent point asked for
    /// (signals, milestones, wall time) to write a checkpoint into `folder` and stop or go on;
    /// writes the partial outputs into `dir` when it fails or stops.
    fn advance(
        &self,
        state: &mut Frontier,
        scheduler: &Options,
        (folder, dir): (&Folder, &Path),
        counts: &mut Counts,
        checkpoints: &mut CheckpointSummary,
    ) -> Result<(), EngineError> {
        let problem = self.problem;
        let config = &problem.loaded.config;
        let t_end = config.time.span();
        let wall_every = Duration::try_from_secs_f64(config.checkpoint.every_wall_s).ok();
        loop {
            let segment = Instant::now();
            if let Some(every) = wall_every {
                let due = (segment - self.started + every).as_nanos();
                let due = u64::try_from(due).unwrap_or(u64::MAX - 1);
                self.next_wall_checkpoint_ns.store(due, Ordering::Relaxed);
            }
            let solvers: Vec<PatchSolver> = (0..scheduler.threads)
                .map(|_| patch_solver(problem, self.max_star))
                .collect();
            let result = sdg_scheduler::run(state, t_end, self, solvers, scheduler);
            counts.wall_time_s += segment.elapsed().as_secs_f64();
            let stats = match result {
                Ok(stats) => stats,
                Err(e) => {
                    self.write_partial_outputs(state, dir);
                    return Err(scheduler_error(e));
                }
            };
            counts.tents += stats.tents;
            counts.events += stats.events;
            counts.rounds += stats.rounds;
            counts.events_s += stats.event_time.as_secs_f64();
            counts.waiting_s += stats.wait_time.as_secs_f64();
            if !stats.paused {
                break;
            }
            // Quiescent: no tent in flight, no event queued.
            let request = match &self.split {
                Some(split) => split.take_request(&self.control),
                None => self.control.take(),
            };
            let path = match self.checkpoint(folder, state, counts, checkpoints) {
                Ok(path) => path,
                Err(e) => {
                    self.write_partial_outputs(state, dir);
                    return Err(match request.failure {
                        Some(failure) => EngineError::Runtime(format!(
                            "{failure}; and the checkpoint of the front before this patch failed: \
                             {e}"
                        )),
                        None => e,
                    });
                }
            };
            if let Some(failure) = request.failure {
                self.write_partial_outputs(state, dir);
                return Err(EngineError::Runtime(format!(
                    "{failure}; the front before this patch is in checkpoint {}",
                    path.display()
                )));
            }
            if let Some(reason) = request.stop {
                self.write_partial_outputs(state, dir);
                return Err(EngineError::Checkpointed {
                    reason,
                    time: config.time.clock(state.front.min_time()),
                    checkpoint: path,
                });
            }
        }
        if config.checkpoint.at_end
            && let Err(e) = self.checkpoint(folder, state, counts, checkpoints)
        {
            self.write_partial_outputs(state, dir);
            return Err(e);
        }
        Ok(())
    }
}

/// [`crate::solve_job`], with `action` run once on the live front as soon as every vertex of the
/// front has passed `after` (s since `time.start`, in `[0, time.end - time.start)`), as a
/// scheduler event: no tent is in flight,
/// and the front is as the tents left it (not flat). What `action` changes through [`Live`]
/// is booked like adaptive refinement (counts, energy accounting, progress) and the run then
/// continues to the end time. Deterministic runs stay deterministic.
///
/// `action` owns what it captures (`'static`): it reports back through shared handles such as
/// an `Arc<Mutex<_>>`. Errors as [`crate::solve_job`], and a runtime error for an `after` outside
/// `[0, time.end - time.start)`.
#[doc(hidden)]
pub fn solve_job_with(
    problem: &Problem,
    options: &RunOptions,
    after: f64,
    action: impl FnOnce(&mut Live<'_>) + Send + 'static,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let t_end = problem.loaded.config.time.span();
    if !(after >= 0.0 && after < t_end) {
        return Err(EngineError::Runtime(format!(
            "an intervention {after:e} s after the start is not within the run's {t_end:e} s"
        )));
    }
    run_job(problem, options, Some((after, Box::new(action))), None)
}
