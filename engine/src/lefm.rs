//! The LEFM tip history of seed 2.5.1 for the mode-I load of `[loading]`, drawn beside the
//! computed tip in `crack_tips.png`.
//!
//! A semi-infinite crack under crack-face loading `sigma_bar H(t')`, `H` the ramp
//! `3 t'^2 - 2 t'^3` over `t' in [0, 1]` (2.71). By (2.61) the stationary-crack stress intensity
//! is `K_step(tau') F(t')` with `F(t') = int_0^min(t', 1) H'(u) sqrt(t' - u) du`, and the
//! equation of motion (2.63) with `Gamma = phi` gives the normalized tip speed
//! `da'/dt' = 1 - 1 / F(t')^2` once `F >= 1` (zero before); `t' = t / tau'`,
//! `a' = a / (tau' c_R)`.
//!
//! The cohesive process zone against its steady-state estimate (seed 2.4.2, Fig. 2.10):
//! [`ZoneEstimate`].

use serde::Serialize;

/// Gauss-Legendre nodes and weights on [-1, 1], 4 points: exact to degree 7.
const GAUSS_4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// `F(t')`. With `u = t' - s^2` the integrand `2 s^2 H'(t' - s^2)` is a polynomial of degree 6
/// in `s`, which the 4-point Gauss rule integrates exactly.
pub fn intensity(t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let (lo, hi) = ((t - t.min(1.0)).sqrt(), t.sqrt());
    let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    GAUSS_4
        .iter()
        .map(|&(x, w)| {
            let s = mid + half * x;
            let u = t - s * s;
            w * half * 2.0 * s * s * 6.0 * u * (1.0 - u)
        })
        .sum()
}

/// The normalized tip speed `da'/dt'` at `t'`.
pub fn speed(t: f64) -> f64 {
    let f = intensity(t);
    if f > 1.0 { 1.0 - 1.0 / (f * f) } else { 0.0 }
}

/// `(t', a', da'/dt')` at `n + 1` equally spaced times from 0 to `end` (normalized), `a'`
/// integrated with Simpson's rule on 16 sub-intervals per output interval.
pub fn tip_history(end: f64, n: usize) -> Vec<(f64, f64, f64)> {
    let n = n.max(1);
    let h = end / n as f64;
    let mut a = 0.0;
    let mut out = Vec::with_capacity(n + 1);
    out.push((0.0, 0.0, speed(0.0)));
    for i in 0..n {
        let t0 = i as f64 * h;
        let m = 16;
        let k = h / m as f64;
        for j in 0..m {
            let t = t0 + j as f64 * k;
            a += k / 6.0 * (speed(t) + 4.0 * speed(t + 0.5 * k) + speed(t + k));
        }
        let t = t0 + h;
        out.push((t, a, speed(t)));
    }
    out
}

/// The normalized time `t'` at which the LEFM tip starts: `F(t') = 1` (by bisection; `F`
/// grows with `t'`).
pub fn initiation() -> f64 {
    let (mut lo, mut hi) = (0.0, 10.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if intensity(mid) < 1.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

/// Rice's factor `zeta` of (2.52) for potential-based cohesive laws, with the seed's process
/// zone from the nominal tip (`delta_c`) to the trailing edge (traction 1% of the strength).
pub const ZETA: f64 = 9.0 / 16.0;

/// Tip states are compared with [`ZoneEstimate`] from this speed on, over `c_R`: after the
/// initial rapid acceleration, where the seed finds the estimate good (Fig. 2.10a), and the
/// zone, much shorter than at rest, is no longer the distance to the crack's origin.
pub const ZONE_FROM_SPEED: f64 = 0.5;

/// The steady-state size of the cohesive process zone of mode I (seed (2.52)-(2.54)):
/// `Lambda(v) = Lambda_0 / A_I(v)`, `Lambda_0 = zeta pi mu / (1 - nu) phi / sigma_c^2`.
/// Written with the wave speeds, `1 / (1 - nu) = 2 (1 - c_s^2 / c_d^2)` in plane strain (and
/// with `nu / (1 + nu)` for `nu` in plane stress, whose `c_d` this is).
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct ZoneEstimate {
    /// `Lambda_0`, m: the quasi-static size.
    pub quasi_static: f64,
    /// Dilatational wave speed `c_d`, m/s.
    pub c_d: f64,
    /// Shear wave speed `c_s`, m/s.
    pub c_s: f64,
}

impl ZoneEstimate {
    /// The estimate for shear modulus `mu` (Pa), wave speeds `c_d`, `c_s` (m/s), work of
    /// separation `phi` (J/m^2) and strength `sigma_c` (Pa), with [`ZETA`].
    pub fn new(mu: f64, c_d: f64, c_s: f64, phi: f64, sigma_c: f64) -> Self {
        let mu_over_one_minus_nu = 2.0 * mu * (1.0 - (c_s / c_d).powi(2));
        Self {
            quasi_static: ZETA * std::f64::consts::PI * mu_over_one_minus_nu * phi
                / (sigma_c * sigma_c),
            c_d,
            c_s,
        }
    }

    /// Freund's universal function `A_I(v)` (2.53): `A_I = v^2 alpha_d / ((1 - nu) c_s^2 R)`,
    /// `alpha_{d,s} = sqrt(1 - v^2 / c_{d,s}^2)`, `R = 4 alpha_d alpha_s - (1 + alpha_s^2)^2`;
    /// 1 at rest (the limit), infinite at `c_R` and beyond (`R <= 0`).
    pub fn universal_a(&self, v: f64) -> f64 {
        let (b, k2) = ((v / self.c_s).powi(2), (self.c_s / self.c_d).powi(2));
        if b < 1e-12 {
            return 1.0;
        }
        let alpha_d = (1.0 - b * k2).max(0.0).sqrt();
        let alpha_s = (1.0 - b).max(0.0).sqrt();
        let r = 4.0 * alpha_d * alpha_s - (2.0 - b).powi(2);
        if r <= 0.0 {
            return f64::INFINITY;
        }
        2.0 * (1.0 - k2) * b * alpha_d / r
    }

    /// `Lambda(v)`, m, at tip speed `v` (m/s): 0 from `c_R` on.
    pub fn at(&self, v: f64) -> f64 {
        self.quasi_static / self.universal_a(v)
    }
}

/// Statistics of the process zone over its estimate, `Lambda / Lambda(v)`, over the tip
/// states whose speed is at least [`ZONE_FROM_SPEED`] `c_R` and below `c_R`, and whose zone has
/// a trailing edge (is shorter than the extension: before the first trailing-edge crossing
/// `crack_tips.csv` measures it to the crack's origin).
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct ZoneRatio {
    /// Tip states counted.
    pub states: usize,
    /// Least ratio.
    pub min: f64,
    /// Median ratio (the mean of the middle two for an even count).
    pub median: f64,
    /// Largest ratio.
    pub max: f64,
}

/// One tip state as [`compare`] reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipPoint {
    /// Normalized time `t'`.
    pub time: f64,
    /// Extension, m.
    pub extension: f64,
    /// Speed, m/s; NaN where none was fitted.
    pub speed: f64,
    /// Process zone length, m (the nominal tip to the trailing edge).
    pub process_zone: f64,
}

/// The scales [`compare`] works in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Units {
    /// `tau' c_R`, m: the unit of normalized length.
    pub length: f64,
    /// Work of separation `phi`, J/m^2.
    pub phi: f64,
    /// Rayleigh wave speed `c_R`, m/s.
    pub c_r: f64,
    /// The process zone's steady-state estimate.
    pub zone: ZoneEstimate,
}

/// `lefm` in `summary.json`: the computed tip of the `[loading]` interface against the LEFM
/// tip history, in normalized time `t' = (t - t0) / tau'` (`t0` the waves' arrival).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct LefmComparison {
    /// `t'` of the first tip state; none without one.
    pub onset_time: Option<f64>,
    /// `t'` at which the LEFM tip starts ([`initiation`]).
    pub lefm_onset_time: f64,
    /// `t'` from which the rest compares (`loading.compare_from`).
    pub compare_from: f64,
    /// Tip states from `compare_from` on.
    pub tip_states_compared: usize,
    /// Largest `abs(a / a_LEFM - 1)` over those states, `a` the extension; none without one.
    pub tip_error_max: Option<f64>,
    /// The work of the cohesive tractions between the first history row from `compare_from`
    /// and the last, over the extension between them (the latest tip state at or before each
    /// row), over `phi`; none when the run ends before `compare_from` or the tip did not move.
    pub energy_release_over_phi: Option<f64>,
    /// The process zone over its steady-state estimate ([`ZoneEstimate`], `zeta = 9/16`) once
    /// the tip runs at [`ZONE_FROM_SPEED`] `c_R` or faster; none without such a state.
    pub process_zone_over_estimate: Option<ZoneRatio>,
    /// The process zone's steady-state estimate the ratios are taken against.
    pub zone_estimate: ZoneEstimate,
}

/// The comparison of the tip states `tips` and the history rows `work` (`t'`, work of the
/// cohesive tractions J/m), both in time order, from `t' = from`, in `units`.
pub fn compare(tips: &[TipPoint], work: &[(f64, f64)], from: f64, units: &Units) -> LefmComparison {
    let late: Vec<(f64, f64)> = (tips.iter())
        .filter(|s| s.time >= from)
        .map(|s| (s.time, s.extension))
        .collect();
    let end = late.last().map_or(0.0, |s| s.0);
    let reference = tip_history(end, (end * 200.0).ceil() as usize);
    let lefm_at = |t: f64| {
        let i = reference
            .partition_point(|r| r.0 < t)
            .clamp(1, reference.len() - 1);
        let ((t0, a0, _), (t1, a1, _)) = (reference[i - 1], reference[i]);
        let s = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
        (a0 + s * (a1 - a0)) * units.length
    };
    let tip_error_max = late
        .iter()
        .map(|&(t, a)| (a / lefm_at(t) - 1.0).abs())
        .reduce(f64::max);
    let extension = |t: f64| {
        tips.iter()
            .take_while(|s| s.time <= t)
            .last()
            .map_or(0.0, |s| s.extension)
    };
    let energy_release_over_phi = match (work.iter().find(|r| r.0 >= from), work.last()) {
        (Some(&(t0, w0)), Some(&(t1, w1))) if extension(t1) > extension(t0) => {
            Some((w1 - w0) / (extension(t1) - extension(t0)) / units.phi)
        }
        _ => None,
    };
    LefmComparison {
        onset_time: tips.first().map(|s| s.time),
        lefm_onset_time: initiation(),
        compare_from: from,
        tip_states_compared: late.len(),
        tip_error_max,
        energy_release_over_phi,
        process_zone_over_estimate: zone_ratio(tips, units),
        zone_estimate: units.zone,
    }
}

/// [`ZoneRatio`] of `tips`.
fn zone_ratio(tips: &[TipPoint], units: &Units) -> Option<ZoneRatio> {
    let mut ratios: Vec<f64> = (tips.iter())
        .filter(|s| s.speed >= ZONE_FROM_SPEED * units.c_r && s.speed < units.c_r)
        .filter(|s| s.process_zone < s.extension * (1.0 - 1e-9))
        .map(|s| s.process_zone / units.zone.at(s.speed))
        .collect();
    ratios.sort_by(f64::total_cmp);
    let n = ratios.len();
    (n > 0).then(|| ZoneRatio {
        states: n,
        min: ratios[0],
        median: 0.5 * (ratios[(n - 1) / 2] + ratios[n / 2]),
        max: ratios[n - 1],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    use sdg_solver::material::{Material, Plane};

    /// PMMA of `configs/mode1_lefm.toml` in `plane` and its Xu-Needleman law (strength
    /// 324 MPa, `phi = e sigma_c delta_c` with `delta_c` = 0.4 um).
    fn pmma(plane: Plane) -> (Material, ZoneEstimate) {
        let m = Material::new(3.24e9, 0.35, 1190.0, plane).unwrap();
        let sigma_c = 3.24e8;
        let phi = std::f64::consts::E * sigma_c * 4e-7;
        (m, ZoneEstimate::new(m.mu(), m.c_d(), m.c_s(), phi, sigma_c))
    }

    /// In the units of `pmma`, with `tau' c_R` = `length`.
    fn units(length: f64) -> Units {
        let (m, zone) = pmma(Plane::Strain);
        Units {
            length,
            phi: 350.0,
            c_r: m.c_r(),
            zone,
        }
    }

    fn points(tips: &[(f64, f64)]) -> Vec<TipPoint> {
        (tips.iter())
            .map(|&(time, extension)| TipPoint {
                time,
                extension,
                speed: f64::NAN,
                process_zone: 0.0,
            })
            .collect()
    }

    #[test]
    fn a_tip_that_is_lefm_s_compares_exactly() {
        let unit = 2e-3;
        let start = initiation();
        assert!((intensity(start) - 1.0).abs() < 1e-12);
        // LEFM's own tip, sampled, with the work phi per unit extension from t' = 3.
        let history = tip_history(5.0, 500);
        let tips: Vec<(f64, f64)> = (history.iter())
            .filter(|r| r.1 > 0.0)
            .map(|r| (r.0, r.1 * unit))
            .collect();
        let work: Vec<(f64, f64)> = tips.iter().map(|&(t, a)| (t, 350.0 * a + 1.0)).collect();
        let c = compare(&points(&tips), &work, 3.0, &units(unit));
        assert!(c.tip_error_max.unwrap() < 1e-6, "{c:?}");
        assert_eq!(c.tip_states_compared, 201);
        assert!((c.energy_release_over_phi.unwrap() - 1.0).abs() < 1e-12);
        assert!((c.onset_time.unwrap() - start).abs() < 0.02);
        // No speeds: no process zone compared.
        assert_eq!(c.process_zone_over_estimate, None);
        // 5% ahead everywhere: an error of 0.05; half the work: 0.5 phi.
        let ahead: Vec<(f64, f64)> = tips.iter().map(|&(t, a)| (t, 1.05 * a)).collect();
        let half: Vec<(f64, f64)> = work.iter().map(|&(t, w)| (t, 0.5 * w)).collect();
        let wider = Units {
            phi: 350.0 * 1.05,
            ..units(unit)
        };
        let c = compare(&points(&ahead), &half, 3.0, &wider);
        assert!((c.tip_error_max.unwrap() - 0.05).abs() < 1e-5, "{c:?}");
        assert!((c.energy_release_over_phi.unwrap() - 0.5 / 1.05 / 1.05).abs() < 1e-12);
        // A run that ends before t' = 3: nothing to compare.
        let c = compare(&points(&tips[..10]), &work[..10], 3.0, &units(unit));
        assert_eq!((c.tip_error_max, c.energy_release_over_phi), (None, None));
    }

    #[test]
    fn the_process_zone_estimate_is_the_seed_s() {
        let (m, zone) = pmma(Plane::Strain);
        let (mu, nu, c_d, c_s, c_r) = (m.mu(), m.poisson(), m.c_d(), m.c_s(), m.c_r());
        // (2.52) with zeta = 9/16: 10.95 um for this PMMA (configs/mode1_lefm.toml: 11 um).
        let phi = std::f64::consts::E * 3.24e8 * 4e-7;
        let rest = 9.0 / 16.0 * std::f64::consts::PI * mu / (1.0 - nu) * phi / 3.24e8f64.powi(2);
        assert!((zone.quasi_static / rest - 1.0).abs() < 1e-12, "{zone:?}");
        assert!((zone.quasi_static - 10.95e-6).abs() < 0.01e-6, "{zone:?}");
        // (2.53) as the seed writes it, with nu: the same A_I; 1 at rest, growing to infinity
        // at c_R, so the zone shrinks to nothing there.
        let freund = |v: f64| {
            let (ad, a_s) = (
                (1.0 - (v / c_d).powi(2)).sqrt(),
                (1.0 - (v / c_s).powi(2)).sqrt(),
            );
            v * v * ad / ((1.0 - nu) * c_s * c_s * (4.0 * ad * a_s - (1.0 + a_s * a_s).powi(2)))
        };
        assert_eq!(zone.universal_a(0.0), 1.0);
        assert!((zone.universal_a(1e-3 * c_r) - 1.0).abs() < 1e-5);
        let mut last = 1.0;
        for k in 1..100 {
            let v = 0.01 * f64::from(k) * c_r;
            let a = zone.universal_a(v);
            assert!(
                (a / freund(v) - 1.0).abs() < 1e-9,
                "{k}: {a} vs {}",
                freund(v)
            );
            assert!(a > last, "{k}: {a}");
            last = a;
        }
        assert!(zone.universal_a(0.9999 * c_r) > 100.0);
        assert_eq!(zone.at(c_r * (1.0 + 1e-9)), 0.0);
        assert!((zone.at(0.5 * c_r) - zone.quasi_static / freund(0.5 * c_r)).abs() < 1e-18);
        // Plane stress: mu / (1 - nu) with nu / (1 + nu) for nu is E / 2.
        let (_, stress) = pmma(Plane::Stress);
        let e_half = 9.0 / 16.0 * std::f64::consts::PI * 1.62e9 * phi / 3.24e8f64.powi(2);
        assert!(
            (stress.quasi_static / e_half - 1.0).abs() < 1e-12,
            "{stress:?}"
        );
    }

    #[test]
    fn the_process_zone_is_compared_once_the_tip_runs() {
        let u = units(1e-3);
        let c_r = u.c_r;
        // Tip states at 0.2 to 0.98 c_R: those at 0.5 c_R and faster count, each zone the
        // estimate times 0.9, 1.0, 1.1, 1.2, ...; slower ones (and the NaN) would be far off,
        // and so would the first, at 0.6 c_R, whose zone reaches the origin (no trailing edge).
        let speeds = [0.6, 0.2, f64::NAN, 0.49, 0.5, 0.7, 0.9, 0.98, 1.01];
        let tips: Vec<TipPoint> = (speeds.iter().enumerate())
            .map(|(i, &s)| TipPoint {
                time: i as f64,
                extension: if i == 0 { 1.0 } else { 1e-3 },
                speed: s * c_r,
                process_zone: if s >= 0.5 && i > 0 {
                    (0.5 + 0.1 * i as f64) * u.zone.at(s * c_r)
                } else {
                    1.0
                },
            })
            .collect();
        let c = compare(&tips, &[], 3.0, &u);
        let zone = c
            .process_zone_over_estimate
            .expect("four states at 0.5 c_R or faster");
        assert_eq!(zone.states, 4, "{zone:?}");
        assert!((zone.min - 0.9).abs() < 1e-12, "{zone:?}");
        assert!((zone.median - 1.05).abs() < 1e-12, "{zone:?}");
        assert!((zone.max - 1.2).abs() < 1e-12, "{zone:?}");
    }

    #[test]
    fn the_ramp_reaches_the_step_load_history() {
        // Beyond t' = 1 the load is constant; F(t') tends to sqrt(t' - 1/2) (the ramp's centroid).
        // During the ramp F(t') = 8/5 t'^(5/2) - 32/35 t'^(7/2).
        for t in [0.25f64, 0.5, 1.0] {
            let closed = 1.6 * t.powf(2.5) - 32.0 / 35.0 * t.powf(3.5);
            assert!((intensity(t) - closed).abs() < 1e-12, "{t}");
        }
        assert!((intensity(900.0) / 899.5f64.sqrt() - 1.0).abs() < 1e-6);
        // Long after, the tip is the step load's (2.68) delayed by 1/2.
        let (t, a, v) = *tip_history(40.0, 400).last().unwrap();
        let step = |t: f64| t - 1.0 - t.ln();
        assert!((a - step(t - 0.5)).abs() < 0.05, "{a}");
        assert!((v - (1.0 - 1.0 / 39.5)).abs() < 1e-3, "{v}");
    }
}
