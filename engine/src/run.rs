//! The run loop: pitching tents from the initial front to the end time, and the commands built
//! on it.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use sdg_mesh::{Front, Mesh, Pitcher, Tent};
use sdg_solver::element::{FrontSolution, Geometry, evaluate};
use sdg_solver::norms::{FrontEnergy, front_energy, slice_errors};
use sdg_solver::patch::{Initial, PatchReport, PatchSolver};
use sdg_solver::{Material, Plane};

use crate::error::EngineError;
use crate::output::write_atomic;
use crate::problem::Problem;
use crate::snapshot::{PointValues, Snapshots};
use crate::spacetime::SpacetimeMesh;

/// Command-line choices that are not part of the configuration.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output folder; overrides `output.dir`.
    pub output_dir: Option<PathBuf>,
}

/// Pitches tents on `front` until every vertex reaches the pitcher's end time, calling
/// `on_tent` after each tent with the advanced front. Returns the number of tents.
pub fn pitch_to_end(
    mesh: &Mesh,
    pitcher: &Pitcher,
    front: &mut Front,
    mut on_tent: impl FnMut(&Tent, &Front),
) -> Result<u64, EngineError> {
    let initial = front.times().to_vec();
    let stats = sdg_scheduler::run_serial(&initial, pitcher.t_end(), |v| {
        let tent = pitcher.pitch(mesh, front, v).ok_or_else(|| {
            EngineError::Runtime(format!("vertex {v} was scheduled but cannot be pitched"))
        })?;
        on_tent(&tent, front);
        Ok(tent.t_new)
    })
    .map_err(|e| match e {
        sdg_scheduler::RunError::Pitch(e) => e,
        stalled => EngineError::Runtime(stalled.to_string()),
    })?;
    Ok(stats.tents)
}

/// `summary.json` of `sdg mesh`.
#[derive(Clone, Debug, Serialize)]
pub struct MeshSummary {
    /// `"mesh"`.
    pub command: &'static str,
    /// The config file.
    pub config_file: PathBuf,
    /// Space mesh vertices.
    pub vertices: usize,
    /// Space mesh triangles.
    pub triangles: usize,
    /// Shortest space edge, m.
    pub min_edge: f64,
    /// Longest space edge, m.
    pub max_edge: f64,
    /// Fastest wave speed the front is causal for, m/s.
    pub c_max: f64,
    /// The configured safety factor.
    pub safety: f64,
    /// Tents pitched.
    pub tents: u64,
    /// Spacetime tetrahedra built (one per triangle of each tent's star).
    pub tetrahedra: u64,
    /// Earliest front time at the end, s: equals `time.end`.
    pub final_time: f64,
    /// Maximum over all front facets ever built of `c_max |grad tau|`; below `safety`.
    pub max_slope_ratio: f64,
    /// Wall-clock time of pitching, s.
    pub wall_time_s: f64,
    /// Worker threads used.
    pub threads: usize,
}

/// `sdg mesh`: pitches tents to the end time without solving, writes `summary.json` and, when
/// `output.spacetime_mesh` is set, `spacetime.vtu`. Returns the summary and the output folder.
pub fn mesh_job(
    problem: &Problem,
    options: &RunOptions,
) -> Result<(MeshSummary, PathBuf), EngineError> {
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let c_max = problem.material.max_wave_speed();
    let pitcher = Pitcher::new(mesh, c_max, config.pitch.safety, config.time.end)
        .map_err(|e| EngineError::Runtime(e.to_string()))?;
    let dir = options
        .output_dir
        .clone()
        .unwrap_or_else(|| config.output.dir.clone());
    std::fs::create_dir_all(&dir).map_err(|e| EngineError::io(&dir, e))?;

    let mut front = Front::flat(mesh.vertices().len(), 0.0);
    let mut spacetime = config
        .output
        .spacetime_mesh
        .then(|| SpacetimeMesh::new(mesh, &front));
    let mut tetrahedra = 0u64;
    let mut max_slope_ratio: f64 = 0.0;
    let start = Instant::now();
    let tents = pitch_to_end(mesh, &pitcher, &mut front, |tent, front| {
        let star = mesh.vertex_triangles(tent.vertex);
        tetrahedra += star.len() as u64;
        for &t in star {
            max_slope_ratio = max_slope_ratio.max(c_max * front.slope(mesh, t));
        }
        if let Some(s) = spacetime.as_mut() {
            s.add_tent(mesh, tent);
        }
    })?;
    let wall_time_s = start.elapsed().as_secs_f64();
    let (min_edge, max_edge) = mesh.edge_length_range();
    let summary = MeshSummary {
        command: "mesh",
        config_file: problem.loaded.file.clone(),
        vertices: mesh.vertices().len(),
        triangles: mesh.triangles().len(),
        min_edge,
        max_edge,
        c_max,
        safety: config.pitch.safety,
        tents,
        tetrahedra,
        final_time: front.min_time(),
        max_slope_ratio,
        wall_time_s,
        threads: 1,
    };
    if let Some(s) = spacetime {
        write_atomic(&dir, "spacetime.vtu", s.to_grid(c_max).to_vtu().as_bytes())?;
    }
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_atomic(&dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir))
}

/// Energy totals of a run, J per metre of thickness.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct EnergySummary {
    /// Kinetic plus strain energy at t = 0.
    pub initial: f64,
    /// Kinetic energy on the final (flat) front.
    pub final_kinetic: f64,
    /// Strain energy on the final front.
    pub final_strain: f64,
    /// Total energy on the final front.
    pub r#final: f64,
    /// Work done on the body through the domain boundary.
    pub boundary_work: f64,
    /// Numerical dissipation of all elements (each non-negative).
    pub dissipation: f64,
    /// `(initial + boundary_work - final - dissipation) / (initial + |boundary_work|)`.
    pub balance_residual_rel: f64,
}

/// Relative L2 errors at the end time against the exact solution.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ErrorSummary {
    /// `||v - v_exact|| / ||v_exact||` on the final slice.
    pub velocity_l2_rel: f64,
    /// `||sigma - sigma_exact|| / ||sigma_exact||` on the final slice.
    pub stress_l2_rel: f64,
}

/// `summary.json` of `sdg run`.
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// `"run"`.
    pub command: &'static str,
    /// The config file.
    pub config_file: PathBuf,
    /// Space mesh vertices.
    pub vertices: usize,
    /// Space mesh triangles.
    pub triangles: usize,
    /// Polynomial order.
    pub order: usize,
    /// Tents pitched and patches solved.
    pub patches: u64,
    /// Spacetime elements solved.
    pub elements: u64,
    /// Mean unknowns per patch linear system.
    pub dofs_per_patch: f64,
    /// End time reached, s.
    pub final_time: f64,
    /// Maximum `c_max |grad tau|` over all front facets.
    pub max_slope_ratio: f64,
    /// Wall-clock time of the solve, s.
    pub wall_time_s: f64,
    /// Patches per second of wall-clock time.
    pub patches_per_second: f64,
    /// Worker threads used.
    pub threads: usize,
    /// Energy accounting.
    pub energy: EnergySummary,
    /// Errors against `[exact]`, when configured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorSummary>,
    /// Snapshot files written: `[time s, file]`.
    pub snapshots: Vec<(f64, String)>,
}

/// Rows of `history.csv` are written when the front's earliest time passes each of this many
/// equal fractions of the end time.
const HISTORY_ROWS: usize = 100;

/// `sdg run`: solves the problem to the end time; writes `summary.json`, `history.csv` and the
/// configured snapshots. Returns the summary and the output folder.
pub fn solve_job(
    problem: &Problem,
    options: &RunOptions,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let system = &problem.system;
    let c_max = problem.material.max_wave_speed();
    let rho = problem.material.density();
    let t_end = config.time.end;
    let pitcher = Pitcher::new(mesh, c_max, config.pitch.safety, t_end)
        .map_err(|e| EngineError::Runtime(e.to_string()))?;
    let dir = options
        .output_dir
        .clone()
        .unwrap_or_else(|| config.output.dir.clone());
    std::fs::create_dir_all(&dir).map_err(|e| EngineError::io(&dir, e))?;

    let max_star = (0..mesh.vertices().len() as u32)
        .map(|v| mesh.vertex_triangles(v).len())
        .max()
        .unwrap_or(0);
    let mut solver = PatchSolver::new(system.clone(), config.solver.order, max_star);
    let mut solution =
        FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width());
    let initial = match &problem.exact {
        Some(w) => Initial::Wave(w),
        None => Initial::Rest,
    };
    let initial_state = |x: [f64; 2]| match &problem.exact {
        Some(w) => system.to_scaled(&w.state(x, 0.0)),
        None => [0.0; sdg_solver::system::MAX_FIELDS],
    };
    let mut front = Front::flat(mesh.vertices().len(), 0.0);
    let energy0 = front_energy(
        mesh,
        front.times(),
        &solution,
        solver.basis(),
        system,
        initial_state,
    );
    let mut snapshots = Snapshots::new(&config.output.snapshot_times, c_max, dir.clone());
    let mut scratch = (vec![0.0; solver.basis().len()], vec![0.0; solver.width()]);
    let solver_basis = &solver.basis().clone();

    let mut history = String::from(
        "time_s,patches,front_energy_j,kinetic_j,strain_j,boundary_work_j,dissipation_j,balance_residual_j\n",
    );
    let mut totals = PatchReport::default();
    let (mut patches, mut elements, mut dofs) = (0u64, 0u64, 0u64);
    let mut max_slope_ratio: f64 = 0.0;
    let mut next_row = 0usize;
    let mut pending: Result<(), EngineError> = Ok(());
    let start = Instant::now();
    history_row_text(
        &mut history,
        0.0,
        0,
        &PatchReport::default(),
        energy0,
        energy0,
        rho,
    );
    let mut history_row =
        |t, patches, totals: &PatchReport, front: &Front, solution: &FrontSolution| {
            let e = front_energy(
                mesh,
                front.times(),
                solution,
                solver_basis,
                system,
                initial_state,
            );
            history_row_text(&mut history, t, patches, totals, energy0, e, rho);
        };
    pitch_to_end(mesh, &pitcher, &mut front, |tent, front| {
        // The serial scheduler pitches the earliest vertex, so `t_old` is the front's minimum
        // and every snapshot at or before it is complete.
        if pending.is_ok() {
            pending = snapshots.flush(tent.t_old).map(drop);
        }
        let report = solver.solve(
            mesh,
            front.times(),
            tent,
            &problem.boundary,
            initial,
            &mut solution,
        );
        patches += 1;
        elements += report.elements as u64;
        dofs += report.dofs as u64;
        totals.energy_in += report.energy_in;
        totals.energy_out += report.energy_out;
        totals.boundary_work += report.boundary_work;
        totals.dissipation += report.dissipation;
        for &t in mesh.vertex_triangles(tent.vertex) {
            max_slope_ratio = max_slope_ratio.max(c_max * front.slope(mesh, t));
            let (geometry, coefficients) = solution.element(t as usize).expect("just solved");
            snapshots.add_element(&geometry.vertices(), |x| {
                point_values(
                    &problem.material,
                    &solver,
                    geometry,
                    coefficients,
                    x,
                    &mut scratch,
                )
            });
        }
        // The earliest front time is at least `t_old`; rows are rare, so the exact minimum is
        // worth its O(N) scan.
        if next_row < HISTORY_ROWS && tent.t_old >= t_end * next_row as f64 / HISTORY_ROWS as f64 {
            history_row(front.min_time(), patches, &totals, front, &solution);
            while tent.t_old >= t_end * next_row as f64 / HISTORY_ROWS as f64 {
                next_row += 1;
            }
        }
    })?;
    pending?;
    let wall_time_s = start.elapsed().as_secs_f64();
    history_row(t_end, patches, &totals, &front, &solution);
    snapshots.flush(t_end)?;

    let e = front_energy(
        mesh,
        front.times(),
        &solution,
        solver.basis(),
        system,
        initial_state,
    );
    let initial_j = rho * energy0.total;
    let work = rho * totals.boundary_work;
    let dissipation = rho * totals.dissipation;
    let final_j = rho * e.total;
    let energy = EnergySummary {
        initial: initial_j,
        final_kinetic: rho * e.kinetic,
        final_strain: rho * e.strain,
        r#final: final_j,
        boundary_work: work,
        dissipation,
        balance_residual_rel: (initial_j + work - final_j - dissipation)
            / (initial_j + work.abs()).max(f64::MIN_POSITIVE),
    };
    let error = problem.exact.as_ref().map(|w| {
        let e = slice_errors(mesh, &solution, solver.basis(), system, t_end, w);
        ErrorSummary {
            velocity_l2_rel: e.velocity,
            stress_l2_rel: e.stress,
        }
    });
    let summary = RunSummary {
        command: "run",
        config_file: problem.loaded.file.clone(),
        vertices: mesh.vertices().len(),
        triangles: mesh.triangles().len(),
        order: config.solver.order,
        patches,
        elements,
        dofs_per_patch: dofs as f64 / patches.max(1) as f64,
        final_time: front.min_time(),
        max_slope_ratio,
        wall_time_s,
        patches_per_second: patches as f64 / wall_time_s.max(f64::MIN_POSITIVE),
        threads: 1,
        energy,
        error,
        snapshots: snapshots.written().to_vec(),
    };
    write_atomic(&dir, "history.csv", history.as_bytes())?;
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_atomic(&dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir))
}

/// Physical field values of an element at the scaled point `x` for snapshots; `scratch` holds
/// the basis values and the element's values.
fn point_values(
    material: &Material,
    solver: &PatchSolver,
    geometry: &Geometry,
    coefficients: &[f64],
    x: [f64; 3],
    (phi, values): &mut (Vec<f64>, Vec<f64>),
) -> PointValues {
    let system = solver.system();
    evaluate(solver.basis(), geometry, coefficients, x, phi, values);
    let fields = system.fields();
    let mut q = [0.0; sdg_solver::system::MAX_FIELDS];
    q[..fields].copy_from_slice(&values[..fields]);
    let strain_energy_density =
        material.density() * (system.energy_density(&q) - system.kinetic_density(&q));
    let p = system.to_physical(&q);
    let u = &values[fields..];
    match material.plane() {
        Plane::Antiplane => PointValues {
            velocity: [0.0, 0.0, p[0]],
            stress: [0.0, 0.0, 0.0, 0.0, p[2], p[1]],
            displacement: [0.0, 0.0, u[0]],
            strain_energy_density,
        },
        plane => {
            let szz = if plane == Plane::Strain {
                material.poisson() * (p[2] + p[3])
            } else {
                0.0
            };
            PointValues {
                velocity: [p[0], p[1], 0.0],
                stress: [p[2], p[3], szz, p[4], 0.0, 0.0],
                displacement: [u[0], u[1], 0.0],
                strain_energy_density,
            }
        }
    }
}

/// Appends one `history.csv` row: time (s), patches, then energies in J/m (physical: `rho` times
/// the scaled values), the last being `initial + work - front - dissipation`.
fn history_row_text(
    out: &mut String,
    t: f64,
    patches: u64,
    totals: &PatchReport,
    initial: FrontEnergy,
    front: FrontEnergy,
    rho: f64,
) {
    let balance = initial.total + totals.boundary_work - front.total - totals.dissipation;
    let _ = writeln!(
        out,
        "{t:e},{patches},{:e},{:e},{:e},{:e},{:e},{:e}",
        rho * front.total,
        rho * front.kinetic,
        rho * front.strain,
        rho * totals.boundary_work,
        rho * totals.dissipation,
        rho * balance
    );
}
