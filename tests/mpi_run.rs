//! `mpirun -n R sdg run CONFIG --mpi`: one rank per MPI process gives the state hash and patch
//! count of `sdg run --threads 1`, the `history.csv` of the run over in-process ranks and
//! snapshot pieces holding the threaded run's slices; a run under `mpirun` without `--mpi` is
//! refused; SIGTERM to `mpirun` checkpoints and stops every rank, and SIGKILL of one rank ends
//! the others within 10 s (of a plane wave, and of a cracking run whose rounds are split over
//! the ranks); either run goes on from its checkpoint on any number of ranks or on
//! threads to the state of the run never stopped. Built
//! only with the feature `mpi`; needs OpenMPI's `mpirun` on the PATH.

mod common;

use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::mpirun::MPIRUN_ENV;
use common::{SMALL_CRACK, pieces, run_args, sdg, slices, stderr, summary_json as summary};

/// `mpirun -n ranks sdg args`, as root, oversubscribed and over loopback (as in CI).
fn mpirun(ranks: usize, args: &[&str]) -> Output {
    Command::new("mpirun")
        .arg("-n")
        .arg(ranks.to_string())
        .arg(env!("CARGO_BIN_EXE_sdg"))
        .args(args)
        .envs(MPIRUN_ENV)
        .output()
        .expect("mpirun runs (OpenMPI installed: openmpi-bin)")
}

/// Runs `name` on one thread and over 2 in-process ranks, then under `mpirun` for each
/// `(ranks, partition, solving threads per rank)`, and checks the state hash, patches, ranks,
/// history and snapshots of each (snapshots written as ASCII).
fn check(name: &str, overrides: &[&str], cases: &[(usize, &str, usize)]) {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], out: &Path| {
        let args = run_args(name, overrides, extra, out);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let result = sdg(&args);
        assert!(result.status.success(), "{}", stderr(&result));
        summary(out)
    };
    let (threads_out, ranks_out) = (dir.path().join("threads"), dir.path().join("ranks"));
    let threads = run(&["--threads", "1"], &threads_out);
    run(&["--ranks", "2"], &ranks_out);
    for &(ranks, partition, per_rank) in cases {
        let out = dir.path().join(format!("{ranks}-{partition}-{per_rank}"));
        let per_rank_arg = per_rank.to_string();
        let extra = [
            "--mpi",
            "--partition",
            partition,
            "--threads",
            &per_rank_arg,
        ];
        let args = run_args(name, overrides, &extra, &out);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let result = mpirun(ranks, &args);
        assert!(
            result.status.success(),
            "mpirun -n {ranks} {args:?}: {}",
            stderr(&result)
        );
        let mpi = summary(&out);
        assert_eq!(
            mpi["state_hash"], threads["state_hash"],
            "{ranks} {partition}"
        );
        assert_eq!(mpi["patches"], threads["patches"]);
        assert_eq!(mpi["ranks"], ranks);
        assert_eq!(mpi["threads"], ranks * per_rank);
        assert_eq!(mpi["energy"]["final"], threads["energy"]["final"]);
        assert_eq!(
            std::fs::read_to_string(out.join("history.csv")).unwrap(),
            std::fs::read_to_string(ranks_out.join("history.csv")).unwrap(),
            "history.csv of {ranks} MPI ranks ({partition}) and of 2 in-process ranks"
        );
        let probes = |out: &Path| std::fs::read_to_string(out.join("interface.csv")).ok();
        assert_eq!(probes(&out), probes(&threads_out), "interface.csv");
        let snapshots = mpi["snapshots"].as_array().unwrap().len();
        for index in 0..snapshots {
            let threaded = slices(&[threads_out.join(format!("snapshot_{index:04}.vtu"))]);
            assert_eq!(
                pieces(&out, "snapshot", index, ranks),
                threaded,
                "snapshot {index}"
            );
        }
    }
}

#[test]
fn plane_wave_over_mpi_is_the_run_on_one_thread() {
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=1e-6",
        "output.snapshot_times=[5e-7, 1e-6]",
        "output.png=false",
        "output.vtu=\"ascii\"",
    ];
    let cases = [
        (1, "coordinate", 2),
        (2, "metis", 1),
        (2, "coordinate", 2),
        (3, "random", 1),
        (4, "stripes", 1),
    ];
    check("plane_wave.toml", &overrides, &cases);
}

#[test]
fn frictional_interface_over_mpi_is_the_run_on_one_thread() {
    let overrides = [
        "mesh.nx=8",
        "mesh.ny=8",
        "time.end=4e-6",
        "output.snapshot_times=[]",
        "output.png=false",
    ];
    check("stick_slip.toml", &overrides, &[(3, "random", 2)]);
}

/// A deterministic run with mesh-changing events (crack growth) under `mpirun`: the rounds
/// split over the processes, each holding the whole state, give the threaded deterministic
/// run's state and bookkeeping.
#[test]
fn a_cracking_run_over_mpi_is_the_threaded_deterministic_run() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = SMALL_CRACK;
    let threads_out = dir.path().join("threads");
    let args = run_args(
        "crack_growth.toml",
        &overrides,
        &["--threads", "2", "--deterministic"],
        &threads_out,
    );
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = sdg(&args);
    assert!(result.status.success(), "{}", stderr(&result));
    let threads = summary(&threads_out);
    for (ranks, per_rank) in [(2, 1), (3, 1)] {
        let out = dir.path().join(format!("{ranks}"));
        let per_rank_arg = per_rank.to_string();
        let extra = ["--mpi", "--deterministic", "--threads", &per_rank_arg];
        let args = run_args("crack_growth.toml", &overrides, &extra, &out);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let result = mpirun(ranks, &args);
        assert!(result.status.success(), "{}", stderr(&result));
        let mpi = summary(&out);
        for key in ["state_hash", "patches", "energy", "crack", "fracture"] {
            assert_eq!(mpi[key], threads[key], "{ranks} ranks: {key}");
        }
        assert_eq!(mpi["ranks"], ranks);
    }
}

#[test]
fn a_run_under_mpirun_without_mpi_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let args = run_args("plane_wave.toml", &[], &[], dir.path());
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = mpirun(2, &args);
    assert_eq!(result.status.code(), Some(2));
    assert!(stderr(&result).contains("add --mpi"), "{}", stderr(&result));
    assert!(!dir.path().join("summary.json").exists());
}

/// A plane wave to `end` s (1.4 s over 2 MPI ranks at 8e-6 s on 2 cores), with a checkpoint
/// every `every` s.
fn long_plane_wave(end: &str, every: &str) -> Vec<String> {
    let fixed = [
        "mesh.nx=16",
        "mesh.ny=16",
        "output.snapshot_times=[]",
        "output.png=false",
    ];
    fixed
        .into_iter()
        .map(String::from)
        .chain([
            format!("time.end={end}"),
            format!("checkpoint.every_sim_s={every}"),
        ])
        .collect()
}

/// `mpirun -n 2 sdg run` of `overrides` into `out` with `--mpi`, started, with OpenMPI's
/// `odls_base_sigkill_timeout` set to `kill_after` s: on SIGTERM `mpirun` sends the ranks SIGCONT,
/// SIGTERM that long after, and SIGKILL as long after that.
fn spawn_mpirun(overrides: &[&str], out: &Path, kill_after: &str) -> Child {
    spawn_mpirun_of("plane_wave.toml", overrides, &["--mpi"], out, kill_after)
}

/// [`spawn_mpirun`] of the shipped config `name` with `extra` arguments.
fn spawn_mpirun_of(
    name: &str,
    overrides: &[&str],
    extra: &[&str],
    out: &Path,
    kill_after: &str,
) -> Child {
    let args = run_args(name, overrides, extra, out);
    Command::new("mpirun")
        .args(["--mca", "odls_base_sigkill_timeout", kill_after])
        .args(["-n", "2", env!("CARGO_BIN_EXE_sdg")])
        .args(&args)
        .envs(MPIRUN_ENV)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("mpirun runs (OpenMPI installed: openmpi-bin)")
}

/// Waits up to `limit` for `child`; returns its output, or `None` if it is still running
/// (then it is killed).
fn wait_within(mut child: Child, limit: Duration) -> Option<Output> {
    let start = Instant::now();
    while start.elapsed() < limit {
        if child.try_wait().unwrap().is_some() {
            return Some(child.wait_with_output().unwrap());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    None
}

/// The state hash and patches of the run of `overrides` on threads (`extra` arguments) into
/// `out`.
fn on_threads(overrides: &[&str], extra: &[&str], out: &Path) -> (serde_json::Value, u64) {
    let args = run_args("plane_wave.toml", overrides, extra, out);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = sdg(&args);
    assert!(result.status.success(), "{}", stderr(&result));
    let s = summary(out);
    (s["state_hash"].clone(), s["patches"].as_u64().unwrap())
}

#[test]
fn sigterm_to_mpirun_checkpoints_every_rank_and_the_run_goes_on_anywhere() {
    let dir = tempfile::tempdir().unwrap();
    // A run of seconds: `mpirun` passes SIGTERM on to the ranks `odls_base_sigkill_timeout`
    // (here 2) s after it gets it, and kills them as long after that.
    let overrides = long_plane_wave("4e-5", "2e-6");
    let overrides: Vec<&str> = overrides.iter().map(String::as_str).collect();
    let expected = on_threads(
        &overrides,
        &["--threads", "2"],
        &dir.path().join("reference"),
    );
    let out = dir.path().join("stopped");
    let child = spawn_mpirun(&overrides, &out, "2");
    // The signal while the ranks solve: after their first checkpoint, at 1/20 of the run.
    wait_for_first_checkpoint(&out);
    let pid = child.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-TERM", &pid])
            .status()
            .unwrap()
            .success()
    );
    let result = wait_within(child, Duration::from_secs(40)).expect("mpirun ends");
    let err = stderr(&result);
    // Every rank stops with the checkpoint; `mpirun` signals the ranks one after the other, so a
    // rank may stop because another was asked to before its own SIGTERM arrives.
    for rank in 0..2 {
        assert!(err.contains(&format!("stopped: rank {rank}: ")), "{err}");
    }
    assert!(err.contains("SIGTERM received: stopped at"), "{err}");
    assert!(!out.join("summary.json").exists());
    let folder = out.join("checkpoints").display().to_string();
    for ranks in [2, 4] {
        let restarted = dir.path().join(format!("restart-{ranks}"));
        let args = run_args(
            "plane_wave.toml",
            &overrides,
            &["--mpi", "--restart", &folder],
            &restarted,
        );
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let result = mpirun(ranks, &args);
        assert!(result.status.success(), "{}", stderr(&result));
        let s = summary(&restarted);
        assert_eq!(
            (s["state_hash"].clone(), s["patches"].as_u64().unwrap()),
            expected
        );
    }
    let threads = dir.path().join("restart-threads");
    let extra = ["--threads", "2", "--restart", &folder];
    assert_eq!(on_threads(&overrides, &extra, &threads), expected);
}

/// Waits up to 60 s for the first checkpoint of the run writing into `out`.
fn wait_for_first_checkpoint(out: &Path) {
    let first = out.join("checkpoints/checkpoint_000000.sdgc");
    let start = Instant::now();
    while !first.exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(first.exists(), "a first checkpoint");
}

/// The pid of rank `rank` of the `sdg` processes writing into `out`.
fn rank_pid(out: &Path, rank: u32) -> Option<String> {
    let out = out.display().to_string();
    std::fs::read_dir("/proc").ok()?.flatten().find_map(|e| {
        let pid = e.file_name().into_string().ok()?;
        pid.parse::<u32>().ok()?;
        let cmdline = std::fs::read(e.path().join("cmdline")).ok()?;
        let environ = std::fs::read(e.path().join("environ")).ok()?;
        let has = |bytes: &[u8], s: &str| bytes.split(|&b| b == 0).any(|a| a == s.as_bytes());
        let sdg = String::from_utf8_lossy(&cmdline).contains("sdg");
        (sdg && has(&cmdline, "--mpi")
            && has(&cmdline, &out)
            && has(&environ, &format!("OMPI_COMM_WORLD_RANK={rank}")))
        .then_some(pid)
    })
}

#[test]
fn sigkill_of_one_rank_ends_the_others_and_the_last_checkpoint_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = long_plane_wave("8e-6", "1e-6");
    let overrides: Vec<&str> = overrides.iter().map(String::as_str).collect();
    let expected = on_threads(
        &overrides,
        &["--threads", "2"],
        &dir.path().join("reference"),
    );
    let out = dir.path().join("killed");
    let child = spawn_mpirun(&overrides, &out, "1");
    kill_rank_1(child, &out);
    let folder = out.join("checkpoints").display().to_string();
    let restarted = dir.path().join("restarted");
    let args = run_args(
        "plane_wave.toml",
        &overrides,
        &["--mpi", "--restart", &folder],
        &restarted,
    );
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = mpirun(2, &args);
    assert!(result.status.success(), "{}", stderr(&result));
    let s = summary(&restarted);
    assert_eq!(
        (s["state_hash"].clone(), s["patches"].as_u64().unwrap()),
        expected
    );
}

#[test]
fn sigkill_of_one_rank_of_a_cracking_run_ends_the_other_and_its_checkpoint_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    // Rounds split over the ranks, each holding the whole state; rank 0 checkpoints.
    let overrides: Vec<&str> = (SMALL_CRACK.iter().copied())
        .chain(["checkpoint.every_sim_s=1e-7"])
        .collect();
    let deterministic = ["--deterministic"];
    let reference = dir.path().join("reference");
    let args = run_args("crack_growth.toml", &overrides, &deterministic, &reference);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = sdg(&args);
    assert!(result.status.success(), "{}", stderr(&result));
    let expected = summary(&reference);
    let out = dir.path().join("killed");
    let extra = ["--mpi", "--deterministic"];
    let child = spawn_mpirun_of("crack_growth.toml", &overrides, &extra, &out, "1");
    kill_rank_1(child, &out);
    let folder = out.join("checkpoints").display().to_string();
    let restarted = dir.path().join("restarted");
    let extra = ["--mpi", "--deterministic", "--restart", &folder];
    let args = run_args("crack_growth.toml", &overrides, &extra, &restarted);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = mpirun(2, &args);
    assert!(result.status.success(), "{}", stderr(&result));
    let s = summary(&restarted);
    for key in ["state_hash", "patches", "crack"] {
        assert_eq!(s[key], expected[key], "{key}");
    }
}

/// Kills rank 1 of the `mpirun` `child` writing into `out` with SIGKILL once the run's first
/// checkpoint is written, and checks that the run ends within 10 s, failed, without a summary.
fn kill_rank_1(child: Child, out: &Path) {
    wait_for_first_checkpoint(out);
    let pid = rank_pid(out, 1).expect("rank 1 runs");
    assert!(
        Command::new("kill")
            .args(["-KILL", &pid])
            .status()
            .unwrap()
            .success()
    );
    let killed = Instant::now();
    let result = wait_within(child, Duration::from_secs(10)).expect("the others end within 10 s");
    assert!(!result.status.success());
    assert!(killed.elapsed() < Duration::from_secs(10));
    assert!(!out.join("summary.json").exists());
}
