//! The fuzz corpus (`tests/data/fuzz/config/`, made by `tests/data/fuzz/mutate.py`): shipped
//! configs with one mutation each, unit slips among them. Every input ends well within 60 s with
//! exit 0, 1 or 2 and a message, never a panic: bad values are rejected at load time, runs that
//! cannot finish are refused by their estimate, and the rest stop at `limits.max_wall_time_s`
//! (with a checkpoint: exit 3).

use crate::common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The wall-time limit the corpus runs with, s.
const LIMIT_S: &str = "2";
/// What no input may reach, s.
const TIMEOUT: Duration = Duration::from_secs(60);

#[test]
fn every_corpus_input_ends_quickly_with_a_reason() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/config");
    let mut inputs: Vec<_> = std::fs::read_dir(&corpus)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    inputs.sort();
    assert!(inputs.len() >= 40, "{} inputs", inputs.len());
    let out = tempfile::tempdir().unwrap();
    let mut codes = [0usize; 4];
    for input in &inputs {
        let start = Instant::now();
        let mut child = Command::new(env!("CARGO_BIN_EXE_sdg"))
            .arg("run")
            .arg(input)
            .arg("--output")
            .arg(out.path())
            .args(["--threads", "2", "--quiet", "--set"])
            .arg(format!("limits.max_wall_time_s={LIMIT_S}"))
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if start.elapsed() > TIMEOUT {
                child.kill().unwrap();
                panic!("{}: still running after {TIMEOUT:?}", input.display());
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let err = common::stderr(&child.wait_with_output().unwrap());
        let seconds = start.elapsed().as_secs_f64();
        let name = input.file_name().unwrap().to_string_lossy();
        let code = status.code().unwrap_or(-1);
        eprintln!("{name}: exit {code} in {seconds:.2} s");
        assert!(!err.contains("panicked"), "{name}: {err}");
        match code {
            0 => {}
            1 | 2 => assert!(err.starts_with("error: "), "{name}: exit {code}: {err}"),
            3 => assert!(err.contains("stopped: "), "{name}: exit 3: {err}"),
            _ => panic!("{name}: exit {code}: {err}"),
        }
        codes[code as usize] += 1;
    }
    eprintln!(
        "exit 0: {}, exit 1: {}, exit 2: {}, exit 3: {}",
        codes[0], codes[1], codes[2], codes[3]
    );
}
