//! Centralized optimum of Problem 1, the reference every distributed run is checked against.
//!
//! * Case 1 (`n = m`): a square linear sum assignment ([`crate::lsap`]).
//! * Case 2 (`n > m`, every task at least one robot): any feasible assignment picks, for
//!   every task, one distinct *covering* robot, and sends each remaining robot to its
//!   cheapest task. So the optimum is an `n × n` assignment over `m` task columns plus
//!   `n − m` identical *free* columns whose cost for robot `i` is `min_t α_i[t]`: exact,
//!   with no big-M and no integer programming.

use crate::lsap::{self, LsapError};
use crate::problem::{AssignmentCase, CostMatrix, TaskAssignmentProblem};

/// An optimal assignment and its cost.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimalAssignment {
    /// Task of each robot.
    pub assignment: Vec<usize>,
    pub cost: f64,
}

/// Solves Problem 1 exactly (see the module docs for Case 2).
pub fn solve(problem: &TaskAssignmentProblem) -> Result<OptimalAssignment, LsapError> {
    let assignment = solve_costs(problem.costs(), problem.case())?;
    let cost = problem
        .cost_of(&assignment)
        .expect("oracle assignment is in range");
    Ok(OptimalAssignment { assignment, cost })
}

/// Optimal task per robot for the given costs and case (costs need not be validated).
pub fn solve_costs(costs: &CostMatrix, case: AssignmentCase) -> Result<Vec<usize>, LsapError> {
    let (n, m) = (costs.robots(), costs.tasks());
    if case == AssignmentCase::One || n == m {
        let cols = lsap::solve(costs.values(), n, m)?;
        return Ok(cols
            .into_iter()
            .map(|c| c.expect("square problem assigns every row"))
            .collect());
    }
    let cheapest: Vec<usize> = (0..n).map(|i| argmin(costs.row(i))).collect();
    let mut expanded = vec![0.0; n * n];
    for i in 0..n {
        let row = &mut expanded[i * n..(i + 1) * n];
        row[..m].copy_from_slice(costs.row(i));
        row[m..].fill(costs.get(i, cheapest[i]));
    }
    let cols = lsap::solve(&expanded, n, n)?;
    Ok(cols
        .into_iter()
        .enumerate()
        .map(
            |(i, c)| match c.expect("square expansion assigns every row") {
                c if c < m => c,
                _ => cheapest[i],
            },
        )
        .collect())
}

/// Index of the smallest value (the first one on ties).
pub fn argmin(values: &[f64]) -> usize {
    let mut best = 0;
    for (k, v) in values.iter().enumerate() {
        if *v < values[best] {
            best = k;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::CaseChoice;

    /// Enumerates every map robots → tasks (small sizes only).
    fn brute_force(problem: &TaskAssignmentProblem) -> f64 {
        let (n, m) = (problem.robots(), problem.tasks());
        let mut best = f64::INFINITY;
        let mut a = vec![0usize; n];
        loop {
            if problem.is_feasible(&a) {
                best = best.min(problem.cost_of(&a).unwrap());
            }
            let mut k = 0;
            while k < n {
                a[k] += 1;
                if a[k] < m {
                    break;
                }
                a[k] = 0;
                k += 1;
            }
            if k == n {
                return best;
            }
        }
    }

    #[test]
    fn case_two_expansion_is_exact() {
        for seed in 0..40 {
            let (n, m) = (3 + seed as usize % 4, 1 + seed as usize % 3);
            let costs = CostMatrix::uniform(n, m, seed).unwrap();
            let p = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
            let opt = solve(&p).unwrap();
            assert!(p.is_feasible(&opt.assignment));
            assert!((opt.cost - brute_force(&p)).abs() < 1e-12, "seed {seed}");
        }
    }
}
