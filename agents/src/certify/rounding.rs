//! From relaxed iterates to assignments that are always feasible.
//!
//! * [`local_assignment`]: robot `i` rounds its *own* matrix `X_i` to the feasible
//!   assignment closest to it (an assignment problem maximising `Σ X_i[t, j]`; in Case 2
//!   with the free-column expansion of [`crate::certify::oracle`]) and keeps its own task. Robots
//!   holding the same matrix make the same, consistent choice; at convergence to a unique
//!   optimum it is the optimum.
//! * [`argmax_assignment`]: the cheap per-column argmax, used every round by stop rules.
//! * [`repair`]: when the robots' choices conflict (not converged, or ties), the team's
//!   assignment is repaired deterministically: the feasible assignment changing the fewest
//!   robots, then cheapest among those.

use crate::certify::oracle;
use crate::problem::{AssignmentCase, IDLE, TaskAssignmentProblem};

/// The feasible assignment closest to `x` (column-major `tasks × robots`). Non-finite
/// entries (which a diverging iterate could hold) count as 0, so this never fails on a
/// shape the case admits.
pub fn local_assignment(
    x: &[f64],
    tasks: usize,
    robots: usize,
    case: AssignmentCase,
) -> Vec<usize> {
    let negated: Vec<f64> = (0..robots)
        .flat_map(|j| {
            x[j * tasks..(j + 1) * tasks]
                .iter()
                .map(|v| if v.is_finite() { -v } else { 0.0 })
        })
        .collect();
    oracle::solve_values(&negated, robots, tasks, case)
        .unwrap_or_else(|_| fallback(robots, tasks, case))
}

/// A feasible assignment of a shape without forbidden pairs (robot `i` takes task `i mod m`
/// or `i`), for the unreachable case where the solver fails.
fn fallback(robots: usize, tasks: usize, case: AssignmentCase) -> Vec<usize> {
    (0..robots)
        .map(|i| match case {
            AssignmentCase::Idle if i >= tasks => IDLE,
            _ => i % tasks,
        })
        .collect()
}

/// Per-column argmax of `x` (first on ties) into `out` (one task per robot).
pub fn argmax_assignment(x: &[f64], tasks: usize, out: &mut [usize]) {
    for (j, slot) in out.iter_mut().enumerate() {
        *slot = argmax(&x[j * tasks..(j + 1) * tasks]);
    }
}

/// Index of the largest entry in the total order (the first on ties; 0 for an empty slice);
/// `NaN` never wins.
pub fn argmax(column: &[f64]) -> usize {
    let mut best = 0;
    for (t, v) in column.iter().enumerate() {
        let current = column[best];
        if !v.is_nan() && (current.is_nan() || v.total_cmp(&current).is_gt()) {
            best = t;
        }
    }
    best
}

/// Whether `assignment` covers the tasks as `case` requires; `load` is scratch of length
/// `tasks`.
pub fn covers(assignment: &[usize], case: AssignmentCase, load: &mut [u32]) -> bool {
    load.fill(0);
    for &t in assignment {
        if t >= load.len() {
            return false;
        }
        load[t] += 1;
    }
    match case {
        AssignmentCase::One => load.iter().all(|&l| l == 1),
        AssignmentCase::Two => load.iter().all(|&l| l >= 1),
        AssignmentCase::Idle => load.iter().all(|&l| l <= 1),
    }
}

/// Makes the robots' choices a feasible assignment on allowed pairs. Returns it and whether
/// anything had to change. The assignment changes the fewest robots, then is cheapest;
/// forbidden pairs are never used.
pub fn repair(problem: &TaskAssignmentProblem, decisions: &[usize]) -> (Vec<usize>, bool) {
    if problem.is_feasible(decisions) {
        return (decisions.to_vec(), false);
    }
    let costs = problem.costs();
    let (n, m) = (problem.robots(), problem.tasks());
    let (lo, hi) = costs
        .allowed_values()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c), hi.max(c))
        });
    let sign = if problem.maximize() { -1.0 } else { 1.0 };
    let spread = if hi > lo { hi - lo } else { 1.0 };
    // Costs normalised to [0, 1]; moving one robot more costs more than any difference in
    // assignment cost.
    let penalty = n as f64 + 1.0;
    let values: Vec<f64> = (0..n * m)
        .map(|k| {
            let (i, t) = (k / m, k % m);
            if !costs.is_allowed(i, t) {
                return f64::INFINITY;
            }
            let base = if sign > 0.0 {
                (costs.get(i, t) - lo) / spread
            } else {
                (hi - costs.get(i, t)) / spread
            };
            let keep = decisions.get(i) == Some(&t);
            base.clamp(0.0, 1.0) + if keep { 0.0 } else { penalty }
        })
        .collect();
    match oracle::solve_values(&values, n, m, problem.case()) {
        Ok(assignment) => (assignment, true),
        // Hall's condition was checked when the problem was built; the exact optimum then
        // exists.
        Err(_) => match oracle::solve(problem) {
            Ok(optimum) => (optimum.assignment, true),
            Err(_) => (decisions.to_vec(), false),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{CaseChoice, CostMatrix};

    #[test]
    fn repair_changes_fewest_robots() {
        let costs = CostMatrix::uniform(4, 4, 2).unwrap();
        let p = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        let (same, repaired) = repair(&p, &[3, 2, 1, 0]);
        assert_eq!((same, repaired), (vec![3, 2, 1, 0], false));
        // Robots 0 and 1 both chose task 0; task 1 is free: one robot moves.
        let (fixed, repaired) = repair(&p, &[0, 0, 2, 3]);
        assert!(repaired && p.is_feasible(&fixed));
        assert_eq!(
            fixed
                .iter()
                .zip([0, 0, 2, 3])
                .filter(|(a, b)| **a != *b)
                .count(),
            1
        );
    }

    #[test]
    fn local_assignment_is_feasible_for_fractional_iterates() {
        // Case 2, 3 robots, 2 tasks; every column prefers task 0.
        let x = [0.9, 0.1, 0.8, 0.2, 0.6, 0.4];
        let a = local_assignment(&x, 2, 3, AssignmentCase::Two);
        assert_eq!(a, vec![0, 0, 1]);
        let mut out = [0; 3];
        argmax_assignment(&x, 2, &mut out);
        assert_eq!(out, [0, 0, 0]);
        assert!(!covers(&out, AssignmentCase::Two, &mut [0; 2]));
    }
}
