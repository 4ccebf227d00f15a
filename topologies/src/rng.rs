//! Seeded, portable random numbers shared by the generators of the project.
//!
//! ChaCha8 is specified to give the same stream on every platform and release, so a seed
//! printed in a report reproduces the same costs and graphs later.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

/// A reproducible random stream.
#[derive(Debug, Clone)]
pub struct SeededRng(ChaCha8Rng);

impl SeededRng {
    /// A stream determined by `seed` alone.
    pub fn new(seed: u64) -> Self {
        Self(ChaCha8Rng::seed_from_u64(seed))
    }

    /// A stream for a purpose (`stream`) derived from a base seed, independent of the other
    /// purposes drawn from the same seed.
    pub fn for_stream(seed: u64, stream: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Self(rng)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in `0..bound` (`bound > 0`), without modulo bias worth mentioning
    /// (bound ≪ 2^64).
    pub fn below(&mut self, bound: usize) -> usize {
        ((self.0.next_u64() as u128 * bound as u128) >> 64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproducible_and_in_range() {
        let a: Vec<f64> = (0..5)
            .map({
                let mut r = SeededRng::new(3);
                move |_| r.uniform()
            })
            .collect();
        let mut r = SeededRng::new(3);
        for x in &a {
            assert_eq!(*x, r.uniform());
            assert!((0.0..1.0).contains(x));
        }
        let mut other = SeededRng::for_stream(3, 1);
        assert_ne!(a[0], other.uniform());
        assert!((0..100).all(|_| r.below(7) < 7));
    }
}
