//! A case's folder: `case.json` (its overrides and config hash, and how its run ended) and
//! what state the folder says the case is in.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::cases::Case;
use crate::error::EngineError;
use crate::output::write_atomic;

/// `case.json` in a case's folder, written (atomically) before its run starts and again when
/// it ends.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
pub(super) struct CaseRecord {
    /// The case number.
    pub case: usize,
    /// The overrides of the base config (`sdg run --set`).
    pub overrides: Vec<String>,
    /// The hash of the config the run ran ([`super::config_hash`]).
    pub config_hash: String,
    /// The exit code of `sdg run`; `None` while it runs (or if the study was killed).
    pub exit_code: Option<i32>,
}

/// The state of a case, from its folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaseStatus {
    /// Not started.
    Pending,
    /// Its run finished: `summary.json` is there, of this config.
    Done,
    /// Its run ended with this exit code and no summary (1 failed, 2 refused, other: killed by
    /// a signal or the code is unknown (-1)).
    Failed(i32),
    /// Its run checkpointed and stopped (exit 3): run again, it goes on from the checkpoint.
    Stopped,
    /// Started and not ended: running, or the study was killed while it ran.
    Unfinished,
    /// Its folder holds a run of another config (the study changed since): run again.
    Stale,
}

impl CaseStatus {
    /// The status as `study.csv` writes it: pending, done, failed, unfinished or stale.
    pub fn name(self) -> &'static str {
        match self {
            Self::Pending => "pending",
            Self::Done => "done",
            Self::Failed(_) => "failed",
            Self::Stopped => "stopped",
            Self::Unfinished => "unfinished",
            Self::Stale => "stale",
        }
    }
}

/// What the case folders hold, case by case.
#[derive(Clone, Debug, PartialEq)]
pub struct Collected {
    /// The state of each case.
    pub statuses: Vec<CaseStatus>,
    /// Each case's value of each metric (in the study's order): `None` where the case is not
    /// done or its summary has no value.
    pub values: Vec<Vec<Option<f64>>>,
}

impl Collected {
    /// Cases in `status`.
    pub fn count(&self, status: fn(&CaseStatus) -> bool) -> usize {
        self.statuses.iter().filter(|s| status(s)).count()
    }
}

/// The file a case's record is kept in.
pub(super) const RECORD: &str = "case.json";
/// The summary a finished run writes.
pub(super) const SUMMARY: &str = "summary.json";

/// The state of `case` from its folder `dir` (`Err` when its `case.json` cannot be read).
pub fn case_status(case: &Case, dir: &Path) -> Result<CaseStatus, EngineError> {
    let path = dir.join(RECORD);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(CaseStatus::Pending),
        Err(e) => return Err(EngineError::io(path, e)),
    };
    let record: CaseRecord = serde_json::from_str(&text).map_err(|e| {
        EngineError::Input(format!(
            "{}: not a case record of sdg study: {e}; remove the case's folder to run it again",
            path.display()
        ))
    })?;
    Ok(if record.config_hash != case.hash {
        CaseStatus::Stale
    } else if dir.join(SUMMARY).is_file() {
        CaseStatus::Done
    } else {
        match record.exit_code {
            None => CaseStatus::Unfinished,
            Some(3) => CaseStatus::Stopped,
            Some(code) => CaseStatus::Failed(code),
        }
    })
}

/// Writes `case.json` of `case` into `dir` with the run's `exit_code` (`None`: starting).
pub(super) fn write(case: &Case, dir: &Path, exit_code: Option<i32>) -> Result<(), EngineError> {
    let record = CaseRecord {
        case: case.index,
        overrides: case.overrides.clone(),
        config_hash: case.hash.clone(),
        exit_code,
    };
    let text = serde_json::to_string_pretty(&record).expect("a record serializes") + "\n";
    write_atomic(dir, RECORD, text.as_bytes()).map(drop)
}
