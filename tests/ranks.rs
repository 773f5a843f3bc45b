//! `sdg run --ranks N`: the front split over in-process ranks gives the state hash, patch count
//! and energies of the run on one thread, for every partition; a run over ranks stopped at a
//! checkpoint goes on from it on any number of ranks or on threads to the same state; what it
//! cannot do yet is bad input (exit 2) naming the key.

use crate::common;

use std::path::Path;

use common::run_shipped as run;
use common::{history_rows, pieces, run_args, sdg, slices, stderr, summary_json};

/// Runs the shipped config `name` with `overrides` (ASCII VTU, `snapshots` snapshots) on
/// `--threads 2` and over each of `cases` (ranks, partition, solving threads per rank), and
/// checks that every run over
/// ranks writes the same `history.csv`, byte for byte, whose rows balance the energy, start
/// with the threaded run's first row and end with its last front (time, patches, energy), and
/// that each snapshot's pieces hold the threaded run's slices and, where the threaded run has
/// `cracks_NNNN.vtu`, its crack pieces that file's segments, and, where the threaded run drew
/// `snapshot_NNNN.png`, the same picture drawn from the pieces. Returns how many crack files
/// it compared.
fn assert_same_outputs_over_ranks(
    name: &str,
    overrides: &[&str],
    snapshots: usize,
    cases: &[(usize, &str, usize)],
) -> usize {
    let dir = tempfile::tempdir().unwrap();
    let mut compared = 0;
    let threads_out = dir.path().join("threads");
    let threads = run(name, overrides, &["--threads", "2"], &threads_out);
    let threads_rows = history_rows(&threads_out);
    let mut first_history: Option<String> = None;
    for &(ranks, partition, per_rank) in cases {
        let out = dir.path().join(format!("{ranks}-{partition}-{per_rank}"));
        let (count, per_rank_arg) = (ranks.to_string(), per_rank.to_string());
        let summary = run(
            name,
            overrides,
            &[
                "--ranks",
                &count,
                "--partition",
                partition,
                "--threads",
                &per_rank_arg,
            ],
            &out,
        );
        assert_eq!(summary["state_hash"], threads["state_hash"]);
        assert_eq!(summary["threads"], ranks * per_rank);
        // Per rank: every tent pitched once; the boundary vertices and messages add up.
        let distributed = &summary["distributed"];
        let per_rank = distributed["per_rank"].as_array().unwrap();
        assert_eq!(per_rank.len(), ranks);
        let total = |key: &str| {
            per_rank
                .iter()
                .map(|r| r[key].as_u64().unwrap())
                .sum::<u64>()
        };
        assert_eq!(total("tents"), summary["patches"].as_u64().unwrap());
        assert!(per_rank.iter().all(|r| r["tents"].as_u64() > Some(0)));
        assert_eq!(
            total("boundary_vertices"),
            distributed["boundary_vertices"].as_u64().unwrap()
        );
        let per_tent = total("updates_sent") as f64 / total("tents") as f64;
        let reported = distributed["updates_per_tent"].as_f64().unwrap();
        assert!((per_tent - reported).abs() <= 1e-12 * reported.max(1.0));
        let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
        match &first_history {
            None => first_history = Some(history),
            Some(first) => assert_eq!(&history, first, "{ranks} ranks, {partition}"),
        }
        assert_eq!(
            probes(&out),
            probes(&threads_out),
            "interface.csv, {ranks} ranks, {partition}"
        );
        let rows = history_rows(&out);
        assert!(
            rows.len() >= 4,
            "rows between the first and the last: {rows:?}"
        );
        assert_eq!(rows[0], threads_rows[0], "the initial front's row");
        let (last, threads_last) = (rows.last().unwrap(), threads_rows.last().unwrap());
        assert_eq!(last[..5], threads_last[..5], "the end front's row");
        let held = rows[0][2] + threads["energy"]["boundary_work"].as_f64().unwrap().abs();
        for pair in rows.windows(2) {
            assert!(
                pair[0][0] < pair[1][0] && pair[0][1] < pair[1][1],
                "{pair:?}"
            );
        }
        for row in &rows {
            assert!(row[10].abs() <= 1e-12 * held, "balance residual: {row:?}");
        }
        assert_eq!(summary["snapshots"].as_array().unwrap().len(), snapshots);
        for index in 0..snapshots {
            let threaded = slices(&[threads_out.join(format!("snapshot_{index:04}.vtu"))]);
            assert!(!threaded.is_empty());
            assert_eq!(
                pieces(&out, "snapshot", index, ranks),
                threaded,
                "snapshot {index}, {ranks} ranks, {partition}"
            );
            let picture = format!("snapshot_{index:04}.png");
            if let Ok(threaded) = std::fs::read(threads_out.join(&picture)) {
                let drawn = std::fs::read(out.join(&picture)).expect("drawn from the pieces");
                assert!(drawn == threaded, "{picture}, {ranks} ranks, {partition}");
            }
            // The interface faces' cuts, where the threaded run has them.
            let cracks = threads_out.join(format!("cracks_{index:04}.vtu"));
            if cracks.exists() {
                assert_eq!(
                    pieces(&out, "cracks", index, ranks),
                    slices(&[cracks]),
                    "cracks {index}, {ranks} ranks, {partition}"
                );
                compared += 1;
            }
        }
    }
    compared
}

#[test]
fn history_and_snapshots_over_ranks_are_the_threaded_runs_for_every_partition() {
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=1e-6",
        "output.snapshot_times=[0.0, 3e-7, 5e-7, 1e-6]",
        "output.png=false",
        "output.vtu=\"ascii\"",
    ];
    let cases = [
        (1, "coordinate", 1),
        (1, "coordinate", 3),
        (2, "random", 2),
        (3, "coordinate", 1),
        (3, "metis", 1),
        (4, "stripes", 2),
    ];
    let cracks = assert_same_outputs_over_ranks("plane_wave.toml", &overrides, 4, &cases);
    assert_eq!(cracks, 0, "no interface, no crack pieces");
}

#[test]
fn history_and_snapshots_of_a_frictional_interface_over_ranks_are_the_threaded_runs() {
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=4e-6",
        "output.snapshot_times=[2e-6, 4e-6]",
        "output.png=true",
        "output.vtu=\"ascii\"",
    ];
    let cases = [(2, "coordinate", 1), (3, "random", 2), (4, "metis", 1)];
    let cracks = assert_same_outputs_over_ranks("stick_slip.toml", &overrides, 2, &cases);
    assert_eq!(
        cracks,
        2 * cases.len(),
        "the interface's cuts at both snapshots"
    );
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
        "output.vtu=\"ascii\"",
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
        // The end-time snapshot has every triangle once, in the pieces of the ranks.
        assert_eq!(summary["snapshots"][0][1], "snapshot_0000.pvtu");
        let threads_slices = slices(&[dir.path().join("threads/snapshot_0000.vtu")]);
        assert_eq!(threads_slices.len() as u64, summary["triangles"]);
        assert_eq!(
            pieces(&out, "snapshot", 0, ranks.parse().unwrap()),
            threads_slices
        );
    }
}

/// Deterministic rounds take every vertex first in `(time, id)` among its neighbours, as the
/// ranks do: without events a deterministic run over ranks is the threaded deterministic run.
#[test]
fn a_deterministic_run_over_ranks_is_the_threaded_deterministic_run() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=1e-6",
        "output.snapshot_times=[]",
        "output.png=false",
    ];
    let threads = run(
        "plane_wave.toml",
        &overrides,
        &["--threads", "2", "--deterministic"],
        &dir.path().join("threads"),
    );
    let ranks = run(
        "plane_wave.toml",
        &overrides,
        &["--ranks", "3", "--deterministic"],
        &dir.path().join("ranks"),
    );
    assert_eq!(threads["mode"], "deterministic");
    assert_eq!(ranks["mode"], "deterministic");
    assert_eq!(ranks["state_hash"], threads["state_hash"]);
    assert_eq!(ranks["patches"], threads["patches"]);
    assert_eq!(ranks["energy"]["final"], threads["energy"]["final"]);
}

#[test]
fn frictional_interface_over_ranks_is_the_run_on_one_thread() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=4e-6",
        "output.snapshot_times=[]",
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
    let cases: [(Vec<String>, &str); 3] = [
        (
            vec![repo("adaptive_pulse.toml")],
            "adapt.enabled: mesh-changing events",
        ),
        (
            vec![
                repo("crack_growth.toml"),
                "--set".into(),
                "scheduler.deterministic=false".into(),
            ],
            "[fracture]: mesh-changing events run over ranks in deterministic mode only",
        ),
        (
            vec![
                repo("plane_wave.toml"),
                "--trace".into(),
                format!("{out}/t.csv"),
            ],
            "--trace",
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
    // --partition needs --ranks; --ranks and --mpi exclude each other.
    for args in [
        &["run", "configs/plane_wave.toml", "--partition", "random"][..],
        &["run", "configs/plane_wave.toml", "--ranks", "2", "--mpi"],
    ] {
        assert_eq!(sdg(args).status.code(), Some(2), "{args:?}");
    }
}

/// The state hash, patch count, and snapshot slices and crack segments (ASCII) of the run in
/// `out`.
fn state(out: &Path, snapshots: usize) -> State {
    let summary = summary_json(out);
    let files = summary["snapshots"].as_array().unwrap().clone();
    assert_eq!(files.len(), snapshots, "{files:?}");
    // The cells of `STEM_NNNN.vtu` of a threaded run, or of its pieces over ranks.
    let cells = |stem: &str, index: usize, pieces: bool| {
        let whole = out.join(format!("{stem}_{index:04}.vtu"));
        let paths: Vec<_> = if pieces {
            (std::fs::read_dir(out).unwrap())
                .map(|e| e.unwrap().path())
                .filter(|p| {
                    let n = p.file_name().unwrap().to_str().unwrap();
                    n.starts_with(&format!("{stem}_{index:04}_")) && n.ends_with(".vtu")
                })
                .collect()
        } else {
            [whole].into_iter().filter(|p| p.exists()).collect()
        };
        slices(&paths)
    };
    let slices = (files.iter().enumerate())
        .flat_map(|(index, file)| {
            let pieces = file[1].as_str().unwrap().ends_with(".pvtu");
            [
                cells("snapshot", index, pieces),
                cells("cracks", index, pieces),
            ]
        })
        .collect();
    (
        summary["state_hash"].clone(),
        summary["patches"].clone(),
        slices,
        probes(out),
    )
}

/// The text of `interface.csv` in `out`, if the run wrote one.
fn probes(out: &Path) -> Option<String> {
    std::fs::read_to_string(out.join("interface.csv")).ok()
}

/// What a run ends with: its state hash, patches, snapshot slices and crack segments (by
/// snapshot) and `interface.csv`.
type State = (
    serde_json::Value,
    serde_json::Value,
    Vec<Vec<String>>,
    Option<String>,
);

/// Runs `name` with `overrides` (a checkpoint every `every` s) over 3 ranks, then from its
/// first checkpoint on 2 and 4 ranks and on threads, and on 2 ranks from the first checkpoint
/// of the run on threads: each ends with the state hash, patches and snapshot slices of the
/// run never stopped.
fn assert_restarts_are_the_run_never_stopped(name: &str, overrides: &[&str], snapshots: usize) {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference");
    run(name, overrides, &["--threads", "2"], &reference);
    let expected = state(&reference, snapshots);
    let checkpointed = dir.path().join("checkpointed");
    run(
        name,
        overrides,
        &["--ranks", "3", "--partition", "random"],
        &checkpointed,
    );
    assert_eq!(state(&checkpointed, snapshots), expected);
    let threads = dir.path().join("threads-checkpointed");
    run(name, overrides, &["--threads", "2"], &threads);
    let first = |out: &Path| {
        let file = out.join("checkpoints/checkpoint_000000.sdgc");
        assert!(file.is_file(), "{}", file.display());
        file.display().to_string()
    };
    let cases = [
        (first(&checkpointed), &["--ranks", "2"][..]),
        (
            first(&checkpointed),
            &["--ranks", "4", "--partition", "stripes"],
        ),
        (first(&checkpointed), &["--threads", "2"]),
        (first(&threads), &["--ranks", "2", "--partition", "random"]),
    ];
    for (i, (checkpoint, extra)) in cases.iter().enumerate() {
        let out = dir.path().join(format!("restart-{i}"));
        let mut args = vec!["--restart", checkpoint.as_str()];
        args.extend_from_slice(extra);
        let summary = run(name, overrides, &args, &out);
        assert_eq!(
            summary["checkpoint"]["restarted_from"].as_str(),
            Some(checkpoint.as_str())
        );
        assert_eq!(state(&out, snapshots), expected, "{args:?}");
    }
}

#[test]
fn a_plane_wave_checkpointed_over_ranks_restarts_on_any_rank_count_and_on_threads() {
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=1e-6",
        "checkpoint.every_sim_s=3e-7",
        "output.snapshot_times=[3e-7, 5e-7, 1e-6]",
        "output.png=false",
        "output.vtu=\"ascii\"",
    ];
    assert_restarts_are_the_run_never_stopped("plane_wave.toml", &overrides, 3);
}

#[test]
fn a_frictional_interface_checkpointed_over_ranks_restarts_on_any_rank_count_and_on_threads() {
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=4e-6",
        "checkpoint.every_sim_s=1.5e-6",
        "output.snapshot_times=[2e-6, 4e-6]",
        "output.png=false",
        "output.vtu=\"ascii\"",
    ];
    assert_restarts_are_the_run_never_stopped("stick_slip.toml", &overrides, 2);
}

#[test]
fn a_run_over_ranks_stopped_by_the_wall_time_limit_goes_on_to_the_same_state() {
    let overrides = [
        "mesh.nx=16",
        "mesh.ny=16",
        "time.end=3e-6",
        "output.snapshot_times=[1e-6, 2e-6, 3e-6]",
        "output.png=false",
        "output.vtu=\"ascii\"",
    ];
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference");
    run(
        "plane_wave.toml",
        &overrides,
        &["--threads", "2"],
        &reference,
    );
    let expected = state(&reference, 3);
    let out = dir.path().join("stopped");
    let args = run_args(
        "plane_wave.toml",
        &overrides,
        &["--ranks", "2", "--max-wall-time", "0.3"],
        &out,
    );
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = sdg(&args);
    // Stopped mid-run on any machine this test runs on (the run takes seconds).
    assert_eq!(result.status.code(), Some(3), "{}", stderr(&result));
    assert!(
        stderr(&result).contains("--max-wall-time"),
        "{}",
        stderr(&result)
    );
    assert!(!out.join("summary.json").exists());
    let folder = out.join("checkpoints").display().to_string();
    run(
        "plane_wave.toml",
        &overrides,
        &["--ranks", "3", "--restart", &folder],
        &out,
    );
    assert_eq!(state(&out, 3), expected);
}

/// A damage interface that debonds under a plane wave: over ranks, and restarted over ranks or
/// on threads from a checkpoint taken while it debonds, `crack_tips.csv` and the summary's
/// `crack` block are the threaded run's.
#[test]
fn crack_tips_of_a_debonding_interface_over_ranks_are_the_threaded_runs() {
    let checkpoint_time = 2.4355e-6;
    let every = format!("checkpoint.every_sim_s={checkpoint_time:e}");
    let overrides = [
        "mesh.ny=32",
        "solver.order=2",
        &every,
        "output.snapshot_times=[]",
        "output.png=false",
    ];
    let name = "damage_interface.toml";
    let dir = tempfile::tempdir().unwrap();
    let tips = |out: &Path| std::fs::read_to_string(out.join("crack_tips.csv")).unwrap();
    let threads_out = dir.path().join("threads");
    let threads = run(name, &overrides, &["--threads", "2"], &threads_out);
    let expected = tips(&threads_out);
    assert!(probes(&threads_out).is_some(), "the config's probe");
    // The checkpoint falls while the interface debonds: tip states on both sides of it.
    let times: Vec<f64> = (expected.lines().skip(1))
        .map(|line| line.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert!(
        times.iter().any(|&t| t < checkpoint_time) && times.iter().any(|&t| t > checkpoint_time),
        "{times:?}"
    );
    let same = |out: &Path, what: &str| {
        let summary = summary_json(out);
        assert_eq!(tips(out), expected, "{what}");
        assert_eq!(probes(out), probes(&threads_out), "{what}");
        assert_eq!(summary["crack"], threads["crack"], "{what}");
        assert_eq!(summary["state_hash"], threads["state_hash"], "{what}");
    };
    let ranks = dir.path().join("ranks");
    run(
        name,
        &overrides,
        &["--ranks", "2", "--threads", "2"],
        &ranks,
    );
    same(&ranks, "2 ranks");
    let checkpoint = |out: &Path| {
        let file = out.join("checkpoints/checkpoint_000000.sdgc");
        file.display().to_string()
    };
    let cases = [
        (
            checkpoint(&ranks),
            &["--ranks", "3", "--partition", "random"][..],
        ),
        (checkpoint(&ranks), &["--threads", "2"]),
        (
            checkpoint(&threads_out),
            &["--ranks", "2", "--partition", "metis"],
        ),
    ];
    for (i, (file, extra)) in cases.iter().enumerate() {
        let out = dir.path().join(format!("restart-{i}"));
        let mut args = vec!["--restart", file.as_str()];
        args.extend_from_slice(extra);
        run(name, &overrides, &args, &out);
        same(&out, &format!("{args:?}"));
    }
}
