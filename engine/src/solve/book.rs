//! The bookkeeping of a solve: energy totals, history rows, snapshots and the milestone times
//! the whole front must pass before they are due.

use sdg_mesh::TagId;
use sdg_solver::crack::Crossing;
use sdg_solver::element::Geometry;
use sdg_solver::patch::{InterfaceSample, PatchReport};

use crate::output::snapshot::Snapshots;
use crate::progress::Progress;

/// A crack-tracking crossing with the tag of its edge.
pub(crate) type TaggedCrossing = (Option<TagId>, Crossing);

/// What a rank of a run over ranks records of its patches besides the history sums, for rank 0
/// to gather (module `rank_outputs`), and a checkpoint of it had recorded before (`rank_prior`).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct Records {
    /// The crack-tracking crossings with their edges' tags (global edge ids).
    pub(crate) crossings: Vec<TaggedCrossing>,
    /// The interface probes' samples: `(probe index, sample)`.
    pub(crate) samples: Vec<(usize, InterfaceSample)>,
}

impl Records {
    /// Adds `other`'s crossings and samples after these.
    pub(crate) fn append(&mut self, other: Records) {
        self.crossings.extend(other.crossings);
        self.samples.extend(other.samples);
    }
}

/// History rows are written when the whole front has passed each of this many equal fractions
/// of the end time (and at the end).
const HISTORY_ROWS: usize = 100;

/// The times (s) that each give a history row when the whole front has passed them, before
/// the end time `t_end` (s), increasing.
pub(crate) fn history_times(t_end: f64) -> Vec<f64> {
    (1..HISTORY_ROWS)
        .map(|k| t_end * k as f64 / HISTORY_ROWS as f64)
        .collect()
}

/// Times the whole front must pass before something happens, with a count of the vertices whose
/// recorded time is still below each.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Milestones {
    /// Increasing times (s) and what they are for.
    times: Vec<(f64, Milestone)>,
    below: Vec<usize>,
    next: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) enum Milestone {
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
    pub(crate) fn new(
        vertices: usize,
        t_end: f64,
        snapshots: &[f64],
        checkpoint_every: Option<f64>,
        intervention: Option<f64>,
    ) -> Self {
        let checkpoints = checkpoint_every.map_or(0, |dt| (t_end / dt).ceil() as usize);
        let mut times: Vec<(f64, Milestone)> = (history_times(t_end).into_iter())
            .map(|t| (t, Milestone::History))
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
    pub(crate) fn resumed(
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
    pub(crate) fn add_vertex(&mut self, t: f64) {
        for (i, &(time, _)) in self.times.iter().enumerate().skip(self.next) {
            if time > t {
                self.below[i] += 1;
            }
        }
    }

    /// Forgets a vertex at time `t` (s) removed by coarsening.
    pub(crate) fn remove_vertex(&mut self, t: f64) {
        for (i, &(time, _)) in self.times.iter().enumerate().skip(self.next) {
            if time > t {
                self.below[i] -= 1;
            }
        }
    }

    /// Records a vertex moving from `t_old` to `t_new`; returns the milestones the whole front
    /// has now passed, in order.
    pub(crate) fn advance(&mut self, t_old: f64, t_new: f64, passed: &mut Vec<(f64, Milestone)>) {
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
pub(crate) struct Book {
    pub(crate) totals: PatchReport,
    pub(crate) patches: u64,
    pub(crate) rejected: u64,
    pub(crate) refinements: u64,
    pub(crate) coarsenings: u64,
    /// Patches accepted with the indicator above the tolerance: no triangle of their star could
    /// be bisected (edge at `min_edge`, star at capacity, or causality).
    #[serde(default)]
    pub(crate) unresolved: u64,
    /// The largest indicator of those patches, in units of the tolerance.
    #[serde(default)]
    pub(crate) unresolved_max: f64,
    /// Interface probe samples: `(probe index, sample)`.
    pub(crate) samples: Vec<(usize, InterfaceSample)>,
    /// Crack-tracking crossings of cohesive faces with the tag of their edge.
    pub(crate) crossings: Vec<TaggedCrossing>,
    /// Crack nucleation, extension, branching and arrest, in the order they happened.
    pub(crate) fracture_events: Vec<crate::fracture::records::FractureEvent>,
    pub(crate) nonlinear_patches: u64,
    pub(crate) newton_iterations: u64,
    pub(crate) newton_max: usize,
    /// Energy of the initial data as the solver takes it in (scaled units): on the initial front,
    /// corrected whenever refinement splits a triangle that still carries initial data.
    pub(crate) initial_energy: f64,
    /// Largest `initial_energy + boundary work` so far (scaled units), the indicator's
    /// reference.
    pub(crate) energy_max: f64,
    pub(crate) elements: u64,
    pub(crate) dofs: u64,
    pub(crate) max_slope_ratio: f64,
    /// Wall time by stage so far, but the scheduler's (events, waiting).
    #[serde(default)]
    pub(crate) timings: super::Timings,
    pub(crate) snapshots: Snapshots,
    pub(crate) milestones: Milestones,
    #[serde(skip)]
    pub(crate) passed: Vec<(f64, Milestone)>,
    pub(crate) history: String,
    #[serde(skip)]
    pub(crate) progress: Progress,
    /// Basis values and element values for snapshot evaluation, and an element copy.
    #[serde(skip)]
    pub(crate) phi: Vec<f64>,
    #[serde(skip)]
    pub(crate) values: Vec<f64>,
    #[serde(skip)]
    pub(crate) geometry: Geometry,
    #[serde(skip)]
    pub(crate) coefficients: Vec<f64>,
}

impl Book {
    /// Makes a book read from a checkpoint ready to go on: scratch for `basis_len` basis
    /// functions of `width` fields, snapshots written to `output`'s folder in its format (those
    /// written before into another folder copied there); `None` for a run that writes nothing.
    pub(crate) fn resume(
        &mut self,
        output: Option<(&std::path::Path, crate::config::VtuFormat)>,
        basis_len: usize,
        width: usize,
    ) -> Result<(), crate::error::EngineError> {
        self.phi = vec![0.0; basis_len];
        self.values = vec![0.0; width];
        self.coefficients = vec![0.0; basis_len * width];
        match output {
            Some((dir, vtu)) => self.snapshots.set_output(dir, vtu),
            None => Ok(()),
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
