//! Crack nucleation and propagation criteria (seed 4.3.1-4.3.2, 4.4.2) as pure functions.
//!
//! - [`Draws`]: counter-based uniform draws keyed by the run seed and stable ids, so that every
//!   random decision is independent of threads and execution order.
//! - [`DefectStrengths`]: the nucleation strengths of defects, a normal law truncated below
//!   ((4.16)-(4.17) with no upper bound), and the weakest of `n` defects from a single draw.
//! - [`poisson`]: the number of defects in a region of area `a`. (4.18) gives it as
//!   `n = rho_N a`; this project reads that as the mean of a Poisson count (defects scattered
//!   uniformly and independently with density `rho_N`), which keeps small patches unbiased.
//!   [`weakest_defect`] combines both into the right-hand side of the nucleation criterion (4.15).
//! - [`effective_traction`], [`max_effective_traction`], [`tensile_maxima`]: the effective traction
//!   (4.10) on a plane, its maximum over orientations (the left-hand side of (4.15)) and its
//!   tensile local maxima (the propagation directions of 4.3.2), all in closed form;
//!   [`crack_directions`] turns a plane's normal into the two directions a crack can run along.
//!
//! Units are SI: stresses and strengths in Pa, densities in 1/m^2, areas in m^2, angles in
//! radians measured counterclockwise from the x axis.

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_2_SQRT_PI, FRAC_PI_2, PI, TAU};

use crate::interface::LawError;

/// Counter-based uniform draws: the stream of one `(seed, key)` pair.
///
/// A stream hash `h` absorbs the seed and the key's components one at a time,
/// `h = mix(seed ^ T0)`, then `h <- mix(h ^ k_i * T_i)` with distinct odd tags `T_i`; draw `i`
/// (from 1) is `mix(h ^ mix(i * W))` with an odd Weyl increment `W`. `mix` is Stafford's
/// "Mix13" xor-shift-multiply finalizer (the one of SplitMix64), a bijection of 64-bit words
/// with full avalanche, so neighbouring keys give unrelated streams, and the counter is mixed
/// before it meets `h`, so two streams never replay each other shifted.
///
/// A draw depends only on the seed, the key and its index: give every random decision its own
/// key of stable ids (e.g. a vertex id and its pitch count, or a crack-tip id) and draw from it
/// in a fixed order.
#[derive(Clone, Debug)]
pub struct Draws {
    /// The stream hash `h`.
    stream: u64,
    /// Draws taken so far.
    counter: u64,
}

/// Tag of the seed.
const SEED_TAG: u64 = 0x2545_f491_4f6c_dd1d;
/// Tags of the key's components.
const KEY_TAGS: [u64; 3] = [
    0xc2b2_ae3d_27d4_eb4f,
    0x1656_67b1_9e37_79f9,
    0xd6e8_feb8_6659_fd93,
];
/// Weyl increment of the counter: 2^64 over the golden ratio, rounded to odd.
const WEYL: u64 = 0x9e37_79b9_7f4a_7c15;

/// Stafford's "Mix13" finalizer: a bijection of 64-bit words with full avalanche.
fn mix(x: u64) -> u64 {
    let x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    let x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

impl Draws {
    /// The stream of the run seed `seed` and the stable ids `key`.
    pub fn new(seed: u64, key: [u64; 3]) -> Self {
        let stream = key
            .iter()
            .zip(KEY_TAGS)
            .fold(mix(seed ^ SEED_TAG), |h, (&k, tag)| {
                mix(h ^ k.wrapping_mul(tag))
            });
        Self { stream, counter: 0 }
    }

    /// The next draw, uniform on the open interval (0, 1): `(j + 1/2) 2^-52` with `j` the top 52
    /// bits of the mixed word, so neither `u` nor `1 - u` is 0 and both are exact.
    pub fn next_uniform(&mut self) -> f64 {
        self.counter = self.counter.wrapping_add(1);
        let bits = mix(self.stream ^ mix(self.counter.wrapping_mul(WEYL)));
        // f64::EPSILON is 2^-52.
        ((bits >> 12) as f64 + 0.5) * f64::EPSILON
    }
}

/// `1 / sqrt(2 pi)`.
const FRAC_1_SQRT_2PI: f64 = 0.5 * FRAC_2_SQRT_PI * FRAC_1_SQRT_2;

/// Evaluates the polynomial with coefficients `c` in ascending powers at `x` (Horner).
fn poly(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ci| acc * x + ci)
}

/// `exp(-x^2 / 2)` without the amplified rounding of `x^2` for large `|x|`: `x = xs + d` with
/// `xs` on a 1/16 grid (so `xs^2` is exact) and `x^2 = xs^2 + d (x + xs)` (Cody's splitting).
fn exp_neg_half_sq(x: f64) -> f64 {
    let xs = (x * 16.0).trunc() / 16.0;
    let del = (x - xs) * (x + xs);
    (-0.5 * xs * xs).exp() * (-0.5 * del).exp()
}

/// The upper tail `Q(x) = P(X > x) = erfc(x / sqrt 2) / 2` of the standard normal law, with a
/// relative error of a few ulps for every `x` (deep tails included; `Q` underflows to 0 near
/// `x = 38.5`). `Phi(x) = Q(-x)`.
///
/// W. J. Cody's rational Chebyshev approximations (Math. Comp. 23, 1969, 631-637) in
/// `y = |x| / sqrt 2`: `erf(y) = y R1(y^2)` for `y <= 0.46875`, `erfc(y) = exp(-y^2) R2(y)` for
/// `y <= 4` and `erfc(y) = exp(-y^2) (1/sqrt(pi) - R3(1/y^2) / y^2) / y` beyond. The tail is taken
/// from erfc of the positive argument only, never as `1 - Phi` of a large one.
fn normal_upper(x: f64) -> f64 {
    const ERF_NUM: [f64; 5] = [
        3.209_377_589_138_469_4e3,
        3.774_852_376_853_02e2,
        1.138_641_541_510_501_6e2,
        3.161_123_743_870_565_5,
        1.857_777_061_846_031_5e-1,
    ];
    const ERF_DEN: [f64; 5] = [
        2.844_236_833_439_171e3,
        1.282_616_526_077_372_3e3,
        2.440_246_379_344_441_7e2,
        2.360_129_095_234_412_2e1,
        1.0,
    ];
    const MID_NUM: [f64; 9] = [
        1.230_339_354_797_997_2e3,
        2.051_078_377_826_071_6e3,
        1.712_047_612_634_070_7e3,
        8.819_522_212_417_69e2,
        2.986_351_381_974_001e2,
        6.611_919_063_714_163e1,
        8.883_149_794_388_377,
        5.641_884_969_886_701e-1,
        2.153_115_354_744_038_3e-8,
    ];
    const MID_DEN: [f64; 9] = [
        1.230_339_354_803_749_5e3,
        3.439_367_674_143_721_6e3,
        4.362_619_090_143_247e3,
        3.290_799_235_733_459_7e3,
        1.621_389_574_566_690_3e3,
        5.371_811_018_620_099e2,
        1.176_939_508_913_125e2,
        1.574_492_611_070_983_5e1,
        1.0,
    ];
    const FAR_NUM: [f64; 6] = [
        6.587_491_615_298_378e-4,
        1.608_378_514_874_227_5e-2,
        1.257_817_261_112_292_6e-1,
        3.603_448_999_498_044_5e-1,
        3.053_266_349_612_323_6e-1,
        1.631_538_713_730_209_7e-2,
    ];
    const FAR_DEN: [f64; 6] = [
        2.335_204_976_268_691_8e-3,
        6.051_834_131_244_132e-2,
        5.279_051_029_514_285e-1,
        1.872_952_849_923_467_3,
        2.568_520_192_289_822,
        1.0,
    ];
    if x > 40.0 {
        return 0.0;
    }
    if x < -40.0 {
        return 1.0;
    }
    let y = x.abs() * FRAC_1_SQRT_2;
    if y <= 0.468_75 {
        let t = y * y;
        let erf = x * FRAC_1_SQRT_2 * poly(&ERF_NUM, t) / poly(&ERF_DEN, t);
        return 0.5 - 0.5 * erf;
    }
    let erfc = if y <= 4.0 {
        exp_neg_half_sq(x) * poly(&MID_NUM, y) / poly(&MID_DEN, y)
    } else {
        let t = 1.0 / (y * y);
        let r = t * poly(&FAR_NUM, t) / poly(&FAR_DEN, t);
        exp_neg_half_sq(x) * (0.5 * FRAC_2_SQRT_PI - r) / y
    };
    if x > 0.0 {
        0.5 * erfc
    } else {
        1.0 - 0.5 * erfc
    }
}

/// The standard normal quantile `Phi^-1(p)` for `p` in [0, 1] (`-inf` at 0, `+inf` at 1), with a
/// relative error near 1e-16: M. J. Wichura's algorithm AS 241 (PPND16; Appl. Statist. 37, 1988,
/// 477-484). Accurate for tiny `p`; for `p` near 1 pass the complement and negate.
fn normal_quantile(p: f64) -> f64 {
    const CENTRAL_NUM: [f64; 8] = [
        3.387_132_872_796_366_5,
        1.331_416_678_917_843_8e2,
        1.971_590_950_306_551_3e3,
        1.373_169_376_550_946e4,
        4.592_195_393_154_987e4,
        6.726_577_092_700_87e4,
        3.343_057_558_358_813e4,
        2.509_080_928_730_122_7e3,
    ];
    const CENTRAL_DEN: [f64; 8] = [
        1.0,
        4.231_333_070_160_091e1,
        6.871_870_074_920_579e2,
        5.394_196_021_424_751e3,
        2.121_379_430_158_659_7e4,
        3.930_789_580_009_271e4,
        2.872_908_573_572_194_3e4,
        5.226_495_278_852_545e3,
    ];
    const NEAR_NUM: [f64; 8] = [
        1.423_437_110_749_683_5,
        4.630_337_846_156_546,
        5.769_497_221_460_691,
        3.647_848_324_763_204_5,
        1.270_458_252_452_368_4,
        2.417_807_251_774_506e-1,
        2.272_384_498_926_918_4e-2,
        7.745_450_142_783_414e-4,
    ];
    const NEAR_DEN: [f64; 8] = [
        1.0,
        2.053_191_626_637_759,
        1.676_384_830_183_803_8,
        6.897_673_349_851e-1,
        1.481_039_764_274_800_8e-1,
        1.519_866_656_361_645_7e-2,
        5.475_938_084_995_345e-4,
        1.050_750_071_644_416_9e-9,
    ];
    const FAR_NUM: [f64; 8] = [
        6.657_904_643_501_103,
        5.463_784_911_164_114,
        1.784_826_539_917_291_3,
        2.965_605_718_285_048_7e-1,
        2.653_218_952_657_612_4e-2,
        1.242_660_947_388_078_4e-3,
        2.711_555_568_743_487_6e-5,
        2.010_334_399_292_288_1e-7,
    ];
    const FAR_DEN: [f64; 8] = [
        1.0,
        5.998_322_065_558_88e-1,
        1.369_298_809_227_358e-1,
        1.487_536_129_085_061_5e-2,
        7.868_691_311_456_133e-4,
        1.846_318_317_510_054_8e-5,
        1.421_511_758_316_446e-7,
        2.044_263_103_389_939_7e-15,
    ];
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        let r = 0.180_625 - q * q;
        return q * poly(&CENTRAL_NUM, r) / poly(&CENTRAL_DEN, r);
    }
    let r = (-(p.min(1.0 - p)).ln()).sqrt();
    let x = if r <= 5.0 {
        let r = r - 1.6;
        poly(&NEAR_NUM, r) / poly(&NEAR_DEN, r)
    } else {
        let r = r - 5.0;
        poly(&FAR_NUM, r) / poly(&FAR_DEN, r)
    };
    if q < 0.0 { -x } else { x }
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

    /// A strength (Pa) drawn with the uniform `u` in (0, 1) (inversion: `quantile(u)`).
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
    let h = |x: f64| FRAC_1_SQRT_2PI * exp_neg_half_sq(x) / normal_upper(-x);
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

/// Poisson means below this are drawn by inversion (expected `mean + 1` steps), the others by
/// PTRS, whose constants Hörmann fitted for means >= 10.
const PTRS_MIN_MEAN: f64 = 10.0;

/// A Poisson count of mean `mean` (>= 0), exact up to rounding and deterministic given the
/// draws: sequential-search inversion with one draw for small means, W. Hörmann's transformed
/// rejection with squeeze PTRS (Insurance Math. Econom. 12, 1993, 39-45) for large ones, two draws
/// per trial and O(1) expected trials. A mean that is not > 0 gives 0, `+inf` gives `u64::MAX`.
pub fn poisson(mean: f64, draws: &mut Draws) -> u64 {
    if mean.is_nan() || mean <= 0.0 {
        0
    } else if mean == f64::INFINITY {
        u64::MAX
    } else if mean < PTRS_MIN_MEAN {
        poisson_inversion(mean, draws.next_uniform())
    } else {
        poisson_ptrs(mean, draws)
    }
}

/// The smallest `k` with `P(N <= k) >= u` (stopping where the remaining tail is below rounding).
fn poisson_inversion(mean: f64, u: f64) -> u64 {
    let mut k = 0;
    let mut pmf = (-mean).exp();
    let mut cdf = pmf;
    while u > cdf {
        k += 1;
        pmf *= mean / k as f64;
        let next = cdf + pmf;
        if next == cdf {
            break;
        }
        cdf = next;
    }
    k
}

/// Hörmann's PTRS for `mean >= 10`: a candidate `k` from the transformed uniform `U`, accepted
/// at once inside the squeeze, else by comparing `V` against the Poisson probability of `k`.
fn poisson_ptrs(mean: f64, draws: &mut Draws) -> u64 {
    let ln_mean = mean.ln();
    let b = 0.931 + 2.53 * mean.sqrt();
    let a = -0.059 + 0.02483 * b;
    let inv_alpha = 1.1239 + 1.1328 / (b - 3.4);
    let v_r = 0.9277 - 3.6224 / (b - 2.0);
    loop {
        let u = draws.next_uniform() - 0.5;
        let v = draws.next_uniform();
        let us = 0.5 - u.abs();
        let k = ((2.0 * a / us + b) * u + mean + 0.43).floor();
        if us >= 0.07 && v <= v_r {
            return k as u64;
        }
        if k < 0.0 || (us < 0.013 && v > us) {
            continue;
        }
        let log_hat = (v * inv_alpha / (a / (us * us) + b)).ln();
        if log_hat <= -mean + k * ln_mean - ln_factorial(k) {
            return k as u64;
        }
    }
}

/// `ln k!` for a whole number `k >= 0`: the logarithm of the product below 30, Stirling's series
/// of `ln Gamma(k + 1)` to the `x^-7` term from 30 on (truncation error below 1e-16).
fn ln_factorial(k: f64) -> f64 {
    if k < 30.0 {
        let mut product = 1.0;
        let mut i = 2.0;
        while i <= k {
            product *= i;
            i += 1.0;
        }
        return product.ln();
    }
    let x = k + 1.0;
    let r = 1.0 / (x * x);
    let series = (1.0 / 12.0 - r * (1.0 / 360.0 - r * (1.0 / 1260.0 - r / 1680.0))) / x;
    (x - 0.5) * x.ln() - x + 0.5 * TAU.ln() + series
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

/// An in-plane stress in its principal frame: on the plane of normal angle `th`,
/// `sn = p + q cos 2(th - angle)` and `st = -q sin 2(th - angle)`.
struct Principal {
    /// Mean normal stress `(sxx + syy) / 2` (Pa).
    p: f64,
    /// Mohr radius (Pa, >= 0).
    q: f64,
    /// Normal angle of the largest principal stress (radians).
    angle: f64,
}

impl Principal {
    fn new([sxx, syy, sxy]: [f64; 3]) -> Self {
        let d = 0.5 * (sxx - syy);
        Self {
            p: 0.5 * (sxx + syy),
            q: d.hypot(sxy),
            angle: 0.5 * sxy.atan2(d),
        }
    }

    /// `s_eff^2` as a function of `c = cos 2(th - angle)` in [-1, 1].
    fn eff_sq(&self, beta: f64, c: f64) -> f64 {
        let tension = (self.p + self.q * c).max(0.0);
        let shear = beta * self.q;
        tension * tension + shear * shear * (1.0 - c) * (1.0 + c)
    }

    /// For `beta > 1` the tensile branch `(p + q c)^2 + beta^2 q^2 (1 - c^2)` is strictly concave
    /// in `c`: its stationary point `c* = p / (q (beta^2 - 1))` when it is tensile and inside
    /// (-1, 1), i.e. `p > 0` and `c* < 1`.
    fn stationary(&self, beta: f64) -> Option<f64> {
        if beta > 1.0 && self.p > 0.0 && self.q > 0.0 {
            let c = self.p / (self.q * (beta * beta - 1.0));
            (c < 1.0).then_some(c)
        } else {
            None
        }
    }
}

/// The effective traction `s_eff = sqrt(<sn>_+^2 + beta^2 st^2)` (seed 4.10; Pa) and the normal
/// traction `sn` (Pa) on the plane of unit normal `n = (cos th, sin th)` under the in-plane stress
/// `[sxx, syy, sxy]` (Pa): `sn = n.S.n`, `st = t.S.n` with `t = (-sin th, cos th)`; `beta >= 0`
/// is the mixity factor.
pub fn effective_traction(stress: [f64; 3], beta: f64, th: f64) -> (f64, f64) {
    let [sxx, syy, sxy] = stress;
    let (s, c) = th.sin_cos();
    let traction = [sxx * c + sxy * s, sxy * c + syy * s];
    let sn = c * traction[0] + s * traction[1];
    let st = c * traction[1] - s * traction[0];
    (sn.max(0.0).hypot(beta * st), sn)
}

/// The global maximum over plane orientations of [`effective_traction`]: `(th, s_eff)` with the
/// normal angle `th` in [0, pi) (radians) and `s_eff` (Pa); the left-hand side `s_*` of (4.15).
///
/// Closed form in the principal frame (`c = cos 2(th - angle)`, see `Principal`): `s_eff^2` is
/// `(p + q c)^2 + beta^2 q^2 (1 - c^2)` where `sn > 0` and `beta^2 q^2 (1 - c^2)` elsewhere, so the
/// maximum over `c` in [-1, 1] is at `c = 1` (largest normal traction), at `c = 0` (largest shear,
/// compressive when `p <= 0`) or, for `beta > 1`, at the stationary point `c*` of the concave
/// tensile branch. Ties (equal values, flat maxima, isotropic stress) return the first of these
/// candidates, with `th = angle + acos(c) / 2`.
pub fn max_effective_traction(stress: [f64; 3], beta: f64) -> (f64, f64) {
    let pr = Principal::new(stress);
    let mut best = (1.0, pr.eff_sq(beta, 1.0));
    let candidates = [(pr.p <= 0.0).then_some(0.0), pr.stationary(beta)];
    for c in candidates.into_iter().flatten() {
        let g = pr.eff_sq(beta, c);
        if g > best.1 {
            best = (c, g);
        }
    }
    (normalize(pr.angle + 0.5 * best.0.acos()), best.1.sqrt())
}

/// The normal angles (radians) of the planes where [`effective_traction`] is a local maximum in
/// `th` with tension (`sn > 0`) and `s_eff > threshold` (Pa): the propagation directions of seed
/// 4.3.2 (a crack runs along such a plane; see [`crack_directions`]). Returns the angles in
/// increasing order and their number (0, 1 or 2); unused entries are NaN.
///
/// `window = Some((centre, half_width))` (radians) keeps only the maxima whose plane lies within
/// `half_width` of `centre` (angles modulo pi), reported as the representative nearest `centre`;
/// without a window the angles are in [0, pi). Only true local maxima of the function over all
/// orientations count: a window's edge never creates one. To bound the kink of a crack whose tip
/// travels in the direction `alpha`, use the window `(alpha + pi/2, kink)`.
///
/// In the principal frame (see [`max_effective_traction`]) a tensile local maximum is either at
/// `c = 1` (one plane, the largest principal stress), when `s_eff^2` does not decrease towards
/// `c = 1` (`p + q (1 - beta^2) >= 0`, with `p + q > 0`), or, for `beta > 1`, at the interior
/// stationary point `c*` (two planes, symmetric about the principal one). A flat plateau counts
/// as one maximum at its centre: for isotropic stress (`q = 0`, every plane alike) that is the
/// window's centre, or 0 without a window.
pub fn tensile_maxima(
    stress: [f64; 3],
    beta: f64,
    window: Option<(f64, f64)>,
    threshold: f64,
) -> ([f64; 2], usize) {
    let pr = Principal::new(stress);
    let mut found = [f64::NAN; 2];
    let mut len = 0;
    let mut keep = |th: f64| {
        let placed = match window {
            None => Some(normalize(th)),
            Some((centre, half_width)) => {
                let near = th + ((centre - th) / PI).round() * PI;
                ((near - centre).abs() <= half_width).then_some(near)
            }
        };
        if let Some(th) = placed {
            found[len] = th;
            len += 1;
        }
    };
    if pr.q == 0.0 {
        if pr.p > 0.0 && pr.p > threshold {
            keep(window.map_or(0.0, |(centre, _)| centre));
        }
    } else if let Some(c) = pr.stationary(beta) {
        if pr.eff_sq(beta, c).sqrt() > threshold {
            let half = 0.5 * c.acos();
            keep(pr.angle + half);
            keep(pr.angle - half);
        }
    } else if pr.p + pr.q > 0.0
        && pr.p + pr.q * (1.0 - beta * beta) >= 0.0
        && pr.p + pr.q > threshold
    {
        keep(pr.angle);
    }
    if len == 2 && found[0] > found[1] {
        found.swap(0, 1);
    }
    (found, len)
}

/// The two directions (radians, in (-pi, pi]) along the plane of normal angle `normal_angle`
/// from a point: `normal_angle + pi/2` and `normal_angle - pi/2`.
///
/// At a crack tip whose crack arrives along the unit tangent of angle `alpha` (pointing out of
/// the crack, the direction of travel), the forward one is the direction `d` with
/// `cos(d - alpha) > 0` (seed 4.3.2's `pi/2 < theta < 3 pi/2` measured from the crack behind);
/// a plane perpendicular to the tangent has no forward direction. A nucleation site extends both.
pub fn crack_directions(normal_angle: f64) -> [f64; 2] {
    let wrap = |a: f64| {
        let t = a.rem_euclid(TAU);
        if t > PI { t - TAU } else { t }
    };
    [
        wrap(normal_angle + FRAC_PI_2),
        wrap(normal_angle - FRAC_PI_2),
    ]
}

/// `th` modulo pi, in [0, pi).
fn normalize(th: f64) -> f64 {
    let t = th.rem_euclid(PI);
    if t >= PI { 0.0 } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cohesive strength of the shipped configuration (Pa); its defects: mean `5 SIGMA_C`,
    /// truncated at `0.4 SIGMA_C`.
    const SIGMA_C: f64 = 62.1e6;

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

    /// Stephens' (1970) 1% critical value of the Kolmogorov-Smirnov statistic for `n` samples.
    fn ks_critical(n: usize) -> f64 {
        let s = (n as f64).sqrt();
        1.628 / (s + 0.12 + 0.11 / s)
    }

    /// The Kolmogorov-Smirnov statistic of `total` draws against the CDF `cdf`, given the finite
    /// ones in `finite` (the others are an atom at `+inf`, where `cdf` tends to
    /// `cdf(inf) <= 1`). With such an atom the statistic is stochastically smaller than for a
    /// continuous law, so the usual critical value stays a valid (conservative) 1% test.
    fn ks_statistic(mut finite: Vec<f64>, total: usize, cdf: impl Fn(f64) -> f64) -> f64 {
        finite.sort_by(f64::total_cmp);
        let n = total as f64;
        let mut d: f64 = 0.0;
        for (i, &x) in finite.iter().enumerate() {
            let f = cdf(x);
            d = d.max((i as f64 + 1.0) / n - f).max(f - i as f64 / n);
        }
        d.max((cdf(f64::INFINITY) - finite.len() as f64 / n).abs())
    }

    /// Pearson's correlation coefficient of the pairs `(x_i, y_i)`.
    fn pearson(x: &[f64], y: &[f64]) -> f64 {
        let n = x.len() as f64;
        let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
        let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
        for (a, b) in x.iter().zip(y) {
            sxy += (a - mx) * (b - my);
            sxx += (a - mx) * (a - mx);
            syy += (b - my) * (b - my);
        }
        sxy / (sxx * syy).sqrt()
    }

    /// The first `n` draws of the stream `(seed, key)`.
    fn stream(seed: u64, key: [u64; 3], n: usize) -> Vec<f64> {
        let mut draws = Draws::new(seed, key);
        (0..n).map(|_| draws.next_uniform()).collect()
    }

    #[test]
    fn draws_are_reproducible() {
        let mut a = Draws::new(42, [7, 3, 1]);
        let mut b = Draws::new(42, [7, 3, 1]);
        for _ in 0..1000 {
            assert_eq!(a.next_uniform().to_bits(), b.next_uniform().to_bits());
        }
        let mut c = a.clone();
        for _ in 0..10 {
            assert_eq!(a.next_uniform().to_bits(), c.next_uniform().to_bits());
        }
        // Pinned: a change of the generator changes every run's defects and cracks.
        assert_eq!(
            Draws::new(0, [0, 0, 0]).next_uniform().to_bits(),
            0x3fef_6fd9_dfe4_a343
        );
        assert_eq!(
            Draws::new(2024, [17, 5, 0]).next_uniform().to_bits(),
            0x3fc7_7f44_9551_c3a4
        );
    }

    #[test]
    fn draws_are_uniform_on_the_open_interval() {
        const N: usize = 100_000;
        let along = stream(1, [2, 3, 4], N);
        // The first draws of consecutive keys in each component, as a vertex's first pitches use.
        let across: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                (0..N as u64)
                    .map(|k| {
                        let mut key = [11, 12, 13];
                        key[i] = k;
                        Draws::new(1, key).next_uniform()
                    })
                    .collect()
            })
            .collect();
        for sample in std::iter::once(&along).chain(&across) {
            assert!(sample.iter().all(|&u| u > 0.0 && u < 1.0));
            let d = ks_statistic(sample.clone(), N, |u| u.clamp(0.0, 1.0));
            assert!(d < ks_critical(N), "KS {d} >= {}", ks_critical(N));
        }
    }

    #[test]
    fn draws_of_neighbouring_keys_are_uncorrelated() {
        // Under independence Pearson's r of n pairs is close to N(0, 1/n): |r| < 4.5 / sqrt(n)
        // has a false-alarm probability of 7e-6 per pair (11 pairs here; largest |r| measured
        // 0.0064 against the bound 0.0142).
        const N: usize = 100_000;
        let bound = 4.5 / (N as f64).sqrt();
        let (seed, key) = (5, [1000, 20, 3]);
        let base = stream(seed, key, N);
        let mut neighbours = vec![stream(seed + 1, key, N)];
        for i in 0..3 {
            let mut next = key;
            next[i] += 1;
            neighbours.push(stream(seed, next, N));
        }
        let mut pairs: Vec<(Vec<f64>, Vec<f64>)> = neighbours
            .into_iter()
            .map(|other| (base.clone(), other))
            .collect();
        // Successive draws of one stream.
        pairs.push((base[..N - 1].to_vec(), base[1..].to_vec()));
        // First and second draws of keys k and k + 1 in each component.
        for draw in 0..2 {
            for i in 0..3 {
                let nth = |k: u64| {
                    let mut next = key;
                    next[i] = k;
                    let mut draws = Draws::new(seed, next);
                    (0..draw).for_each(|_| {
                        draws.next_uniform();
                    });
                    draws.next_uniform()
                };
                let x: Vec<f64> = (0..N as u64 + 1).map(nth).collect();
                pairs.push((x[..N].to_vec(), x[1..].to_vec()));
            }
        }
        for (x, y) in &pairs {
            let r = pearson(x, y);
            assert!(r.abs() < bound, "r = {r}");
        }
    }

    #[test]
    fn normal_tail_matches_references() {
        // Q(x) from mpmath at 60 digits. Cody's approximations are accurate to ~1e-17 relative
        // and the evaluation adds a few ulps: 1e-15 relative (4.5 ulps) allowed, 2 measured.
        let references = [
            (-38.0, 1.0),
            (-10.0, 1.0),
            (-5.0, 0.999_999_713_348_428_1),
            (-1.5, 0.933_192_798_731_141_9),
            (-0.6, 0.725_746_882_249_926_5),
            (-0.3, 0.617_911_422_188_952_7),
            (0.0, 0.5),
            (0.001, 0.499_601_057_786_088_93),
            (0.3, 0.382_088_577_811_047_4),
            (0.66, 0.254_626_914_671_336_14),
            (0.67, 0.251_428_895_095_310_1),
            (1.0, 0.158_655_253_931_457_05),
            (2.5, 0.006_209_665_325_776_135),
            (5.0, 2.866_515_718_791_939e-7),
            (5.65, 8.022_391_850_663_497e-9),
            (5.66, 7.568_649_751_997_714e-9),
            (8.0, 6.220_960_574_271_784e-16),
            (12.0, 1.776_482_112_077_679e-33),
            (20.0, 2.753_624_118_606_233_7e-89),
            (30.0, 4.906_713_927_148_187e-198),
            (37.5, 4.605_353_009_581_955e-308),
        ];
        for (x, q) in references {
            let err = (normal_upper(x) - q).abs() / q;
            assert!(err <= 1e-15, "Q({x}) = {}, expected {q}", normal_upper(x));
        }
        assert_eq!(normal_upper(41.0), 0.0);
        assert_eq!(normal_upper(-41.0), 1.0);
    }

    #[test]
    fn normal_quantile_matches_references() {
        // Phi^-1(p) from mpmath at 60 digits; AS 241 is accurate to ~1e-16 relative: 1e-15
        // (4.5 ulps) allowed, 1.5 measured.
        let references = [
            (1e-300, -37.047_096_299_361_2),
            (1e-100, -21.273_453_560_965_326),
            (1e-20, -9.262_340_089_798_407),
            (1e-11, -6.706_023_155_495_136),
            (1e-10, -6.361_340_902_404_057),
            (1e-5, -4.264_890_793_922_825),
            (0.01, -2.326_347_874_040_841),
            (0.07, -1.475_791_028_179_170_6),
            (0.08, -1.405_071_560_309_632_7),
            (0.2, -0.841_621_233_572_914_2),
            (0.8, 0.841_621_233_572_914_4),
            (0.99, 2.326_347_874_040_840_8),
        ];
        for (p, x) in references {
            let err = ((normal_quantile(p) - x) / x).abs();
            assert!(
                err <= 1e-15,
                "Phi^-1({p}) = {}, expected {x}",
                normal_quantile(p)
            );
        }
        assert_eq!(normal_quantile(0.5), 0.0);
        assert_eq!(normal_quantile(0.0), f64::NEG_INFINITY);
        assert_eq!(normal_quantile(1.0), f64::INFINITY);
        // Round trip through the lower tail down to 1e-300.
        for e in 1..=300 {
            let p = 10f64.powi(-e);
            let x = normal_quantile(p);
            // The relative error of Q(-x) is that of x times |x| |d ln Phi / dx| ~ x^2: allow
            // (1 + x^2) 2e-15 (measured up to (1 + x^2) 7e-16).
            let err = (normal_upper(-x) - p).abs() / p;
            assert!(
                err <= (1.0 + x * x) * 2e-15,
                "Phi(Phi^-1({p})) off by {err}"
            );
        }
    }

    #[test]
    fn truncated_cdf_matches_references() {
        // (mean, std, lower, s, F(s)) from mpmath at 60 digits. Forming z = (s - mean) / std
        // rounds by an ulp of mean / std, which moves F by |d ln F / dz| ~ |z| times that
        // (relative): up to ~20 * 20 ulps for the deep law. Allowed: 2e-13; measured 2.7e-14.
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
        // 4.8e-15 measured.
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
        // the truncation it is most of F: F is proportional to s - lower there). Allowed:
        // 4 eps mean pdf(s); measured up to 1.7.
        for law in [shipped(), deep(), wide()] {
            let a = (law.lower - law.mean) / law.std;
            let pdf = |s: f64| {
                let z = (s - law.mean) / law.std;
                FRAC_1_SQRT_2PI * (-0.5 * z * z).exp() / (law.std * normal_upper(a))
            };
            for e in 1..=60 {
                for q in [10f64.powi(-e), 1.0 - 10f64.powf(-0.25 * e as f64), 0.5] {
                    let s = law.quantile(q);
                    assert!(s >= law.lower);
                    let unit = f64::EPSILON * law.mean * pdf(s);
                    let err = (law.cdf(s) - q).abs();
                    assert!(err <= 4.0 * unit, "F(quantile({q})) = {}", law.cdf(s));
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
            assert!(d < ks_critical(N), "KS {d}");
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
            assert!(d < ks_critical(N), "KS {d} for n = {n}");
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
        let pmf = |k: usize| (-mean + k as f64 * mean.ln() - ln_factorial(k as f64)).exp();
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
    fn log_factorial_matches_references() {
        // ln Gamma(k + 1) from mpmath: the product branch rounds k times (< 30 ulps of the
        // product, 7e-15 absolute in the log), Stirling's series to an ulp or two of its terms.
        let references = [
            (0.0, 0.0),
            (1.0, 0.0),
            (2.0, std::f64::consts::LN_2),
            (10.0, 15.104_412_573_075_516),
            (29.0, 71.257_038_967_168_01),
            (30.0, 74.658_236_348_830_16),
            (31.0, 78.092_223_553_315_3),
            (100.0, 363.739_375_555_563_47),
            (2000.0, 13_206.524_350_513_806),
            (1e6, 12_815_518.384_658_169),
        ];
        for (k, reference) in references {
            let err = (ln_factorial(k) - reference).abs();
            assert!(
                err <= 1e-14 * reference.max(1.0),
                "ln {k}! = {}",
                ln_factorial(k)
            );
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
            assert!(d < ks_critical(N), "KS {d} at rho A = {expected}");
        }
        let mut draws = Draws::new(0, [0, 0, 0]);
        assert_eq!(weakest_defect(0.0, 1.0, &shipped(), &mut draws), None);
    }

    /// Distance between two plane normals (radians, modulo pi).
    fn plane_distance(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(PI);
        d.min(PI - d)
    }

    /// A local maximum of `s_eff` over the normal angle found by the brute-force scan.
    #[derive(Clone, Copy, Debug)]
    struct Peak {
        th: f64,
        s_eff: f64,
        sn: f64,
    }

    /// The brute-force scan of `s_eff` over `GRID` normal angles in [0, pi) (periodic): the grid
    /// points higher than the previous one and at least as high as the next, each refined by a
    /// golden-section search between its neighbours (to ~1e-8 rad, the value to ~1e-16
    /// relative); and the largest grid value.
    fn scan(stress: [f64; 3], beta: f64) -> (Vec<Peak>, f64) {
        const GRID: usize = 1 << 17;
        let h = PI / GRID as f64;
        let f = |th: f64| effective_traction(stress, beta, th).0;
        let values: Vec<f64> = (0..GRID).map(|i| f(i as f64 * h)).collect();
        let mut peaks = Vec::new();
        for i in 0..GRID {
            let (prev, next) = (values[(i + GRID - 1) % GRID], values[(i + 1) % GRID]);
            if values[i] > prev && values[i] >= next {
                let (mut a, mut b) = ((i as f64 - 1.0) * h, (i as f64 + 1.0) * h);
                let ratio = 0.5 * (5f64.sqrt() - 1.0);
                for _ in 0..80 {
                    let (x1, x2) = (b - ratio * (b - a), a + ratio * (b - a));
                    if f(x1) < f(x2) {
                        a = x1;
                    } else {
                        b = x2;
                    }
                }
                let th = 0.5 * (a + b);
                let (s_eff, sn) = effective_traction(stress, beta, th);
                peaks.push(Peak { th, s_eff, sn });
            }
        }
        (peaks, values.iter().copied().fold(0.0, f64::max))
    }

    /// Stresses for the orientation tests (Pa): random ones with mixed signs, and the special
    /// states of the brief (pure shear, equal biaxial, uniaxial tension and compression).
    fn stresses() -> Vec<[f64; 3]> {
        let mut draws = Draws::new(77, [0, 0, 0]);
        let mut all: Vec<[f64; 3]> = (0..200)
            .map(|_| [0; 3].map(|_| (2.0 * draws.next_uniform() - 1.0) * SIGMA_C))
            .collect();
        let s = SIGMA_C;
        all.extend([
            [s, 0.0, 0.0],
            [0.0, s, 0.0],
            [-s, 0.0, 0.0],
            [0.0, -s, 0.0],
            [0.3 * s, -s, 0.2 * s],
            [-s, -0.5 * s, 0.1 * s],
            [-s, -s, 0.0],
            [s, 0.99 * s, 0.0],
            [0.0, 0.0, s],
            [0.5 * s, -0.5 * s, 0.0],
        ]);
        all
    }

    #[test]
    fn effective_traction_on_a_plane() {
        // Uniaxial tension s along x on the plane of normal (cos th, sin th): sn = s cos^2 th,
        // st = -s sin th cos th.
        let (s, beta) = (SIGMA_C, 0.7);
        for th in [0.0, 0.3, 1.0, FRAC_PI_2, 2.5, -0.4] {
            let (c, si) = (f64::cos(th), f64::sin(th));
            let (sn, st) = (s * c * c, -s * si * c);
            let expected = (sn.max(0.0).powi(2) + (beta * st).powi(2)).sqrt();
            let (s_eff, got_sn) = effective_traction([s, 0.0, 0.0], beta, th);
            assert!(
                (s_eff - expected).abs() <= 1e-15 * s,
                "{s_eff} vs {expected}"
            );
            assert!((got_sn - sn).abs() <= 1e-15 * s);
        }
        // Pure shear: on the x plane st = sxy; tension at 45 degrees, compression at 135.
        let (s_eff, sn) = effective_traction([0.0, 0.0, SIGMA_C], 2.0, 0.0);
        assert!(sn.abs() <= 1e-15 * SIGMA_C && (s_eff - 2.0 * SIGMA_C).abs() <= 1e-15 * SIGMA_C);
        let (s_eff, sn) = effective_traction([0.0, 0.0, SIGMA_C], 2.0, 0.75 * PI);
        assert!((sn + SIGMA_C).abs() <= 1e-15 * SIGMA_C && s_eff.abs() <= 1e-15 * SIGMA_C);
    }

    #[test]
    fn orientation_search_matches_a_brute_force_scan() {
        // The closed forms are exact to rounding; the scan's refined peaks to ~1e-16 relative in
        // value and ~1e-8 rad in angle (golden section on a smooth peak), so the brief's 1e-9
        // relative and 1e-4 rad hold with margin.
        //
        // Global maximum: the value against the highest peak; the angle, when the peak is not
        // flat (s_eff drops by more than 1e-9 relative within 1e-3 rad), against the nearest of
        // the highest peaks (symmetric global maxima tie).
        //
        // Tensile maxima: the peaks with sn > 0 and s_eff > threshold, inside the window: same
        // number, same angles and values. Cases whose answer hinges on rounding are skipped and
        // counted: a peak within 1e-7 rad of the window's edge or with |sn| below 1e-7 of the
        // stress (the scan's angle is good to ~1e-8 rad, and sn varies by up to 2 q per rad),
        // with |s_eff - threshold| below 1e-9 of it, two maxima closer than the scan resolves
        // (1e-3 rad), or
        // a plateau, where rounding noise makes the scan see many peaks (pure shear with
        // beta = 1; maxima_of_special_stresses checks it).
        let mut draws = Draws::new(78, [0, 0, 0]);
        let (mut angles_compared, mut compared, mut skipped) = (0, 0, 0);
        for stress in stresses() {
            let scale = stress.iter().fold(0.0, |m: f64, s| m.max(s.abs()));
            for beta in [0.0, 0.5, 1.0, 2.0] {
                let (peaks, grid_max) = scan(stress, beta);
                let (th, global) = max_effective_traction(stress, beta);
                assert!((0.0..PI).contains(&th));
                let best = peaks.iter().map(|p| p.s_eff).fold(grid_max, f64::max);
                let tol = 1e-9 * best + 1e-12 * scale;
                assert!(
                    (global - best).abs() <= tol,
                    "{stress:?} beta {beta}: {global} vs {best}"
                );
                let at = effective_traction(stress, beta, th).0;
                assert!(
                    (at - global).abs() <= 1e-12 * scale,
                    "s_eff({th}) = {at} vs {global}"
                );
                let flat = [th - 1e-3, th + 1e-3]
                    .iter()
                    .all(|&t| effective_traction(stress, beta, t).0 >= global - tol);
                if !flat {
                    let nearest = peaks
                        .iter()
                        .filter(|p| p.s_eff >= best - tol)
                        .map(|p| plane_distance(p.th, th))
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        nearest <= 1e-4,
                        "{stress:?} beta {beta}: th {th}, nearest {nearest}"
                    );
                    angles_compared += 1;
                }

                let random_window = (
                    (3.0 * draws.next_uniform() - 1.0) * PI,
                    0.05 + 1.55 * draws.next_uniform(),
                );
                for window in [None, Some(random_window), Some((0.3, 0.2))] {
                    let inside = |th: f64| match window {
                        None => true,
                        Some((c, w)) => plane_distance(th, c) <= w,
                    };
                    let edge = |th: f64| match window {
                        None => false,
                        Some((c, w)) => (plane_distance(th, c) - w).abs() <= 1e-7,
                    };
                    for threshold in [-1.0, 0.0, 0.6 * global, 1.01 * global] {
                        let (angles, len) = tensile_maxima(stress, beta, window, threshold);
                        let doubtful = peaks.len() > 4
                            || peaks.iter().any(|p| {
                                p.sn.abs() <= 1e-7 * scale
                                    || (p.s_eff - threshold).abs() <= 1e-9 * scale
                                    || edge(p.th)
                            })
                            || (len == 2 && plane_distance(angles[0], angles[1]) < 1e-3);
                        if doubtful {
                            skipped += 1;
                            continue;
                        }
                        let expected: Vec<&Peak> = peaks
                            .iter()
                            .filter(|p| p.sn > 0.0 && p.s_eff > threshold && inside(p.th))
                            .collect();
                        let case = format!(
                            "{stress:?} beta {beta} window {window:?} threshold {threshold}"
                        );
                        assert_eq!(len, expected.len(), "{case}: {angles:?} vs {expected:?}");
                        for &th in &angles[..len] {
                            match window {
                                None => assert!((0.0..PI).contains(&th), "{case}: {th}"),
                                Some((c, w)) => assert!((th - c).abs() <= w, "{case}: {th}"),
                            }
                            let peak = expected
                                .iter()
                                .find(|p| plane_distance(p.th, th) <= 1e-4)
                                .unwrap_or_else(|| panic!("{case}: {th} vs {expected:?}"));
                            let value = effective_traction(stress, beta, th).0;
                            assert!((value - peak.s_eff).abs() <= 1e-9 * peak.s_eff, "{case}");
                        }
                        assert!(angles[len..].iter().all(|a| a.is_nan()));
                        compared += 1;
                    }
                }
            }
        }
        // Not vacuous: 809 of the 840 global angles are sharp, and only the degenerate special
        // stresses (84 cases) are skipped.
        assert!(angles_compared > 800, "{angles_compared} angles compared");
        assert!(skipped * 100 < compared, "{skipped} skipped of {compared}");
    }

    #[test]
    fn maxima_of_special_stresses() {
        let s = SIGMA_C;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * s.max(b.abs());
        // Equal biaxial tension: every plane alike; one maximum at 0 or at the window's centre.
        for beta in [0.0, 1.0, 2.0] {
            let (th, value) = max_effective_traction([s, s, 0.0], beta);
            assert!(th == 0.0 && close(value, s));
            assert_eq!(tensile_maxima([s, s, 0.0], beta, None, 0.0).1, 1);
            let (angles, len) = tensile_maxima([s, s, 0.0], beta, Some((1.0, 0.2)), 0.0);
            assert!(len == 1 && angles[0] == 1.0);
            assert_eq!(tensile_maxima([s, s, 0.0], beta, None, s).1, 0);
            // Equal biaxial compression: nothing anywhere.
            assert!(close(max_effective_traction([-s, -s, 0.0], beta).1, 0.0));
            assert_eq!(tensile_maxima([-s, -s, 0.0], beta, None, -1.0).1, 0);
        }
        // Pure shear, beta = 1: a plateau s_eff = s over normals within pi/4 of the tensile
        // principal direction pi/4; reported once, at its centre.
        let (th, value) = max_effective_traction([0.0, 0.0, s], 1.0);
        assert!(close(value, s) && plane_distance(th, 0.25 * PI) <= 0.25 * PI + 1e-12);
        let (angles, len) = tensile_maxima([0.0, 0.0, s], 1.0, None, 0.0);
        assert!(len == 1 && (angles[0] - 0.25 * PI).abs() <= 1e-15);
        // Pure shear, beta = 2: the largest s_eff = 2 s is pure shear on the x and y planes
        // (sn = 0), so no tensile maximum.
        let (th, value) = max_effective_traction([0.0, 0.0, s], 2.0);
        assert!(
            close(value, 2.0 * s)
                && plane_distance(th, 0.0).min(plane_distance(th, FRAC_PI_2)) <= 1e-12
        );
        assert_eq!(tensile_maxima([0.0, 0.0, s], 2.0, None, 0.0).1, 0);
        // Uniaxial compression: only shear maxima, s_eff = beta s / 2 at 45 degrees.
        let (th, value) = max_effective_traction([-s, 0.0, 0.0], 0.5);
        assert!(
            close(value, 0.25 * s)
                && (plane_distance(th, 0.25 * PI) <= 1e-12
                    || plane_distance(th, 0.75 * PI) <= 1e-12)
        );
        assert_eq!(tensile_maxima([-s, 0.0, 0.0], 0.5, None, -1.0).1, 0);
        // Uniaxial tension, beta = 2: p = q = s / 2, c* = 1/3, two planes at +-acos(1/3) / 2 with
        // s_eff^2 = (2 s / 3)^2 + 4 (s / 2)^2 (8 / 9) = 4 s^2 / 3.
        let (angles, len) = tensile_maxima([s, 0.0, 0.0], 2.0, None, 0.0);
        let half = 0.5 * (1.0f64 / 3.0).acos();
        assert!(
            len == 2
                && (angles[0] - half).abs() <= 1e-15
                && (angles[1] - (PI - half)).abs() <= 1e-15
        );
        assert!(close(
            max_effective_traction([s, 0.0, 0.0], 2.0).1,
            2.0 * s / 3f64.sqrt()
        ));
        // Uniaxial tension, beta = 0.5: one plane, normal along x. A window beside it reports
        // nothing (its edge is not a maximum); one reaching it reports the representative in it.
        assert_eq!(
            tensile_maxima([s, 0.0, 0.0], 0.5, Some((0.5, 0.3)), 0.0).1,
            0
        );
        let (angles, len) = tensile_maxima([s, 0.0, 0.0], 0.5, Some((0.5, 0.6)), 0.0);
        assert!(len == 1 && angles[0].abs() <= 1e-15);
        let (angles, len) = tensile_maxima([s, 0.0, 0.0], 0.5, Some((3.0, 0.2)), 0.0);
        assert!(len == 1 && (angles[0] - PI).abs() <= 1e-15);
    }

    #[test]
    fn crack_directions_lie_along_the_plane() {
        for normal in [0.0, 0.3, FRAC_PI_2, 2.0, 0.75 * PI, PI - 1e-17, -1.0] {
            let [d1, d2] = crack_directions(normal);
            for d in [d1, d2] {
                assert!(d > -PI && d <= PI);
                // Perpendicular to the normal.
                assert!((d - normal).cos().abs() <= 1e-15);
            }
            assert!(((d1 - d2).rem_euclid(TAU) - PI).abs() <= 1e-15);
        }
        // A tip travelling along +x (alpha = 0.1) under tension along y: the plane's normal is
        // pi/2, so the crack continues along 0, the direction with cos(d - alpha) > 0.
        let (angles, len) =
            tensile_maxima([0.0, SIGMA_C, 0.0], 1.0, Some((0.1 + FRAC_PI_2, 1.0)), 0.0);
        assert_eq!(len, 1);
        let forward: Vec<f64> = crack_directions(angles[0])
            .into_iter()
            .filter(|d| (d - 0.1).cos() > 0.0)
            .collect();
        assert!(forward.len() == 1 && forward[0].abs() <= 1e-15);
    }
}
