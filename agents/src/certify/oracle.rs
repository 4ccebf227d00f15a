//! Centralized optimum of Problem 1, the reference every distributed run is checked against.
//!
//! * Case 1 (`n = m`): a square linear sum assignment ([`crate::numerics::lsap`]).
//! * Case 2 (`n > m`, every task at least one robot): any feasible assignment picks, for
//!   every task, one distinct *covering* robot, and sends each remaining robot to its
//!   cheapest task. So the optimum is an `n × n` assignment over `m` task columns plus
//!   `n − m` identical *free* columns whose cost for robot `i` is `min_t α_i[t]`: exact,
//!   with no big-M and no integer programming.
//! * `idle`: the rectangular assignment itself (the smaller side saturated), no padding.
//!
//! Forbidden pairs are `+∞` for the solver (as in scipy); [`solve`] works on the user's
//! exact numbers (sign-adjusted), not the normalised ones, so it resolves any finite range.

use crate::numerics::lsap::{self, LsapError};
use crate::problem::normalise::signed;
use crate::problem::{AssignmentCase, CostMatrix, IDLE, TaskAssignmentProblem};

/// An optimal assignment and its cost.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimalAssignment {
    /// Task of each robot ([`IDLE`] for an idle robot).
    pub assignment: Vec<usize>,
    /// In the problem's own numbers (a profit total when maximising).
    pub cost: f64,
}

/// Solves Problem 1 exactly (see the module docs for Case 2).
pub fn solve(problem: &TaskAssignmentProblem) -> Result<OptimalAssignment, LsapError> {
    let n = problem.robots();
    let (values, columns, case) = exact_costs(problem);
    let internal = solve_values(&values, n, columns, case)?;
    let assignment = problem.from_internal(&internal);
    let cost = problem
        .cost_of(&assignment)
        .map_err(|_| LsapError::Infeasible)?;
    Ok(OptimalAssignment { assignment, cost })
}

/// The exact costs in the minimisation sign, forbidden pairs `+∞` (no loss of precision),
/// with the problem's own shape and case.
fn exact_costs(problem: &TaskAssignmentProblem) -> (Vec<f64>, usize, AssignmentCase) {
    let (n, m) = (problem.robots(), problem.tasks());
    let costs = problem.costs();
    let values = (0..n * m)
        .map(|k| {
            let (i, t) = (k / m, k % m);
            if costs.is_allowed(i, t) {
                signed(problem.maximize(), costs.get(i, t))
            } else {
                f64::INFINITY
            }
        })
        .collect();
    (values, m, problem.case())
}

/// Optimal task per robot for the given costs and case; pairs the matrix does not allow
/// are never used ([`IDLE`] for robots left out in `idle` with `n > m`).
pub fn solve_costs(costs: &CostMatrix, case: AssignmentCase) -> Result<Vec<usize>, LsapError> {
    let (n, m) = (costs.robots(), costs.tasks());
    let values: Vec<f64> = if costs.has_forbidden() {
        (0..n * m)
            .map(|k| {
                if costs.is_allowed(k / m, k % m) {
                    costs.values()[k]
                } else {
                    f64::INFINITY
                }
            })
            .collect()
    } else {
        costs.values().to_vec()
    };
    solve_values(&values, n, m, case)
}

/// [`solve_costs`] on row-major values (`+∞`: forbidden).
pub fn solve_values(
    values: &[f64],
    n: usize,
    m: usize,
    case: AssignmentCase,
) -> Result<Vec<usize>, LsapError> {
    if case != AssignmentCase::Two || n == m {
        let cols = lsap::solve(values, n, m)?;
        let assignment: Vec<usize> = cols.into_iter().map(|c| c.unwrap_or(IDLE)).collect();
        if case != AssignmentCase::Idle && assignment.contains(&IDLE) {
            return Err(LsapError::Infeasible);
        }
        return Ok(assignment);
    }
    let cheapest: Vec<usize> = (0..n)
        .map(|i| argmin(&values[i * m..(i + 1) * m]))
        .collect();
    let mut expanded = vec![0.0; n * n];
    for i in 0..n {
        let row = &mut expanded[i * n..(i + 1) * n];
        row[..m].copy_from_slice(&values[i * m..(i + 1) * m]);
        row[m..].fill(values[i * m + cheapest[i]]);
    }
    let cols = lsap::solve(&expanded, n, n)?;
    cols.into_iter()
        .enumerate()
        .map(|(i, c)| match c {
            Some(c) if c < m => Ok(c),
            Some(_) if values[i * m + cheapest[i]].is_finite() => Ok(cheapest[i]),
            _ => Err(LsapError::Infeasible),
        })
        .collect()
}

/// Index of the smallest value in the total order (the first one on ties).
pub fn argmin(values: &[f64]) -> usize {
    let mut best = 0;
    for (k, v) in values.iter().enumerate() {
        if v.total_cmp(&values[best]).is_lt() {
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
