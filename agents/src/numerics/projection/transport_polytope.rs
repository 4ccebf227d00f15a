//! Fast exact projection onto the relaxed assignment polytope (see the module above).
//!
//! **Method.** With multipliers `u ∈ R^m` for the row sums and `v ∈ R^n` for the column
//! sums, the projection of `Z` is `X(u, v) = clip(Z − u1ᵀ − 1vᵀ, 0, 1)` at the maximiser of
//! the concave, piecewise-quadratic, C¹ dual
//!
//! `g(u, v) = Σ_rc [½(x_rc − z_rc)² + (u_r + v_c) x_rc] − Σ_r u_r − Σ_c v_c`,
//! `∇_u g = X1 − 1`, `∇_v g = Xᵀ1 − 1`,
//!
//! with the sign constraint `u ≤ 0` in Case 2 (row sums `≥ 1`). We run a regularised
//! semismooth Newton method: the generalised Hessian of `−g` is
//! `[diag(r) F; Fᵀ diag(c)]`, `F` the indicator of *free* entries (`0 < w < 1`), `r`, `c`
//! their row and column counts. The step solves `(H + μI) d = ∇g` with `μ = min(1, ‖KKT‖∞)`
//! (so steps stay bounded along the null space of `H` and the method is locally fast), by
//! eliminating the columns and factoring the `m × m` Schur complement with faer's Cholesky.
//! Rows or columns with no free entry take an exact 1-D step instead (their dual is
//! piecewise *linear* there). Case 2 rows pinned at `u_r = 0` with row sum above 1 are held
//! fixed (projected Newton), and iterates are projected back onto `u ≤ 0`. An Armijo
//! backtracking line search on `g` globalises the method.
//!
//! **Tolerance.** We stop when the KKT residual (row/column sum violations, and for Case 2
//! the natural residual `u − min(u + ∇_u g, 0)`) is at most `1e-10` by default: `X` is then
//! in the box exactly, and its row and column sums are within `1e-10` of their targets —
//! four orders below the consensus residuals ADMM ever resolves (≥ 1e-6), so the inexact
//! projection cannot be what limits convergence.
//!
//! **Cost.** Warm-started from the previous round's `(u, v)`, a step inside ADMM is one
//! `O(mn)` evaluation plus, when the free set changed, an `O(m³/3)` factorisation.

use super::clipped_root::clipped_sum_root;
use super::interior::InteriorProjection;
use crate::problem::AssignmentCase;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, MatRef, Par};

/// Smallest Newton regularisation μ.
const MIN_REGULARISATION: f64 = 1e-8;

/// Knobs of the Newton projection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProjectionSettings {
    /// Stop when the KKT residual (max-norm) is at most this.
    pub tolerance: f64,
    /// Give up (and report `converged: false`) after this many Newton steps.
    pub max_newton_steps: usize,
}

impl Default for ProjectionSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_newton_steps: 200,
        }
    }
}

/// What one projection did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ProjectionStats {
    pub newton_steps: usize,
    /// Objective/gradient evaluations (each `O(mn)`), line search included.
    pub evaluations: usize,
    /// Final KKT residual.
    pub residual: f64,
    pub converged: bool,
}

/// Dual iterate with everything computed from it in one pass.
#[derive(Debug, Clone)]
struct DualPoint {
    u: Vec<f64>,
    v: Vec<f64>,
    grad_u: Vec<f64>,
    grad_v: Vec<f64>,
    row_free: Vec<usize>,
    col_free: Vec<usize>,
    value: f64,
    residual: f64,
}

impl DualPoint {
    fn new(m: usize, n: usize) -> Self {
        Self {
            u: vec![0.0; m],
            v: vec![0.0; n],
            grad_u: vec![0.0; m],
            grad_v: vec![0.0; n],
            row_free: vec![0; m],
            col_free: vec![0; n],
            value: 0.0,
            residual: f64::INFINITY,
        }
    }

    /// Fills value, gradient, free counts and KKT residual for the current `(u, v)`.
    fn evaluate(&mut self, z: MatRef<'_, f64>, case: AssignmentCase) {
        self.grad_u.fill(0.0);
        self.row_free.fill(0);
        let mut value = 0.0;
        for c in 0..z.ncols() {
            let column = column(z, c);
            let vc = self.v[c];
            let (mut sum, mut free) = (0.0, 0);
            for (r, &zr) in column.iter().enumerate() {
                let shift = self.u[r] + vc;
                let w = shifted(zr, self.u[r], vc);
                let x = w.clamp(0.0, 1.0);
                value += 0.5 * (x - zr) * (x - zr) + shift * x;
                self.grad_u[r] += x;
                sum += x;
                if w > 0.0 && w < 1.0 {
                    self.row_free[r] += 1;
                    free += 1;
                }
            }
            self.grad_v[c] = sum - 1.0;
            self.col_free[c] = free;
        }
        value -= self.u.iter().sum::<f64>() + self.v.iter().sum::<f64>();
        let mut residual: f64 = 0.0;
        for (g, &u) in self.grad_u.iter_mut().zip(&self.u) {
            *g -= 1.0;
            residual = residual.max(match case {
                AssignmentCase::One | AssignmentCase::Idle => g.abs(),
                AssignmentCase::Two => (u - (u + *g).min(0.0)).abs(),
            });
        }
        for g in &self.grad_v {
            residual = residual.max(g.abs());
        }
        if !value.is_finite() || self.grad_u.iter().chain(&self.grad_v).any(|g| g.is_nan()) {
            residual = f64::INFINITY;
        }
        self.value = value;
        self.residual = residual;
    }
}

/// `w = z − (u + v)`, the unclipped entry. Every place that classifies entries as free or
/// clipped must round it identically, or the Newton system stops matching the gradient
/// (a non-PSD Schur complement and a stalled Newton method); hence this one definition.
#[inline(always)]
fn shifted(z: f64, u: f64, v: f64) -> f64 {
    z - (u + v)
}

/// Column `c` of a column-major view as a slice.
fn column<'a>(z: MatRef<'a, f64>, c: usize) -> &'a [f64] {
    z.col(c)
        .try_as_col_major()
        .expect("projection inputs must have unit row stride (column-major)")
        .as_slice()
}

/// Projects `m × n` matrices onto the relaxed assignment polytope; owns all its scratch
/// space and keeps the last multipliers to warm-start the next call.
///
/// ```
/// use admm_ta_agents::problem::AssignmentCase;
/// use admm_ta_agents::numerics::projection::TransportPolytopeProjector;
/// use faer::Mat;
/// let z = Mat::from_fn(2, 2, |r, c| if r == c { 0.8 } else { 0.1 });
/// let mut x = Mat::<f64>::zeros(2, 2);
/// let mut projector = TransportPolytopeProjector::new(2, 2, AssignmentCase::One);
/// let stats = projector.project(z.as_ref(), x.as_mut());
/// assert!(stats.converged);
/// assert!((x[(0, 0)] - 0.85).abs() < 1e-12 && (x[(1, 0)] - 0.15).abs() < 1e-12);
/// ```
pub struct TransportPolytopeProjector {
    tasks: usize,
    robots: usize,
    case: AssignmentCase,
    settings: ProjectionSettings,
    warm: bool,
    current: DualPoint,
    trial: DualPoint,
    du: Vec<f64>,
    dv: Vec<f64>,
    in_newton_block: Vec<bool>,
    /// Free rows (of the Newton block) per column, CSR-style.
    free_start: Vec<usize>,
    free_rows: Vec<usize>,
    /// Column-major `m × m` Schur complement (lower triangle used).
    schur: Vec<f64>,
    gathered: Vec<f64>,
    simplex_scratch: Vec<f64>,
    cholesky_scratch: MemBuffer,
    /// The closed-form path tried first, if enabled.
    interior: Option<InteriorProjection>,
}

impl TransportPolytopeProjector {
    /// A projector for `tasks × robots` matrices with default settings.
    pub fn new(tasks: usize, robots: usize, case: AssignmentCase) -> Self {
        Self::with_settings(tasks, robots, case, ProjectionSettings::default())
    }

    pub fn with_settings(
        tasks: usize,
        robots: usize,
        case: AssignmentCase,
        settings: ProjectionSettings,
    ) -> Self {
        let longest = tasks.max(robots);
        Self {
            tasks,
            robots,
            case,
            settings,
            warm: false,
            current: DualPoint::new(tasks, robots),
            trial: DualPoint::new(tasks, robots),
            du: vec![0.0; tasks],
            dv: vec![0.0; robots],
            in_newton_block: vec![false; tasks],
            free_start: vec![0; robots + 1],
            free_rows: vec![0; tasks * robots],
            schur: vec![0.0; tasks * tasks],
            gathered: Vec::with_capacity(longest),
            simplex_scratch: Vec::with_capacity(longest),
            cholesky_scratch: MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(
                tasks,
                Par::Seq,
                Default::default(),
            )),
            interior: None,
        }
    }

    /// Tries the closed-form projection of `super::interior` first (iterates that stay
    /// inside the polytope, as in the fast primal variant); off by default.
    pub fn set_interior_fast_path(&mut self, on: bool) {
        self.interior = on.then(|| InteriorProjection::new(self.tasks, self.robots));
    }

    /// Forget the warm start: the next call starts from scratch.
    pub fn reset(&mut self) {
        self.warm = false;
    }

    /// Current multipliers `(u, v)` (rows, columns).
    pub fn multipliers(&self) -> (&[f64], &[f64]) {
        (&self.current.u, &self.current.v)
    }

    /// Writes `Π_P(z)` into `out`. Both are `tasks × robots` with unit row stride.
    pub fn project(&mut self, z: MatRef<'_, f64>, mut out: MatMut<'_, f64>) -> ProjectionStats {
        assert_eq!(
            (z.nrows(), z.ncols()),
            (self.tasks, self.robots),
            "z has the wrong shape"
        );
        assert_eq!(
            (out.nrows(), out.ncols()),
            (self.tasks, self.robots),
            "out has the wrong shape"
        );
        if let Some(interior) = &mut self.interior
            && interior.try_project(z, out.rb_mut(), self.case)
        {
            self.current.u.copy_from_slice(&interior.u);
            self.current.v.copy_from_slice(&interior.v);
            self.warm = true;
            return ProjectionStats {
                newton_steps: 0,
                evaluations: 1,
                residual: 0.0,
                converged: true,
            };
        }
        if !self.warm {
            self.cold_start(z);
            self.warm = true;
        }
        let mut stats = ProjectionStats::default();
        self.current.evaluate(z, self.case);
        stats.evaluations += 1;
        while self.current.residual > self.settings.tolerance {
            if stats.newton_steps == self.settings.max_newton_steps {
                break;
            }
            stats.newton_steps += 1;
            self.newton_direction(z);
            match self.line_search(z, &mut stats) {
                true => std::mem::swap(&mut self.current, &mut self.trial),
                false => break,
            }
        }
        stats.residual = self.current.residual;
        stats.converged = stats.residual <= self.settings.tolerance;
        if !stats.converged {
            // A stalled warm start must not poison later calls.
            self.warm = false;
        }
        for c in 0..self.robots {
            let zc = column(z, c);
            let vc = self.current.v[c];
            let mut oc = out.rb_mut().col_mut(c);
            for (r, &zr) in zc.iter().enumerate() {
                oc[r] = shifted(zr, self.current.u[r], vc).clamp(0.0, 1.0);
            }
        }
        stats
    }

    /// `u = 0` and every column projected onto its simplex: the right answer when the row
    /// constraints are slack, and a good start otherwise.
    fn cold_start(&mut self, z: MatRef<'_, f64>) {
        self.current.u.fill(0.0);
        for c in 0..self.robots {
            self.current.v[c] = clipped_sum_root(column(z, c), &mut self.simplex_scratch);
        }
    }

    /// Fills `du`, `dv` with the regularised semismooth Newton direction (module docs).
    fn newton_direction(&mut self, z: MatRef<'_, f64>) {
        // μ tracks the residual (fast local convergence) but stays well above the rounding
        // error of the Schur complement, whose diagonal is a difference of O(m) terms.
        let mu = self.current.residual.clamp(MIN_REGULARISATION, 1.0);
        self.mark_free(z);
        self.solve_schur(mu);
        self.off_block_steps(z, mu);
    }

    /// The rows of the Newton block (not pinned, with free entries) and, per column, its
    /// free rows.
    #[inline]
    fn mark_free(&mut self, z: MatRef<'_, f64>) {
        let (m, n) = (self.tasks, self.robots);
        let p = &self.current;
        for r in 0..m {
            let pinned = self.case == AssignmentCase::Two && p.u[r] >= 0.0 && p.grad_u[r] > 0.0;
            self.in_newton_block[r] = !pinned && p.row_free[r] > 0;
        }
        let mut next = 0;
        for c in 0..n {
            self.free_start[c] = next;
            let zc = column(z, c);
            for (r, &zr) in zc.iter().enumerate() {
                let w = shifted(zr, p.u[r], p.v[c]);
                if self.in_newton_block[r] && w > 0.0 && w < 1.0 {
                    self.free_rows[next] = r;
                    next += 1;
                }
            }
        }
        self.free_start[n] = next;
    }

    /// The rows' step `du` on the Newton block: the Schur complement
    /// `S = diag(r) + μ − F diag(1/(c + μ)) Fᵀ` solved for `rhs = g_u − F (g_v/(c + μ))`
    /// by a regularised Cholesky factorisation (a scaled gradient should it fail).
    #[inline]
    fn solve_schur(&mut self, mu: f64) {
        let (m, n) = (self.tasks, self.robots);
        let p = &self.current;
        let schur = &mut self.schur;
        schur.fill(0.0);
        for r in 0..m {
            if self.in_newton_block[r] {
                schur[r * m + r] = p.row_free[r] as f64 + mu;
                self.du[r] = p.grad_u[r];
            } else {
                schur[r * m + r] = 1.0;
                self.du[r] = 0.0;
            }
        }
        for c in 0..n {
            let rows = &self.free_rows[self.free_start[c]..self.free_start[c + 1]];
            if rows.is_empty() {
                continue;
            }
            let inv = 1.0 / (p.col_free[c] as f64 + mu);
            for (k, &b) in rows.iter().enumerate() {
                self.du[b] -= inv * p.grad_v[c];
                // Rows are increasing, so (a, b) with a ≥ b lies in the lower triangle.
                let column = &mut schur[b * m..(b + 1) * m];
                for &a in &rows[k..] {
                    column[a] -= inv;
                }
            }
        }
        let mut schur = MatMut::from_column_major_slice_mut(schur, m, m);
        let stack = MemStack::new(&mut self.cholesky_scratch);
        let factored = llt::factor::cholesky_in_place(
            schur.rb_mut(),
            // Pivots below μ/1000 can only be rounding noise (S ⪰ μI): replace them by μ.
            llt::factor::LltRegularization {
                dynamic_regularization_delta: mu,
                dynamic_regularization_epsilon: 1e-3 * mu,
            },
            Par::Seq,
            stack,
            Default::default(),
        );
        let rhs = MatMut::from_column_major_slice_mut(&mut self.du, m, 1);
        if factored.is_ok() {
            llt::solve::solve_in_place(schur.rb(), rhs, Par::Seq, stack);
        }
        if factored.is_err() || self.du.iter().any(|d| !d.is_finite()) {
            // Cannot happen for an SPD Schur complement; fall back to a scaled gradient.
            for r in 0..m {
                if self.in_newton_block[r] {
                    self.du[r] = p.grad_u[r] / (p.row_free[r] as f64 + mu);
                }
            }
        }
    }

    /// The steps outside the Newton block: rows fixed (pinned) or an exact 1-D step; columns
    /// by back-substitution, or an exact 1-D step when nothing in them is free.
    #[inline]
    fn off_block_steps(&mut self, z: MatRef<'_, f64>, mu: f64) {
        let (m, n) = (self.tasks, self.robots);
        let p = &self.current;
        for r in 0..m {
            if self.in_newton_block[r] || p.row_free[r] > 0 {
                continue;
            }
            self.gathered.clear();
            self.gathered.extend((0..n).map(|c| z[(r, c)] - p.v[c]));
            let mut root = clipped_sum_root(&self.gathered, &mut self.simplex_scratch);
            if self.case == AssignmentCase::Two {
                root = root.min(0.0);
            }
            self.du[r] = root - p.u[r];
        }
        for c in 0..n {
            if p.col_free[c] > 0 {
                let rows = &self.free_rows[self.free_start[c]..self.free_start[c + 1]];
                let coupled: f64 = rows.iter().map(|&r| self.du[r]).sum();
                self.dv[c] = (p.grad_v[c] - coupled) / (p.col_free[c] as f64 + mu);
            } else {
                self.gathered.clear();
                self.gathered
                    .extend(column(z, c).iter().zip(&p.u).map(|(zr, u)| zr - u));
                self.dv[c] = clipped_sum_root(&self.gathered, &mut self.simplex_scratch) - p.v[c];
            }
        }
    }

    /// Backtracking (Armijo) along `(du, dv)`, projecting onto `u ≤ 0` in Case 2. Leaves the
    /// accepted point in `trial`; `false` if no step was accepted.
    fn line_search(&mut self, z: MatRef<'_, f64>, stats: &mut ProjectionStats) -> bool {
        const SUFFICIENT_INCREASE: f64 = 1e-4;
        const MAX_HALVINGS: usize = 60;
        let mut t = 1.0;
        for _ in 0..MAX_HALVINGS {
            let p = &self.current;
            let mut predicted = 0.0;
            for r in 0..self.tasks {
                let mut u = p.u[r] + t * self.du[r];
                if self.case == AssignmentCase::Two {
                    u = u.min(0.0);
                }
                self.trial.u[r] = u;
                predicted += p.grad_u[r] * (u - p.u[r]);
            }
            for c in 0..self.robots {
                self.trial.v[c] = p.v[c] + t * self.dv[c];
                predicted += p.grad_v[c] * t * self.dv[c];
            }
            self.trial.evaluate(z, self.case);
            stats.evaluations += 1;
            let p = &self.current;
            // Armijo; or a clear drop of the residual; or, once the increase of g is below
            // what rounding of its O(mn) terms can resolve, any drop of the residual.
            let unresolvable = predicted.abs() <= 1e-12 * (1.0 + p.value.abs());
            if self.trial.value >= p.value + SUFFICIENT_INCREASE * predicted
                || self.trial.residual <= 0.5 * p.residual
                || (unresolvable && self.trial.residual < p.residual)
            {
                return true;
            }
            t *= 0.5;
        }
        false
    }
}
