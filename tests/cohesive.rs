//! Cohesive interfaces (Xu-Needleman, seed 2.2.5, 2.5.2) through the shipped configs: a plane
//! wave stretching a cohesive interface below its strength against an independent 1D reference,
//! with the work of the cohesive tractions in the energy balance; determinism across thread
//! counts; the mode-I crack of `mode1_lefm.toml` against LEFM, whose reference (seed 2.5.1)
//! lives in `lefm/`.

use crate::common;
use crate::lefm;

use std::path::Path;

/// The seed's cohesive law in `cohesive_wave.toml`.
const SIGMA_C: f64 = 3.24e8;
const DELTA_C: f64 = 4e-7;
/// The incoming characteristic's level in `cohesive_wave.toml`, Pa, and its ramp, s.
const W: f64 = 0.8 * SIGMA_C;
const RAMP: f64 = 0.2e-6;
/// The level in `decohesion.toml`, Pa.
const W_DECOHESION: f64 = 1.25 * SIGMA_C;

/// `c_d` and `Z = rho c_d` in plane strain.
fn p_wave() -> (f64, f64) {
    common::pmma_p_wave()
}

/// The Xu-Needleman normal traction at a normal opening `delta >= 0` without slip, (2.69).
fn traction(delta: f64) -> f64 {
    let d = delta / DELTA_C;
    SIGMA_C * d * (1.0 - d).exp()
}

/// The 1D reference for a wave of level `w`: both faces receive `w(t - t0)`, so the bonded
/// traction is `sI = w(t - t0)` and the opening obeys `d delta / dt = (2 / Z)(sI - T(delta))` (the faces
/// keep their outgoing characteristics; no contact in tension). RK4 in steps of 1e-12 s, well
/// below the law's time constant `Z delta_c / (2 e sigma_c) = 0.57 ns`. Returns
/// `(t, delta, T(delta))` every 1e-10 s.
fn reference(w: f64, t_end: f64) -> Vec<(f64, f64, f64)> {
    let (c, z) = p_wave();
    let t0 = 0.002 / c;
    let si = |t: f64| {
        let r = ((t - t0) / RAMP).clamp(0.0, 1.0);
        w * r * r * (3.0 - 2.0 * r)
    };
    let rate = |t: f64, delta: f64| 2.0 / z * (si(t) - traction(delta));
    let dt = 1e-12;
    let (mut t, mut delta) = (0.0, 0.0);
    let mut out = Vec::new();
    for step in 0.. {
        if t >= t_end {
            break;
        }
        let k1 = rate(t, delta);
        let k2 = rate(t + 0.5 * dt, delta + 0.5 * dt * k1);
        let k3 = rate(t + 0.5 * dt, delta + 0.5 * dt * k2);
        let k4 = rate(t + dt, delta + dt * k3);
        delta += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        t += dt;
        if step % 100 == 99 {
            out.push((t, delta, traction(delta)));
        }
    }
    out
}

/// Rows of `interface.csv`: (t, s_n, delta).
fn interface_rows(dir: &Path) -> Vec<(f64, f64, f64)> {
    let text = std::fs::read_to_string(dir.join("interface.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, s, d) = (col("t_s"), col("s_n_pa"), col("delta_m"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[t].parse().unwrap(),
                f[s].parse().unwrap(),
                f[d].parse().unwrap(),
            )
        })
        .collect()
}

/// Checks a run of `cohesive_wave.toml` (summary, output folder) against the 1D reference: the
/// opening and the traction at the probe while the load ramps and holds, the fracture energy
/// against the law's potential, the balance, and no crack tip.
fn check_spring(summary: &sdg_engine::RunSummary, dir: &Path) {
    let t_end = 2e-6;
    let rows = interface_rows(dir);
    let reference = reference(W, t_end);
    let at = |t: f64| {
        reference[reference
            .partition_point(|p| p.0 < t)
            .min(reference.len() - 1)]
    };
    // The opening where T(delta) = w on the rising branch, by bisection.
    let (mut lo, mut hi) = (0.0, DELTA_C);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if traction(mid) < W {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let delta_hold = lo;
    let (mut delta_err, mut s_err) = (0.0f64, 0.0f64);
    for &(t, s, delta) in &rows {
        let (_, d_ref, s_ref) = at(t);
        delta_err = delta_err.max((delta - d_ref).abs() / delta_hold);
        s_err = s_err.max((s - s_ref).abs() / W);
    }
    let &(_, s_last, delta_last) = rows.last().unwrap();
    // The work of the cohesive tractions is the law's potential at the final opening, per unit
    // area, over the 4 mm interface: phi (1 - (1 + D) e^-D).
    let d = delta_last / DELTA_C;
    let phi = phi();
    let stored = 0.004 * phi * (1.0 - (1.0 + d) * (-d).exp());
    let energy = summary.energy.fracture_energy;
    eprintln!(
        "{} rows, {} patches ({} nonlinear, {:.2} solves each, {} refinements, {} \
         coarsenings); largest errors: delta {delta_err:.2e} of {delta_hold:.4e} m, s_n \
         {s_err:.2e} of {W:.3e} Pa; final delta {delta_last:.5e} m, s_n {s_last:.5e} Pa; \
         fracture energy {energy:.5e} J/m against the potential {stored:.5e}; balance {:.1e}",
        rows.len(),
        summary.patches,
        summary.interface.nonlinear_patches,
        summary.interface.newton_iterations_mean,
        summary.refinements,
        summary.coarsenings,
        summary.energy.balance_residual_rel
    );
    assert!(rows.len() > 20);
    // Measured: 1.3e-2 and 6.8e-3 on the shipped mesh, largest while the load ramps (tents of
    // about 0.05 us against a 0.2 us ramp); the hold values to 1e-3 below.
    assert!(delta_err < 0.02, "{delta_err}");
    assert!(s_err < 0.01, "{s_err}");
    assert!((delta_last / delta_hold - 1.0).abs() < 1e-3);
    assert!((s_last / W - 1.0).abs() < 1e-3);
    assert!((energy / stored - 1.0).abs() < 0.01, "{energy} vs {stored}");
    // Opening only: no face slides in contact.
    assert_eq!(summary.energy.friction_dissipation, 0.0);
    assert!(summary.energy.balance_residual_rel.abs() < 1e-9);
    // Below the strength nothing reaches delta_c: no crack tip.
    let crack = summary
        .crack
        .as_ref()
        .expect("a cohesive run reports its cracks");
    assert_eq!(crack.tip_states, 0);
    let tips = std::fs::read_to_string(dir.join("crack_tips.csv")).unwrap();
    assert_eq!(tips.lines().count(), 1, "the header only");
}

#[test]
fn a_cohesive_interface_below_its_strength_is_a_nonlinear_spring() {
    let problem = common::shipped("cohesive_wave.toml", &[]);
    let (summary, dir) = common::solve(&problem, 2, true);
    check_spring(&summary, dir.path());
}

/// Segments of the interface on a snapshot's slice (`cracks_NNNN.vtu`): one per interface
/// face the plane cuts, so one per interface edge where the slice crosses each face once.
fn interface_segments(dir: &Path, k: usize) -> usize {
    let text = std::fs::read_to_string(dir.join(format!("cracks_{k:04}.vtu"))).unwrap();
    let at = text.find("NumberOfCells=\"").unwrap() + "NumberOfCells=\"".len();
    text[at..].split('"').next().unwrap().parse().unwrap()
}

/// With adaptivity the wave's arrival refines the front across the interface and the calm that
/// follows coarsens it again, the interface's own edges included: their separation crosses each
/// coarsening on the coarsening patch's face (no projection), so the opening still follows the
/// reference and the energy still balances.
#[test]
fn coarsening_across_a_cohesive_interface_keeps_the_spring() {
    let problem = common::shipped(
        "cohesive_wave.toml",
        &[
            "adapt.enabled=true",
            "adapt.tol=0.3",
            // Measured: 196 refinements, as many coarsenings, 11,940 patches (with 30 um: 704 and
            // 20,135 for the same checks).
            "adapt.min_edge=60e-6",
            "output.snapshot_times=[1.2e-6, 2e-6]",
        ],
    );
    let (summary, dir) = common::solve(&problem, 2, true);
    check_spring(&summary, dir.path());
    // Measured: 8 interface segments at 1.2 us (every interface edge halved), 4 at the end.
    let (refined, end) = (
        interface_segments(dir.path(), 0),
        interface_segments(dir.path(), 1),
    );
    assert!(refined > 4, "the interface was refined: {refined} segments");
    assert_eq!(end, 4, "and coarsened back to the mesh's four edges");
    assert!(summary.coarsenings > 0);
}

#[test]
fn decohesion_absorbs_the_work_of_separation_when_the_1d_reference_does() {
    let width = 0.001;
    let problem = common::shipped("decohesion.toml", &[]);
    let (summary, dir) = common::solve(&problem, 2, true);
    let reference = reference(W_DECOHESION, 1.2e-6);
    let opened = reference
        .iter()
        .find(|p| p.1 >= DELTA_C)
        .expect("the reference decoheres")
        .0;
    let phi = phi();
    let energy = summary.energy.fracture_energy;
    let tips = std::fs::read_to_string(dir.path().join("crack_tips.csv")).unwrap();
    let times: Vec<f64> = tips
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    let spread = times
        .iter()
        .map(|t| (t - opened).abs())
        .fold(0.0f64, f64::max);
    let rows = interface_rows(dir.path());
    let peak = rows.iter().map(|r| r.1).fold(f64::MIN, f64::max);
    eprintln!(
        "{} patches ({} rejected, {} refinements, smallest edge {:.2e} m); fracture energy \
         {energy:.6e} J/m against phi x width {:.6e}; {} tip states at most {spread:.2e} s from \
         the reference's delta_c time {opened:.6e} s; largest sampled traction {:.4} sigma_c; \
         balance {:.1e}",
        summary.patches,
        summary.rejected_patches,
        summary.refinements,
        summary.min_edge,
        phi * width,
        times.len(),
        peak / SIGMA_C,
        summary.energy.balance_residual_rel
    );
    // Measured: 0.22% below phi x width, tips within 1.8 ns of the reference.
    assert!((energy / (phi * width) - 1.0).abs() < 0.01, "{energy}");
    assert!(times.len() >= 4 && spread < 5e-9, "{times:?} vs {opened}");
    assert!(peak > 0.97 * SIGMA_C && peak < 1.01 * SIGMA_C, "{peak}");
    assert!(summary.refinements > 0, "decohesion needs small tents");
    assert!(summary.energy.balance_residual_rel.abs() < 1e-9);
}

#[test]
fn cohesive_runs_are_bitwise_deterministic_across_thread_counts() {
    let problem = common::shipped("cohesive_wave.toml", &["time.end=1.3e-6"]);
    let (one, dir_one) = common::solve(&problem, 1, true);
    let (two, dir_two) = common::solve(&problem, 2, true);
    assert!(one.interface.nonlinear_patches > 0);
    assert_eq!(one.state_hash, two.state_hash);
    assert_eq!(
        common::outputs(dir_one.path()),
        common::outputs(dir_two.path())
    );
}

/// The mode-I configs' (tau' (s), t0 (s), c_R (m/s)) from the material, the law, the load ratio
/// `ratio` (sigma') and the distance `half` (m) from the loaded sides to the crack plane,
/// independently of the solver (seed 2.59, 2.67).
fn mode1_scales_at(ratio: f64, half: f64) -> (f64, f64, f64) {
    let (e, nu, rho): (f64, f64, f64) = (3.24e9, 0.35, 1190.0);
    let mu = e / (2.0 * (1.0 + nu));
    let (c_d, _) = p_wave();
    let c_s = (mu / rho).sqrt();
    let sigma_bar = ratio * SIGMA_C;
    let tau = std::f64::consts::PI * mu * phi() * c_d / (4.0 * (c_s * sigma_bar).powi(2));
    (tau, half / c_d, lefm::rayleigh_speed(c_d, c_s))
}

/// `configs/mode1_lefm.toml`'s scales: sigma' = 0.1, crack plane 1.2 mm from the loaded sides.
fn mode1_scales() -> (f64, f64, f64) {
    mode1_scales_at(0.1, 1.2e-3)
}

/// The work of separation `phi = e sigma_c delta_c` (2.70), J/m^2.
fn phi() -> f64 {
    std::f64::consts::E * SIGMA_C * DELTA_C
}

/// The energy released per unit crack extension between normalized times `from` and the end of
/// the run in `dir` (J/m^2): the growth of `fracture_energy_j` in `history.csv` over the growth
/// of the extension in `crack_tips.csv` (the latest tip state at each of the two rows' times).
fn energy_release_rate(dir: &Path, from: f64, (tau, t0): (f64, f64)) -> f64 {
    let history = common::csv_columns(&dir.join("history.csv"), &["time_s", "fracture_energy_j"]);
    let tips = tip_rows(dir);
    let extension = |t: f64| {
        tips.iter()
            .take_while(|r| r.0 <= t)
            .last()
            .map_or(0.0, |r| r.1)
    };
    let first = history
        .iter()
        .find(|r| (r[0] - t0) / tau >= from)
        .expect("history rows after the start");
    let last = history.last().unwrap();
    let grown = extension(last[0]) - extension(first[0]);
    assert!(grown > 0.0, "the crack grew after t' = {from}");
    (last[1] - first[1]) / grown
}

/// Rows of `crack_tips.csv`: (t, extension).
fn tip_rows(dir: &Path) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(dir.join("crack_tips.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, a) = (col("t_s"), col("extension_m"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[t].parse().unwrap(), f[a].parse().unwrap())
        })
        .collect()
}

/// The normalized time `t'` at which the crack extension first exceeds `a` (m) in `rows`.
fn time_to(rows: &[(f64, f64)], a: f64, (tau, t0): (f64, f64)) -> f64 {
    let &(t, _) = rows
        .iter()
        .find(|r| r.1 > a)
        .expect("the crack grew that far");
    (t - t0) / tau
}

/// The normalized time at which the LEFM tip reaches `a` (m), by bisection.
fn lefm_time_to(a: f64, length: f64) -> f64 {
    let (mut lo, mut hi) = (lefm::initiation(), 10.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if lefm::tip(mid, 4000).0 * length < a {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The crack of `mode1_lefm.toml` starts when LEFM says: the times at which it has grown 5, 10
/// and 20 um (a few probe spacings of the refined tip) against the reference's, to t' = 1.85.
/// The full run to t' = 3.5 is `mode1_crack_follows_lefm` below (9 minutes, not in CI).
#[test]
fn mode1_crack_starts_when_lefm_says() {
    let (tau, t0, c_r) = mode1_scales();
    let end = t0 + 1.85 * tau;
    let problem = common::shipped("mode1_lefm.toml", &[&format!("time.end={end:e}")]);
    let (summary, dir) = common::solve(&problem, 2, false);
    let rows = tip_rows(dir.path());
    for a in [5e-6, 10e-6, 20e-6] {
        let (t, t_ref) = (time_to(&rows, a, (tau, t0)), lefm_time_to(a, tau * c_r));
        eprintln!("extension {a:e} m at t' = {t:.3}, LEFM {t_ref:.3}");
        // Measured: within 0.05 (1.60, 1.67, 1.77 against 1.64, 1.70, 1.79); asserted within
        // 0.1, twice that, a sixth of the 0.6 the crack takes from its start to 20 um.
        assert!((t - t_ref).abs() < 0.1, "{a}: {t} vs {t_ref}");
    }
    assert!(summary.energy.balance_residual_rel.abs() < 1e-6);
    assert!(summary.coarsenings > 0);
    assert_fracture_energy_never_negative(dir.path());
    // summary.json's comparison: the first tip state and LEFM's start in t', and nothing
    // compared before t' = 3 (the default `compare_from`).
    let lefm_block = summary.lefm.expect("[loading] runs compare with LEFM");
    let first = (rows[0].0 - t0) / tau;
    assert!(
        (lefm_block.onset_time.unwrap() - first).abs() < 1e-9,
        "{lefm_block:?}"
    );
    assert!((lefm_block.lefm_onset_time - lefm::initiation()).abs() < 1e-9);
    assert_eq!(lefm_block.tip_states_compared, 0);
    assert_eq!(lefm_block.tip_error_max, None);
}

/// The work of the cohesive tractions (`history.csv`) is the law's potential plus what the
/// faces dissipate, so never negative. A tip edge as long as the process zone broke this
/// (docs/verification.md, sigma' = 10^-1.5): the faces there gained energy.
fn assert_fracture_energy_never_negative(dir: &Path) {
    let history = common::csv_columns(&dir.join("history.csv"), &["fracture_energy_j"]);
    let lowest = history.iter().map(|r| r[0]).fold(f64::INFINITY, f64::min);
    let largest = history.iter().map(|r| r[0]).fold(0.0, f64::max);
    assert!(lowest >= -1e-9 * largest, "{lowest} (largest {largest})");
}

/// The acceptance on `mode1_lefm.toml` (seed 2.5.3, sigma' = 0.1): the tip within 5% of
/// LEFM for t' >= 3, slower than c_R, and the fracture energy about phi per unit extension.
/// `cargo test --release --test suite cohesive::mode1_crack_follows_lefm -- --ignored --nocapture`
/// (9 minutes on 1 thread).
#[test]
#[ignore = "9 minutes on 1 thread: run on demand"]
fn mode1_crack_follows_lefm() {
    let (tau, t0, c_r) = mode1_scales();
    let problem = common::shipped("mode1_lefm.toml", &[]);
    let (summary, dir) = common::solve(&problem, 2, false);
    let rows = tip_rows(dir.path());
    let length = tau * c_r;
    let mut worst = 0.0f64;
    for &(t, a) in rows.iter().filter(|r| (r.0 - t0) / tau >= 3.0) {
        let a_ref = lefm::tip((t - t0) / tau, 4000).0 * length;
        worst = worst.max((a / a_ref - 1.0).abs());
    }
    let crack = summary.crack.expect("a cohesive run reports its cracks");
    let per_area = summary.energy.fracture_energy / crack.final_length;
    let phi = phi();
    eprintln!(
        "tip within {worst:.3} of LEFM for t' >= 3; final extension {:.4e} m; largest speed \
         {:.3} c_R; fracture energy per unit extension {per_area:.1} J/m^2 (phi = {phi:.1}); \
         {} patches",
        crack.final_length, crack.max_speed_over_c_r, summary.patches
    );
    assert!(worst < 0.05, "{worst}");
    assert!(crack.max_speed_over_c_r < 1.0);
    assert!((per_area / phi - 1.0).abs() < 0.1, "{per_area}");
    let zone = process_zone_ratios(dir.path(), (tau, t0));
    eprintln!(
        "process zone over the steady-state estimate (2.54), zeta = 9/16, for t' >= 3: median \
         {:.3}, from {:.3} to {:.3} over {} tip states",
        zone[zone.len() / 2],
        zone[0],
        zone[zone.len() - 1],
        zone.len()
    );
    // The seed (Fig. 2.10a): "very good agreement ... after the initial rapid crack
    // acceleration". Measured: median 1.048, from 0.955 to 1.091 over 209 states; the zone's
    // ends are first crossings of the faces' points, a fraction of a 3 um edge apart, about a
    // tenth of the 7 to 11 um zone.
    assert!(
        zone[0] > 0.85 && zone[zone.len() - 1] < 1.15,
        "{:?}",
        (zone[0], zone[zone.len() - 1])
    );
}

/// The process zone of each tip state of the run in `dir` from `t' = 3` on (after the initial
/// acceleration) over the seed's steady-state estimate (2.54) at that state's speed, with its
/// `zeta = 9/16`: `Lambda_0 / A_I(v)`, `Lambda_0 = zeta pi mu / (1 - nu) phi / sigma_c^2`
/// (11 um); sorted.
fn process_zone_ratios(dir: &Path, (tau, t0): (f64, f64)) -> Vec<f64> {
    let (e, nu, rho): (f64, f64, f64) = (3.24e9, 0.35, 1190.0);
    let mu = e / (2.0 * (1.0 + nu));
    let (c_d, _) = p_wave();
    let c_s = (mu / rho).sqrt();
    let rest = 9.0 / 16.0 * std::f64::consts::PI * mu / (1.0 - nu) * phi() / SIGMA_C.powi(2);
    let rows = common::csv_columns(
        &dir.join("crack_tips.csv"),
        &["t_s", "speed_m_s", "process_zone_length_m"],
    );
    let mut ratios: Vec<f64> = rows
        .iter()
        .filter(|r| (r[0] - t0) / tau >= 3.0 && r[1].is_finite() && r[1] > 0.0)
        .map(|r| r[2] / (rest / lefm::universal_a(r[1], c_d, c_s, nu)))
        .collect();
    assert!(!ratios.is_empty(), "tip states after t' = 3");
    ratios.sort_by(f64::total_cmp);
    ratios
}

/// `configs/mode1_lefm_high.toml`'s scales: sigma' = 10^(-1/128), crack plane 0.5 mm from the
/// loaded sides.
fn mode1_high_scales() -> (f64, f64, f64) {
    mode1_scales_at(10f64.powf(-1.0 / 128.0), 0.5e-3)
}

/// The seed's point against Xu and Needleman (2.6): even at sigma' = 10^(-1/128) every recorded
/// tip speed stays below c_R, to t' = 60. Reports the energy released per unit extension once
/// the crack runs (seed Fig. 2.9b: below phi, part of it spent on the uniform stretch ahead).
/// `cargo test --release --test suite cohesive::mode1_crack_at_high_load_stays_below_c_r --
/// --ignored --nocapture` (4 minutes on 2 cores).
#[test]
#[ignore = "4 minutes on 2 cores: run on demand"]
fn mode1_crack_at_high_load_stays_below_c_r() {
    let (tau, t0, c_r) = mode1_high_scales();
    let problem = common::shipped("mode1_lefm_high.toml", &[]);
    let (summary, dir) = common::solve(&problem, 2, false);
    let crack = summary.crack.expect("a cohesive run reports its cracks");
    let speeds = common::csv_columns(&dir.path().join("crack_tips.csv"), &["speed_m_s"]);
    let fastest = speeds.iter().map(|s| s[0]).fold(0.0, f64::max);
    let g = energy_release_rate(dir.path(), 10.0, (tau, t0)) / phi();
    eprintln!(
        "fastest tip state {fastest:.1} m/s = {:.4} c_R; extension {:.4e} m at t' = {:.1}; \
         energy released per unit extension from t' = 10: {g:.3} phi; {} patches",
        fastest / c_r,
        crack.final_length,
        (problem.loaded.config.time.end - t0) / tau,
        summary.patches
    );
    assert!(fastest < c_r, "{fastest}");
    assert!((crack.max_speed_over_c_r - fastest / c_r).abs() < 1e-9);
    assert!(summary.energy.balance_residual_rel.abs() < 1e-6);
}

/// `configs/mode1_lefm_low.toml`'s scales: sigma' = 10^-1.5, crack plane 12 mm from the loaded
/// sides.
fn mode1_low_scales() -> (f64, f64, f64) {
    mode1_scales_at(10f64.powf(-1.5), 12e-3)
}

/// Steady growth at a low load ratio (sigma' = 10^-1.5, seed Fig. 2.9a): once the crack runs
/// (t' >= 2.5), the energy released per unit extension is phi within 5%; the tip follows LEFM.
/// `cargo test --release --test suite cohesive::mode1_crack_at_low_load_releases_phi -- --ignored
/// --nocapture`: about five hours on 2 cores
/// (38M patches). The same run, restarted from checkpoints, met every assertion here: 0.9991 phi,
/// the tip 1.8% behind LEFM at t' = 3 (docs/verification.md).
#[test]
#[ignore = "hours on 2 cores: run on demand"]
fn mode1_crack_at_low_load_releases_phi() {
    let (tau, t0, c_r) = mode1_low_scales();
    let problem = common::shipped("mode1_lefm_low.toml", &[]);
    let (summary, dir) = common::solve(&problem, 2, false);
    let g = energy_release_rate(dir.path(), 2.5, (tau, t0)) / phi();
    let rows = tip_rows(dir.path());
    let &(t, a) = rows.last().unwrap();
    let a_ref = lefm::tip((t - t0) / tau, 4000).0 * tau * c_r;
    eprintln!(
        "energy released per unit extension from t' = 2.5: {g:.4} phi; last tip state at t' = \
         {:.3}: extension {a:.4e} m, LEFM {a_ref:.4e} m; {} patches",
        (t - t0) / tau,
        summary.patches
    );
    assert!((g - 1.0).abs() < 0.05, "{g}");
    assert!((a / a_ref - 1.0).abs() < 0.05, "{a} vs {a_ref}");
    assert!(summary.energy.balance_residual_rel.abs() < 1e-6);
    assert_fracture_energy_never_negative(dir.path());
}

/// `configs/mode1_lefm_low.toml` is loaded as the seed says: to the time the waves meet on the
/// crack plane the sides' rollers keep them one-dimensional, so the load's work is the closed form
/// `2 W s_inf^2 / Z tau' (9x^5/5 - 2x^6 + 4x^7/7)`, x = t0 / tau' (the ramp (2.71) squared and
/// integrated), with s_inf = sigma' sigma_c / 2; the run reports the scales computed here and no
/// crack yet. The crack itself is `mode1_crack_at_low_load_releases_phi`.
#[test]
fn mode1_low_load_is_the_seed_s() {
    let (tau, t0, _) = mode1_low_scales();
    let (_, z) = p_wave();
    let problem = common::shipped(
        "mode1_lefm_low.toml",
        &[
            &format!("time.end={t0:e}"),
            "adapt.enabled=false",
            "output.png=false",
        ],
    );
    let (summary, _dir) = common::solve(&problem, 2, true);
    let loading = summary.loading.expect("the run reports its loading");
    assert!((loading.scales.tau / tau - 1.0).abs() < 1e-12);
    assert!((loading.arrival_time / t0 - 1.0).abs() < 1e-12);
    let (width, s) = (55e-3, 10f64.powf(-1.5) * SIGMA_C / 2.0);
    let x = t0 / tau;
    let ramp = 9.0 / 5.0 * x.powi(5) - 2.0 * x.powi(6) + 4.0 / 7.0 * x.powi(7);
    let work = 2.0 * width * s * s / z * tau * ramp;
    common::assert_plane_wave_load(&summary, work);
    assert_eq!(summary.crack.expect("cohesive").tip_states, 0);
}

/// Mesh convergence of the tip history on `mode1_lefm.toml`: halving the indicator's tolerance
/// and the smallest edge (3 um to 1.5 um) moves the tip at the end time by less than 2%.
/// `cargo test --release --test suite cohesive::mode1_tip_history_converges_with_the_mesh --
/// --ignored --nocapture` (about 30 minutes on 2 cores).
#[test]
#[ignore = "30 minutes on 2 cores: run on demand"]
fn mode1_tip_history_converges_with_the_mesh() {
    let end_extension = |overrides: &[&str]| {
        let problem = common::shipped("mode1_lefm.toml", overrides);
        let (summary, dir) = common::solve(&problem, 2, false);
        let rows = tip_rows(dir.path());
        (rows.last().unwrap().1, summary.patches)
    };
    let (coarse, coarse_patches) = end_extension(&[]);
    let (fine, fine_patches) = end_extension(&["adapt.tol=0.5", "adapt.min_edge=1.5e-6"]);
    let change = (fine / coarse - 1.0).abs();
    eprintln!(
        "extension at the end: {coarse:.4e} m ({coarse_patches} patches), halved: {fine:.4e} m \
         ({fine_patches} patches); change {change:.4}"
    );
    assert!(change < 0.02, "{change}");
}
