//! What both dual agents do with a robot's own column: centre its costs on its allowed
//! tasks, round the column to a task, and report a step.

use crate::agent::StepReport;

/// The robot's costs minus their mean over its allowed tasks (0 at forbidden ones). Each
/// robot does exactly one task, so a shift of its own costs changes every assignment's cost
/// alike: centred, the iterates do not depend on cost shifts. At least one task is allowed.
pub fn centred(costs: &[f64], allowed: &[bool]) -> Vec<f64> {
    assert_eq!(costs.len(), allowed.len(), "one flag per task");
    let count = allowed.iter().filter(|&&a| a).count();
    assert!(count > 0, "a robot needs an allowed task");
    let mean = costs
        .iter()
        .zip(allowed)
        .filter(|(_, a)| **a)
        .map(|(c, _)| c)
        .sum::<f64>()
        / count as f64;
    costs
        .iter()
        .zip(allowed)
        .map(|(c, &a)| if a { c - mean } else { 0.0 })
        .collect()
}

/// The allowed task with the largest entry of `x` (the first on ties).
pub fn round(x: &[f64], allowed: &[bool]) -> usize {
    let mut best = None;
    for t in (0..x.len()).filter(|&t| allowed[t]) {
        if best.is_none_or(|b: usize| x[t] > x[b]) {
            best = Some(t);
        }
    }
    best.expect("a robot has an allowed task")
}

/// A dual agent's step report: its column `x` against its `task`, the neighbours'
/// `disagreement`, and the change from its multipliers `before` to those it sends `now`.
pub fn report(
    x: &[f64],
    task: usize,
    disagreement: f64,
    now: &[f64],
    before: &[f64],
) -> StepReport {
    let change = now
        .iter()
        .zip(before)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let gap = x
        .iter()
        .enumerate()
        .map(|(t, v)| (v - if t == task { 1.0 } else { 0.0 }).abs())
        .fold(0.0, f64::max);
    StepReport {
        disagreement,
        change,
        // The x-update is closed form (exact root or one gradient step): no inner loop.
        inner_iterations: 0,
        inner_converged: true,
        integrality_gap: gap,
        own_integrality_gap: gap,
        // No view of the team's assignment: neighbours always "agree", the certificate
        // alone decides.
        assignment_digest: 0,
    }
}
