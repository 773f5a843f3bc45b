//! The bookkeeping of a solve: energy totals, history rows, snapshots and the milestone times
//! the whole front must pass before they are due.

use std::fmt::Write as _;

use std::sync::atomic::Ordering;

use sdg_mesh::{TagId, TriangleId};
use sdg_solver::crack::Crossing;
use sdg_solver::element::{FrontSolution, Geometry, evaluate};
use sdg_solver::norms::front_energy;
use sdg_solver::patch::{InterfaceSample, PatchReport};
use sdg_solver::system::MAX_FIELDS;
use sdg_solver::{Material, Plane};

use super::{Solve, initial_state};
use crate::frontier::Frontier;
use crate::progress::Progress;
use crate::snapshot::{PointValues, Snapshots};

/// History rows are written when the whole front has passed each of this many equal fractions
/// of the end time (and at the end).
const HISTORY_ROWS: usize = 100;

/// Times the whole front must pass before something happens, with a count of the vertices whose
/// recorded time is still below each.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Milestones {
    /// Increasing times (s) and what they are for.
    times: Vec<(f64, Milestone)>,
    below: Vec<usize>,
    next: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(super) enum Milestone {
    History,
    Snapshot,
    /// A checkpoint is due (`checkpoint.every_sim_s`).
    Checkpoint,
    /// The change of [`super::solve_job_with`] is due.
    Intervention,
}

impl Milestones {
    /// Milestones for a front of `vertices` vertices at time 0: the history rows up to `t_end`
    /// (s), the snapshot times, the multiples of `checkpoint_every` (s) below `t_end` and the
    /// intervention time, if any (s).
    pub(super) fn new(
        vertices: usize,
        t_end: f64,
        snapshots: &[f64],
        checkpoint_every: Option<f64>,
        intervention: Option<f64>,
    ) -> Self {
        let checkpoints = checkpoint_every.map_or(0, |dt| (t_end / dt).ceil() as usize);
        let mut times: Vec<(f64, Milestone)> = (1..HISTORY_ROWS)
            .map(|k| (t_end * k as f64 / HISTORY_ROWS as f64, Milestone::History))
            .chain(snapshots.iter().map(|&t| (t, Milestone::Snapshot)))
            .chain(
                (1..checkpoints)
                    .map(|k| k as f64 * checkpoint_every.unwrap_or(0.0))
                    .filter(|&t| t < t_end)
                    .map(|t| (t, Milestone::Checkpoint)),
            )
            .chain(intervention.map(|t| (t, Milestone::Intervention)))
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

    /// The milestones of [`Self::new`] for the rest of a run resumed from a front with the
    /// vertex times `times` (s): those after its earliest time, each counting the vertices
    /// still below it.
    pub(super) fn resumed(
        times: &[f64],
        t_end: f64,
        snapshots: &[f64],
        checkpoint_every: Option<f64>,
    ) -> Self {
        let earliest = times.iter().copied().fold(f64::INFINITY, f64::min);
        let mut milestones = Self::new(0, t_end, snapshots, checkpoint_every, None);
        milestones.times.retain(|&(t, _)| t > earliest);
        milestones.below = (milestones.times.iter())
            .map(|&(t, _)| times.iter().filter(|&&v| v < t).count())
            .collect();
        milestones
    }

    /// Counts a vertex added at time `t` (s) by refinement.
    pub(super) fn add_vertex(&mut self, t: f64) {
        for (i, &(time, _)) in self.times.iter().enumerate().skip(self.next) {
            if time > t {
                self.below[i] += 1;
            }
        }
    }

    /// Forgets a vertex at time `t` (s) removed by coarsening.
    pub(super) fn remove_vertex(&mut self, t: f64) {
        for (i, &(time, _)) in self.times.iter().enumerate().skip(self.next) {
            if time > t {
                self.below[i] -= 1;
            }
        }
    }

    /// Records a vertex moving from `t_old` to `t_new`; returns the milestones the whole front
    /// has now passed, in order.
    pub(super) fn advance(&mut self, t_old: f64, t_new: f64, passed: &mut Vec<(f64, Milestone)>) {
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
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Book {
    pub(super) totals: PatchReport,
    pub(super) patches: u64,
    pub(super) rejected: u64,
    pub(super) refinements: u64,
    pub(super) coarsenings: u64,
    /// Patches accepted with the indicator above the tolerance: no triangle of their star could
    /// be bisected (edge at `min_edge`, star at capacity, or causality).
    #[serde(default)]
    pub(super) unresolved: u64,
    /// The largest indicator of those patches, in units of the tolerance.
    #[serde(default)]
    pub(super) unresolved_max: f64,
    /// Interface probe samples: `(probe index, sample)`.
    pub(super) samples: Vec<(usize, InterfaceSample)>,
    /// Crack-tracking crossings of cohesive faces with the tag of their edge.
    pub(super) crossings: Vec<(Option<TagId>, Crossing)>,
    /// Crack nucleation, extension, branching and arrest, in the order they happened.
    pub(super) fracture_events: Vec<super::propagation::FractureEvent>,
    pub(super) nonlinear_patches: u64,
    pub(super) newton_iterations: u64,
    pub(super) newton_max: usize,
    /// Energy of the initial data as the solver takes it in (scaled units): on the initial front,
    /// corrected whenever refinement splits a triangle that still carries initial data.
    pub(super) initial_energy: f64,
    /// Largest `initial_energy + boundary work` so far (scaled units), the indicator's
    /// reference.
    pub(super) energy_max: f64,
    pub(super) elements: u64,
    pub(super) dofs: u64,
    pub(super) max_slope_ratio: f64,
    /// Wall time by stage so far, but the scheduler's (events, waiting).
    #[serde(default)]
    pub(super) timings: super::Timings,
    pub(super) snapshots: Snapshots,
    pub(super) milestones: Milestones,
    #[serde(skip)]
    pub(super) passed: Vec<(f64, Milestone)>,
    pub(super) history: String,
    #[serde(skip)]
    pub(super) progress: Progress,
    /// Basis values and element values for snapshot evaluation, and an element copy.
    #[serde(skip)]
    pub(super) phi: Vec<f64>,
    #[serde(skip)]
    pub(super) values: Vec<f64>,
    #[serde(skip)]
    pub(super) geometry: Geometry,
    #[serde(skip)]
    pub(super) coefficients: Vec<f64>,
}

impl Book {
    /// Makes a book read from a checkpoint ready to go on: scratch for `basis_len` basis
    /// functions of `width` fields, snapshots written to `dir` in `vtu` (those written before
    /// into another folder copied there).
    pub(super) fn resume(
        &mut self,
        dir: &std::path::Path,
        vtu: crate::config::VtuFormat,
        basis_len: usize,
        width: usize,
    ) -> Result<(), crate::error::EngineError> {
        self.phi = vec![0.0; basis_len];
        self.values = vec![0.0; width];
        self.coefficients = vec![0.0; basis_len * width];
        self.snapshots.set_output(dir, vtu)
    }
}

impl Solve<'_> {
    /// Adds a solved patch to the totals.
    pub(super) fn add_patch(&self, book: &mut Book, report: &PatchReport) {
        book.patches += 1;
        book.timings.assembly_s += report.assembly_s;
        book.timings.solve_s += report.solve_s;
        book.timings.evaluation_s += report.evaluation_s;
        book.elements += report.elements as u64;
        book.dofs += report.dofs as u64;
        book.totals.energy_in += report.energy_in;
        book.totals.energy_out += report.energy_out;
        book.totals.boundary_work += report.boundary_work;
        book.totals.interface_work += report.interface_work;
        book.totals.friction_dissipation += report.friction_dissipation;
        book.totals.fracture_work += report.fracture_work;
        book.totals.dissipation += report.dissipation;
        if report.newton_iterations > 0 {
            book.nonlinear_patches += 1;
            book.newton_iterations += report.newton_iterations as u64;
            book.newton_max = book.newton_max.max(report.newton_iterations);
        }
        let totals = &mut book.totals;
        totals.momentum_imbalance = totals.momentum_imbalance.max(report.momentum_imbalance);
        totals.momentum_flux = totals.momentum_flux.max(report.momentum_flux);
        book.energy_max = book
            .energy_max
            .max(book.initial_energy + book.totals.boundary_work);
        self.energy_reference
            .store(book.energy_max.to_bits(), Ordering::Relaxed);
    }

    /// Cuts the elements under `triangles`, just solved, by the snapshot planes.
    pub(super) fn add_to_snapshots(
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

    /// Appends a `history.csv` row for the current front, unless the last row is of the same
    /// front time and patch count: the front must not move meanwhile.
    pub(super) fn history_row(&self, state: &Frontier, book: &mut Book) {
        let time = self
            .problem
            .loaded
            .config
            .time
            .clock(state.front.min_time());
        // The same front and books as the last row (the end's milestone and the final row):
        // the row would repeat it.
        let key = format!("{time:e},{},", book.patches);
        let last = book.history.trim_end().lines().next_back().unwrap_or("");
        if last.starts_with(&key) {
            return;
        }
        let system = &self.problem.system;
        let rho = self.problem.material.density();
        let e = front_energy(
            &state.mesh,
            &state.front,
            &state.solution,
            &self.basis,
            system,
            self.threads,
            |x| initial_state(self.problem, self.initial, x),
        );
        let totals = &book.totals;
        let balance = book.initial_energy + totals.boundary_work
            - e.total
            - totals.dissipation
            - totals.interface_work;
        let _ = writeln!(
            book.history,
            "{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            time,
            book.patches,
            rho * e.total,
            rho * e.kinetic,
            rho * e.strain,
            rho * totals.boundary_work,
            rho * totals.dissipation,
            rho * totals.interface_work,
            rho * totals.friction_dissipation,
            rho * totals.fracture_work,
            rho * balance
        );
        // Progress for batch jobs, which have no progress bar: one line per history row.
        tracing::info!(
            front_min_time_s = time,
            patches = book.patches,
            rejected = book.rejected,
            vertices = state.mesh.vertices().len(),
            crack_crossings = book.crossings.len(),
            "progress"
        );
    }
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
    fn resumed_milestones_count_the_vertices_still_below() {
        let m = Milestones::resumed(&[0.5, 0.55, 0.7], 1.0, &[0.3, 0.6, 0.9], Some(0.25));
        let after: Vec<(f64, Milestone, usize)> = (m.times.iter().zip(&m.below))
            .map(|(&(t, w), &b)| (t, w, b))
            .collect();
        assert!(after.iter().all(|&(t, _, _)| t > 0.5), "{after:?}");
        assert_eq!(
            after.iter().filter(|a| a.1 == Milestone::History).count(),
            49
        );
        let below = |time: f64, what: Milestone| {
            after
                .iter()
                .find(|a| a.0 == time && a.1 == what)
                .map(|a| a.2)
        };
        assert_eq!(below(0.6, Milestone::Snapshot), Some(2));
        assert_eq!(below(0.9, Milestone::Snapshot), Some(3));
        assert_eq!(below(0.75, Milestone::Checkpoint), Some(3));
        assert_eq!(
            below(0.3, Milestone::Snapshot),
            None,
            "passed before the restart"
        );
        assert_eq!(below(0.51, Milestone::History), Some(1));
    }

    #[test]
    fn milestones_pass_when_every_vertex_has() {
        let mut m = Milestones::new(2, 1.0, &[0.0, 0.5], None, None);
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
