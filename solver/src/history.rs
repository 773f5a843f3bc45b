//! Time histories of boundary data: dimensionless multipliers of a prescribed amplitude.

/// A multiplier `h(t)` for `t >= 0` (seconds).
#[derive(Clone, Debug, PartialEq)]
pub enum History {
    /// `h = 1`.
    Constant,
    /// Linear ramp from 0 to 1 over `ramp` seconds, then 1.
    Linear {
        /// Ramp time, s.
        ramp: f64,
    },
    /// The seed's C1 cubic ramp `3 r^2 - 2 r^3`, `r = t / ramp` (seed 2.71, 4.14), then 1.
    Smooth {
        /// Ramp time, s.
        ramp: f64,
    },
    /// Piecewise linear through `(t, h)` points with increasing `t`; constant outside.
    Table(Vec<(f64, f64)>),
    /// Through `(t, h)` points like `Table`, but each piece is the C1 cubic
    /// `h0 + (h1 - h0) (3 r^2 - 2 r^3)`: levels joined by smooth ramps (seed 3.4.1's loads).
    SmoothTable(Vec<(f64, f64)>),
}

impl History {
    /// The multiplier at time `t` (s).
    pub fn value(&self, t: f64) -> f64 {
        match self {
            Self::Constant => 1.0,
            Self::Linear { ramp } => (t / ramp).clamp(0.0, 1.0),
            Self::Smooth { ramp } => {
                let r = (t / ramp).clamp(0.0, 1.0);
                r * r * (3.0 - 2.0 * r)
            }
            Self::Table(points) => interpolate(points, t, |r| r),
            Self::SmoothTable(points) => interpolate(points, t, |r| r * r * (3.0 - 2.0 * r)),
        }
    }

    /// Checks parameters: positive ramps, at least one table point, strictly increasing times.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Self::Constant => Ok(()),
            Self::Linear { ramp } | Self::Smooth { ramp } if !(*ramp > 0.0 && ramp.is_finite()) => {
                Err(format!("ramp must be a positive time in s, got {ramp}"))
            }
            Self::Linear { .. } | Self::Smooth { .. } => Ok(()),
            Self::Table(points) | Self::SmoothTable(points) if points.is_empty() => {
                Err("the table has no points".into())
            }
            Self::Table(points) | Self::SmoothTable(points) => {
                if points.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
                    return Err("table values must be finite".into());
                }
                if points.windows(2).any(|w| w[1].0 <= w[0].0) {
                    return Err("table times must increase strictly".into());
                }
                Ok(())
            }
        }
    }
}

/// The value at `t` through `points`, shaped by `shape(r)` for `r` in [0, 1] between two points;
/// constant outside.
fn interpolate(points: &[(f64, f64)], t: f64, shape: impl Fn(f64) -> f64) -> f64 {
    let i = points.partition_point(|&(ti, _)| ti <= t);
    match (i, points.get(i)) {
        (0, _) => points.first().map_or(0.0, |p| p.1),
        (_, None) => points[i - 1].1,
        (_, Some(&(t1, h1))) => {
            let (t0, h0) = points[i - 1];
            h0 + (h1 - h0) * shape((t - t0) / (t1 - t0))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramps_and_tables() {
        assert_eq!(History::Constant.value(5.0), 1.0);
        assert_eq!(History::Linear { ramp: 2.0 }.value(1.0), 0.5);
        assert_eq!(History::Linear { ramp: 2.0 }.value(3.0), 1.0);
        let s = History::Smooth { ramp: 2.0 };
        assert_eq!(
            (s.value(0.0), s.value(1.0), s.value(2.0), s.value(9.0)),
            (0.0, 0.5, 1.0, 1.0)
        );
        let t = History::Table(vec![(0.0, 0.0), (1.0, 2.0), (3.0, -2.0)]);
        assert_eq!(
            (t.value(-1.0), t.value(0.5), t.value(2.0), t.value(4.0)),
            (0.0, 1.0, 0.0, -2.0)
        );
        assert!(
            History::Table(vec![(1.0, 0.0), (1.0, 1.0)])
                .validate()
                .is_err()
        );
        assert!(History::Smooth { ramp: 0.0 }.validate().is_err());
        let square = History::SmoothTable(vec![(0.0, 0.0), (1.0, -1.0), (3.0, -1.0), (4.0, 1.0)]);
        assert_eq!(
            (square.value(0.5), square.value(2.0), square.value(3.5)),
            (-0.5, -1.0, 0.0)
        );
        // C1: the slope vanishes at the points.
        let slope = (square.value(1.0 + 1e-6) - square.value(1.0 - 1e-6)) / 2e-6;
        assert!(slope.abs() < 1e-5);
    }
}
