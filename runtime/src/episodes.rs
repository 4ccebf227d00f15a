//! Repeated assignments: one team of agents, alive across many episodes (the persistent
//! surveillance case study, [`admm_ta_agents::surveillance`]).
//!
//! Every episode each robot computes its own cost row from its own state, the team runs
//! primal consensus ADMM to the decentralized certified stop, and each robot moves to its
//! station, updating its position and battery. The agents are not restarted: after the
//! stop (all robots stop at the same round), the next episode goes on from that round with
//! the new costs, **warm-started** from the current iterates and multipliers
//! ([`admm_ta_agents::method::MethodAgent::set_costs`]) and a fresh stop rule. Threads and
//! ipc (one process per robot for the whole run) run the same agent function,
//! [`run_surveillance_agent`].

use crate::exchange::round_loop::{AgentOutcome, AgentPlan, AgentStop, RoundLoop};
use crate::exchange::{Exchange, ExchangeError};
use crate::latency::{LatencySummary, RoundLatency};
use crate::process::launcher::{self, IpcOptions};
use crate::process::scenario::{ProcessTransport, Scenario, Workload};
use crate::solve::{SolveError, Transport};
use crate::threads;
use crate::wait::WaitStrategy;
use admm_ta_agents::local_stop::LocalCertifiedStop;
use admm_ta_agents::method::{AgentSettings, Method, MethodAgent};
use admm_ta_agents::problem::{AssignmentCase, CostMatrix};
use admm_ta_agents::rho;
use admm_ta_agents::surveillance::SurveillanceScenario;
use admm_ta_topologies::Graph;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::time::{Duration, Instant};

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
        let rho = rho::default_rho_for(Method::Primal, &costs, mean_degree);
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
            AgentSettings::new(Method::Primal, self.rho, self.diameter, self.tolerance),
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

/// How a surveillance team runs.
#[derive(Debug, Clone)]
pub struct EpisodeRunConfig {
    /// threads or ipc (one process per robot for the whole run) or uds.
    pub transport: Transport,
    pub wait: WaitStrategy,
    /// Round limit of each episode.
    pub max_rounds: u64,
    pub round_timeout: Duration,
    pub startup_timeout: Duration,
    /// The `admm-ta` binary (ipc, uds).
    pub agent_program: Option<PathBuf>,
}

impl Default for EpisodeRunConfig {
    fn default() -> Self {
        Self {
            transport: Transport::Ipc,
            wait: WaitStrategy::Auto,
            max_rounds: 5000,
            round_timeout: Duration::from_secs(30),
            startup_timeout: Duration::from_secs(60),
            agent_program: None,
        }
    }
}

/// What a surveillance team did.
#[derive(Debug, Clone)]
pub struct EpisodeRun {
    /// Per robot, its episodes in order.
    pub records: Vec<Vec<EpisodeRecord>>,
    pub latency: LatencySummary,
    pub startup: Option<Duration>,
    pub wall: Duration,
}

/// Runs `settings.episodes` episodes with one agent per robot on `graph`, alive for the whole
/// run.
pub fn run_episodes(
    settings: &EpisodeSettings,
    graph: &Graph,
    config: &EpisodeRunConfig,
) -> Result<EpisodeRun, SolveError> {
    let n = settings.model.robots;
    if graph.robots() != n {
        return Err(SolveError::SizeMismatch {
            graph: graph.robots(),
            problem: n,
        });
    }
    let started = Instant::now();
    let plan = |index| AgentPlan {
        index,
        max_rounds: config.max_rounds,
        stop: AgentStop::MaxIters,
        round_timeout: config.round_timeout,
        global_barrier: false,
        warmup_rounds: 0,
    };
    match config.transport {
        Transport::Sim => Err(SolveError::NotDistributed),
        Transport::Threads => {
            let mut agents: Vec<MethodAgent> =
                (0..n).map(|i| settings.agent(i, graph.degree(i))).collect();
            let plans: Vec<AgentPlan> = (0..n).map(plan).collect();
            let results = threads::run_threads_with(
                &mut agents,
                graph,
                &plans,
                config.wait,
                &|agent, exchange, plan| run_surveillance_agent(agent, exchange, plan, settings),
            )?;
            let mut latency = RoundLatency::new();
            let mut records = Vec::with_capacity(n);
            for (r, outcome) in results {
                latency
                    .merge(&outcome.latency)
                    .expect("agents record every component");
                records.push(r);
            }
            Ok(EpisodeRun {
                records,
                latency: latency.summary(),
                startup: None,
                wall: started.elapsed(),
            })
        }
        Transport::Ipc | Transport::Uds | Transport::Zenoh => {
            let program = config
                .agent_program
                .clone()
                .ok_or(SolveError::NoAgentProgram)?;
            let scenario = Scenario {
                case: AssignmentCase::Two,
                cost_bits: settings
                    .model
                    .initial_costs()
                    .iter()
                    .map(|v| v.to_bits())
                    .collect(),
                rho_bits: settings.rho.to_bits(),
                max_rounds: config.max_rounds,
                diameter: settings.diameter,
                workload: Workload::Episodes(Box::new(settings.clone())),
                transport: ProcessTransport::for_transport(config.transport),
                wait: config.wait,
                ..Scenario::blank(graph, settings.model.tasks())
            };
            let ran = launcher::launch(
                scenario,
                &IpcOptions {
                    agent_program: program,
                    round_timeout: config.round_timeout,
                    startup_timeout: config.startup_timeout,
                    global_barrier: false,
                    fault_injection: false,
                },
            )?;
            if !ran.leftovers.is_empty() {
                return Err(SolveError::Leftovers(ran.leftovers));
            }
            Ok(EpisodeRun {
                records: ran.episodes,
                latency: ran.latency.summary(),
                startup: Some(ran.startup),
                wall: started.elapsed(),
            })
        }
    }
}
