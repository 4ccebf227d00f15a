//! A latency-benchmark run: a team of [`ProbeAgent`]s (payload of any length, a step of
//! known cost) for a fixed number of rounds on one transport, with warm-up rounds excluded
//! from the recorded latency and resource usage. The algorithmic counterpart is
//! [`crate::solve::solve`] with `StopRule::MaxIters` and `warmup_rounds`.
//!
//! ```
//! use admm_ta_agents::probe::ProbeStep;
//! use admm_ta_runtime::probe_run::{ProbeRun, run_probe};
//! use admm_ta_runtime::transport::Transport;
//! use admm_ta_topologies::generate;
//! let graph = generate::ring(4).unwrap();
//! let run = ProbeRun { transport: Transport::Threads, rounds: 50, warmup_rounds: 10,
//!                      ..ProbeRun::new(16, ProbeStep::Average) };
//! let report = run_probe(&graph, &run).unwrap();
//! assert_eq!(report.latency.round.count, 4 * 40);
//! ```

use crate::exchange::round_loop::{AgentPlan, AgentStop};
use crate::latency::{LatencySummary, RoundLatency};
use crate::process::launcher::{self, IpcOptions};
use crate::process::scenario::{Scenario, Workload};
use crate::solve::error::SolveError;
use crate::threads;
use crate::transport::{Execution, Transport};
use crate::usage::ThreadUsage;
use crate::wait::WaitStrategy;
use admm_ta_agents::probe::{ProbeAgent, ProbeStep};
use admm_ta_topologies::Graph;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// One benchmark run's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeRun {
    /// Values of every payload.
    pub payload_len: usize,
    pub step: ProbeStep,
    /// threads, ipc or uds.
    pub transport: Transport,
    pub wait: WaitStrategy,
    pub global_barrier: bool,
    /// Rounds run in total, warm-up included.
    pub rounds: u64,
    pub warmup_rounds: u64,
    pub round_timeout: Duration,
    pub startup_timeout: Duration,
    /// The `admm-ta` binary (ipc and uds).
    pub agent_program: Option<PathBuf>,
}

impl ProbeRun {
    /// 1000 rounds after 100 of warm-up on threads, waiting by the default strategy.
    pub fn new(payload_len: usize, step: ProbeStep) -> Self {
        Self {
            payload_len,
            step,
            transport: Transport::Threads,
            wait: WaitStrategy::Auto,
            global_barrier: false,
            rounds: 1100,
            warmup_rounds: 100,
            round_timeout: Duration::from_secs(30),
            startup_timeout: Duration::from_secs(60),
            agent_program: None,
        }
    }
}

/// What a benchmark run measured.
#[derive(Debug, Clone)]
pub struct ProbeReport {
    /// Every agent's recorded rounds merged.
    pub latency: LatencySummary,
    /// All agents' CPU time and context switches over the recorded rounds.
    pub usage: ThreadUsage,
    /// From the first agent process's spawn until all were connected (ipc, uds).
    pub startup: Option<Duration>,
    /// The whole run, start-up included.
    pub wall: Duration,
}

/// Runs `run` on `graph`.
pub fn run_probe(graph: &Graph, run: &ProbeRun) -> Result<ProbeReport, SolveError> {
    let n = graph.robots();
    let capabilities = run.transport.capabilities();
    if run.global_barrier
        && capabilities.execution != Execution::Lockstep
        && !capabilities.global_barrier
    {
        return Err(SolveError::BarrierNeedsAgents);
    }
    let started = Instant::now();
    let (latency, outcomes_usage, startup) = match capabilities.execution {
        Execution::Lockstep => return Err(SolveError::NotDistributed),
        Execution::Threads => {
            let mut agents: Vec<ProbeAgent> = (0..n)
                .map(|i| ProbeAgent::new(i, run.payload_len, run.step))
                .collect();
            let plans: Vec<AgentPlan> = (0..n)
                .map(|index| AgentPlan {
                    index,
                    max_rounds: run.rounds,
                    stop: AgentStop::MaxIters,
                    round_timeout: run.round_timeout,
                    global_barrier: run.global_barrier,
                    warmup_rounds: run.warmup_rounds,
                })
                .collect();
            let outcomes = threads::run_threads_waiting(&mut agents, graph, &plans, run.wait)?;
            let mut latency = RoundLatency::new();
            for o in &outcomes {
                latency
                    .merge(&o.latency)
                    .expect("agents record every component");
            }
            (
                latency,
                outcomes.iter().map(|o| o.usage).collect::<Vec<_>>(),
                None,
            )
        }
        Execution::Processes => {
            let program = run
                .agent_program
                .clone()
                .ok_or(SolveError::NoAgentProgram)?;
            let scenario = Scenario {
                max_rounds: run.rounds,
                global_barrier: run.global_barrier,
                workload: Workload::Probe {
                    payload_len: run.payload_len,
                    step: run.step,
                },
                transport: run.transport,
                wait: run.wait,
                warmup_rounds: run.warmup_rounds,
                ..Scenario::blank(graph, 1)
            };
            let ran = launcher::launch(
                scenario,
                &IpcOptions {
                    agent_program: program,
                    round_timeout: run.round_timeout,
                    startup_timeout: run.startup_timeout,
                    global_barrier: run.global_barrier,
                    fault_injection: false,
                },
            )?;
            if !ran.leftovers.is_empty() {
                return Err(SolveError::Leftovers(ran.leftovers));
            }
            (
                ran.latency,
                ran.outcomes.iter().map(|o| o.usage).collect(),
                Some(ran.startup),
            )
        }
    };
    Ok(ProbeReport {
        latency: latency.summary(),
        usage: outcomes_usage
            .iter()
            .fold(ThreadUsage::default(), |sum, u| sum.plus(u)),
        startup,
        wall: started.elapsed(),
    })
}
