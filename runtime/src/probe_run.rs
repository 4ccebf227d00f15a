//! A latency-benchmark run: a team of [`ProbeAgent`](admm_ta_agents::methods::probe::ProbeAgent)s (payload of any length, a step of
//! known cost) for a fixed number of rounds on one transport, with warm-up rounds excluded
//! from the recorded latency and resource usage. The algorithmic counterpart is
//! [`crate::solve::solve`] with `StopRule::MaxIters` and warm-up rounds. The team runs on
//! the team runner ([`crate::runner`]), like a solve's.
//!
//! ```
//! use admm_ta_agents::methods::probe::ProbeStep;
//! use admm_ta_runtime::options::run::RunOptions;
//! use admm_ta_runtime::probe_run::{ProbeRun, run_probe};
//! use admm_ta_transport::Transport;
//! use admm_ta_topologies::generate;
//! let graph = generate::ring(4).unwrap();
//! let options = RunOptions::builder().transport(Transport::Threads).warmup_rounds(10).build().unwrap();
//! let run = ProbeRun { rounds: 50, ..ProbeRun::new(16, ProbeStep::Average, options) };
//! let report = run_probe(&graph, &run).unwrap();
//! assert_eq!(report.latency.round.count, 4 * 40);
//! ```

use crate::options::run::RunOptions;
use crate::runner::{RunError, run_team};
use crate::workload::Workload;
use admm_ta_agents::methods::probe::ProbeStep;
use admm_ta_topologies::Graph;
use admm_ta_transport::latency::LatencySummary;
use admm_ta_transport::usage::ThreadUsage;
use std::time::{Duration, Instant};

/// One benchmark run's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeRun {
    /// Values of every payload.
    pub payload_len: usize,
    pub step: ProbeStep,
    /// Rounds run in total, warm-up (`options.warmup_rounds()`) included.
    pub rounds: u64,
    /// The transport (threads or processes: a lockstep run measures no latency), waiting,
    /// barrier, timeouts, warm-up and agent program.
    pub options: RunOptions,
}

impl ProbeRun {
    /// 1100 rounds (the warm-up included) of `step` on payloads of `payload_len` values, run
    /// as `options` say.
    pub fn new(payload_len: usize, step: ProbeStep, options: RunOptions) -> Self {
        Self {
            payload_len,
            step,
            rounds: 1100,
            options,
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
    /// From the first agent process's spawn until all were connected (processes).
    pub startup: Option<Duration>,
    /// The whole run, start-up included.
    pub wall: Duration,
    /// Every agent's round stamps (`options.timeline()` on; [`admm_ta_transport::timeline`] renders them).
    pub timeline: Vec<Vec<admm_ta_transport::timeline::RoundStamp>>,
}

/// Runs `run` on `graph`.
pub fn run_probe(graph: &Graph, run: &ProbeRun) -> Result<ProbeReport, RunError> {
    let started = Instant::now();
    let team = run_team(
        Workload::Probe {
            payload_len: run.payload_len,
            step: run.step,
            rounds: run.rounds,
        },
        graph,
        &run.options,
    )?;
    Ok(ProbeReport {
        latency: team.latency.summary(),
        usage: team.usage,
        startup: team.startup,
        wall: started.elapsed(),
        timeline: team.outcomes.into_iter().map(|o| o.timeline).collect(),
    })
}
