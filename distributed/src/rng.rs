//! A small seeded pseudo-random generator (SplitMix64) for random partitions, delays and
//! candidate orders: reproducible from its seed, no global state.

/// SplitMix64: 64 bits of state, one multiply-xorshift chain per draw.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator started from `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (`n > 0`), nearly uniform (bias below `n / 2^64`).
    pub fn below(&mut self, n: usize) -> usize {
        assert!(n > 0, "a range to draw from");
        ((u128::from(self.next_u64()) * n as u128) >> 64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_reproducible_and_covers_its_range() {
        let draws = |seed| {
            let mut r = SplitMix64::new(seed);
            (0..1000).map(|_| r.below(7)).collect::<Vec<_>>()
        };
        assert_eq!(draws(3), draws(3));
        assert_ne!(draws(3), draws(4));
        let counts = draws(5).iter().fold([0; 7], |mut c, &d| {
            c[d] += 1;
            c
        });
        assert!(
            counts.iter().all(|&c| (100..190).contains(&c)),
            "{counts:?}"
        );
    }
}
