//! What the dual methods' examples share: the problems their first arguments name, and a
//! team of agents for one of them.
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::team::{AgentInit, MethodSetup, TeamContext, TeamParams};
use admm_ta_agents::problem::cost_model::CostModel;
use admm_ta_agents::problem::{CaseChoice, TaskAssignmentProblem};
use admm_ta_topologies::{Graph, TopologySpec};

/// `ROBOTS TASKS TOPOLOGY uniform|distance`: the first four arguments.
pub struct Problems {
    pub robots: usize,
    tasks: usize,
    topology: TopologySpec,
    model: CostModel,
}

impl Problems {
    pub fn from_args(args: &[String]) -> Self {
        Self {
            robots: args[1].parse().unwrap(),
            tasks: args[2].parse().unwrap(),
            topology: args[3].parse().unwrap(),
            model: match args[4].as_str() {
                "uniform" => CostModel::Uniform,
                _ => CostModel::Geometric,
            },
        }
    }

    /// Seed `seed`'s problem and graph.
    pub fn instance(&self, seed: u64) -> (TaskAssignmentProblem, Graph) {
        let costs = self.model.costs(self.robots, self.tasks, seed).unwrap();
        let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        (problem, self.topology.build(self.robots, seed).unwrap())
    }
}

/// The team's parameters with penalty `rho`: the solver's stop tolerance (`10⁻⁹` of the
/// spread per robot).
pub fn params(problem: &TaskAssignmentProblem, graph: &Graph, rho: f64) -> TeamParams {
    TeamParams {
        rho,
        diameter: graph.diameter().unwrap(),
        tolerance: 1e-9 * problem.costs().spread() * graph.robots() as f64,
    }
}

/// One agent of `setup`'s team per robot.
pub fn agents(
    setup: &dyn MethodSetup,
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    params: TeamParams,
) -> Vec<MethodAgent> {
    let team = setup.team(TeamContext {
        problem,
        graph,
        params,
    });
    (0..graph.robots())
        .map(|i| {
            MethodAgent::new(team.agent(AgentInit {
                index: i,
                costs: problem.costs().row(i).to_vec(),
                robots: graph.robots(),
                case: problem.case(),
                degree: graph.degree(i),
            }))
        })
        .collect()
}
