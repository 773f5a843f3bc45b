//! Defects and their strengths: the nucleation strengths of defects, a normal law truncated
//! below ((4.16)-(4.17) with no upper bound), the weakest of `n` defects from a single draw, and
//! the number of defects in a region.
//!
//! (4.18) gives that number as `n = rho_N a`; this project reads it as the mean of a Poisson
//! count (defects scattered uniformly and independently with density `rho_N`), which keeps small
//! patches unbiased. [`weakest_defect`] combines both into the right-hand side of the nucleation
//! criterion (4.15).

use super::draws::Draws;
use crate::interface::LawError;
use rand_distr::{Distribution, Poisson};
use statrs::distribution::{Continuous, ContinuousCDF, Normal};
use std::f64::consts::FRAC_1_SQRT_2;

/// The upper tail `Q(x) = P(X > x) = erfc(x / sqrt 2) / 2` of the standard normal law, from
/// `libm`'s `erfc` (FreeBSD's, within an ulp of its argument): the rounding of `x / sqrt 2` adds
/// a relative error of about `x^2` ulps (5e-14 at `x = 37.5`; `Q` underflows to 0 near
/// `x = 38.5`). `Phi(x) = Q(-x)`; the tail is taken from erfc of the positive argument only,
/// never as `1 - Phi` of a large one. (`statrs`'s `erfc` is good to about 1e-10 only: its
/// interval constants are truncated to ten digits.)
fn normal_upper(x: f64) -> f64 {
    0.5 * libm::erfc(x * FRAC_1_SQRT_2)
}

/// The standard normal quantile `Phi^-1(p)` for `p` in [0, 1] (`-inf` at 0, `+inf` at 1), from
/// `statrs` (Boost's rational approximations of `erfc^-1`, within 2 ulps down to `p = 1e-300`).
/// Accurate for tiny `p`; for `p` near 1 pass the complement and negate.
fn normal_quantile(p: f64) -> f64 {
    Normal::standard().inverse_cdf(p)
}

/// Nucleation strengths of defects (Pa): the normal law of mean `mean` and standard deviation
/// `std` truncated below at `lower` (seed (4.16)-(4.17), without an upper bound).
///
/// CDF: `F(s) = (Phi(z) - Phi(a)) / Q(a)` for `s > lower`, with `z = (s - mean) / std`,
/// `a = (lower - mean) / std < 0` and `Q(a) = 1 - Phi(a)`; every difference is formed from tails
/// of the right sign, so the lower tail stays accurate however many standard deviations the
/// truncation lies below the mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefectStrengths {
    /// Mean of the untruncated normal law (Pa, finite, > `lower`).
    pub mean: f64,
    /// Standard deviation of the untruncated normal law (Pa, finite, > 0).
    pub std: f64,
    /// Truncation point: no defect is weaker (Pa, finite, >= 0).
    pub lower: f64,
}

/// Checks `mean` and `lower` of a [`DefectStrengths`].
fn check_mean_lower(mean: f64, lower: f64) -> Result<(), LawError> {
    if !mean.is_finite() {
        return Err(LawError {
            key: "defect_mean",
            reason: format!("must be a finite number (Pa), got {mean}"),
        });
    }
    if !(lower.is_finite() && lower >= 0.0) {
        return Err(LawError {
            key: "defect_lower",
            reason: format!("must be a finite number >= 0 (Pa), got {lower}"),
        });
    }
    if lower >= mean {
        return Err(LawError {
            key: "defect_lower",
            reason: format!("must be < defect_mean = {mean} Pa, got {lower}"),
        });
    }
    Ok(())
}

impl DefectStrengths {
    /// The law of the given mean, standard deviation and truncation point (Pa), validated.
    pub fn new(mean: f64, std: f64, lower: f64) -> Result<Self, LawError> {
        let law = Self { mean, std, lower };
        law.validate()?;
        Ok(law)
    }

    /// The law of the given `mean` and truncation point `lower` (Pa) whose CDF at `value` (Pa) is
    /// `probability`: the standard deviation solves `F(value) = probability` for the truncated law
    /// (the seed's `P~` is the untruncated `Phi`; the two agree when the truncation lies far in
    /// the tail).
    ///
    /// As a function of the standard deviation, `F(value)` runs from 1 (`value > mean`) or 1/2
    /// (`value = mean`) at `std -> 0` down to 0 at `std -> inf`, monotonically. For
    /// `value < mean` it rises from 0, peaks and falls back to 0 (the mass spreads over the
    /// unbounded upper side); then the smaller root is taken, the one that tends to the
    /// untruncated `std = (value - mean) / Phi^-1(probability)` as `lower -> -inf`.
    ///
    /// Errors: `defect_mean`, `defect_lower` as for [`Self::validate`]; `defect_probability` when
    /// it is not in (0, 1) or no standard deviation attains it; `defect_value` when it is not
    /// finite and above `lower`.
    pub fn from_probability(
        mean: f64,
        probability: f64,
        value: f64,
        lower: f64,
    ) -> Result<Self, LawError> {
        check_mean_lower(mean, lower)?;
        if !(probability > 0.0 && probability < 1.0) {
            return Err(LawError {
                key: "defect_probability",
                reason: format!("must be in (0, 1), got {probability}"),
            });
        }
        if !(value.is_finite() && value > lower) {
            return Err(LawError {
                key: "defect_value",
                reason: format!(
                    "must be a finite strength > defect_lower = {lower} Pa, got {value}"
                ),
            });
        }
        let unattainable = |most: f64| LawError {
            key: "defect_probability",
            reason: format!(
                "no standard deviation gives it: the CDF at defect_value = {value} Pa is at most \
                 {most} for defect_mean = {mean} Pa and defect_lower = {lower} Pa, got {probability}"
            ),
        };
        let out_of_range = || LawError {
            key: "defect_probability",
            reason: format!(
                "no standard deviation within the floating-point range gives it at \
                 defect_value = {value} Pa, got {probability}"
            ),
        };
        // Unknown: the precision t = 1 / std. `below(t)`: F(value) < probability.
        let below = |t: f64| {
            Self {
                mean,
                std: 1.0 / t,
                lower,
            }
            .cdf(value)
                < probability
        };
        let gap = mean - lower;
        let (lo, hi) = if value < mean {
            let t_peak = peak_precision(mean - value, gap);
            if below(t_peak) {
                let most = Self {
                    mean,
                    std: 1.0 / t_peak,
                    lower,
                }
                .cdf(value);
                return Err(unattainable(most));
            }
            let hi = grow(t_peak, 2.0, |t| !below(t)).ok_or_else(out_of_range)?;
            (t_peak, hi)
        } else {
            if value == mean && probability >= 0.5 {
                return Err(unattainable(0.5));
            }
            let lo = grow(1.0 / gap, 0.5, |t| !below(t)).ok_or_else(out_of_range)?;
            let hi = grow(1.0 / gap, 2.0, below).ok_or_else(out_of_range)?;
            (lo, hi)
        };
        // Geometric bisection keeping the sign change of F(value) - probability in [lo, hi].
        let (mut lo, mut hi) = (lo, hi);
        let lo_below = below(lo);
        loop {
            let mid = lo.sqrt() * hi.sqrt();
            if mid <= lo || mid >= hi {
                break;
            }
            if below(mid) == lo_below {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Self::new(mean, 2.0 / (lo + hi), lower)
    }

    /// Checks `mean` and `lower` finite, `0 <= lower < mean`, and `std` finite and > 0.
    pub fn validate(&self) -> Result<(), LawError> {
        check_mean_lower(self.mean, self.lower)?;
        if !(self.std.is_finite() && self.std > 0.0) {
            return Err(LawError {
                key: "defect_std",
                reason: format!("must be a finite number > 0 (Pa), got {}", self.std),
            });
        }
        Ok(())
    }

    /// The probability that a defect is weaker than `s` (Pa): `F(s)` in [0, 1], exact up to the
    /// rounding of `s` at the scale of `mean` (an error of about `pdf(s)` times an ulp of
    /// `mean`, which near the truncation is most of `F`, proportional to `s - lower` there).
    pub fn cdf(&self, s: f64) -> f64 {
        if s <= self.lower {
            return 0.0;
        }
        let a = (self.lower - self.mean) / self.std;
        let z = (s - self.mean) / self.std;
        let kept = normal_upper(a);
        let f = if z <= 0.0 {
            (normal_upper(-z) - normal_upper(-a)) / kept
        } else {
            1.0 - normal_upper(z) / kept
        };
        f.clamp(0.0, 1.0)
    }

    /// The strength `s` (Pa) with `F(s) = q`, `q` in [0, 1]: `lower` at 0, `+inf` at 1.
    pub fn quantile(&self, q: f64) -> f64 {
        self.quantile_split(q, 1.0 - q)
    }

    /// A strength (Pa) drawn with the uniform `u` in (0, 1) by inversion, `quantile(u)`: exact up
    /// to rounding, one draw per strength and none rejected (which [`Self::weakest`] relies on).
    pub fn sample(&self, u: f64) -> f64 {
        self.quantile(u)
    }

    /// The weakest of `n` independent strengths (Pa), drawn with the single uniform `u` in
    /// (0, 1): the minimum has the CDF `1 - (1 - F)^n`, so it is `quantile(1 - (1 - u)^(1/n))`,
    /// evaluated as `q = -expm1(ln_1p(-u) / n)` (and its complement `exp(ln_1p(-u) / n)`) to keep
    /// the tiny probabilities of large `n`. `n = 0` gives `+inf`, the minimum over no defects.
    pub fn weakest(&self, n: u64, u: f64) -> f64 {
        let log_kept = (-u).ln_1p() / n as f64;
        self.quantile_split(-log_kept.exp_m1(), log_kept.exp())
    }

    /// [`Self::quantile`] of `q` given with its complement `qc = 1 - q`, which the upper half
    /// uses so that `q` near 1 loses nothing.
    fn quantile_split(&self, q: f64, qc: f64) -> f64 {
        if q <= 0.0 {
            return self.lower;
        }
        let a = (self.lower - self.mean) / self.std;
        let kept = normal_upper(a);
        // Phi(z) = Phi(a) + q Q(a); in the upper half solve Q(z) = (1 - q) Q(a) instead.
        let phi_z = normal_upper(-a) + q * kept;
        let z = if phi_z <= 0.5 {
            normal_quantile(phi_z)
        } else {
            -normal_quantile(qc * kept)
        };
        (self.mean + self.std * z).max(self.lower)
    }
}

/// For `value < mean`: the precision `t = 1 / std` at which the truncated CDF at `value` peaks,
/// given `alpha = mean - value` and `gamma = mean - lower > alpha`.
///
/// `F = 1 - Phi(alpha t) / Phi(gamma t)`, so `dF/dt` has the sign of
/// `gamma h(gamma t) - alpha h(alpha t)` with `h = phi / Phi`: positive at `t = 0`, and negative
/// from `t0` on, where `alpha phi(alpha t0) = gamma phi(gamma t0)`; bisection between.
fn peak_precision(alpha: f64, gamma: f64) -> f64 {
    let h = |x: f64| Normal::standard().pdf(x) / normal_upper(-x);
    let rising = |t: f64| gamma * h(gamma * t) > alpha * h(alpha * t);
    let (mut lo, mut hi) = (
        0.0,
        (2.0 * (gamma / alpha).ln()).sqrt() / (gamma * gamma - alpha * alpha).sqrt(),
    );
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return mid;
        }
        if rising(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// Multiplies `t` by `factor` while `keep_going(t)`; the last `t`, or `None` if it leaves the
/// positive finite numbers first.
fn grow(mut t: f64, factor: f64, keep_going: impl Fn(f64) -> bool) -> Option<f64> {
    while keep_going(t) {
        t *= factor;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
    }
    Some(t)
}

/// A Poisson count of mean `mean` (>= 0), exact up to rounding and deterministic given the
/// draws: `rand_distr`'s `Poisson` (Knuth's multiplication of uniforms below a mean of 12, Ahrens
/// and Dieter's rejection method PD from 12 on). A mean that is not > 0 gives 0; one above
/// `Poisson::MAX_LAMBDA` (1.844e19, where the count reaches the range of `u64`), `+inf` included,
/// gives `u64::MAX`.
pub fn poisson(mean: f64, draws: &mut Draws) -> u64 {
    if mean.is_nan() || mean <= 0.0 {
        0
    } else {
        // The only errors left: an infinite mean or one above MAX_LAMBDA.
        Poisson::new(mean).map_or(u64::MAX, |law| law.sample(&mut draws.rng) as u64)
    }
}

/// The weakest defect strength (Pa) in a region of area `area` (m^2) with defect density
/// `density` (1/m^2): a Poisson number of defects of mean `density * area`, the weakest of them by
/// [`DefectStrengths::weakest`] with one more draw; `None` when there is no defect. Its law:
/// `P(min <= s) = 1 - exp(-density area F(s))`.
pub fn weakest_defect(
    density: f64,
    area: f64,
    strengths: &DefectStrengths,
    draws: &mut Draws,
) -> Option<f64> {
    match poisson(density * area, draws) {
        0 => None,
        n => Some(strengths.weakest(n, draws.next_uniform())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nucleation::testing::{SIGMA_C, ks_critical, ks_statistic};
    use statrs::function::factorial::ln_factorial;

    /// The shipped law with `std = SIGMA_C` (truncation 4.6 standard deviations below the mean).
    fn shipped() -> DefectStrengths {
        DefectStrengths::new(5.0 * SIGMA_C, SIGMA_C, 0.4 * SIGMA_C).unwrap()
    }

    /// The shipped mean and truncation with `std = SIGMA_C / 4` (truncation 18.4 standard
    /// deviations below the mean: `Phi(a) ~ 6e-76`).
    fn deep() -> DefectStrengths {
        DefectStrengths::new(5.0 * SIGMA_C, 0.25 * SIGMA_C, 0.4 * SIGMA_C).unwrap()
    }

    /// A wide law whose truncation removes 6% of the normal mass.
    fn wide() -> DefectStrengths {
        DefectStrengths::new(5.0 * SIGMA_C, 3.0 * SIGMA_C, 0.4 * SIGMA_C).unwrap()
    }

    #[test]
    fn truncated_cdf_matches_references() {
        // (mean, std, lower, s, F(s)) from mpmath at 60 digits. Forming z = (s - mean) / std
        // rounds by an ulp of mean / std, which moves F by |d ln F / dz| ~ |z| times that
        // (relative), and the tails carry about z^2 ulps each: up to ~20 * 20 ulps for the deep
        // law. Allowed: 2e-13; measured 3.9e-14.
        let references = [
            (5.0, 1.0, 0.41, 1.037_755_648_358_711_5e-7),
            (5.0, 1.0, 0.5, 1.285_221_137_198_645_6e-6),
            (5.0, 1.0, 1.0, 2.955_884_957_234_785e-5),
            (5.0, 1.0, 2.0, 0.001_347_788_424_069_586),
            (5.0, 1.0, 3.0, 0.022_748_067_547_738_97),
            (5.0, 1.0, 4.0, 0.158_653_476_625_037_32),
            (5.0, 1.0, 5.0, 0.499_998_943_770_417_54),
            (5.0, 1.0, 6.5, 0.933_192_657_603_657_3),
            (5.0, 0.25, 0.41, 7.162_119_110_061_718e-76),
            (5.0, 0.25, 0.5, 9.734_380_680_443_764e-73),
            (5.0, 0.25, 1.0, 6.388_754_400_538_087e-58),
            (5.0, 0.25, 2.0, 1.776_482_112_077_679e-33),
            (5.0, 0.25, 3.0, 6.220_960_574_271_784e-16),
            (5.0, 0.25, 4.0, 3.167_124_183_311_992_4e-5),
            (5.0, 0.25, 5.0, 0.5),
            (5.0, 0.25, 6.5, 0.999_999_999_013_412_3),
        ];
        for (mean, std, s, f) in references {
            let law = DefectStrengths::new(mean * SIGMA_C, std * SIGMA_C, 0.4 * SIGMA_C).unwrap();
            let err = (law.cdf(s * SIGMA_C) - f).abs() / f;
            assert!(
                err <= 2e-13,
                "F({s} sigma_c) = {}, expected {f}",
                law.cdf(s * SIGMA_C)
            );
        }
        let law = shipped();
        assert_eq!(law.cdf(law.lower), 0.0);
        assert_eq!(law.cdf(0.0), 0.0);
        assert_eq!(law.cdf(f64::INFINITY), 1.0);
    }

    #[test]
    fn truncated_quantile_matches_references() {
        // (law, q, s) from mpmath at 80 digits (q as the double it rounds to). s = mean + std z
        // is exact to a few ulps of mean (the terms are of that size): 1e-14 relative allowed,
        // 3.0e-15 measured.
        let references = [
            (shipped(), 1e-300, 24_840_000.0),
            (shipped(), 1e-20, 24_840_000.000_000_06),
            (shipped(), 1e-12, 24_840_006.123_731_45),
            (shipped(), 0.3, 277_934_992.268_550_46),
            (shipped(), 0.9, 390_084_426.969_485),
            (shipped(), 0.999_999_999, 682_963_837.225_949),
            (deep(), 1e-300, 24_840_000.0),
            (deep(), 1e-60, 55_932_255.747_542_02),
            (deep(), 1e-20, 166_702_170.105_879_72),
            (deep(), 1e-12, 201_289_638.612_199_93),
            (deep(), 0.3, 302_358_682.040_207_7),
            (deep(), 0.9, 330_396_088.055_079_94),
            (deep(), 0.999_999_999, 403_615_953.979_315_4),
        ];
        for (law, q, s) in references {
            let err = (law.quantile(q) - s).abs() / s;
            assert!(
                err <= 1e-14,
                "quantile({q}) = {}, expected {s}",
                law.quantile(q)
            );
        }
        // The weakest of 10^15 defects at the median draw: q = 1 - 2^(-1e-15).
        let err = (shipped().weakest(1_000_000_000_000_000, 0.5) - 24_840_000.004_244_648).abs();
        assert!(err <= 1e-14 * 24_840_000.0);
        let law = shipped();
        assert_eq!(law.quantile(0.0), law.lower);
        assert_eq!(law.quantile(1.0), f64::INFINITY);
        assert_eq!(law.weakest(0, 0.5), f64::INFINITY);
    }

    #[test]
    fn truncated_quantile_inverts_the_cdf() {
        // Both directions pass through s = mean + std z, held to about an ulp of `mean`: that
        // moves F by the density times it, the limit of any CDF evaluated at a rounded s (near
        // the truncation it is most of F: F is proportional to s - lower there), plus the
        // rounding of F itself (an ulp of q, which dominates near q = 1 for the wide law).
        // Allowed: 4 eps mean pdf(s) + eps q; measured up to 1.7 eps mean pdf(s) below q = 0.9
        // and one ulp of q above.
        for law in [shipped(), deep(), wide()] {
            let a = (law.lower - law.mean) / law.std;
            let pdf = |s: f64| {
                let z = (s - law.mean) / law.std;
                Normal::standard().pdf(z) / (law.std * normal_upper(a))
            };
            for e in 1..=60 {
                for q in [10f64.powi(-e), 1.0 - 10f64.powf(-0.25 * e as f64), 0.5] {
                    let s = law.quantile(q);
                    assert!(s >= law.lower);
                    let unit = f64::EPSILON * law.mean * pdf(s);
                    let err = (law.cdf(s) - q).abs();
                    assert!(
                        err <= 4.0 * unit + f64::EPSILON * q,
                        "F(quantile({q})) = {}",
                        law.cdf(s)
                    );
                }
            }
        }
    }

    #[test]
    fn truncated_samples_follow_the_law() {
        const N: usize = 100_000;
        for (i, law) in [shipped(), deep(), wide()].into_iter().enumerate() {
            let mut draws = Draws::new(3, [i as u64, 0, 0]);
            let samples: Vec<f64> = (0..N).map(|_| law.sample(draws.next_uniform())).collect();
            assert!(samples.iter().all(|&s| s >= law.lower));
            let d = ks_statistic(samples, N, |s| law.cdf(s));
            assert!(d < ks_critical(N, 0.01), "KS {d}");
        }
    }

    #[test]
    fn weakest_of_n_follows_the_law_of_the_minimum() {
        // P(min of n <= s) = 1 - (1 - F(s))^n, evaluated without cancellation.
        const N: usize = 100_000;
        for (i, (law, n)) in [(shipped(), 7), (wide(), 7), (shipped(), 1_000_000_000)]
            .into_iter()
            .enumerate()
        {
            let mut draws = Draws::new(4, [i as u64, 0, 0]);
            let samples: Vec<f64> = (0..N)
                .map(|_| law.weakest(n, draws.next_uniform()))
                .collect();
            let cdf = |s: f64| -((n as f64) * (-law.cdf(s)).ln_1p()).exp_m1();
            let d = ks_statistic(samples, N, cdf);
            assert!(d < ks_critical(N, 0.01), "KS {d} for n = {n}");
        }
        let law = shipped();
        for u in [1e-9, 0.3, 0.5, 0.999] {
            // n = 1 is one sample: the two routes differ by the rounding of q, ~1e-16.
            let (one, sample) = (law.weakest(1, u), law.sample(u));
            assert!((one - sample).abs() <= 1e-14 * sample, "{one} vs {sample}");
            assert!(law.weakest(2, u) < one && law.weakest(1000, u) < law.weakest(2, u));
        }
    }

    #[test]
    fn std_from_a_probability() {
        for law in [shipped(), deep(), wide()] {
            // Not at the mean, where F barely depends on std while the truncation is far.
            for value in [0.8, 1.0, 3.0, 6.0] {
                let value = value * SIGMA_C;
                let p = law.cdf(value);
                if !(p > 1e-300 && p < 1.0) {
                    continue;
                }
                let found =
                    DefectStrengths::from_probability(law.mean, p, value, law.lower).unwrap();
                // All three laws are on the small-std branch (below the peaks near 5.1 sigma_c).
                // The bisection ends at adjacent doubles of 1 / std; what remains is F's rounding
                // over its sensitivity to std, worst near F = 1 where 1 - F keeps only eps
                // absolute (1e-13 for the deep law at 6 sigma_c).
                let err = (found.std - law.std).abs() / law.std;
                assert!(err <= 1e-12, "std {} instead of {}", found.std, law.std);
            }
        }
        // A std beyond the peak (F at sigma_c peaks at 0.040 near std = 5.1 sigma_c): the
        // smaller root gives the same probability.
        let (mean, lower, value) = (5.0 * SIGMA_C, 0.4 * SIGMA_C, SIGMA_C);
        let far = DefectStrengths::new(mean, 20.0 * SIGMA_C, lower).unwrap();
        let p = far.cdf(value);
        let found = DefectStrengths::from_probability(mean, p, value, lower).unwrap();
        assert!(found.std < 5.1 * SIGMA_C);
        assert!((found.cdf(value) - p).abs() <= 1e-12 * p);
        // At the mean the probability is below 1/2 for every std.
        let half = DefectStrengths::from_probability(mean, 0.3, mean, lower).unwrap();
        assert!((half.cdf(mean) - 0.3).abs() <= 1e-12);
        let key = |r: Result<DefectStrengths, LawError>| r.unwrap_err().key;
        assert_eq!(
            key(DefectStrengths::from_probability(mean, 0.5, mean, lower)),
            "defect_probability"
        );
        // Below the mean the CDF is at most 0.040 at sigma_c.
        assert_eq!(
            key(DefectStrengths::from_probability(mean, 0.2, value, lower)),
            "defect_probability"
        );
        for p in [0.0, 1.0, f64::NAN, -0.1] {
            assert_eq!(
                key(DefectStrengths::from_probability(mean, p, value, lower)),
                "defect_probability"
            );
        }
        for v in [lower, 0.1 * SIGMA_C, f64::NAN, f64::INFINITY] {
            assert_eq!(
                key(DefectStrengths::from_probability(mean, 0.01, v, lower)),
                "defect_value"
            );
        }
        assert_eq!(
            key(DefectStrengths::from_probability(
                f64::NAN,
                0.01,
                value,
                lower
            )),
            "defect_mean"
        );
        assert_eq!(
            key(DefectStrengths::from_probability(mean, 0.01, value, mean)),
            "defect_lower"
        );
    }

    #[test]
    fn validation_names_the_parameter() {
        let (mean, std, lower) = (5.0 * SIGMA_C, SIGMA_C, 0.4 * SIGMA_C);
        assert!(DefectStrengths::new(mean, std, lower).is_ok());
        assert!(DefectStrengths::new(mean, std, 0.0).is_ok());
        let key = |m, s, l| DefectStrengths::new(m, s, l).unwrap_err().key;
        for m in [f64::NAN, f64::INFINITY] {
            assert_eq!(key(m, std, lower), "defect_mean");
        }
        for s in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(key(mean, s, lower), "defect_std");
        }
        for l in [-1.0, mean, 2.0 * mean, f64::NAN] {
            assert_eq!(key(mean, std, l), "defect_lower");
        }
    }

    /// Pearson's chi-square statistic of Poisson counts against the law of mean `mean`, with
    /// consecutive counts merged until each class expects at least 10 draws (the tails included
    /// in the first and last classes), and its number of degrees of freedom.
    fn poisson_chi_square(counts: &[u64], mean: f64) -> (f64, usize) {
        let n = counts.len() as f64;
        let top = counts.iter().copied().max().unwrap_or(0) as usize;
        let mut observed = vec![0.0; top + 1];
        for &k in counts {
            observed[k as usize] += 1.0;
        }
        let pmf = |k: usize| (-mean + k as f64 * mean.ln() - ln_factorial(k as u64)).exp();
        let mut classes: Vec<(f64, f64)> = Vec::new();
        let (mut o, mut e) = (0.0, 0.0);
        for (k, count) in observed.iter().enumerate() {
            o += count;
            e += n * pmf(k);
            if e >= 10.0 {
                classes.push((o, e));
                (o, e) = (0.0, 0.0);
            }
        }
        // The rest of the upper tail joins the last class.
        let others: f64 = classes.iter().rev().skip(1).map(|c| c.1).sum();
        let last = classes.last_mut().unwrap();
        last.0 += o;
        last.1 = n - others;
        let chi2 = classes.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
        (chi2, classes.len() - 1)
    }

    /// The 99% quantile of the chi-square law with `df` degrees of freedom by Wilson and
    /// Hilferty's cube-root normal approximation (within 0.2% from df = 2 up: 9.22 vs 9.21 at 2).
    fn chi_square_critical(df: usize) -> f64 {
        let k = df as f64;
        let z = 2.326_347_874_040_841;
        let c = 2.0 / (9.0 * k);
        k * (1.0 - c + z * c.sqrt()).powi(3)
    }

    #[test]
    fn poisson_counts_follow_the_law() {
        // The count is discrete, so Kolmogorov-Smirnov's critical values do not apply: Pearson's
        // chi-square test at 1% instead. Sample mean and variance within 5 standard errors
        // (false alarm 6e-7 each): Var(mean) = mean / n, Var(s^2) ~ (mean + 2 mean^2) / n.
        const N: usize = 100_000;
        for (i, mean) in [0.05, 2.5, 10.0, 40.0, 2000.0].into_iter().enumerate() {
            let mut draws = Draws::new(9, [i as u64, 0, 0]);
            let counts: Vec<u64> = (0..N).map(|_| poisson(mean, &mut draws)).collect();
            let (chi2, df) = poisson_chi_square(&counts, mean);
            assert!(
                chi2 < chi_square_critical(df),
                "mean {mean}: chi2 {chi2}, df {df}"
            );
            let n = N as f64;
            let m = counts.iter().map(|&k| k as f64).sum::<f64>() / n;
            let var = counts.iter().map(|&k| (k as f64 - m).powi(2)).sum::<f64>() / (n - 1.0);
            assert!((m - mean).abs() <= 5.0 * (mean / n).sqrt(), "mean {m}");
            assert!(
                (var - mean).abs() <= 5.0 * ((mean + 2.0 * mean * mean) / n).sqrt(),
                "var {var}"
            );
        }
        let mut draws = Draws::new(0, [0, 0, 0]);
        assert_eq!(poisson(0.0, &mut draws), 0);
        assert_eq!(poisson(-1.0, &mut draws), 0);
        assert_eq!(poisson(f64::NAN, &mut draws), 0);
        assert_eq!(poisson(f64::INFINITY, &mut draws), u64::MAX);
    }

    #[test]
    fn poisson_is_a_function_of_the_draws() {
        for mean in [0.3, 7.0, 500.0] {
            let mut a = Draws::new(1, [2, 3, 4]);
            let mut b = Draws::new(1, [2, 3, 4]);
            for _ in 0..1000 {
                assert_eq!(poisson(mean, &mut a), poisson(mean, &mut b));
            }
        }
    }

    #[test]
    fn weakest_defect_follows_the_closed_form() {
        // P(min <= s) = 1 - exp(-rho A F(s)), with an atom exp(-rho A) at None (see ks_statistic).
        const N: usize = 100_000;
        let density = 2.0e6; // defects per m^2
        for (i, (area, law)) in [(0.35e-6, shipped()), (1.5e-6, wide()), (5e-3, shipped())]
            .into_iter()
            .enumerate()
        {
            let mut draws = Draws::new(12, [i as u64, 0, 0]);
            let finite: Vec<f64> = (0..N)
                .filter_map(|_| weakest_defect(density, area, &law, &mut draws))
                .collect();
            let expected = density * area;
            let cdf = |s: f64| -(-expected * law.cdf(s)).exp_m1();
            let d = ks_statistic(finite, N, cdf);
            assert!(d < ks_critical(N, 0.01), "KS {d} at rho A = {expected}");
        }
        let mut draws = Draws::new(0, [0, 0, 0]);
        assert_eq!(weakest_defect(0.0, 1.0, &shipped(), &mut draws), None);
    }
}
