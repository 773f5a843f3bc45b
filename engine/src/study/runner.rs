//! Running a study's cases, each as its own `sdg run` process, a few at a time.
//!
//! A case is a child process rather than a run inside this one: a case that panics, runs out
//! of memory or is killed takes no other case with it, its exit code (0, 1, 2, 3) is that of
//! `sdg run` and means the same, and its output folder is exactly that of `sdg run`. The cost,
//! a process start and a config load per case, is nothing beside a run.
//!
//! Resuming: a case is run unless its folder holds a `summary.json` and a `case.json` of the
//! same config hash. Before a run starts its old `summary.json` is removed and `case.json`
//! (the overrides and the hash) is written, both atomically; when it ends `case.json` gets the
//! exit code. A study killed at any point so leaves every case either finished with its
//! summary or to be run again; a case run again goes on from its last checkpoint when its
//! folder holds one of the same config (a case of another config has its checkpoints
//! removed), so a long case stopped by a time limit loses at most the time since then.
//!
//! Stopping: each case's standard input is a pipe from the study ([`STUDY_ENV`]). The study
//! closes it to ask the run to checkpoint and stop (exit 3), and the kernel closes it when
//! the study dies, even by SIGKILL: no run outlives its study, and none is lost.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{ChildStdin, Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use super::cases::{Case, case_dir};
use super::file::Study;
use super::record::{self, CaseStatus, SUMMARY};
use crate::error::EngineError;

/// Set (to the study's process id) in the environment of a case's `sdg run`: its standard
/// input is a pipe from the study, on which a byte [`CHECKPOINT_BYTE`] asks for a checkpoint
/// (the run goes on) and the end asks it to checkpoint and stop (exit 3).
pub const STUDY_ENV: &str = "SDG_STUDY_PARENT";

/// The byte on a case's standard input that asks its run for a checkpoint.
pub const CHECKPOINT_BYTE: u8 = b'c';

/// A case's checkpoint folder, in its output folder (`sdg run`'s default).
const CHECKPOINTS: &str = "checkpoints";

/// The study's hold on its running cases: asks them to checkpoint, or to checkpoint and stop.
#[derive(Debug, Default)]
pub struct Stop {
    requested: AtomicBool,
    /// The standard input of each running case, by case number.
    inputs: Mutex<Vec<(usize, ChildStdin)>>,
}

impl Stop {
    /// Asks every running case to checkpoint and stop (closes their standard inputs) and
    /// starts no case after.
    pub fn request(&self) {
        self.requested.store(true, Ordering::SeqCst);
        self.lock().clear();
    }

    /// Whether [`Self::request`] was called.
    pub fn requested(&self) -> bool {
        self.requested.load(Ordering::SeqCst)
    }

    /// Asks every running case for a checkpoint; they go on.
    pub fn checkpoint(&self) {
        for (_, input) in self.lock().iter_mut() {
            // A run that has just ended has closed its end: nothing to ask.
            let _ = input.write_all(&[CHECKPOINT_BYTE]);
            let _ = input.flush();
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(usize, ChildStdin)>> {
        self.inputs.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Keeps the standard input of case `case`'s run, or closes it at once after a request.
    fn hold(&self, case: usize, input: ChildStdin) {
        let mut inputs = self.lock();
        if !self.requested() {
            inputs.push((case, input));
        }
    }

    /// Lets go of case `case`'s standard input (its run has ended).
    fn release(&self, case: usize) {
        self.lock().retain(|(k, _)| *k != case);
    }
}

/// The log of a case's run (its standard output and error) in the case's folder.
const LOG: &str = "log.txt";

/// Lines of a failed case's log repeated in the study's report.
const LOG_TAIL: usize = 5;

/// How to run a study's cases.
#[derive(Clone, Debug)]
pub struct RunPlan {
    /// The `sdg` binary that runs each case.
    pub program: PathBuf,
    /// The study's output folder: the cases run in `out/cases/NNN`.
    pub out: PathBuf,
    /// Cases run at once.
    pub jobs: usize,
    /// Worker threads of each run (`sdg run --threads`).
    pub threads: usize,
    /// Print a line per case with an estimate of the time left (stderr); failures are printed
    /// regardless.
    pub progress: bool,
    /// Estimated wall time of one case, s (`sdg validate`'s estimate of the first), for the
    /// time left until a case has finished.
    pub estimate_s: Option<f64>,
    /// How the study stops its cases (signals to the study: `sdg study`).
    pub stop: std::sync::Arc<Stop>,
}

/// What a call of [`run_cases`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Cases run that finished.
    pub finished: usize,
    /// Cases skipped: finished before, with the same config.
    pub skipped: usize,
    /// Cases run that failed: (case, exit code; 128 + N for signal N, -1 unknown).
    pub failed: Vec<(usize, i32)>,
    /// Cases whose run checkpointed and stopped (exit 3): run the study again to go on.
    pub stopped: Vec<usize>,
}

/// Progress shared by the workers: what is done and how long it took.
#[derive(Debug)]
struct Shared {
    tally: Tally,
    /// Wall time of each case run to the end, s.
    times: Vec<f64>,
}

/// Runs the cases numbered `selected` of `cases` that are not finished, `plan.jobs` at a time.
/// A case that fails is reported (its exit code and the end of its log on stderr) and the
/// others go on; `Err` only when a case cannot be started at all (the program is missing, a
/// folder cannot be written).
pub fn run_cases(
    study: &Study,
    cases: &[Case],
    selected: &[usize],
    plan: &RunPlan,
) -> Result<Tally, EngineError> {
    let mut todo = Vec::new();
    let mut tally = Tally::default();
    for &k in selected {
        let case = &cases[k];
        match record::case_status(case, &case_dir(&plan.out, k, cases.len()))? {
            CaseStatus::Done => tally.skipped += 1,
            status => todo.push((case, status)),
        }
    }
    let started = Instant::now();
    if plan.progress {
        let resuming = (todo.iter())
            .filter(|(case, status)| {
                !matches!(status, CaseStatus::Stale | CaseStatus::Pending)
                    && crate::solve::checkpoint::holds_checkpoint(
                        &case_dir(&plan.out, case.index, cases.len()).join(CHECKPOINTS),
                    )
            })
            .count();
        say(format_args!(
            "study {}: {} cases, {} finished before; running {}{} ({} at a time, {} thread{} each){}",
            study.file.display(),
            selected.len(),
            tally.skipped,
            todo.len(),
            match resuming {
                0 => String::new(),
                n => format!(", {n} from their checkpoints"),
            },
            plan.jobs,
            plan.threads,
            if plan.threads == 1 { "" } else { "s" },
            plan.estimate_s.map_or(String::new(), |s| format!(
                ", about {} left",
                duration(s * todo.len().div_ceil(plan.jobs) as f64)
            ))
        ));
    }
    let shared = Mutex::new(Shared {
        tally,
        times: Vec::new(),
    });
    let next = AtomicUsize::new(0);
    let worker = || -> Result<(), EngineError> {
        loop {
            if plan.stop.requested() {
                return Ok(());
            }
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(&(case, status)) = todo.get(i) else {
                return Ok(());
            };
            let start = Instant::now();
            let dir = case_dir(&plan.out, case.index, cases.len());
            let code = run_case(study, (case, status), &dir, plan)?;
            let seconds = start.elapsed().as_secs_f64();
            let mut s = shared.lock().unwrap_or_else(|e| e.into_inner());
            if code == 0 {
                s.tally.finished += 1;
                s.times.push(seconds);
            } else if code == 3 {
                s.tally.stopped.push(case.index);
            } else {
                s.tally.failed.push((case.index, code));
                report_failure(study, case, &dir, code);
            }
            if plan.progress {
                let ended = s.tally.finished + s.tally.failed.len() + s.tally.stopped.len();
                let mean = match s.times.len() {
                    0 => plan.estimate_s,
                    n => Some(s.times.iter().sum::<f64>() / n as f64),
                };
                let rounds = (todo.len() - ended).div_ceil(plan.jobs) as f64;
                let left = match mean.filter(|_| rounds > 0.0) {
                    Some(m) => format!(", about {} left", duration(m * rounds)),
                    None => String::new(),
                };
                say(format_args!(
                    "case {} ({}): {} in {}; {ended} of {} run, {} failed, {} elapsed{left}",
                    case.index,
                    case.label(&study.axes),
                    match code {
                        0 => "finished",
                        3 => "checkpointed and stopped",
                        _ => "failed",
                    },
                    duration(seconds),
                    todo.len(),
                    s.tally.failed.len(),
                    duration(started.elapsed().as_secs_f64()),
                ));
            }
        }
    };
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..plan.jobs.max(1)).map(|_| scope.spawn(worker)).collect();
        workers
            .into_iter()
            .map(|w| w.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect::<Result<Vec<()>, _>>()
    })?;
    let mut tally = shared.into_inner().unwrap_or_else(|e| e.into_inner()).tally;
    tally.failed.sort_unstable();
    tally.stopped.sort_unstable();
    Ok(tally)
}

/// Runs `case`, in state `status`, into `dir` with `sdg run` and returns its exit code: from
/// its last checkpoint when `dir` holds one of the case's config, from the beginning otherwise.
fn run_case(
    study: &Study,
    (case, status): (&Case, CaseStatus),
    dir: &Path,
    plan: &RunPlan,
) -> Result<i32, EngineError> {
    std::fs::create_dir_all(dir).map_err(|e| EngineError::io(dir, e))?;
    let summary = dir.join(SUMMARY);
    match std::fs::remove_file(&summary) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(EngineError::io(summary, e));
        }
        _ => {}
    }
    let checkpoints = dir.join(CHECKPOINTS);
    let resume = match status {
        // Checkpoints of another config: `sdg run` would refuse to write beside them.
        CaseStatus::Stale | CaseStatus::Pending => match std::fs::remove_dir_all(&checkpoints) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(EngineError::io(checkpoints, e));
            }
            _ => false,
        },
        _ => crate::solve::checkpoint::holds_checkpoint(&checkpoints),
    };
    record::write(case, dir, None)?;
    let log_path = dir.join(LOG);
    let log = std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .append(resume)
        .truncate(!resume)
        .open(&log_path)
        .map_err(|e| EngineError::io(&log_path, e))?;
    let err_log = log.try_clone().map_err(|e| EngineError::io(&log_path, e))?;
    let mut command = Command::new(&plan.program);
    command.arg("run").arg(&study.base);
    for spec in &case.overrides {
        command.arg("--set").arg(spec);
    }
    if resume {
        command.arg("--restart").arg(&checkpoints);
    }
    command
        .arg("--output")
        .arg(dir)
        .arg("--threads")
        .arg(plan.threads.to_string())
        .arg("--quiet")
        .env(STUDY_ENV, std::process::id().to_string())
        .stdin(Stdio::piped())
        .stdout(log)
        .stderr(err_log);
    let mut child = command
        .spawn()
        .map_err(|e| EngineError::io(&plan.program, e))?;
    if let Some(input) = child.stdin.take() {
        plan.stop.hold(case.index, input);
    }
    let status = child.wait();
    plan.stop.release(case.index);
    let status = status.map_err(|e| EngineError::io(&plan.program, e))?;
    let code = status.code().unwrap_or_else(|| {
        use std::os::unix::process::ExitStatusExt;
        status.signal().map_or(-1, |s| 128 + s)
    });
    record::write(case, dir, Some(code))?;
    Ok(code)
}

/// Reports on stderr that `case` failed with `code`, with the end of its log.
fn report_failure(study: &Study, case: &Case, dir: &Path, code: i32) {
    let log = dir.join(LOG);
    let text = std::fs::read_to_string(&log).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    let tail = lines[lines.len().saturating_sub(LOG_TAIL)..].join("\n  ");
    say(format_args!(
        "case {} ({}) failed: sdg run exited {code}; log {}{}",
        case.index,
        case.label(&study.axes),
        log.display(),
        if tail.is_empty() {
            String::new()
        } else {
            format!(":\n  {tail}")
        }
    ));
}

/// Writes a line to stderr, dropping it if stderr cannot be written.
fn say(line: std::fmt::Arguments) {
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// `s` seconds as `1 h 02 min`, `3 min 20 s` or `12.3 s`.
fn duration(s: f64) -> String {
    let whole = s.round() as u64;
    match whole {
        _ if s < 60.0 => format!("{s:.1} s"),
        0..3600 => format!("{} min {:02} s", whole / 60, whole % 60),
        _ => format!("{} h {:02} min", whole / 3600, whole % 3600 / 60),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn durations_read_well() {
        assert_eq!(super::duration(12.34), "12.3 s");
        assert_eq!(super::duration(200.0), "3 min 20 s");
        assert_eq!(super::duration(3720.0), "1 h 02 min");
    }
}
