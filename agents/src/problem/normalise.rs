//! The problem the agents solve, built from the user's: every number they see is a
//! normalised cost.
//!
//! * **Sign**: profits (`--maximize`) are negated, so everything below minimises.
//! * **Shift and scale**: the allowed costs are mapped to `[0, 1]` (`w = (c − lo) / (hi − lo)`;
//!   constant costs map to 0, so no rule ever divides by a zero spread). The methods' scale
//!   rules (ρ, γ, the certificate tolerance, the tie-breaking perturbation) then see a spread
//!   of order 1 whatever the user's units: 1-ulp-apart costs become a lattice the
//!   perturbation separates, costs in metres or in `[0, 1)` give the same run.
//! * **Forbidden pairs** hold the penalty `2·max(n, m) + 4` and are flagged in the mask: any
//!   assignment using one costs more than every allowed assignment (each of the at most
//!   `max(n, m)` agents' pairs costs
//!   at most 2, plus a perturbation below 1 in total), so the LP optimum, and every method
//!   that reaches it, never puts weight on them; rounding, repair and the oracle treat them
//!   as `+∞`. The scale rules read the allowed entries only.
//! * **Idle robots** (`idle` with `n > m`): one extra *idle* task of cost 0, the real tasks'
//!   costs raised by 1 to `[1, 2]`, and Case 2 (every task at least one robot): a second
//!   robot on a real task costs at least 1 more than idling, so the optimum puts exactly one
//!   robot on every real task and the rest on the idle task — scipy's meaning, solved by
//!   every method, with a single idle column (no ties between identical idle columns).
//! * **Unserved tasks** (`idle` with `n < m`): the problem is *transposed*, then reduced as
//!   above: the `m` tasks are the agents (each hosted by a robot, see the runtime) and the
//!   `n` robots plus the idle column are their "tasks", Case 2 on `m × (n + 1)`. Every
//!   robot's column gets exactly one task at the optimum and the other `m − n` tasks idle
//!   (unserved): scipy's meaning, with the single idle column's non-degenerate optimum that
//!   every method certifies (phantom robots, one per unserved task, would be `m − n`
//!   identical zero-cost rows whose ties no certificate resolves on generic costs).
//!
//! [`resolution`] decides whether floating-point methods can resolve the normalised costs.

use crate::problem::costs::{AssignmentCase, CostMatrix, ProblemError};
use crate::problem::feasibility::{AllowedGraph, Saturate, blocking_set, maximum_matching};

/// Normalised values below this (but above 0) are beyond what the floating-point methods
/// resolve next to the spread of 1 (their certificate tolerance is `1e-9 · n · spread`).
pub const RESOLUTION: f64 = 1e-7;

/// Refuses a problem without an assignment that the case accepts on allowed pairs, with one
/// sentence naming a blocking set.
pub fn check_hall(costs: &CostMatrix, case: AssignmentCase) -> Result<(), ProblemError> {
    let (n, m) = (costs.robots(), costs.tasks());
    let mask = costs.allowed_mask();
    if matches!(case, AssignmentCase::Two)
        && let Some(robot) = (0..n).find(|&i| (0..m).all(|t| !mask[i * m + t]))
    {
        return Err(ProblemError::Infeasible(format!(
            "robot {robot} has no allowed task"
        )));
    }
    let graph = AllowedGraph::from_mask(n, m, &mask);
    let matching = maximum_matching(&graph);
    let side = match case {
        AssignmentCase::Idle if n < m => Saturate::Robots,
        _ => Saturate::Tasks,
    };
    match blocking_set(&graph, &matching, side) {
        Some(sentence) => Err(ProblemError::Infeasible(sentence)),
        None => Ok(()),
    }
}

/// The map of the allowed costs `[lo, hi]` (minimisation sign) onto `[0, 1]`: `(c − lo) /
/// (hi − lo)`, 0 for constant costs, in halves for spreads beyond the largest double.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitMap {
    lo: f64,
    /// `hi − lo`, or `hi/2 − lo/2` in halves.
    scale: f64,
    halves: bool,
}

impl UnitMap {
    pub fn new(lo: f64, hi: f64) -> Self {
        // Halves keep `hi − lo` finite for spreads beyond the largest double.
        let halves = !(hi - lo).is_finite();
        let scale = if halves { hi / 2.0 - lo / 2.0 } else { hi - lo };
        Self { lo, scale, halves }
    }

    /// `c` in `[0, 1]`.
    pub fn map(&self, c: f64) -> f64 {
        if self.scale <= 0.0 {
            0.0
        } else if self.halves {
            ((c / 2.0 - self.lo / 2.0) / self.scale).clamp(0.0, 1.0)
        } else {
            ((c - self.lo) / self.scale).clamp(0.0, 1.0)
        }
    }
}

/// Costs in the minimisation sign: `c`, or `−c` for profits.
pub fn signed(maximize: bool, value: f64) -> f64 {
    if maximize { -value } else { value }
}

/// The shape of the problem the agents solve: its tasks (with the idle task) and case, and
/// whether it has the idle task.
pub fn internal_shape(n: usize, m: usize, case: AssignmentCase) -> (usize, AssignmentCase, bool) {
    match case {
        AssignmentCase::Idle if n < m => (n + 1, AssignmentCase::Two, true),
        AssignmentCase::Idle if n > m => (m + 1, AssignmentCase::Two, true),
        AssignmentCase::Idle => (m, AssignmentCase::One, false),
        case => (m, case, false),
    }
}

/// Whether the agents solve the transposed problem (`idle` with fewer robots than tasks:
/// the tasks are the agents).
pub fn transposed(n: usize, m: usize, case: AssignmentCase) -> bool {
    case == AssignmentCase::Idle && n < m
}

/// The normalised problem's parts, and how its costs relate to the user's.
#[derive(Debug, Clone, PartialEq)]
pub struct Parts {
    pub matrix: CostMatrix,
    pub case: AssignmentCase,
    pub shift: f64,
    pub scale: f64,
    pub raise: f64,
    pub unresolved: Option<String>,
}

/// The normalised problem (see the module docs) of the user's costs.
pub fn normalise(
    costs: &CostMatrix,
    case: AssignmentCase,
    maximize: bool,
) -> Result<Parts, ProblemError> {
    let (n, m) = (costs.robots(), costs.tasks());
    let (lo, hi) = costs
        .allowed_values()
        .map(|v| signed(maximize, v))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) };
    let unit = UnitMap::new(lo, hi);
    let normalise = |v: f64| unit.map(v);
    let (halves, scale) = (unit.halves, unit.scale);
    let (columns, internal_case, idle_task) = internal_shape(n, m, case);
    let raise = if idle_task { 1.0 } else { 0.0 };
    let transposed = transposed(n, m, case);
    // The agents: robots, or the tasks when transposed.
    let rows = if transposed { m } else { n };
    let penalty = 2.0 * n.max(m) as f64 + 4.0;
    // The idle column (the last, when there is one) stays at cost 0.
    let mut values = vec![0.0; rows * columns];
    let mut allowed = vec![true; rows * columns];
    for i in 0..n {
        for t in 0..m {
            let k = if transposed {
                t * columns + i
            } else {
                i * columns + t
            };
            if costs.is_allowed(i, t) {
                values[k] = raise + normalise(signed(maximize, costs.get(i, t)));
            } else {
                values[k] = penalty;
                allowed[k] = false;
            }
        }
    }
    let matrix = CostMatrix::with_mask(rows, columns, values, Some(allowed))?;
    let unresolved = resolution(&matrix, lo, hi, raise);
    Ok(Parts {
        matrix,
        case: internal_case,
        shift: lo,
        scale: if scale > 0.0 {
            if halves { 2.0 * scale } else { scale }
        } else {
            1.0
        },
        raise,
        unresolved,
    })
}

/// Why floating-point methods cannot resolve these normalised costs, or `None`: at least
/// 1% of the allowed costs (and two or more) are nonzero but below [`RESOLUTION`], i.e. the
/// differences that decide the optimum sit far below the spread (wide log-uniform ranges, a
/// big sentinel next to small costs). `lo`, `hi`: the user's range (minimisation sign);
/// `raise`: what the normalisation added to the real tasks' costs.
pub fn resolution(costs: &CostMatrix, lo: f64, hi: f64, raise: f64) -> Option<String> {
    let mut allowed = 0usize;
    let mut tiny = 0usize;
    let mut at_top = 0usize;
    let mut below_top = 0.0f64;
    let tasks = costs.tasks();
    let real = costs
        .allowed_values_indexed()
        .filter(|&(k, _)| raise == 0.0 || k % tasks + 1 < tasks)
        .map(|(_, w)| w - raise);
    for w in real {
        allowed += 1;
        if w > 0.0 && w < RESOLUTION {
            tiny += 1;
        }
        if w == 1.0 {
            at_top += 1;
        } else {
            below_top = below_top.max(w);
        }
    }
    if tiny < 2 || tiny * 100 < allowed {
        return None;
    }
    let sentinel = if at_top >= 2 && below_top < 1e-3 {
        format!("; if {hi:e} marks pairs that may not be used, write inf for them instead")
    } else {
        String::new()
    };
    Some(format!(
        "the costs span {lo:e} to {hi:e}: {tiny} of {allowed} allowed costs differ from the cheapest by less than {RESOLUTION:e} of that range, below what this method resolves in floating point (use --method hungarian or dist-hungarian, which solve the exact numbers{sentinel})"
    ))
}
