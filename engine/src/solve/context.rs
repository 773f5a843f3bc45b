//! The context of a solve: what every tent reads, and the bookkeeping it writes to.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use parking_lot::Mutex;

use sdg_mesh::{Front, Mesh, Pitcher, SplitError, TriangleId};
use sdg_scheduler::{Changed, Region, VertexId};
use sdg_solver::basis::Basis;
use sdg_solver::element::FrontSolution;
use sdg_solver::norms::initial_energy;
use sdg_solver::norms::{FrontEnergy, front_energy};
use sdg_solver::patch::{BLOW_UP, Initial, PatchReport};
use sdg_solver::system::{MAX_FIELDS, State};

use crate::adaptivity::indicator::Adapt;
use crate::frontier::Frontier;
use crate::problem::Problem;
use crate::trace::Tracer;

use super::book::Book;
use super::control::Control;

/// The read-only context and the bookkeeping of a solve.
pub(crate) struct Solve<'a> {
    pub(crate) problem: &'a Problem,
    pub(crate) adapt: Option<Adapt>,
    /// Triangles a vertex star may have: the patch solvers' capacity.
    pub(crate) max_star: usize,
    /// Worker threads: events that integrate over the whole front use them all.
    pub(crate) threads: usize,
    /// No split for crack alignment makes a piece of an edge shorter than this, m:
    /// `fracture.min_piece`, by default `adapt.min_edge`, or without adaptivity a quarter of the
    /// initial mesh's shortest edge (cracks running through ever smaller triangles would
    /// otherwise shrink the tents without bound).
    pub(crate) min_edge: f64,
    /// `output.snapshot_times` on the run's own clock (s since `time.start`).
    pub(crate) snapshot_times: Vec<f64>,
    /// `Book::energy_max` as bits, read by tents without the book's lock.
    pub(crate) energy_reference: AtomicU64,
    pub(crate) initial: Initial<'a>,
    /// Basis of every element (each worker's solver has the same).
    pub(crate) basis: sdg_solver::basis::Basis,
    /// Values per point of an element's fields (the patch solvers' width).
    pub(crate) width: usize,
    pub(crate) book: Mutex<Book>,
    /// The change [`solve_job_with`] applies once, until its milestone passes.
    pub(crate) intervention: Mutex<Option<Intervention>>,
    /// Requests from outside (signals) and the run's own checkpoint and stop times.
    pub(crate) control: Arc<Control>,
    /// When the wall-time limit is up: the run checkpoints and stops, and why.
    pub(crate) deadline: Option<(Instant, String)>,
    /// When the solve started, and when the next checkpoint by wall time is due
    /// (`checkpoint.every_wall_s`), ns after it; `u64::MAX` for none.
    pub(crate) started: Instant,
    pub(crate) next_wall_checkpoint_ns: AtomicU64,
    /// Records every tent and event with `--trace`.
    pub(crate) tracer: Option<Tracer>,
    /// This rank's part when the rounds are split over ranks ([`super::split`]).
    pub(crate) split: Option<super::split::Split>,
}

/// The scaled initial state at `x`.
pub(crate) fn initial_state(problem: &Problem, initial: Initial, x: [f64; 2]) -> State {
    match initial {
        Initial::Wave(w) => problem.system.to_scaled(&w.state(x, 0.0)),
        Initial::Rest => [0.0; MAX_FIELDS],
    }
}

impl Solve<'_> {
    /// What is wrong with a solved patch's `report`, if anything: a non-finite value or an
    /// energy blow-up ([`BLOW_UP`]).
    pub(crate) fn guard(&self, report: &PatchReport) -> Option<String> {
        if let Some((name, value)) = report.first_non_finite() {
            return Some(format!("{name} is {value} (a non-finite value)"));
        }
        let held = f64::from_bits(self.energy_reference.load(Ordering::Relaxed));
        let rho = self.problem.material.density();
        report.blows_up(held).then(|| {
            let held = held + report.boundary_work.max(0.0);
            format!(
                "energy blow-up: the patch carries {:e} J/m out, more than {BLOW_UP} times the \
                 {:e} J/m the body has held",
                rho * report.energy_out,
                rho * held
            )
        })
    }
}

impl Solve<'_> {
    /// Whether this run writes files (outputs, checkpoints): all but the ranks other than 0 of
    /// rounds split over ranks, whose state is a copy of rank 0's.
    pub(crate) fn writes(&self) -> bool {
        self.split.as_ref().is_none_or(super::split::Split::writes)
    }

    /// Runs the event `action`, traced with `--trace` as one that holds the whole state.
    pub(crate) fn traced<T>(&self, action: impl FnOnce() -> T) -> T {
        match &self.tracer {
            Some(tracer) => tracer.event(action),
            None => action(),
        }
    }

    /// Runs the event `action` on `state`, which changes the mesh only around the vertices it
    /// offers (refinement, crack extension; with `coarsening`, the coarsening of that vertex,
    /// which the last vertex may replace), traced with `--trace` as a regional event.
    pub(crate) fn traced_region(
        &self,
        state: &mut Frontier,
        coarsening: Option<VertexId>,
        action: impl FnOnce(&mut Frontier) -> Changed,
    ) -> Changed {
        let Some(tracer) = &self.tracer else {
            return action(state);
        };
        let (begun, count) = (tracer.begin_region(), state.mesh.vertices().len());
        let changed = action(state);
        let removed = coarsening.filter(|_| state.mesh.vertices().len() < count);
        tracer.end_region(begun, &state.mesh, &changed.offer, removed);
        changed
    }

    /// Discrete energy of the initial data on the triangle with `corners` (scaled units).
    pub(crate) fn initial_energy(&self, corners: [[f64; 2]; 3]) -> f64 {
        initial_energy(
            &self.problem.system,
            self.problem.loaded.config.solver.order,
            corners,
            |x| initial_state(self.problem, self.initial, x),
        )
    }
}

/// The change [`solve_job_with`] applies.
pub(crate) type Intervention = Box<dyn FnOnce(&mut Live<'_>) + Send>;

/// The live state of a run, held exclusively by the event of [`solve_job_with`].
#[doc(hidden)]
pub struct Live<'s> {
    solve: &'s Solve<'s>,
    state: &'s mut Frontier,
    changed: Changed,
}

impl std::fmt::Debug for Live<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Live")
            .field("vertices", &self.state.mesh.vertices().len())
            .field("changed", &self.changed)
            .finish_non_exhaustive()
    }
}

impl Live<'_> {
    /// The space mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.state.mesh
    }

    /// The front: one time per vertex, s.
    pub fn front(&self) -> &Front {
        &self.state.front
    }

    /// The elements under the front and the interface faces over its edges.
    pub fn solution(&self) -> &FrontSolution {
        &self.state.solution
    }

    /// The run's pitcher.
    pub fn pitcher(&self) -> &Pitcher {
        &self.state.pitcher
    }

    /// The basis of every element.
    pub fn basis(&self) -> &Basis {
        &self.solve.basis
    }

    /// Energy on the front in the solver's scaled units (times the density for J/m), as the
    /// history rows take it: triangles without an element carry the initial data.
    pub fn front_energy(&self) -> FrontEnergy {
        let solve = self.solve;
        front_energy(
            &self.state.mesh,
            &self.state.front,
            &self.state.solution,
            &solve.basis,
            &solve.problem.system,
            solve.threads,
            |x| initial_state(solve.problem, solve.initial, x),
        )
    }

    /// Splits the refinement edge of triangle `t` at `fraction` of its length from its
    /// smaller-id end, as the engine refines: the closure bisects what it needs first, every
    /// step within the limits of refinement and the pitcher's causality
    /// ([`sdg_mesh::Pitcher::may_split_at`] off the midpoint, [`sdg_mesh::Pitcher::may_bisect`]
    /// at it). Returns whether `t` was split; `Ok(false)` when
    /// a step was refused (the steps before it stay done). Errors (bad `t` or `fraction`, a
    /// degenerate child) change nothing.
    pub fn split_at(&mut self, t: TriangleId, fraction: f64) -> Result<bool, SplitError> {
        let everything = Region::everything();
        let (split, changed, _) =
            (self.solve).split_at(self.state, &everything, t, None, fraction)?;
        self.changed.offer.extend(changed.offer);
        self.changed.below_end += changed.below_end;
        Ok(split)
    }
}

impl Solve<'_> {
    /// The event of [`solve_job_with`]: runs its action (once) and reports what it changed.
    pub(crate) fn intervene(&self, state: &mut Frontier) -> Changed {
        let Some(action) = self.intervention.lock().take() else {
            return Changed::default();
        };
        let mut live = Live {
            solve: self,
            state,
            changed: Changed::default(),
        };
        action(&mut live);
        let mut changed = live.changed;
        changed.offer.sort_unstable();
        changed.offer.dedup();
        changed
    }
}
