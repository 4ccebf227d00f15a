//! The settings of a solve.

use crate::transport::Transport;
use crate::wait::WaitStrategy;
use admm_ta_agents::method::Method;
use admm_ta_agents::primal::ProjectionPath;
use admm_ta_agents::ties;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Duration;

/// When the run ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum StopRule {
    /// All robots agree on one near-integral assignment for some rounds (default 10).
    Agreement,
    /// All robots round to the same assignment and their optimality-certificate slacks
    /// ([`admm_ta_agents::primal::PrimalAgent::certificate_slack`]) sum to at most `1e-9 ·` its cost scale: the
    /// assignment is then provably optimal to that tolerance. Checked centrally (sim only).
    Certified,
    /// The same certificate, decentralized: each robot checks its own slack and agreement
    /// with its neighbours, and a header protocol makes all robots stop at the same round
    /// (see [`admm_ta_agents::local_stop`]); costs about a graph diameter of extra rounds.
    /// Works on every transport (default).
    #[default]
    Local,
    /// Run to the iteration limit.
    MaxIters,
    /// The paper's criterion, for experiments only: stop at the first round whose relaxed
    /// objective (the robots' own columns) is within 0.1% of the centralized optimum. It
    /// needs the optimum, which no robot has (sim only).
    Oracle,
}

impl StopRule {
    pub fn name(self) -> &'static str {
        match self {
            Self::Agreement => "agreement",
            Self::Certified => "certified",
            Self::Local => "local",
            Self::MaxIters => "max-iters",
            Self::Oracle => "oracle",
        }
    }
}

/// Everything a solve needs besides the problem and the graph.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveConfig {
    pub method: Method,
    pub transport: Transport,
    /// `None`: the scale-free default of [`admm_ta_agents::rho::default_rho_for`].
    pub rho: Option<f64>,
    /// Anneal ρ by the schedule of [`admm_ta_agents::rho::RhoSchedule`] (every agent applies it at the same
    /// round).
    pub adaptive_rho: bool,
    /// `g` of the inexact dual's `γ = g (m+1)/(2dρ)`; `None`: the default.
    pub gamma_factor: Option<f64>,
    pub max_iters: usize,
    pub stop: StopRule,
    pub stop_rounds: usize,
    /// Seed of the tie-breaking perturbations.
    pub seed: u64,
    pub perturbation: ties::Perturbation,
    pub projection: ProjectionPath,
    /// Compare with the centralized optimum and trace convergence.
    pub check: bool,
    /// With `check` on the sim transport: record every round's objective in
    /// [`crate::solve::report::OracleCheck::trace`] (for convergence plots).
    pub trace: bool,
    /// Add a global barrier to every round (threads and ipc; for lockstep benchmarks).
    pub global_barrier: bool,
    /// Deadline of every wait for a neighbour or barrier (threads and ipc).
    pub round_timeout: Duration,
    /// Deadline for all agent processes to connect (ipc).
    pub startup_timeout: Duration,
    /// The `admm-ta` binary that runs agent processes (ipc).
    pub agent_program: Option<PathBuf>,
    /// What to do when an agent process fails (ipc).
    pub on_failure: OnFailure,
    /// Let agent processes honour the `ADMM_TA_FAULT` test switch (off for the survivors'
    /// re-solve, whose indices differ).
    pub fault_injection: bool,
    /// How agents wait for their neighbours (threads, ipc, uds).
    pub wait: WaitStrategy,
    /// Rounds run before latency and CPU usage are recorded (benchmarks).
    pub warmup_rounds: u64,
}

/// What the team does when an agent fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum OnFailure {
    /// Stop every agent and report the failure (the default).
    #[default]
    Abort,
    /// The survivors drop the failed robot and re-solve without it, if they still can
    /// (connected graph, at least as many robots as tasks).
    Continue,
}

impl Default for SolveConfig {
    fn default() -> Self {
        Self {
            method: Method::Primal,
            transport: Transport::Sim,
            rho: None,
            adaptive_rho: false,
            gamma_factor: None,
            max_iters: 5000,
            stop: StopRule::Local,
            stop_rounds: 10,
            seed: 0,
            perturbation: ties::Perturbation::Auto,
            projection: ProjectionPath::Fast,
            check: false,
            trace: false,
            global_barrier: false,
            round_timeout: Duration::from_secs(30),
            startup_timeout: Duration::from_secs(60),
            agent_program: None,
            on_failure: OnFailure::Abort,
            fault_injection: true,
            wait: WaitStrategy::Auto,
            warmup_rounds: 0,
        }
    }
}
