//! `mpirun -n R sdg run CONFIG --mpi`: one rank per MPI process gives the state hash and patch
//! count of `sdg run --threads 1`, the `history.csv` of the run over in-process ranks and
//! snapshot pieces holding the threaded run's slices; a run under `mpirun` without `--mpi` is
//! refused. Built
//! only with the feature `mpi`; needs OpenMPI's `mpirun` on the PATH.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::mpirun::MPIRUN_ENV;
use common::{pieces, run_args, sdg, slices, stderr, summary_json as summary};

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
/// `(ranks, partition)`, and checks the state hash, patches, ranks, history and snapshots of
/// each (snapshots written as ASCII).
fn check(name: &str, overrides: &[&str], cases: &[(usize, &str)]) {
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
    for &(ranks, partition) in cases {
        let out = dir.path().join(format!("{ranks}-{partition}"));
        let args = run_args(name, overrides, &["--mpi", "--partition", partition], &out);
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
        assert_eq!(mpi["energy"]["final"], threads["energy"]["final"]);
        assert_eq!(
            std::fs::read_to_string(out.join("history.csv")).unwrap(),
            std::fs::read_to_string(ranks_out.join("history.csv")).unwrap(),
            "history.csv of {ranks} MPI ranks ({partition}) and of 2 in-process ranks"
        );
        let snapshots = mpi["snapshots"].as_array().unwrap().len();
        for index in 0..snapshots {
            let threaded = slices(&[threads_out.join(format!("snapshot_{index:04}.vtu"))]);
            assert_eq!(pieces(&out, index, ranks), threaded, "snapshot {index}");
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
        (1, "coordinate"),
        (2, "coordinate"),
        (3, "random"),
        (4, "stripes"),
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
        "output.interface_probes=[]",
        "output.png=false",
    ];
    check("stick_slip.toml", &overrides, &[(3, "random")]);
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
