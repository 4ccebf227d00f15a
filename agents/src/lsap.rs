//! Exact rectangular linear sum assignment (the centralized "Hungarian" reference).
//!
//! Shortest augmenting paths with dual potentials (Jonker–Volgenant as restated by Crouse,
//! "On implementing 2D rectangular assignment algorithms", 2016 — the algorithm behind
//! scipy's `linear_sum_assignment`). A `rows × cols` matrix with `rows ≤ cols` is solved
//! directly, a tall one through its transpose; nothing is padded. `O(rows² · cols)`.

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
        let col4row = ShortestAugmentingPath::new(rows, cols).run(|r, c| cost[r * cols + c])?;
        Ok(col4row.into_iter().map(Some).collect())
    } else {
        let row4col = ShortestAugmentingPath::new(cols, rows).run(|r, c| cost[c * cols + r])?;
        let mut out = vec![None; rows];
        for (col, row) in row4col.into_iter().enumerate() {
            out[row] = Some(col);
        }
        Ok(out)
    }
}

const UNSET: usize = usize::MAX;

/// Working arrays of the augmenting-path solver for `rows ≤ cols`.
struct ShortestAugmentingPath {
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
}

impl ShortestAugmentingPath {
    fn new(rows: usize, cols: usize) -> Self {
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
        }
    }

    fn run(mut self, cost: impl Fn(usize, usize) -> f64) -> Result<Vec<usize>, LsapError> {
        for current in 0..self.rows {
            let (sink, min_value) = self
                .augmenting_path(current, &cost)
                .ok_or(LsapError::Infeasible)?;
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
        Ok(self.col4row)
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
        loop {
            self.visited_rows[row] = true;
            let mut best_index = UNSET;
            let mut lowest = f64::INFINITY;
            for k in 0..remaining {
                let c = self.remaining[k];
                let reduced = min_value + cost(row, c) - self.u[row] - self.v[c];
                if reduced < self.shortest[c] {
                    self.path[c] = row;
                    self.shortest[c] = reduced;
                }
                if self.shortest[c] < lowest
                    || (self.shortest[c] == lowest && self.row4col[c] == UNSET)
                {
                    lowest = self.shortest[c];
                    best_index = k;
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
            if self.row4col[c] == UNSET {
                return Some((c, min_value));
            }
            row = self.row4col[c];
        }
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
