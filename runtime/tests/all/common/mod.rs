//! Inputs shared by the runtime's integration tests.

use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::{Graph, TopologySpec};

/// Uniform `[0, 1)` costs drawn from `cost_seed` and a `topology` graph built from
/// `graph_seed`.
pub fn uniform_instance(
    robots: usize,
    tasks: usize,
    cost_seed: u64,
    topology: &str,
    graph_seed: u64,
) -> (TaskAssignmentProblem, Graph) {
    let problem = TaskAssignmentProblem::new(
        CostMatrix::uniform(robots, tasks, cost_seed).unwrap(),
        CaseChoice::Auto,
    )
    .unwrap();
    let graph = topology
        .parse::<TopologySpec>()
        .unwrap()
        .build(robots, graph_seed)
        .unwrap();
    (problem, graph)
}
