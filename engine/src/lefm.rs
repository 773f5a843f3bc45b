//! The LEFM tip history of seed 2.5.1 for the mode-I load of `[loading]`, drawn beside the
//! computed tip in `crack_tips.png`.
//!
//! A semi-infinite crack under crack-face loading `sigma_bar H(t')`, `H` the ramp
//! `3 t'^2 - 2 t'^3` over `t' in [0, 1]` (2.71). By (2.61) the stationary-crack stress intensity
//! is `K_step(tau') F(t')` with `F(t') = int_0^min(t', 1) H'(u) sqrt(t' - u) du`, and the
//! equation of motion (2.63) with `Gamma = phi` gives the normalized tip speed
//! `da'/dt' = 1 - 1 / F(t')^2` once `F >= 1` (zero before); `t' = t / tau'`,
//! `a' = a / (tau' c_R)`.

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

#[cfg(test)]
mod tests {
    use super::*;

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
