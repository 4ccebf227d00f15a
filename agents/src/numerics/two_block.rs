//! Generic two-block ADMM, as in Boyd, Parikh, Chu, Peleato & Eckstein, *Distributed Optimization and Statistical Learning via the Alternating Direction Method of Multipliers* (2011), §3:
//!
//! ```text
//! minimise f(x) + g(z)   subject to   A x + B z = c
//! x^{k+1} = argmin_x f(x) + (ρ/2) ‖A x + B z^k − c + u^k‖²
//! z^{k+1} = argmin_z g(z) + (ρ/2) ‖A x^{k+1} + B z − c + u^k‖²
//! u^{k+1} = u^k + A x^{k+1} + B z^{k+1} − c                      (u = λ/ρ)
//! ```
//!
//! The caller supplies the two minimisers (proximal operators): the x-minimiser gets
//! `v = B z − c + u` and must return `argmin_x f(x) + (ρ/2)‖A x + v‖²`; the z-minimiser gets
//! `w = A x − c + u` and returns `argmin_z g(z) + (ρ/2)‖B z + w‖²`. The multiplier is kept
//! scaled (`u`) or unscaled (`λ = ρ u`, the tutorial's form (3), where the offsets are
//! formed as `B z − c + λ/ρ`); both give the same iterates. Stopping follows Boyd et al.
//! §3.3.1: primal residual `r = A x + B z − c`, dual residual `s = ρ Aᵀ B (z^{k+1} − z^k)`,
//! `‖r‖ ≤ √p ε_abs + ε_rel max(‖A x‖, ‖B z‖, ‖c‖)` and `‖s‖ ≤ √n ε_abs + ε_rel ‖Aᵀ λ‖`.
//!
//! [`TwoBlockAdmm::step`] is one iteration over preallocated buffers; [`TwoBlockAdmm::solve`]
//! is the loop with the stopping test. Example — project `a` onto `z ≥ 0` by splitting
//! `min ½‖x − a‖² + I(z ≥ 0)` with `x − z = 0`:
//!
//! ```
//! use admm_ta_agents::numerics::two_block::{Multipliers, TwoBlockAdmm};
//! use faer::Mat;
//! let a = [1.5, -2.0, 0.25];
//! let mut admm = TwoBlockAdmm::builder(Mat::identity(3, 3), -Mat::<f64>::identity(3, 3), vec![0.0; 3])
//!     .rho(1.0)
//!     .multipliers(Multipliers::Unscaled)
//!     .tolerances(1e-10, 1e-10)
//!     .build()
//!     .unwrap();
//! // x-update: argmin ½‖x − a‖² + (ρ/2)‖x + v‖²  ⇒  x = (a − ρ v)/(1 + ρ).
//! let x_min = |v: &[f64], rho: f64, x: &mut [f64]| {
//!     for i in 0..3 { x[i] = (a[i] - rho * v[i]) / (1.0 + rho); }
//! };
//! // z-update: argmin I(z ≥ 0) + (ρ/2)‖−z + w‖²  ⇒  z = max(w, 0).
//! let z_min = |w: &[f64], _rho: f64, z: &mut [f64]| {
//!     for i in 0..3 { z[i] = w[i].max(0.0); }
//! };
//! let result = admm.solve(x_min, z_min);
//! assert!(result.converged);
//! let z = admm.z();
//! assert!((z[0] - 1.5).abs() < 1e-5 && z[1].abs() < 1e-5 && (z[2] - 0.25).abs() < 1e-5);
//! ```
//!
//! A lasso (`min ½‖D x − y‖² + κ‖z‖₁`, `x − z = 0`: a factored linear solve and soft
//! thresholding) is worked in `agents/examples/two_block_lasso.rs`, which prints the
//! recovered coefficients and the optimality conditions
//! (`cargo run -p admm-ta-agents --example two_block_lasso`); `agents/tests/all/two_block_lasso.rs`
//! checks both multiplier forms against those conditions.

use faer::{Mat, MatRef};

/// How the multiplier is stored and reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Multipliers {
    /// `u = λ/ρ` (Boyd et al. §3.1.1).
    #[default]
    Scaled,
    /// `λ` itself (the tutorial's form).
    Unscaled,
}

/// Problems with the problem data or the settings.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TwoBlockError {
    #[error("A has {a} rows, B has {b} rows and c has {c} entries: they must be equal")]
    Shape { a: usize, b: usize, c: usize },
    #[error("ρ must be positive and finite, got {0}")]
    Rho(f64),
    #[error("tolerances must be non-negative and finite, with at least one positive")]
    Tolerance,
    #[error("the problem data contain a NaN or infinite value")]
    NonFinite,
}

/// Builder of a [`TwoBlockAdmm`].
pub struct TwoBlockBuilder {
    a: Mat<f64>,
    b: Mat<f64>,
    c: Vec<f64>,
    rho: f64,
    multipliers: Multipliers,
    eps_abs: f64,
    eps_rel: f64,
    max_iterations: usize,
}

impl TwoBlockBuilder {
    pub fn rho(mut self, rho: f64) -> Self {
        self.rho = rho;
        self
    }
    pub fn multipliers(mut self, multipliers: Multipliers) -> Self {
        self.multipliers = multipliers;
        self
    }
    /// Absolute and relative tolerances of the stopping test (default 1e-6, 1e-4).
    pub fn tolerances(mut self, absolute: f64, relative: f64) -> Self {
        self.eps_abs = absolute;
        self.eps_rel = relative;
        self
    }
    pub fn max_iterations(mut self, iterations: usize) -> Self {
        self.max_iterations = iterations;
        self
    }

    pub fn build(self) -> Result<TwoBlockAdmm, TwoBlockError> {
        let p = self.c.len();
        if self.a.nrows() != p || self.b.nrows() != p {
            return Err(TwoBlockError::Shape {
                a: self.a.nrows(),
                b: self.b.nrows(),
                c: p,
            });
        }
        if !(self.rho > 0.0 && self.rho.is_finite()) {
            return Err(TwoBlockError::Rho(self.rho));
        }
        let tolerances_ok = [self.eps_abs, self.eps_rel]
            .iter()
            .all(|t| *t >= 0.0 && t.is_finite())
            && (self.eps_abs > 0.0 || self.eps_rel > 0.0);
        if !tolerances_ok {
            return Err(TwoBlockError::Tolerance);
        }
        let finite =
            |m: &Mat<f64>| (0..m.ncols()).all(|j| (0..m.nrows()).all(|i| m[(i, j)].is_finite()));
        if !finite(&self.a) || !finite(&self.b) || self.c.iter().any(|v| !v.is_finite()) {
            return Err(TwoBlockError::NonFinite);
        }
        let (n, q) = (self.a.ncols(), self.b.ncols());
        Ok(TwoBlockAdmm {
            x: vec![0.0; n],
            z: vec![0.0; q],
            z_previous: vec![0.0; q],
            multiplier: vec![0.0; p],
            offset: vec![0.0; p],
            ax: vec![0.0; p],
            bz: vec![0.0; p],
            dual: vec![0.0; n],
            scratch: vec![0.0; p],
            a: self.a,
            b: self.b,
            c: self.c,
            rho: self.rho,
            multipliers: self.multipliers,
            eps_abs: self.eps_abs,
            eps_rel: self.eps_rel,
            max_iterations: self.max_iterations,
            iterations: 0,
        })
    }
}

/// Residuals of one iteration and the thresholds they are held to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Residuals {
    pub primal: f64,
    pub dual: f64,
    pub primal_threshold: f64,
    pub dual_threshold: f64,
}

impl Residuals {
    pub fn converged(&self) -> bool {
        self.primal <= self.primal_threshold && self.dual <= self.dual_threshold
    }
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoBlockResult {
    pub iterations: usize,
    pub converged: bool,
    pub residuals: Residuals,
}

/// Two-block ADMM state and workspace.
pub struct TwoBlockAdmm {
    a: Mat<f64>,
    b: Mat<f64>,
    c: Vec<f64>,
    rho: f64,
    multipliers: Multipliers,
    eps_abs: f64,
    eps_rel: f64,
    max_iterations: usize,
    x: Vec<f64>,
    z: Vec<f64>,
    z_previous: Vec<f64>,
    /// `u` (scaled) or `λ` (unscaled).
    multiplier: Vec<f64>,
    offset: Vec<f64>,
    ax: Vec<f64>,
    bz: Vec<f64>,
    dual: Vec<f64>,
    scratch: Vec<f64>,
    iterations: usize,
}

/// A block minimiser: `(offset, ρ, out)`, see the module docs.
pub type Minimiser<'a> = dyn FnMut(&[f64], f64, &mut [f64]) + 'a;

/// `out = M v`.
fn apply(m: MatRef<'_, f64>, v: &[f64], out: &mut [f64]) {
    out.fill(0.0);
    for (j, vj) in v.iter().enumerate() {
        for (i, o) in out.iter_mut().enumerate() {
            *o += m[(i, j)] * vj;
        }
    }
}

/// `out = Mᵀ v`.
fn apply_transpose(m: MatRef<'_, f64>, v: &[f64], out: &mut [f64]) {
    for (j, o) in out.iter_mut().enumerate() {
        *o = (0..m.nrows()).map(|i| m[(i, j)] * v[i]).sum();
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl TwoBlockAdmm {
    /// `minimise f(x) + g(z) s.t. A x + B z = c`; defaults ρ = 1, scaled multipliers,
    /// tolerances 1e-6 / 1e-4, 10 000 iterations.
    pub fn builder(a: Mat<f64>, b: Mat<f64>, c: Vec<f64>) -> TwoBlockBuilder {
        TwoBlockBuilder {
            a,
            b,
            c,
            rho: 1.0,
            multipliers: Multipliers::Scaled,
            eps_abs: 1e-6,
            eps_rel: 1e-4,
            max_iterations: 10_000,
        }
    }

    pub fn x(&self) -> &[f64] {
        &self.x
    }
    pub fn z(&self) -> &[f64] {
        &self.z
    }
    /// The unscaled multiplier `λ` of `A x + B z = c`, whichever form is stored.
    pub fn lambda(&self) -> Vec<f64> {
        match self.multipliers {
            Multipliers::Scaled => self.multiplier.iter().map(|u| self.rho * u).collect(),
            Multipliers::Unscaled => self.multiplier.clone(),
        }
    }
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// `u` whatever the stored form.
    fn scaled(&self, k: usize) -> f64 {
        match self.multipliers {
            Multipliers::Scaled => self.multiplier[k],
            Multipliers::Unscaled => self.multiplier[k] / self.rho,
        }
    }

    /// One iteration; returns its residuals.
    pub fn step(
        &mut self,
        x_minimiser: &mut Minimiser<'_>,
        z_minimiser: &mut Minimiser<'_>,
    ) -> Residuals {
        let rho = self.rho;
        // x-update with v = B z − c + u.
        for k in 0..self.c.len() {
            self.offset[k] = self.bz[k] - self.c[k] + self.scaled(k);
        }
        x_minimiser(&self.offset, rho, &mut self.x);
        apply(self.a.as_ref(), &self.x, &mut self.ax);
        // z-update with w = A x − c + u.
        for k in 0..self.c.len() {
            self.offset[k] = self.ax[k] - self.c[k] + self.scaled(k);
        }
        self.z_previous.copy_from_slice(&self.z);
        z_minimiser(&self.offset, rho, &mut self.z);
        apply(self.b.as_ref(), &self.z, &mut self.bz);
        // Multiplier update and residuals.
        let mut primal = 0.0;
        for k in 0..self.c.len() {
            let r = self.ax[k] + self.bz[k] - self.c[k];
            primal += r * r;
            self.multiplier[k] += match self.multipliers {
                Multipliers::Scaled => r,
                Multipliers::Unscaled => rho * r,
            };
        }
        for (previous, new) in self.z_previous.iter_mut().zip(&self.z) {
            *previous = new - *previous;
        }
        // z_previous now holds z^{k+1} − z^k.
        apply(self.b.as_ref(), &self.z_previous, &mut self.scratch);
        apply_transpose(self.a.as_ref(), &self.scratch, &mut self.dual);
        let dual = rho * norm(&self.dual);
        let lambda_scale = match self.multipliers {
            Multipliers::Scaled => rho,
            Multipliers::Unscaled => 1.0,
        };
        for (s, m) in self.scratch.iter_mut().zip(&self.multiplier) {
            *s = lambda_scale * m;
        }
        apply_transpose(self.a.as_ref(), &self.scratch, &mut self.dual);
        let (p, n) = (self.c.len() as f64, self.x.len() as f64);
        let primal_threshold = p.sqrt() * self.eps_abs
            + self.eps_rel * norm(&self.ax).max(norm(&self.bz)).max(norm(&self.c));
        let dual_threshold = n.sqrt() * self.eps_abs + self.eps_rel * norm(&self.dual);
        self.iterations += 1;
        Residuals {
            primal: primal.sqrt(),
            dual,
            primal_threshold,
            dual_threshold,
        }
    }

    /// Iterates until the residual test passes or the iteration limit.
    pub fn solve(
        &mut self,
        mut x_minimiser: impl FnMut(&[f64], f64, &mut [f64]),
        mut z_minimiser: impl FnMut(&[f64], f64, &mut [f64]),
    ) -> TwoBlockResult {
        let mut residuals = Residuals {
            primal: f64::INFINITY,
            dual: f64::INFINITY,
            primal_threshold: 0.0,
            dual_threshold: 0.0,
        };
        for _ in 0..self.max_iterations {
            residuals = self.step(&mut x_minimiser, &mut z_minimiser);
            if residuals.converged() {
                return TwoBlockResult {
                    iterations: self.iterations,
                    converged: true,
                    residuals,
                };
            }
        }
        TwoBlockResult {
            iterations: self.iterations,
            converged: false,
            residuals,
        }
    }
}
