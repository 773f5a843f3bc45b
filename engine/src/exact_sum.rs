//! Exact sums of `f64` values: the same result, the correctly rounded sum, in any order and
//! however the values are split among partial sums (Shewchuk's non-overlapping expansions, as
//! Python's `math.fsum`).

/// A sum kept exactly as non-overlapping partials in increasing magnitude. Finite values only.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ExactSum {
    partials: Vec<f64>,
}

impl ExactSum {
    /// Adds `x` exactly.
    pub(crate) fn add(&mut self, mut x: f64) {
        let mut i = 0;
        for j in 0..self.partials.len() {
            let mut y = self.partials[j];
            if x.abs() < y.abs() {
                std::mem::swap(&mut x, &mut y);
            }
            let hi = x + y;
            let lo = y - (hi - x);
            if lo != 0.0 {
                self.partials[i] = lo;
                i += 1;
            }
            x = hi;
        }
        self.partials.truncate(i);
        self.partials.push(x);
    }

    /// Adds the sum `other` exactly.
    pub(crate) fn merge(&mut self, other: &ExactSum) {
        for &x in &other.partials {
            self.add(x);
        }
    }

    /// The partials, for sending the sum elsewhere ([`Self::from_partials`]).
    pub(crate) fn partials(&self) -> &[f64] {
        &self.partials
    }

    /// The sum whose partials are `partials` (from [`Self::partials`]).
    pub(crate) fn from_partials(partials: &[f64]) -> Self {
        let mut sum = Self::default();
        for &x in partials {
            sum.add(x);
        }
        sum
    }

    /// The exact sum rounded to the nearest `f64` (ties to even).
    pub(crate) fn value(&self) -> f64 {
        let p = &self.partials;
        let Some(mut n) = p.len().checked_sub(1) else {
            return 0.0;
        };
        let mut hi = p[n];
        let mut lo = 0.0;
        while n > 0 {
            let x = hi;
            n -= 1;
            let y = p[n];
            hi = x + y;
            lo = y - (hi - x);
            if lo != 0.0 {
                break;
            }
        }
        // Half-way cases: round by the sign of the rest.
        if n > 0 && ((lo < 0.0 && p[n - 1] < 0.0) || (lo > 0.0 && p[n - 1] > 0.0)) {
            let y = lo * 2.0;
            let x = hi + y;
            if y == x - hi {
                hi = x;
            }
        }
        hi
    }
}

#[cfg(test)]
mod tests {
    use super::ExactSum;

    /// Values whose naive sums differ by order: 1e16, 1, -1e16 and many small ones.
    fn values() -> Vec<f64> {
        let mut v = vec![1e16, 1.0, -1e16, 3.0, 0.1, 0.2, 0.3, -0.6, 1e-20];
        v.extend((1..200).map(|k| 1.0 / f64::from(k)));
        v
    }

    #[test]
    fn the_sum_is_the_same_in_any_order_and_split() {
        let v = values();
        let whole = {
            let mut s = ExactSum::default();
            v.iter().for_each(|&x| s.add(x));
            s.value()
        };
        let mut reversed = ExactSum::default();
        v.iter().rev().for_each(|&x| reversed.add(x));
        assert_eq!(reversed.value().to_bits(), whole.to_bits());
        for parts in [2, 3, 7] {
            let mut merged = ExactSum::default();
            for chunk in v.chunks(v.len().div_ceil(parts)) {
                let mut s = ExactSum::default();
                chunk.iter().rev().for_each(|&x| s.add(x));
                merged.merge(&ExactSum::from_partials(s.partials()));
            }
            assert_eq!(merged.value().to_bits(), whole.to_bits(), "{parts} parts");
        }
    }

    #[test]
    fn the_sum_is_rounded_correctly() {
        let mut s = ExactSum::default();
        for x in [1e16, 1.0, -1e16] {
            s.add(x);
        }
        assert_eq!(s.value(), 1.0, "a naive sum gives 0");
        let mut t = ExactSum::default();
        for x in [0.1, 0.2, 0.3] {
            t.add(x);
        }
        assert_eq!(
            t.value(),
            0.6,
            "fsum([0.1, 0.2, 0.3]); a naive sum gives 0.6000000000000001"
        );
        assert_eq!(ExactSum::default().value(), 0.0);
    }
}
