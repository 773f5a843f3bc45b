//! One rank of a run over ranks, the same on in-process ranks and on MPI: it solves its part of
//! the front in phases separated by checkpoints (module `rank_checkpoint`), and at the end
//! gathers the results on rank 0, which writes the outputs.
//!
//! # Phases
//! Each phase runs [`sdg_distributed::solve_rank_observed`] to the next pause: the next
//! multiple of `checkpoint.every_sim_s`, a request (signal, wall time), or the end time. Then
//! the ranks meet ([`Transport::sum`]) to learn whether every vertex has reached the end time,
//! every rank has reached the pause time, and whether any rank was asked to stop. Unless the
//! run is over, rank 0 gathers the state and writes a checkpoint, the ranks meet again to learn
//! that it was written, and either stop (exit 3) or go on with a new phase. Messages of one
//! phase never reach the next: a phase ends on a rank only once every message its neighbour
//! ranks sent it has arrived, and the meeting is a barrier.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use sdg_distributed::{
    Gathered, Held, LocalView, Options, Partition, Pause, PauseRequest, Physics, PitchingError,
    Transport, TransportError, gather, rank_state, solve_rank_observed,
};
use sdg_mesh::{Front, Pitcher};
use sdg_solver::element::FrontSolution;

use crate::error::EngineError;
use crate::estimate::Estimate;
use crate::problem::Problem;
use crate::rank_checkpoint::{self, Pausing};
use crate::rank_finish::{End, finish, initial_energy};
use crate::rank_outputs::{self, RankOutputs, merged};
use crate::rank_prior::Prior;
use crate::rank_setup::{PartitionKind, causality, physics};
use crate::solve::book::{Records, history_times};
use crate::solve::checkpoint::Folder;
use crate::solve::work::deadline;
use crate::solve::{Control, RunSummary};

/// Longest a rank waits for an update while it has vertices left, before it reports a stall.
pub(crate) const IDLE_LIMIT: Duration = Duration::from_secs(120);

/// The reason a rank gives for a stop that another rank was asked for.
pub(crate) const OTHER_RANK_STOPPED: &str = "another rank was asked to stop";

/// What every rank of a run shares.
pub(crate) struct Shared<'a> {
    pub(crate) problem: &'a Problem,
    pub(crate) partition: (&'a Partition, PartitionKind),
    /// The output folder and the checkpoint folder.
    pub(crate) dir: &'a Path,
    pub(crate) folder: &'a Folder,
    /// What the run did before, and the whole front and elements it goes on from.
    pub(crate) prior: &'a Prior,
    pub(crate) restored: Option<(&'a Front, &'a FrontSolution)>,
    /// Where requests come from, and the check between tents that reads them.
    pub(crate) control: &'a Control,
    pub(crate) request: PauseRequest,
    pub(crate) estimate: &'a Estimate,
    /// The scheduler mode asked for: without events the ranks' tents are those of both modes.
    pub(crate) mode: &'static str,
    /// Threads that solve each rank's tents (`--threads`; 1 unless asked).
    pub(crate) threads: usize,
    /// When the solve started.
    pub(crate) started: Instant,
}

/// Why a rank failed: by itself, or stopped by another rank's failure.
#[derive(Debug)]
pub(crate) enum Failure {
    Own(EngineError),
    Aborted(EngineError),
}

impl From<EngineError> for Failure {
    fn from(e: EngineError) -> Self {
        Failure::Own(e)
    }
}

impl Failure {
    /// The error to report.
    pub(crate) fn into_error(self) -> EngineError {
        match self {
            Failure::Own(e) | Failure::Aborted(e) => e,
        }
    }
}

/// A rank's error from the distributed engine, over `ranks` ranks.
fn failed(ranks: usize, e: PitchingError) -> Failure {
    let aborted = matches!(
        e,
        PitchingError::Aborted { .. }
            | PitchingError::Transport {
                source: TransportError::Aborted { .. },
                ..
            }
    );
    let e = EngineError::Runtime(format!("the run over {ranks} ranks failed: {e}"));
    if aborted {
        Failure::Aborted(e)
    } else {
        Failure::Own(e)
    }
}

/// The first multiple of `every` (s) after `time` (s), by its index.
fn next_multiple(every: f64, time: f64) -> u64 {
    let mut k = (time / every).floor().max(0.0) as u64 + 1;
    while k as f64 * every <= time {
        k += 1;
    }
    k
}

/// What rank 0 holds across phases: the ranks' counts so far and the last state gathered.
#[derive(Default)]
struct Collected {
    gathered: Option<Gathered>,
}

impl Collected {
    /// Adds a phase's `gathered` results: its counts (tents and messages) to each rank's, its
    /// front, elements and outputs (the ranks' sums and tallies since the (re)start) for the
    /// earlier ones'.
    fn add(&mut self, mut gathered: Gathered) -> &Gathered {
        if let Some(before) = self.gathered.take() {
            for (now, then) in (gathered.tents_by_rank.iter_mut()).zip(before.tents_by_rank) {
                *now += then;
            }
            for (now, then) in gathered.reports.iter_mut().zip(before.reports) {
                now.updates_sent += then.updates_sent;
                now.update_bytes += then.update_bytes;
                now.updates_applied += then.updates_applied;
                now.updates_stale += then.updates_stale;
                now.waited += then.waited;
            }
        }
        self.gathered.insert(gathered)
    }
}

/// Runs rank `transport.rank()` of the run `shared` to the end: returns the summary and the
/// output folder on rank 0, `None` on the others. A stop request ends every rank with
/// [`EngineError::Checkpointed`] after the checkpoint is written.
pub(crate) fn run_rank<T: Transport>(
    shared: &Shared<'_>,
    transport: &mut T,
) -> Result<Option<(RunSummary, PathBuf)>, Failure> {
    let problem = shared.problem;
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let (rank, ranks) = (transport.rank(), transport.ranks());
    let (partition, kind) = shared.partition;
    let probes: Vec<[f64; 2]> = problem.probes.iter().map(|p| p.at).collect();
    let cut_times: Vec<f64> = (config.output.snapshot_times.iter())
        .map(|&t| config.time.elapsed(t))
        .collect();
    let physics = Physics {
        cut_times: &cut_times,
        ..physics(problem, &probes)
    };
    let causality = causality(problem);
    let t_end = causality.t_end;
    let view = LocalView::new(mesh, partition, rank).map_err(|e| failed(ranks, e.into()))?;
    let (pitcher, front, solution) = match shared.restored {
        Some(state) => rank_state(&view, causality, physics, state),
        None => Pitcher::new(view.mesh(), causality.c_max, causality.safety, t_end)
            .map(|p| {
                let front = Front::flat(view.mesh().vertices().len(), 0.0);
                (p, front, physics.initial_solution(&view))
            })
            .map_err(PitchingError::from),
    }
    .map_err(|e| failed(ranks, e))?;
    let start = shared.restored.map(|(front, _)| front.snapshot());
    let resumed = shared.prior.snapshots.as_ref().map(|s| s.to_stored());
    let mut outputs = RankOutputs::new(
        problem,
        partition,
        rank,
        shared.dir,
        (start.as_deref(), resumed),
    )?;
    let transport_failed = |source| failed(ranks, PitchingError::Transport { rank, source });
    let every = config.checkpoint.every_sim_s;
    let start_time = start
        .as_ref()
        .map_or(0.0, |s| s.iter().copied().fold(f64::INFINITY, f64::min));
    let mut next = every.map(|dt| next_multiple(dt, start_time));
    let mut collected = Collected::default();
    let mut number = shared.prior.written;
    let mut written = (0_u64, 0.0_f64);
    let energy0 = initial_energy(problem, ranks);
    // The blow-up guard's bound, carried from phase to phase: the energy held at the start (the
    // initial front's, with the net boundary work before a restart) and what the rank learns.
    let before = energy0.total + shared.prior.totals.boundary_work.max(0.0);
    let mut held = Some(Held::new(before, problem.material.density(), ranks));
    // The checkpoint at the end (`checkpoint.at_end`) is written.
    let mut ended = false;
    loop {
        let at = next
            .zip(every)
            .map(|(k, dt)| k as f64 * dt)
            .filter(|&t| t < t_end);
        let options = Options {
            pause: Pause {
                at,
                requested: Some(shared.request.clone()),
            },
            threads: shared.threads,
            held: held.take(),
            keep_tents: false,
            ..Options::new(u64::from(rank), IDLE_LIMIT)
        };
        let state = (&view, &pitcher, &front, &solution);
        let mut report = solve_rank_observed(state, physics, transport, &mut outputs, &options)
            .map_err(|e| failed(ranks, e))?;
        held = report.held.take();
        let stop = shared.control.take().stop;
        let below_at = at.map_or(0, |t| view.owned().filter(|&v| front.time(v) < t).count());
        let met = [report.below_end, below_at, usize::from(stop.is_some())].map(|x| x as u64);
        let met = transport.sum(&met).map_err(transport_failed)?;
        let over = met[0] == 0;
        if over && (ended || !config.checkpoint.at_end) {
            let (values, snapshots) = outputs.finish()?;
            report.outputs = values;
            let gathered = gather(
                mesh,
                &view,
                (&front, &solution, &report),
                transport,
                IDLE_LIMIT,
            )
            .map_err(|e| failed(ranks, e))?;
            let Some(gathered) = gathered else {
                return Ok(None);
            };
            let gathered = collected.add(gathered);
            let end = End {
                partition: kind,
                gathered,
                snapshots,
                prior: shared.prior,
                wall_time_s: shared.started.elapsed().as_secs_f64(),
                checkpoints: written,
                mode: shared.mode,
                threads: shared.threads,
            };
            return finish(problem, shared.dir, end, *shared.estimate)
                .map(Some)
                .map_err(Failure::Own);
        }
        if at.is_some() && met[1] == 0 {
            next = next.map(|k| k + 1);
        }
        report.outputs = outputs.checkpoint_values()?;
        let gathered = gather(
            mesh,
            &view,
            (&front, &solution, &report),
            transport,
            IDLE_LIMIT,
        )
        .map_err(|e| failed(ranks, e))?;
        let outcome = gathered.map(|gathered| {
            let gathered = collected.add(gathered);
            let pausing = (gathered, &outputs, &energy0, shared.started.elapsed());
            write_checkpoint(shared, pausing, number)
        });
        let (ok, time, next_all) = match &outcome {
            Some(Ok((_, _, time, next_all))) => (1, time.to_bits(), *next_all as u64),
            _ => (0, 0, 0),
        };
        let status = transport
            .sum(&[u64::from(rank == 0) - ok, time, next_all])
            .map_err(transport_failed)?;
        outputs.checkpointed(status[2] as usize);
        if status[0] > 0 {
            return Err(match outcome {
                Some(Err(e)) => Failure::Own(e),
                _ => Failure::Aborted(EngineError::Runtime(
                    "rank 0 could not write the checkpoint".into(),
                )),
            });
        }
        if let Some(Ok((_, seconds, _, _))) = &outcome {
            written.0 += 1;
            written.1 += seconds;
        }
        let path = shared
            .folder
            .dir
            .join(format!("checkpoint_{number:06}.sdgc"));
        number += 1;
        ended = over;
        if met[2] > 0 && !over {
            return Err(Failure::Own(EngineError::Checkpointed {
                reason: stop.unwrap_or_else(|| OTHER_RANK_STOPPED.into()),
                time: config.time.clock(f64::from_bits(status[1])),
                checkpoint: path,
            }));
        }
    }
}

/// Writes checkpoint number `number` on rank 0 from the `gathered` state after `elapsed` since the
/// (re)start, with the snapshots of rank 0's `outputs`, the other ranks' pending slices, every
/// rank's records and the initial front's energy `energy0`. Returns the path, the
/// seconds it took, the front's least time (s) and the number of snapshots every rank has written.
fn write_checkpoint(
    shared: &Shared<'_>,
    (gathered, outputs, energy0, elapsed): (
        &Gathered,
        &RankOutputs<'_>,
        &sdg_solver::norms::FrontEnergy,
        Duration,
    ),
    number: u64,
) -> Result<(PathBuf, f64, f64, usize), EngineError> {
    let problem = shared.problem;
    let values: Vec<&[f64]> = gathered.reports.iter().map(|r| &r.outputs[..]).collect();
    let times = history_times(problem.loaded.config.time.span());
    let (sums, tally, rests) = merged(&values, &times)?;
    let (mut records, mut pending) = (Records::default(), Vec::new());
    for rest in rests {
        let (theirs, rest) = rank_outputs::records(rest)?;
        records.append(theirs);
        pending.push(rank_outputs::pending(rest)?);
    }
    let next_all = pending.iter().map(|p| p.0).min().unwrap_or(0);
    let mut snapshots = outputs.stored_snapshots(next_all);
    for (_, cbor) in pending.iter().skip(1) {
        snapshots
            .add_pending(cbor)
            .map_err(|e| EngineError::Runtime(format!("a rank's snapshot slices: {e}")))?;
    }
    let pausing = Pausing {
        gathered,
        tally: &tally,
        sums: &sums,
        snapshots,
        records,
        energy0,
        wall_time_s: elapsed.as_secs_f64(),
    };
    let (path, seconds) =
        rank_checkpoint::write(problem, shared.folder, shared.prior, pausing, number)?;
    Ok((path, seconds, gathered.front.min_time(), next_all))
}

/// The check between tents of a run of `problem` with `options`: true when `control` has a
/// request, and makes one when the wall-time limit is up (stop) or a wall-clock checkpoint is
/// due (`checkpoint.every_wall_s`).
pub(crate) fn pause_request(
    problem: &Problem,
    options: &crate::job::RunOptions,
    control: Arc<Control>,
) -> PauseRequest {
    let config = &problem.loaded.config;
    let deadline = deadline(config.limits.max_wall_time_s, options.max_wall_time_s);
    let every = Duration::try_from_secs_f64(config.checkpoint.every_wall_s).ok();
    let started = Instant::now();
    let nanos = |d: Duration| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
    let due = AtomicU64::new(every.map_or(u64::MAX, nanos));
    Arc::new(move || {
        if control.is_pending() {
            return true;
        }
        let now = Instant::now();
        if let Some((at, reason)) = &deadline
            && now >= *at
        {
            control.stop(reason.clone());
            return true;
        }
        let elapsed = nanos(now - started);
        if let Some(every) = every
            && elapsed >= due.load(Ordering::Relaxed)
        {
            due.store(elapsed.saturating_add(nanos(every)), Ordering::Relaxed);
            control.checkpoint();
            return true;
        }
        false
    })
}
