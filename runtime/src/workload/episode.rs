//! One surveillance robot's life over many episodes (the persistent surveillance case
//! study, [`admm_ta_agents::problem::surveillance`]): what every agent of the team shares, what each
//! records per episode, and the agent function every transport runs — threads in
//! [`crate::episodes`], or one agent process per robot for the whole run.

use crate::exchange::Exchange;
use crate::exchange::ExchangeError;
use crate::exchange::round_loop::{AgentOutcome, AgentPlan, AgentStop, RoundLoop};
use admm_ta_agents::certify::local_stop::LocalCertifiedStop;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::methods::rho::RhoRule;
use admm_ta_agents::methods::{AgentMethod, AgentSettings};
use admm_ta_agents::problem::surveillance::SurveillanceScenario;
use admm_ta_agents::problem::{AssignmentCase, CostMatrix};
use serde::{Deserialize, Serialize};

/// One robot's view of one episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeRecord {
    /// The robot's cost row of the episode.
    pub costs: Vec<f64>,
    /// Its station.
    pub task: usize,
    /// Rounds the episode took.
    pub rounds: u64,
    /// The stop certified the assignment (else the round limit ended the episode).
    pub certified: bool,
    /// Battery level after the episode.
    pub battery: f64,
}

/// What every agent of a surveillance team shares.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeSettings {
    pub model: SurveillanceScenario,
    pub episodes: usize,
    pub warm_start: bool,
    pub rho: f64,
    /// Total cost tolerance of the certified stop.
    pub tolerance: f64,
    pub diameter: usize,
}

impl EpisodeSettings {
    /// Settings for `episodes` of `model`: ρ by the primal's scale-free rule and the stop
    /// tolerance from the spread of the first episode's costs, leaving out the safety
    /// penalties (which would otherwise set the scale).
    pub fn new(
        model: SurveillanceScenario,
        episodes: usize,
        warm_start: bool,
        mean_degree: f64,
        diameter: usize,
    ) -> Self {
        let n = model.robots;
        let first = model.initial_costs();
        let ordinary = first
            .iter()
            .copied()
            .filter(|&c| c < model.penalty / 2.0)
            .fold(0.0, f64::max);
        let capped: Vec<f64> = first.iter().map(|&c| c.min(ordinary)).collect();
        let costs = CostMatrix::new(n, model.tasks(), capped).expect("a validated model");
        let rho = RhoRule::Primal.rho(&costs, mean_degree);
        let tolerance = 1e-9 * costs.spread().max(1e-12) * n as f64;
        Self {
            model,
            episodes,
            warm_start,
            rho,
            tolerance,
            diameter,
        }
    }

    /// Robot `index`'s agent, built with its first episode's costs.
    pub fn agent(&self, index: usize, degree: usize) -> MethodAgent {
        let costs = self.model.cost_row(index, &self.model.initial_state(index));
        MethodAgent::new(
            index,
            costs,
            self.model.robots,
            AssignmentCase::Two,
            degree,
            AgentSettings::new(AgentMethod::Primal, self.rho, self.diameter, self.tolerance),
        )
    }
}

/// Runs robot `plan.index`'s episodes over `exchange`; `plan.max_rounds` limits each one.
pub fn run_surveillance_agent(
    agent: &mut MethodAgent,
    exchange: &mut dyn Exchange,
    plan: &AgentPlan,
    settings: &EpisodeSettings,
) -> Result<(Vec<EpisodeRecord>, AgentOutcome), ExchangeError> {
    let i = plan.index;
    let model = &settings.model;
    let mut state = model.initial_state(i);
    let mut rounds = RoundLoop::start(agent, exchange, plan)?;
    let mut records = Vec::with_capacity(settings.episodes);
    let mut last = (0, None);
    for episode in 0..settings.episodes {
        let costs = model.cost_row(i, &state);
        if episode > 0 {
            agent
                .set_costs(&costs, settings.warm_start)
                .map_err(|what| ExchangeError::Transport { agent: i, what })?;
        }
        let stop = LocalCertifiedStop::new(settings.diameter, model.robots, settings.tolerance)
            .map_err(|e| ExchangeError::Transport {
                agent: i,
                what: e.to_string(),
            })?;
        let before = rounds.round();
        last = rounds.run(agent, exchange, plan, AgentStop::Local(stop))?;
        state = model.advance(&state, last.0);
        records.push(EpisodeRecord {
            costs,
            task: last.0,
            rounds: rounds.round() - before,
            certified: last.1.is_some(),
            battery: state.battery,
        });
    }
    Ok((records, rounds.outcome(i, last.0, last.1)))
}
