//! Faults a batch job meets (issue 69), through the `sdg` binary: output that cannot be written
//! (a closed stdout or stderr, a pipe whose reader has gone) never ends a command nor changes
//! its exit code, and never stops SIGTERM, SIGINT or SIGUSR1 from working; a panic of the signal
//! listener ends the run with exit 1 instead of leaving it deaf; SIGHUP stops a run as SIGTERM
//! does; signals reach sdg through `timeout` and a shell that passes them on. Disk faults are
//! in `tests/disk.rs`, kills and restarts in `tests/chaos.rs`, the Slurm scripts in
//! `tests/slurm.rs`.

use crate::common;

use common::checkpoints;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::CONFIG;

/// How long a run may take from SIGTERM to its exit with a checkpoint here (a few ms on an idle
/// machine; the test machine runs other builds), s.
const STOP_WITHIN: Duration = Duration::from_secs(2);

/// Overrides of `plane_wave.toml` for a run of minutes: it is stopped long before its end.
const LONG: [&str; 3] = ["time.end=1e-3", "mesh.nx=32", "mesh.ny=32"];

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn sdg() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sdg"))
}

/// The write end of a pipe whose read end is closed already: every write to it fails with EPIPE
/// (a closed fd 1 or 2 would be reopened on /dev/null by the Rust runtime).
fn closed() -> Stdio {
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    writer.into()
}

/// Kills the child on drop unless it has been waited for, so that a failed test leaves no run.
struct Running(Child);

impl Running {
    fn id(&self) -> u32 {
        self.0.id()
    }

    fn is_running(&mut self) -> bool {
        self.0.try_wait().unwrap().is_none()
    }

    /// Waits at most `limit` for the exit; its code (-1 if killed by a signal).
    fn exit_within(&mut self, limit: Duration) -> i32 {
        let start = Instant::now();
        loop {
            if let Some(status) = self.0.try_wait().unwrap() {
                return status.code().unwrap_or(-1);
            }
            assert!(
                start.elapsed() < limit,
                "still running {limit:?} after the signal"
            );
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// What the exited process wrote to its piped standard error.
    fn stderr(&mut self) -> String {
        let mut err = String::new();
        let pipe = self.0.stderr.as_mut().expect("standard error piped");
        pipe.read_to_string(&mut err).unwrap();
        err
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if self.0.try_wait().ok().flatten().is_none() {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }
}

/// Sends the signal `name` to `target` (a pid, or `-PGID` for a process group).
fn signal(target: &str, name: &str) {
    let status = Command::new("kill")
        .args([format!("-{name}"), "--".into(), target.into()])
        .status()
        .unwrap();
    assert!(status.success(), "kill -{name} {target}");
}

/// The children of process `pid` (Linux).
fn children(pid: u32) -> Vec<u32> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    (tasks.flatten())
        .filter_map(|task| std::fs::read_to_string(task.path().join("children")).ok())
        .flat_map(|text| {
            (text.split_whitespace())
                .filter_map(|p| p.parse().ok())
                .collect::<Vec<u32>>()
        })
        .collect()
}

/// True when process `pid` has its thread named `signals`, i.e. sdg listens to signals.
fn listens(pid: u32) -> bool {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return false;
    };
    (tasks.flatten()).any(|task| {
        std::fs::read_to_string(task.path().join("comm")).is_ok_and(|c| c.trim() == "signals")
    })
}

/// Waits until `root` or one of its descendants is an sdg listening to signals; its pid.
fn listening_sdg(root: &mut Running) -> u32 {
    let start = Instant::now();
    loop {
        let mut pending = vec![root.id()];
        while let Some(pid) = pending.pop() {
            if listens(pid) {
                return pid;
            }
            pending.extend(children(pid));
        }
        assert!(root.is_running(), "the run ended before it listened");
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no signal listener"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Waits until `dir` holds `n` checkpoints, the run going on.
fn wait_for_checkpoints(child: &mut Running, dir: &Path, n: usize) {
    let start = Instant::now();
    while checkpoints(dir).len() < n {
        assert!(child.is_running(), "the run ended first");
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// `sdg run configs/plane_wave.toml` for minutes into `out`, with `args`.
fn long_run(out: &Path, args: &[&str]) -> Command {
    let mut command = sdg();
    command
        .arg("run")
        .arg(repo("configs/plane_wave.toml"))
        .arg("--output")
        .arg(out)
        .args(["--threads", "2"])
        .args(args);
    for o in LONG {
        command.args(["--set", o]);
    }
    command
}

/// The issue's reproduction: stdout and stderr into a pipe whose reader goes away while the
/// run is solving, then SIGTERM. Until issue 69 the signal listener's message on stderr
/// panicked (EPIPE) before it passed the request on: the run went on to its end, deaf to every
/// further SIGTERM, SIGINT and SIGUSR1.
#[test]
fn sigterm_stops_a_run_whose_output_pipe_reader_has_gone() {
    let dir = tempfile::tempdir().unwrap();
    let (mut reader, writer) = std::io::pipe().unwrap();
    let mut command = sdg();
    command
        .arg("run")
        .arg(repo("configs/adaptive_pulse.toml"))
        .arg("--output")
        .arg(dir.path())
        .args(["--force", "--set", "time.end=4e-5"])
        .stdout(writer.try_clone().unwrap())
        .stderr(writer);
    let mut child = Running(command.spawn().expect("the sdg binary runs"));
    // No copy of the write end is left here: the reader sees the end of the output.
    drop(command);
    // A reader that reads until the run is solving (its estimate is out), then goes.
    let mut text = Vec::new();
    let mut buf = [0u8; 4096];
    while !String::from_utf8_lossy(&text).contains("estimate:") {
        match reader.read(&mut buf) {
            Ok(0) | Err(_) => panic!("no estimate: {}", String::from_utf8_lossy(&text)),
            Ok(n) => text.extend_from_slice(&buf[..n]),
        }
    }
    drop(reader);
    let pid = listening_sdg(&mut child);
    std::thread::sleep(Duration::from_millis(500));
    assert!(child.is_running(), "the run ended before SIGTERM");
    let sent = Instant::now();
    signal(&pid.to_string(), "TERM");
    let code = child.exit_within(STOP_WITHIN);
    eprintln!("SIGTERM to exit: {:?}", sent.elapsed());
    assert_eq!(code, 3);
    assert_eq!(checkpoints(&dir.path().join("checkpoints")).len(), 1);
}

/// With stdout and stderr closed and the log at info: SIGUSR1 checkpoints and the run goes on
/// (the listener logs it), SIGTERM checkpoints and stops with exit 3.
#[test]
fn signals_work_with_stdout_and_stderr_closed() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("checkpoints");
    let mut command = long_run(dir.path(), &["--log-level", "info"]);
    command.stdout(closed()).stderr(closed());
    let mut child = Running(command.spawn().unwrap());
    let pid = listening_sdg(&mut child).to_string();
    signal(&pid, "USR1");
    wait_for_checkpoints(&mut child, &folder, 1);
    std::thread::sleep(Duration::from_millis(100));
    assert!(child.is_running(), "SIGUSR1 ends no run");
    signal(&pid, "TERM");
    assert_eq!(child.exit_within(STOP_WITHIN), 3);
    assert_eq!(checkpoints(&folder).len(), 2, "USR1's and TERM's");
}

/// SIGHUP (the terminal or the job's session gone) stops a run as SIGTERM does: a checkpoint
/// and exit 3.
#[test]
fn sighup_stops_with_a_checkpoint_and_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let mut command = long_run(dir.path(), &[]);
    command.stdout(Stdio::null()).stderr(Stdio::piped());
    let mut child = Running(command.spawn().unwrap());
    let pid = listening_sdg(&mut child).to_string();
    std::thread::sleep(Duration::from_millis(200));
    signal(&pid, "HUP");
    assert_eq!(child.exit_within(STOP_WITHIN), 3);
    let err = child.stderr();
    assert!(err.contains("SIGHUP received: stopped at t ="), "{err}");
    assert_eq!(checkpoints(&dir.path().join("checkpoints")).len(), 1);
}

/// Should the signal listener panic all the same (injected here), the run ends at once with
/// exit 1 and says so, instead of going on deaf to signals.
#[test]
fn a_panic_of_the_signal_listener_ends_the_run_with_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let mut command = long_run(dir.path(), &["--quiet"]);
    command
        .env("SDG_FAULT", "signal-listener")
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = Running(command.spawn().unwrap());
    let pid = listening_sdg(&mut child).to_string();
    signal(&pid, "USR1");
    assert_eq!(child.exit_within(STOP_WITHIN), 1);
    let err = child.stderr();
    assert!(
        err.contains("SDG_FAULT=signal-listener")
            && err.contains("error: internal error: the signal listener failed"),
        "{err}"
    );
}

/// Which output of a command a test closes.
#[derive(Clone, Copy, Debug)]
enum Closed {
    Both,
    /// stdout closed, stderr read.
    Stdout,
    /// stderr closed, stdout read.
    Stderr,
}

/// Runs `args` with `streams`: the exit code and the stream read, if any.
fn run_with(args: &[&str], streams: Closed) -> (i32, String) {
    let mut command = sdg();
    command.args(args);
    let (out, err) = match streams {
        Closed::Both => (closed(), closed()),
        Closed::Stdout => (closed(), Stdio::piped()),
        Closed::Stderr => (Stdio::piped(), closed()),
    };
    let output = command.stdout(out).stderr(err).output().unwrap();
    let text = [output.stdout, output.stderr].concat();
    let code = output.status.code().unwrap_or(-1);
    (code, String::from_utf8_lossy(&text).into_owned())
}

/// Runs `args` (from `make`, called afresh for each) with stdout, stderr or both closed: each
/// time exit code `code`, no panic, and the stream read (when it is one of `streams_read`)
/// holds `needle`.
fn expect_with_closed_outputs(make: impl Fn() -> Vec<String>, code: i32, needle: &str) {
    for streams in [Closed::Both, Closed::Stdout, Closed::Stderr] {
        let args = make();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (got, text) = run_with(&args, streams);
        let context = format!("{args:?} with {streams:?}");
        assert_eq!(got, code, "{context}: {text}");
        assert!(!text.contains("panicked"), "{context}: {text}");
        // An error is written to stderr, the rest to stdout.
        let read = match streams {
            Closed::Both => false,
            Closed::Stdout => code != 0,
            Closed::Stderr => code == 0,
        };
        if read {
            assert!(text.contains(needle), "{context}: `{needle}` not in {text}");
        }
    }
}

/// `sdg run`, `mesh`, `validate`, `plot` and `scaling` with stdout, stderr or both closed
/// finish with their documented exit codes: 0, 2 on bad input (a trace that is not there
/// included), 1 on a failure while running.
#[test]
fn commands_keep_their_exit_codes_with_stdout_or_stderr_closed() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("case.toml");
    std::fs::write(&config, CONFIG).unwrap();
    let config = config.to_str().unwrap().to_string();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let args = |list: &[&str]| list.iter().map(|s| s.to_string()).collect::<Vec<_>>();

    // run: a snapshot for `plot`, every log line failing to be written (debug; json).
    for format in ["text", "json"] {
        let out = path(&format!("run_{format}"));
        expect_with_closed_outputs(
            || {
                args(&[
                    "run",
                    &config,
                    "--output",
                    &out,
                    "--log-level",
                    "debug",
                    "--log-format",
                    format,
                    "--set",
                    "output.snapshot_times=[1e-7]",
                ])
            },
            0,
            "patches (order",
        );
        assert!(Path::new(&out).join("summary.json").is_file());
    }
    // run: a checkpoint that cannot be written (a folder where it goes) fails with exit 1.
    let failing = path("failing");
    expect_with_closed_outputs(
        || {
            let blocker = Path::new(&failing).join("checkpoints/checkpoint_000000.sdgc/x");
            std::fs::create_dir_all(blocker).unwrap();
            args(&[
                "run",
                &config,
                "--output",
                &failing,
                "--set",
                "checkpoint.at_end=true",
            ])
        },
        1,
        "checkpoint_000000.sdgc",
    );
    // run: refused before any work.
    let refused = path("refused");
    let limits = ["--set", "material.density=1e-30"];
    expect_with_closed_outputs(
        || args(&["run", &config, "--output", &refused, limits[0], limits[1]]),
        2,
        "density = 1e-30",
    );

    let out = path("mesh");
    expect_with_closed_outputs(|| args(&["mesh", &config, "--output", &out]), 0, "tents");
    expect_with_closed_outputs(|| args(&["mesh", "no/such/file.toml"]), 2, "file.toml");

    expect_with_closed_outputs(|| args(&["validate", &config]), 0, "valid");
    let over = ["validate", &config, limits[0], limits[1]];
    expect_with_closed_outputs(|| args(&over), 2, "density = 1e-30");

    let snapshot = path("run_text/snapshot_0000.vtu");
    let png = path("snapshot.png");
    let plot = ["plot", &snapshot, "--out", &png];
    expect_with_closed_outputs(|| args(&plot), 0, "snapshot.png");
    assert!(Path::new(&png).is_file());
    let bogus = path("bogus.vtu");
    std::fs::write(&bogus, "not xml").unwrap();
    expect_with_closed_outputs(|| args(&["plot", &bogus]), 2, "bogus.vtu");

    expect_with_closed_outputs(|| args(&["scaling", &path("no_trace.csv")]), 2, "no_trace");
}

/// `timeout -s TERM` signals sdg (and its process group): one request, a checkpoint and exit 3
/// (`--preserve-status`; without it `timeout` itself exits 124).
#[test]
fn sigterm_from_timeout_stops_with_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let run = long_run(dir.path(), &["--quiet"]);
    let mut command = Command::new("timeout");
    command
        .args(["--preserve-status", "-s", "TERM", "5"])
        .arg(run.get_program())
        .args(run.get_args())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = Running(command.spawn().unwrap());
    listening_sdg(&mut child);
    let code = child.exit_within(Duration::from_secs(5) + STOP_WITHIN);
    let err = child.stderr();
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("SIGTERM") && err.contains("--restart"),
        "{err}"
    );
    assert!(!err.contains("SIGTERM again"), "one request: {err}");
    assert_eq!(checkpoints(&dir.path().join("checkpoints")).len(), 1);
}

/// A job shell that runs sdg in the background and passes SIGTERM on (as
/// `examples/slurm/*.sbatch` do), signalled together with sdg as a batch system signals a
/// job's processes: one request, a checkpoint, exit 3 returned by the shell.
#[test]
fn sigterm_through_a_forwarding_shell_and_to_the_group_stops_with_exit_3() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().unwrap();
    let run = long_run(dir.path(), &["--quiet"]);
    let script = r#"trap 'kill -TERM "$pid"' TERM
"$@" &
pid=$!
wait "$pid"
wait "$pid""#;
    let mut command = Command::new("bash");
    command
        .args(["-c", script, "bash"])
        .arg(run.get_program())
        .args(run.get_args())
        .process_group(0)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = Running(command.spawn().unwrap());
    let shell = child.id();
    assert_ne!(
        listening_sdg(&mut child),
        shell,
        "sdg runs in the background"
    );
    signal(&format!("-{shell}"), "TERM");
    let code = child.exit_within(STOP_WITHIN);
    let err = child.stderr();
    assert_eq!(code, 3, "{err}");
    assert!(!err.contains("SIGTERM again"), "one request: {err}");
    assert_eq!(checkpoints(&dir.path().join("checkpoints")).len(), 1);
}
