//! Runs over ranks with mesh-changing events (`[adapt]`, `[fracture]`), in deterministic mode:
//! every rank runs the threaded engine's rounds on its own copy of the whole state and solves
//! its share of each round's tents, the ranks exchanging their results once a round
//! ([`crate::solve::split`]). Rank 0 writes the outputs and checkpoints; the others, whose
//! state is a copy of rank 0's, write no file.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use parking_lot::Mutex;
use sdg_distributed::{Loopback, LoopbackOptions, Message, Rank, Transport, TransportError};

use crate::error::EngineError;
use crate::job::RunOptions;
use crate::problem::Problem;
use crate::solve::RunSummary;
use crate::solve::run::run_job;
use crate::solve::split::Split;

/// A rank's transport, shared between its run's [`Split`] and the caller, which ends the
/// other ranks with it when this one fails.
struct Shared<T>(Arc<Mutex<T>>);

impl<T: Transport> Transport for Shared<T> {
    fn rank(&self) -> Rank {
        self.0.lock().rank()
    }

    fn ranks(&self) -> usize {
        self.0.lock().ranks()
    }

    fn send(&mut self, to: Rank, message: Message) -> Result<(), TransportError> {
        self.0.lock().send(to, message)
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<(Rank, Message)>, TransportError> {
        self.0.lock().receive(timeout)
    }

    fn is_fifo(&self) -> bool {
        self.0.lock().is_fifo()
    }

    fn sum(&mut self, values: &[u64]) -> Result<Vec<u64>, TransportError> {
        self.0.lock().sum(values)
    }

    fn all_gather(&mut self, bytes: Vec<u8>) -> Result<Vec<Vec<u8>>, TransportError> {
        self.0.lock().all_gather(bytes)
    }
}

/// Runs rank `rank`'s part of the split rounds over `end` (shared with the caller).
fn run_rank<T: Transport + Send + 'static>(
    problem: &Problem,
    options: &RunOptions,
    end: &Arc<Mutex<T>>,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let split = Split::new(Box::new(Shared(Arc::clone(end))));
    run_job(problem, options, None, Some(split))
}

/// `sdg run --ranks N` of a config with events, deterministic: N in-process ranks of
/// `options.threads` workers each (1 by default). Returns rank 0's summary and folder; errors as
/// a run on threads, the first rank's that failed by itself.
pub(crate) fn solve_split_ranks(
    problem: &Problem,
    options: &RunOptions,
    ranks: usize,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let delays = LoopbackOptions {
        seed: 0,
        max_delay: std::time::Duration::ZERO,
        fifo: true,
    };
    let ends: Vec<Arc<Mutex<Loopback>>> = (Loopback::connect(ranks, delays).into_iter())
        .map(|end| Arc::new(Mutex::new(end)))
        .collect();
    let results: Vec<Result<(RunSummary, PathBuf), EngineError>> = std::thread::scope(|s| {
        let handles: Vec<_> = (ends.iter().enumerate())
            .map(|(rank, end)| {
                let options = rank_options(options, rank);
                s.spawn(move || {
                    let result = run_rank(problem, &options, end);
                    if result.as_ref().is_err_and(|e| e.exit_code() != 3) {
                        abort_others(&mut *end.lock());
                    }
                    result
                })
            })
            .collect();
        (handles.into_iter())
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(EngineError::Runtime(
                        "a rank thread panicked (a bug, please report it)".into(),
                    ))
                })
            })
            .collect()
    });
    let mut results = results.into_iter();
    let first = results.next().expect("at least one rank");
    // A failure of rank 0, or else of the first other rank that failed.
    match (first, results.find(Result::is_err)) {
        (Ok(_), Some(Err(e))) => Err(e),
        (first, _) => first,
    }
}

/// What rank `rank` runs with: `options` with 1 worker unless they ask for more; the ranks
/// but 0 without progress or trace (they write no file).
fn rank_options(options: &RunOptions, rank: usize) -> RunOptions {
    let options = RunOptions {
        threads: Some(options.threads.unwrap_or(1)),
        ..options.clone()
    };
    if rank == 0 {
        return options;
    }
    RunOptions {
        progress: false,
        trace: None,
        ..options
    }
}

/// Tells every other rank to stop: they end their wait in the round's all-gather.
fn abort_others(transport: &mut dyn Transport) {
    let rank = transport.rank();
    for r in (0..transport.ranks() as u32).filter(|&r| r != rank) {
        let _ = transport.send(r, Message::Abort);
    }
}

/// `mpirun -n N sdg run CONFIG --mpi` of a config with events, deterministic: this process's
/// rank of the split rounds over MPI. Returns the summary and folder on rank 0, `None` on the
/// others. A rank that fails by itself reports its error and ends every rank with exit code 1
/// (`MPI_Abort`); a stop ends every rank with exit code 3 once rank 0 has written its
/// checkpoint, which it names.
#[cfg(feature = "mpi")]
pub(crate) fn solve_split_mpi(
    problem: &Problem,
    options: &RunOptions,
) -> Result<Option<(RunSummary, PathBuf)>, EngineError> {
    use sdg_distributed::{MpiOptions, MpiTransport};
    let transport = MpiTransport::start(MpiOptions::default())
        .map_err(|e| EngineError::Runtime(format!("starting MPI: {e}")))?;
    let rank = transport.rank();
    let options = rank_options(options, rank as usize);
    let end = Arc::new(Mutex::new(transport));
    let result = run_rank(problem, &options, &end);
    let Ok(end) = Arc::try_unwrap(end) else {
        return Err(EngineError::Runtime(format!(
            "rank {rank}: the transport is still in use (a bug, please report it)"
        )));
    };
    let transport = end.into_inner();
    match result {
        Ok(done) if rank == 0 => Ok(Some(done)),
        Ok(_) => Ok(None),
        // Rank 0 wrote the checkpoint the run goes on from.
        Err(e) if e.exit_code() == 3 => {
            if rank == 0 {
                crate::progress::note(format_args!("stopped: {e}"));
            }
            transport.abort(3)
        }
        Err(e) => {
            crate::progress::note(format_args!("error: rank {rank}: {e}"));
            transport.abort(e.exit_code().into())
        }
    }
}
