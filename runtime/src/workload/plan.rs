//! What a solve's agents are built from: ρ, γ, the tie-breaking perturbation, the stop
//! tolerance and the agents' settings, computed once from the problem, the graph and the
//! options, exactly as every transport (and every independently started agent) needs them.

use crate::options::SolveOptions;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::methods::primal::agent::PrimalSettings;
use admm_ta_agents::methods::primal::readout_filter::ReadoutFilter;
use admm_ta_agents::methods::primal::settings::{FastTuning, PrimalVariant, fast_rho};
use admm_ta_agents::methods::rho::RhoSchedule;
use admm_ta_agents::methods::{AgentMethod, AgentSettings};
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_agents::problem::ties;
use admm_ta_topologies::Graph;
use std::sync::{Arc, OnceLock};

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
    /// The fast primal variant's readout filter ([`readout_filter`]), designed on first use
    /// and shared by every agent built here (`OnceLock::new()` when building a factory).
    pub readout_filter: OnceLock<Option<Arc<ReadoutFilter>>>,
}

impl AgentFactory<'_> {
    /// Robot `i`'s agent, with its own (optionally perturbed) costs.
    pub fn agent(&self, i: usize) -> MethodAgent {
        let costs = admm_ta_agents::problem::ties::perturbed_row(
            self.problem.costs(),
            i,
            self.epsilon,
            self.seed,
        );
        MethodAgent::new(
            i,
            costs,
            self.problem.robots(),
            self.problem.case(),
            self.graph.degree(i),
            self.settings,
        )
        .with_schedule(self.schedule)
        .with_readout_filter(
            self.readout_filter
                .get_or_init(|| readout_filter(self.problem, self.graph, &self.settings))
                .clone(),
        )
    }

    /// Every robot's agent.
    pub fn agents(&self) -> Vec<MethodAgent> {
        (0..self.problem.robots()).map(|i| self.agent(i)).collect()
    }
}

/// The readout filter every robot of a fast primal team uses, designed from the graph
/// (`admm_ta_agents::methods::primal::readout_filter`); `None` for the other methods and variants, below a
/// tenth of the fast variant's ρ, on graphs without edges, and where no history window fits
/// the robot's memory budget.
pub fn readout_filter(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    settings: &AgentSettings,
) -> Option<Arc<ReadoutFilter>> {
    if settings.method != AgentMethod::Primal || settings.primal_variant != PrimalVariant::Fast {
        return None;
    }
    // The weights fit the iteration's linear large-ρ regime (every factor from 10 up gives
    // the same rounds); a much smaller `--rho` clips the iterates and the fit would not hold.
    let linear = fast_rho(problem.costs().spread(), graph.mean_degree()) / 10.0;
    if settings.rho.is_nan() || settings.rho < linear {
        return None;
    }
    let window = ReadoutFilter::window_for(problem.tasks(), problem.robots(), settings.diameter);
    ReadoutFilter::design(graph, FastTuning::for_diameter(settings.diameter), window).map(Arc::new)
}

/// The ρ a problem's costs give by the method's default rule is no penalty (the costs have
/// no spread): the only option the problem can refute.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("ρ must be a positive finite number, got {0}")]
pub struct BadRho(pub f64);

/// What every transport's agents are built from.
pub struct Plan<'a> {
    // The stop protocol's cadence is `agents.settings.stop_cadence()`.
    pub rho: f64,
    /// Total cost tolerance of the optimality certificate.
    pub tolerance: f64,
    pub diameter: usize,
    pub agents: AgentFactory<'a>,
}

/// ρ, γ, the tie-breaking perturbation, the stop tolerance and the agents' settings of the
/// team method `method` (the options' method), as every transport (and every independently
/// started agent) computes them.
pub fn prepare<'a>(
    problem: &'a TaskAssignmentProblem,
    graph: &'a Graph,
    options: &SolveOptions,
    method: AgentMethod,
) -> Result<Plan<'a>, BadRho> {
    let n = problem.robots();
    // Methods without a penalty report ρ = 0 and ignore --rho and --adaptive-rho.
    let variant = options.primal_variant();
    let rho = match method.rho_rule() {
        Some(rule) => options
            .rho()
            .unwrap_or_else(|| rule.rho_for(problem.costs(), graph.mean_degree(), variant)),
        None => 0.0,
    };
    if method.rho_rule().is_some() && !(rho > 0.0 && rho.is_finite()) {
        return Err(BadRho(rho));
    }
    // The options checked a given factor.
    let gamma_factor = options
        .gamma_factor()
        .unwrap_or(admm_ta_agents::methods::dual::agent::DEFAULT_GAMMA_FACTOR);
    let epsilon = ties::epsilon(problem.costs(), options.perturbation());
    let tolerance = 1e-9 * problem.costs().spread() * n as f64;
    let diameter = graph.diameter().unwrap_or(0);
    let settings = AgentSettings {
        projection: options.projection(),
        gamma_factor,
        primal_variant: variant,
        ..AgentSettings::new(method, rho, diameter, tolerance)
    };
    let schedule = (options.adaptive_rho() && method.has_schedule(variant))
        .then(|| method.schedule(rho))
        .flatten();
    let agents = AgentFactory {
        problem,
        graph,
        settings,
        epsilon,
        seed: options.seed(),
        schedule,
        readout_filter: OnceLock::new(),
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
            ..AgentSettings::new(AgentMethod::Primal, settings.rho, diameter, f64::INFINITY)
        },
        epsilon,
        seed,
        schedule: None,
        readout_filter: OnceLock::new(),
    }
    .agents()
}
