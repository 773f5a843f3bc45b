//! What a rank of a run over ranks sums of its tents as it solves them: the accounts of the
//! summary, of the history's rows and of a checkpoint's bookkeeping. A rank keeps no tent, so
//! its memory does not grow with the run; rank 0 merges the ranks' tallies.
//!
//! History row `k` (time `t_k`) counts the tents with `t_old < t_k` (module `rank_outputs`): a
//! tent goes into the bin of the first history time above its `t_old`, and a row's accounts
//! are its own bin and those before. Energy terms are exact sums ([`ExactSum`]): the totals are
//! the correctly rounded sums of every patch's terms for any partition and timing (a run on
//! threads adds them in the order it records the patches; the two agree to rounding). The
//! momentum diagnostics and the slope are maxima, the rest counts.

use sdg_distributed::SolvedPatch;
use sdg_mesh::Tent;
use sdg_solver::patch::{ENERGY_TERMS as ENERGY, MOMENTUM_TERMS as MOMENTUM, PatchReport};

use crate::exact_sum::ExactSum;

/// The tents of one history bin.
#[derive(Clone, Debug, Default)]
struct Bin {
    tents: u64,
    energy: [ExactSum; ENERGY],
    momentum: [f64; MOMENTUM],
}

impl Bin {
    fn merge(&mut self, other: &Bin) {
        self.tents += other.tents;
        for (sum, theirs) in self.energy.iter_mut().zip(&other.energy) {
            sum.merge(theirs);
        }
        for (m, &theirs) in self.momentum.iter_mut().zip(&other.momentum) {
            *m = m.max(theirs);
        }
    }
}

/// A rank's tents (or, merged, every rank's) summed by history bin.
#[derive(Clone, Debug)]
pub(crate) struct Tally {
    /// The history times, s (`crate::solve::book::history_times`).
    times: Vec<f64>,
    /// One bin per history time and one after the last.
    bins: Vec<Bin>,
    /// Per history time, the earliest `t_new` of the tents crossing it, s.
    earliest: Vec<f64>,
    elements: u64,
    dofs: u64,
    /// Patches with Newton iterations, their iterations and the most of one patch.
    nonlinear: u64,
    newton: u64,
    newton_max: u64,
    /// The largest slope of a front triangle a tent left, s/m.
    slope: f64,
    /// Assembly, solve and evaluation time summed over the patches, s.
    timings: [f64; 3],
}

impl Tally {
    /// No tents yet, for the history times `times` (s, increasing).
    pub(crate) fn new(times: &[f64]) -> Self {
        Self {
            times: times.to_vec(),
            bins: vec![Bin::default(); times.len() + 1],
            earliest: vec![f64::INFINITY; times.len()],
            elements: 0,
            dofs: 0,
            nonlinear: 0,
            newton: 0,
            newton_max: 0,
            slope: 0.0,
            timings: [0.0; 3],
        }
    }

    /// Adds a solved tent.
    pub(crate) fn add(&mut self, tent: &Tent, patch: &SolvedPatch) {
        let r = &patch.report;
        let first = self.times.partition_point(|&t| t <= tent.t_old);
        let last = self.times.partition_point(|&t| t <= tent.t_new);
        for e in &mut self.earliest[first..last] {
            *e = e.min(tent.t_new);
        }
        let bin = &mut self.bins[first];
        bin.tents += 1;
        for (sum, x) in bin.energy.iter_mut().zip(r.energy_terms()) {
            sum.add(x);
        }
        for (m, x) in bin.momentum.iter_mut().zip(r.momentum_terms()) {
            *m = m.max(x);
        }
        self.elements += r.elements as u64;
        self.dofs += r.dofs as u64;
        if r.newton_iterations > 0 {
            self.nonlinear += 1;
            self.newton += r.newton_iterations as u64;
            self.newton_max = self.newton_max.max(r.newton_iterations as u64);
        }
        self.slope = self.slope.max(patch.slope);
        for (t, x) in self
            .timings
            .iter_mut()
            .zip([r.assembly_s, r.solve_s, r.evaluation_s])
        {
            *t += x;
        }
    }

    /// Adds another rank's tally (of the same history times).
    pub(crate) fn merge(&mut self, other: &Tally) {
        for (bin, theirs) in self.bins.iter_mut().zip(&other.bins) {
            bin.merge(theirs);
        }
        for (e, &theirs) in self.earliest.iter_mut().zip(&other.earliest) {
            *e = e.min(theirs);
        }
        self.elements += other.elements;
        self.dofs += other.dofs;
        self.nonlinear += other.nonlinear;
        self.newton += other.newton;
        self.newton_max = self.newton_max.max(other.newton_max);
        self.slope = self.slope.max(other.slope);
        for (t, &theirs) in self.timings.iter_mut().zip(&other.timings) {
            *t += theirs;
        }
    }

    /// The tents summed.
    pub(crate) fn tents(&self) -> u64 {
        self.bins.iter().map(|b| b.tents).sum()
    }

    /// The earliest end of the tents crossing history time `k`, s (infinite if none does).
    pub(crate) fn earliest(&self, k: usize) -> f64 {
        self.earliest[k]
    }

    /// Running accounts over the bins in order, starting from `prior`'s.
    pub(crate) fn running(&self, prior: &PatchReport) -> Running<'_> {
        Running {
            tally: self,
            prior: *prior,
            next: 0,
            tents: 0,
            sums: Default::default(),
            momentum: prior.momentum_terms(),
        }
    }

    /// `prior`'s accounts with every tent's added.
    pub(crate) fn totals(&self, prior: &PatchReport) -> PatchReport {
        let mut running = self.running(prior);
        running.through(self.bins.len() - 1);
        running.report()
    }

    /// Patches with Newton iterations, their iterations and the most of one patch.
    pub(crate) fn newton(&self) -> (u64, u64, usize) {
        (self.nonlinear, self.newton, self.newton_max as usize)
    }

    /// Elements and unknowns solved, summed over the patches.
    pub(crate) fn elements_and_dofs(&self) -> (u64, u64) {
        (self.elements, self.dofs)
    }

    /// The largest slope of a front triangle a tent left, s/m.
    pub(crate) fn slope(&self) -> f64 {
        self.slope
    }

    /// Assembly, solve and evaluation time summed over the patches, s.
    pub(crate) fn timings(&self) -> [f64; 3] {
        self.timings
    }

    /// Appends the tally to `values` ([`Self::take`] reads it back).
    pub(crate) fn push_values(&self, values: &mut Vec<f64>) {
        for bin in &self.bins {
            values.push(bin.tents as f64);
            for sum in &bin.energy {
                values.push(sum.partials().len() as f64);
                values.extend_from_slice(sum.partials());
            }
            values.extend_from_slice(&bin.momentum);
        }
        values.extend_from_slice(&self.earliest);
        values.extend([
            self.elements as f64,
            self.dofs as f64,
            self.nonlinear as f64,
            self.newton as f64,
            self.newton_max as f64,
            self.slope,
        ]);
        values.extend_from_slice(&self.timings);
    }

    /// The tally for the history times `times` that [`Self::push_values`] put at the start of
    /// `values`, and the values after it; `None` for values of the wrong form.
    pub(crate) fn take<'v>(values: &'v [f64], times: &[f64]) -> Option<(Self, &'v [f64])> {
        let mut tally = Self::new(times);
        let mut rest = values;
        let mut next = |n: usize| -> Option<&'v [f64]> {
            let (head, tail) = rest.split_at_checked(n)?;
            rest = tail;
            Some(head)
        };
        for bin in &mut tally.bins {
            bin.tents = next(1)?[0] as u64;
            for sum in &mut bin.energy {
                let n = next(1)?[0] as usize;
                *sum = ExactSum::from_partials(next(n)?);
            }
            bin.momentum.copy_from_slice(next(MOMENTUM)?);
        }
        tally.earliest.copy_from_slice(next(times.len())?);
        let counts = next(6)?;
        tally.elements = counts[0] as u64;
        tally.dofs = counts[1] as u64;
        tally.nonlinear = counts[2] as u64;
        tally.newton = counts[3] as u64;
        tally.newton_max = counts[4] as u64;
        tally.slope = counts[5];
        tally.timings.copy_from_slice(next(3)?);
        Some((tally, rest))
    }
}

/// Accounts summed over the bins of a [`Tally`] in order ([`Tally::running`]).
pub(crate) struct Running<'t> {
    tally: &'t Tally,
    prior: PatchReport,
    /// The first bin not summed yet.
    next: usize,
    tents: u64,
    sums: [ExactSum; ENERGY],
    momentum: [f64; MOMENTUM],
}

impl Running<'_> {
    /// Sums the bins up to `k` (inclusive) that are not summed yet.
    pub(crate) fn through(&mut self, k: usize) {
        while self.next <= k.min(self.tally.bins.len() - 1) {
            let bin = &self.tally.bins[self.next];
            self.tents += bin.tents;
            for (sum, theirs) in self.sums.iter_mut().zip(&bin.energy) {
                sum.merge(theirs);
            }
            for (m, &theirs) in self.momentum.iter_mut().zip(&bin.momentum) {
                *m = m.max(theirs);
            }
            self.next += 1;
        }
    }

    /// Tents summed so far.
    pub(crate) fn tents(&self) -> u64 {
        self.tents
    }

    /// The prior accounts with the tents summed so far.
    pub(crate) fn report(&self) -> PatchReport {
        let mut r = self.prior;
        r.add_terms(self.sums.each_ref().map(ExactSum::value), self.momentum);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn patch(x: f64, newton: usize) -> SolvedPatch {
        SolvedPatch {
            report: PatchReport {
                energy_in: x,
                boundary_work: -x / 3.0,
                dissipation: x * 1e-17,
                momentum_residual: x,
                elements: 6,
                dofs: 120,
                newton_iterations: newton,
                ..PatchReport::default()
            },
            slope: x,
        }
    }

    /// Tents split over two tallies in one order and over three in another merge to the same
    /// accounts, and the values read back to a tally of the same accounts.
    #[test]
    fn tallies_merge_to_the_same_accounts_in_any_order_and_split() {
        let times = [0.25, 0.5, 0.75, 1.0];
        let tents: Vec<(Tent, SolvedPatch)> = (0..40)
            .map(|i| {
                let t_old = (i % 9) as f64 * 0.11;
                let tent = Tent {
                    vertex: i,
                    t_old,
                    t_new: t_old + 0.13,
                };
                (
                    tent,
                    patch(
                        1.0 + (i as f64) * 1e-3 + 1e16 * f64::from(i % 2),
                        i as usize % 3,
                    ),
                )
            })
            .collect();
        let merged = |split: usize, reverse: bool| {
            let mut parts = vec![Tally::new(&times); split];
            let mut order: Vec<usize> = (0..tents.len()).collect();
            if reverse {
                order.reverse();
            }
            for (n, &i) in order.iter().enumerate() {
                parts[n % split].add(&tents[i].0, &tents[i].1);
            }
            let mut all = Tally::new(&times);
            for part in &parts {
                all.merge(part);
            }
            all
        };
        let (a, b) = (merged(2, false), merged(3, true));
        let prior = PatchReport {
            energy_in: 2.0,
            ..PatchReport::default()
        };
        let (ta, tb) = (a.totals(&prior), b.totals(&prior));
        assert_eq!(ta.energy_in.to_bits(), tb.energy_in.to_bits());
        assert_eq!(ta.boundary_work.to_bits(), tb.boundary_work.to_bits());
        assert_eq!(ta.dissipation.to_bits(), tb.dissipation.to_bits());
        let exact: f64 = 2.0 + tents.iter().map(|(_, p)| p.report.energy_in).sum::<f64>();
        assert!((ta.energy_in - exact).abs() <= 1e-15 * exact);
        assert_eq!(ta.momentum_residual, 1.0 + 39e-3 + 1e16);
        assert_eq!((a.tents(), b.tents()), (40, 40));
        assert_eq!(a.newton(), b.newton());
        assert_eq!(a.elements_and_dofs(), (240, 4800));
        // Row k counts the tents with t_old < t_k.
        let mut running = a.running(&PatchReport::default());
        for (k, &t_k) in times.iter().enumerate() {
            running.through(k);
            let below = tents.iter().filter(|(t, _)| t.t_old < t_k).count() as u64;
            assert_eq!(running.tents(), below, "row {k}");
            let crossing = tents
                .iter()
                .filter(|(t, _)| t.t_old < t_k && t_k <= t.t_new);
            let earliest = crossing.map(|(t, _)| t.t_new).fold(f64::INFINITY, f64::min);
            assert_eq!(a.earliest(k), earliest, "row {k}");
            assert_eq!(b.earliest(k), earliest, "row {k}");
        }
        let mut values = Vec::new();
        a.push_values(&mut values);
        values.push(42.0);
        let (back, rest) = Tally::take(&values, &times).expect("its own values");
        assert_eq!(rest, &[42.0]);
        let tb = back.totals(&prior);
        assert_eq!(tb.energy_in.to_bits(), ta.energy_in.to_bits());
        assert_eq!(tb.dissipation.to_bits(), ta.dissipation.to_bits());
        assert_eq!(tb.momentum_residual, ta.momentum_residual);
        assert_eq!((back.tents(), back.newton()), (a.tents(), a.newton()));
        assert_eq!(back.earliest, a.earliest);
        assert_eq!((back.slope(), back.timings()), (a.slope(), a.timings()));
        assert!(Tally::take(&values[..values.len() - 3], &times).is_none());
    }
}
