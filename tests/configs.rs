//! Every shipped config runs, and its results match the stored values.

use crate::common;

use std::path::Path;
use std::process::Command;

/// Stored results of `sdg mesh --deterministic` per pitching config: (file, tents, tetrahedra),
/// exact for any thread count.
const EXPECTED: [(&str, u64, u64); 2] = [
    ("plate_mesh.toml", 35212, 203162),
    ("plate_with_hole.toml", 590, 2844),
];

/// Stored results of `sdg run --deterministic` per solver config, run to a shorter end time
/// (s): (file, end time, patches, velocity error, stress error). Errors are compared to 1e-6
/// relative.
const EXPECTED_RUNS: [(&str, f64, u64, f64, f64); 3] = [
    (
        "plane_wave.toml",
        5e-7,
        850,
        5.437164358389984e-4,
        5.280764054298484e-4,
    ),
    (
        "antiplane_pulse.toml",
        2.5e-6,
        3483,
        4.5546812168393305e-4,
        4.751844003759898e-4,
    ),
    (
        "adaptive_pulse.toml",
        1e-6,
        9853,
        8.411138693994109e-4,
        8.54894169405936e-4,
    ),
];

/// Shipped configs checked against references by other tests: (file, test).
const CHECKED_ELSEWHERE: [(&str, &str); 13] = [
    ("crack_growth.toml", "tests/fracture.rs"),
    ("crack_branching.toml", "tests/fracture.rs"),
    ("crack_branching_full.toml", "tests/fracture.rs"),
    ("crack_branching_set2.toml", "tests/fracture.rs"),
    ("contact_separation.toml", "tests/contact.rs"),
    ("stick_slip.toml", "tests/contact.rs"),
    ("cohesive_wave.toml", "tests/cohesive.rs"),
    ("decohesion.toml", "tests/cohesive.rs"),
    ("mode1_lefm.toml", "tests/cohesive.rs"),
    ("mode1_lefm_high.toml", "tests/cohesive.rs"),
    ("mode1_lefm_low.toml", "tests/cohesive.rs"),
    ("damage_interface.toml", "tests/damage.rs"),
    ("damage_mode1.toml", "tests/damage.rs"),
];

fn run_mesh(config: &str, out: &Path) -> serde_json::Value {
    run_sdg("mesh", config, &[], out)
}

/// Runs `sdg COMMAND configs/CONFIG --set ...` into `out` and reads its summary.
fn run_sdg(command: &str, config: &str, set: &[String], out: &Path) -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(config);
    let mut args = vec![command.to_string(), path.to_str().unwrap().to_string()];
    for s in set {
        args.extend(["--set".to_string(), s.clone()]);
    }
    let status = Command::new(env!("CARGO_BIN_EXE_sdg"))
        .args(&args)
        .args(["--quiet", "--deterministic", "--output"])
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success(), "{config}");
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn pitching_configs_match_stored_results() {
    // Run configs: the files of configs/ (its folder studies/ holds study files, each run by
    // tests/study.rs).
    let shipped = std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs"))
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().is_file())
        .count();
    assert_eq!(
        shipped,
        EXPECTED.len() + EXPECTED_RUNS.len() + CHECKED_ELSEWHERE.len(),
        "every shipped config has stored results"
    );
    for (config, tents, tetrahedra) in EXPECTED {
        let dir = tempfile::tempdir().unwrap();
        let s = run_mesh(config, dir.path());
        assert_eq!(s["tents"].as_u64(), Some(tents), "{config}");
        assert_eq!(s["tetrahedra"].as_u64(), Some(tetrahedra), "{config}");
        assert!(s["max_slope_ratio"].as_f64().unwrap() < s["safety"].as_f64().unwrap());
    }
}

#[test]
fn solver_configs_match_stored_results() {
    for (config, end, patches, velocity, stress) in EXPECTED_RUNS {
        let dir = tempfile::tempdir().unwrap();
        let set = [
            format!("time.end={end:e}"),
            format!("output.snapshot_times=[{end:e}]"),
        ];
        let s = run_sdg("run", config, &set, dir.path());
        assert_eq!(s["patches"].as_u64(), Some(patches), "{config}");
        let close = |got: &serde_json::Value, want: f64| {
            (got.as_f64().unwrap() - want).abs() <= 1e-6 * want
        };
        assert!(
            close(&s["error"]["velocity_l2_rel"], velocity),
            "{config}: {}",
            s["error"]
        );
        assert!(
            close(&s["error"]["stress_l2_rel"], stress),
            "{config}: {}",
            s["error"]
        );
        assert!(s["energy"]["balance_residual_rel"].as_f64().unwrap().abs() < 1e-10);
        assert!(dir.path().join("snapshot_0000.vtu").exists());
        assert!(dir.path().join("history.csv").exists());
        // `output.png = true` in every shipped config: the pictures decode at their sizes (a
        // snapshot of a wide domain is cut below its axis labels).
        for (file, size) in [
            ("snapshot_0000.png", sdg_engine::plot::FIELD_PNG_SIZE),
            ("history.png", sdg_engine::plot::HISTORY_PNG_SIZE),
        ] {
            let bytes = std::fs::read(dir.path().join(file)).unwrap();
            let info = png::Decoder::new(std::io::Cursor::new(bytes))
                .read_info()
                .unwrap()
                .info()
                .clone();
            assert_eq!(info.width, size.0, "{config}: {file}");
            assert!(
                info.height <= size.1 && (file == "snapshot_0000.png" || info.height == size.1),
                "{config}: {file} is {} high",
                info.height
            );
        }
    }
}

/// meshio (the reader behind many Python post-processing scripts) opens `spacetime.vtu`. Needs
/// `python3` with meshio: required under CI, skipped with a notice elsewhere.
#[test]
fn spacetime_mesh_opens_in_meshio() {
    if !common::meshio_available("meshio reads spacetime.vtu") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let s = run_mesh("plate_with_hole.toml", dir.path());
    let script = "import sys, meshio\n\
                  m = meshio.read(sys.argv[1])\n\
                  t = m.point_data['time']\n\
                  print(len(m.points), m.cells_dict['tetra'].shape[0], t.min(), t.max(), \
                  m.points[:, 2].max())";
    let fields: Vec<f64> = common::python(script, &[&dir.path().join("spacetime.vtu")])
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    let points = s["vertices"].as_f64().unwrap() + s["tents"].as_f64().unwrap();
    assert_eq!(
        fields,
        [points, s["tetrahedra"].as_f64().unwrap(), 0.0, 5e-7, 5e-7]
    );
}
