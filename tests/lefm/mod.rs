//! The LEFM reference for a semi-infinite mode-I crack under uniform crack-face loading ramped
//! by `H(t') = 3 t'^2 - 2 t'^3` over `tau'` (seed 2.5.1, (2.61), (2.63), (2.71)), independent of
//! the solver.
//!
//! With `K_step(t) = C_I sqrt(2 pi c_d t) sigma_bar` the stationary-crack stress intensity of the
//! step load, (2.61) for the ramp gives `K(t) = K_step(tau') F(t')` with
//! `F(t') = int_0^min(t', 1) H'(u) sqrt(t' - u) du`, and (2.63) with `g(v) = 1 - v / c_R` and
//! `Gamma_0 = phi` gives the normalized tip speed `da'/dt' = 1 - 1 / F(t')^2` once `F >= 1`
//! (zero before), `a' = a / (tau' c_R)`. For the step load `F = sqrt(t')`, which gives (2.68).

/// Normalized stationary-crack stress intensity `F(t')` of the ramped load, in closed form:
/// with `s = t' - u`, `H'(u) = A + B s + C s^2` and the integral of `s^(1/2)` times it is a sum
/// of powers of `s`.
pub fn intensity(t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let (a, b, c) = (6.0 * t - 6.0 * t * t, 12.0 * t - 6.0, -6.0);
    let primitive = |s: f64| {
        a * 2.0 / 3.0 * s.powf(1.5) + b * 2.0 / 5.0 * s.powf(2.5) + c * 2.0 / 7.0 * s.powf(3.5)
    };
    primitive(t) - primitive(t - t.min(1.0))
}

/// Normalized tip extension `a'(t')` and speed `da'/dt'` of the ramped load, integrated with
/// `steps` midpoint steps per unit of `t'`.
pub fn tip(t: f64, steps: usize) -> (f64, f64) {
    let speed = |t: f64| {
        let f = intensity(t);
        if f > 1.0 { 1.0 - 1.0 / (f * f) } else { 0.0 }
    };
    let n = (t * steps as f64).ceil().max(1.0) as usize;
    let h = t / n as f64;
    let a = (0..n).map(|i| h * speed((i as f64 + 0.5) * h)).sum();
    (a, speed(t))
}

/// The normalized time at which the crack starts to grow, `F(t') = 1`.
pub fn initiation() -> f64 {
    let (mut lo, mut hi) = (1.0, 3.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if intensity(mid) < 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The Rayleigh wave speed (m/s) for dilatational and shear speeds `c_d`, `c_s`: the root in
/// `(0, c_s)` of `(2 - x)^2 - 4 sqrt(1 - x c_s^2 / c_d^2) sqrt(1 - x)` with `x = (c / c_s)^2`.
pub fn rayleigh_speed(c_d: f64, c_s: f64) -> f64 {
    let k = (c_s / c_d).powi(2);
    let f = |x: f64| (2.0 - x).powi(2) - 4.0 * (1.0 - k * x).sqrt() * (1.0 - x).sqrt();
    // For Poisson ratios of solids f < 0 at x = 1/2 and f(1) = 1: the root is between.
    let (mut lo, mut hi) = (0.5, 0.999_999);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    c_s * (0.5 * (lo + hi)).sqrt()
}

/// Freund's universal function `A_I(v)` of mode I (seed (2.53)): the factor by which a crack
/// running at `v` (m/s) shortens the quasi-static process zone, `Lambda = Lambda_0 / A_I(v)`;
/// `A_I(v) = v^2 alpha_d / ((1 - nu) c_s^2 R(v))` with `alpha_{d,s} = sqrt(1 - v^2 / c_{d,s}^2)`
/// and `R = 4 alpha_d alpha_s - (1 + alpha_s^2)^2`; 1 at rest, unbounded as `v -> c_R`.
pub fn universal_a(v: f64, c_d: f64, c_s: f64, nu: f64) -> f64 {
    if v <= 0.0 {
        return 1.0;
    }
    let alpha_d = (1.0 - (v / c_d).powi(2)).sqrt();
    let alpha_s = (1.0 - (v / c_s).powi(2)).sqrt();
    let r = 4.0 * alpha_d * alpha_s - (1.0 + alpha_s * alpha_s).powi(2);
    v * v * alpha_d / ((1.0 - nu) * c_s * c_s * r)
}

#[test]
fn the_universal_function_is_one_at_rest_and_grows_toward_c_r() {
    let (c_d, c_s, nu) = (2090.0, 1004.0, 0.35);
    let c_r = rayleigh_speed(c_d, c_s);
    // The limit v -> 0: R ~ v^2 / c_s^2 (1 - c_s^2 / c_d^2) = v^2 / (2 c_s^2 (1 - nu)) in plane
    // strain, so A_I -> 1.
    assert!((universal_a(1e-3 * c_r, c_d, c_s, nu) - 1.0).abs() < 1e-4);
    let mut last = 1.0;
    for k in 1..100 {
        let a = universal_a(0.01 * f64::from(k) * c_r, c_d, c_s, nu);
        assert!(a > last, "{k}: {a}");
        last = a;
    }
    assert!(universal_a(0.9999 * c_r, c_d, c_s, nu) > 100.0);
}

#[test]
fn the_reference_reproduces_the_step_load_limit_and_the_seed_s_delay() {
    // Beyond the ramp F(t') = int H' sqrt(t' - u): against quadrature, and F ~ sqrt(t' - 1/2)
    // for large t' (the ramp's centroid is at u = 1/2).
    for t in [0.3f64, 0.9, 1.0, 1.7, 4.0] {
        let n = 200_000;
        let m = t.min(1.0);
        let h = m / n as f64;
        let quadrature: f64 = (0..n)
            .map(|i| {
                let u = (i as f64 + 0.5) * h;
                h * (6.0 * u - 6.0 * u * u) * (t - u).sqrt()
            })
            .sum();
        assert!((intensity(t) - quadrature).abs() < 1e-6, "{t}");
    }
    assert!((intensity(400.0) / (399.5f64).sqrt() - 1.0).abs() < 1e-5);
    // The seed: initiation near t' = 1.5, about tau'/2 after the step load's t' = 1.
    let t0 = initiation();
    assert!((t0 - 1.5).abs() < 0.05, "{t0}");
    // Long after, the ramped tip trails the step-load one (2.68) by the delay.
    let step = |t: f64| t - 1.0 - t.ln();
    let (a, v) = tip(40.0, 2000);
    assert!((a - step(40.0 - 0.5)).abs() < 0.05, "{a} vs {}", step(39.5));
    assert!((v - (1.0 - 1.0 / 39.5)).abs() < 1e-3);
}
