//! Private costs: a team in which every robot holds only its own cost row.
//!
//! What [`crate::problem::normalise`] and [`crate::problem::ties`] read of the whole matrix
//! comes down, for a team that never gathers it, to three numbers the robots can agree on
//! by flooding over the graph: the lowest and the highest allowed cost (minimisation sign),
//! and the step of the lattice the allowed costs lie on, if any ([`TeamScale`]). Each robot
//! summarises its own row ([`TeamScale::of_row`]); [`TeamScale::join`] merges two summaries
//! and is commutative, associative and idempotent on the bounds (exactly: `min` and `max`)
//! and on the lattice (the smallest lattice holding both), so after `D` rounds of
//! "merge what the neighbours hold" (the graph's diameter) every robot holds the summary
//! of the stacked rows. From it each robot normalises its own row exactly as the
//! centralized normalisation would ([`TeamScale::normalised_row`]) and picks the
//! tie-breaking perturbation ([`TeamScale::epsilon`]).
//!
//! Two things differ from a solve of the whole matrix, both documented in docs/standing-teams.md: the
//! spread the ρ rules read is the normalised range (1), not `√12 · std` (a standard
//! deviation needs every cost), and the perturbation is used whenever the costs lie on a
//! lattice (a solve also asks for repeated values). Neither changes the optimum.
//!
//! ```
//! use admm_ta_agents::problem::private::TeamScale;
//! let rows = [vec![Some(3.0), Some(7.0)], vec![Some(5.0), None]];
//! let mut team = TeamScale::of_row(&rows[0], false);
//! team.join(&TeamScale::of_row(&rows[1], false));
//! assert_eq!((team.lo, team.hi), (3.0, 7.0));
//! assert_eq!(team.normalised_row(&rows[1], false, 2, 2), vec![0.5, 8.0]); // 8 = 2·2 + 4: forbidden
//! assert_eq!(team.epsilon(2), Some(0.5 / 3.0)); // integer costs: step 2 of a range of 4
//! ```

use crate::problem::normalise::{RESOLUTION, UnitMap, signed};

/// What the team agrees on about its stacked cost rows (minimisation sign, allowed pairs
/// only): their bounds and the lattice they lie on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TeamScale {
    /// The lowest allowed cost (`+∞` before any).
    pub lo: f64,
    /// The highest allowed cost (`−∞` before any).
    pub hi: f64,
    /// Step of the lattice `lo + k·step` every allowed cost lies on: `0` while all are
    /// equal, negative when there is none.
    pub step: f64,
}

/// No lattice.
const NO_LATTICE: f64 = -1.0;

impl TeamScale {
    /// Values a summary takes in a message.
    pub const WORDS: usize = 3;

    /// Nothing known yet (the identity of [`TeamScale::join`]).
    pub const EMPTY: Self = Self {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
        step: 0.0,
    };

    /// The summary of one robot's row (`None`: a forbidden pair; with `maximize` the values
    /// are profits).
    pub fn of_row(row: &[Option<f64>], maximize: bool) -> Self {
        let mut scale = Self::EMPTY;
        for v in row.iter().flatten() {
            let v = signed(maximize, *v);
            scale.join(&Self {
                lo: v,
                hi: v,
                step: 0.0,
            });
        }
        scale
    }

    /// Merges `other` into `self`: the bounds of both, and the smallest lattice that holds
    /// both lattices.
    pub fn join(&mut self, other: &Self) {
        if other.lo > other.hi {
            return;
        }
        if self.lo > self.hi {
            *self = *other;
            return;
        }
        let lo = self.lo.min(other.lo);
        let hi = self.hi.max(other.hi);
        let spread = hi - lo;
        let step = if self.step < 0.0 || other.step < 0.0 || !spread.is_finite() {
            NO_LATTICE
        } else {
            // Exact for integer data (`%` is exact in floating point); fixed-point data
            // leaves remainders of a few ulps, which the tolerance absorbs.
            let tolerance = 1e-12 * spread;
            let step = gcd(
                gcd(self.step, other.step, tolerance),
                (self.lo - other.lo).abs(),
                tolerance,
            );
            if step == 0.0 || step >= RESOLUTION * spread {
                step
            } else {
                NO_LATTICE
            }
        };
        *self = Self { lo, hi, step };
    }

    /// Writes the summary into a message.
    pub fn write(&self, out: &mut [f64]) {
        out[..Self::WORDS].copy_from_slice(&[self.lo, self.hi, self.step]);
    }

    /// A summary [`TeamScale::write`] wrote.
    pub fn read(words: &[f64]) -> Self {
        Self {
            lo: words[0],
            hi: words[1],
            step: words[2],
        }
    }

    /// Whether no robot has an allowed pair.
    pub fn is_empty(&self) -> bool {
        self.lo > self.hi
    }

    /// One robot's row as the agents solve it (the centralized normalisation's row, Cases 1
    /// and 2): allowed costs mapped to `[0, 1]` by the team's bounds, forbidden pairs at the
    /// penalty `2·max(n, m) + 4`.
    pub fn normalised_row(
        &self,
        row: &[Option<f64>],
        maximize: bool,
        robots: usize,
        tasks: usize,
    ) -> Vec<f64> {
        let penalty = 2.0 * robots.max(tasks) as f64 + 4.0;
        let (lo, hi) = if self.is_empty() {
            (0.0, 0.0)
        } else {
            (self.lo, self.hi)
        };
        let unit = UnitMap::new(lo, hi);
        row.iter()
            .map(|v| v.map_or(penalty, |v| unit.map(signed(maximize, v))))
            .collect()
    }

    /// The tie-breaking perturbation's size for `robots` robots ([`crate::problem::ties`]):
    /// the normalised lattice step over `n + 1`, when the costs lie on a lattice (constant
    /// costs: step 1).
    pub fn epsilon(&self, robots: usize) -> Option<f64> {
        if self.is_empty() || self.step < 0.0 {
            return None;
        }
        let spread = self.hi - self.lo;
        let step = if self.step == 0.0 || spread <= 0.0 {
            1.0
        } else {
            self.step / spread
        };
        Some(step / (robots + 1) as f64)
    }
}

/// Greatest common divisor of two non-negative numbers, with remainders within `tolerance`
/// of 0 (or of the divisor) taken as 0; `0` is the identity. [`NO_LATTICE`] if Euclid does
/// not end (numbers that share no step).
fn gcd(a: f64, b: f64, tolerance: f64) -> f64 {
    if a < 0.0 || b < 0.0 {
        return NO_LATTICE;
    }
    let (mut a, mut b) = (a.max(b), a.min(b));
    for _ in 0..200 {
        if b <= tolerance {
            return a;
        }
        let mut r = a % b;
        if b - r <= tolerance {
            r = 0.0;
        }
        (a, b) = (b, r);
    }
    NO_LATTICE
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::normalise::normalise;
    use crate::problem::ties::lattice_step;
    use crate::problem::{AssignmentCase, CostMatrix};
    use admm_ta_topologies::rng::SeededRng;

    fn rows_of(costs: &CostMatrix) -> Vec<Vec<Option<f64>>> {
        (0..costs.robots())
            .map(|i| {
                (0..costs.tasks())
                    .map(|t| costs.is_allowed(i, t).then(|| costs.get(i, t)))
                    .collect()
            })
            .collect()
    }

    /// Every order of merging gives the same summary, and the rows normalise exactly as the
    /// whole matrix does.
    #[test]
    fn agreed_scale_normalises_like_the_whole_matrix() {
        let mut rng = SeededRng::new(5);
        for trial in 0..60 {
            let (n, m) = (2 + trial % 5, 2 + trial % 3);
            let (n, m) = (n.max(m), m);
            let values: Vec<f64> = (0..n * m)
                .map(|_| match trial % 3 {
                    0 => rng.uniform() * 100.0 - 30.0,
                    1 => (rng.uniform() * 9.0).floor() * 2.5 + 7.0,
                    _ => (rng.uniform() * 4.0).floor() * 0.1,
                })
                .collect();
            let mut costs = CostMatrix::new(n, m, values.clone()).unwrap();
            if trial % 4 == 1 {
                let mut mask = vec![true; n * m];
                mask[trial % (n * m)] = false;
                costs = CostMatrix::with_mask(n, m, values, Some(mask)).unwrap();
            }
            let maximize = trial % 5 == 2;
            let rows = rows_of(&costs);
            let forward = rows.iter().fold(TeamScale::EMPTY, |mut s, r| {
                s.join(&TeamScale::of_row(r, maximize));
                s
            });
            let backward = rows.iter().rev().fold(TeamScale::EMPTY, |mut s, r| {
                s.join(&TeamScale::of_row(r, maximize));
                s
            });
            assert_eq!((forward.lo, forward.hi), (backward.lo, backward.hi));
            assert!((forward.step - backward.step).abs() <= 1e-12 * (forward.hi - forward.lo));
            let case = if n == m {
                AssignmentCase::One
            } else {
                AssignmentCase::Two
            };
            let parts = normalise(&costs, case, maximize).unwrap();
            for (i, row) in rows.iter().enumerate() {
                assert_eq!(
                    forward.normalised_row(row, maximize, n, m),
                    parts.matrix.row(i),
                    "trial {trial}, robot {i}"
                );
            }
            // Lattice data: the perturbation of the whole matrix's rule (which also asks for
            // repeated values); generic reals: none.
            match (lattice_step(&parts.matrix), forward.epsilon(n)) {
                (Some(step), Some(eps)) => {
                    assert!((eps - step / (n + 1) as f64).abs() < 1e-9, "trial {trial}")
                }
                (None, None) => {}
                // Lattice data without repeated values: only the private rule perturbs.
                (central, private) => assert!(
                    trial % 3 != 0 && central.is_none() && private.is_some(),
                    "trial {trial}: {central:?} {private:?}"
                ),
            }
            if trial % 3 == 0 {
                assert_eq!(forward.epsilon(n), None, "generic reals have no lattice");
            }
        }
    }

    #[test]
    fn edge_cases() {
        let constant = TeamScale::of_row(&[Some(4.0), Some(4.0)], false);
        assert_eq!(constant.epsilon(3), Some(0.25));
        assert_eq!(
            constant.normalised_row(&[Some(4.0), None], false, 2, 2),
            [0.0, 8.0]
        );
        let empty = TeamScale::of_row(&[None, None], false);
        assert!(empty.is_empty() && empty.epsilon(2).is_none());
        let mut joined = empty;
        joined.join(&constant);
        assert_eq!(joined, constant);
        let huge = TeamScale::of_row(&[Some(-1e308), Some(1e308)], false);
        assert_eq!(huge.normalised_row(&[Some(0.0)], false, 1, 1), [0.5]);
        assert!(huge.epsilon(2).is_none());
        let mut words = [0.0; 3];
        constant.write(&mut words);
        assert_eq!(TeamScale::read(&words), constant);
        // Fixed-point data: 0.1 steps are found despite their rounding.
        let tenths = TeamScale::of_row(&[Some(0.3), Some(0.7), Some(1.1)], false);
        assert!((tenths.step - 0.4).abs() < 1e-12);
        let mut more = tenths;
        more.join(&TeamScale::of_row(&[Some(0.4)], false));
        assert!((more.step - 0.1).abs() < 1e-12, "{more:?}");
    }
}
