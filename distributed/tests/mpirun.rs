//! `examples/mpi_pitch.rs` and `examples/mpi_solve.rs` under `mpirun` on 1 to 4 ranks (3 and 4
//! oversubscribed on small machines), over loopback: every rank's tents are the serial order's,
//! and every rank's elements the serial run's. Built only with the feature `mpi`; needs
//! OpenMPI's `mpirun` on the PATH and the examples built (plain `cargo test` builds them,
//! `--test mpirun` alone does not).

use std::path::PathBuf;
use std::process::Command;

// As root (containers, CI), on more ranks than cores, and over loopback only: the root crate's
// tests use the same file.
#[path = "../../tests/common/mpirun.rs"]
mod mpirun_env;
use mpirun_env::MPIRUN_ENV;

/// The binary of example `name`, which `cargo test` builds beside the test binaries' folder.
fn example(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let profile = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("target/<profile>/deps/<test>");
    let path = profile.join("examples").join(name);
    assert!(
        path.exists(),
        "{} is not built: `cargo test` builds the examples, `cargo test --test mpirun` alone \
         does not (build it with `cargo build --release -p sdg-distributed --features mpi \
         --examples`)",
        path.display()
    );
    path
}

/// Runs `mpi_pitch` on `ranks` ranks and returns rank 0's summary line.
fn mpirun(ranks: usize, args: &[&str]) -> String {
    run("mpi_pitch", ranks, args, "tents bitwise the serial order's")
}

/// Runs example `name` on `ranks` ranks and returns rank 0's summary line, which ends with
/// `success`.
fn run(name: &str, ranks: usize, args: &[&str], success: &str) -> String {
    let output = Command::new("mpirun")
        .arg("-n")
        .arg(ranks.to_string())
        .arg(example(name))
        .args(args)
        .envs(MPIRUN_ENV)
        .output()
        .expect("mpirun runs (OpenMPI installed: openmpi-bin)");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "mpirun -n {ranks} {name} {args:?}: {}\n{stdout}\n{stderr}",
        output.status
    );
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("rank ")).count(),
        ranks,
        "one line per rank:\n{stdout}"
    );
    let summary = stdout
        .lines()
        .find(|l| l.starts_with(&format!("{ranks} ranks")))
        .unwrap_or_else(|| panic!("no summary line:\n{stdout}"));
    assert!(summary.ends_with(success), "{summary}");
    summary.to_string()
}

/// The update messages per tent in a summary line.
fn per_tent(summary: &str) -> f64 {
    let (before, _) = summary.split_once(" per tent,").expect("messages per tent");
    let number = before.rsplit('(').next().expect("an opening parenthesis");
    number.parse().expect("a number")
}

#[test]
fn pitching_over_mpi_gives_the_serial_tents_on_1_to_4_ranks() {
    let mut previous = 0.0;
    for ranks in 1..=4 {
        let summary = mpirun(ranks, &[]);
        println!("{summary}");
        let messages = per_tent(&summary);
        match ranks {
            1 => assert_eq!(messages, 0.0, "one rank sends nothing"),
            _ => assert!(
                messages > previous && messages < 0.2,
                "more ranks, more boundary: {messages} after {previous}"
            ),
        }
        previous = messages;
    }
}

#[test]
fn a_random_partition_sends_an_update_for_most_tents() {
    let summary = mpirun(3, &["24", "random"]);
    println!("{summary}");
    assert!(per_tent(&summary) > 1.0, "{summary}");
}

#[test]
fn solving_over_mpi_gives_the_serial_elements_on_2_to_4_ranks() {
    let success = "elements bitwise the serial run's";
    for ranks in [2, 4] {
        let summary = run("mpi_solve", ranks, &[], success);
        println!("{summary}");
        assert!(per_tent(&summary) > 0.05, "{summary}");
    }
    let summary = run("mpi_solve", 3, &["10", "random"], success);
    println!("{summary}");
    assert!(per_tent(&summary) > 1.0, "{summary}");
}

#[test]
fn bad_arguments_exit_2() {
    for (name, bad) in [("mpi_pitch", "4"), ("mpi_solve", "1")] {
        let output = Command::new(example(name)).arg(bad).output().expect("runs");
        assert_eq!(output.status.code(), Some(2));
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains(&format!("CELLS: `{bad}`")), "{stderr}");
    }
}
