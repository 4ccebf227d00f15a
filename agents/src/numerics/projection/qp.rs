//! The general path of the x-update: a clarabel QP.
//!
//! Solves `min ½‖X − Z‖²_F` over `{ X : Σ_j A_j X e_j = b, Σ_j C_j X e_j ≤ d,
//! lower ≤ X ≤ upper }` — the primal ADMM x-update (8) for any Problem 2 instance. For the
//! task assignment mappings it is the same projection as the fast path, so it serves as its
//! cross-check. It allocates and factors on every call (≈ 10 ms at 50×50): not for hot loops.

use crate::problem::general::GeneralProblem;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
    ZeroConeT,
};

/// The QP solver did not return a solution.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum QpError {
    #[error("clarabel could not set up the QP: {0}")]
    Setup(String),
    #[error("clarabel stopped with status {0}")]
    NotSolved(String),
}

/// A projection QP with its constraint data built once.
pub struct QpProjector {
    variables: usize,
    a: CscMatrix<f64>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
}

impl QpProjector {
    /// Builds the constraints of `problem` for `X ∈ R^{dim × robots}` (column-major).
    pub fn new(problem: &GeneralProblem) -> Self {
        let (m, n) = (problem.dim, problem.robots());
        let variables = m * n;
        let (mut rows, mut cols, mut vals, mut b) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut next_row = 0;
        let mut coupling =
            |mats: &[Vec<f64>], rhs: &[f64], rows: &mut Vec<usize>, b: &mut Vec<f64>| {
                for (l, &value) in rhs.iter().enumerate() {
                    for (j, mat) in mats.iter().enumerate() {
                        for t in 0..m {
                            let coefficient = mat[l * m + t];
                            if coefficient != 0.0 {
                                rows.push(next_row);
                                cols.push(j * m + t);
                                vals.push(coefficient);
                            }
                        }
                    }
                    b.push(value);
                    next_row += 1;
                }
            };
        coupling(&problem.a, &problem.b, &mut rows, &mut b);
        coupling(&problem.c, &problem.d, &mut rows, &mut b);
        let equalities = problem.b.len();
        let inequalities = problem.d.len();
        // Box: x ≤ upper and −x ≤ −lower.
        for k in 0..variables {
            rows.extend([next_row + k, next_row + variables + k]);
            cols.extend([k, k]);
            vals.extend([1.0, -1.0]);
        }
        b.extend(std::iter::repeat_n(problem.upper, variables));
        b.extend(std::iter::repeat_n(-problem.lower, variables));
        let total_rows = next_row + 2 * variables;
        let a = CscMatrix::new_from_triplets(total_rows, variables, rows, cols, vals);
        let mut cones = Vec::new();
        if equalities > 0 {
            cones.push(ZeroConeT(equalities));
        }
        cones.push(NonnegativeConeT(inequalities + 2 * variables));
        Self {
            variables,
            a,
            b,
            cones,
        }
    }

    /// Writes the projection of `z` (column-major) into `out`.
    pub fn project(&self, z: &[f64], out: &mut [f64]) -> Result<(), QpError> {
        assert_eq!(z.len(), self.variables);
        assert_eq!(out.len(), self.variables);
        let p = CscMatrix::identity(self.variables);
        let q: Vec<f64> = z.iter().map(|v| -v).collect();
        let settings = DefaultSettings {
            verbose: false,
            tol_gap_abs: 1e-11,
            tol_gap_rel: 1e-11,
            tol_feas: 1e-11,
            max_iter: 500,
            ..DefaultSettings::default()
        };
        let mut solver = DefaultSolver::new(&p, &q, &self.a, &self.b, &self.cones, settings)
            .map_err(|e| QpError::Setup(format!("{e:?}")))?;
        solver.solve();
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                out.copy_from_slice(&solver.solution.x);
                Ok(())
            }
            status => Err(QpError::NotSolved(format!("{status:?}"))),
        }
    }
}
