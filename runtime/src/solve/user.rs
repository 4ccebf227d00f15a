//! Between the user's problem and the normalised one the agents solve
//! ([`admm_ta_agents::problem::normalise`]): what each method can take, and the report in the user's
//! numbers (assignment with idle robots, cost, the exact check).

use crate::solve::error::SolveError;
use crate::solve::report::SolveReport;
use crate::solve::trace::Affine;
use admm_ta_agents::certify::oracle::OptimalAssignment;
use admm_ta_agents::method::info::Numbers;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::normalise;
use admm_ta_agents::problem::{IDLE, TaskAssignmentProblem};
use admm_ta_topologies::Graph;

/// Refuses, with one line, what `method` cannot solve faithfully.
pub(crate) fn check_supported(
    problem: &TaskAssignmentProblem,
    method: Method,
) -> Result<(), SolveError> {
    if method.info().numbers == Numbers::Normalised
        && let Some(why) = problem.normalised().and_then(|n| n.unresolved.as_ref())
    {
        return Err(SolveError::Unresolvable(format!(
            "--method {} cannot solve this problem faithfully: {why}",
            method.name()
        )));
    }
    Ok(())
}

/// User cost (minimisation sign) of a normalised cost.
pub(crate) fn affine(problem: &TaskAssignmentProblem) -> Affine {
    match problem.normalised() {
        None => Affine::IDENTITY,
        Some(n) => {
            let pairs = problem.robots().min(problem.tasks()) as f64;
            Affine {
                offset: (n.shift - n.scale * n.raise) * pairs,
                factor: n.scale,
            }
        }
    }
}

/// A user assignment on the internal shape: idle robots take the idle task; transposed
/// (`idle` with `n < m`), each task takes its robot or, unserved, the idle column `n`.
pub(crate) fn to_internal(problem: &TaskAssignmentProblem, assignment: &[usize]) -> Vec<usize> {
    let (n, m) = (problem.robots(), problem.tasks());
    if normalise::transposed(n, m, problem.case()) {
        let mut tasks = vec![n; m];
        for (robot, &task) in assignment.iter().enumerate() {
            if task < m {
                tasks[task] = robot;
            }
        }
        return tasks;
    }
    assignment
        .iter()
        .map(|&t| if t == IDLE { m } else { t })
        .collect()
}

/// The graph the agents run on: the user's, or for the transposed problem (`idle` with
/// `n < m`, the tasks are the agents, see [`admm_ta_agents::problem::normalise`]) task `t` hosted by
/// robot `t mod n`, and two tasks neighbours when their robots are the same or neighbours
/// (the user's graph, lifted: connected as it is, of the same diameter, complete when it is).
pub(crate) fn internal_graph(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
) -> Result<Graph, SolveError> {
    let (n, agents) = (graph.robots(), problem.internal().robots());
    if agents == n || problem.robots() != n {
        return Ok(graph.clone());
    }
    let linked = |a: usize, b: usize| {
        let (ha, hb) = (a % n, b % n);
        ha == hb || graph.neighbours(ha).binary_search(&hb).is_ok()
    };
    let edges: Vec<(usize, usize)> = (0..agents)
        .flat_map(|a| (a + 1..agents).map(move |b| (a, b)))
        .filter(|&(a, b)| linked(a, b))
        .collect();
    Graph::from_edges(
        agents,
        &edges,
        format!("{}, with the tasks as agents", graph.name()),
    )
    .map_err(|e| SolveError::Internal(format!("the tasks' graph: {e}")))
}

/// The exact optimum as the internal problem's assignment and cost.
pub(crate) fn internal_optimum(
    problem: &TaskAssignmentProblem,
    exact: &OptimalAssignment,
) -> Result<OptimalAssignment, SolveError> {
    let assignment = to_internal(problem, &exact.assignment);
    let cost = problem
        .internal()
        .cost_of(&assignment)
        .map_err(|e| SolveError::Internal(format!("the optimum does not map back: {e}")))?;
    Ok(OptimalAssignment { assignment, cost })
}

/// Whether `cost` is optimal against `optimum` (user numbers): within 1e-9 relative, with an
/// absolute floor of 1e-12 of the allowed costs' range.
pub(crate) fn is_optimal(problem: &TaskAssignmentProblem, cost: f64, optimum: f64) -> bool {
    let sign = if problem.maximize() { -1.0 } else { 1.0 };
    let range = problem.normalised().map_or(1.0, |n| n.scale);
    sign * (cost - optimum) <= (1e-9 * optimum.abs()).max(1e-12 * range)
}

/// The report of a run of the internal problem, in the user's numbers.
pub(crate) fn to_user(
    problem: &TaskAssignmentProblem,
    mut report: SolveReport,
    exact: Option<&OptimalAssignment>,
) -> Result<SolveReport, SolveError> {
    let assignment = match (report.method.team(), exact) {
        // The centralized solver's answer is the exact optimum of the user's numbers.
        (None, Some(exact)) => exact.assignment.clone(),
        _ => problem.from_internal(&report.assignment),
    };
    if !problem.is_feasible(&assignment) {
        return Err(SolveError::Internal(format!(
            "the {} run ended with an assignment that is not feasible for the problem",
            report.method.name()
        )));
    }
    report.cost = problem
        .cost_of(&assignment)
        .map_err(|e| SolveError::Internal(e.to_string()))?;
    let m = problem.tasks();
    let mut served = vec![false; m];
    for &t in assignment.iter().filter(|&&t| t != IDLE) {
        served[t] = true;
    }
    report.idle_robots = (0..assignment.len())
        .filter(|&i| assignment[i] == IDLE)
        .collect();
    report.unserved_tasks = (0..m).filter(|&t| !served[t]).collect();
    report.assignment = assignment;
    report.robots = problem.robots();
    report.tasks = m;
    report.case = problem.case();
    report.maximize = problem.maximize();
    if let (Some(check), Some(exact)) = (report.check.as_mut(), exact) {
        check.optimal_cost = exact.cost;
        check.optimal_profit = problem.maximize().then_some(exact.cost);
        let sign = if problem.maximize() { -1.0 } else { 1.0 };
        // `+ 0.0`: no "-0" gap for profits.
        let diff = sign * (report.cost - exact.cost) + 0.0;
        check.gap = if exact.cost != 0.0 {
            diff / exact.cost.abs()
        } else {
            diff
        };
        check.optimal = is_optimal(problem, report.cost, exact.cost);
    }
    report.certified = certified(&report);
    Ok(report)
}

/// Whether the method certifies its result optimal, as its registration declares: the
/// centralized solver always; the optimal protocols (market, distributed Hungarian) when
/// they finished; the ADMM methods when a stop rule that proves optimality fired; a
/// heuristic (CBAA) never.
fn certified(report: &SolveReport) -> bool {
    report
        .method
        .info()
        .certification
        .certifies(report.converged, report.stop)
}
