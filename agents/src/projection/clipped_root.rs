/// Solves `Σ_k clip(values[k] − s, 0, 1) = target` for `s`, exactly (up to rounding).
///
/// The left side is a non-increasing piecewise-linear function of `s` with breakpoints at
/// `values[k] − 1` and `values[k]`; the root is found by bisection over the sorted
/// breakpoints and linear interpolation on the bracketing segment. Needs
/// `1 ≤ target ≤ values.len()`-ish (`target ∈ (0, len]`). `breakpoints` is scratch with
/// capacity `2 · values.len()` (no allocation then). `O(len · log len)`.
pub fn clipped_sum_root(values: &[f64], target: f64, breakpoints: &mut Vec<f64>) -> f64 {
    breakpoints.clear();
    for &a in values {
        breakpoints.push(a - 1.0);
        breakpoints.push(a);
    }
    breakpoints.sort_unstable_by(f64::total_cmp);
    let clipped_sum = |s: f64| values.iter().map(|&a| (a - s).clamp(0.0, 1.0)).sum::<f64>();
    // At the smallest breakpoint every term is 1; at the largest every term is 0.
    let (mut lo, mut hi) = (0, breakpoints.len() - 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if clipped_sum(breakpoints[mid]) >= target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (s_lo, s_hi) = (breakpoints[lo], breakpoints[hi]);
    let (f_lo, f_hi) = (clipped_sum(s_lo), clipped_sum(s_hi));
    if f_lo <= f_hi || f_lo <= target {
        return s_lo;
    }
    s_lo + (f_lo - target) * (s_hi - s_lo) / (f_lo - f_hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_on_hand_cases() {
        let mut scratch = Vec::with_capacity(8);
        // One value: clip(a - s) = 1 at s = a - 1.
        assert_eq!(clipped_sum_root(&[0.3], 1.0, &mut scratch), -0.7);
        // Simplex projection of (0.5, 0.5): s = 0.
        assert!(clipped_sum_root(&[0.5, 0.5], 1.0, &mut scratch).abs() < 1e-15);
        // (2, 0): s = 1 gives (1, 0).
        assert!((clipped_sum_root(&[2.0, 0.0], 1.0, &mut scratch) - 1.0).abs() < 1e-15);
        // (0.9, 0.8, 0.1): s = 0.35 gives 0.55 + 0.45 + 0 = 1.
        let s = clipped_sum_root(&[0.9, 0.8, 0.1], 1.0, &mut scratch);
        assert!((s - 0.35).abs() < 1e-15, "{s}");
    }

    #[test]
    fn residual_is_tiny_on_random_values() {
        let mut rng = admm_ta_topologies::rng::SeededRng::new(1);
        let mut scratch = Vec::with_capacity(100);
        for len in 1..50 {
            let values: Vec<f64> = (0..len).map(|_| rng.uniform() * 6.0 - 3.0).collect();
            let s = clipped_sum_root(&values, 1.0, &mut scratch);
            let sum: f64 = values.iter().map(|a| (a - s).clamp(0.0, 1.0)).sum();
            assert!((sum - 1.0).abs() < 1e-12, "len {len}: {sum}");
        }
    }
}
