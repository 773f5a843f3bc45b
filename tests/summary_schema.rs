//! `summary.json` against its schema, the key table of `docs/reference/summary.md`: every key a
//! run writes is documented, and every key documented as always present is written (when its
//! object is).

use crate::common;

use std::collections::BTreeSet;
use std::path::Path;

use serde_json::Value;

/// The documented keys and those documented as always present: the first and fourth cells of
/// the table rows of `docs/reference/summary.md`.
fn documented() -> (BTreeSet<String>, BTreeSet<String>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/reference/summary.md");
    let text = std::fs::read_to_string(path).expect("docs/reference/summary.md");
    let (mut all, mut always) = (BTreeSet::new(), BTreeSet::new());
    for line in text.lines().filter(|l| l.starts_with("| `")) {
        let line = line.replace("\\|", "");
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let key = cells[1].trim_matches('`').to_string();
        if cells[4] == "always" {
            always.insert(key.clone());
        }
        all.insert(key);
    }
    assert!(
        always.contains("state_hash"),
        "no key table in docs/reference/summary.md"
    );
    (all, always)
}

/// The keys of `value` as dotted paths below `prefix`; an array's elements as `prefix[]`, the
/// objects among them walked further.
fn paths(value: &Value, prefix: &str, out: &mut BTreeSet<String>) {
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                let path = match prefix {
                    "" => key.clone(),
                    _ => format!("{prefix}.{key}"),
                };
                paths(v, &path, out);
                out.insert(path);
            }
        }
        Value::Array(items) => {
            let path = format!("{prefix}[]");
            for v in items {
                if v.is_object() {
                    paths(v, &path, out);
                }
                out.insert(path.clone());
            }
        }
        _ => {}
    }
}

/// Runs the shipped `config` with `sets` on one thread and checks its summary against the
/// documentation; `sections` are optional keys the run must write. Returns the summary.
fn check(config: &str, sets: &[&str], sections: &[&str]) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let config = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(config);
    let mut args = vec![
        "run",
        config.to_str().unwrap(),
        "--output",
        dir.path().to_str().unwrap(),
        "--threads",
        "1",
        "--quiet",
        "--set",
        "output.png=false",
    ];
    for set in sets {
        args.extend(["--set", set]);
    }
    let out = common::sdg(&args);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
    let summary: Value = serde_json::from_str(&text).unwrap();
    let mut written = BTreeSet::new();
    paths(&summary, "", &mut written);

    let (all, always) = documented();
    let undocumented: Vec<_> = written.difference(&all).collect();
    assert!(
        undocumented.is_empty(),
        "keys not in docs/reference/summary.md: {undocumented:?}"
    );
    let missing: Vec<_> = always
        .iter()
        .filter(|k| !written.contains(*k))
        .filter(|k| k.rsplit_once('.').is_none_or(|(p, _)| written.contains(p)))
        .collect();
    assert!(
        missing.is_empty(),
        "always present in docs/reference/summary.md, not written: {missing:?}"
    );
    for s in sections {
        assert!(written.contains(*s), "{s} not written: {text}");
    }
    summary
}

/// `overrides` holds the `--set` overrides in the order given.
#[test]
fn plane_wave_summary_is_documented() {
    let sets = [
        "mesh.nx=4",
        "mesh.ny=4",
        "time.end=2e-7",
        "output.snapshot_times=[0.0]",
    ];
    let summary = check("plane_wave.toml", &sets, &["error", "snapshots[]"]);
    let mut given = vec!["output.png=false"];
    given.extend(sets);
    assert_eq!(summary["overrides"], serde_json::json!(given));
}

/// With `[fracture]`, `crack` repeats the network's totals of `fracture` under the names of
/// the crack-branching problem's outputs.
#[test]
fn fracture_summary_is_documented() {
    let network = [
        "branches",
        "total_length",
        "first_branching_time",
        "first_branching_distance",
    ];
    let keys: Vec<String> = network.iter().map(|k| format!("crack.{k}")).collect();
    let mut sections = vec!["crack", "fracture"];
    sections.extend(keys.iter().map(String::as_str));
    let summary = check("crack_growth.toml", &["time.end=2e-8"], &sections);
    for k in network {
        assert_eq!(summary["crack"][k], summary["fracture"][k], "{k}");
    }
    assert!(summary["crack"]["branches"].as_u64().unwrap() >= 1);
}

/// Without `[fracture]`, `crack` has the tips' keys alone.
#[test]
fn loading_summary_is_documented() {
    let summary = check("mode1_lefm.toml", &["time.end=2e-8"], &["loading", "crack"]);
    assert!(summary["crack"].get("branches").is_none(), "{summary}");
}
