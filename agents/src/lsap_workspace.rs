//! The shortest-augmenting-path solver of [`crate::lsap`] over a reusable workspace, so that
//! a robot can solve an assignment problem every round without allocating (the fast primal
//! readout, [`crate::readout`]). Like faer's scratch buffers: allocate once for the
//! largest shape, then solve as often as needed.

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
        }
    }

    /// Minimises `Σ_r cost(r, col[r])` over injective maps of the `rows` rows into the `cols`
    /// columns (`rows ≤ cols`, within the workspace's shape); returns the column of every
    /// row, or `None` when `+∞` (forbidden) or NaN costs leave some row no column. Allocates
    /// nothing.
    pub fn solve(&mut self, cost: impl Fn(usize, usize) -> f64) -> Option<&[usize]> {
        self.u.fill(0.0);
        self.v.fill(0.0);
        self.col4row.fill(UNSET);
        self.row4col.fill(UNSET);
        for current in 0..self.rows {
            let (sink, min_value) = self.augmenting_path(current, &cost)?;
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
