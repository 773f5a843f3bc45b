//! `sdg run --ranks N`: the front split over in-process ranks gives the state hash, patch count
//! and energies of the run on one thread, for every partition; what it cannot do yet is bad
//! input (exit 2) naming the key.

mod common;

use std::path::Path;

use common::{run_args, sdg, stderr, summary_json};

/// Runs the shipped config `name` with `overrides` and `extra` arguments into `out`; returns
/// its `summary.json`.
fn run(name: &str, overrides: &[&str], extra: &[&str], out: &Path) -> serde_json::Value {
    let args = run_args(name, overrides, extra, out);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = sdg(&args);
    assert!(result.status.success(), "{args:?}: {}", stderr(&result));
    summary_json(out)
}

/// Cells of a VTU file written in any of its encodings.
fn cells(vtu: &Path) -> u64 {
    let text = std::fs::read_to_string(vtu).unwrap();
    let at = text.find("NumberOfCells=\"").expect("a piece") + "NumberOfCells=\"".len();
    text[at..].split('"').next().unwrap().parse().unwrap()
}

/// Asserts that `ranks` is the run `threads` over ranks: the same state hash, patches, final
/// energy, and energy totals to round-off of the energy the body holds (summed in another
/// order).
fn assert_same_run(threads: &serde_json::Value, ranks: &serde_json::Value, count: u64) {
    assert_eq!(ranks["state_hash"], threads["state_hash"]);
    assert_eq!(ranks["patches"], threads["patches"]);
    assert_eq!(ranks["elements"], threads["elements"]);
    assert_eq!(ranks["ranks"], count);
    assert_eq!(threads["ranks"], 1);
    assert_eq!(ranks["mode"], "asynchronous");
    assert_eq!(ranks["energy"]["final"], threads["energy"]["final"]);
    assert_eq!(ranks["energy"]["initial"], threads["energy"]["initial"]);
    assert_eq!(ranks["max_slope_ratio"], threads["max_slope_ratio"]);
    let held = threads["energy"]["initial"].as_f64().unwrap()
        + threads["energy"]["boundary_work"].as_f64().unwrap().abs();
    for key in [
        "boundary_work",
        "dissipation",
        "interface_work",
        "friction_dissipation",
    ] {
        let (a, b) = (
            threads["energy"][key].as_f64().unwrap(),
            ranks["energy"][key].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() <= 1e-12 * held,
            "energy.{key}: {a} on threads, {b} over ranks"
        );
    }
    let balance = ranks["energy"]["balance_residual_rel"].as_f64().unwrap();
    assert!(balance.abs() < 1e-12, "balance residual {balance}");
}

#[test]
fn plane_wave_over_ranks_is_the_run_on_one_thread() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=1e-6",
        "output.snapshot_times=[1e-6]",
        "output.png=false",
    ];
    let threads = run(
        "plane_wave.toml",
        &overrides,
        &["--threads", "1"],
        &dir.path().join("threads"),
    );
    assert!(threads["patches"].as_u64().unwrap() > 200);
    for (ranks, partition) in [("3", "coordinate"), ("2", "random"), ("4", "stripes")] {
        let out = dir.path().join(format!("{ranks}-{partition}"));
        let summary = run(
            "plane_wave.toml",
            &overrides,
            &["--ranks", ranks, "--partition", partition],
            &out,
        );
        assert_same_run(&threads, &summary, ranks.parse().unwrap());
        assert_eq!(summary["error"], threads["error"], "errors against [exact]");
        let distributed = &summary["distributed"];
        assert_eq!(distributed["partition"], partition);
        assert!(distributed["updates_per_tent"].as_f64().unwrap() > 0.0);
        // The end-time snapshot has every triangle once.
        assert_eq!(summary["snapshots"][0][1], "snapshot_0000.vtu");
        let snapshot = |d: &Path| cells(&d.join("snapshot_0000.vtu"));
        assert_eq!(snapshot(&out), snapshot(&dir.path().join("threads")));
        assert_eq!(snapshot(&out), summary["triangles"].as_u64().unwrap());
        let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
        let last = history.lines().last().unwrap();
        assert!(
            last.starts_with(&format!("1e-6,{},", summary["patches"])),
            "{last}"
        );
    }
}

#[test]
fn frictional_interface_over_ranks_is_the_run_on_one_thread() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=4e-6",
        "output.snapshot_times=[]",
        "output.interface_probes=[]",
        "output.png=false",
    ];
    let threads = run(
        "stick_slip.toml",
        &overrides,
        &["--threads", "1"],
        &dir.path().join("threads"),
    );
    let ranks = run(
        "stick_slip.toml",
        &overrides,
        &["--ranks", "3", "--partition", "random"],
        &dir.path().join("ranks"),
    );
    assert_same_run(&threads, &ranks, 3);
    let nonlinear = &ranks["interface"]["nonlinear_patches"];
    assert_eq!(nonlinear, &threads["interface"]["nonlinear_patches"]);
    assert!(nonlinear.as_u64().unwrap() > 0, "some patches slipped");
    assert!(ranks["energy"]["friction_dissipation"].as_f64().unwrap() > 0.0);
}

#[test]
fn what_ranks_cannot_do_yet_is_bad_input_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let repo = |name: &str| format!("{}/configs/{name}", env!("CARGO_MANIFEST_DIR"));
    let cases: [(Vec<String>, &str); 6] = [
        (
            vec![repo("adaptive_pulse.toml")],
            "adapt.enabled: mesh-changing events",
        ),
        (vec![repo("crack_growth.toml")], "[fracture]"),
        (vec![repo("stick_slip.toml")], "output.interface_probes"),
        (
            vec![repo("plane_wave.toml"), "--deterministic".into()],
            "--deterministic",
        ),
        (
            vec![
                repo("plane_wave.toml"),
                "--trace".into(),
                format!("{out}/t.csv"),
            ],
            "--trace",
        ),
        (
            vec![
                repo("plane_wave.toml"),
                "--set".into(),
                "checkpoint.at_end=true".into(),
            ],
            "checkpoint.at_end",
        ),
    ];
    for (args, needle) in cases {
        let mut all = vec!["run".to_string()];
        all.extend(args);
        all.extend(["--ranks", "2", "--output", out].map(String::from));
        let all: Vec<&str> = all.iter().map(String::as_str).collect();
        let result = sdg(&all);
        let err = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "{all:?}: {err}");
        assert!(err.contains(needle), "{all:?}: `{needle}` not in {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // --partition needs --ranks; --ranks takes no --threads.
    for args in [
        &["run", "configs/plane_wave.toml", "--partition", "random"][..],
        &[
            "run",
            "configs/plane_wave.toml",
            "--ranks",
            "2",
            "--threads",
            "2",
        ],
    ] {
        assert_eq!(sdg(args).status.code(), Some(2), "{args:?}");
    }
}
