//! `sdg run --ranks N --deterministic` of configs with mesh-changing events (`[adapt]`,
//! `[fracture]`): the rounds split over ranks that each hold the whole state give the threaded
//! deterministic run's state hash, patches, events and energies, for any rank and thread
//! count; a run stopped mid-run goes on from its checkpoint over other ranks or on threads to
//! the same state; only rank 0 writes files.

use crate::common;

use std::path::Path;

use common::{SMALL_CRACK, run_args, sdg, stderr, summary_json};
use serde_json::Value;

/// Runs the shipped config `name` with `overrides` and `extra` arguments into `out`, asserting
/// that it succeeds; returns its `summary.json` and its warnings (stderr's `WARN` lines).
fn run(name: &str, overrides: &[&str], extra: &[&str], out: &Path) -> (Value, Vec<String>) {
    let args = run_args(name, overrides, extra, out);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = sdg(&args);
    let err = stderr(&result);
    assert!(result.status.success(), "{err}");
    let warnings = (err.lines().filter(|l| l.contains(" WARN ")))
        .map(|l| l.split_once(" WARN ").unwrap().1.to_string())
        .collect();
    (summary_json(out), warnings)
}

/// Asserts that `ranks` is the run `threads`: the same state, patches, rounds' outcomes and
/// bookkeeping (rank 0 keeps the threaded run's books).
fn assert_same_run(what: &str, threads: &Value, ranks: &Value) {
    for key in ["state_hash", "patches", "elements", "vertices", "mode"] {
        assert_eq!(ranks[key], threads[key], "{what}: {key}");
    }
    for block in ["energy", "adapt", "crack", "fracture"] {
        assert_eq!(ranks[block], threads[block], "{what}: {block}");
    }
}

#[test]
fn adaptive_and_cracking_runs_over_ranks_are_the_threaded_deterministic_runs() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[&str]); 2] = [
        (
            "adaptive_pulse.toml",
            &[
                "time.end=2e-6",
                "output.snapshot_times=[]",
                "output.png=false",
            ],
        ),
        ("crack_growth.toml", &SMALL_CRACK),
    ];
    for (name, overrides) in cases {
        let reference = dir.path().join(format!("{name}-threads"));
        let (threads, said) = run(
            name,
            overrides,
            &["--threads", "2", "--deterministic"],
            &reference,
        );
        assert_eq!(threads["mode"], "deterministic");
        // The adaptive run's refinement meets its floor: the warning that the ranks must say once.
        if name == "adaptive_pulse.toml" {
            assert_eq!(said.len(), 1, "{said:?}");
        }
        for (ranks, per_rank) in [(3, 1), (2, 2)] {
            let out = dir.path().join(format!("{name}-{ranks}-{per_rank}"));
            let (ranks_arg, per_rank_arg) = (ranks.to_string(), per_rank.to_string());
            let extra = [
                "--ranks",
                &ranks_arg,
                "--threads",
                &per_rank_arg,
                "--deterministic",
            ];
            let (summary, warnings) = run(name, overrides, &extra, &out);
            assert_same_run(&format!("{name} on {ranks} ranks"), &threads, &summary);
            // Said once, by rank 0, as on threads.
            assert_eq!(warnings, said, "{name} on {ranks} ranks");
            assert_eq!(summary["ranks"], ranks);
            assert_eq!(summary["threads"], ranks * per_rank);
        }
    }
    // The cracks grew and the mesh changed: there were events to split.
    let growth = summary_json(&dir.path().join("crack_growth.toml-threads"));
    assert!(
        growth["crack"]["branches"].as_u64().unwrap() > 0,
        "{growth}"
    );
}

#[test]
fn a_cracking_run_over_ranks_stopped_mid_run_goes_on_over_other_ranks_and_on_threads() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = SMALL_CRACK;
    let name = "crack_growth.toml";
    let reference = dir.path().join("reference");
    let (expected, _) = run(
        name,
        &overrides,
        &["--threads", "1", "--deterministic"],
        &reference,
    );
    let out = dir.path().join("stopped");
    let args = run_args(
        name,
        &overrides,
        &["--ranks", "2", "--deterministic", "--max-wall-time", "0.5"],
        &out,
    );
    // The ranks but 0 write no file, not even into a temporary folder: one that cannot be
    // made changes nothing.
    let not_a_folder = dir.path().join("tmp-is-a-file");
    std::fs::write(&not_a_folder, b"").unwrap();
    let result = std::process::Command::new(env!("CARGO_BIN_EXE_sdg"))
        .args(&args)
        .env("TMPDIR", &not_a_folder)
        .output()
        .expect("the sdg binary runs");
    // Stopped mid-run on any machine this test runs on (the run takes seconds).
    assert_eq!(result.status.code(), Some(3), "{}", stderr(&result));
    assert!(!out.join("summary.json").exists());
    let folder = out.join("checkpoints").display().to_string();
    let on_threads = dir.path().join("restart-threads");
    let extra = ["--threads", "2", "--deterministic", "--restart", &folder];
    let (threads, _) = run(name, &overrides, &extra, &on_threads);
    assert_eq!(threads["state_hash"], expected["state_hash"]);
    assert_eq!(threads["patches"], expected["patches"]);
    let extra = ["--ranks", "3", "--deterministic", "--restart", &folder];
    let (ranks, _) = run(name, &overrides, &extra, &out);
    assert_eq!(ranks["state_hash"], expected["state_hash"]);
    assert_eq!(ranks["patches"], expected["patches"]);
}
