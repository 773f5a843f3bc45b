//! What a solve starts from, and the estimate made from it.

use super::book::{Book, Milestones};
use super::context::{Intervention, Solve, initial_state};
use super::summary::Timings;
use super::work::deadline;
use crate::output::snapshot::Snapshots;
use crate::progress::Progress;
use crate::trace::Tracer;
use parking_lot::Mutex;
use sdg_mesh::{Front, Pitcher};
use sdg_solver::element::FrontSolution;
use sdg_solver::element::Geometry;
use sdg_solver::norms::front_energy;
use sdg_solver::patch::PatchReport;
use sdg_solver::patch::{Initial, Newton, PatchSolver};
use std::path::Path;
use std::sync::atomic::AtomicU64;
use std::time::Instant;

use crate::adaptivity::indicator::Adapt;
use crate::error::EngineError;
use crate::estimate::{self, Estimate};
use crate::frontier::Frontier;
use crate::job::RunOptions;
use crate::problem::Problem;

use crate::adaptivity::policy::refine_to_max_edge;

/// A patch solver for `problem` whose stars have at most `max_star` triangles.
pub(crate) fn patch_solver(problem: &Problem, max_star: usize) -> PatchSolver {
    let config = &problem.loaded.config;
    PatchSolver::new(problem.system.clone(), config.solver.order, max_star).with_interfaces(
        problem.interfaces.clone(),
        Newton {
            tol: config.solver.newton_tol,
            max_iter: config.solver.newton_max_iter,
        },
    )
}

/// What a solve starts from: the flat front at time 0 (refined to the zones' `max_edge`), with
/// crack tips, the adaptivity and the patch solvers' capacity.
pub(crate) struct Start {
    pub(crate) state: Frontier,
    pub(crate) adapt: Option<Adapt>,
    /// Triangles a vertex star may have.
    pub(crate) max_star: usize,
}

impl Start {
    pub(crate) fn new(problem: &Problem) -> Result<Self, EngineError> {
        let config = &problem.loaded.config;
        let mesh = &problem.mesh;
        let c_max = problem.material.max_wave_speed();
        let pitcher = Pitcher::new(mesh, c_max, config.pitch.safety, config.time.span())
            .map_err(|e| EngineError::Runtime(e.to_string()))?;
        let adapt = Adapt::new(&config.adapt, mesh, c_max, problem.material.density());
        // Crack alignment splits edges as refinement does.
        let splits = adapt.is_some() || problem.fracture.is_some();
        let pitcher = if splits {
            pitcher.for_refinement(mesh)
        } else {
            pitcher
        };
        let initial_star = (0..mesh.vertices().len() as u32)
            .map(|v| mesh.vertex_triangles(v).len())
            .max()
            .unwrap_or(0);
        // Bisection adds triangles to stars; the solvers are sized once, and refinement never
        // grows a star beyond them.
        let max_star = if splits {
            (2 * initial_star).max(12)
        } else {
            initial_star
        };
        let (n, width) = {
            let solver = PatchSolver::new(problem.system.clone(), config.solver.order, 0);
            (solver.basis().len(), solver.width())
        };
        let mut state = Frontier::new(
            mesh.clone(),
            Front::flat(mesh.vertices().len(), 0.0),
            FrontSolution::new(mesh.triangles().len(), n, width).with_edges(mesh.edges().len()),
            pitcher,
        );
        if let Some(adapt) = &adapt {
            // The config asks for what the mesh cannot give: bad input (exit 2).
            refine_to_max_edge(&mut state, adapt, max_star).map_err(|reason| {
                EngineError::Input(format!("{}: {reason}", problem.loaded.file.display()))
            })?;
        }
        if let Some(fracture) = &problem.fracture {
            state.tips = fracture.initial_tips(&state.mesh);
            state.next_branch = state.tips.iter().flatten().count() as u32;
        }
        Ok(Self {
            state,
            adapt,
            max_star,
        })
    }
}

impl Frontier {
    /// The estimate of a solve from this (initial) state on `threads`; `adapts` when
    /// refinement is on.
    pub(crate) fn estimate(
        &self,
        problem: &Problem,
        max_star: usize,
        threads: usize,
        adapts: bool,
    ) -> Estimate {
        let start = estimate::Start {
            mesh: &self.mesh,
            pitcher: &self.pitcher,
            solution: &self.solution,
            initial: problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave),
            new_solver: || patch_solver(problem, max_star),
        };
        estimate::solve(
            problem,
            start,
            threads,
            adapts || problem.fracture.is_some(),
        )
    }
}

/// The estimate of `sdg run` for `problem` with `options`, made as the run makes it before
/// any work (`sdg validate`).
pub fn estimate_job(problem: &Problem, options: &RunOptions) -> Result<Estimate, EngineError> {
    let start = Start::new(problem)?;
    let threads = options.scheduler(problem).threads;
    Ok(start
        .state
        .estimate(problem, start.max_star, threads, start.adapt.is_some()))
}

impl<'a> Solve<'a> {
    /// The context of a solve of `problem` from the initial `start` (its front, adaptivity and
    /// star capacity) on `threads` workers, writing into `dir`; `intervention` is the change of
    /// [`super::run::solve_job_with`] and when it applies (s since `time.start`).
    pub(crate) fn new(
        problem: &'a Problem,
        options: &RunOptions,
        (state, adapt, max_star): (&Frontier, Option<Adapt>, usize),
        threads: usize,
        dir: &Path,
        (after, intervention): (Option<f64>, Option<Intervention>),
    ) -> Self {
        let config = &problem.loaded.config;
        let system = &problem.system;
        let c_max = problem.material.max_wave_speed();
        let t_end = config.time.span();
        let snapshot_times: Vec<f64> = (config.output.snapshot_times.iter())
            .map(|&t| config.time.elapsed(t))
            .collect();
        let (basis, width) = {
            let solver = PatchSolver::new(system.clone(), config.solver.order, 0);
            (solver.basis().clone(), solver.width())
        };
        let initial = problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave);
        let energy0 = front_energy(
            &state.mesh,
            &state.front,
            &state.solution,
            &basis,
            system,
            threads,
            |x| initial_state(problem, initial, x),
        );
        let min_edge = problem
            .loaded
            .config
            .fracture
            .as_ref()
            .and_then(|f| f.min_piece)
            .unwrap_or_else(|| {
                adapt
                    .as_ref()
                    .map_or(problem.mesh.edge_length_range().0 / 4.0, |a| a.min_edge)
            });
        Solve {
            problem,
            adapt,
            max_star,
            threads,
            min_edge,
            snapshot_times: snapshot_times.clone(),
            energy_reference: AtomicU64::new(energy0.total.to_bits()),
            initial,
            basis: basis.clone(),
            width,
            book: Mutex::new(Book {
                totals: PatchReport::default(),
                patches: 0,
                rejected: 0,
                refinements: 0,
                coarsenings: 0,
                unresolved: 0,
                unresolved_max: 0.0,
                samples: Vec::new(),
                crossings: Vec::new(),
                fracture_events: Vec::new(),
                nonlinear_patches: 0,
                newton_iterations: 0,
                newton_max: 0,
                initial_energy: energy0.total,
                energy_max: energy0.total,
                elements: 0,
                dofs: 0,
                max_slope_ratio: 0.0,
                timings: Timings::default(),
                snapshots: Snapshots::on_clock(
                    &config.output.snapshot_times,
                    config.time.start,
                    c_max,
                    // Absolute, so that a restart from another working directory finds the files.
                    std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf()),
                )
                .with_png(config.output.png)
                .with_vtu(config.output.vtu),
                milestones: Milestones::new(
                    state.mesh.vertices().len(),
                    t_end,
                    &snapshot_times,
                    config.checkpoint.every_sim_s,
                    after,
                ),
                passed: Vec::new(),
                history: super::history::history_header(),
                progress: Progress::new(
                    options.progress,
                    state.mesh.vertices().len() as f64 * t_end,
                ),
                phi: vec![0.0; basis.len()],
                values: vec![0.0; width],
                geometry: Geometry::default(),
                coefficients: vec![0.0; basis.len() * width],
            }),
            intervention: Mutex::new(intervention),
            control: options.control.clone().unwrap_or_default(),
            deadline: deadline(config.limits.max_wall_time_s, options.max_wall_time_s),
            started: Instant::now(),
            next_wall_checkpoint_ns: AtomicU64::new(u64::MAX),
            tracer: options.trace.as_ref().map(|_| Tracer::new()),
            split: None,
        }
    }
}
