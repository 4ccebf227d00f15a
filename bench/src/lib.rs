//! Benchmarks and experiment helpers for admm-ta.
//!
//! `cargo bench -p admm-ta-bench` runs the criterion micro-benchmarks in `benches/`
//! (see `bench/README.md`). This library holds the inputs they share and the experiments
//! `admm-ta experiment NAME` reproduces ([`table1`], [`compare`]).

pub mod compare;
pub mod experiment;
pub mod figures;
pub mod plot;
pub mod rounds;
pub mod rounds_anatomy;
pub mod size_sweep;
pub mod surveillance;
pub mod table1;

use admm_ta_topologies::rng::SeededRng;
use faer::Mat;

/// Inputs of the projection benchmark: `m × n` matrices like the ones ADMM projects.
pub mod inputs {
    use super::*;

    /// Uniform entries in `[-1, 2)`: a cold, far-from-feasible input.
    pub fn uniform(m: usize, n: usize, seed: u64) -> Mat<f64> {
        let mut rng = SeededRng::new(seed);
        Mat::from_fn(m, n, |_, _| 3.0 * rng.uniform() - 1.0)
    }

    /// A permutation-like matrix plus noise: the near-vertex inputs of a converging run,
    /// where most entries clip to 0 or 1.
    pub fn near_vertex(m: usize, n: usize, seed: u64) -> Mat<f64> {
        let mut rng = SeededRng::new(seed);
        Mat::from_fn(m, n, |r, c| {
            let base = if r == c % m { 1.0 } else { 0.0 };
            base + 0.4 * (rng.uniform() - 0.5)
        })
    }
}
