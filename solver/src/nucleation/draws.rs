//! Counter-based uniform draws keyed by the run seed and stable ids, so that every random
//! decision is independent of threads and execution order.

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nucleation::testing::{ks_critical, ks_statistic};

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
}
