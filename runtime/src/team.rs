//! A team: every robot's agent built the same way by every transport, so that they compute
//! with exactly the same numbers.

use admm_ta_agents::method::{AgentSettings, MethodAgent};
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_agents::rho::RhoSchedule;
use admm_ta_topologies::Graph;

/// What the agents share: the problem, the graph and the algorithm's settings.
pub struct Team<'a> {
    pub problem: &'a TaskAssignmentProblem,
    pub graph: &'a Graph,
    pub settings: AgentSettings,
    pub epsilon: Option<f64>,
    pub seed: u64,
    pub schedule: Option<RhoSchedule>,
}

impl Team<'_> {
    /// Robot `i`'s agent, with its own (optionally perturbed) costs.
    pub fn agent(&self, i: usize) -> MethodAgent {
        let costs =
            admm_ta_agents::ties::perturbed_row(self.problem.costs(), i, self.epsilon, self.seed);
        MethodAgent::new(
            i,
            costs,
            self.problem.robots(),
            self.problem.case(),
            self.graph.degree(i),
            self.settings,
        )
        .with_schedule(self.schedule)
    }

    /// Every robot's agent.
    pub fn agents(&self) -> Vec<MethodAgent> {
        (0..self.problem.robots()).map(|i| self.agent(i)).collect()
    }
}
