//! `sdg run --ranks N` and `sdg run --mpi`: one front split over N ranks, each a thread of
//! this process connected to the others by the in-process transport
//! (`sdg_distributed::Loopback`), or each an MPI process (`MpiTransport`, cargo feature `mpi`),
//! with the same tents, elements and interface states as a run on threads.
//!
//! Each rank pitches and solves the tents at the vertices it owns
//! ([`sdg_distributed::solve_rank_observed`]), writing its pieces of the snapshots, summing
//! the history's energies and tallying its tents' reports as it goes (modules `rank_outputs`,
//! `rank_tally`); at the end the elements are gathered on rank 0
//! ([`sdg_distributed::gathering`]), each from the rank owning its triangle's first corner (an
//! interface face from the owner of its edge's first end), and rank 0 writes `summary.json`
//! with the state hash and the merged tallies' totals, and `history.csv` (module
//! `rank_finish`). The partition and what every rank
//! solves with are module `rank_setup`'s; what a restarted run did before, `rank_prior`'s. The
//! ranks run in phases between checkpoints (module
//! `rank_run`), which are the threaded run's checkpoint files (module `rank_checkpoint`): a
//! run over ranks restarts from either kind, on any number of ranks, and a run on threads from
//! a checkpoint of one over ranks.
//!
//! Without events the ranks take the tents of both scheduler modes (each rank's share of the
//! deterministic rounds' vertices, those first in `(time, id)` among their neighbours), so a
//! run over ranks is the threaded run of either mode. What cannot be honoured yet is refused
//! as bad input (exit 2), naming the key and why: mesh-changing events (`[adapt]`,
//! `[fracture]`) in asynchronous mode, and `--trace`. (`output.spacetime_mesh` is `sdg mesh`'s:
//! `sdg run` writes no spacetime mesh on threads or over ranks.)
//! Deterministic runs with events go to the module `rank_rounds` instead: rounds split over
//! ranks that each hold the whole state.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use sdg_distributed::{LoopbackOptions, Partition, Transport};
use sdg_mesh::Front;
use sdg_solver::element::FrontSolution;

use crate::error::EngineError;
use crate::job::RunOptions;
use crate::problem::Problem;
use crate::rank_prior::Prior;
use crate::rank_run::{Failure, OTHER_RANK_STOPPED, Shared, pause_request, run_rank};
pub use crate::rank_setup::{PartitionKind, causality, partition_for, physics};
use crate::solve::checkpoint::{self, Folder};
use crate::solve::start::Start;
use crate::solve::{Control, RunSummary};

/// What `sdg run --ranks` asks beyond [`RunOptions`].
#[derive(Clone, Copy, Debug)]
pub struct RankOptions {
    /// Ranks, at least 1.
    pub ranks: usize,
    /// How the vertices are split among them.
    pub partition: PartitionKind,
}

/// `sdg run` over `ranks.ranks` in-process ranks: solves `problem` to the end time and writes
/// `summary.json`, `history.csv` and the snapshots into the output folder, and checkpoints as
/// configured or asked (module `rank_checkpoint`). Returns the summary and the folder.
/// Errors: what the ranks cannot do yet, and bad `options` (a trace), as
/// [`EngineError::Input`] (exit 2); a failed rank as [`EngineError::Runtime`] (exit 1); a stop
/// request as [`EngineError::Checkpointed`] (exit 3) once the checkpoint is written.
pub fn solve_ranks(
    problem: &Problem,
    options: &RunOptions,
    ranks: &RankOptions,
) -> Result<(RunSummary, PathBuf), EngineError> {
    if split_rounds(problem, options) && ranks.ranks > 0 && options.trace.is_none() {
        return crate::rank_rounds::solve_split_ranks(problem, options, ranks.ranks);
    }
    refuse(problem, options, ranks)?;
    let set_up = SetUp::new(problem, options, ranks.ranks, true)?;
    warn_if_oversubscribed(ranks.ranks * set_up.threads, "this process's ranks");
    let partition = partition_for(problem, ranks.partition, ranks.ranks)?;
    let _span = tracing::info_span!("solve", config = %problem.loaded.file.display()).entered();
    tracing::info!(
        ranks = ranks.ranks,
        partition = ranks.partition.name(),
        order = problem.loaded.config.solver.order,
        vertices = problem.mesh.vertices().len(),
        "solve over ranks started"
    );
    let shared = set_up.shared(problem, (&partition, ranks.partition));
    let delays = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let ends = sdg_distributed::Loopback::connect(ranks.ranks, delays);
    let results: Vec<Result<Option<(RunSummary, PathBuf)>, Failure>> = std::thread::scope(|s| {
        let shared = &shared;
        let handles: Vec<_> = (ends.into_iter())
            .map(|mut end| {
                s.spawn(move || {
                    let rank = end.rank();
                    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        run_rank(shared, &mut end)
                    }))
                    .unwrap_or_else(|_| {
                        Err(Failure::Own(EngineError::Runtime(format!(
                            "rank {rank}: internal error (a bug, please report it)"
                        ))))
                    });
                    if matches!(result, Err(Failure::Own(ref e)) if e.exit_code() != 3) {
                        for r in (0..end.ranks() as u32).filter(|&r| r != rank) {
                            let _ = end.send(r, sdg_distributed::Message::Abort);
                        }
                    }
                    result
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(Failure::Own(EngineError::Runtime(
                        "a rank thread panicked".into(),
                    )))
                })
            })
            .collect()
    });
    let mut own: Vec<EngineError> = Vec::new();
    let (mut aborted, mut done) = (None, None);
    for result in results {
        match result {
            Ok(Some(d)) => done = Some(d),
            Ok(None) => {}
            Err(Failure::Own(e)) => own.push(e),
            Err(e) => aborted = aborted.or(Some(e.into_error())),
        }
    }
    // A failure before a stop, and a stop with the reason of the rank that was asked.
    let told = |e: &EngineError| match e {
        EngineError::Checkpointed { reason, .. } => reason != OTHER_RANK_STOPPED,
        _ => true,
    };
    own.sort_by_key(|e| (e.exit_code() == 3, !told(e)));
    match (own.into_iter().next().or(aborted), done) {
        (Some(e), _) => Err(e),
        (None, Some(done)) => Ok(done),
        (None, None) => Err(EngineError::Runtime("rank 0 returned no summary".into())),
    }
}

/// `sdg run --mpi` on this MPI process (one rank per process of `mpirun`): the ranks split the
/// front as [`solve_ranks`] does, with `sdg_distributed::MpiTransport`, and gather the results
/// on rank 0, which writes the outputs. Returns the summary and the folder on rank 0, `None`
/// on the others. Errors as [`solve_ranks`]; what is refused, every rank refuses alike, before
/// MPI starts. A rank that fails by itself reports its error and ends every rank with exit
/// code 1 (`MPI_Abort`), so that none waits for it.
#[cfg(feature = "mpi")]
pub fn solve_mpi(
    problem: &Problem,
    options: &RunOptions,
    partition: PartitionKind,
) -> Result<Option<(RunSummary, PathBuf)>, EngineError> {
    use sdg_distributed::{MpiOptions, MpiTransport, Transport};
    if split_rounds(problem, options) && options.trace.is_none() {
        return crate::rank_rounds::solve_split_mpi(problem, options);
    }
    refuse(
        problem,
        options,
        &RankOptions {
            ranks: 1,
            partition,
        },
    )?;
    let mut transport = MpiTransport::start(MpiOptions::default())
        .map_err(|e| EngineError::Runtime(format!("starting MPI: {e}")))?;
    let (rank, ranks) = (transport.rank(), transport.ranks());
    let result = (|| {
        let set_up = SetUp::new(problem, options, ranks, rank == 0)?;
        warn_if_oversubscribed(set_up.threads, &format!("rank {rank}"));
        let partition_of = partition_for(problem, partition, ranks)?;
        let shared = set_up.shared(problem, (&partition_of, partition));
        // Every rank set up before any sends (a barrier).
        transport.sum(&[0]).map_err(|e| {
            Failure::Own(EngineError::Runtime(format!(
                "the run over {ranks} MPI ranks failed: rank {rank}: {e}"
            )))
        })?;
        run_rank(&shared, &mut transport)
    })();
    match result {
        Ok(done) => Ok(done),
        // Every rank has the checkpoint on disk: end at once, before `mpirun`, which got the
        // signal too, kills the processes (1 s after its SIGTERM by default).
        Err(Failure::Own(e @ EngineError::Checkpointed { .. })) => {
            crate::progress::note(format_args!("stopped: rank {rank}: {e}"));
            transport.abort(e.exit_code().into())
        }
        Err(Failure::Own(e)) => {
            crate::progress::note(format_args!("error: rank {rank}: {e}"));
            transport.abort(1)
        }
        Err(f) => Err(f.into_error()),
    }
}

/// What every rank sets up before it solves: the estimate, the folders, the checkpoint read
/// back and the pause request.
struct SetUp {
    estimate: crate::estimate::Estimate,
    dir: PathBuf,
    folder: Folder,
    prior: Prior,
    restored: Option<(Front, FrontSolution)>,
    control: std::sync::Arc<Control>,
    request: sdg_distributed::PauseRequest,
    /// The scheduler mode asked for (`summary.json`'s `mode`).
    mode: &'static str,
    /// Threads that solve each rank's tents.
    threads: usize,
}

impl SetUp {
    /// The set-up of a run of `problem` with `options` over `ranks` ranks; `first` prepares
    /// the folders (rank 0, or the process of the in-process ranks).
    fn new(
        problem: &Problem,
        options: &RunOptions,
        ranks: usize,
        first: bool,
    ) -> Result<Self, EngineError> {
        let config = &problem.loaded.config;
        let Start {
            state, max_star, ..
        } = Start::new(problem)?;
        let threads = options.threads.unwrap_or(1).max(1);
        let estimate = state.estimate(problem, max_star, ranks * threads, false);
        let restored = match &options.restart {
            Some(path) => Some(checkpoint::restore(path, config)?),
            None => None,
        };
        let estimate = match &restored {
            Some((_, r)) => estimate.remaining(&r.frontier.front.snapshot(), config.time.span()),
            None => estimate,
        };
        if options.progress && first {
            crate::progress::note(format_args!("estimate: {}", estimate.describe()));
        }
        if !options.force {
            estimate.check(problem)?;
        }
        let dir = options.output_dir(problem)?;
        let folder = Folder::new(config, &dir);
        if first {
            folder.check_unmixed(options.restart.as_deref())?;
            prepare_folder(&dir, restored.is_some())?;
        }
        let (prior, restored) = match restored {
            Some(r) => {
                let (prior, front, solution) = Prior::restored(problem, r, &folder)?;
                (prior, Some((front, solution)))
            }
            None => (Prior::fresh(), None),
        };
        let control = options.control.clone().unwrap_or_default();
        let request = pause_request(problem, options, control.clone());
        let mode = if options.deterministic || config.scheduler.deterministic {
            "deterministic"
        } else {
            "asynchronous"
        };
        Ok(Self {
            estimate,
            dir,
            folder,
            prior,
            restored,
            control,
            request,
            mode,
            threads,
        })
    }

    /// What the ranks of the run share, on `partition`.
    fn shared<'a>(
        &'a self,
        problem: &'a Problem,
        partition: (&'a Partition, PartitionKind),
    ) -> Shared<'a> {
        Shared {
            problem,
            partition,
            dir: &self.dir,
            folder: &self.folder,
            prior: &self.prior,
            restored: self.restored.as_ref().map(|(f, s)| (f, s)),
            control: &self.control,
            request: self.request.clone(),
            estimate: &self.estimate,
            mode: self.mode,
            threads: self.threads,
            started: Instant::now(),
        }
    }
}

/// Warns when `threads` solving threads of `who` exceed the cores this process may use (its
/// CPU affinity): under `mpirun`, which binds each process to one core unless told otherwise,
/// they would share it.
fn warn_if_oversubscribed(threads: usize, who: &str) {
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    if threads > cores {
        tracing::warn!(
            "{who}: {threads} solving threads on {cores} cores this process may use; with \
             --mpi --threads T start each rank on T cores (mpirun --map-by slot:PE=T, srun \
             --cpus-per-task=T)"
        );
    }
}

/// True for a deterministic run with mesh-changing events: its rounds are split over ranks that
/// each hold the whole state ([`crate::rank_rounds`]).
fn split_rounds(problem: &Problem, options: &RunOptions) -> bool {
    let config = &problem.loaded.config;
    (config.adapt.enabled || config.fracture.is_some())
        && (options.deterministic || config.scheduler.deterministic)
}

/// What a run over ranks cannot do yet, as bad input naming the key or option and why.
fn refuse(problem: &Problem, options: &RunOptions, ranks: &RankOptions) -> Result<(), EngineError> {
    let config = &problem.loaded.config;
    let file = problem.loaded.file.display();
    let events = "mesh-changing events run over ranks in deterministic mode only (--deterministic \
                  or scheduler.deterministic = true)";
    let split = split_rounds(problem, options);
    let refusals = [
        (ranks.ranks == 0).then(|| "--ranks: must be at least 1".to_string()),
        (config.adapt.enabled && !split).then(|| {
            format!("{file}: adapt.enabled: {events}, or on threads (without --ranks or --mpi)")
        }),
        (config.fracture.is_some() && !split).then(|| {
            format!("{file}: [fracture]: {events}, or on threads (without --ranks or --mpi)")
        }),
        options
            .trace
            .is_some()
            .then(|| "--trace: a run over ranks records no trace yet".to_string()),
    ];
    match refusals.into_iter().flatten().next() {
        Some(reason) => Err(EngineError::Input(reason)),
        None => Ok(()),
    }
}

/// Removes an earlier run's `summary.json` and, unless `restarted`, its snapshot files from
/// `dir`.
fn prepare_folder(dir: &Path, restarted: bool) -> Result<(), EngineError> {
    match std::fs::remove_file(dir.join("summary.json")) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(EngineError::io(dir.join("summary.json"), e));
        }
        _ => {}
    }
    if !restarted {
        crate::output::snapshot::remove_earlier(dir)?;
    }
    Ok(())
}
