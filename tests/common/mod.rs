// Each test binary uses a different subset of these helpers.
#![allow(dead_code)]

//! Helpers shared by the integration tests: run configs through the engine or the `sdg`
//! binary, read our files back with Python.

use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use sdg_engine::{Config, LoadedConfig, Problem, RunOptions, RunSummary};

pub mod mpirun;

/// Parses `text` with `overrides`, solves it in deterministic mode on two threads with outputs in
/// a fresh temporary folder, and returns the summary and the folder (kept alive by the returned
/// guard).
pub fn run(text: &str, overrides: &[String]) -> (RunSummary, tempfile::TempDir) {
    let config = Config::parse(text, "test.toml", overrides).expect("valid config");
    let loaded = LoadedConfig {
        config,
        file: "test.toml".into(),
        overrides: overrides.to_vec(),
    };
    let problem = Problem::setup(loaded).expect("valid problem");
    let dir = tempfile::tempdir().expect("temporary folder");
    let options = RunOptions {
        output_dir: Some(dir.path().to_path_buf()),
        threads: Some(2),
        deterministic: true,
        progress: false,
        force: false,
        ..RunOptions::default()
    };
    let (summary, _) = sdg_engine::solve_job(&problem, &options).expect("run succeeds");
    (summary, dir)
}

/// Runs `problem` on `threads` threads into a fresh folder; returns the summary and the folder.
pub fn solve(
    problem: &Problem,
    threads: usize,
    deterministic: bool,
) -> (RunSummary, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let options = RunOptions {
        output_dir: Some(dir.path().to_path_buf()),
        threads: Some(threads),
        deterministic,
        progress: false,
        force: false,
        ..RunOptions::default()
    };
    let (summary, _) = sdg_engine::solve_job(problem, &options).unwrap();
    (summary, dir)
}

/// Every output file (not the checkpoint folder), with the fields measured on the machine
/// (`wall_time_s`, `patches_per_second`, `threads`, `peak_memory_bytes`, `estimate`), the
/// process's checkpoints and its command line's `overrides` removed from `summary.json`.
pub fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|path| path.is_file())
        .map(|path| {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let mut bytes = std::fs::read(&path).unwrap();
            if name == "summary.json" {
                let mut json: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                for key in [
                    "wall_time_s",
                    "patches_per_second",
                    "threads",
                    "peak_memory_bytes",
                    "estimate",
                    "checkpoint",
                    "timings",
                    "overrides",
                ] {
                    json.as_object_mut().unwrap().remove(key);
                }
                bytes = serde_json::to_vec_pretty(&json).unwrap();
            }
            (name, bytes)
        })
        .collect();
    files.sort();
    files
}

/// Asserts that `got` holds the same files as `expected` (both from [`outputs`]), by name and
/// byte for byte; `context` says which run differs.
pub fn assert_same_outputs(
    expected: &[(String, Vec<u8>)],
    got: &[(String, Vec<u8>)],
    context: &str,
) {
    assert_eq!(
        expected.iter().map(|f| &f.0).collect::<Vec<_>>(),
        got.iter().map(|f| &f.0).collect::<Vec<_>>(),
        "{context}: other files"
    );
    for ((name, a), (_, b)) in expected.iter().zip(got) {
        assert!(a == b, "{context}: {name} differs");
    }
}

/// `stick_slip.toml` made small and adaptive: refinement, coarsening, Newton contact patches,
/// two snapshots and a probe in about 10 s (the runs that must stay bitwise identical).
pub const STICK_SLIP_ADAPTIVE: [&str; 9] = [
    "mesh.nx=8",
    "mesh.ny=8",
    "time.end=1e-6",
    "solver.order=2",
    "adapt.enabled=true",
    "adapt.tol=1e-2",
    "adapt.min_edge=1.25e-4",
    "output.snapshot_times=[5e-7, 1e-6]",
    "output.interface_probes=[[0.00075, 0.002]]",
];

/// `crack_growth.toml` on a quarter of its plate: 2 x 1 mm with the same 62.5 um edges and the
/// same 1 mm notch, the waves meeting on it 0.24 us after they enter. The notch grows from
/// 0.38 us and branches at 0.82 us; 35k patches, under 2 s on two threads (the cracking runs
/// that must stay bitwise the same over ranks and restarts).
pub const SMALL_CRACK: [&str; 7] = [
    "mesh.width=2e-3",
    "mesh.height=1e-3",
    "mesh.nx=32",
    "mesh.ny=16",
    "mesh.interface=[{from=[0.0,5e-4],to=[1e-3,5e-4],tag=\"notch\"}]",
    "time.end=0.9e-6",
    "output.png=false",
];

/// The shipped config `configs/NAME` with `overrides`, set up.
pub fn shipped(name: &str, overrides: &[&str]) -> Problem {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let loaded = LoadedConfig::load(&path, &overrides).expect("valid config");
    Problem::setup(LoadedConfig {
        file: name.into(),
        ..loaded
    })
    .expect("valid problem")
}

/// `c_d` (m/s) and `Z = rho c_d` of the shipped configs' PMMA (E = 3.24 GPa, nu = 0.35,
/// rho = 1190 kg/m^3) in plane strain, written out.
pub fn pmma_p_wave() -> (f64, f64) {
    let (e, nu, rho): (f64, f64, f64) = (3.24e9, 0.35, 1190.0);
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let c = ((lambda + 2.0 * mu) / rho).sqrt();
    (c, rho * c)
}

/// Checks a run loaded by incoming plane waves, ended before they reach anything: the load's
/// work equals the closed form `work` (J/m) within 1e-5, the travelling waves carry as much
/// kinetic as strain energy, and the energy balance closes to 1e-12.
pub fn assert_plane_wave_load(summary: &RunSummary, work: f64) {
    let energy = &summary.energy;
    eprintln!(
        "load's work {:.6e} J/m, closed form {work:.6e}",
        energy.boundary_work
    );
    assert!(
        (energy.boundary_work / work - 1.0).abs() < 1e-5,
        "{} J/m against {work} J/m",
        energy.boundary_work
    );
    assert!((energy.final_kinetic / energy.final_strain - 1.0).abs() < 1e-3);
    assert!(energy.balance_residual_rel.abs() < 1e-12, "{energy:?}");
}

/// `key=value` overrides from pairs.
pub fn set(pairs: &[(&str, String)]) -> Vec<String> {
    pairs.iter().map(|(k, v)| format!("{k}={v}")).collect()
}

use sdg_mesh::{Front, Mesh, Pitcher};
use sdg_solver::Material;
use sdg_solver::boundary::Boundary;
use sdg_solver::element::FrontSolution;
use sdg_solver::exact::PlaneWave;
use sdg_solver::interface::Interfaces;
use sdg_solver::patch::{ElementReport, Initial, Newton, PatchSolver};
use sdg_solver::system::System;

/// The state of a run driven directly through the solver API.
pub struct Direct {
    pub mesh: Mesh,
    pub system: System,
    pub solver: PatchSolver,
    pub solution: FrontSolution,
    pub front: Front,
    /// Sum of all patches' dissipation (scaled units).
    pub dissipation: f64,
    /// Sum of all patches' Newton iterations.
    pub newton_iterations: usize,
}

/// Solves `mesh` to `t_end` with `boundary`, initial data `initial` (rest if none) and order
/// `order`, calling `check` on every element report.
pub fn solve_direct(
    mesh: Mesh,
    material: &Material,
    boundary: &Boundary,
    initial: Option<&PlaneWave>,
    order: usize,
    t_end: f64,
    check: impl FnMut(&ElementReport),
) -> Direct {
    let none = Interfaces::default();
    solve_direct_with(
        mesh, material, boundary, &none, initial, order, t_end, check,
    )
}

/// [`solve_direct`] with interface laws.
#[allow(clippy::too_many_arguments)]
pub fn solve_direct_with(
    mesh: Mesh,
    material: &Material,
    boundary: &Boundary,
    interfaces: &Interfaces,
    initial: Option<&PlaneWave>,
    order: usize,
    t_end: f64,
    mut check: impl FnMut(&ElementReport),
) -> Direct {
    let system = System::new(material);
    let max_star = (0..mesh.vertices().len() as u32)
        .map(|v| mesh.vertex_triangles(v).len())
        .max()
        .unwrap();
    let mut solver = PatchSolver::new(system.clone(), order, max_star)
        .with_interfaces(interfaces.clone(), Newton::default());
    let solution = FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width())
        .with_edges(mesh.edges().len());
    let pitcher = Pitcher::new(&mesh, system.c_ref(), 0.9, t_end).unwrap();
    let front = Front::flat(mesh.vertices().len(), 0.0);
    let init = initial.map_or(Initial::Rest, Initial::Wave);
    let mut dissipation = 0.0;
    let mut newton_iterations = 0;
    sdg_engine::pitch_to_end(&mesh, &pitcher, &front, |tent, front| {
        let r = solver
            .solve(&mesh, front, tent, boundary, init, &solution)
            .expect("linear patches always solve");
        solver.commit(&solution);
        dissipation += r.dissipation;
        newton_iterations += r.newton_iterations;
        solver.element_reports().iter().for_each(&mut check);
    })
    .unwrap();
    Direct {
        mesh,
        system,
        solver,
        solution,
        front,
        dissipation,
        newton_iterations,
    }
}

/// True when `python3` can import meshio. Tests that read our files back with meshio skip
/// `check` without it, with a notice that shows even when the test passes, except under CI (`CI`
/// set, as `.ci/run` does), where a missing meshio fails the test.
pub fn meshio_available(check: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import meshio"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        assert!(std::env::var_os("CI").is_none(), "CI must install meshio");
        // Straight to stderr: the test harness captures `eprintln!` of passing tests.
        let notice = format!("skipped: {check} (python3 cannot import meshio)\n");
        std::io::stderr().write_all(notice.as_bytes()).unwrap();
    }
    ok
}

/// The numeric columns `names` of the CSV file `path` (header on the first line): one vector per
/// row, in the order of `names`; fields that are not numbers read as NaN.
pub fn csv_columns(path: &Path, names: &[&str]) -> Vec<Vec<f64>> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let header = reader.headers().unwrap().clone();
    let index: Vec<usize> = names
        .iter()
        .map(|n| header.iter().position(|h| h == *n).expect("column"))
        .collect();
    reader
        .records()
        .map(|row| {
            let row = row.unwrap();
            index
                .iter()
                .map(|&i| row[i].parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// Runs the Python `script` with `args` (`sys.argv[1..]`); returns its standard output.
pub fn python(script: &str, args: &[&Path]) -> String {
    let out = Command::new("python3")
        .args(["-c", script])
        .args(args)
        .output()
        .expect("python3 runs");
    assert!(out.status.success(), "{}", stderr(&out));
    String::from_utf8(out.stdout).unwrap()
}

/// Runs the `sdg` binary with `args`.
pub fn sdg(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sdg"))
        .args(args)
        .output()
        .expect("the sdg binary runs")
}

/// The `sdg run` arguments of the shipped config `name` (in `configs/`) with `overrides` and
/// `extra` arguments, quiet, writing into `out`.
pub fn run_args(name: &str, overrides: &[&str], extra: &[&str], out: &Path) -> Vec<String> {
    let config = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name);
    let mut args = vec!["run".to_string(), config.display().to_string()];
    args.push("--quiet".into());
    for o in overrides {
        args.extend(["--set".to_string(), o.to_string()]);
    }
    args.extend(extra.iter().map(|a| a.to_string()));
    args.extend(["--output".to_string(), out.display().to_string()]);
    args
}

/// The `summary.json` in `out`, parsed.
pub fn summary_json(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Runs the shipped config `name` with `overrides` and `extra` arguments into `out`
/// ([`run_args`]), asserting that it succeeds; returns its `summary.json`.
pub fn run_shipped(
    name: &str,
    overrides: &[&str],
    extra: &[&str],
    out: &Path,
) -> serde_json::Value {
    let args = run_args(name, overrides, extra, out);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = sdg(&args);
    assert!(result.status.success(), "{args:?}: {}", stderr(&result));
    summary_json(out)
}

/// The cells of the ASCII VTU files `paths` of snapshots, each as the text of its points'
/// coordinates and point values and its area, sorted: the same for the same slices in any
/// order and split among any files.
pub fn slices(paths: &[std::path::PathBuf]) -> Vec<String> {
    let mut all = Vec::new();
    for path in paths {
        let text = std::fs::read_to_string(path).unwrap();
        let at = text.find("NumberOfCells=\"").expect("a piece") + "NumberOfCells=\"".len();
        let cells: usize = text[at..].split('"').next().unwrap().parse().unwrap();
        // (values per cell, the values) of each array but the cells' connectivity.
        let mut arrays: Vec<(usize, Vec<&str>)> = Vec::new();
        for part in text.split("<DataArray ").skip(1) {
            let (attrs, rest) = part.split_once(">\n").unwrap();
            assert!(
                attrs.contains("format=\"ascii\""),
                "{}: ASCII",
                path.display()
            );
            if ["connectivity", "offsets", "types"]
                .iter()
                .any(|n| attrs.contains(&format!("Name=\"{n}\"")))
            {
                continue;
            }
            let values: Vec<&str> = rest
                .split("</DataArray>")
                .next()
                .unwrap()
                .split_whitespace()
                .collect();
            assert_eq!(values.len() % cells.max(1), 0, "{attrs}");
            arrays.push((values.len() / cells.max(1), values));
        }
        for c in 0..cells {
            let cell: Vec<&str> = (arrays.iter())
                .flat_map(|(n, values)| values[c * n..(c + 1) * n].iter().copied())
                .collect();
            all.push(cell.join(" "));
        }
    }
    all.sort();
    all
}

/// The cells of snapshot `index`'s pieces `STEM_NNNN_R.vtu` of a run over `ranks` ranks in
/// `out` (STEM `snapshot` or `cracks`), as [`slices`] reads them; checks that `STEM_NNNN.pvtu`
/// lists the pieces in rank order and that `snapshots.pvd` lists it.
pub fn pieces(out: &Path, stem: &str, index: usize, ranks: usize) -> Vec<String> {
    let names: Vec<String> = (0..ranks)
        .map(|r| format!("{stem}_{index:04}_{r}.vtu"))
        .collect();
    let pvtu = std::fs::read_to_string(out.join(format!("{stem}_{index:04}.pvtu"))).unwrap();
    let listed: Vec<&str> = (pvtu.split("<Piece Source=\"").skip(1))
        .map(|rest| rest.split('"').next().unwrap())
        .collect();
    assert_eq!(listed, names, "the pieces of {}", out.display());
    let pvd = std::fs::read_to_string(out.join("snapshots.pvd")).unwrap();
    assert!(
        pvd.contains(&format!("file=\"{stem}_{index:04}.pvtu\"")),
        "{pvd}"
    );
    slices(&names.iter().map(|n| out.join(n)).collect::<Vec<_>>())
}

/// The rows of `history.csv` in `out` as numbers.
pub fn history_rows(out: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    (text.lines().skip(1))
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

/// The standard error of a finished command, as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A small free plate (4 x 2 mm, 8 x 4 cells, to 0.1 us) that solves in well under a second.
pub const CONFIG: &str = r#"
[mesh]
kind = "rectangle"
width = 0.004
height = 0.002
nx = 8
ny = 4

[material]
young = 3.24e9
poisson = 0.35
density = 1190.0
plane = "strain"

[time]
end = 1e-7

[[boundary]]
sides = ["left", "right", "bottom", "top"]
kind = "free"
"#;

/// The checkpoint files (`*.sdgc`) in `dir`, sorted; none if it cannot be read.
pub fn checkpoints(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "sdgc"))
        .collect();
    files.sort();
    files
}
