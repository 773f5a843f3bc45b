//! The seed's contact examples (3.4) through the shipped configs: histories on the interface
//! against an independent 1D reference, energy balance with friction.

use crate::common;

use std::path::Path;

/// `c_d` and `Z = rho c_d` in plane strain.
fn p_wave() -> (f64, f64) {
    common::pmma_p_wave()
}

/// The C1 cubic step `3 r^2 - 2 r^3` of `r` clamped to [0, 1].
fn smoothstep(r: f64) -> f64 {
    let r = r.clamp(0.0, 1.0);
    r * r * (3.0 - 2.0 * r)
}

/// The load multiplier of `contact_separation.toml` at `t` (s): 0, then -1 (compression) for
/// three quarters of each 2 us period and +1 for the last quarter, ramps of 0.2 us.
fn load(t: f64) -> f64 {
    let us = t * 1e6;
    if us < 0.2 {
        return -smoothstep(us / 0.2);
    }
    // Within a period from the first ramp's end: up at 1.5 us, down at 2.0 us.
    let phase = (us - 1.4).rem_euclid(2.0);
    if us < 1.4 {
        -1.0
    } else if phase < 0.2 {
        -1.0 + 2.0 * smoothstep(phase / 0.2)
    } else if phase < 0.5 {
        1.0
    } else if phase < 0.7 {
        1.0 - 2.0 * smoothstep((phase - 0.5) / 0.2)
    } else {
        -1.0
    }
}

/// The cubic smoothstep area fraction of `x` between `lo` (1) and `hi` (0).
fn fraction(x: f64, lo: f64, hi: f64) -> f64 {
    if x <= lo {
        1.0
    } else if x >= hi {
        0.0
    } else {
        smoothstep((hi - x) / (hi - lo))
    }
}

/// One point of the 1D reference: time (s), separation (m), normal target traction (Pa).
type Reference = Vec<(f64, f64, f64)>;

/// The 1D reference of seed 3.4.1: both faces receive `w(t - t0)`, `w = 2 sigma`, so the
/// bonded normal traction is `sI = w(t - t0)` and `d delta / dt = (2 / Z) (1 - eta) sI` with
/// `eta = eta_delta(delta) eta_s(sI)`; the target traction is `eta sI`. RK4 in steps of 1e-11 s.
fn reference(amplitude: f64, r: [f64; 2], s: [f64; 2], t_end: f64) -> Reference {
    let (c, z) = p_wave();
    let t0 = 0.002 / c;
    let si = |t: f64| amplitude * if t > t0 { load(t - t0) } else { 0.0 };
    let rate = |t: f64, delta: f64| {
        let eta = fraction(delta, r[0], r[1]) * fraction(si(t), s[0], s[1]);
        2.0 / z * (1.0 - eta) * si(t)
    };
    let dt = 1e-11;
    let (mut t, mut delta) = (0.0, 0.0);
    let mut out = Vec::new();
    while t < t_end {
        let k1 = rate(t, delta);
        let k2 = rate(t + 0.5 * dt, delta + 0.5 * dt * k1);
        let k3 = rate(t + 0.5 * dt, delta + 0.5 * dt * k2);
        let k4 = rate(t + dt, delta + dt * k3);
        delta += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        t += dt;
        let eta = fraction(delta, r[0], r[1]) * fraction(si(t), s[0], s[1]);
        out.push((t, delta, eta * si(t)));
    }
    out
}

/// Rows of `interface.csv`: (t, s_n, delta, mode).
fn interface_rows(dir: &Path) -> Vec<(f64, f64, f64, String)> {
    let text = std::fs::read_to_string(dir.join("interface.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, s, d, m) = (col("t_s"), col("s_n_pa"), col("delta_m"), col("mode"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[t].parse().unwrap(),
                f[s].parse().unwrap(),
                f[d].parse().unwrap(),
                f[m].to_string(),
            )
        })
        .collect()
}

/// When the interface closes again after its first separation (the seed's shock): the 1D
/// reference's traction jumps there, first below half its peak.
fn closing_shock(reference: &Reference, t0: f64) -> f64 {
    let opened = reference
        .iter()
        .position(|p| p.0 > t0 + 1.5e-6 && p.2 == 0.0)
        .expect("the interface opens");
    reference[opened..]
        .iter()
        .find(|p| p.2 < -1e8)
        .expect("the interface closes")
        .0
}

/// The seed's first regularization set (3.4.1): `r_c` = -1 um, `s_s` = 600 kPa.
#[test]
fn contact_separation_follows_the_1d_reference() {
    follows_the_1d_reference(-1e-6, 6e5);
}

/// The seed's second set, ten times stiffer: the same assertions (about 40 s on 2 cores, out of
/// CI for its time; `cargo test --release --test suite
/// contact::contact_separation_with_the_stiffer_regularization_follows_the_1d_reference --
/// --ignored`).
#[test]
#[ignore = "40 s on 2 cores: run on demand"]
fn contact_separation_with_the_stiffer_regularization_follows_the_1d_reference() {
    follows_the_1d_reference(-1e-7, 6e4);
}

/// `contact_separation.toml` with the regularization `r_c` (m) and `s_s` (Pa) against the 1D
/// reference: separation and traction within 1% of their peaks, the mode changes at the seed's
/// times, momentum and energy balanced.
fn follows_the_1d_reference(r_c: f64, s_s: f64) {
    let (c, _) = p_wave();
    let t0 = 0.002 / c;
    let t_end = 4.5e-6;
    // 62.5 um cells (ny = 64) at p = 3: at 125 um the kinks of the load's C1 ramps (their
    // curvature jumps) cost 1.4% of the peak traction where they reach the interface.
    let ny = 64;
    // The closing shock is a jump of the exact traction: a sample within one element's transit
    // time of it compares the jump's two sides, whatever the resolution.
    let near_shock = 0.004 / ny as f64 / c;
    let problem = common::shipped(
        "contact_separation.toml",
        &[
            &format!("time.end={t_end}"),
            &format!("interface.0.r_c={r_c}"),
            &format!("interface.0.s_s={s_s}"),
            &format!("mesh.ny={ny}"),
        ],
    );
    let (summary, dir) = common::solve(&problem, 2, true);
    // Every element balances momentum, those still at rest included (each of their
    // fluxes is round-off: against their own they read up to 1, until 2026-11-28).
    assert!(
        summary.max_momentum_residual < 1e-10,
        "{}",
        summary.max_momentum_residual
    );
    let rows = interface_rows(dir.path());
    let reference = reference(2e8, [r_c, 0.0], [0.0, s_s], t_end);
    let at = |t: f64| {
        let i = reference
            .partition_point(|p| p.0 < t)
            .min(reference.len() - 1);
        reference[i]
    };
    let peak = |get: fn(&(f64, f64, f64)) -> f64| {
        reference.iter().map(|p| get(p).abs()).fold(0.0, f64::max)
    };
    let (delta_peak, s_peak) = (peak(|p| p.1), peak(|p| p.2));
    let shock = closing_shock(&reference, t0);
    let (mut delta_err, mut s_err, mut s_err_shock) = (0.0f64, 0.0f64, 0.0f64);
    for &(t, s, delta, _) in &rows {
        let (_, d_ref, s_ref) = at(t);
        delta_err = delta_err.max((delta - d_ref).abs() / delta_peak);
        let e = (s - s_ref).abs() / s_peak;
        if (t - shock).abs() < near_shock {
            s_err_shock = s_err_shock.max(e);
        } else {
            s_err = s_err.max(e);
        }
    }
    // Mode changes: separation starts when the tensile load arrives (t0 + 1.5 us, the
    // seed's 2.46 us), ends when the faces meet again (the seed's t0 + 5T/4 = 3.46 us) and
    // starts again a period after the first (the seed's 4.46 us).
    let changes: Vec<(f64, bool)> = rows
        .windows(2)
        .filter(|w| (w[0].3 == "separation") != (w[1].3 == "separation"))
        .map(|w| (0.5 * (w[0].0 + w[1].0), w[1].3 == "separation"))
        .filter(|&(t, _)| t > t0 + 0.5e-6)
        .collect();
    eprintln!(
        "r_c {r_c} m, s_s {s_s} Pa: {} rows, {} patches ({} nonlinear, {:.2} solves each, at \
         most {}); largest errors over the peaks: delta {delta_err:.2e} (peak {delta_peak:.3e} \
         m), s_n {s_err:.2e} ({s_err_shock:.2e} within {near_shock:.1e} s of the closing \
         shock at {shock:.4e} s; peak {s_peak:.3e} Pa); separation from/to at {changes:?}; \
         energy balance {:.1e}",
        rows.len(),
        summary.patches,
        summary.interface.nonlinear_patches,
        summary.interface.newton_iterations_mean,
        summary.interface.newton_iterations_max,
        summary.energy.balance_residual_rel
    );
    assert!(rows.len() > 100);
    assert!(delta_err < 0.01, "{delta_err}");
    assert!(s_err < 0.01, "{s_err}");
    let opened = [
        (t0 + 1.5e-6, true),
        (t0 + 2.5e-6, false),
        (t0 + 3.5e-6, true),
    ];
    assert_eq!(changes.len(), opened.len(), "{changes:?}");
    for ((t, open), (expected, want)) in changes.iter().zip(opened) {
        assert_eq!(*open, want);
        assert!((t - expected).abs() < 0.05e-6, "{t} against {expected}");
    }
    assert!(summary.energy.balance_residual_rel.abs() < 1e-10);
}

/// The slip (m) of the interface probe at `x` (m) of `interface.csv` in `dir`, at the row
/// nearest to each of `times` (s).
fn slips_at(dir: &Path, x: f64, times: &[f64]) -> Vec<f64> {
    let text = std::fs::read_to_string(dir.join("interface.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, px, slip) = (col("t_s"), col("x_m"), col("slip_m"));
    let rows: Vec<(f64, f64)> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| (f[px].parse::<f64>().unwrap() - x).abs() < 1e-9)
        .map(|f| (f[t].parse().unwrap(), f[slip].parse().unwrap()))
        .collect();
    assert!(!rows.is_empty(), "no probe at x = {x}");
    times
        .iter()
        .map(|&at| {
            let nearest = rows
                .iter()
                .min_by(|a, b| (a.0 - at).abs().total_cmp(&(b.0 - at).abs()))
                .unwrap();
            nearest.1.abs()
        })
        .collect()
}

#[test]
fn stick_slip_balances_energy_and_slips_as_the_seed_describes() {
    // The shipped run as shipped (p = 3, 16 cells a side, to 12 us); its reading of the seed's
    // loads and the other readings are compared in docs/verification.md
    // (scripts/stick_slip_readings.py).
    let problem = common::shipped("stick_slip.toml", &["output.snapshot_times=[]"]);
    let (summary, dir) = common::solve(&problem, 2, true);
    let e = summary.energy;
    let friction = 100.0 * e.friction_dissipation / e.boundary_work;
    let numerical = 100.0 * e.dissipation / e.boundary_work;
    let times = [3e-6, 7e-6, 9e-6, 12e-6];
    let (end, centre) = (
        slips_at(dir.path(), 1.25e-4, &times),
        slips_at(dir.path(), 2.125e-3, &times),
    );
    eprintln!(
        "stick-slip: inflow {:.4e} J/m, friction {friction:.3}%, numerical dissipation \
         {numerical:.4}%, balance {:.1e}; slip (m) at 3, 7, 9, 12 us: near the left end \
         {end:?}, at the centre {centre:?}; {} patches ({} nonlinear, {:.2} solves each, \
         at most {})",
        e.boundary_work,
        e.balance_residual_rel,
        summary.patches,
        summary.interface.nonlinear_patches,
        summary.interface.newton_iterations_mean,
        summary.interface.newton_iterations_max,
    );
    assert!(e.balance_residual_rel.abs() < 1e-8);
    assert!(e.interface_work >= e.friction_dissipation);
    // The converged share of this reading (docs/verification.md: 13.57% on 16 cells, the same
    // to 0.1 point on 32); the seed's 30.6% is not reproduced by any reading its words allow.
    assert!((friction - 13.57).abs() < 0.1, "friction {friction}%");
    // The seed: 0.02%; ours falls with the mesh (0.034% here).
    assert!(numerical < 0.05, "numerical dissipation {numerical}%");
    // The seed's account (3.4.2): slip before the waves arrive is negligible; at 7 us small slip
    // near the ends of the interface only; much larger at 9 and 12 us.
    assert!(end[0] < 1e-5 && end[1] < 1e-5, "{end:?}");
    assert!(
        centre[1] < 1e-7,
        "the centre still sticks at 7 us: {centre:?}"
    );
    assert!(end[2] > 2.0 * end[1] && end[3] > 10.0 * end[1], "{end:?}");
    assert!(centre[3] > 1e-5, "the centre slips by 12 us: {centre:?}");
}
