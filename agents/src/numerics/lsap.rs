//! Exact rectangular linear sum assignment (the centralized "Hungarian" reference).
//!
//! Shortest augmenting paths with dual potentials (Jonker–Volgenant as restated by Crouse,
//! "On implementing 2D rectangular assignment algorithms", 2016 — the algorithm behind
//! scipy's `linear_sum_assignment`). A `rows × cols` matrix with `rows ≤ cols` is solved
//! directly, a tall one through its transpose; nothing is padded. `O(rows² · cols)`. The
//! solver itself, with a reusable workspace, is [`crate::numerics::lsap_workspace`].

use crate::numerics::lsap_workspace::LsapWorkspace;

/// Why an assignment could not be computed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LsapError {
    #[error("cost matrix has {0} values for a {1}×{2} shape")]
    Shape(usize, usize, usize),
    #[error("cost ({0}, {1}) is not a number or −∞ (+∞ marks a forbidden pair)")]
    NonFinite(usize, usize),
    #[error("cost matrix is infeasible: no assignment avoids the forbidden (+∞) pairs")]
    Infeasible,
}

/// Minimises `Σ_r cost[r][col_of_row[r]]` over injective maps from the smaller side into the
/// larger one. `cost` is row-major `rows × cols`. Returns, for every row, its column
/// (`Some`) — or `None` for rows left out when `rows > cols`. `+∞` marks a forbidden pair
/// (as in scipy); [`LsapError::Infeasible`] when no assignment avoids them.
pub fn solve(cost: &[f64], rows: usize, cols: usize) -> Result<Vec<Option<usize>>, LsapError> {
    if cost.len() != rows * cols {
        return Err(LsapError::Shape(cost.len(), rows, cols));
    }
    if let Some(k) = cost
        .iter()
        .position(|c| c.is_nan() || *c == f64::NEG_INFINITY)
    {
        return Err(LsapError::NonFinite(k / cols.max(1), k % cols.max(1)));
    }
    if rows == 0 || cols == 0 {
        return Ok(vec![None; rows]);
    }
    if rows <= cols {
        let mut workspace = LsapWorkspace::new(rows, cols);
        let col4row = workspace
            .solve(|r, c| cost[r * cols + c])
            .ok_or(LsapError::Infeasible)?;
        Ok(col4row.iter().copied().map(Some).collect())
    } else {
        let mut workspace = LsapWorkspace::new(cols, rows);
        let row4col = workspace
            .solve(|r, c| cost[c * cols + r])
            .ok_or(LsapError::Infeasible)?;
        let mut out = vec![None; rows];
        for (col, &row) in row4col.iter().enumerate() {
            out[row] = Some(col);
        }
        Ok(out)
    }
}

/// scipy's `linear_sum_assignment(cost, maximize)` on a row-major `rows × cols` matrix, step
/// for step: a tall matrix is solved through a contiguous transpose, profits through their
/// negation, then NaN and `−∞` (after the negation: `+∞` profits) are refused, and the
/// same shortest-augmenting-path search runs in the same order, so ties resolve to the
/// same assignment. Returns `(row_ind, col_ind)`, `min(rows, cols)` pairs sorted by row
/// (empty for an empty matrix, which is never checked). [`ScipyLsap`] does the same
/// without allocating once warm.
pub fn linear_sum_assignment(
    cost: &[f64],
    rows: usize,
    cols: usize,
    maximize: bool,
) -> Result<(Vec<usize>, Vec<usize>), LsapError> {
    let mut scratch = ScipyLsap::default();
    Ok(scratch
        .solve(cost, rows, cols, maximize)?
        .iter()
        .copied()
        .unzip())
}

/// [`linear_sum_assignment`] over memory kept between calls (the Python package keeps one
/// per thread): after the first call of a size, a call allocates nothing.
#[derive(Debug, Clone)]
pub struct ScipyLsap {
    workspace: LsapWorkspace,
    /// The negated or transposed matrix, when the input is not used as it is.
    copy: Vec<f64>,
    /// The answer: `(row, col)` pairs sorted by row.
    pairs: Vec<(usize, usize)>,
}

impl Default for ScipyLsap {
    fn default() -> Self {
        Self {
            workspace: LsapWorkspace::new(0, 0),
            copy: Vec::new(),
            pairs: Vec::new(),
        }
    }
}

impl ScipyLsap {
    /// The last successful [`ScipyLsap::solve`]'s pairs.
    pub fn pairs(&self) -> &[(usize, usize)] {
        &self.pairs
    }

    /// As [`linear_sum_assignment`]: the `(row, col)` pairs sorted by row.
    pub fn solve(
        &mut self,
        cost: &[f64],
        rows: usize,
        cols: usize,
        maximize: bool,
    ) -> Result<&[(usize, usize)], LsapError> {
        if rows.checked_mul(cols) != Some(cost.len()) {
            return Err(LsapError::Shape(cost.len(), rows, cols));
        }
        self.pairs.clear();
        if rows == 0 || cols == 0 {
            return Ok(&self.pairs);
        }
        let transpose = cols < rows;
        let (nr, nc) = if transpose {
            (cols, rows)
        } else {
            (rows, cols)
        };
        if transpose || maximize {
            let sign = if maximize { -1.0 } else { 1.0 };
            self.copy.clear();
            if transpose {
                self.copy.resize(rows * cols, 0.0);
                for r in 0..rows {
                    for c in 0..cols {
                        self.copy[c * rows + r] = sign * cost[r * cols + c];
                    }
                }
            } else {
                self.copy.extend(cost.iter().map(|&c| sign * c));
            }
        }
        let matrix: &[f64] = if transpose || maximize {
            &self.copy
        } else {
            cost
        };
        if let Some(k) = matrix
            .iter()
            .position(|c| c.is_nan() || *c == f64::NEG_INFINITY)
        {
            return Err(LsapError::NonFinite(k / nc, k % nc));
        }
        self.workspace.reshape(nr, nc);
        assert_eq!(matrix.len(), nr * nc);
        let col4row = self
            .workspace
            // SAFETY: the solver asks for rows `< nr` and columns `< nc` only, and the
            // matrix has `nr × nc` entries (asserted above).
            .solve(|r, c| unsafe { *matrix.get_unchecked(r * nc + c) })
            .ok_or(LsapError::Infeasible)?;
        if transpose {
            // Row `j` of the transpose is column `j`: pair it with its row, sorted by row.
            self.pairs
                .extend(col4row.iter().enumerate().map(|(col, &row)| (row, col)));
            self.pairs.sort_unstable();
        } else {
            self.pairs.extend(col4row.iter().copied().enumerate());
        }
        Ok(&self.pairs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_force(cost: &[f64], rows: usize, cols: usize) -> f64 {
        fn go(cost: &[f64], rows: usize, cols: usize, r: usize, used: &mut Vec<bool>) -> f64 {
            if r == rows {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for c in 0..cols {
                if !used[c] {
                    used[c] = true;
                    best = best.min(cost[r * cols + c] + go(cost, rows, cols, r + 1, used));
                    used[c] = false;
                }
            }
            best
        }
        go(cost, rows, cols, 0, &mut vec![false; cols])
    }

    fn total(cost: &[f64], cols: usize, a: &[Option<usize>]) -> f64 {
        a.iter()
            .enumerate()
            .filter_map(|(r, c)| c.map(|c| cost[r * cols + c]))
            .sum()
    }

    #[test]
    fn matches_brute_force_on_small_rectangles() {
        let mut rng = admm_ta_topologies::rng::SeededRng::new(5);
        for rows in 1..=6 {
            for cols in rows..=7 {
                for _ in 0..5 {
                    let cost: Vec<f64> = (0..rows * cols)
                        .map(|_| rng.uniform() * 10.0 - 3.0)
                        .collect();
                    let a = solve(&cost, rows, cols).unwrap();
                    let mut seen = vec![false; cols];
                    for c in a.iter().map(|c| c.unwrap()) {
                        assert!(!seen[c]);
                        seen[c] = true;
                    }
                    let expected = brute_force(&cost, rows, cols);
                    assert!((total(&cost, cols, &a) - expected).abs() < 1e-9);
                    // The transpose gives the same optimum through the tall path.
                    let mut t = vec![0.0; rows * cols];
                    for r in 0..rows {
                        for c in 0..cols {
                            t[c * rows + r] = cost[r * cols + c];
                        }
                    }
                    let at = solve(&t, cols, rows).unwrap();
                    assert_eq!(at.iter().filter(|c| c.is_some()).count(), rows);
                    assert!((total(&t, rows, &at) - expected).abs() < 1e-9);
                }
            }
        }
    }

    /// scipy's call: the optimum of `solve`, pairs sorted by row, profits by negation,
    /// scipy's refusals; one reused `ScipyLsap` over shapes that grow and shrink.
    #[test]
    fn scipy_s_call_is_optimal_sorted_and_refuses_as_scipy() {
        let mut rng = admm_ta_topologies::rng::SeededRng::new(9);
        let mut reused = ScipyLsap::default();
        for (rows, cols) in [(3, 5), (5, 3), (1, 1), (6, 6), (2, 7), (7, 2), (4, 4)] {
            let cost: Vec<f64> = (0..rows * cols)
                .map(|_| (rng.uniform() * 4.0).floor())
                .collect();
            for maximize in [false, true] {
                let (r, c) = linear_sum_assignment(&cost, rows, cols, maximize).unwrap();
                assert_eq!(r.len(), rows.min(cols));
                assert!(r.windows(2).all(|w| w[0] < w[1]), "rows sorted: {r:?}");
                let total: f64 = r.iter().zip(&c).map(|(&i, &j)| cost[i * cols + j]).sum();
                let sign = if maximize { -1.0 } else { 1.0 };
                let signed: Vec<f64> = cost.iter().map(|x| sign * x).collect();
                let best = total_of(&signed, cols, &solve(&signed, rows, cols).unwrap());
                assert!((sign * total - best).abs() < 1e-9);
                let again = reused.solve(&cost, rows, cols, maximize).unwrap();
                assert_eq!(again.iter().map(|p| p.0).collect::<Vec<_>>(), r);
                assert_eq!(again.iter().map(|p| p.1).collect::<Vec<_>>(), c);
            }
        }
        let inf = f64::INFINITY;
        assert_eq!(
            linear_sum_assignment(&[f64::NAN], 1, 1, false),
            Err(LsapError::NonFinite(0, 0))
        );
        assert!(linear_sum_assignment(&[-inf], 1, 1, false).is_err());
        assert!(linear_sum_assignment(&[inf], 1, 1, true).is_err());
        assert!(linear_sum_assignment(&[-inf, 1.0], 1, 2, true).is_ok());
        assert_eq!(
            linear_sum_assignment(&[inf, 1.0, inf, 2.0], 2, 2, false),
            Err(LsapError::Infeasible)
        );
        assert_eq!(
            linear_sum_assignment(&[], 0, 3, false),
            Ok((Vec::new(), Vec::new()))
        );
        assert!(linear_sum_assignment(&[1.0], 2, 2, false).is_err());
    }

    fn total_of(cost: &[f64], cols: usize, a: &[Option<usize>]) -> f64 {
        a.iter()
            .enumerate()
            .filter_map(|(r, c)| c.map(|c| cost[r * cols + c]))
            .sum()
    }

    #[test]
    fn a_reused_workspace_gives_the_solver_s_answers() {
        let mut rng = admm_ta_topologies::rng::SeededRng::new(9);
        let mut workspace = LsapWorkspace::new(5, 7);
        for _ in 0..20 {
            let cost: Vec<f64> = (0..35).map(|_| rng.uniform()).collect();
            let expected: Vec<usize> = solve(&cost, 5, 7)
                .unwrap()
                .into_iter()
                .map(Option::unwrap)
                .collect();
            assert_eq!(workspace.solve(|r, c| cost[r * 7 + c]), Some(&expected[..]));
        }
    }

    #[test]
    fn rejects_bad_input() {
        assert_eq!(
            solve(&[1.0, f64::NAN], 1, 2),
            Err(LsapError::NonFinite(0, 1))
        );
        assert_eq!(solve(&[1.0], 1, 2), Err(LsapError::Shape(1, 1, 2)));
        let inf = f64::INFINITY;
        assert_eq!(
            solve(&[inf, 1.0, inf, 2.0], 2, 2),
            Err(LsapError::Infeasible)
        );
        assert_eq!(
            solve(&[inf, 1.0, 2.0, inf], 2, 2).unwrap(),
            vec![Some(1), Some(0)]
        );
        assert_eq!(solve(&[], 0, 3).unwrap(), Vec::<Option<usize>>::new());
    }
}
