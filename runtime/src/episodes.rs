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
//! [`run_surveillance_agent`](crate::workload::episode::run_surveillance_agent).

use crate::exchange::round_loop::{AgentPlan, AgentStop};
use crate::latency::{LatencySummary, RoundLatency};
use crate::process::launcher::{self, IpcOptions};
use crate::process::scenario::{Scenario, Workload};
use crate::solve::error::SolveError;
use crate::threads;
use crate::transport::{Execution, Transport};
use crate::wait::WaitStrategy;
use crate::workload::episode::{EpisodeRecord, EpisodeSettings, run_surveillance_agent};
use admm_ta_agents::method::MethodAgent;
use admm_ta_agents::problem::AssignmentCase;
use admm_ta_topologies::Graph;
use std::path::PathBuf;
use std::time::{Duration, Instant};

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
    match config.transport.capabilities().execution {
        Execution::Lockstep => Err(SolveError::NotDistributed),
        Execution::Threads => {
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
        Execution::Processes => {
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
                transport: config.transport,
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
