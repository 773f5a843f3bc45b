//! Statistics of a metric over the draws: mean, sample standard deviation and the Student-t 95%
//! interval of the mean.

use serde::Serialize;

/// A metric over a group of finished cases (`study.json`). Values are `None` (JSON `null`)
/// where they are undefined: no value (mean, min, max), fewer than two (std, ci95).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stats {
    /// Cases with a value.
    pub count: usize,
    /// Mean of the values.
    pub mean: Option<f64>,
    /// Sample standard deviation (divided by `count - 1`).
    pub std: Option<f64>,
    /// 95% interval of the mean: `mean -+ t std / sqrt(count)`, `t` the 0.975 quantile of
    /// Student's t with `count - 1` degrees of freedom ([`t_975`]).
    pub ci95: Option<[f64; 2]>,
    /// Least value.
    pub min: Option<f64>,
    /// Largest value.
    pub max: Option<f64>,
    /// `count` over the finished cases of the group: e.g. the fraction that forked.
    pub present: Option<f64>,
}

impl Stats {
    /// The statistics of one metric over finished cases: `values` holds each case's value,
    /// `None` where its summary has none.
    pub fn of(values: &[Option<f64>]) -> Self {
        let v: Vec<f64> = values.iter().flatten().copied().collect();
        let n = v.len();
        let mean = (n > 0).then(|| v.iter().sum::<f64>() / n as f64);
        let std = mean.filter(|_| n > 1).map(|m| {
            let squares: f64 = v.iter().map(|x| (x - m) * (x - m)).sum();
            (squares / (n - 1) as f64).sqrt()
        });
        let ci95 = mean.zip(std).map(|(m, s)| {
            let half = t_975(n - 1) * s / (n as f64).sqrt();
            [m - half, m + half]
        });
        Self {
            count: n,
            mean,
            std,
            ci95,
            min: v.iter().copied().reduce(f64::min),
            max: v.iter().copied().reduce(f64::max),
            present: (!values.is_empty()).then(|| n as f64 / values.len() as f64),
        }
    }
}

/// `t_{0.975, df}` for `df` from 1 to 30 (standard tables, six decimals).
const T_975: [f64; 30] = [
    12.706205, 4.302653, 3.182446, 2.776445, 2.570582, 2.446912, 2.364624, 2.306004, 2.262157,
    2.228139, 2.200985, 2.178813, 2.160369, 2.144787, 2.131450, 2.119905, 2.109816, 2.100922,
    2.093024, 2.085963, 2.079614, 2.073873, 2.068658, 2.063899, 2.059539, 2.055529, 2.051831,
    2.048407, 2.045230, 2.042272,
];

/// The 0.975 quantile of Student's t with `df >= 1` degrees of freedom: a table to 30, above
/// that the Cornish-Fisher expansion in `1/df` about the normal quantile (to `df^-3`; below
/// 1e-5 off from 31 on).
pub fn t_975(df: usize) -> f64 {
    assert!(df >= 1, "Student's t needs one degree of freedom");
    if let Some(&t) = T_975.get(df - 1) {
        return t;
    }
    let z: f64 = 1.959_963_984_540_054;
    let n = df as f64;
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * n)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * n * n)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * n.powi(3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles_match_the_tables() {
        // n samples: n - 1 degrees of freedom.
        for (n, t) in [(2, 12.706), (5, 2.776), (8, 2.365), (30, 2.045)] {
            assert!((t_975(n - 1) - t).abs() < 5e-4, "n = {n}: {}", t_975(n - 1));
        }
        // The expansion above the table (values from integrating the density).
        for (df, t) in [
            (31, 2.039513),
            (40, 2.021075),
            (60, 2.000298),
            (120, 1.979930),
        ] {
            assert!((t_975(df) - t).abs() < 2e-6, "df = {df}: {}", t_975(df));
        }
        assert!(t_975(100_000) > 1.95996 && t_975(100_000) < 1.96);
    }

    #[test]
    fn statistics_of_a_small_sample() {
        // 1, 2, 4 and a case without the metric: mean 7/3, variance ((4/3)^2 + (1/3)^2 +
        // (5/3)^2) / 2 = 7/3, interval 4.302653 sqrt(7/3) / sqrt(3).
        let s = Stats::of(&[Some(1.0), Some(2.0), None, Some(4.0)]);
        assert_eq!(s.count, 3);
        assert!((s.mean.unwrap() - 7.0 / 3.0).abs() < 1e-15);
        let std = (7.0f64 / 3.0).sqrt();
        assert!((s.std.unwrap() - std).abs() < 1e-15);
        let half = 4.302653 * std / 3f64.sqrt();
        let [lo, hi] = s.ci95.unwrap();
        assert!((lo - (7.0 / 3.0 - half)).abs() < 1e-12 && (hi - (7.0 / 3.0 + half)).abs() < 1e-12);
        // By hand: 2 x 4.302653 x 0.8819171 = 7.589168.
        assert!((hi - lo - 7.589168).abs() < 1e-5, "{}", hi - lo);
        assert_eq!(
            (s.min, s.max, s.present),
            (Some(1.0), Some(4.0), Some(0.75))
        );
        // Two values 1 and 3: std sqrt(2), half width 12.706205 sqrt(2) / sqrt(2).
        let s = Stats::of(&[Some(1.0), Some(3.0)]);
        assert_eq!(s.ci95, Some([2.0 - 12.706205, 2.0 + 12.706205]));
        // One value: no spread; none: nothing but the count.
        let s = Stats::of(&[Some(5.0), None]);
        assert_eq!(
            (s.mean, s.std, s.ci95, s.present),
            (Some(5.0), None, None, Some(0.5))
        );
        let s = Stats::of(&[]);
        assert_eq!((s.count, s.mean, s.present), (0, None, None));
    }
}
