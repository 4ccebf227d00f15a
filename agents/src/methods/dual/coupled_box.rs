//! The dual methods' x-updates as one-dimensional root problems.
//!
//! Every entry of a robot's column responds to one scalar `τ` (the multiplier of the
//! constraint that couples the entries) by a nonincreasing function described by
//! `response(t) = (jump, offset)`: `x_t(τ) = 1` for `τ < jump`, `clip(offset − τ, 0, 1)` for
//! `τ > jump`, anything between at `τ = jump` (no jump: `jump = −∞`; an entry fixed at 0:
//! `offset = −∞` too). Two couplings occur:
//!
//! * [`solve_coupled_box`]: `τ = base + Σ_t x_t(τ)` — Algorithm 2's x-update (15), whose
//!   robot row is a consensus row like the others;
//! * [`solve_simplex_box`]: `Σ_t x_t(τ) = 1` — the x-update with the robot's "one task" row
//!   as its own constraint (the fast variant), and the Euclidean projection onto the allowed
//!   simplex (`response(t) = (−∞, z_t)`).
//!
//! In both the residual `G(τ) = s τ − base − Σ_t x_t(τ)` (`s` = 1 or 0) is nondecreasing and
//! piecewise linear between at most `3m` sorted breakpoints: a sort and a binary search find
//! the exact root, and a root inside jumps fills them evenly. `scratch` must hold
//! `3 · tasks + 2` values; it is never grown by a caller that reserved that much.

/// Solves `τ = base + Σ_t x_t(τ)` and writes the `x_t` (see the module docs).
pub fn solve_coupled_box(
    base: f64,
    tasks: usize,
    response: impl Fn(usize) -> (f64, f64),
    scratch: &mut Vec<f64>,
    x: &mut [f64],
) {
    let root = Root {
        slope: 1.0,
        base,
        lo: base,
        hi: base + tasks as f64,
    };
    root.solve(tasks, response, scratch, x);
}

/// Solves `Σ_t x_t(τ) = 1` and writes the `x_t` (see the module docs). At least one entry
/// must be free to reach 1 (`offset > −∞`).
pub fn solve_simplex_box(
    tasks: usize,
    response: impl Fn(usize) -> (f64, f64),
    scratch: &mut Vec<f64>,
    x: &mut [f64],
) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut jumps = false;
    for t in 0..tasks {
        let (jump, offset) = response(t);
        if offset > f64::NEG_INFINITY {
            lo = lo.min(offset - 1.0);
            hi = hi.max(offset).max(jump);
            jumps |= jump > f64::NEG_INFINITY;
        }
    }
    assert!(lo.is_finite(), "the simplex needs an entry that can be 1");
    if !jumps {
        return project_onto_simplex(tasks, |t| response(t).1, scratch, x);
    }
    // Below `lo` some entry is 1 (G ≤ 0); above `hi` every entry is 0 (G = 1 > 0).
    let root = Root {
        slope: 0.0,
        base: -1.0,
        lo: lo - 1.0,
        hi: hi + 1.0,
    };
    root.solve(tasks, response, scratch, x);
}

/// `Σ_t x_t(τ) = 1` without jumps, `x_t = max(offset_t − τ, 0)` (`offset_t = −∞`: fixed at
/// 0): the Euclidean projection of the offsets onto the simplex, by Michelot's method: `τ`
/// is the mean excess over 1 of the entries above the last `τ`, until they stay the same
/// (`τ` only grows, the entries above it only drop out, and the largest never does). One
/// pass of `O(m)` for the largest offset and one for the entries above it less 1, then a
/// few over the entries left, instead of a sort of the breakpoints.
fn project_onto_simplex(
    tasks: usize,
    offset: impl Fn(usize) -> f64,
    scratch: &mut Vec<f64>,
    x: &mut [f64],
) {
    scratch.clear();
    scratch.extend((0..tasks).map(offset));
    // The entries above τ set the next τ; when they are the same as last time, τ is the root.
    // Every pass but the last drops an entry (a bound against rounding all the same). The
    // entries above τ are kept, in order, in the second half of the scratch: each pass reads
    // only those of the last (the same sums as over all entries, in the same order).
    scratch.extend_from_within(..tasks);
    let (offsets, above_tau) = scratch.split_at_mut(tasks);
    // τ starts at the largest offset less 1, below the root (the largest entry is at most
    // 1): the first pass keeps only the few entries above it (Condat's start).
    let top = largest(offsets);
    let (mut tau, mut above, mut live) = (top - 1.0, usize::MAX, tasks);
    for _ in 0..=tasks {
        let (mut sum, mut count) = (0.0, 0usize);
        for k in 0..live {
            let o = above_tau[k];
            if o > tau {
                above_tau[count] = o;
                sum += o;
                count += 1;
            }
        }
        live = count;
        if count == 0 {
            // Offsets so large that `top − 1` rounds to `top`: nothing is above τ. As far as
            // an f64 can tell, the projection is the largest entry alone.
            x.fill(0.0);
            if let Some(first) = offsets.iter().position(|&o| o == top) {
                x[first] = 1.0;
            }
            return;
        }
        if count == above {
            break;
        }
        above = count;
        tau = (sum - 1.0) / count as f64;
    }
    for (slot, &o) in x.iter_mut().zip(offsets.iter()) {
        *slot = (o - tau).clamp(0.0, 1.0);
    }
}

/// The largest of `values`, by four running maxima (they do not wait on each other).
fn largest(values: &[f64]) -> f64 {
    let mut top = [f64::NEG_INFINITY; 4];
    let chunks = values.chunks_exact(4);
    for &v in chunks.remainder() {
        top[0] = top[0].max(v);
    }
    for chunk in chunks {
        for (top, &v) in top.iter_mut().zip(chunk) {
            *top = top.max(v);
        }
    }
    top.into_iter().fold(f64::NEG_INFINITY, f64::max)
}

/// `G(τ) = slope · τ − base − Σ_t x_t(τ)` on `[lo, hi]`, with `G(lo) ≤ 0`.
struct Root {
    slope: f64,
    base: f64,
    lo: f64,
    hi: f64,
}

impl Root {
    fn solve(
        &self,
        tasks: usize,
        response: impl Fn(usize) -> (f64, f64),
        scratch: &mut Vec<f64>,
        x: &mut [f64],
    ) {
        let value = |t: usize, tau: f64, right: bool| {
            let (jump, offset) = response(t);
            if tau < jump || (!right && tau == jump) {
                1.0
            } else {
                (offset - tau).clamp(0.0, 1.0)
            }
        };
        // G at τ with the left (right) limit at jumps.
        let g = |tau: f64, right: bool| {
            self.slope * tau - self.base - (0..tasks).map(|t| value(t, tau, right)).sum::<f64>()
        };
        scratch.clear();
        scratch.push(self.lo);
        scratch.push(self.hi);
        for t in 0..tasks {
            let (jump, offset) = response(t);
            for b in [jump, offset - 1.0, offset] {
                if b > self.lo && b < self.hi {
                    scratch.push(b);
                }
            }
        }
        scratch.sort_unstable_by(f64::total_cmp);
        // Largest breakpoint with G(b⁻) ≤ 0.
        let (mut a, mut b) = (0usize, scratch.len() - 1);
        if g(scratch[b], false) <= 0.0 {
            a = b;
        } else {
            while b - a > 1 {
                let mid = (a + b) / 2;
                if g(scratch[mid], false) <= 0.0 {
                    a = mid;
                } else {
                    b = mid;
                }
            }
        }
        let left = scratch[a];
        let right_value = g(left, true);
        if right_value >= 0.0 || a + 1 == scratch.len() {
            // The root is at `left`, inside the jumps there: fill them evenly.
            let mut fixed = 0.0;
            let (mut floor, mut room) = (0.0, 0.0);
            for (t, slot) in x.iter_mut().enumerate().take(tasks) {
                let (jump, offset) = response(t);
                if jump == left {
                    let low = (offset - left).clamp(0.0, 1.0);
                    floor += low;
                    room += 1.0 - low;
                    *slot = low;
                } else {
                    *slot = value(t, left, true);
                    fixed += *slot;
                }
            }
            let share = if room > 0.0 {
                ((self.slope * left - self.base - fixed - floor) / room).clamp(0.0, 1.0)
            } else {
                0.0
            };
            for (t, slot) in x.iter_mut().enumerate().take(tasks) {
                if response(t).0 == left {
                    *slot += share * (1.0 - *slot);
                }
            }
            return;
        }
        // Linear between `left` and the next breakpoint: slope `s` + number of free entries
        // (positive there: G rises from below 0 to above it).
        let mid = 0.5 * (left + scratch[a + 1]);
        let free = (0..tasks)
            .filter(|&t| {
                let (jump, offset) = response(t);
                mid > jump && offset - mid > 0.0 && offset - mid < 1.0
            })
            .count();
        let tau = left - right_value / (self.slope + free as f64).max(f64::MIN_POSITIVE);
        for (t, slot) in x.iter_mut().enumerate().take(tasks) {
            *slot = value(t, tau, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admm_ta_topologies::rng::SeededRng;

    /// Random responses, with jumps in every other trial and entries fixed at 0 in some.
    fn responses(rng: &mut SeededRng, trial: usize) -> Vec<(f64, f64)> {
        let tasks = 1 + trial % 9;
        let with_jumps = trial % 2 == 1;
        (0..tasks)
            .map(|t| {
                if t > 0 && trial % 5 == 2 && rng.uniform() < 0.4 {
                    return (f64::NEG_INFINITY, f64::NEG_INFINITY);
                }
                let jump = if with_jumps {
                    4.0 * rng.uniform() - 2.0
                } else {
                    f64::NEG_INFINITY
                };
                (jump, 6.0 * rng.uniform() - 3.0)
            })
            .collect()
    }

    /// Each entry is its response at `tau` (or inside its jump there).
    fn assert_responds(x: &[f64], responses: &[(f64, f64)], tau: f64, trial: usize) {
        for (t, &(jump, offset)) in responses.iter().enumerate() {
            assert!((0.0..=1.0).contains(&x[t]), "trial {trial}: x = {x:?}");
            let expected = if tau < jump - 1e-12 {
                (1.0, 1.0)
            } else if tau > jump + 1e-12 {
                let v = (offset - tau).clamp(0.0, 1.0);
                (v, v)
            } else {
                ((offset - tau).clamp(0.0, 1.0), 1.0)
            };
            assert!(
                x[t] >= expected.0 - 1e-9 && x[t] <= expected.1 + 1e-9,
                "trial {trial}, entry {t}: {} not in {expected:?} at τ = {tau}",
                x[t]
            );
        }
    }

    /// The root of the coupled box problem satisfies its equation, and each entry is the
    /// response at the root (or inside its jump there).
    #[test]
    fn coupled_box_root_is_exact() {
        let mut rng = SeededRng::new(11);
        let mut scratch = Vec::with_capacity(64);
        for trial in 0..2000 {
            let responses = responses(&mut rng, trial);
            let tasks = responses.len();
            // Some trials put the root exactly on a jump.
            let base = if responses[0].0.is_finite() && trial % 4 == 1 {
                responses[0].0 - 0.5
            } else {
                4.0 * rng.uniform() - 3.0
            };
            let mut x = vec![f64::NAN; tasks];
            solve_coupled_box(base, tasks, |t| responses[t], &mut scratch, &mut x);
            let tau = base + x.iter().sum::<f64>();
            assert_responds(&x, &responses, tau, trial);
            assert!(scratch.capacity() >= 3 * tasks + 2);
        }
    }

    /// The simplex root sums to one, and each entry is its response at one common `τ`.
    #[test]
    fn simplex_root_is_exact() {
        let mut rng = SeededRng::new(12);
        let mut scratch = Vec::with_capacity(64);
        for trial in 0..2000 {
            let responses = responses(&mut rng, trial);
            let tasks = responses.len();
            let mut x = vec![f64::NAN; tasks];
            solve_simplex_box(tasks, |t| responses[t], &mut scratch, &mut x);
            assert!(
                (x.iter().sum::<f64>() - 1.0).abs() < 1e-9,
                "trial {trial}: {x:?}"
            );
            // Recover τ from a free entry, or check the extremes against every τ between.
            let tau = responses
                .iter()
                .zip(&x)
                .find(|((j, o), v)| **v > 1e-12 && **v < 1.0 - 1e-12 && *o - **v > *j)
                .map(|((_, o), v)| o - v);
            match tau {
                Some(tau) => assert_responds(&x, &responses, tau, trial),
                None => {
                    // Every entry is 0 or 1 (or inside a jump): one entry carries the 1, or
                    // a jump shares it; forbidden entries stay 0.
                    for (t, &(_, offset)) in responses.iter().enumerate() {
                        if offset == f64::NEG_INFINITY {
                            assert_eq!(x[t], 0.0, "trial {trial}");
                        }
                    }
                }
            }
        }
    }

    /// The projection onto the simplex, against a direct sort-based projection.
    #[test]
    fn simplex_projection_matches_the_sort_rule() {
        let mut rng = SeededRng::new(13);
        let mut scratch = Vec::with_capacity(64);
        for trial in 0..500 {
            let tasks = 1 + trial % 12;
            let z: Vec<f64> = (0..tasks).map(|_| 3.0 * rng.uniform() - 1.5).collect();
            let mut x = vec![0.0; tasks];
            solve_simplex_box(tasks, |t| (f64::NEG_INFINITY, z[t]), &mut scratch, &mut x);
            // Held–Wolfe–Crowder: the threshold from the sorted values (the box's upper
            // bound never binds on the simplex).
            let mut sorted = z.clone();
            sorted.sort_by(|a, b| b.total_cmp(a));
            let mut cumulative = 0.0;
            let mut theta = 0.0;
            for (k, v) in sorted.iter().enumerate() {
                cumulative += v;
                let candidate = (cumulative - 1.0) / (k + 1) as f64;
                if v - candidate > 0.0 {
                    theta = candidate;
                }
            }
            for t in 0..tasks {
                let expected = (z[t] - theta).max(0.0);
                assert!(
                    (x[t] - expected).abs() < 1e-9,
                    "trial {trial}: {x:?} vs θ {theta}"
                );
            }
        }
        // Offsets beyond an f64's unit (a neighbour's finite but huge multipliers): the
        // largest entry alone, never a NaN beside a disallowed task.
        let z = [1e17, 0.0, f64::NEG_INFINITY, 5.0];
        let mut x = vec![0.5; 4];
        solve_simplex_box(4, |t| (f64::NEG_INFINITY, z[t]), &mut scratch, &mut x);
        assert_eq!(x, [1.0, 0.0, 0.0, 0.0]);
    }
}
