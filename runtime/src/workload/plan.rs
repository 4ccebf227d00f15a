//! What a solve's agents are built from: ρ, γ, the tie-breaking perturbation, the stop
//! tolerance and the agents' settings, computed once from the problem, the graph and the
//! options, exactly as every transport (and every independently started agent) needs them.

use crate::options::SolveConfig;
use admm_ta_agents::method::{AgentSettings, Method, MethodAgent};
use admm_ta_agents::primal::PrimalSettings;
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_agents::rho::{self, RhoSchedule};
use admm_ta_agents::ties;
use admm_ta_topologies::Graph;

/// Every robot's agent, built the same way by every transport (and every independently
/// started agent) so that they compute with exactly the same numbers: the problem, the
/// graph and the algorithm's settings.
pub struct AgentFactory<'a> {
    pub problem: &'a TaskAssignmentProblem,
    pub graph: &'a Graph,
    pub settings: AgentSettings,
    pub epsilon: Option<f64>,
    pub seed: u64,
    pub schedule: Option<RhoSchedule>,
}

impl AgentFactory<'_> {
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

/// A solve's settings that do not fit its problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    #[error("ρ must be a positive finite number, got {0}")]
    BadRho(f64),
    #[error("the γ factor must be a positive finite number, got {0}")]
    BadGamma(f64),
}

/// What every transport's agents are built from.
pub struct Plan<'a> {
    pub rho: f64,
    /// Total cost tolerance of the optimality certificate.
    pub tolerance: f64,
    pub diameter: usize,
    pub agents: AgentFactory<'a>,
}

/// ρ, γ, the tie-breaking perturbation, the stop tolerance and the agents' settings, as every
/// transport (and every independently started agent) computes them.
pub fn prepare<'a>(
    problem: &'a TaskAssignmentProblem,
    graph: &'a Graph,
    config: &SolveConfig,
) -> Result<Plan<'a>, PlanError> {
    let n = problem.robots();
    // Methods without a penalty report ρ = 0 and ignore --rho and --adaptive-rho.
    let rho = if config.method.is_admm() {
        config.rho.unwrap_or_else(|| {
            rho::default_rho_for(config.method, problem.costs(), graph.mean_degree())
        })
    } else {
        0.0
    };
    if config.method.is_admm() && !(rho > 0.0 && rho.is_finite()) {
        return Err(PlanError::BadRho(rho));
    }
    let gamma_factor = config
        .gamma_factor
        .unwrap_or(admm_ta_agents::dual::DEFAULT_GAMMA_FACTOR);
    if !(gamma_factor > 0.0 && gamma_factor.is_finite()) {
        return Err(PlanError::BadGamma(gamma_factor));
    }
    let epsilon = ties::epsilon(problem.costs(), config.perturbation);
    let tolerance = 1e-9 * problem.costs().spread() * n as f64;
    let diameter = graph.diameter().unwrap_or(0);
    let settings = AgentSettings {
        projection: config.projection,
        gamma_factor,
        ..AgentSettings::new(config.method, rho, diameter, tolerance)
    };
    let schedule = (config.adaptive_rho && config.method.is_admm())
        .then(|| RhoSchedule::for_method(config.method, rho));
    let agents = AgentFactory {
        problem,
        graph,
        settings,
        epsilon,
        seed: config.seed,
        schedule,
    };
    Ok(Plan {
        rho,
        tolerance,
        diameter,
        agents,
    })
}

/// One primal agent per robot of `graph`, each with its own (optionally perturbed) costs,
/// built as [`crate::solve::solve`] builds them (for examples and tests that drive a simulation).
pub fn primal_team(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    settings: PrimalSettings,
    epsilon: Option<f64>,
    seed: u64,
) -> Vec<MethodAgent> {
    let diameter = graph.diameter().unwrap_or(0);
    AgentFactory {
        problem,
        graph,
        settings: AgentSettings {
            projection: settings.projection,
            ..AgentSettings::new(Method::Primal, settings.rho, diameter, f64::INFINITY)
        },
        epsilon,
        seed,
        schedule: None,
    }
    .agents()
}
