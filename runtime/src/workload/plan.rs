//! What a solve's agents are built from: ρ, the tie-breaking perturbation, the stop
//! tolerance and the method with its settings, computed once from the problem, the graph and
//! the options, exactly as every transport (and every independently started agent) needs
//! them.

use crate::options::SolveOptions;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::team::{AgentInit, MethodSetup, TeamBuilder, TeamContext, TeamParams};
use admm_ta_agents::methods::Method;
use admm_ta_agents::methods::rho::RhoSchedule;
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_agents::problem::ties;
use admm_ta_topologies::Graph;

/// Every robot's agent, built the same way by every transport (and every independently
/// started agent) so that they compute with exactly the same numbers: the problem, the
/// graph, the method's team builder (with whatever the team shares) and the perturbation.
pub struct AgentFactory<'a> {
    pub problem: &'a TaskAssignmentProblem,
    pub graph: &'a Graph,
    /// The method with its settings.
    pub setup: Box<dyn MethodSetup>,
    /// What every agent shares: ρ, the diameter, the certificate's tolerance.
    pub params: TeamParams,
    pub epsilon: Option<f64>,
    pub seed: u64,
    pub schedule: Option<RhoSchedule>,
    team: Box<dyn TeamBuilder + 'a>,
}

impl<'a> AgentFactory<'a> {
    /// The factory of `setup`'s agents for `problem` on `graph`.
    pub fn new(
        problem: &'a TaskAssignmentProblem,
        graph: &'a Graph,
        setup: Box<dyn MethodSetup>,
        params: TeamParams,
        epsilon: Option<f64>,
        seed: u64,
        schedule: Option<RhoSchedule>,
    ) -> Self {
        let team = setup.team(TeamContext {
            problem,
            graph,
            params,
        });
        Self {
            problem,
            graph,
            setup,
            params,
            epsilon,
            seed,
            schedule,
            team,
        }
    }

    /// Robot `i`'s agent, with its own (optionally perturbed) costs.
    pub fn agent(&self, i: usize) -> MethodAgent {
        self.agent_with_degree(Some(i), self.graph.degree(i))
    }

    /// Robot `i`'s agent with `degree` neighbours (a standing team's robot that runs robot
    /// `i`'s part of an episode's problem from another place of the graph), or (`i`
    /// `None`) one that relays there ([`TeamBuilder::relay`]).
    pub fn agent_with_degree(&self, i: Option<usize>, degree: usize) -> MethodAgent {
        let index = i.unwrap_or(0);
        let costs = ties::perturbed_row(self.problem.costs(), index, self.epsilon, self.seed);
        let init = AgentInit {
            index,
            costs,
            robots: self.problem.robots(),
            case: self.problem.case(),
            degree,
        };
        let agent = match i {
            Some(_) => self.team.agent(init),
            None => self.team.relay(init),
        };
        MethodAgent::new(agent).with_schedule(self.schedule)
    }

    /// Every robot's agent.
    pub fn agents(&self) -> Vec<MethodAgent> {
        (0..self.problem.robots()).map(|i| self.agent(i)).collect()
    }
}

/// The ρ a problem's costs give by the method's default rule is no penalty (the costs have
/// no spread): the only option the problem can refute.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("ρ must be a positive finite number, got {0}")]
pub struct BadRho(pub f64);

/// What every transport's agents are built from.
pub struct Plan<'a> {
    /// The method (with its settings in `agents.setup`).
    pub method: Method,
    pub rho: f64,
    /// Total cost tolerance of the optimality certificate.
    pub tolerance: f64,
    pub diameter: usize,
    /// The decentralized stop's cadence (the method's).
    pub stop_cadence: (u64, u32),
    pub agents: AgentFactory<'a>,
}

/// ρ, the tie-breaking perturbation, the stop tolerance and the agents of `setup` (the
/// options' method with its settings), as every transport (and every independently started
/// agent) computes them.
pub fn prepare<'a>(
    problem: &'a TaskAssignmentProblem,
    graph: &'a Graph,
    options: &SolveOptions,
    setup: Box<dyn MethodSetup>,
) -> Result<Plan<'a>, BadRho> {
    prepare_for_stop(problem, graph, options, setup, problem.robots())
}

/// [`prepare`] for a part of a team in which `stoppers` agents (the problem's robots and
/// the relays beside them) take part in the stop, each certifying its share of
/// [`Plan::tolerance`]: the method's own tolerance (its tie-break, its certificate's
/// thresholds), sized for the problem's robots alone, is scaled to that share, so that
/// every agent's slack fits it and the slacks of all of them sum to at most the tolerance.
pub fn prepare_for_stop<'a>(
    problem: &'a TaskAssignmentProblem,
    graph: &'a Graph,
    options: &SolveOptions,
    setup: Box<dyn MethodSetup>,
    stoppers: usize,
) -> Result<Plan<'a>, BadRho> {
    let n = problem.robots();
    // Methods without a penalty report ρ = 0 and ignore --rho and --adaptive-rho.
    let rho = match setup.default_rho(problem.costs(), graph.mean_degree()) {
        Some(default) => {
            let rho = options.rho().unwrap_or(default);
            if !(rho > 0.0 && rho.is_finite()) {
                return Err(BadRho(rho));
            }
            rho
        }
        None => 0.0,
    };
    let epsilon = ties::epsilon(problem.costs(), options.perturbation());
    let tolerance = 1e-9 * problem.costs().spread() * n as f64;
    let diameter = graph.diameter().unwrap_or(0);
    let schedule = options
        .adaptive_rho()
        .then(|| setup.schedule(rho))
        .flatten();
    let stop_cadence = setup.stop_cadence();
    let method_tolerance = if stoppers > n {
        tolerance * n as f64 / stoppers as f64
    } else {
        tolerance
    };
    let params = TeamParams {
        rho,
        diameter,
        tolerance: method_tolerance,
    };
    let agents = AgentFactory::new(
        problem,
        graph,
        setup,
        params,
        epsilon,
        options.seed(),
        schedule,
    );
    Ok(Plan {
        method: options.method(),
        rho,
        tolerance,
        diameter,
        stop_cadence,
        agents,
    })
}
