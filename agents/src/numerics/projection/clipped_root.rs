/// Solves `Σ_k clip(values[k] − s, 0, 1) = 1` for `s`: the threshold of the Euclidean
/// projection of `values` onto the unit simplex.
///
/// With a target of exactly 1 the upper clip never binds at the root (non-negative terms
/// summing to 1 are each at most 1), so the threshold is the simplex one and Michelot's
/// algorithm finds it exactly without sorting: start from the mean shift, drop the values
/// at or below the threshold, recompute, until nothing is dropped. The threshold only
/// grows and the largest value is never dropped, so it ends after at most `len` passes and
/// in practice a handful, each `O(len)`. `scratch` needs capacity `values.len()` (then no
/// allocation). `values` must not be empty.
pub fn clipped_sum_root(values: &[f64], scratch: &mut Vec<f64>) -> f64 {
    scratch.clear();
    scratch.extend_from_slice(values);
    let mut threshold = (scratch.iter().sum::<f64>() - 1.0) / scratch.len() as f64;
    loop {
        let before = scratch.len();
        scratch.retain(|&a| a > threshold);
        let next = (scratch.iter().sum::<f64>() - 1.0) / scratch.len() as f64;
        if scratch.len() == before {
            return next;
        }
        threshold = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clipped_sum(values: &[f64], s: f64) -> f64 {
        values.iter().map(|a| (a - s).clamp(0.0, 1.0)).sum()
    }

    #[test]
    fn exact_on_hand_cases() {
        let mut scratch = Vec::with_capacity(8);
        // One value: clip(a - s) = 1 at s = a - 1.
        assert!((clipped_sum_root(&[0.3], &mut scratch) + 0.7).abs() < 1e-15);
        // Simplex projection of (0.5, 0.5): s = 0.
        assert!(clipped_sum_root(&[0.5, 0.5], &mut scratch).abs() < 1e-15);
        // (2, 0): s = 1 gives (1, 0).
        assert!((clipped_sum_root(&[2.0, 0.0], &mut scratch) - 1.0).abs() < 1e-15);
        // (0.9, 0.8, 0.1): s = 0.35 gives 0.55 + 0.45 + 0 = 1.
        let s = clipped_sum_root(&[0.9, 0.8, 0.1], &mut scratch);
        assert!((s - 0.35).abs() < 1e-15, "{s}");
    }

    #[test]
    fn residual_is_tiny_on_random_values() {
        let mut rng = admm_ta_topologies::rng::SeededRng::new(1);
        let mut scratch = Vec::with_capacity(100);
        for len in 1..100 {
            for spread in [0.1, 1.0, 6.0, 100.0] {
                let values: Vec<f64> = (0..len).map(|_| spread * (rng.uniform() - 0.5)).collect();
                let s = clipped_sum_root(&values, &mut scratch);
                let sum = clipped_sum(&values, s);
                assert!((sum - 1.0).abs() < 1e-12, "len {len}: {sum}");
            }
        }
    }
}
