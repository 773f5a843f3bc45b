//! Disk faults a batch job meets (issue 69), through the `sdg` binary: a full disk, a read-only
//! file system or an output folder removed under the running job, while writing a checkpoint,
//! a snapshot or a CSV file. The run says which file and why, keeps the last good checkpoint
//! and exits 1; a restart from that checkpoint ends as an uninterrupted run. The faults are
//! injected in the writer (`SDG_FAULT`, engine/src/output/fault.rs), and a real full disk is a
//! small tmpfs where the test may mount one (root, a container that allows it).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{assert_same_outputs, outputs};

/// `configs/plane_wave.toml` with a checkpoint every 0.2 us of its 2 us (about 0.5 MB each,
/// all kept) and no pictures: three snapshots, `history.csv`, in about a second.
const OVERRIDES: [&str; 3] = [
    "checkpoint.every_sim_s=2e-7",
    "checkpoint.keep=100",
    "output.png=false",
];

/// `sdg run configs/plane_wave.toml` into `out`, deterministic, with [`OVERRIDES`], `args`
/// and the fault `fault` (`SDG_FAULT`), if any.
fn run(out: &Path, args: &[&str], fault: Option<&str>) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_sdg"));
    command
        .arg("run")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/plane_wave.toml"))
        .arg("--output")
        .arg(out)
        .args(["--deterministic", "--quiet", "--threads", "2"])
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    for o in OVERRIDES {
        command.args(["--set", o]);
    }
    match fault {
        Some(f) => command.env("SDG_FAULT", f),
        None => command.env_remove("SDG_FAULT"),
    };
    command
}

/// Runs `command` to its end: exit code and standard error.
fn finish(command: &mut Command) -> (i32, String) {
    let Output { status, stderr, .. } = command.output().expect("the sdg binary runs");
    (
        status.code().unwrap_or(-1),
        String::from_utf8_lossy(&stderr).into_owned(),
    )
}

/// The names of the files in `dir`, sorted (hidden temporary files included).
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = (std::fs::read_dir(dir).into_iter().flatten())
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The outputs of an uninterrupted run, its folder kept alive by the guard.
fn reference() -> (Vec<(String, Vec<u8>)>, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let (code, err) = finish(&mut run(dir.path(), &[], None));
    assert_eq!(code, 0, "{err}");
    (outputs(dir.path()), dir)
}

/// Restarts the run in `out` from the checkpoint folder `folder` (its newest valid file) with
/// checkpoints into `into`, and asserts that it ends with the outputs of `expected`.
fn restart_ends_as(out: &Path, folder: &Path, into: &Path, expected: &[(String, Vec<u8>)]) {
    let into = format!("checkpoint.dir=\"{}\"", into.display());
    let args = ["--restart", folder.to_str().unwrap(), "--set", &into];
    let (code, err) = finish(&mut run(out, &args, None));
    assert_eq!(code, 0, "the restart: {err}");
    assert_same_outputs(expected, &outputs(out), "restarted after a disk fault");
}

/// A full disk while writing checkpoint 2: exit 1 naming the file and the reason, checkpoints
/// 0 and 1 whole and no temporary file left; the restart from the folder (checkpoint 1) ends
/// bitwise as the uninterrupted run.
#[test]
fn a_full_disk_during_a_checkpoint_keeps_the_previous_one_usable() {
    let (expected, _reference) = reference();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let folder = out.join("checkpoints");
    let (code, err) = finish(&mut run(
        &out,
        &[],
        Some("disk-full:checkpoint_000002.sdgc"),
    ));
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("checkpoint_000002.sdgc: cannot write: No space left on device"),
        "{err}"
    );
    assert_eq!(
        names(&folder),
        ["checkpoint_000000.sdgc", "checkpoint_000001.sdgc"]
    );
    assert!(
        !out.join("summary.json").exists(),
        "a failed run has no summary"
    );
    restart_ends_as(&out, &folder, &dir.path().join("more"), &expected);
}

/// A snapshot, the collection or a CSV file that cannot be written (a full disk, a read-only
/// file system) ends the run with exit 1 naming the file: no output is optional, no
/// `summary.json`, no temporary file left. A restart from the last checkpoint writes them all.
#[test]
fn an_output_file_that_cannot_be_written_ends_the_run_with_exit_1() {
    let (expected, _reference) = reference();
    for (fault, reason) in [
        ("read-only:snapshot_0001.vtu", "Read-only file system"),
        ("disk-full:snapshots.pvd", "No space left on device"),
        ("disk-full:history.csv", "No space left on device"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let (code, err) = finish(&mut run(&out, &[], Some(fault)));
        assert_eq!(code, 1, "{fault}: {err}");
        let file = fault.split_once(':').unwrap().1;
        assert!(
            err.contains(&format!("{file}: cannot write: {reason}")),
            "{fault}: {err}"
        );
        let left = names(&out);
        assert!(
            !left
                .iter()
                .any(|n| n == "summary.json" || n.ends_with(".tmp")),
            "{fault}: {left:?}"
        );
        let folder = out.join("checkpoints");
        assert!(!names(&folder).is_empty(), "{fault}: a checkpoint before");
        restart_ends_as(&out, &folder, &dir.path().join("more"), &expected);
    }
}

/// The output folder removed under a running job: the next write (a checkpoint, a snapshot)
/// fails naming the file or folder, exit 1, and the folder is not made again.
#[test]
fn an_output_folder_removed_under_the_job_ends_it_with_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut command = run(
        &out,
        &[
            "--set",
            "mesh.nx=32",
            "--set",
            "mesh.ny=32",
            "--set",
            "time.end=1e-3",
        ],
        None,
    );
    let mut child = command.spawn().unwrap();
    let folder = out.join("checkpoints");
    let start = Instant::now();
    while names(&folder).is_empty() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended first");
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint");
        std::thread::sleep(Duration::from_millis(10));
    }
    // The run writes on meanwhile: remove until nothing is left.
    while out.exists() {
        let _ = std::fs::remove_dir_all(&out);
    }
    // The next checkpoint now, should none be due soon (a run that has failed already ignores it).
    let _ = Command::new("kill")
        .args(["-USR1", &child.id().to_string()])
        .status();
    let output = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{err}");
    let missing = format!("{}", out.display());
    assert!(
        err.contains(&missing) && err.contains("cannot write: No such file or directory"),
        "{err}"
    );
    assert!(!out.exists(), "the removed folder is not made again");
}

/// Mounts a tmpfs of `size` (mount's syntax) on a fresh folder; `None` when this machine does
/// not allow it (not root, a container without the capability).
fn tmpfs(size: &str) -> Option<Mounted> {
    let dir = tempfile::tempdir().unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
        .arg(dir.path())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    mounted.then_some(Mounted(dir))
}

/// A mounted tmpfs, unmounted on drop.
struct Mounted(tempfile::TempDir);

impl Mounted {
    fn path(&self) -> PathBuf {
        self.0.path().to_path_buf()
    }
}

impl Drop for Mounted {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.0.path()).status();
    }
}

/// A real full disk: the checkpoint folder on a tmpfs of 1,200 kB, which takes two of the
/// run's checkpoints (about 0.5 MB each) and not the third. Exit 1 naming the file and ENOSPC,
/// the two checkpoints whole, and the restart from them ends as the uninterrupted run.
#[test]
fn a_checkpoint_folder_on_a_full_tmpfs_keeps_its_whole_checkpoints() {
    let Some(disk) = tmpfs("1200k") else {
        eprintln!("skipped: mounting a tmpfs is not allowed here");
        return;
    };
    let (expected, _reference) = reference();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let folder = disk.path().join("checkpoints");
    let into = format!("checkpoint.dir=\"{}\"", folder.display());
    let (code, err) = finish(&mut run(&out, &["--set", &into], None));
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("checkpoint_000002.sdgc: cannot write: No space left on device"),
        "{err}"
    );
    assert_eq!(
        names(&folder),
        ["checkpoint_000000.sdgc", "checkpoint_000001.sdgc"],
        "whole checkpoints, no temporary file"
    );
    restart_ends_as(&out, &folder, &dir.path().join("more"), &expected);
}
