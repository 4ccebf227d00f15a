//! The shortest-augmenting-path solver of [`crate::numerics::lsap`] over a reusable workspace, so that
//! a robot can solve an assignment problem every round without allocating (the fast primal
//! readout, [`crate::methods::primal::readout`]). Like faer's scratch buffers: allocate once for the
//! largest shape, then solve as often as needed.
//!
//! # Warm start
//! A robot solves a slowly changing problem every round. [`LsapWorkspace::solve_warm`]
//! starts a square problem from the previous solve's column potentials `v` and
//! assignment: every row gets `u_r = min_c (cost(r, c) − v_c)` (so the duals are feasible
//! for the new costs); a row keeps its previous column when that column attains the
//! minimum (complementary slackness), and only the other rows are augmented. The result is
//! an exact minimiser, as from a cold start; the work drops from `O(n³)` to `O(n²)` plus
//! one shortest-path search per row whose best column moved (120×120 chain, the fast
//! primal readout: see `admm-ta experiment size-sweep`). Rectangular problems (`rows <
//! cols`) always start cold: their free columns must keep `v = 0`.

const UNSET: usize = usize::MAX;

/// Working arrays of the augmenting-path solver for `rows ≤ cols`, reused across solves.
#[derive(Debug, Clone, Default)]
pub struct LsapWorkspace {
    rows: usize,
    cols: usize,
    u: Vec<f64>,
    v: Vec<f64>,
    shortest: Vec<f64>,
    path: Vec<usize>,
    col4row: Vec<usize>,
    row4col: Vec<usize>,
    visited_rows: Vec<bool>,
    visited_cols: Vec<bool>,
    remaining: Vec<usize>,
    /// `v` and the assignment are the last successful solve's (the warm start may use them).
    warm: bool,
}

impl LsapWorkspace {
    /// A workspace for problems of up to `rows × cols` (`rows ≤ cols`).
    pub fn new(rows: usize, cols: usize) -> Self {
        assert!(rows <= cols, "the solver needs rows ≤ cols");
        Self {
            rows,
            cols,
            u: vec![0.0; rows],
            v: vec![0.0; cols],
            shortest: vec![f64::INFINITY; cols],
            path: vec![UNSET; cols],
            col4row: vec![UNSET; rows],
            row4col: vec![UNSET; cols],
            visited_rows: vec![false; rows],
            visited_cols: vec![false; cols],
            remaining: vec![0; cols],
            warm: false,
        }
    }

    /// The workspace for `rows × cols` problems (`rows ≤ cols`), reusing its memory: no
    /// allocation once it has held a problem as large. The next solve starts cold.
    pub fn reshape(&mut self, rows: usize, cols: usize) {
        assert!(rows <= cols, "the solver needs rows ≤ cols");
        let fit = |v: &mut Vec<usize>, len: usize| {
            v.clear();
            v.resize(len, UNSET);
        };
        self.rows = rows;
        self.cols = cols;
        self.u.clear();
        self.u.resize(rows, 0.0);
        self.v.clear();
        self.v.resize(cols, 0.0);
        self.shortest.clear();
        self.shortest.resize(cols, f64::INFINITY);
        fit(&mut self.path, cols);
        fit(&mut self.col4row, rows);
        fit(&mut self.row4col, cols);
        fit(&mut self.remaining, cols);
        self.visited_rows.clear();
        self.visited_rows.resize(rows, false);
        self.visited_cols.clear();
        self.visited_cols.resize(cols, false);
        self.warm = false;
    }

    /// Minimises `Σ_r cost(r, col[r])` over injective maps of the `rows` rows into the `cols`
    /// columns (`rows ≤ cols`, within the workspace's shape); returns the column of every
    /// row, or `None` when `+∞` (forbidden) or NaN costs leave some row no column. Allocates
    /// nothing.
    pub fn solve(&mut self, cost: impl Fn(usize, usize) -> f64) -> Option<&[usize]> {
        self.cold_start();
        self.augment_free_rows(&cost)
    }

    /// As [`LsapWorkspace::solve`], warm-started from the previous solve when the problem
    /// is square and the previous solve succeeded (module docs). Same result set: a
    /// minimiser of the new costs. Allocates nothing.
    pub fn solve_warm(&mut self, cost: impl Fn(usize, usize) -> f64) -> Option<&[usize]> {
        if !(self.warm && self.rows == self.cols && self.warm_start(&cost)) {
            self.cold_start();
        }
        self.augment_free_rows(&cost)
    }

    /// The next [`LsapWorkspace::solve_warm`] starts cold.
    pub fn forget(&mut self) {
        self.warm = false;
    }

    fn cold_start(&mut self) {
        self.u.fill(0.0);
        self.v.fill(0.0);
        self.col4row.fill(UNSET);
        self.row4col.fill(UNSET);
    }

    /// Keeps `v`, sets `u_r = min_c (cost(r, c) − v_c)` and keeps the rows whose previous
    /// column attains it; `false` (start cold) when some minimum is not finite.
    fn warm_start(&mut self, cost: &impl Fn(usize, usize) -> f64) -> bool {
        for r in 0..self.rows {
            let kept = self.col4row[r];
            let mut lowest = cost(r, kept) - self.v[kept];
            let mut moved = false;
            for c in 0..self.cols {
                let value = cost(r, c) - self.v[c];
                if value < lowest {
                    lowest = value;
                    moved = true;
                }
            }
            if !lowest.is_finite() {
                return false;
            }
            self.u[r] = lowest;
            if moved {
                self.col4row[r] = UNSET;
                self.row4col[kept] = UNSET;
            }
        }
        true
    }

    /// Augments every row without a column (all of them after a cold start).
    fn augment_free_rows(&mut self, cost: &impl Fn(usize, usize) -> f64) -> Option<&[usize]> {
        self.warm = false;
        for current in 0..self.rows {
            if self.col4row[current] != UNSET {
                continue;
            }
            let (sink, min_value) = self.augmenting_path(current, cost)?;
            // Update the dual potentials of the rows and columns on the search tree.
            self.u[current] += min_value;
            for r in 0..self.rows {
                if self.visited_rows[r] && r != current {
                    self.u[r] += min_value - self.shortest[self.col4row[r]];
                }
            }
            for c in 0..self.cols {
                if self.visited_cols[c] {
                    self.v[c] -= min_value - self.shortest[c];
                }
            }
            // Flip the alternating path ending at `sink`.
            let mut c = sink;
            loop {
                let r = self.path[c];
                self.row4col[c] = r;
                std::mem::swap(&mut self.col4row[r], &mut c);
                if r == current {
                    break;
                }
            }
        }
        self.warm = true;
        Some(&self.col4row)
    }

    /// Dijkstra over reduced costs from an unassigned row to the nearest free column.
    fn augmenting_path(
        &mut self,
        start: usize,
        cost: &impl Fn(usize, usize) -> f64,
    ) -> Option<(usize, f64)> {
        let mut min_value = 0.0;
        let mut remaining = self.cols;
        for (k, slot) in self.remaining.iter_mut().enumerate() {
            *slot = self.cols - k - 1;
        }
        self.visited_rows.fill(false);
        self.visited_cols.fill(false);
        self.shortest.fill(f64::INFINITY);
        let mut row = start;
        let cols = self.cols;
        let (v, shortest, path, row4col) = (
            &self.v[..cols],
            &mut self.shortest[..cols],
            &mut self.path[..cols],
            &self.row4col[..cols],
        );
        loop {
            self.visited_rows[row] = true;
            let mut best_index = UNSET;
            let mut lowest = f64::INFINITY;
            let u_row = self.u[row];
            for (k, &c) in self.remaining[..remaining].iter().enumerate() {
                debug_assert!(c < cols);
                // SAFETY: `remaining` holds distinct columns `< cols` (filled above, then
                // only moved within), and every slice here has `cols` entries. The
                // unchecked reads are the solver's inner loop (scipy's speed at n = 3000).
                unsafe {
                    // scipy's order of operations, so that ties break as scipy's do.
                    let reduced = min_value + cost(row, c) - u_row - *v.get_unchecked(c);
                    let best = shortest.get_unchecked_mut(c);
                    if reduced < *best {
                        *path.get_unchecked_mut(c) = row;
                        *best = reduced;
                    }
                    let best = *best;
                    if best < lowest || (best == lowest && *row4col.get_unchecked(c) == UNSET) {
                        lowest = best;
                        best_index = k;
                    }
                }
            }
            // Finite costs and rows ≤ cols guarantee a free column is always reachable;
            // forbidden (+∞) pairs may leave none.
            if best_index == UNSET || lowest == f64::INFINITY {
                return None;
            }
            min_value = lowest;
            let c = self.remaining[best_index];
            self.visited_cols[c] = true;
            remaining -= 1;
            self.remaining[best_index] = self.remaining[remaining];
            if row4col[c] == UNSET {
                return Some((c, min_value));
            }
            row = row4col[c];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admm_ta_topologies::rng::SeededRng;

    fn total(cost: &[f64], n: usize, assignment: &[usize]) -> f64 {
        assignment
            .iter()
            .enumerate()
            .map(|(r, &c)| cost[r * n + c])
            .sum()
    }

    /// A drifting square problem (small and large moves, integer ties, a forbidden pair
    /// now and then): the warm solve's assignment is always a minimiser, as the cold one's.
    #[test]
    fn warm_solves_of_a_drifting_problem_are_minimisers() {
        let mut rng = SeededRng::new(22);
        for n in [1, 2, 5, 12] {
            let (mut warm, mut cold) = (LsapWorkspace::new(n, n), LsapWorkspace::new(n, n));
            let mut cost: Vec<f64> = (0..n * n).map(|_| rng.uniform()).collect();
            for round in 0..300 {
                let step = [1e-6, 1e-3, 0.3][round % 3];
                for c in cost.iter_mut() {
                    *c += step * (rng.uniform() - 0.5);
                }
                if round % 7 == 0 {
                    // Exact ties: integer costs.
                    cost.iter_mut().for_each(|c| *c = (*c * 4.0).round());
                }
                let forbidden = (round % 11 == 5).then_some(n - 1);
                let saved = forbidden.map(|e| std::mem::replace(&mut cost[e], f64::INFINITY));
                let expected = cold
                    .solve(|r, c| cost[r * n + c])
                    .map(|a| total(&cost, n, a));
                let got = warm
                    .solve_warm(|r, c| cost[r * n + c])
                    .map(|a| total(&cost, n, a));
                match (expected, got) {
                    (Some(e), Some(g)) => assert!((e - g).abs() <= 1e-9 * (1.0 + e.abs())),
                    (e, g) => assert_eq!(e.is_some(), g.is_some()),
                }
                if let (Some(e), Some(value)) = (forbidden, saved) {
                    cost[e] = value;
                }
            }
        }
    }

    #[test]
    fn a_warm_start_of_an_unchanged_problem_augments_nothing() {
        let mut rng = SeededRng::new(3);
        let n = 20;
        let cost: Vec<f64> = (0..n * n).map(|_| rng.uniform()).collect();
        let mut workspace = LsapWorkspace::new(n, n);
        let first = workspace.solve(|r, c| cost[r * n + c]).unwrap().to_vec();
        let evaluations = std::cell::Cell::new(0);
        let again = workspace
            .solve_warm(|r, c| {
                evaluations.set(evaluations.get() + 1);
                cost[r * n + c]
            })
            .unwrap();
        assert_eq!(again, &first[..]);
        // One pass over the rows (each row's kept column and every column): no search.
        assert_eq!(evaluations.get(), n * (n + 1));
    }
}
