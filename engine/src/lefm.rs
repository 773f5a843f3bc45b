//! The LEFM tip history of seed 2.5.1 for the mode-I load of `[loading]`, drawn beside the
//! computed tip in `crack_tips.png`.
//!
//! A semi-infinite crack under crack-face loading `sigma_bar H(t')`, `H` the ramp
//! `3 t'^2 - 2 t'^3` over `t' in [0, 1]` (2.71). By (2.61) the stationary-crack stress intensity
//! is `K_step(tau') F(t')` with `F(t') = int_0^min(t', 1) H'(u) sqrt(t' - u) du`, and the
//! equation of motion (2.63) with `Gamma = phi` gives the normalized tip speed
//! `da'/dt' = 1 - 1 / F(t')^2` once `F >= 1` (zero before); `t' = t / tau'`,
//! `a' = a / (tau' c_R)`.

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
}

/// The comparison of the tip states `tips` (`t'`, extension m) and the history rows `work`
/// (`t'`, work of the cohesive tractions J/m), both in time order, from `t' = from`; `unit`
/// is `tau' c_R` (m), `phi` the work of separation (J/m^2).
pub fn compare(
    tips: &[(f64, f64)],
    work: &[(f64, f64)],
    from: f64,
    unit: f64,
    phi: f64,
) -> LefmComparison {
    let late: Vec<(f64, f64)> = tips.iter().copied().filter(|s| s.0 >= from).collect();
    let end = late.last().map_or(0.0, |s| s.0);
    let reference = tip_history(end, (end * 200.0).ceil() as usize);
    let lefm_at = |t: f64| {
        let i = reference
            .partition_point(|r| r.0 < t)
            .clamp(1, reference.len() - 1);
        let ((t0, a0, _), (t1, a1, _)) = (reference[i - 1], reference[i]);
        let s = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
        (a0 + s * (a1 - a0)) * unit
    };
    let tip_error_max = late
        .iter()
        .map(|&(t, a)| (a / lefm_at(t) - 1.0).abs())
        .reduce(f64::max);
    let extension = |t: f64| {
        tips.iter()
            .take_while(|s| s.0 <= t)
            .last()
            .map_or(0.0, |s| s.1)
    };
    let energy_release_over_phi = match (work.iter().find(|r| r.0 >= from), work.last()) {
        (Some(&(t0, w0)), Some(&(t1, w1))) if extension(t1) > extension(t0) => {
            Some((w1 - w0) / (extension(t1) - extension(t0)) / phi)
        }
        _ => None,
    };
    LefmComparison {
        onset_time: tips.first().map(|s| s.0),
        lefm_onset_time: initiation(),
        compare_from: from,
        tip_states_compared: late.len(),
        tip_error_max,
        energy_release_over_phi,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let c = compare(&tips, &work, 3.0, unit, 350.0);
        assert!(c.tip_error_max.unwrap() < 1e-6, "{c:?}");
        assert_eq!(c.tip_states_compared, 201);
        assert!((c.energy_release_over_phi.unwrap() - 1.0).abs() < 1e-12);
        assert!((c.onset_time.unwrap() - start).abs() < 0.02);
        // 5% ahead everywhere: an error of 0.05; half the work: 0.5 phi.
        let ahead: Vec<(f64, f64)> = tips.iter().map(|&(t, a)| (t, 1.05 * a)).collect();
        let half: Vec<(f64, f64)> = work.iter().map(|&(t, w)| (t, 0.5 * w)).collect();
        let c = compare(&ahead, &half, 3.0, unit, 350.0 * 1.05);
        assert!((c.tip_error_max.unwrap() - 0.05).abs() < 1e-5, "{c:?}");
        assert!((c.energy_release_over_phi.unwrap() - 0.5 / 1.05 / 1.05).abs() < 1e-12);
        // A run that ends before t' = 3: nothing to compare.
        let c = compare(&tips[..10], &work[..10], 3.0, unit, 350.0);
        assert_eq!((c.tip_error_max, c.energy_release_over_phi), (None, None));
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
