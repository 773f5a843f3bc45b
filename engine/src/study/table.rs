//! Gathering finished cases: `study.csv` (a row per case), `study.json` (statistics per group
//! of cases) and `study.png`.

use std::path::Path;

use serde_json::{Value, json};

use super::cases::{self, Case, Group, case_dir, groups};
use super::file::Study;
use super::metrics::metric_value;
use super::picture;
use super::record::{self, CaseStatus, Collected, SUMMARY};
use super::stats::Stats;
use crate::error::EngineError;
use crate::output::table::Table;
use crate::output::write_atomic;

/// Reads every case's folder under `out` and writes `study.csv`, `study.json` and `study.png`
/// there. Nothing runs; cases not done have empty metrics.
pub fn collect(study: &Study, cases: &[Case], out: &Path) -> Result<Collected, EngineError> {
    let mut collected = Collected {
        statuses: Vec::new(),
        values: Vec::new(),
    };
    for case in cases {
        let dir = case_dir(out, case.index, cases.len());
        let status = record::case_status(case, &dir)?;
        let summary = match status {
            CaseStatus::Done => Some(read_summary(&dir.join(SUMMARY))?),
            _ => None,
        };
        let values = (study.metrics.iter())
            .map(|m| summary.as_ref().and_then(|s| metric_value(s, m)))
            .collect();
        collected.statuses.push(status);
        collected.values.push(values);
    }
    write_atomic(out, "study.csv", csv(study, cases, &collected).as_bytes())?;
    let groups = groups(&study.axes, cases);
    let json = summary_json(study, &groups, &collected);
    let text = serde_json::to_string_pretty(&json).expect("JSON serializes") + "\n";
    write_atomic(out, "study.json", text.as_bytes())?;
    picture::write_png(study, cases, &groups, &collected, &out.join("study.png"))?;
    Ok(collected)
}

/// The summary at `path`, parsed.
fn read_summary(path: &Path) -> Result<Value, EngineError> {
    let text = std::fs::read_to_string(path).map_err(|e| EngineError::io(path, e))?;
    serde_json::from_str(&text)
        .map_err(|e| EngineError::Input(format!("{}: not JSON: {e}", path.display())))
}

/// `study.csv`: `case`, a column per axis (each followed by the keys that go with it) and per
/// metric (named by their keys), `status`.
fn csv(study: &Study, cases: &[Case], collected: &Collected) -> String {
    let mut header = vec!["case".to_string()];
    for axis in &study.axes {
        header.push(axis.key.clone());
        header.extend(axis.with.iter().map(|(k, _)| k.clone()));
    }
    header.extend(study.metrics.iter().cloned());
    header.push("status".into());
    let mut table = Table::new(header);
    for (case, (status, values)) in cases
        .iter()
        .zip(collected.statuses.iter().zip(&collected.values))
    {
        let mut cells = vec![case.index.to_string()];
        for (axis, value) in study.axes.iter().zip(&case.values) {
            cells.push(cases::value_text(value));
            cells.extend(axis.companions(value).map(|(_, v)| cases::value_text(v)));
        }
        cells.extend(values.iter().map(|v| v.map_or(String::new(), number)));
        cells.push(status.name().into());
        table.row(cells);
    }
    table.into_text()
}

/// A metric's value as a cell: whole numbers as integers, others in exact exponent notation.
fn number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:e}")
    }
}

/// `study.json`: the study, and per group per metric the statistics over its finished cases.
fn summary_json(study: &Study, groups: &[Group], collected: &Collected) -> Value {
    let axes: Vec<Value> = (study.axes.iter())
        .map(|a| {
            let with: serde_json::Map<String, Value> = (a.with.iter())
                .map(|(k, vs)| (k.clone(), json!(vs)))
                .collect();
            json!({"key": a.key, "values": a.values, "draws": a.draws, "with": with})
        })
        .collect();
    let non_draws: Vec<&str> = (study.axes.iter())
        .filter(|a| !a.draws)
        .map(|a| a.key.as_str())
        .collect();
    let groups: Vec<Value> = groups
        .iter()
        .map(|g| {
            let done: Vec<usize> = (g.cases.iter().copied())
                .filter(|&c| collected.statuses[c] == CaseStatus::Done)
                .collect();
            let metrics: serde_json::Map<String, Value> = (study.metrics.iter().enumerate())
                .map(|(m, key)| {
                    let values: Vec<Option<f64>> =
                        done.iter().map(|&c| collected.values[c][m]).collect();
                    (key.clone(), json!(Stats::of(&values)))
                })
                .collect();
            let values: serde_json::Map<String, Value> = (non_draws.iter().zip(&g.values))
                .map(|(k, v)| (k.to_string(), json!(v)))
                .collect();
            json!({"axes": values, "cases": g.cases.len(), "done": done.len(), "metrics": metrics})
        })
        .collect();
    json!({
        "study": study.file,
        "base": study.base,
        "cases": collected.statuses.len(),
        "done": collected.count(|s| *s == CaseStatus::Done),
        "failed": collected.count(|s| matches!(s, CaseStatus::Failed(_))),
        "stopped": collected.count(|s| *s == CaseStatus::Stopped),
        "metrics": study.metrics,
        "axes": axes,
        "groups": groups,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_exact() {
        assert_eq!(number(1234.0), "1234");
        assert_eq!(number(1.009080010288655e-6), "1.009080010288655e-6");
        assert_eq!(number(-0.5), "-5e-1");
    }
}
