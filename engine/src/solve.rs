//! `sdg run`: the SDG solve, tents pitched and solved by the scheduler's workers.
//!
//! Each worker owns a [`PatchSolver`] (its scratch memory). A tent pitches on the shared front,
//! solves its patch and hands a [`PatchReport`] to the bookkeeping ([`Book`]), which sums energy
//! terms, cuts snapshots and notices when the whole front has passed a milestone time: a
//! snapshot is then complete, or a history row is due. History rows integrate the energy over the
//! whole front, so they run as scheduler events over every vertex: with no tent in flight.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use parking_lot::Mutex;
use serde::Serialize;

use sdg_mesh::{Front, Pitcher};
use sdg_scheduler::{Events, VertexId, Work};
use sdg_solver::element::{FrontSolution, Geometry, evaluate};
use sdg_solver::norms::{FrontEnergy, front_energy, slice_errors};
use sdg_solver::patch::{Initial, PatchReport, PatchSolver};
use sdg_solver::system::{MAX_FIELDS, State};
use sdg_solver::{Material, Plane};

use crate::error::EngineError;
use crate::output::write_atomic;
use crate::problem::Problem;
use crate::progress::Progress;
use crate::run::{RunOptions, scheduler_error};
use crate::snapshot::{PointValues, Snapshots};

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

/// `summary.json` of `sdg run`. In deterministic mode every field but `wall_time_s`,
/// `patches_per_second` and `threads` is the same for any thread count.
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
    /// `"deterministic"` or `"asynchronous"`.
    pub mode: &'static str,
    /// FNV-1a hash of the final front: vertex times, then every element's geometry and
    /// coefficients, as hexadecimal. Equal hashes mean bitwise equal final states.
    pub state_hash: String,
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

/// History rows are written when the whole front has passed each of this many equal fractions
/// of the end time (and at the end).
const HISTORY_ROWS: usize = 100;

/// Times the whole front must pass before something happens, with a count of the vertices whose
/// recorded time is still below each.
#[derive(Debug)]
struct Milestones {
    /// Increasing times (s) and what they are for.
    times: Vec<(f64, Milestone)>,
    below: Vec<usize>,
    next: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Milestone {
    History,
    Snapshot,
}

impl Milestones {
    fn new(vertices: usize, t_end: f64, snapshots: &[f64]) -> Self {
        let mut times: Vec<(f64, Milestone)> = (1..HISTORY_ROWS)
            .map(|k| (t_end * k as f64 / HISTORY_ROWS as f64, Milestone::History))
            .chain(snapshots.iter().map(|&t| (t, Milestone::Snapshot)))
            .collect();
        times.sort_by(|a, b| a.0.total_cmp(&b.0));
        let below = times
            .iter()
            .map(|&(t, _)| if t > 0.0 { vertices } else { 0 })
            .collect();
        Self {
            times,
            below,
            next: 0,
        }
    }

    /// Records a vertex moving from `t_old` to `t_new`; returns the milestones the whole front
    /// has now passed, in order.
    fn advance(&mut self, t_old: f64, t_new: f64, passed: &mut Vec<(f64, Milestone)>) {
        let first = self.times.partition_point(|&(t, _)| t <= t_old);
        for i in first..self.times.len() {
            if self.times[i].0 > t_new {
                break;
            }
            self.below[i] -= 1;
        }
        while self.next < self.times.len() && self.below[self.next] == 0 {
            passed.push(self.times[self.next]);
            self.next += 1;
        }
    }
}

/// Everything recorded across tents, behind one lock.
#[derive(Debug)]
struct Book {
    totals: PatchReport,
    patches: u64,
    elements: u64,
    dofs: u64,
    max_slope_ratio: f64,
    snapshots: Snapshots,
    milestones: Milestones,
    passed: Vec<(f64, Milestone)>,
    history: String,
    progress: Progress,
    /// Basis values and element values for snapshot evaluation, and an element copy.
    phi: Vec<f64>,
    values: Vec<f64>,
    geometry: Geometry,
    coefficients: Vec<f64>,
}

/// The shared state of a solve.
struct Solve<'a> {
    problem: &'a Problem,
    pitcher: &'a Pitcher,
    front: &'a Front,
    solution: &'a FrontSolution,
    initial: Initial<'a>,
    energy0: FrontEnergy,
    /// Basis of every element (each worker's solver has the same).
    basis: sdg_solver::basis::Basis,
    book: Mutex<Book>,
}

/// The scaled initial state at `x`.
fn initial_state(problem: &Problem, initial: Initial, x: [f64; 2]) -> State {
    match initial {
        Initial::Wave(w) => problem.system.to_scaled(&w.state(x, 0.0)),
        Initial::Rest => [0.0; MAX_FIELDS],
    }
}

impl Solve<'_> {
    /// Appends a `history.csv` row for the current front: it must not move meanwhile.
    fn history_row(&self, book: &mut Book) {
        let system = &self.problem.system;
        let rho = self.problem.material.density();
        let e = front_energy(
            &self.problem.mesh,
            self.front,
            self.solution,
            &self.basis,
            system,
            |x| initial_state(self.problem, self.initial, x),
        );
        let totals = &book.totals;
        let balance = self.energy0.total + totals.boundary_work - e.total - totals.dissipation;
        let _ = writeln!(
            book.history,
            "{:e},{},{:e},{:e},{:e},{:e},{:e},{:e}",
            self.front.min_time(),
            book.patches,
            rho * e.total,
            rho * e.kinetic,
            rho * e.strain,
            rho * totals.boundary_work,
            rho * totals.dissipation,
            rho * balance
        );
    }
}

/// What one tent hands to the bookkeeping.
#[derive(Debug)]
struct Outcome {
    t_old: f64,
    t_new: f64,
    report: PatchReport,
}

impl<'a> Work<'a> for Solve<'a> {
    type Scratch = PatchSolver;
    type Outcome = Outcome;
    type Error = EngineError;

    fn tent(
        &self,
        solver: &mut PatchSolver,
        v: VertexId,
        _: &Events<'a>,
    ) -> Result<(f64, Outcome), EngineError> {
        let mesh = &self.problem.mesh;
        let tent = self.pitcher.pitch(mesh, self.front, v).ok_or_else(|| {
            EngineError::Runtime(format!("vertex {v} was claimed but cannot be pitched"))
        })?;
        let report = solver.solve(
            mesh,
            self.front,
            &tent,
            &self.problem.boundary,
            self.initial,
            self.solution,
        );
        let outcome = Outcome {
            t_old: tent.t_old,
            t_new: tent.t_new,
            report,
        };
        Ok((tent.t_new, outcome))
    }

    fn record(&'a self, v: VertexId, o: Outcome, events: &Events<'a>) -> Result<(), EngineError> {
        let mesh = &self.problem.mesh;
        let c_max = self.pitcher.c_max();
        let slope = mesh
            .vertex_triangles(v)
            .iter()
            .map(|&t| c_max * self.front.slope(mesh, t))
            .fold(0.0, f64::max);
        let mut guard = self.book.lock();
        let book = &mut *guard;
        book.patches += 1;
        book.elements += o.report.elements as u64;
        book.dofs += o.report.dofs as u64;
        book.totals.energy_in += o.report.energy_in;
        book.totals.energy_out += o.report.energy_out;
        book.totals.boundary_work += o.report.boundary_work;
        book.totals.dissipation += o.report.dissipation;
        book.max_slope_ratio = book.max_slope_ratio.max(slope);
        for &t in mesh.vertex_triangles(v) {
            if self
                .solution
                .load(t as usize, &mut book.geometry, &mut book.coefficients)
            {
                let (phi, values, geometry, coefficients) = (
                    &mut book.phi,
                    &mut book.values,
                    &book.geometry,
                    &book.coefficients,
                );
                book.snapshots.add_element(&geometry.vertices(), |x| {
                    point_values(
                        &self.problem.material,
                        self,
                        geometry,
                        coefficients,
                        x,
                        phi,
                        values,
                    )
                });
            }
        }
        book.progress.advance(o.t_new - o.t_old, book.patches);
        let mut passed = std::mem::take(&mut book.passed);
        book.milestones.advance(o.t_old, o.t_new, &mut passed);
        for &(t, _) in passed.iter().filter(|p| p.1 == Milestone::Snapshot) {
            book.snapshots.flush(t)?;
        }
        // One row for however many history milestones passed at once.
        if passed.iter().any(|p| p.1 == Milestone::History) {
            let all: Vec<VertexId> = (0..mesh.vertices().len() as VertexId).collect();
            events.push(
                all,
                Box::new(move || self.history_row(&mut self.book.lock())),
            );
        }
        passed.clear();
        book.passed = passed;
        Ok(())
    }
}

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
    let dir = options.output_dir(problem)?;
    let scheduler = options.scheduler(problem);

    let max_star = (0..mesh.vertices().len() as u32)
        .map(|v| mesh.vertex_triangles(v).len())
        .max()
        .unwrap_or(0);
    let solvers: Vec<PatchSolver> = (0..scheduler.threads)
        .map(|_| PatchSolver::new(system.clone(), config.solver.order, max_star))
        .collect();
    let (basis, width) = (solvers[0].basis().clone(), solvers[0].width());
    let solution = FrontSolution::new(mesh.triangles().len(), basis.len(), width);
    let initial = problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave);
    let front = Front::flat(mesh.vertices().len(), 0.0);
    let energy0 = front_energy(mesh, &front, &solution, &basis, system, |x| {
        initial_state(problem, initial, x)
    });
    let solve = Solve {
        problem,
        pitcher: &pitcher,
        front: &front,
        solution: &solution,
        initial,
        energy0,
        basis: basis.clone(),
        book: Mutex::new(Book {
            totals: PatchReport::default(),
            patches: 0,
            elements: 0,
            dofs: 0,
            max_slope_ratio: 0.0,
            snapshots: Snapshots::new(&config.output.snapshot_times, c_max, dir.clone()),
            milestones: Milestones::new(
                mesh.vertices().len(),
                t_end,
                &config.output.snapshot_times,
            ),
            passed: Vec::new(),
            history: String::from(
                "time_s,patches,front_energy_j,kinetic_j,strain_j,boundary_work_j,dissipation_j,\
                 balance_residual_j\n",
            ),
            progress: Progress::new(options.progress, mesh.vertices().len() as f64 * t_end),
            phi: vec![0.0; basis.len()],
            values: vec![0.0; width],
            geometry: Geometry::default(),
            coefficients: vec![0.0; basis.len() * width],
        }),
    };
    solve.history_row(&mut solve.book.lock());
    let _span = tracing::info_span!("solve", config = %problem.loaded.file.display()).entered();
    tracing::info!(
        threads = scheduler.threads,
        deterministic = scheduler.deterministic,
        order = config.solver.order,
        vertices = mesh.vertices().len(),
        "solve started"
    );
    let start = Instant::now();
    let stats = sdg_scheduler::run(mesh, &front, t_end, &solve, solvers, &scheduler)
        .map_err(scheduler_error)?;
    let wall_time_s = start.elapsed().as_secs_f64();
    let mut book = solve.book.lock();
    book.progress.finish();
    solve.history_row(&mut book);
    book.snapshots.flush(t_end)?;
    tracing::info!(patches = stats.tents, wall_time_s, "solve finished");

    let e = front_energy(mesh, &front, &solution, &basis, system, |x| {
        initial_state(problem, initial, x)
    });
    let initial_j = rho * solve.energy0.total;
    let work = rho * book.totals.boundary_work;
    let dissipation = rho * book.totals.dissipation;
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
        let e = slice_errors(mesh, &solution, &basis, system, t_end, w);
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
        patches: book.patches,
        elements: book.elements,
        dofs_per_patch: book.dofs as f64 / book.patches.max(1) as f64,
        final_time: front.min_time(),
        max_slope_ratio: book.max_slope_ratio,
        mode: if scheduler.deterministic {
            "deterministic"
        } else {
            "asynchronous"
        },
        state_hash: state_hash(&front, &solution, basis.len() * width),
        wall_time_s,
        patches_per_second: book.patches as f64 / wall_time_s.max(f64::MIN_POSITIVE),
        threads: scheduler.threads,
        energy,
        error,
        snapshots: book.snapshots.written().to_vec(),
    };
    write_atomic(&dir, "history.csv", book.history.as_bytes())?;
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_atomic(&dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir))
}

/// FNV-1a over the bits of the front times and of every element under the front.
fn state_hash(front: &Front, solution: &FrontSolution, size: usize) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |x: f64| {
        for byte in x.to_bits().to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for t in front.snapshot() {
        feed(t);
    }
    let mut geometry = Geometry::default();
    let mut coefficients = vec![0.0; size];
    for t in 0..solution.len() {
        if solution.load(t, &mut geometry, &mut coefficients) {
            geometry.vertices().iter().flatten().for_each(|&x| feed(x));
            coefficients.iter().for_each(|&x| feed(x));
        }
    }
    format!("{hash:016x}")
}

/// Physical field values of an element at the scaled point `x` for snapshots.
fn point_values(
    material: &Material,
    solve: &Solve<'_>,
    geometry: &Geometry,
    coefficients: &[f64],
    x: [f64; 3],
    phi: &mut [f64],
    values: &mut [f64],
) -> PointValues {
    let system = &solve.problem.system;
    evaluate(&solve.basis, geometry, coefficients, x, phi, values);
    let fields = system.fields();
    let mut q = [0.0; MAX_FIELDS];
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn milestones_pass_when_every_vertex_has() {
        let mut m = Milestones::new(2, 1.0, &[0.0, 0.5]);
        let mut passed = Vec::new();
        m.advance(0.0, 0.3, &mut passed);
        assert_eq!(passed, [(0.0, Milestone::Snapshot)], "t = 0 passes at once");
        passed.clear();
        m.advance(0.0, 0.6, &mut passed);
        // Both vertices are now at 0.3 or later: history milestones 0.01 to 0.3 pass.
        assert_eq!(passed.len(), 30);
        assert!(
            passed
                .iter()
                .all(|&(t, w)| w == Milestone::History && t <= 0.3)
        );
        passed.clear();
        m.advance(0.3, 0.7, &mut passed);
        assert_eq!(passed.len(), 31, "0.31 to 0.6 and the snapshot at 0.5");
        assert_eq!(
            passed.iter().filter(|p| p.1 == Milestone::Snapshot).count(),
            1
        );
        assert_eq!(passed.last().map(|p| p.0), Some(0.6));
    }
}
