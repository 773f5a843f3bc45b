//! Test support: one change to the live front in the middle of a run, through the engine's own
//! event path. It is how the building blocks of crack alignment (splitting an edge at a given
//! point) are exercised on a real run before the crack propagation that will drive them exists.

use std::path::PathBuf;

use sdg_mesh::{Front, Mesh, Pitcher, SplitError, TriangleId};
use sdg_scheduler::{Changed, Region};
use sdg_solver::basis::Basis;
use sdg_solver::element::FrontSolution;
use sdg_solver::norms::{FrontEnergy, front_energy};

use super::{RunSummary, Solve, initial_state, run_job};
use crate::error::EngineError;
use crate::frontier::Frontier;
use crate::problem::Problem;
use crate::run::RunOptions;

/// The change [`solve_job_with`] applies.
pub(super) type Intervention = Box<dyn FnOnce(&mut Live<'_>) + Send>;

/// [`crate::solve_job`], with `action` run once on the live front as soon as every vertex of the
/// front has passed `after` (s since `time.start`, in `[0, time.end - time.start)`), as a
/// scheduler event: no tent is in flight,
/// and the front is as the tents left it (not flat). What `action` changes through [`Live`]
/// is booked like adaptive refinement (counts, energy accounting, progress) and the run then
/// continues to the end time. Deterministic runs stay deterministic.
///
/// `action` owns what it captures (`'static`): it reports back through shared handles such as
/// an `Arc<Mutex<_>>`. Errors as [`crate::solve_job`], and a runtime error for an `after` outside
/// `[0, time.end - time.start)`.
#[doc(hidden)]
pub fn solve_job_with(
    problem: &Problem,
    options: &RunOptions,
    after: f64,
    action: impl FnOnce(&mut Live<'_>) + Send + 'static,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let t_end = problem.loaded.config.time.span();
    if !(after >= 0.0 && after < t_end) {
        return Err(EngineError::Runtime(format!(
            "an intervention {after:e} s after the start is not within the run's {t_end:e} s"
        )));
    }
    run_job(problem, options, Some((after, Box::new(action))))
}

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
    pub(super) fn intervene(&self, state: &mut Frontier) -> Changed {
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
