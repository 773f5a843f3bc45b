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
//! summary or to be run again.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use super::cases::{Case, case_dir};
use super::file::Study;
use super::record::{self, CaseStatus, SUMMARY};
use crate::error::EngineError;

/// The environment variable that gives a case's `sdg run` the study's process id: the run
/// exits at once when its parent process is gone (a study killed outright leaves no runs
/// behind).
pub const PARENT_ENV: &str = "SDG_STUDY_PARENT";

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
            _ => todo.push(case),
        }
    }
    let started = Instant::now();
    if plan.progress {
        say(format_args!(
            "study {}: {} cases, {} finished before; running {} ({} at a time, {} thread{} each){}",
            study.file.display(),
            selected.len(),
            tally.skipped,
            todo.len(),
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
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(case) = todo.get(i) else {
                return Ok(());
            };
            let start = Instant::now();
            let dir = case_dir(&plan.out, case.index, cases.len());
            let code = run_case(study, case, &dir, plan)?;
            let seconds = start.elapsed().as_secs_f64();
            let mut s = shared.lock().unwrap_or_else(|e| e.into_inner());
            if code == 0 {
                s.tally.finished += 1;
                s.times.push(seconds);
            } else {
                s.tally.failed.push((case.index, code));
                report_failure(study, case, &dir, code);
            }
            if plan.progress {
                let ended = s.tally.finished + s.tally.failed.len();
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
                    if code == 0 { "finished" } else { "failed" },
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
    Ok(tally)
}

/// Runs `case` into `dir` with `sdg run` and returns its exit code.
fn run_case(study: &Study, case: &Case, dir: &Path, plan: &RunPlan) -> Result<i32, EngineError> {
    std::fs::create_dir_all(dir).map_err(|e| EngineError::io(dir, e))?;
    let summary = dir.join(SUMMARY);
    match std::fs::remove_file(&summary) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(EngineError::io(summary, e));
        }
        _ => {}
    }
    record::write(case, dir, None)?;
    let log_path = dir.join(LOG);
    let log = std::fs::File::create(&log_path).map_err(|e| EngineError::io(&log_path, e))?;
    let err_log = log.try_clone().map_err(|e| EngineError::io(&log_path, e))?;
    let mut command = Command::new(&plan.program);
    command.arg("run").arg(&study.base);
    for spec in &case.overrides {
        command.arg("--set").arg(spec);
    }
    command
        .arg("--output")
        .arg(dir)
        .arg("--threads")
        .arg(plan.threads.to_string())
        .arg("--quiet")
        .env(PARENT_ENV, std::process::id().to_string())
        .stdin(Stdio::null())
        .stdout(log)
        .stderr(err_log);
    let status = command
        .status()
        .map_err(|e| EngineError::io(&plan.program, e))?;
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
