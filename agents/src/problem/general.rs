//! Problem 2 of the paper: `min Σ_i f_i(x_i) + g_i(x_i)` subject to `Σ_i A_i x_i = b` and
//! `Σ_i C_i x_i ≤ d`, with linear `f_i(x) = α_iᵀx` and `g_i` the indicator of a box.
//!
//! The relaxed task assignment problem maps onto it by (3) (Case 1:
//! `A_i = [M_i; I_m]`, `b = 1_{n+m}`, `C_i = d = 0`) and (4) (Case 2: `A_i = M_i`,
//! `b = 1_n`, `C_i = −I_m`, `d = −1_m`), where `M_i ∈ R^{n×m}` has ones in row `i`. The
//! paper prints `b = 1_m` in (4); the `n` rows of `M_i` need `b = 1_n`.

use crate::problem::{AssignmentCase, TaskAssignmentProblem};

/// A dense Problem 2 instance with box `g_i = indicator(lower ≤ x ≤ upper)`.
#[derive(Debug, Clone, PartialEq)]
pub struct GeneralProblem {
    /// Variables per robot (`m`).
    pub dim: usize,
    /// Per robot `A_i`, row-major `l1 × dim`.
    pub a: Vec<Vec<f64>>,
    pub b: Vec<f64>,
    /// Per robot `C_i`, row-major `l2 × dim`.
    pub c: Vec<Vec<f64>>,
    pub d: Vec<f64>,
    /// Per robot linear cost `α_i`.
    pub alpha: Vec<Vec<f64>>,
    pub lower: f64,
    pub upper: f64,
}

impl GeneralProblem {
    pub fn robots(&self) -> usize {
        self.alpha.len()
    }

    /// The relaxation of a task assignment problem, by mapping (3) or (4).
    pub fn from_task_assignment(problem: &TaskAssignmentProblem) -> Self {
        let mut general =
            Self::assignment_constraints(problem.robots(), problem.tasks(), problem.case());
        general.alpha = (0..problem.robots())
            .map(|i| problem.costs().row(i).to_vec())
            .collect();
        general
    }

    /// Mapping (3) or (4) for `n` robots and `m` tasks, with zero costs: the constraint set
    /// every robot knows without knowing the others' costs.
    pub fn assignment_constraints(n: usize, m: usize, case: AssignmentCase) -> Self {
        let robot_row = |i: usize| {
            // M_i: ones in row i.
            let mut rows = vec![0.0; n * m];
            rows[i * m..(i + 1) * m].fill(1.0);
            rows
        };
        let identity = |sign: f64| {
            let mut rows = vec![0.0; m * m];
            for t in 0..m {
                rows[t * m + t] = sign;
            }
            rows
        };
        let alpha = vec![vec![0.0; m]; n];
        match case {
            AssignmentCase::One | AssignmentCase::Idle => Self {
                dim: m,
                a: (0..n)
                    .map(|i| [robot_row(i), identity(1.0)].concat())
                    .collect(),
                b: vec![1.0; n + m],
                c: vec![Vec::new(); n],
                d: Vec::new(),
                alpha,
                lower: 0.0,
                upper: 1.0,
            },
            AssignmentCase::Two => Self {
                dim: m,
                a: (0..n).map(robot_row).collect(),
                b: vec![1.0; n],
                c: vec![identity(-1.0); n],
                d: vec![-1.0; m],
                alpha,
                lower: 0.0,
                upper: 1.0,
            },
        }
    }

    /// Largest violation of the coupling constraints and the box by `x` (column-major
    /// `dim × robots`, column `i` is `x_i`).
    pub fn violation(&self, x: &[f64]) -> f64 {
        let (m, n) = (self.dim, self.robots());
        let mut worst: f64 = 0.0;
        for v in x {
            worst = worst.max(self.lower - v).max(v - self.upper);
        }
        let product = |mats: &[Vec<f64>], rows: usize| {
            let mut out = vec![0.0; rows];
            for i in 0..n {
                for (l, o) in out.iter_mut().enumerate() {
                    *o += (0..m)
                        .map(|t| mats[i][l * m + t] * x[i * m + t])
                        .sum::<f64>();
                }
            }
            out
        };
        for (lhs, rhs) in product(&self.a, self.b.len()).iter().zip(&self.b) {
            worst = worst.max((lhs - rhs).abs());
        }
        for (lhs, rhs) in product(&self.c, self.d.len()).iter().zip(&self.d) {
            worst = worst.max(lhs - rhs);
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{CaseChoice, CostMatrix};

    /// Column-major `m × n` indicator matrix of an assignment.
    fn indicator(assignment: &[usize], tasks: usize) -> Vec<f64> {
        let mut x = vec![0.0; tasks * assignment.len()];
        for (robot, &task) in assignment.iter().enumerate() {
            x[robot * tasks + task] = 1.0;
        }
        x
    }

    #[test]
    fn mappings_three_and_four_encode_the_assignment_constraints() {
        // Case 1, mapping (3): a permutation satisfies Σ A_i x_i = b; a collision does not.
        let square = CostMatrix::uniform(3, 3, 0).unwrap();
        let p1 = TaskAssignmentProblem::new(square, CaseChoice::Auto).unwrap();
        let g1 = GeneralProblem::from_task_assignment(&p1);
        assert_eq!((g1.b.len(), g1.d.len()), (6, 0));
        assert_eq!(g1.violation(&indicator(&[2, 0, 1], 3)), 0.0);
        assert_eq!(g1.violation(&indicator(&[0, 0, 1], 3)), 1.0);
        // Case 2, mapping (4) with b = 1_n: covering maps are feasible, uncovered tasks not.
        let tall = CostMatrix::uniform(4, 2, 0).unwrap();
        let p2 = TaskAssignmentProblem::new(tall, CaseChoice::Auto).unwrap();
        let g2 = GeneralProblem::from_task_assignment(&p2);
        assert_eq!((g2.b.len(), g2.d.len()), (4, 2));
        assert_eq!(g2.violation(&indicator(&[0, 1, 1, 1], 2)), 0.0);
        assert_eq!(g2.violation(&indicator(&[1, 1, 1, 1], 2)), 1.0);
        // The box g_i: entries outside [0, 1].
        let mut x = indicator(&[0, 1, 1, 1], 2);
        x[0] = 1.5;
        x[1] = -0.5;
        assert_eq!(g2.violation(&x), 0.5);
        assert_eq!(g2.alpha[3], p2.costs().row(3));
    }
}
