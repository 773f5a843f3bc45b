//! What a command line asks of a job beyond its configuration.

use std::path::PathBuf;
use std::sync::Arc;

use sdg_scheduler::Options;

use crate::error::EngineError;
use crate::problem::Problem;
use crate::solve::Control;

/// Command-line choices that are not part of the configuration.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output folder; overrides `output.dir`.
    pub output_dir: Option<PathBuf>,
    /// Worker threads; `None` means all available cores.
    pub threads: Option<usize>,
    /// Forces deterministic mode on (overrides `scheduler.deterministic`).
    pub deterministic: bool,
    /// Show a progress bar on a terminal, and the estimate before the run on standard error.
    pub progress: bool,
    /// Run even when the estimate exceeds `[limits]`.
    pub force: bool,
    /// Go on from this checkpoint, or from the newest valid one in this folder.
    pub restart: Option<PathBuf>,
    /// Checkpoint and stop (exit code 3) after this much wall time, s.
    pub max_wall_time_s: Option<f64>,
    /// Record every tent and event in this file (`sdg scaling` replays it).
    pub trace: Option<PathBuf>,
    /// Where requests to checkpoint or stop come from (the signal listener); a run makes its
    /// own when `None`.
    pub control: Option<Arc<Control>>,
}

impl RunOptions {
    /// The scheduler options for `problem`: threads and mode.
    pub fn scheduler(&self, problem: &Problem) -> Options {
        let threads = self
            .threads
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        Options {
            threads: threads.max(1),
            deterministic: self.deterministic || problem.loaded.config.scheduler.deterministic,
        }
    }

    /// The output folder for `problem` and where it came from (`--output` or `output.dir`).
    fn output_path(&self, problem: &Problem) -> (PathBuf, &'static str) {
        match &self.output_dir {
            Some(dir) => (dir.clone(), "--output"),
            None => (problem.loaded.config.output.dir.clone(), "output.dir"),
        }
    }

    /// The output folder for `problem`, not created (a rank that writes nothing).
    pub(crate) fn output_folder(&self, problem: &Problem) -> PathBuf {
        self.output_path(problem).0
    }

    /// The output folder for `problem`, created; a folder that cannot be created is bad input,
    /// named with where it came from (`--output` or `output.dir`).
    pub fn output_dir(&self, problem: &Problem) -> Result<PathBuf, EngineError> {
        let (dir, from) = self.output_path(problem);
        let bad = |reason: String| {
            EngineError::Input(format!(
                "{from} {}: cannot create the output folder: {reason}",
                dir.display()
            ))
        };
        if dir.exists() && !dir.is_dir() {
            return Err(bad("it is a file, not a folder".into()));
        }
        std::fs::create_dir_all(&dir).map_err(|e| bad(e.to_string()))?;
        crate::output::check_writable(&dir, &format!("{from} {}", dir.display()))?;
        Ok(dir)
    }
}
