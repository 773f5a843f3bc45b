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

use std::sync::atomic::{AtomicU64, Ordering};

use sdg_mesh::{Front, Pitcher, Tent, TriangleId};
use sdg_scheduler::{Changed, Events, VertexId, Work};
use sdg_solver::element::{FrontSolution, Geometry, evaluate};
use sdg_solver::norms::{front_energy, initial_energy, slice_errors};
use sdg_solver::patch::{Initial, PatchReport, PatchSolver};
use sdg_solver::system::{MAX_FIELDS, State};
use sdg_solver::{Material, Plane};

use crate::adapt::Adapt;
use crate::error::EngineError;
use crate::frontier::{Coarsening, Frontier, Refined, refinement_edge_length};
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
    /// Work absorbed by interfaces (contact, free): the power their targets take out of the
    /// elements on both sides, integrated.
    pub interface_work: f64,
    /// Part of `interface_work` done by tangential tractions on tangential velocity jumps.
    pub friction_dissipation: f64,
    /// `(initial + boundary_work - final - dissipation - interface_work) /
    /// (initial + |boundary_work|)`.
    pub balance_residual_rel: f64,
}

/// Nonlinear interface patches of a run.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct InterfaceSummary {
    /// Patches solved by Newton iterations (with a contact face).
    pub nonlinear_patches: u64,
    /// Mean linear solves per nonlinear patch (the first from the bonded solution).
    pub newton_iterations_mean: f64,
    /// Most linear solves of one nonlinear patch.
    pub newton_iterations_max: usize,
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
    /// Largest relative momentum residual of an element (zero to round-off: every element
    /// balances linear momentum).
    pub max_momentum_residual: f64,
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
    /// Newton statistics of patches with contact faces.
    pub interface: InterfaceSummary,
    /// Errors against `[exact]`, when configured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorSummary>,
    /// Snapshot files written: `[time s, file]`.
    pub snapshots: Vec<(f64, String)>,
    /// Edge bisections (new vertices) made by adaptive refinement.
    pub refinements: u64,
    /// Patches (tents or coarsenings) solved and rejected by the error indicator (included in
    /// `patches`).
    pub rejected_patches: u64,
    /// Bisection vertices removed again by coarsening patches (included in `patches`).
    pub coarsenings: u64,
    /// Scheduler events run (refinement, coarsening, history rows): each holds the whole
    /// front, so the other workers wait for it.
    pub events: u64,
    /// Shortest edge of the final space mesh, m.
    pub min_edge: f64,
    /// Longest edge of the final space mesh, m.
    pub max_edge: f64,
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

    /// Counts a vertex added at time `t` (s) by refinement.
    fn add_vertex(&mut self, t: f64) {
        for (i, &(time, _)) in self.times.iter().enumerate().skip(self.next) {
            if time > t {
                self.below[i] += 1;
            }
        }
    }

    /// Forgets a vertex at time `t` (s) removed by coarsening.
    fn remove_vertex(&mut self, t: f64) {
        for (i, &(time, _)) in self.times.iter().enumerate().skip(self.next) {
            if time > t {
                self.below[i] -= 1;
            }
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
    rejected: u64,
    refinements: u64,
    coarsenings: u64,
    nonlinear_patches: u64,
    newton_iterations: u64,
    newton_max: usize,
    /// Energy of the initial data as the solver takes it in (scaled units): on the initial front,
    /// corrected whenever refinement splits a triangle that still carries initial data.
    initial_energy: f64,
    /// Largest `initial_energy + boundary work` so far (scaled units), the indicator's
    /// reference.
    energy_max: f64,
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

/// The read-only context and the bookkeeping of a solve.
struct Solve<'a> {
    problem: &'a Problem,
    adapt: Option<Adapt>,
    /// Triangles a vertex star may have: the patch solvers' capacity.
    max_star: usize,
    /// `Book::energy_max` as bits, read by tents without the book's lock.
    energy_reference: AtomicU64,
    initial: Initial<'a>,
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
    /// Discrete energy of the initial data on the triangle with `corners` (scaled units).
    fn initial_energy(&self, corners: [[f64; 2]; 3]) -> f64 {
        initial_energy(
            &self.problem.system,
            self.problem.loaded.config.solver.order,
            corners,
            |x| initial_state(self.problem, self.initial, x),
        )
    }

    /// The indicator of a patch with `report` over spacetime volume `volume` (m^2 s).
    fn indicator(&self, adapt: &Adapt, report: &PatchReport, volume: f64) -> f64 {
        let energy = f64::from_bits(self.energy_reference.load(Ordering::Relaxed));
        adapt.indicator(report.dissipation, volume, energy)
    }

    /// Adds a solved patch to the totals.
    fn add_patch(&self, book: &mut Book, report: &PatchReport) {
        book.patches += 1;
        book.elements += report.elements as u64;
        book.dofs += report.dofs as u64;
        book.totals.energy_in += report.energy_in;
        book.totals.energy_out += report.energy_out;
        book.totals.boundary_work += report.boundary_work;
        book.totals.interface_work += report.interface_work;
        book.totals.friction_dissipation += report.friction_dissipation;
        book.totals.dissipation += report.dissipation;
        if report.newton_iterations > 0 {
            book.nonlinear_patches += 1;
            book.newton_iterations += report.newton_iterations as u64;
            book.newton_max = book.newton_max.max(report.newton_iterations);
        }
        book.totals.momentum_residual = book.totals.momentum_residual.max(report.momentum_residual);
        book.energy_max = book
            .energy_max
            .max(book.initial_energy + book.totals.boundary_work);
        self.energy_reference
            .store(book.energy_max.to_bits(), Ordering::Relaxed);
    }

    /// Cuts the elements under `triangles`, just solved, by the snapshot planes.
    fn add_to_snapshots(
        &self,
        book: &mut Book,
        solution: &FrontSolution,
        triangles: &[TriangleId],
    ) {
        for &t in triangles {
            if solution.load(t as usize, &mut book.geometry, &mut book.coefficients) {
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
    }

    /// The edge ends of bisection vertex `m` and the front times of `m` and of the edge's
    /// midpoint (s) when `m` may be coarsened now: its elements are calm, it is at least a
    /// quarter of its smallest tent budget below the edge's midpoint (thinner coarsening
    /// elements are slivers, singular at round-off height), the restored parents keep the
    /// pitcher's invariant and the edge is not longer than `adapt.max_edge`.
    fn coarsening(
        &self,
        adapt: &Adapt,
        state: &Frontier,
        m: VertexId,
    ) -> Option<([VertexId; 2], f64, f64)> {
        let (mesh, front) = (&state.mesh, &state.front);
        let ends = mesh.coarsenable(m)?;
        let (t_m, t_mid) = (
            front.time(m),
            0.5 * (front.time(ends[0]) + front.time(ends[1])),
        );
        let long = sdg_mesh::geometry::distance(mesh.vertex(ends[0]), mesh.vertex(ends[1]));
        let budget = mesh
            .vertex_triangles(m)
            .iter()
            .map(|&t| state.pitcher.budget(t))
            .fold(f64::INFINITY, f64::min);
        (t_mid - t_m >= 0.25 * budget
            && long <= adapt.max_edge
            && state.calm_around(m)
            && state.pitcher.may_coarsen(mesh, front, m, ends))
        .then_some((ends, t_m, t_mid))
    }

    /// Solves the coarsening patch of vertex `m`, claimed for a tent, when `m` may be coarsened
    /// now and the patch is within the tolerance: the outcome for the coarsening event.
    fn try_coarsening(
        &self,
        adapt: &Adapt,
        state: &Frontier,
        solver: &mut PatchSolver,
        m: VertexId,
    ) -> Option<Outcome> {
        let (_, t_m, t_mid) = self.coarsening(adapt, state, m)?;
        let (mesh, front) = (&state.mesh, &state.front);
        let report = solver.solve_coarsening(
            mesh,
            front,
            m,
            &self.problem.boundary,
            self.initial,
            &state.solution,
        )?;
        let area: f64 = mesh.vertex_triangles(m).iter().map(|&t| mesh.area(t)).sum();
        let eta = self.indicator(adapt, &report, area * (t_mid - t_m) / 3.0);
        if eta > adapt.tol {
            return None;
        }
        let times = mesh
            .vertex_neighbors(m)
            .iter()
            .chain([&m])
            .map(|&w| (w, front.time(w)))
            .collect();
        let elements = solver
            .elements()
            .map(|(t, geometry, coefficients)| {
                (
                    mesh.triangles()[t as usize],
                    *geometry,
                    coefficients.to_vec(),
                )
            })
            .collect();
        let coarsening = Coarsening {
            vertex: m,
            at: mesh.vertex(m),
            times,
            elements,
            calm: eta < adapt.lower,
        };
        Some(Outcome::Coarsen {
            coarsening: Box::new(coarsening),
            report,
        })
    }

    /// The coarsening event: applies `coarsening` (with `report`) if nothing changed since it
    /// was solved; otherwise the patch counts as rejected.
    fn coarsen(
        &self,
        state: &mut Frontier,
        coarsening: &Coarsening,
        report: &PatchReport,
    ) -> Changed {
        let m = coarsening.vertex;
        let Some((merge, parents)) = state.coarsen(coarsening) else {
            let mut book = self.book.lock();
            book.patches += 1;
            book.rejected += 1;
            return Changed::default();
        };
        let t_m = coarsening
            .times
            .iter()
            .find(|&&(w, _)| w == m)
            .map(|&(_, t)| t)
            .expect("the times include the vertex");
        let t_end = self.problem.loaded.config.time.end;
        let mut book = self.book.lock();
        self.add_patch(&mut book, report);
        book.coarsenings += 1;
        book.milestones.remove_vertex(t_m);
        book.progress.grow(-(t_end - t_m));
        self.add_to_snapshots(&mut book, &state.solution, &parents);
        let mut offer: Vec<VertexId> = coarsening
            .times
            .iter()
            .filter(|&&(w, _)| w != m)
            .map(|&(w, _)| merge.vertex_after(w))
            .collect();
        if (m as usize) < state.mesh.vertices().len() {
            // The former last vertex now has m's id.
            offer.push(m);
        }
        Changed {
            offer,
            below_end: -1,
        }
    }

    /// True when star triangle `t` may be bisected now: its halves would not be too short, the
    /// front stays causal, and the star of the corner that gains a triangle stays within the
    /// patch solvers' capacity.
    fn may_refine(&self, adapt: &Adapt, state: &Frontier, t: TriangleId) -> bool {
        let mesh = &state.mesh;
        let apex = mesh.triangles()[t as usize][mesh.refinement_edge(t)];
        refinement_edge_length(mesh, t) >= 2.0 * adapt.min_edge
            && mesh.vertex_triangles(apex).len() < self.max_star
            && state.pitcher.may_bisect(mesh, |w| state.front.time(w), t)
    }

    /// The refinement event of a rejected patch at `v` (at `at`, m, to notice renumbering by
    /// coarsening): bisects the triangles of `star` that are unchanged since. When none could
    /// be, the next tent at `v` is accepted whatever its indicator, so that the front keeps
    /// moving. Returns the vertices whose readiness changed.
    fn refine(
        &self,
        state: &mut Frontier,
        v: VertexId,
        at: [f64; 2],
        star: &[(TriangleId, [VertexId; 3])],
    ) -> Changed {
        let adapt = self.adapt.expect("refinement only runs with adaptivity on");
        let mut refined = Refined::default();
        let unchanged = |state: &Frontier, t: TriangleId, corners: [VertexId; 3]| {
            state.mesh.triangles().get(t as usize) == Some(&corners)
        };
        for &(t, corners) in star {
            if unchanged(state, t, corners) {
                state.refine(
                    t,
                    adapt.min_edge,
                    self.max_star,
                    &|corners| self.initial_energy(corners),
                    &mut refined,
                );
            }
        }
        let here = (v as usize) < state.mesh.vertices().len() && state.mesh.vertex(v) == at;
        if here
            && star
                .iter()
                .all(|&(t, corners)| unchanged(state, t, corners))
        {
            state.insist(v);
        }
        let t_end = self.problem.loaded.config.time.end;
        let mut book = self.book.lock();
        book.refinements += refined.vertices.len() as u64;
        book.initial_energy += refined.initial_energy;
        for &(_, t) in &refined.vertices {
            book.milestones.add_vertex(t);
            book.progress.grow(t_end - t);
        }
        let mut touched = refined.touched;
        if here {
            touched.push(v);
            touched.extend(state.mesh.vertex_neighbors(v));
        }
        touched.extend(refined.vertices.iter().map(|&(w, _)| w));
        touched.sort_unstable();
        touched.dedup();
        Changed {
            offer: touched,
            below_end: refined.vertices.iter().filter(|&&(_, t)| t < t_end).count() as isize,
        }
    }

    /// Appends a `history.csv` row for the current front: it must not move meanwhile.
    fn history_row(&self, state: &Frontier, book: &mut Book) {
        let system = &self.problem.system;
        let rho = self.problem.material.density();
        let e = front_energy(
            &state.mesh,
            &state.front,
            &state.solution,
            &self.basis,
            system,
            |x| initial_state(self.problem, self.initial, x),
        );
        let totals = &book.totals;
        let balance = book.initial_energy + totals.boundary_work
            - e.total
            - totals.dissipation
            - totals.interface_work;
        let _ = writeln!(
            book.history,
            "{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            state.front.min_time(),
            book.patches,
            rho * e.total,
            rho * e.kinetic,
            rho * e.strain,
            rho * totals.boundary_work,
            rho * totals.dissipation,
            rho * totals.interface_work,
            rho * totals.friction_dissipation,
            rho * balance
        );
    }
}

/// What one tent hands to the bookkeeping.
#[derive(Debug)]
enum Outcome {
    /// The patch is stored and the vertex advanced.
    Accepted {
        t_old: f64,
        t_new: f64,
        report: PatchReport,
    },
    /// The indicator rejected the patch: nothing advanced; these star triangles (with their
    /// corners, to notice a change) are to be bisected.
    Rejected {
        star: Vec<(TriangleId, [VertexId; 3])>,
    },
    /// The tent's vertex is to be removed by the coarsening patch solved in its place.
    Coarsen {
        coarsening: Box<Coarsening>,
        report: PatchReport,
    },
}

impl<'a> Work<'a> for Solve<'a> {
    type State = Frontier;
    type Scratch = PatchSolver;
    type Outcome = Outcome;
    type Error = EngineError;

    fn tent(
        &self,
        state: &Frontier,
        solver: &mut PatchSolver,
        v: VertexId,
        _: &Events<'a, Frontier>,
    ) -> Result<(f64, Outcome), EngineError> {
        let (mesh, front) = (&state.mesh, &state.front);
        let star = mesh.vertex_triangles(v);
        if star.len() > self.max_star {
            return Err(EngineError::Runtime(format!(
                "vertex {v} has {} triangles, more than the {} the patch solvers hold",
                star.len(),
                self.max_star
            )));
        }
        if let Some(adapt) = &self.adapt {
            if let Some(outcome) = self.try_coarsening(adapt, state, solver, v) {
                return Ok((front.time(v), outcome));
            }
        }
        let t_new = state.pitcher.pole_height(mesh, front, v).ok_or_else(|| {
            EngineError::Runtime(format!("vertex {v} was claimed but cannot be pitched"))
        })?;
        let tent = Tent {
            vertex: v,
            t_old: front.time(v),
            t_new,
        };
        let solved = solver.solve(
            mesh,
            front,
            &tent,
            &self.problem.boundary,
            self.initial,
            &state.solution,
        );
        let report = match solved {
            Ok(report) => report,
            Err(failure) => {
                // Not converged: refine around the vertex when adaptivity can, else stop.
                let star: Vec<_> = self
                    .adapt
                    .iter()
                    .flat_map(|adapt| {
                        star.iter()
                            .filter(|&&t| self.may_refine(adapt, state, t))
                            .map(|&t| (t, mesh.triangles()[t as usize]))
                    })
                    .collect();
                if star.is_empty() {
                    let [x, y] = mesh.vertex(v);
                    return Err(EngineError::Runtime(format!(
                        "the patch of vertex {v} at ({x:e}, {y:e}) m, t = {:e} s: {failure}",
                        tent.t_old
                    )));
                }
                return Ok((tent.t_old, Outcome::Rejected { star }));
            }
        };
        if let Some(adapt) = &self.adapt {
            let area: f64 = star.iter().map(|&t| mesh.area(t)).sum();
            let eta = self.indicator(adapt, &report, area * (t_new - tent.t_old) / 3.0);
            if !state.insists(v) && eta > adapt.tol {
                let star = star
                    .iter()
                    .filter(|&&t| self.may_refine(adapt, state, t))
                    .map(|&t| (t, mesh.triangles()[t as usize]))
                    .collect::<Vec<_>>();
                if !star.is_empty() {
                    return Ok((tent.t_old, Outcome::Rejected { star }));
                }
            }
            for &t in star {
                state.set_calm(t, eta < adapt.lower);
            }
        }
        solver.commit(&state.solution);
        front.set_time(v, t_new);
        let outcome = Outcome::Accepted {
            t_old: tent.t_old,
            t_new,
            report,
        };
        Ok((t_new, outcome))
    }

    fn record(
        &'a self,
        state: &Frontier,
        v: VertexId,
        o: Outcome,
        events: &Events<'a, Frontier>,
    ) -> Result<(), EngineError> {
        let (t_old, t_new, report) = match o {
            Outcome::Accepted {
                t_old,
                t_new,
                report,
            } => (t_old, t_new, report),
            Outcome::Coarsen { coarsening, report } => {
                events.push(Box::new(move |state: &mut Frontier| {
                    self.coarsen(state, &coarsening, &report)
                }));
                return Ok(());
            }
            Outcome::Rejected { star } => {
                let mut book = self.book.lock();
                book.patches += 1;
                book.rejected += 1;
                let at = state.mesh.vertex(v);
                events.push(Box::new(move |state: &mut Frontier| {
                    self.refine(state, v, at, &star)
                }));
                return Ok(());
            }
        };
        let mesh = &state.mesh;
        let c_max = state.pitcher.c_max();
        let slope = mesh
            .vertex_triangles(v)
            .iter()
            .map(|&t| c_max * state.front.slope(mesh, t))
            .fold(0.0, f64::max);
        let mut guard = self.book.lock();
        let book = &mut *guard;
        self.add_patch(book, &report);
        book.max_slope_ratio = book.max_slope_ratio.max(slope);
        self.add_to_snapshots(book, &state.solution, mesh.vertex_triangles(v));
        book.progress.advance(t_new - t_old, book.patches);
        let mut passed = std::mem::take(&mut book.passed);
        book.milestones.advance(t_old, t_new, &mut passed);
        for &(t, _) in passed.iter().filter(|p| p.1 == Milestone::Snapshot) {
            book.snapshots.flush(t)?;
        }
        // One row for however many history milestones passed at once.
        if passed.iter().any(|p| p.1 == Milestone::History) {
            events.push(Box::new(move |state: &mut Frontier| {
                self.history_row(state, &mut self.book.lock());
                Changed::default()
            }));
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

    let adapt = Adapt::new(&config.adapt, mesh, c_max);
    let pitcher = if adapt.is_some() {
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
    let max_star = if adapt.is_some() {
        (2 * initial_star).max(12)
    } else {
        initial_star
    };
    let solvers: Vec<PatchSolver> = (0..scheduler.threads)
        .map(|_| PatchSolver::new(system.clone(), config.solver.order, max_star))
        .collect();
    let (basis, width) = (solvers[0].basis().clone(), solvers[0].width());
    let initial = problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave);
    let mut state = Frontier::new(
        mesh.clone(),
        Front::flat(mesh.vertices().len(), 0.0),
        FrontSolution::new(mesh.triangles().len(), basis.len(), width)
            .with_edges(mesh.edges().len()),
        pitcher,
    );
    if let Some(adapt) = &adapt {
        // Energies of the initial data are taken on the refined front below.
        refine_to_max_edge(&mut state, adapt, max_star)?;
    }
    let energy0 = front_energy(
        &state.mesh,
        &state.front,
        &state.solution,
        &basis,
        system,
        |x| initial_state(problem, initial, x),
    );
    let solve = Solve {
        problem,
        adapt,
        max_star,
        energy_reference: AtomicU64::new(energy0.total.to_bits()),
        initial,
        basis: basis.clone(),
        book: Mutex::new(Book {
            totals: PatchReport::default(),
            patches: 0,
            rejected: 0,
            refinements: 0,
            coarsenings: 0,
            nonlinear_patches: 0,
            newton_iterations: 0,
            newton_max: 0,
            initial_energy: energy0.total,
            energy_max: energy0.total,
            elements: 0,
            dofs: 0,
            max_slope_ratio: 0.0,
            snapshots: Snapshots::new(&config.output.snapshot_times, c_max, dir.clone()),
            milestones: Milestones::new(
                state.mesh.vertices().len(),
                t_end,
                &config.output.snapshot_times,
            ),
            passed: Vec::new(),
            history: String::from(
                "time_s,patches,front_energy_j,kinetic_j,strain_j,boundary_work_j,dissipation_j,\
                 interface_work_j,friction_dissipation_j,balance_residual_j\n",
            ),
            progress: Progress::new(options.progress, state.mesh.vertices().len() as f64 * t_end),
            phi: vec![0.0; basis.len()],
            values: vec![0.0; width],
            geometry: Geometry::default(),
            coefficients: vec![0.0; basis.len() * width],
        }),
    };
    solve.history_row(&state, &mut solve.book.lock());
    let _span = tracing::info_span!("solve", config = %problem.loaded.file.display()).entered();
    tracing::info!(
        threads = scheduler.threads,
        deterministic = scheduler.deterministic,
        order = config.solver.order,
        vertices = state.mesh.vertices().len(),
        "solve started"
    );
    let start = Instant::now();
    let stats = match sdg_scheduler::run(&mut state, t_end, &solve, solvers, &scheduler) {
        Ok(stats) => stats,
        Err(e) => {
            // Keep what the run produced so far: the history up to the failure and the
            // snapshots already complete.
            let mut book = solve.book.lock();
            book.progress.finish();
            solve.history_row(&state, &mut book);
            write_atomic(&dir, "history.csv", book.history.as_bytes())?;
            return Err(scheduler_error(e));
        }
    };
    let wall_time_s = start.elapsed().as_secs_f64();
    let mut book = solve.book.lock();
    book.progress.finish();
    solve.history_row(&state, &mut book);
    book.snapshots.flush(t_end)?;
    tracing::info!(patches = stats.tents, wall_time_s, "solve finished");

    let Frontier {
        mesh,
        front,
        solution,
        ..
    } = &state;
    let e = front_energy(mesh, front, solution, &basis, system, |x| {
        initial_state(problem, initial, x)
    });
    let initial_j = rho * book.initial_energy;
    let work = rho * book.totals.boundary_work;
    let dissipation = rho * book.totals.dissipation;
    let interface_work = rho * book.totals.interface_work;
    let final_j = rho * e.total;
    let energy = EnergySummary {
        initial: initial_j,
        final_kinetic: rho * e.kinetic,
        final_strain: rho * e.strain,
        r#final: final_j,
        boundary_work: work,
        dissipation,
        interface_work,
        friction_dissipation: rho * book.totals.friction_dissipation,
        balance_residual_rel: (initial_j + work - final_j - dissipation - interface_work)
            / (initial_j + work.abs()).max(f64::MIN_POSITIVE),
    };
    let interface = InterfaceSummary {
        nonlinear_patches: book.nonlinear_patches,
        newton_iterations_mean: book.newton_iterations as f64
            / book.nonlinear_patches.max(1) as f64,
        newton_iterations_max: book.newton_max,
    };
    let error = problem.exact.as_ref().map(|w| {
        let e = slice_errors(mesh, solution, &basis, system, t_end, w);
        ErrorSummary {
            velocity_l2_rel: e.velocity,
            stress_l2_rel: e.stress,
        }
    });
    let (min_edge, max_edge) = mesh.edge_length_range();
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
        max_momentum_residual: book.totals.momentum_residual,
        mode: if scheduler.deterministic {
            "deterministic"
        } else {
            "asynchronous"
        },
        state_hash: state_hash(front, solution, basis.len() * width),
        wall_time_s,
        patches_per_second: book.patches as f64 / wall_time_s.max(f64::MIN_POSITIVE),
        threads: scheduler.threads,
        energy,
        interface,
        error,
        snapshots: book.snapshots.written().to_vec(),
        refinements: book.refinements,
        rejected_patches: book.rejected,
        coarsenings: book.coarsenings,
        events: stats.events,
        min_edge,
        max_edge,
    };
    write_atomic(&dir, "history.csv", book.history.as_bytes())?;
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_atomic(&dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir))
}

/// Bisects every triangle whose refinement edge is longer than `adapt.max_edge`, on the flat
/// initial front.
fn refine_to_max_edge(
    state: &mut Frontier,
    adapt: &Adapt,
    max_star: usize,
) -> Result<(), EngineError> {
    let mut refined = Refined::default();
    let mut t: TriangleId = 0;
    while (t as usize) < state.mesh.triangles().len() {
        if refinement_edge_length(&state.mesh, t) <= adapt.max_edge {
            t += 1;
            continue;
        }
        let before = state.mesh.triangles().len();
        state.refine(t, adapt.min_edge, max_star, &|_| 0.0, &mut refined);
        if state.mesh.triangles().len() == before {
            return Err(EngineError::Runtime(format!(
                "adapt.max_edge = {} m cannot be reached: a vertex star would exceed {max_star} \
                 triangles",
                adapt.max_edge
            )));
        }
    }
    Ok(())
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
