//! The energy the body has held, as far as one rank knows: the bound of the blow-up guard over
//! ranks.
//!
//! On threads a patch that carries more than [`BLOW_UP`] times the most energy the body has
//! held (initial energy plus boundary work so far) out has blown up. A rank cannot know the
//! boundary work other ranks did, only what reached it: each rank sums the energy its patches
//! brought in through the boundary (their boundary work where positive), keeps per rank the
//! largest such sum it has heard of, and sends the entries that changed with its updates; a
//! receiver keeps the larger of each entry (each only grows, so order and duplicates do not
//! matter). The energy a patch reads came with its inflow, left by tents in its causal past;
//! every one of them was counted by its rank before that rank sent the update that carried the
//! inflow on (or before the tent, on the same rank), so a rank's bound at a tent covers the
//! initial energy and all that came in through the boundary in its causal past, whatever left
//! elsewhere: all a sound patch can carry out, and the guard never stops one. (The running
//! maximum of the net work, which the threaded run takes over the whole body, would not do: a
//! rank's net sum counts energy that left through its boundary outside a tent's causal past.)
//! Not a value of the run's results: only the guard reads it.
//!
//! [`BLOW_UP`]: sdg_solver::patch::BLOW_UP

use sdg_solver::patch::PatchReport;

use crate::partition::Rank;

/// What a rank knows of the energy the body has held (scaled units, as the patch reports').
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Held {
    /// The energy held before the first tent counted in `known`: the initial front's, plus the
    /// net boundary work before a restart.
    pub base: f64,
    /// Physical energy (J/m) per scaled unit, for messages: the density, kg/m^3.
    pub scale: f64,
    /// Per rank, the energy its patches brought in through the boundary (the sum of their
    /// positive boundary work), as far as this rank has heard.
    pub known: Vec<f64>,
}

impl Held {
    /// Nothing known beyond `base` on `ranks` ranks, with energies shown times `scale`.
    pub fn new(base: f64, scale: f64, ranks: usize) -> Self {
        Self {
            base,
            scale,
            known: vec![0.0; ranks],
        }
    }

    /// The most the body can have held before a tent of this rank now.
    pub fn bound(&self) -> f64 {
        self.base + self.known.iter().sum::<f64>()
    }

    /// Counts `report`, a patch solved on `rank` (this rank).
    pub fn add(&mut self, rank: Rank, report: &PatchReport) {
        self.known[rank as usize] += report.boundary_work.max(0.0);
    }

    /// Keeps the larger of each entry of `known` and of `entries`, `(rank, value)`.
    pub fn merge(&mut self, entries: impl IntoIterator<Item = (Rank, f64)>) {
        for (rank, value) in entries {
            if let Some(entry) = self.known.get_mut(rank as usize) {
                *entry = entry.max(value);
            }
        }
    }

    /// The entries of `known` that differ from `sent`, which then holds them: what an update
    /// to a rank last sent `sent` carries.
    pub fn changes(&self, sent: &mut [f64], out: &mut Vec<(Rank, f64)>) {
        for (r, (&now, then)) in self.known.iter().zip(sent.iter_mut()).enumerate() {
            if now != *then {
                *then = now;
                out.push((r as Rank, now));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn work(w: f64) -> PatchReport {
        PatchReport {
            boundary_work: w,
            ..PatchReport::default()
        }
    }

    /// A rank's entry sums the energy brought in (work that takes energy out does not lower
    /// it); merged entries keep the larger, in any order; changes carry each entry once.
    #[test]
    fn entries_only_grow_and_travel_once() {
        let mut held = Held::new(2.0, 1.0, 3);
        held.add(1, &work(3.0));
        held.add(1, &work(-2.0));
        assert_eq!(held.known, [0.0, 3.0, 0.0]);
        held.add(1, &work(2.0));
        assert_eq!(held.known, [0.0, 5.0, 0.0]);
        held.merge([(0, 1.5), (1, 4.0), (2, 0.5), (7, 9.0)]);
        held.merge([(0, 1.0)]);
        assert_eq!(held.known, [1.5, 5.0, 0.5]);
        assert_eq!(held.bound(), 2.0 + 7.0);
        let mut sent = vec![1.5, 0.0, 0.0];
        let mut out = Vec::new();
        held.changes(&mut sent, &mut out);
        assert_eq!(out, [(1, 5.0), (2, 0.5)]);
        out.clear();
        held.changes(&mut sent, &mut out);
        assert!(out.is_empty());
    }
}
