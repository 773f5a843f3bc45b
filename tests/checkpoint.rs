//! Checkpoints and restarts through the `sdg` binary, as a batch job uses them: a run killed
//! (SIGKILL) after a checkpoint and restarted on another thread count ends bitwise as an
//! uninterrupted deterministic run; SIGTERM checkpoints and exits 3; SIGUSR1 checkpoints and
//! goes on; damaged checkpoints and checkpoints of another configuration are refused (exit 2).

use crate::common;

use common::checkpoints;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{assert_same_outputs, outputs, stderr};

/// The most a run may take from SIGTERM to its exit with a checkpoint (documented in the
/// user guide's "Long runs on a cluster", `docs/guide.md`), s.
const STOP_WITHIN: Duration = Duration::from_secs(10);

/// `sdg run` on the shipped `config` with `args` and `overrides`, started.
fn spawn(config: &str, out: &Path, args: &[&str], overrides: &[&str]) -> Child {
    spawn_in(Path::new("."), config, out, args, overrides)
}

/// [`spawn`] in the working directory `cwd`.
fn spawn_in(cwd: &Path, config: &str, out: &Path, args: &[&str], overrides: &[&str]) -> Child {
    let mut command = Command::new(env!("CARGO_BIN_EXE_sdg"));
    command
        .current_dir(cwd)
        .arg("run")
        .arg(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("configs")
                .join(config),
        )
        .arg("--output")
        .arg(out)
        .args(["--deterministic", "--quiet"])
        .args(args);
    for o in overrides {
        command.args(["--set", o]);
    }
    command
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the sdg binary runs")
}

/// Runs to the end: exit code and standard error.
fn finish(child: Child) -> (i32, String) {
    let out = child.wait_with_output().unwrap();
    (out.status.code().unwrap_or(-1), stderr(&out))
}

/// Waits until `dir` holds a checkpoint or `child` has ended.
fn wait_for_checkpoint(child: &mut Child, dir: &Path) {
    let start = Instant::now();
    while checkpoints(dir).is_empty() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended first");
        assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([format!("-{name}"), child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// Asserts that `got` holds the same output files as `expected`, byte for byte (`summary.json`
/// without its measured fields).
fn assert_same_folders(expected: &Path, got: &Path, context: &str) {
    let context = format!("{context}, after the restart");
    assert_same_outputs(&outputs(expected), &outputs(got), &context);
}

/// Kills a run with `before` threads after its first checkpoint, restarts it from the folder on
/// `after` threads, and compares every output with an uninterrupted run's; returns the
/// restarted run's summary.
fn killed_and_restarted(
    config: &str,
    overrides: &[&str],
    before: &str,
    after: &str,
) -> serde_json::Value {
    let reference = tempfile::tempdir().unwrap();
    let (code, err) = finish(spawn(
        config,
        reference.path(),
        &["--threads", after],
        overrides,
    ));
    assert_eq!(code, 0, "{err}");
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("checkpoints");
    let mut child = spawn(config, dir.path(), &["--threads", before], overrides);
    wait_for_checkpoint(&mut child, &folder);
    child.kill().unwrap();
    child.wait().unwrap();
    let folder_arg = folder.to_str().unwrap();
    let restart = ["--threads", after, "--restart", folder_arg];
    let (code, err) = finish(spawn(config, dir.path(), &restart, overrides));
    assert_eq!(code, 0, "{err}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("summary.json")).unwrap()).unwrap();
    let from = summary["checkpoint"]["restarted_from"].as_str().unwrap();
    let time = summary["checkpoint"]["restart_time"].as_f64().unwrap();
    eprintln!("{config}: restarted from {from} at t = {time:e} s");
    let start = common::shipped(config, overrides).loaded.config.time.start;
    assert!(
        time > start,
        "the restart went on from the checkpoint's front"
    );
    assert_same_folders(reference.path(), dir.path(), config);
    summary
}

#[test]
fn a_killed_crack_run_restarts_bitwise_on_two_threads() {
    // Damage interfaces, crack tips extending by edge splits, snapshots with interface cuts, a
    // run that starts before 0 (its snapshots keep their labels through the checkpoint); on the
    // plate's quarter, the notch grows from 0.08 us.
    let mut overrides = common::SMALL_CRACK.to_vec();
    overrides.extend([
        "time.start=-3e-7",
        "time.end=5e-7",
        "checkpoint.every_sim_s=2e-7",
        "output.snapshot_times=[1e-7, 5e-7]",
    ]);
    let summary = killed_and_restarted("crack_growth.toml", &overrides, "1", "2");
    let labels: Vec<f64> = (summary["snapshots"].as_array().unwrap().iter())
        .map(|s| s[0].as_f64().unwrap())
        .collect();
    assert_eq!(labels, [1e-7, 5e-7]);
    assert_eq!(summary["final_time"].as_f64(), Some(5e-7));
}

#[test]
fn a_killed_adaptive_contact_run_restarts_bitwise_on_one_thread() {
    // Refinement, coarsening, contact faces solved by Newton, interface probes.
    let overrides = [
        &common::STICK_SLIP_ADAPTIVE[..],
        &["checkpoint.every_sim_s=3e-7"],
    ]
    .concat();
    killed_and_restarted("stick_slip.toml", &overrides, "2", "1");
}

#[test]
fn sigusr1_checkpoints_and_goes_on_and_sigterm_stops_with_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("checkpoints");
    let long = ["time.end=1e-3", "mesh.nx=32", "mesh.ny=32"];
    let mut child = spawn("plane_wave.toml", dir.path(), &["--threads", "2"], &long);
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, "USR1");
    wait_for_checkpoint(&mut child, &folder);
    assert!(child.try_wait().unwrap().is_none(), "SIGUSR1 ends no run");
    let sent = Instant::now();
    // Twice within a second, as a batch system signalling the job's shell and sdg does: one
    // request, a checkpoint and exit 3 (not 130).
    signal(&child, "TERM");
    std::thread::sleep(Duration::from_millis(50));
    signal(&child, "TERM");
    let (code, err) = finish(child);
    let took = sent.elapsed();
    eprintln!("SIGTERM to exit: {took:?}; {err}");
    assert_eq!(code, 3, "{err}");
    assert!(took < STOP_WITHIN, "{took:?}");
    assert!(
        err.contains("SIGTERM") && err.contains("--restart"),
        "{err}"
    );
    assert_eq!(checkpoints(&folder).len(), 2, "USR1's and TERM's");
    assert!(dir.path().join("history.csv").is_file(), "outputs so far");
    let newest = checkpoints(&folder).pop().unwrap();
    let bytes = std::fs::read(&newest).unwrap();
    // The newest checkpoint is whole: the run goes on from it, and stops again at the limit.
    let restart = [
        "--threads",
        "1",
        "--restart",
        folder.to_str().unwrap(),
        "--max-wall-time",
        "1",
    ];
    let (code, err) = finish(spawn("plane_wave.toml", dir.path(), &restart, &long));
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("--max-wall-time = 1 s is up"), "{err}");
    // The restart numbered its checkpoint after the folder's files: the one it started from
    // is kept whole, and the newest is the last written.
    let names: Vec<String> = (checkpoints(&folder).iter())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["checkpoint_000001.sdgc", "checkpoint_000002.sdgc"]);
    assert_eq!(
        std::fs::read(&newest).unwrap(),
        bytes,
        "the restart's start changed"
    );
}

/// Runs plane_wave into `dir` until `--max-wall-time` stops it with a checkpoint (exit 3);
/// returns the checkpoint folder.
fn stopped_plane_wave(dir: &Path) -> PathBuf {
    let limit = ["--threads", "1", "--max-wall-time", "0.3"];
    let (code, err) = finish(spawn("plane_wave.toml", dir, &limit, &[]));
    assert_eq!(code, 3, "{err}");
    dir.join("checkpoints")
}

#[test]
fn damaged_and_foreign_checkpoints_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let folder = stopped_plane_wave(dir.path());
    let good = checkpoints(&folder).pop().expect("a checkpoint");
    let bytes = std::fs::read(&good).unwrap();
    let restart = |file: &Path, overrides: &[&str]| {
        let args = ["--threads", "1", "--restart", file.to_str().unwrap()];
        let (code, err) = finish(spawn("plane_wave.toml", dir.path(), &args, overrides));
        assert_eq!(code, 2, "{}: {err}", file.display());
        assert!(err.starts_with("error: "), "{err}");
        err
    };
    let damaged = dir.path().join("damaged.sdgc");
    let mut flipped = bytes.clone();
    flipped[bytes.len() / 2] ^= 0x10;
    std::fs::write(&damaged, &flipped).unwrap();
    assert!(restart(&damaged, &[]).contains("checksum mismatch"));
    std::fs::write(&damaged, &bytes[..bytes.len() - 100]).unwrap();
    assert!(restart(&damaged, &[]).contains("truncated"));
    assert!(restart(&good, &["material.density=1000"]).contains("material.density differs"));
    // In a folder, a damaged newest file is skipped for an older whole one.
    let newer = folder.join("checkpoint_999999.sdgc");
    std::fs::write(&newer, &flipped).unwrap();
    let args = ["--threads", "1", "--restart", folder.to_str().unwrap()];
    let (code, err) = finish(spawn("plane_wave.toml", dir.path(), &args, &[]));
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("skipped") && err.contains("checksum"), "{err}");
}

/// A new run into a folder that holds an earlier run's checkpoints is refused (exit 2) before
/// it writes anything: it would number its own from 0 and the rotation would keep the earlier
/// run's. `--restart` on the folder goes on from them.
#[test]
fn a_new_run_beside_an_earlier_run_s_checkpoints_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let folder = stopped_plane_wave(dir.path());
    let before = checkpoints(&folder);
    assert!(!before.is_empty());
    let (code, err) = finish(spawn(
        "plane_wave.toml",
        dir.path(),
        &["--threads", "1"],
        &[],
    ));
    assert_eq!(code, 2, "{err}");
    assert!(err.starts_with("error: "), "{err}");
    for needle in ["checkpoints", "earlier run", "--restart", "checkpoint.dir"] {
        assert!(err.contains(needle), "`{needle}` not in: {err}");
    }
    assert_eq!(
        checkpoints(&folder),
        before,
        "the refused run changed the checkpoints"
    );
    let restart = ["--threads", "1", "--restart", folder.to_str().unwrap()];
    let (code, err) = finish(spawn("plane_wave.toml", dir.path(), &restart, &[]));
    assert_eq!(code, 0, "{err}");
}

/// Copies the files of `from` into `to` (one level of folders, as a run's output has).
fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_folder(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

/// A restart that writes to another folder than the run it goes on from copies the snapshots
/// written before into it: the folder's collection is whole, and every output is the
/// uninterrupted run's.
#[test]
fn a_restart_into_another_folder_takes_the_earlier_snapshots_along() {
    let dir = tempfile::tempdir().unwrap();
    let [here, there] = ["here", "there"].map(|name| dir.path().join(name));
    let (first, second) = (here.join("first"), there.join("second"));
    std::fs::create_dir_all(&here).unwrap();
    let every = ["checkpoint.every_sim_s=1e-6"];
    // Both runs name their folders relative to their own working directories.
    let (code, err) = finish(spawn_in(
        &here,
        "plane_wave.toml",
        Path::new("first"),
        &["--threads", "1"],
        &every,
    ));
    assert_eq!(code, 0, "{err}");
    let file = checkpoints(&first.join("checkpoints")).remove(0);
    // Another run's file of the same name in the new folder gives way to the first run's.
    std::fs::create_dir_all(&second).unwrap();
    std::fs::write(second.join("snapshot_0000.vtu"), "another run's").unwrap();
    let restart = ["--threads", "2", "--restart", file.to_str().unwrap()];
    let (code, err) = finish(spawn_in(
        &there,
        "plane_wave.toml",
        Path::new("second"),
        &restart,
        &every,
    ));
    assert_eq!(code, 0, "{err}");
    let restarted = summary(&second);
    assert!(restarted["checkpoint"]["restart_time"].as_f64().unwrap() > 0.0);
    assert!(second.join("snapshot_0000.vtu").is_file());
    assert_same_folders(&first, &second, "plane_wave into another folder");
}

/// A run with `checkpoint.at_end` goes on to a later `time.end` from its last checkpoint, with
/// more snapshots: as accurate as a run straight to that end, bitwise the same on 1 and 2
/// threads. Moving the end before the front, or a snapshot the front has passed, is refused.
#[test]
fn a_finished_run_goes_on_to_a_later_end() {
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("first");
    let short = [
        "time.end=1e-6",
        "output.snapshot_times=[0.0, 1e-6]",
        "checkpoint.at_end=true",
    ];
    let (code, err) = finish(spawn(
        "plane_wave.toml",
        &first,
        &["--threads", "1"],
        &short,
    ));
    assert_eq!(code, 0, "{err}");
    assert_eq!(checkpoints(&first.join("checkpoints")).len(), 1);
    let copies = ["two_threads", "refused"].map(|name| dir.path().join(name));
    for copy in &copies {
        copy_folder(&first, copy);
    }
    let long = ["output.snapshot_times=[0.0, 1e-6, 2e-6]"];
    let go_on = |out: &Path, threads: &str, overrides: &[&str]| {
        let folder = out.join("checkpoints");
        let args = ["--threads", threads, "--restart", folder.to_str().unwrap()];
        finish(spawn("plane_wave.toml", out, &args, overrides))
    };
    let (code, err) = go_on(&first, "1", &long);
    assert_eq!(code, 0, "{err}");
    let (code, err) = go_on(&copies[0], "2", &long);
    assert_eq!(code, 0, "{err}");
    let (one, two) = (summary(&first), summary(&copies[0]));
    assert_eq!(one["final_time"].as_f64(), Some(2e-6));
    assert_eq!(one["state_hash"], two["state_hash"]);
    for name in [
        "snapshot_0000.vtu",
        "snapshot_0001.vtu",
        "snapshot_0002.vtu",
    ] {
        assert!(first.join(name).exists(), "{name}");
    }
    let pvd = std::fs::read_to_string(first.join("snapshots.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    let history = std::fs::read_to_string(first.join("history.csv")).unwrap();
    let last: f64 = (history.lines().last().unwrap().split(',').next().unwrap())
        .parse()
        .unwrap();
    assert_eq!(last, 2e-6);
    assert!(one["energy"]["balance_residual_rel"].as_f64().unwrap() < 1e-10);
    // As accurate as the run straight to 2e-6 (whose tents near 1e-6 were not cut at it).
    let straight = dir.path().join("straight");
    let (code, err) = finish(spawn(
        "plane_wave.toml",
        &straight,
        &["--threads", "2"],
        &[],
    ));
    assert_eq!(code, 0, "{err}");
    let error = |s: &serde_json::Value| s["error"]["velocity_l2_rel"].as_f64().unwrap();
    let (extended, direct) = (error(&one), error(&summary(&straight)));
    assert!(
        extended < 1.2 * direct && direct < 1.2 * extended,
        "velocity errors: extended {extended:e}, straight {direct:e}"
    );
    // The front is at 1e-6: an end before it, or a new snapshot at or before it, is refused.
    for (overrides, needle) in [
        (
            &["time.end=5e-7", "output.snapshot_times=[0.0]"][..],
            "time.end",
        ),
        (
            &["output.snapshot_times=[0.0, 5e-7, 1e-6, 2e-6]"][..],
            "output.snapshot_times",
        ),
    ] {
        let (code, err) = go_on(&copies[1], "1", overrides);
        assert_eq!(code, 2, "{overrides:?}: {err}");
        assert!(err.contains(needle) && err.contains("checkpoint"), "{err}");
    }
}

/// Runs plane_wave with `value` written into the element under triangle 0 at half the end
/// time, as a bug or an unstable law would leave it; returns the error, the options and the
/// output folder.
fn poisoned(value: f64) -> (String, sdg_engine::RunOptions, tempfile::TempDir) {
    poisoned_run("plane_wave.toml", &["mesh.nx=8", "mesh.ny=8"], value, 0.5)
}

/// Runs the shipped `config` with `overrides` and `value` written at `fraction` of the end time
/// into the element under a triangle of the earliest vertex's star, which the next tent reads;
/// returns the error, the options and the output folder.
fn poisoned_run(
    config: &str,
    overrides: &[&str],
    value: f64,
    fraction: f64,
) -> (String, sdg_engine::RunOptions, tempfile::TempDir) {
    let problem = common::shipped(config, overrides);
    let t_end = problem.loaded.config.time.end;
    let dir = tempfile::tempdir().unwrap();
    let options = sdg_engine::RunOptions {
        output_dir: Some(dir.path().to_path_buf()),
        threads: Some(2),
        deterministic: true,
        ..Default::default()
    };
    let poison = move |live: &mut sdg_engine::Live<'_>| {
        let (mesh, front) = (live.mesh(), live.front());
        let earliest = (0..mesh.vertices().len() as u32)
            .min_by(|&a, &b| front.time(a).total_cmp(&front.time(b)))
            .unwrap();
        let t = mesh.vertex_triangles(earliest)[0] as usize;
        let solution = live.solution();
        let mut geometry = sdg_solver::element::Geometry::default();
        let mut coefficients = vec![0.0; live.basis().len() * solution.width()];
        assert!(solution.load(t, &mut geometry, &mut coefficients));
        coefficients[0] = value;
        solution.store(t, &geometry, &coefficients, None);
    };
    let err = sdg_engine::solve_job_with(&problem, &options, fraction * t_end, poison)
        .unwrap_err()
        .to_string();
    eprintln!("{err}");
    (err, options, dir)
}

#[test]
fn a_non_finite_patch_stops_the_run_with_a_checkpoint_before_it() {
    let (err, options, dir) = poisoned(f64::NAN);
    assert!(err.contains("a non-finite value") && err.contains("the patch of vertex"));
    let folder = dir.path().join("checkpoints");
    let [checkpoint] = &checkpoints(&folder)[..] else {
        panic!("one checkpoint in {}", folder.display())
    };
    assert!(err.contains(&checkpoint.display().to_string()), "{err}");
    assert!(dir.path().join("history.csv").is_file());
    // The checkpoint holds the front before the bad patch: a restart meets it again.
    let problem = common::shipped("plane_wave.toml", &["mesh.nx=8", "mesh.ny=8"]);
    let again = sdg_engine::solve_job(
        &problem,
        &sdg_engine::RunOptions {
            restart: Some(folder.clone()),
            threads: Some(1),
            ..options
        },
    )
    .unwrap_err()
    .to_string();
    let patch = |e: &str| e.split(';').next().unwrap().to_string();
    assert_eq!(patch(&again), patch(&err));
}

#[test]
fn an_energy_blow_up_stops_the_run() {
    let (err, _, dir) = poisoned(1e6);
    assert!(err.contains("energy blow-up"), "{err}");
    assert_eq!(checkpoints(&dir.path().join("checkpoints")).len(), 1);
}

/// A run that stops early leaves the crack tips it has crossed so far: decohesion's interface
/// comes apart at 1.108 us, and a bad patch at 1.12 us stops the run with `crack_tips.csv` (and
/// its picture) beside the history.
#[test]
fn a_stopped_cohesive_run_leaves_its_crack_tips() {
    let (err, _, dir) = poisoned_run("decohesion.toml", &["time.end=1.4e-6"], f64::NAN, 0.8);
    assert!(err.contains("a non-finite value"), "{err}");
    let tips = common::csv_columns(&dir.path().join("crack_tips.csv"), &["t_s"]);
    assert!(!tips.is_empty(), "the tips crossed before the stop");
    assert!(
        tips.iter().all(|t| (1.0e-6..1.12e-6).contains(&t[0])),
        "{tips:?}"
    );
    assert!(dir.path().join("crack_tips.png").is_file());
}
