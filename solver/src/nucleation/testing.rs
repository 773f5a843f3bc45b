//! Helpers shared by the nucleation tests: the shipped cohesive strength and the
//! Kolmogorov-Smirnov test.

/// Cohesive strength of the shipped configuration (Pa); its defects: mean `5 SIGMA_C`,
/// truncated at `0.4 SIGMA_C`.
pub(super) const SIGMA_C: f64 = 62.1e6;

/// The critical value of the Kolmogorov-Smirnov statistic for `n` samples at the level `level`
/// (e.g. 0.01): Stephens' (1970) `c / (sqrt n + 0.12 + 0.11 / sqrt n)` with Kolmogorov's
/// asymptotic `c = sqrt(-ln(level / 2) / 2)` (1.628 at 1%).
pub(super) fn ks_critical(n: usize, level: f64) -> f64 {
    let s = (n as f64).sqrt();
    (-0.5 * (0.5 * level).ln()).sqrt() / (s + 0.12 + 0.11 / s)
}

/// The Kolmogorov-Smirnov statistic of `total` draws against the CDF `cdf`, given the finite
/// ones in `finite` (the others are an atom at `+inf`, where `cdf` tends to
/// `cdf(inf) <= 1`). With such an atom the statistic is stochastically smaller than for a
/// continuous law, so the usual critical value stays a valid (conservative) 1% test.
pub(super) fn ks_statistic(mut finite: Vec<f64>, total: usize, cdf: impl Fn(f64) -> f64) -> f64 {
    finite.sort_by(f64::total_cmp);
    let n = total as f64;
    let mut d: f64 = 0.0;
    for (i, &x) in finite.iter().enumerate() {
        let f = cdf(x);
        d = d.max((i as f64 + 1.0) / n - f).max(f - i as f64 / n);
    }
    d.max((cdf(f64::INFINITY) - finite.len() as f64 / n).abs())
}
