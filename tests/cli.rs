//! The `sdg` command line: outputs, overrides, and exit codes with clear messages on bad input.

use crate::common;

use std::path::{Path, PathBuf};

use common::{CONFIG, sdg, stderr};

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// `CONFIG` with a 2 mm edge crack at mid-height in frictional contact.
const CRACKED: &str = r#"
[[mesh.interface]]
from = [0.0, 0.001]
to = [0.002, 0.001]
tag = "crack"

[[interface]]
tags = ["crack"]
law = "contact"
friction = 0.25
r_c = -1e-6
r_s = 0.0
s_c = 0.0
s_s = 6e5
"#;

/// Writes `text` as a config in a fresh folder; returns the folder and the config path.
fn config_file(text: &str) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("case.toml");
    std::fs::write(&path, text).unwrap();
    let path = path.to_str().unwrap().to_string();
    (dir, path)
}

/// Runs `args`, expects exit code 2 and a message containing every one of `needles`.
fn expect_input_error(args: &[&str], needles: &[&str]) {
    let out = sdg(args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: `{n}` not in: {err}");
    }
}

/// A config that extends another runs as the merge of the two; a cycle in the chain and a
/// missing base are bad input (exit 2) naming the chain.
#[test]
fn extends_builds_on_a_base_and_refuses_cycles_and_missing_files() {
    let (dir, base) = config_file(CONFIG);
    let folder = dir.path();
    let write = |name: &str, text: &str| {
        let path = folder.join(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_string()
    };
    let finer = write("finer.toml", "extends = \"case.toml\"\n[mesh]\nnx = 16\n");
    let summary = |config: &str, out: &str| {
        let out_dir = folder.join(out);
        let run = sdg(&["mesh", config, "--output", out_dir.to_str().unwrap()]);
        assert!(run.status.success(), "{}", stderr(&run));
        let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let (coarse, fine) = (summary(&base, "base"), summary(&finer, "finer"));
    let direct = {
        let out_dir = folder.join("direct");
        let run = sdg(&[
            "mesh",
            &base,
            "--set",
            "mesh.nx=16",
            "--output",
            out_dir.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{}", stderr(&run));
        let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    assert_ne!(coarse["tents"], fine["tents"]);
    assert_eq!(fine["tents"], direct["tents"]);
    let a = write("a.toml", "extends = \"b.toml\"\n");
    write("b.toml", "extends = \"a.toml\"\n");
    expect_input_error(
        &["validate", &a],
        &["extends", "a.toml -> ", "b.toml -> ", "a cycle"],
    );
    let c = write("c.toml", "extends = \"gone.toml\"\n");
    expect_input_error(
        &["validate", &c],
        &["extends", "c.toml -> ", "gone.toml", "cannot read"],
    );
}

#[test]
fn mesh_writes_summary_and_spacetime_mesh() {
    let (dir, config) = config_file(CONFIG);
    let out_dir = dir.path().join("out");
    let out = sdg(&[
        "mesh",
        &config,
        "--output",
        out_dir.to_str().unwrap(),
        "--set",
        "output.spacetime_mesh=true",
        "--set",
        "mesh.nx=16",
        "--threads",
        "2",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(out.stdout.is_empty(), "--quiet prints nothing");
    let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(s["final_time"].as_f64(), Some(1e-7));
    assert_eq!(
        s["vertices"].as_u64(),
        Some(17 * 5),
        "the override took effect"
    );
    let ratio = s["max_slope_ratio"].as_f64().unwrap();
    assert!(ratio > 0.0 && ratio < 0.9, "{ratio}");
    assert!(s["tents"].as_u64().unwrap() > 0);
    let estimated = s["estimate"]["tents"].as_f64().unwrap();
    let ratio = s["tents"].as_f64().unwrap() / estimated;
    assert!(
        (0.9..1.1).contains(&ratio),
        "{estimated} tents estimated: {s}"
    );
    assert!(s["tetrahedra"].as_u64().unwrap() > s["tents"].as_u64().unwrap());
    assert!(s["wall_time_s"].as_f64().is_some() && s["threads"].as_u64() == Some(2));
    let vtu = std::fs::read_to_string(out_dir.join("spacetime.vtu")).unwrap();
    let cells = format!("NumberOfCells=\"{}\"", s["tetrahedra"]);
    assert!(vtu.contains(&cells));
    // A folder with the summary of `sdg run` keeps it: `sdg mesh` refuses to write there.
    let run_summary = r#"{"command": "run", "patches": 7}"#;
    std::fs::write(out_dir.join("summary.json"), run_summary).unwrap();
    let out_arg = out_dir.to_str().unwrap();
    expect_input_error(
        &["mesh", &config, "--output", out_arg, "--quiet"],
        &["summary.json", "sdg run", "--output"],
    );
    let kept = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    assert_eq!(kept, run_summary);
}

#[test]
fn validate_accepts_the_shipped_configs() {
    // Run configs: the TOML files of configs/ (its folder studies/ holds study files).
    for entry in std::fs::read_dir(repo("configs")).unwrap() {
        let path = entry.unwrap().path();
        if !path.is_file() {
            continue;
        }
        let out = sdg(&["validate", path.to_str().unwrap()]);
        assert!(out.status.success(), "{}: {}", path.display(), stderr(&out));
    }
}

#[test]
fn each_command_lists_only_its_options() {
    let help = |command: &str| {
        let out = sdg(&[command, "--help"]);
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8(out.stdout).unwrap()
    };
    let job = [
        "--output",
        "--threads",
        "--deterministic",
        "--log-level",
        "--log-format",
    ];
    for command in ["run", "mesh"] {
        let text = help(command);
        for option in ["<CONFIG>", "--set", "--quiet"].iter().chain(&job) {
            assert!(
                text.contains(option),
                "{command}: {option} missing:\n{text}"
            );
        }
    }
    let text = help("validate");
    for option in ["<CONFIG>", "--set", "--quiet"] {
        assert!(text.contains(option), "validate: {option} missing:\n{text}");
    }
    for option in job.iter().filter(|&&o| o != "--threads") {
        assert!(!text.contains(option), "validate: {option} listed:\n{text}");
    }
    assert!(
        text.contains("--threads"),
        "validate: --threads missing:\n{text}"
    );
    assert!(
        !text.contains("--force"),
        "validate: --force listed:\n{text}"
    );
    for command in ["run", "mesh"] {
        assert!(
            help(command).contains("--force"),
            "{command}: --force missing"
        );
    }
    let text = help("plot");
    for option in ["<FILE>...", "--field", "--out ", "--edges", "--quiet"] {
        assert!(text.contains(option), "plot: {option} missing:\n{text}");
    }
    for option in ["--set"].iter().chain(&job) {
        assert!(!text.contains(option), "plot: {option} listed:\n{text}");
    }
}

#[test]
fn malformed_config() {
    let (_dir, config) = config_file(&format!("{CONFIG}\n[pitch\nsafety = 0.5\n"));
    expect_input_error(
        &["mesh", &config],
        &["case.toml", "invalid TOML", "line 22"],
    );
}

#[test]
fn unknown_key() {
    let (_dir, config) = config_file(&CONFIG.replace("[time]", "[time]\nbegin = 0.0"));
    expect_input_error(
        &["validate", &config],
        &["case.toml", "time", "unknown field `begin`"],
    );
    let (_dir, config) = config_file(CONFIG);
    expect_input_error(&["mesh", &config, "--set", "pitch.speed=2"], &["speed"]);
}

#[test]
fn negative_density() {
    let (_dir, config) = config_file(&CONFIG.replace("1190.0", "-1190.0"));
    expect_input_error(
        &["mesh", &config],
        &["case.toml", "material.density", "positive"],
    );
}

#[test]
fn poisson_ratio_at_or_above_one_half() {
    let (_dir, config) = config_file(CONFIG);
    for nu in ["0.5", "0.7"] {
        let set = format!("material.poisson={nu}");
        expect_input_error(
            &["mesh", &config, "--set", &set],
            &["material.poisson", "(-1, 0.5)"],
        );
    }
}

#[test]
fn invalid_adaptivity_settings() {
    let (_dir, config) = config_file(CONFIG);
    for (set, words) in [
        ("adapt.tol=-1e-3", ["adapt.tol", "positive"]),
        (
            "adapt.coarsen_ratio=0.5",
            ["adapt.coarsen_ratio", "above 1"],
        ),
        ("adapt.min_edge=0.0", ["adapt.min_edge", "positive length"]),
        (
            "adapt.tip_edge=-1e-6",
            ["adapt.tip_edge", "positive length"],
        ),
        ("adapt.far_edge=0.0", ["adapt.far_edge", "positive length"]),
        (
            "adapt.max_edge=1e-4",
            ["adapt.max_edge", "twice adapt.min_edge"],
        ),
        (
            "adapt.reference_energy=-1.0",
            ["adapt.reference_energy", "positive energy"],
        ),
        (
            "adapt.fixed_reference=true",
            ["adapt.fixed_reference", "needs adapt.reference_energy"],
        ),
    ] {
        let args = [
            "validate",
            &config,
            "--set",
            "adapt.min_edge=1e-4",
            "--set",
            set,
        ];
        let source = format!("--set {set}");
        expect_input_error(&args, &[&source, words[0], words[1]]);
    }
}

#[test]
fn invalid_interface_settings() {
    let (_dir, config) = config_file(&format!("{CONFIG}{CRACKED}"));
    let out = sdg(&["validate", &config]);
    assert!(out.status.success(), "{}", stderr(&out));
    for (set, words) in [
        (
            "interface.0.friction=-0.1",
            ["interface[0].friction", ">= 0"],
        ),
        ("interface.0.r_c=1e-6", ["interface[0].r_c", "must be <= 0"]),
        (
            "interface.0.r_s=-2e-6",
            ["interface[0].r_s", "must be >= r_c"],
        ),
        (
            "interface.0.s_c=7e5",
            ["interface[0].s_s", "must be >= s_c"],
        ),
        (
            "interface.0.law=glued",
            ["interface[0].law", "unknown variant `glued`"],
        ),
        (
            "material.plane=antiplane",
            ["interface[0].law", "anti-plane"],
        ),
        (
            r#"interface.0.tags=["crack", "top"]"#,
            ["interface[0].tags", "`top` tags boundary edges"],
        ),
        (
            "output.interface_probes=[[0.003, 0.0015]]",
            [
                "output.interface_probes[0]",
                "farther than the longest edge",
            ],
        ),
        (
            "solver.newton_tol=2.0",
            ["solver.newton_tol", "must be in (0, 1)"],
        ),
        (
            "solver.newton_max_iter=0",
            ["solver.newton_max_iter", "at least 1"],
        ),
    ] {
        expect_input_error(
            &["validate", &config, "--set", set],
            &[&source_of(set, words[0]), words[0], words[1]],
        );
    }
    // A cohesive law with a non-positive strength or critical separation.
    let cohesive = format!("{CONFIG}{CRACKED}").replace(
        "law = \"contact\"",
        "law = \"xu_needleman\"\nstrength = 3.24e8\ncritical_separation = 4e-7",
    );
    let (_dir, config) = config_file(&cohesive);
    for (set, words) in [
        (
            "interface.0.strength=0.0",
            ["interface[0].strength", "must be a finite number > 0"],
        ),
        (
            "interface.0.critical_separation=-1e-7",
            [
                "interface[0].critical_separation",
                "must be a finite number > 0",
            ],
        ),
    ] {
        expect_input_error(
            &["validate", &config, "--set", set],
            &[&source_of(set, words[0]), words[0], words[1]],
        );
    }
    let bonded = format!("{CONFIG}{CRACKED}").replace("law = \"contact\"", "law = \"bonded\"");
    let (_dir, config) = config_file(&bonded);
    expect_input_error(
        &["validate", &config],
        &[
            "case.toml",
            "interface[0].friction",
            "not a parameter of law = \"bonded\"",
        ],
    );
}

/// Where an error at `key` caused by the override `set` comes from: the override when it set
/// that key (or a list holding it), checks against the mesh (interface tags, probes) included,
/// else the config file (`interface.0.s_c` makes `s_s` invalid).
fn source_of(set: &str, key: &str) -> String {
    let path = set.split('=').next().unwrap().replace(".0.", "[0].");
    if key.starts_with(&path) {
        format!("--set {set}")
    } else {
        "case.toml".into()
    }
}

#[test]
fn errors_name_the_override_or_the_file() {
    let (_dir, config) = config_file(CONFIG);
    let out = sdg(&["validate", &config, "--set", "mesh.nx=0"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("error: --set mesh.nx=0: mesh.nx: must be at least 1"),
        "{err}"
    );
    assert!(!err.contains("case.toml"), "{err}");
    // The same value from the file names the file, whatever else is overridden.
    let (_dir, config) = config_file(&CONFIG.replace("nx = 8", "nx = 0"));
    expect_input_error(
        &["validate", &config, "--set", "mesh.ny=8"],
        &["case.toml: mesh.nx: must be at least 1"],
    );
}

#[test]
fn checks_against_the_mesh_name_the_override() {
    let (_dir, config) = config_file(&format!("{CONFIG}{CRACKED}"));
    for (set, message) in [
        (
            r#"interface.0.tags=["crak"]"#,
            "interface[0].tags: no interior edge is tagged `crak`",
        ),
        (
            r#"boundary.0.sides=["left", "right", "bottom", "top", "middle"]"#,
            "boundary[0].sides: no boundary side is tagged `middle`",
        ),
    ] {
        let out = sdg(&["validate", &config, "--set", "mesh.nx=16", "--set", set]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        let expected = format!("error: --set {set}: {message}");
        assert!(
            err.starts_with(&expected),
            "expected `{expected}`, got: {err}"
        );
    }
    // The same side in the file names the file.
    let (_dir, config) = config_file(&CONFIG.replace(r#""top"]"#, r#""top", "middle"]"#));
    expect_input_error(
        &["validate", &config, "--set", "mesh.nx=16"],
        &["case.toml: boundary[0].sides: no boundary side is tagged `middle`"],
    );
}

#[test]
fn every_tag_must_be_named() {
    let (_dir, config) = config_file(CONFIG);
    expect_input_error(
        &[
            "mesh",
            &config,
            "--set",
            r#"boundary.0.sides=["left", "right", "bottom"]"#,
        ],
        &["case.toml", "boundary:", "`top` has no [[boundary]] entry"],
    );
    expect_input_error(
        &[
            "run",
            &config,
            "--set",
            "output.interface_probes=[[0.001, 0.001]]",
        ],
        &[
            "--set output.interface_probes=[[0.001, 0.001]]",
            "output.interface_probes[0]",
            "no interface edge",
        ],
    );
    let uncracked = format!("{CONFIG}{CRACKED}");
    let uncracked = uncracked.split("[[interface]]").next().unwrap();
    let (_dir, config) = config_file(uncracked);
    expect_input_error(
        &["validate", &config],
        &[
            "case.toml",
            "interface:",
            "`crack` has no [[interface]] entry",
        ],
    );
    expect_input_error(
        &[
            "validate",
            &config,
            "--set",
            r#"boundary.0.sides=["left", "right", "bottom", "top", "crack"]"#,
        ],
        &[
            r#"--set boundary.0.sides=["left", "right", "bottom", "top", "crack"]"#,
            "boundary[0].sides",
            "`crack` tags interior edges",
        ],
    );
}

#[test]
fn non_causal_safety_factor() {
    let (_dir, config) = config_file(CONFIG);
    expect_input_error(
        &["mesh", &config, "--set", "pitch.safety=1.2"],
        &["pitch.safety"],
    );
}

#[test]
fn wrong_type_in_an_override() {
    let (_dir, config) = config_file(CONFIG);
    expect_input_error(
        &["mesh", &config, "--set", "mesh.nx=many"],
        &["mesh.nx", "many"],
    );
}

#[test]
fn truncated_gmsh_file() {
    let msh = repo("tests/data/truncated.msh");
    let text = CONFIG
        .replace(
            "kind = \"rectangle\"",
            &format!("kind = \"gmsh\"\npath = {:?}", msh),
        )
        .replace("width = 0.004\nheight = 0.002\nnx = 8\nny = 4\n", "");
    let (_dir, config) = config_file(&text);
    expect_input_error(&["mesh", &config], &["truncated.msh:"]);
}

#[test]
fn missing_config_file_and_bad_arguments() {
    expect_input_error(
        &["mesh", "no/such/file.toml"],
        &["no/such/file.toml", "cannot read"],
    );
    expect_input_error(&["mesh"], &["CONFIG"]);
    expect_input_error(&["mesh", "x.toml", "--threads", "0"], &["--threads"]);
}

#[test]
fn run_solves_and_reports() {
    let (dir, config) = config_file(CONFIG);
    let out_dir = dir.path().join("out");
    let out = sdg(&[
        "run",
        &config,
        "--output",
        out_dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(s["command"], "run");
    assert_eq!(s["final_time"].as_f64(), Some(1e-7));
    assert!(s["patches"].as_u64().unwrap() > 0);
    assert!(out_dir.join("history.csv").exists());
}

/// A history row each time the front passes a hundredth of the span, taken then, also in the
/// asynchronous mode: until 2026-11-28 its rows waited for a batch of 32 events, which gave
/// runs of identical rows late; and the end's row is written once.
#[test]
fn asynchronous_history_rows_are_taken_when_the_front_passes_them() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let config = repo("configs/plane_wave.toml");
    let out = sdg(&[
        "run",
        config.to_str().unwrap(),
        "--output",
        out_dir.to_str().unwrap(),
        "--threads",
        "2",
        "--set",
        "time.end=5e-7",
        "--set",
        "output.snapshot_times=[]",
        "--set",
        "mesh.nx=48",
        "--set",
        "mesh.ny=48",
        "--set",
        "scheduler.deterministic=false",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let history = std::fs::read_to_string(out_dir.join("history.csv")).unwrap();
    let times: Vec<f64> = (history.lines().skip(1))
        .map(|row| row.split(',').next().unwrap().parse().unwrap())
        .collect();
    // The front's least time moves by a tent's height, about 6.3e-8 s here, and the end's
    // milestone and the final row are one row.
    assert!(times.len() >= 8, "{history}");
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{history}");
    assert_eq!(times.last(), Some(&5e-7));
}

/// A new run into a folder of an earlier run removes that run's snapshot files, which its own
/// collection would not list, and keeps everything else.
#[test]
fn a_rerun_with_fewer_snapshots_leaves_none_of_the_earlier_ones() {
    let (dir, config) = config_file(CONFIG);
    let out_dir = dir.path().join("out");
    let run = |times: &str| {
        let set = format!("output.snapshot_times={times}");
        let out = sdg(&[
            "run",
            &config,
            "--output",
            out_dir.to_str().unwrap(),
            "--quiet",
            "--set",
            &set,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
    };
    run("[5e-8, 1e-7]");
    assert!(out_dir.join("snapshot_0001.vtu").exists());
    std::fs::write(out_dir.join("notes.txt"), b"mine").unwrap();
    run("[1e-7]");
    assert!(out_dir.join("snapshot_0000.vtu").exists());
    assert!(!out_dir.join("snapshot_0001.vtu").exists());
    assert!(!out_dir.join("snapshot_0001.png").exists());
    let pvd = std::fs::read_to_string(out_dir.join("snapshots.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 1, "{pvd}");
    assert!(out_dir.join("notes.txt").exists());
}

/// An output folder that cannot be created is a bad argument: nothing runs, exit 2 (until
/// 2026-11-28 it was exit 1 with the bare OS error). A write that fails during a run is still
/// exit 1.
#[test]
fn an_output_folder_that_cannot_be_created_is_bad_input() {
    let (dir, config) = config_file(CONFIG);
    // A file where the output folder's parent should be: creating the folder fails.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, b"").unwrap();
    let inside = blocker.join("out");
    expect_input_error(
        &["run", &config, "--output", inside.to_str().unwrap()],
        &["--output", "blocker", "cannot create the output folder"],
    );
    // The checkpoint folder and the trace are checked before the run too (until 2026-11-28
    // only their first write found them: exit 1 after the whole solve).
    let out = dir.path().join("out");
    let (out, inside) = (out.to_str().unwrap(), inside.to_str().unwrap());
    let checkpoint_dir = format!("checkpoint.dir={inside}");
    expect_input_error(
        &["run", &config, "--output", out, "--set", &checkpoint_dir],
        &["checkpoint.dir", "blocker", "is a file, not a folder"],
    );
    expect_input_error(
        &["run", &config, "--output", out, "--trace", inside],
        &["--trace", "blocker", "is a file, not a folder"],
    );
    assert!(!dir.path().join("out").join("history.csv").exists());
}

/// `sdg run configs/crack_growth.toml --quiet` into `out_dir` with `args`.
fn crack_growth_into(out_dir: &Path, args: &[&str]) -> std::process::Output {
    let config = repo("configs/crack_growth.toml");
    let mut all = vec!["run", config.to_str().unwrap(), "--output"];
    all.extend([out_dir.to_str().unwrap(), "--quiet"]);
    all.extend(args);
    sdg(&all)
}

/// A run whose checkpoint cannot be written fails (exit 1) naming the file, and leaves the
/// outputs so far; an earlier run's `summary.json` in its folder does not survive it, so that
/// a job script never reads it as this run's.
#[test]
fn a_failed_checkpoint_write_leaves_the_outputs_so_far_and_no_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    // A folder that is not empty where the checkpoint should go: its rename fails.
    std::fs::create_dir_all(out_dir.join("checkpoints/checkpoint_000000.sdgc/x")).unwrap();
    std::fs::write(out_dir.join("summary.json"), "{}").unwrap();
    let out = crack_growth_into(
        &out_dir,
        &["--set", "time.end=2e-7", "--set", "checkpoint.at_end=true"],
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("checkpoint_000000.sdgc") && !err.contains(".sdgc.tmp"),
        "{err}"
    );
    for name in ["history.csv", "events.csv", "cracks.csv", "crack_tips.csv"] {
        assert!(out_dir.join(name).is_file(), "{name}");
    }
    assert!(!out_dir.join("summary.json").exists());
    assert!(
        !out_dir
            .join("checkpoints/.checkpoint_000000.sdgc.tmp")
            .exists()
    );
}

/// The issue's unit slips: runs whose wave speed makes the tent count astronomical are refused
/// before any work, quickly, with the estimate and what drives it.
#[test]
fn a_run_that_cannot_finish_is_refused_before_any_work() {
    let (dir, config) = config_file(CONFIG);
    for (command, set, driver) in [
        ("run", "material.density=1e-30", "density = 1e-30"),
        ("run", "material.young=1e308", "young = 1e308"),
        ("mesh", "material.density=1e-30", "density = 1e-30"),
        ("validate", "material.density=1e-30", "density = 1e-30"),
    ] {
        let out_dir = dir.path().join("refused");
        let start = std::time::Instant::now();
        let mut args = vec![command, &config, "--set", set];
        if command != "validate" {
            args.extend(["--output", out_dir.to_str().unwrap(), "--quiet"]);
        }
        expect_input_error(
            &args,
            &["case.toml", "limits.max_tents", "tents", driver, "--force"],
        );
        let seconds = start.elapsed().as_secs_f64();
        assert!(seconds < 5.0, "{command} {set}: {seconds} s");
        assert!(!out_dir.exists(), "{command} {set}: wrote outputs");
    }
}

/// A limit below a small run's estimate refuses it (exit 2); `--force` runs it, and its
/// summary carries the estimate beside the actual values.
#[test]
fn force_runs_beyond_the_limits_and_the_summary_keeps_the_estimate() {
    let (dir, config) = config_file(CONFIG);
    let out_dir = dir.path().join("out");
    let args = [
        "run",
        &config,
        "--output",
        out_dir.to_str().unwrap(),
        "--threads",
        "2",
        "--set",
        "limits.max_tents=10",
    ];
    expect_input_error(&args, &["limits.max_tents", "more than the limit 1.000e1"]);
    let out = sdg(&[&args[..], &["--force", "--quiet"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    let estimate = &s["estimate"];
    let (tents, patches) = (
        estimate["tents"].as_f64().unwrap(),
        s["patches"].as_f64().unwrap(),
    );
    assert!(
        (patches / tents - 1.0).abs() < 0.1,
        "{tents} estimated, {patches} solved"
    );
    assert_eq!(estimate["lower_bound"].as_bool(), Some(false));
    assert_eq!(estimate["threads"].as_u64(), Some(2));
    for key in ["wall_time_s", "memory_bytes", "seconds_per_tent"] {
        assert!(estimate[key].as_f64().unwrap() > 0.0, "{key}: {estimate}");
    }
    if cfg!(target_os = "linux") {
        assert!(s["peak_memory_bytes"].as_f64().unwrap() > 1e6);
    }
    let out = sdg(&["validate", &config, "--threads", "3"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    for needle in [
        "c_d = ",
        "c_s = ",
        "c_R = ",
        "estimate: ",
        "tents",
        "on 3 thread(s)",
    ] {
        assert!(text.contains(needle), "`{needle}` not in:\n{text}");
    }
}

/// A run past `limits.max_wall_time_s` (an estimate can be short: refinement adds tents) stops
/// with exit 1 and a message, leaving its history.
#[test]
fn a_run_stops_when_its_wall_time_is_up() {
    let (dir, config) = config_file(CONFIG);
    let out_dir = dir.path().join("out");
    let out = sdg(&[
        "run",
        &config,
        "--output",
        out_dir.to_str().unwrap(),
        "--set",
        "limits.max_wall_time_s=1e-9",
        "--force",
        "--quiet",
    ]);
    let err = stderr(&out);
    assert_eq!(
        out.status.code(),
        Some(3),
        "checkpointed and stopped: {err}"
    );
    assert!(
        err.starts_with("stopped: limits.max_wall_time_s = 0.000000001 s is up"),
        "{err}"
    );
    assert!(out_dir.join("history.csv").exists());
    assert!(out_dir.join("checkpoints/checkpoint_000000.sdgc").exists());
}

/// A crack run stopped early leaves the crack outputs of its front as it is: events, crack
/// edges and their pictures.
#[test]
fn a_stopped_crack_run_leaves_its_crack_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let out = crack_growth_into(
        &out_dir,
        &["--set", "limits.max_wall_time_s=1e-9", "--force"],
    );
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    for name in [
        "events.csv",
        "cracks.csv",
        "crack_path.png",
        "crack_tips.csv",
    ] {
        assert!(out_dir.join(name).is_file(), "{name}");
    }
    // The notch's edges, from x = 0 to 1 mm on y = 1 mm.
    let cracks = std::fs::read_to_string(out_dir.join("cracks.csv")).unwrap();
    assert_eq!(cracks.lines().count(), 1 + 16, "{cracks}");
}

/// `sdg run CONFIG --trace TRACE` into `out_dir` with `options`: the summary and the trace.
fn traced_run(
    config: &str,
    out_dir: &Path,
    trace: &Path,
    options: &[&str],
) -> (serde_json::Value, String) {
    let mut args = vec![
        "run",
        config,
        "--output",
        out_dir.to_str().unwrap(),
        "--force",
        "--quiet",
        "--trace",
        trace.to_str().unwrap(),
    ];
    args.extend(options);
    let out = sdg(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let summary = serde_json::from_slice(&std::fs::read(out_dir.join("summary.json")).unwrap());
    (summary.unwrap(), std::fs::read_to_string(trace).unwrap())
}

#[test]
fn a_traced_run_replays_on_more_workers() {
    let (dir, config) = config_file(CONFIG);
    let out_dir = dir.path().join("out");
    let trace = dir.path().join("trace.csv");
    let (summary, text) = traced_run(&config, &out_dir, &trace, &["--threads", "1"]);
    let patches = summary["patches"].as_u64().unwrap();
    let tents = text.lines().filter(|l| l.contains(",patch,")).count() as u64;
    assert_eq!(tents, patches, "one line per patch");
    let png = dir.path().join("scaling.png");
    let out = sdg(&[
        "scaling",
        trace.to_str().unwrap(),
        "--workers",
        "1,2,64",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(
        table.starts_with("model: the asynchronous scheduler"),
        "{table}"
    );
    let speedups: Vec<f64> = table
        .lines()
        .skip(2)
        .take(3)
        .map(|l| l.split_whitespace().nth(2).unwrap().parse().unwrap())
        .collect();
    eprintln!("{table}");
    // Two workers at most halve the time; no number of workers beats the critical path.
    let bound = number_after(&table, "at most ", 'x');
    assert_eq!(speedups[0], 1.0);
    assert!((1.0..=2.0).contains(&speedups[1]), "{speedups:?}");
    assert!(speedups[2] <= bound + 0.01, "{speedups:?} {bound}");
    assert!(png.is_file());
    // Over ranks (the config's mesh partitioned): one rank is the scheduler's replay; two ranks
    // of one worker at most halve the time, and a latency between them only delays.
    let over_ranks = |ranks: &str, latency_us: &str| -> (f64, String) {
        let out = sdg(&[
            "scaling",
            trace.to_str().unwrap(),
            "--workers",
            "1",
            "--ranks",
            ranks,
            "--config",
            &config,
            "--latency-us",
            latency_us,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let table = String::from_utf8(out.stdout).unwrap();
        let line = table.lines().nth(2).unwrap_or_else(|| panic!("{table}"));
        (
            line.split_whitespace().nth(2).unwrap().parse().unwrap(),
            table,
        )
    };
    let (one_rank, table) = over_ranks("1", "100");
    assert_eq!(one_rank, 1.0, "{table}");
    let (two, table) = over_ranks("2", "0");
    assert!(
        table.starts_with("model: 2 ranks (coordinate partition)"),
        "{table}"
    );
    assert!(1.0 < two && two <= 2.0, "{table}");
    // A latency far above any tent's time, so that the table's rounding cannot hide it.
    let (late, table) = over_ranks("2", "100000");
    assert!(late < two, "{table}");
    expect_input_error(
        &over_two_ranks(&trace, &config, &["--latency-us=-1"]),
        &["--latency-us", ">= 0"],
    );
    // A deterministic run's trace marks its rounds and is replayed as them.
    let (summary, text) = traced_run(&config, &out_dir, &trace, &["--deterministic"]);
    let rounds = summary["rounds"].as_u64().unwrap();
    assert_eq!(
        text.lines().filter(|l| l.contains(",round,")).count() as u64,
        rounds
    );
    // Each round's tents are settled in chunks of 16, listed before the round's end.
    let (mut tents, mut chunks) = (0usize, 0usize);
    for kind in text.lines().skip(1).filter_map(|l| l.split(',').nth(1)) {
        match kind {
            "patch" | "newton" | "rejected" | "coarsen" => tents += 1,
            "settle" => chunks += 1,
            "round" => {
                assert_eq!(chunks, tents.div_ceil(16), "{tents} tents");
                (tents, chunks) = (0, 0);
            }
            _ => {}
        }
    }
    let out = sdg(&["scaling", trace.to_str().unwrap(), "--workers", "1,2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(
        table.starts_with(&format!(
            "model: the deterministic scheduler's {rounds} rounds"
        )),
        "{table}"
    );
    std::fs::write(&trace, "id,kind\n").unwrap();
    expect_input_error(
        &["scaling", trace.to_str().unwrap()],
        &["trace.csv:1", "header"],
    );
}

/// `sdg scaling TRACE --ranks 2 --config CONFIG` and `more`.
fn over_two_ranks<'a>(trace: &'a Path, config: &'a str, more: &[&'a str]) -> Vec<&'a str> {
    let args = [
        "scaling",
        trace.to_str().unwrap(),
        "--ranks",
        "2",
        "--config",
        config,
    ];
    [&args[..], more].concat()
}

/// The number after `key` in `text`, up to `end`.
fn number_after(text: &str, key: &str, end: char) -> f64 {
    text.split(key)
        .nth(1)
        .and_then(|rest| rest.split(end).next())
        .and_then(|x| x.trim().parse().ok())
        .unwrap_or_else(|| panic!("no number after {key:?} in {text}"))
}

/// An adaptive run's refinements and coarsenings are traced as regional events, which `sdg
/// scaling` replays beside the tents, as the scheduler runs them: they are not on the critical
/// path's list of events that run alone.
#[test]
fn a_traced_adaptive_run_replays_its_regional_events_beside_tents() {
    let dir = tempfile::tempdir().unwrap();
    let (out_dir, trace) = (dir.path().join("out"), dir.path().join("trace.csv"));
    let config = repo("configs/adaptive_pulse.toml");
    let (summary, text) = traced_run(
        config.to_str().unwrap(),
        &out_dir,
        &trace,
        &[
            "--threads",
            "2",
            "--set",
            "time.end=3e-7",
            "--set",
            "output.snapshot_times=[]",
        ],
    );
    let regions = text.lines().filter(|l| l.contains(",region,")).count();
    assert!(regions > 0, "no refinement in {summary}");
    let out = sdg(&["scaling", trace.to_str().unwrap(), "--workers", "1,2,16"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(
        table.contains(&format!("its {regions} refinements,")),
        "{table}"
    );
    // Only the `event` rows (history rows) run alone: the critical path's events are theirs.
    let alone: f64 = text
        .lines()
        .filter(|l| l.contains(",event,"))
        .map(|l| l.split(',').nth(4).unwrap().parse::<f64>().unwrap())
        .sum();
    let events = number_after(&table, "s, events ", 's');
    assert!(
        (events - alone).abs() <= 1e-4,
        "{events} s against {alone} s: {table}"
    );
    // No number of workers beats the critical path.
    let bound = number_after(&table, "at most ", 'x');
    let line = table
        .lines()
        .find(|l| l.trim_start().starts_with("16 "))
        .unwrap_or_else(|| panic!("no 16-worker row in {table}"));
    let at_16: f64 = line.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!(at_16 <= bound + 0.01, "{table}");
    // Runs over ranks do not change their mesh: such a trace is not replayed over them.
    let set = [
        "--set",
        "time.end=3e-7",
        "--set",
        "output.snapshot_times=[]",
    ];
    let args = over_two_ranks(&trace, config.to_str().unwrap(), &set);
    expect_input_error(
        &[&args[..], &["--latency-us", "1"]].concat(),
        &["--ranks", "mesh-changing"],
    );
}

/// An output folder that cannot be made is bad input (exit 2) naming where it came from; an
/// unknown table an override adds is the override's error; a shortened run's snapshot times
/// outside its span say how to drop them.
#[test]
fn output_folders_overrides_and_snapshot_times_are_blamed_on_their_source() {
    let (dir, config) = config_file(CONFIG);
    let file = dir.path().join("a_file");
    std::fs::write(&file, "").unwrap();
    expect_input_error(
        &[
            "run",
            &config,
            "--output",
            file.to_str().unwrap(),
            "--quiet",
        ],
        &[
            "--output",
            "cannot create the output folder",
            "a file, not a folder",
        ],
    );
    expect_input_error(
        &["validate", &config, "--set", "foo.bar=1"],
        &["--set foo.bar=1: foo: unknown field"],
    );
    let branching = repo("configs/crack_branching.toml");
    expect_input_error(
        &[
            "validate",
            branching.to_str().unwrap(),
            "--set",
            "time.end=-1.5e-6",
        ],
        &[
            "output.snapshot_times",
            "[-2.392e-6, -1.5e-6]",
            "--set 'output.snapshot_times=[]'",
        ],
    );
}

/// `validate` on a config over its limits, or beyond the machine's memory, says so before the
/// error, which tells how `sdg run` would accept it.
#[test]
fn validate_over_the_limits_says_so() {
    let (_dir, config) = config_file(CONFIG);
    let out = sdg(&["validate", &config, "--set", "material.density=1e-30"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    assert!(text.contains(": valid input, over its [limits]"), "{text}");
    assert!(stderr(&out).contains("pass --force to `sdg run`"));
    // More workers than the machine's memory holds: refused before any work, naming
    // `--threads` (until 2026-11-28 the kernel killed the run, exit 137).
    let out = sdg(&["validate", &config, "--threads", "1000000"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    assert!(
        text.contains(": valid input, beyond this machine's memory"),
        "{text}"
    );
    let err = stderr(&out);
    assert!(
        err.contains("--threads 1000000: ") && err.contains("GiB"),
        "{err}"
    );
}
