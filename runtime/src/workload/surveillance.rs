//! One surveillance robot's life over many episodes (the persistent surveillance case
//! study, [`admm_ta_agents::problem::surveillance`]): what every agent of the team shares, what each
//! records per episode, and the agent function every transport runs — threads in
//! [`crate::surveillance`], or one agent process per robot for the whole run.

use admm_ta_agents::certify::local_stop::LocalCertifiedStop;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::settings::SettingError;
use admm_ta_agents::method::team::{AgentInit, TeamContext, TeamParams};
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::surveillance::SurveillanceMission;
use admm_ta_agents::problem::{AssignmentCase, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::Graph;
use admm_ta_transport::exchange::Exchange;
use admm_ta_transport::exchange::ExchangeError;
use admm_ta_transport::exchange::round_loop::{AgentOutcome, AgentPlan, AgentStop, RoundLoop};
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

/// Why a method cannot run surveillance episodes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurveillanceError {
    #[error("--method {method} is solved centrally: it has no team to keep alive")]
    NoTeam { method: &'static str },
    #[error(transparent)]
    Setting(#[from] SettingError),
}

/// What every agent of a surveillance team shares.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeSettings {
    pub model: SurveillanceMission,
    pub episodes: usize,
    pub warm_start: bool,
    /// The method (one whose agents take new costs between episodes) and its own settings,
    /// as its settings type serialises them.
    pub method: Method,
    pub settings: serde_json::Value,
    pub rho: f64,
    /// Total cost tolerance of the certified stop.
    pub tolerance: f64,
    pub diameter: usize,
}

impl EpisodeSettings {
    /// Settings for `episodes` of `model` solved by `contender`: ρ by the method's
    /// scale-free rule and the stop tolerance from the spread of the first episode's costs,
    /// leaving out the safety penalties (which would otherwise set the scale).
    pub fn new(
        model: SurveillanceMission,
        episodes: usize,
        warm_start: bool,
        mean_degree: f64,
        diameter: usize,
        contender: Contender,
    ) -> Result<Self, SurveillanceError> {
        let n = model.robots;
        let first = model.initial_costs();
        let ordinary = first
            .iter()
            .copied()
            .filter(|&c| c < model.penalty / 2.0)
            .fold(0.0, f64::max);
        let capped: Vec<f64> = first.iter().map(|&c| c.min(ordinary)).collect();
        let costs = CostMatrix::new(n, model.tasks(), capped).expect("a validated model");
        let setup =
            contender
                .method
                .setup(&contender.settings())?
                .ok_or(SurveillanceError::NoTeam {
                    method: contender.method.name(),
                })?;
        let rho = setup.default_rho(&costs, mean_degree).unwrap_or(0.0);
        let tolerance = 1e-9 * costs.spread().max(1e-12) * n as f64;
        Ok(Self {
            model,
            episodes,
            warm_start,
            method: contender.method,
            settings: setup.settings_json(),
            rho,
            tolerance,
            diameter,
        })
    }

    /// Robot `index`'s agent on `graph`, built with its first episode's costs.
    pub fn agent(&self, index: usize, graph: &Graph) -> MethodAgent {
        let model = &self.model;
        let first = CostMatrix::new(model.robots, model.tasks(), model.initial_costs())
            .expect("a validated model");
        let problem = TaskAssignmentProblem::internal_from(first, AssignmentCase::Two)
            .expect("a validated model");
        let setup = self
            .method
            .team()
            .and_then(|team| team.configure_json(&self.settings).ok())
            .expect("the settings its method wrote");
        let team = setup.team(TeamContext {
            problem: &problem,
            graph,
            params: TeamParams {
                rho: self.rho,
                diameter: self.diameter,
                tolerance: self.tolerance,
            },
        });
        MethodAgent::new(team.agent(AgentInit {
            index,
            costs: model.cost_row(index, &model.initial_state(index)),
            robots: model.robots,
            case: AssignmentCase::Two,
            degree: graph.degree(index),
        }))
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
    let mut rounds = RoundLoop::start(agent, exchange, plan, settings.episodes as u64)?;
    let mut records = Vec::with_capacity(settings.episodes);
    let mut last = (0, None);
    for episode in 0..settings.episodes {
        let costs = model.cost_row(i, &state);
        if episode > 0 {
            agent
                .set_costs(&costs, settings.warm_start)
                .map_err(|e| ExchangeError::Transport {
                    agent: i,
                    what: e.to_string(),
                })?;
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
