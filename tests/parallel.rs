//! Parallel runs of the solver: deterministic mode gives bitwise identical outputs for any
//! thread count; asynchronous mode is as accurate as a serial run.

mod common;

use std::path::Path;

use sdg_engine::{Config, LoadedConfig, Problem, RunOptions, solve_job};

fn plane_wave(overrides: &[&str]) -> Problem {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/plane_wave.toml"),
    )
    .unwrap();
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let config = Config::parse(&text, "plane_wave.toml", &overrides).unwrap();
    Problem::setup(LoadedConfig {
        config,
        file: "plane_wave.toml".into(),
    })
    .unwrap()
}

/// Runs `problem` on `threads` threads into a fresh folder; returns the summary and the folder.
fn solve(
    problem: &Problem,
    threads: usize,
    deterministic: bool,
) -> (sdg_engine::RunSummary, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let options = RunOptions {
        output_dir: Some(dir.path().to_path_buf()),
        threads: Some(threads),
        deterministic,
        progress: false,
    };
    let (summary, _) = solve_job(problem, &options).unwrap();
    (summary, dir)
}

/// Every output file, with the wall-clock fields (`wall_time_s`, `patches_per_second`,
/// `threads`) removed from `summary.json`.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let mut bytes = std::fs::read(&path).unwrap();
            if name == "summary.json" {
                let mut json: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                for key in ["wall_time_s", "patches_per_second", "threads"] {
                    json.as_object_mut().unwrap().remove(key);
                }
                bytes = serde_json::to_vec_pretty(&json).unwrap();
            }
            (name, bytes)
        })
        .collect();
    files.sort();
    files
}

#[test]
fn deterministic_mode_is_bitwise_identical_for_1_2_4_and_8_threads() {
    let problem = plane_wave(&[
        "mesh.nx=12",
        "mesh.ny=12",
        "time.end=6e-7",
        "output.snapshot_times=[0.0, 3e-7, 6e-7]",
    ]);
    let (reference, dir) = solve(&problem, 1, true);
    let expected = outputs(dir.path());
    assert_eq!(
        expected.len(),
        6,
        "summary, history, pvd and three snapshots"
    );
    for threads in [2, 4, 8] {
        let (summary, dir) = solve(&problem, threads, true);
        assert_eq!(
            summary.state_hash, reference.state_hash,
            "{threads} threads"
        );
        let got = outputs(dir.path());
        for ((name, a), (other, b)) in expected.iter().zip(&got) {
            assert_eq!(name, other);
            assert!(a == b, "{name} differs with {threads} threads");
        }
    }
}

#[test]
fn asynchronous_mode_is_as_accurate_as_a_serial_run() {
    let problem = plane_wave(&[
        "mesh.nx=24",
        "mesh.ny=24",
        "time.end=1e-6",
        "output.snapshot_times=[]",
    ]);
    let (serial, _d) = solve(&problem, 1, true);
    let (parallel, _e) = solve(&problem, 2, false);
    let (s, p) = (serial.error.unwrap(), parallel.error.unwrap());
    eprintln!("serial {s:?}, asynchronous {p:?}");
    for (a, b) in [
        (s.velocity_l2_rel, p.velocity_l2_rel),
        (s.stress_l2_rel, p.stress_l2_rel),
    ] {
        assert!((b - a).abs() <= 0.05 * a, "{b} vs serial {a}");
    }
    assert!(parallel.energy.balance_residual_rel.abs() < 1e-10);
}
