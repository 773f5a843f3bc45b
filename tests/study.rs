//! `sdg study`: the shipped studies run; a study resumes where it stopped (a killed one to the
//! same `study.csv`), reruns cases whose config changed, runs under Slurm one case per array
//! task, and refuses bad study files before running anything.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use common::{CONFIG, sdg, stderr};

/// Study files shipped in configs/studies/, each run by a test here (the branching
/// convergence study and the LEFM sweeps, hours on 2 cores, are checked and listed only; the
/// reduced LEFM sweep runs in tests/lefm_sweep.rs).
const SHIPPED: [&str; 6] = [
    "branching_async.toml",
    "branching_convergence.toml",
    "lefm_sweep_ci.toml",
    "lefm_sweep_high.toml",
    "lefm_sweep_low.toml",
    "plate_draws.toml",
];

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// A folder with the small plate `CONFIG` as `base.toml` and `study` as `study.toml`; returns
/// the folder and the study's path.
fn study_folder(study: &str) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("base.toml"), CONFIG).unwrap();
    let path = dir.path().join("study.toml");
    std::fs::write(&path, study).unwrap();
    (dir, path.to_str().unwrap().to_string())
}

/// A study of the plate: 2 grids by 2 (or `draws`) "draws" of the number of rows, to `end`.
fn plate_study(nx: [u32; 2], draws: u32, end: &str) -> String {
    format!(
        "base = \"base.toml\"\nmetrics = [\"patches\", \"vertices\", \"energy.final\"]\n\
         [axes]\n\"mesh.nx\" = [{}, {}]\n\"mesh.ny\" = {{ draws = {draws}, first = 4 }}\n\
         [set]\n\"time.end\" = {end}\n\"scheduler.deterministic\" = true\n",
        nx[0], nx[1]
    )
}

/// Runs `sdg study` with `args`, expecting exit code 0; returns its standard error.
fn study(args: &[&str]) -> String {
    let out = sdg(&[&["study"], args].concat());
    let err = stderr(&out);
    assert!(out.status.success(), "{args:?}: {err}");
    err
}

/// `sdg study FILE --dry-run` into a scratch folder, expecting success; returns its listing.
fn dry_run(file: &Path) -> String {
    let dir = tempfile::tempdir().unwrap();
    let out = sdg(&[
        "study",
        file.to_str().unwrap(),
        "--dry-run",
        "--output",
        dir.path().to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}: {}", file.display(), stderr(&out));
    String::from_utf8(out.stdout).unwrap()
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&read(path)).unwrap()
}

#[test]
fn every_shipped_study_is_run_here() {
    let mut shipped: Vec<String> = std::fs::read_dir(repo("configs/studies"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    shipped.sort();
    assert_eq!(shipped, SHIPPED);
}

/// The branching convergence study (docs/verification.md): every case's config is valid and
/// the cases are the three resolutions by eight draws, coarsest first.
#[test]
fn the_branching_convergence_study_is_valid_and_lists_its_cases() {
    let file = repo("configs/studies/branching_convergence.toml");
    let listing = dry_run(&file);
    let cases: Vec<&str> = listing.lines().filter(|l| l.contains("pending")).collect();
    assert_eq!(cases.len(), 24, "{listing}");
    assert!(
        cases[0].contains("adapt.min_edge=5e-6, fracture.seed=1 (with adapt.tip_edge=5e-6)"),
        "{listing}"
    );
    assert!(
        cases[23].contains("adapt.min_edge=1.5e-6, fracture.seed=8"),
        "{listing}"
    );
}

/// The asynchronous branching study: valid, eight draws of the asynchronous scheduler.
#[test]
fn the_asynchronous_branching_study_is_valid() {
    let file = repo("configs/studies/branching_async.toml");
    let listing = dry_run(&file);
    assert!(
        listing.contains("scheduler.deterministic=false"),
        "{listing}"
    );
    assert_eq!(listing.lines().filter(|l| l.contains("pending")).count(), 8);
}

/// The LEFM sweeps (scripts/lefm_sweep.py writes them): every case's config is valid, and the
/// load ratios are the seed's, lowest first (the reduced sweep of CI: two low, one high).
#[test]
fn the_lefm_sweeps_are_valid_and_list_the_seed_s_load_ratios() {
    for (name, exponents) in [
        ("lefm_sweep_low.toml", vec![-1.5, -1.25, -1.0, -0.75, -0.5]),
        (
            "lefm_sweep_high.toml",
            [4.0, 8.0, 16.0, 32.0, 64.0, 128.0]
                .map(|d| -1.0 / d)
                .to_vec(),
        ),
        ("lefm_sweep_ci.toml", vec![-0.75, -0.5, -1.0 / 128.0]),
    ] {
        let file = repo(&format!("configs/studies/{name}"));
        let listing = dry_run(&file);
        let ratios: Vec<f64> = (listing.lines())
            .filter_map(|l| l.split("loading.load_ratio=").nth(1))
            .map(|r| r.split_whitespace().next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(ratios.len(), exponents.len(), "{listing}");
        for (r, e) in ratios.iter().zip(&exponents) {
            assert!(
                (r / 10f64.powf(*e) - 1.0).abs() < 1e-12,
                "{name}: {r} vs 10^{e}"
            );
        }
    }
}

/// The shipped example: 2 loads by 3 draws of the defects, its table and its statistics.
#[test]
fn the_plate_draws_study_runs_and_gathers_its_statistics() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().to_str().unwrap();
    let file = repo("configs/studies/plate_draws.toml");
    let err = study(&[
        file.to_str().unwrap(),
        "--output",
        dir,
        "--jobs",
        "2",
        "--threads",
        "1",
    ]);
    assert!(err.contains("about") && err.contains("case 5"), "{err}");
    let csv = read(&out.path().join("study.csv"));
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    // The list value of the load is quoted: split on commas it takes two cells.
    assert_eq!(
        rows[0],
        [
            "case",
            "boundary.1.incoming",
            "fracture.seed",
            "fracture.nucleations",
            "fracture.total_length",
            "energy.fracture_energy",
            "crack.first_branching_time",
            "patches",
            "status"
        ]
    );
    assert_eq!(rows.len(), 7);
    assert_eq!(rows[5][..4], ["4", "\"[5e7", " 0.0]\"", "2"]);
    assert!(rows[1..].iter().all(|r| r[9] == "done"), "{csv}");
    let s = json(&out.path().join("study.json"));
    assert_eq!(
        (s["cases"].as_u64(), s["done"].as_u64()),
        (Some(6), Some(6))
    );
    let groups = s["groups"].as_array().unwrap();
    assert_eq!(groups.len(), 2);
    // Each load's nucleations over its three draws, against the table's own column.
    for (g, group) in groups.iter().enumerate() {
        let values: Vec<f64> = rows[1 + 3 * g..4 + 3 * g]
            .iter()
            .map(|r| r[4].parse().unwrap())
            .collect();
        let mean = values.iter().sum::<f64>() / 3.0;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 2.0;
        let half = 4.302653 * var.sqrt() / 3f64.sqrt();
        let n = &group["metrics"]["fracture.nucleations"];
        assert_eq!(n["count"].as_u64(), Some(3));
        assert!((n["mean"].as_f64().unwrap() - mean).abs() < 1e-12, "{n}");
        assert!(
            (n["std"].as_f64().unwrap() - var.sqrt()).abs() < 1e-12,
            "{n}"
        );
        assert!(
            (n["ci95"][1].as_f64().unwrap() - (mean + half)).abs() < 1e-9,
            "{n}"
        );
        assert_eq!(n["present"].as_f64(), Some(1.0));
        // Cracks nucleate from the defects, more at the higher load.
        assert!(mean > 5.0, "{n}");
        // Nothing branches by 0.8 us: a metric missing in every case is data.
        let b = &group["metrics"]["crack.first_branching_time"];
        assert_eq!(
            (b["count"].as_u64(), b["present"].as_f64()),
            (Some(0), Some(0.0))
        );
        assert!(b["mean"].is_null(), "{b}");
    }
    let (low, high) = (&groups[0]["metrics"], &groups[1]["metrics"]);
    assert!(
        high["fracture.total_length"]["mean"].as_f64()
            > low["fracture.total_length"]["mean"].as_f64()
    );
    assert_eq!(
        groups[1]["axes"]["boundary.1.incoming"],
        serde_json::json!([5e7, 0.0])
    );
    let png = std::fs::read(out.path().join("study.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

/// Finished cases are skipped; a case whose config changed runs again; a failed case is
/// reported and the others go on (exit 1).
#[test]
fn a_study_resumes_and_reruns_what_changed() {
    let (dir, file) = study_folder(&plate_study([8, 12], 2, "1e-7"));
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    study(&[&file, "--output", o, "--quiet"]);
    let summary = |k: &str| out.join("cases").join(k).join("summary.json");
    let modified = |k: &str| std::fs::metadata(summary(k)).unwrap().modified().unwrap();
    let before = [modified("000"), modified("002")];
    let patches_12 = json(&summary("002"))["patches"].clone();
    // Again: nothing to run.
    let err = study(&[&file, "--output", o]);
    assert!(err.contains("4 finished before; running 0"), "{err}");
    // The second grid changes: its two cases run again, the first grid's do not.
    std::fs::write(&file, plate_study([8, 10], 2, "1e-7")).unwrap();
    let err = study(&[&file, "--output", o]);
    assert!(err.contains("2 finished before; running 2"), "{err}");
    assert_eq!(modified("000"), before[0]);
    assert_ne!(modified("002"), before[1]);
    assert_ne!(json(&summary("002"))["patches"], patches_12);
    let csv = read(&out.join("study.csv"));
    assert!(csv.lines().nth(3).unwrap().starts_with("2,10,4,"), "{csv}");
    // Cases that fail (the finer grid's tents are over `[limits]`: sdg run refuses it, exit
    // 2) are reported with their logs; the others run and are gathered; the study exits 1.
    let limited = plate_study([8, 12], 2, "1e-7") + "\"limits.max_tents\" = 60\n";
    std::fs::write(&file, limited).unwrap();
    let out2 = dir.path().join("out2");
    let run = sdg(&["study", &file, "--output", out2.to_str().unwrap()]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(
        err.contains("case 2 (mesh.nx=12, mesh.ny=4) failed: sdg run exited 2"),
        "{err}"
    );
    assert!(err.contains("limits.max_tents"), "the log's end: {err}");
    assert!(
        err.contains("2 of 4 cases failed: 2 (exit 2), 3 (exit 2)"),
        "{err}"
    );
    let csv = read(&out2.join("study.csv"));
    let statuses: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap())
        .collect();
    assert_eq!(statuses, ["done", "done", "failed", "failed"]);
    let record = json(&out2.join("cases/003/case.json"));
    assert_eq!(record["exit_code"].as_i64(), Some(2));
}

/// `--slurm` writes an array job whose task K runs case K: run as Slurm would, with
/// SLURM_ARRAY_TASK_ID set.
#[test]
fn the_slurm_script_runs_the_case_of_its_task() {
    let (dir, file) = study_folder(&plate_study([8, 12], 2, "1e-7"));
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let err = study(&[&file, "--output", o, "--slurm"]);
    let script = out.join("study.slurm");
    let text = read(&script);
    assert!(text.contains("#SBATCH --array=0-3"), "{text}");
    assert!(text.contains(env!("CARGO_BIN_EXE_sdg")), "{text}");
    assert!(err.is_empty(), "{err}");
    let task = Command::new("bash")
        .arg(&script)
        .env("SLURM_ARRAY_TASK_ID", "2")
        .output()
        .unwrap();
    assert!(task.status.success(), "{}", stderr(&task));
    let cases = out.join("cases");
    assert!(cases.join("002/summary.json").is_file());
    for k in ["000", "001", "003"] {
        assert!(!cases.join(k).exists(), "{k}");
    }
    // Without a task id the script refuses to run.
    let bare = Command::new("bash")
        .arg(&script)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(!bare.status.success());
    assert!(stderr(&bare).contains("sbatch"), "{}", stderr(&bare));
    // Gathering: one case done, the others pending.
    study(&[&file, "--output", o, "--collect", "--quiet"]);
    let csv = read(&out.join("study.csv"));
    let statuses: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap())
        .collect();
    assert_eq!(statuses, ["pending", "pending", "done", "pending"]);
    let s = json(&out.join("study.json"));
    assert_eq!(s["groups"][1]["done"].as_u64(), Some(1));
    assert_eq!(
        s["groups"][1]["metrics"]["patches"]["present"].as_f64(),
        Some(1.0)
    );
    // --case out of range is bad input.
    let run = sdg(&["study", &file, "--output", o, "--case", "4"]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
}

/// A study killed outright (SIGKILL) in the middle of a case resumes to the `study.csv` of a
/// study that was never interrupted.
#[test]
fn a_killed_study_resumes_to_the_same_table() {
    let (dir, file) = study_folder(&plate_study([12, 16], 3, "4e-7"));
    let whole = dir.path().join("whole");
    study(&[
        &file,
        "--output",
        whole.to_str().unwrap(),
        "--threads",
        "1",
        "--quiet",
    ]);
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_sdg"))
        .args(["study", &file, "--output", o, "--threads", "1", "--quiet"])
        .spawn()
        .unwrap();
    // Kill it once two cases have finished (while the third runs).
    let start = Instant::now();
    while !out.join("cases/001/summary.json").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no case finished"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("study.csv").exists());
    // Its run of the third case sees its standard input end, checkpoints and stops, unless it
    // finished first (a case takes about 0.1 s): then it counts as finished. Run again, the
    // case goes on from its checkpoint.
    std::thread::sleep(Duration::from_millis(300));
    let err = study(&[&file, "--output", o, "--threads", "1"]);
    assert!(
        err.contains("6 cases, 2 finished before; running 4")
            || err.contains("6 cases, 3 finished before; running 3"),
        "{err}"
    );
    assert_eq!(read(&out.join("study.csv")), read(&whole.join("study.csv")));
}

/// SIGTERM to a study: its running case checkpoints and stops (SIGUSR1 before it asks for a
/// checkpoint and the case goes on), no other case starts, the study exits 3; run again, the
/// case goes on from its checkpoint and the study ends with the `study.csv` of a study never
/// stopped. A case folder of another config has its checkpoints removed before it runs.
#[test]
fn a_stopped_study_goes_on_from_its_cases_checkpoints() {
    let (dir, file) = study_folder(
        "base = \"base.toml\"\nmetrics = [\"patches\", \"vertices\", \"energy.final\"]\n\
         [axes]\n\"mesh.ny\" = { draws = 2, first = 16 }\n[set]\n\"mesh.nx\" = 32\n\
         \"time.end\" = 5e-7\n\"scheduler.deterministic\" = true\n",
    );
    let whole = dir.path().join("whole");
    let w = whole.to_str().unwrap();
    study(&[&file, "--output", w, "--threads", "1", "--quiet"]);
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_sdg"))
        .args(["study", &file, "--output", o, "--threads", "1", "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let kill = |name: &str| {
        let status = Command::new("kill")
            .args([format!("-{name}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    };
    let start = Instant::now();
    while !out.join("cases/000/log.txt").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no case started");
        std::thread::sleep(Duration::from_millis(10));
    }
    // A case takes about 3 s (6 s on a loaded machine); its first checkpoint is on request.
    let checkpoints = out.join("cases/000/checkpoints");
    kill("USR1");
    while common::checkpoints(&checkpoints).is_empty() {
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint");
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(
        !out.join("cases/000/summary.json").exists(),
        "the case ended first"
    );
    kill("TERM");
    let ended = child.wait_with_output().unwrap();
    let err = stderr(&ended);
    assert_eq!(ended.status.code(), Some(3), "{err}");
    assert!(err.contains("stopped: 1 case(s) checkpointed (0)"), "{err}");
    let record = json(&out.join("cases/000/case.json"));
    assert_eq!(record["exit_code"].as_i64(), Some(3));
    assert!(
        !out.join("cases/001/case.json").exists(),
        "a case started after the stop"
    );
    let csv = read(&out.join("study.csv"));
    assert!(
        csv.contains(",stopped\n") && csv.contains(",pending\n"),
        "{csv}"
    );
    assert_eq!(json(&out.join("study.json"))["stopped"].as_u64(), Some(1));
    let err = study(&[&file, "--output", o, "--threads", "1"]);
    assert!(
        err.contains("2 cases, 0 finished before; running 2, 1 from their checkpoints"),
        "{err}"
    );
    assert_eq!(read(&out.join("study.csv")), read(&whole.join("study.csv")));
    let summary = json(&out.join("cases/000/summary.json"));
    assert!(
        summary["checkpoint"]["restarted_from"].is_string(),
        "{summary}"
    );
    // The study changed: case 1's folder holds checkpoints of another config, which go.
    let stale = out.join("cases/001/checkpoints");
    std::fs::create_dir_all(&stale).unwrap();
    std::fs::copy(
        &common::checkpoints(&checkpoints)[0],
        stale.join("checkpoint_000000.sdgc"),
    )
    .unwrap();
    let changed = read(Path::new(&file)).replace("5e-7", "4e-7");
    std::fs::write(&file, changed).unwrap();
    study(&[
        &file,
        "--output",
        o,
        "--threads",
        "1",
        "--case",
        "1",
        "--quiet",
    ]);
    let summary = json(&out.join("cases/001/summary.json"));
    assert!(
        summary["checkpoint"]["restarted_from"].is_null(),
        "{summary}"
    );
}

/// Bad studies exit 2 naming the study file and the key, before anything runs.
#[test]
fn bad_studies_are_refused_before_running() {
    let good = plate_study([8, 12], 2, "1e-7");
    for (study, key, reason) in [
        (
            good.replace("\"vertices\"", "\"vertice\""),
            "metrics",
            "`vertice`",
        ),
        (
            good.replace("\"time.end\"", "\"time.ends\""),
            "set.\"time.ends\"",
            "unknown field",
        ),
        (
            good.replace("draws = 2", "draws = 0"),
            "axes.\"mesh.ny\"",
            "draws = 0",
        ),
        (
            good.replace("\"mesh.nx\" = [8, 12]", "\"mesh.nx\" = []"),
            "axes.\"mesh.nx\"",
            "empty",
        ),
        (
            good.replace("base.toml", "nowhere.toml"),
            "base",
            "cannot read",
        ),
    ] {
        let (dir, file) = study_folder(&study);
        let out = dir.path().join("out");
        let run = sdg(&["study", &file, "--output", out.to_str().unwrap()]);
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("{file}: {key}: ")), "{key}: {err}");
        assert!(err.contains(reason), "{reason}: {err}");
        assert!(!out.exists(), "{key}: something ran");
    }
}
