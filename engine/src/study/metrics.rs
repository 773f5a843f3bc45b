//! Metrics: the numeric keys of `summary.json` a study may collect, and their values.
//!
//! The keys are those of the key table of `docs/reference/summary.md` (compiled in) whose type
//! is a number or an integer; `tests/summary_schema.rs` checks that table against what runs
//! write, so the two cannot drift apart.

use std::collections::BTreeSet;

/// The summary's documentation, whose key table lists every key.
const SUMMARY_DOC: &str = include_str!("../../../docs/reference/summary.md");

/// The dotted `summary.json` keys that hold a number (possibly `null`), keys inside arrays
/// excluded.
pub fn metric_keys() -> BTreeSet<&'static str> {
    let rows = SUMMARY_DOC.lines().filter_map(|line| {
        let mut cells = line.strip_prefix("| `")?.split('|');
        let key = cells.next()?.trim().trim_end_matches('`');
        let kind = cells.next()?.trim();
        let numeric = kind.starts_with("number") || kind.starts_with("integer");
        (numeric && !key.contains('[')).then_some(key)
    });
    rows.collect()
}

/// `Ok` when `key` is a metric; else why not, with the keys that share its first part.
pub(super) fn check_metric(key: &str) -> Result<(), String> {
    let keys = metric_keys();
    if keys.contains(key) {
        return Ok(());
    }
    let head = key.split('.').next().unwrap_or(key);
    let near: Vec<&str> = keys
        .iter()
        .copied()
        .filter(|k| k.split('.').next() == Some(head))
        .collect();
    let hint = match near.is_empty() {
        true => String::new(),
        false => format!("; keys under `{head}`: {}", near.join(", ")),
    };
    Err(format!(
        "`{key}` is not a number of summary.json (docs/reference/summary.md lists the keys){hint}"
    ))
}

/// The value of the dotted `key` in a summary: `None` when absent or `null` (a missing metric
/// is data: nothing branched, say).
pub fn metric_value(summary: &serde_json::Value, key: &str) -> Option<f64> {
    key.split('.')
        .try_fold(summary, |node, k| node.get(k))
        .and_then(serde_json::Value::as_f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_are_the_numeric_keys_of_the_summary() {
        let keys = metric_keys();
        for key in [
            "patches",
            "wall_time_s",
            "energy.balance_residual_rel",
            "crack.first_branching_time",
            "fracture.macro_branching.distance",
            "crack.max_branch_speed_over_c_r",
        ] {
            assert!(keys.contains(key), "{key}");
        }
        for key in ["mode", "energy", "estimate.lower_bound", "snapshots[]"] {
            assert!(!keys.contains(key), "{key}");
        }
        assert!(keys.len() > 50, "{}", keys.len());
        let e = check_metric("crack.first_branching_tme").unwrap_err();
        assert!(e.contains("crack.first_branching_time"), "{e}");
    }

    #[test]
    fn values_are_read_by_dotted_key() {
        let s =
            serde_json::json!({"patches": 12, "crack": {"first_branching_time": null, "x": 1.5}});
        assert_eq!(metric_value(&s, "patches"), Some(12.0));
        assert_eq!(metric_value(&s, "crack.x"), Some(1.5));
        assert_eq!(metric_value(&s, "crack.first_branching_time"), None);
        assert_eq!(metric_value(&s, "crack.y"), None);
    }
}
