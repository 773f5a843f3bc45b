//! Outputs of contact interfaces: probes at configured points over time (`interface.csv`) and
//! the interfaces' cuts by the snapshot planes.
//!
//! After each accepted tent, every probe that lies on the edge of one of the patch's contact
//! faces is sampled halfway up that face (where the face has height: a probe at the face's far
//! end is sampled by the tent on the other side). Rows are sorted by probe and time, so the file
//! does not depend on the order in which tents were solved.

use sdg_solver::interface::Mode;
use sdg_solver::patch::{FaceCut, InterfaceSample, PatchSolver};

use crate::config::TimeConfig;
use crate::output::snapshot::InterfaceValues;
use crate::output::table::Table;
use crate::problem::Probe;

/// One interface face's cut by a snapshot plane: time (s), ends (m) and values there.
pub(crate) type Cut = (f64, [[f64; 2]; 2], [InterfaceValues; 2]);

/// Cuts the last patch's contact faces by the planes of the snapshot `times` (s) they cross.
pub(crate) fn snapshot_cuts(times: &[f64], solver: &mut PatchSolver) -> Vec<Cut> {
    let mut cuts = Vec::new();
    solver.snapshot_cuts(times, &mut cuts);
    cuts.iter().map(cut).collect()
}

/// A face's cut as the snapshots record it: time (s), ends (m) and values there (zero where
/// the face could not be sampled).
pub(crate) fn cut(cut: &FaceCut) -> Cut {
    let values = cut.samples.map(|s| {
        s.map_or_else(InterfaceValues::default, |s| InterfaceValues {
            delta: s.delta,
            slip: s.slip,
            damage: s.damage,
            traction: s.traction,
            eta: s.eta,
            mode: match s.mode {
                Mode::Stick => 0.0,
                Mode::Slip => 1.0,
                Mode::Separation => 2.0,
                Mode::Bonded => 3.0,
            },
        })
    });
    (cut.time, cut.ends, values)
}

/// `interface.csv`: one row per sample, sorted by probe and time, at its time on the clock of
/// `time`.
pub(crate) fn csv(
    probes: &[Probe],
    samples: &mut [(usize, InterfaceSample)],
    time: &TimeConfig,
) -> String {
    samples.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.time.total_cmp(&b.1.time)));
    let mut out = Table::new([
        "t_s",
        "x_m",
        "y_m",
        "tag",
        "s_n_pa",
        "s_t_pa",
        "sI_n_pa",
        "sI_t_pa",
        "delta_m",
        "slip_m",
        "jump_vn_m_s",
        "jump_vt_m_s",
        "eta",
        "gamma",
        "damage",
        "mode",
    ]);
    for (i, s) in samples.iter() {
        let probe = &probes[*i];
        let e = |v: f64| format!("{v:e}");
        out.row([
            e(time.clock(s.time)),
            e(probe.at[0]),
            e(probe.at[1]),
            probe.tag.to_string(),
            e(s.traction[0]),
            e(s.traction[1]),
            e(s.bonded_traction[0]),
            e(s.bonded_traction[1]),
            e(s.delta),
            e(s.slip),
            e(s.velocity_jump[0]),
            e(s.velocity_jump[1]),
            s.eta.to_string(),
            s.gamma.to_string(),
            s.damage.to_string(),
            s.mode.name().to_string(),
        ]);
    }
    out.into_text()
}
