//! One end-to-end solve: build the agents, run them, round, repair, check.

use crate::exchange::ExchangeError;
use crate::exchange::round_loop::{AgentOutcome, AgentPlan, AgentStop, payload_digest};
use crate::latency::LatencySummary;
use crate::process::launcher::{self, IpcOptions, LaunchError};
use crate::process::scenario::{ProcessTransport, Scenario, ScenarioStop};
use crate::sim::{LockstepSim, RoundView, SimOutcome};
use crate::team::Team;
use crate::threads;
use crate::usage::ThreadUsage;
use crate::wait::WaitStrategy;
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::local_stop::{LocalCertifiedStop, LocalStopError};
use admm_ta_agents::method::{AgentSettings, MethodAgent};
use admm_ta_agents::oracle::{self, OptimalAssignment};
use admm_ta_agents::primal::{PrimalSettings, ProjectionPath};
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_agents::rho::{self, RhoSchedule};
use admm_ta_agents::stopping::{AgreementStop, AgreementStreak, NeverStop};
use admm_ta_agents::{rounding, ties};
use admm_ta_topologies::Graph;
use serde::Serialize;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Agent state plus round buffers above this many bytes is refused up front.
pub const MEMORY_LIMIT_BYTES: f64 = 8.0 * (1u64 << 30) as f64;

pub use admm_ta_agents::method::Method;

/// What carries the messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Transport {
    /// Lockstep simulation in one thread.
    #[default]
    Sim,
    /// One OS thread per agent, lock-free slots, crossbeam parkers.
    Threads,
    /// One OS process per agent, iceoryx2 zero-copy publish-subscribe.
    Ipc,
    /// One OS process per agent, every payload copied through Unix-domain sockets: the
    /// baseline that shows what zero-copy saves ([`crate::uds`]).
    Uds,
    /// One OS process per agent, Zenoh publish-subscribe through a router: the transport of
    /// multi-host teams ([`crate::zenoh_net`]; needs the `zenoh` feature).
    Zenoh,
}

impl Transport {
    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sim => "sim",
            Self::Threads => "threads",
            Self::Ipc => "ipc",
            Self::Uds => "uds",
            Self::Zenoh => "zenoh",
        }
    }
}

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
    /// `None`: the scale-free default of [`rho::default_rho_for`].
    pub rho: Option<f64>,
    /// Anneal ρ by the schedule of [`rho::RhoSchedule`] (every agent applies it at the same
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
    /// [`OracleCheck::trace`] (for convergence plots).
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

/// Why the survivors of a failure could not re-solve (`--on-failure continue`).
#[derive(Debug, thiserror::Error)]
pub enum CannotContinue {
    #[error(
        "the {survivors} surviving robots cannot cover the {tasks} tasks (dropping a robot from Case 1 leaves fewer robots than tasks)"
    )]
    TooFewRobots { survivors: usize, tasks: usize },
    #[error("without robot {failed} the communication graph is disconnected")]
    Disconnected { failed: usize },
    #[error("the survivors' re-solve failed too: {0}")]
    ResolveFailed(Box<SolveError>),
}

/// A failed robot and how the survivors went on (`--on-failure continue`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Degraded {
    /// The failure of the first run, as the launcher reported it.
    pub failure: String,
    pub failed_robot: usize,
    /// Original index of each robot of `assignment` (the survivors, in order).
    pub survivors: Vec<usize>,
    /// Rounds of the first run lost to the failure (the failed robot's last published round).
    pub lost_rounds: u64,
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

/// Reasons a solve cannot start or complete.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(
        "--stop {stop} needs the whole team's state: it runs on the sim transport only (use --stop local or max-iters)"
    )]
    CentralStop { stop: &'static str },
    #[error("--global-barrier needs the threads or ipc transport (sim, uds and zenoh have none)")]
    BarrierNeedsAgents,
    #[error("round latency is measured on a distributed transport: threads, ipc, uds or zenoh")]
    NotDistributed,
    #[error("the ipc, uds and zenoh transports need the admm-ta binary to start agents from")]
    NoAgentProgram,
    #[error(transparent)]
    LocalStop(#[from] LocalStopError),
    #[error(transparent)]
    Exchange(#[from] ExchangeError),
    #[error(transparent)]
    Launch(#[from] LaunchError),
    #[error("the run finished but could not remove its files: {0:?}")]
    Leftovers(Vec<PathBuf>),
    #[error("the topology has {graph} robots but the costs have {problem}")]
    SizeMismatch { graph: usize, problem: usize },
    #[error("ρ must be a positive finite number, got {0}")]
    BadRho(f64),
    #[error(
        "--method hungarian is the centralized solver: it runs in this process, with --transport sim"
    )]
    CentralizedMethod,
    #[error("the γ factor must be a positive finite number, got {0}")]
    BadGamma(f64),
    #[error(
        "--stop {stop} reads every robot's m×n matrix: it works with --method primal only (use --stop local, oracle or max-iters)"
    )]
    PrimalOnlyStop { stop: &'static str },
    #[error("--max-iters must be at least 1")]
    NoIterations,
    /// An agent failed and, with `--on-failure continue`, the survivors could not go on.
    #[error("{first}; --on-failure continue: {reason}")]
    CannotContinue {
        first: Box<SolveError>,
        reason: CannotContinue,
    },
    #[error(
        "{robots} robots × {tasks} tasks need about {gib:.1} GiB of agent state (each robot holds an m×n matrix); the limit is 8 GiB"
    )]
    TooLarge {
        robots: usize,
        tasks: usize,
        gib: f64,
    },
}

/// Comparison with the centralized optimum, and how fast the run got there.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OracleCheck {
    pub optimal_cost: f64,
    /// `(cost − optimal) / |optimal|` (absolute gap when the optimum is 0).
    pub gap: f64,
    pub optimal: bool,
    /// First round whose relaxed objective (robots' own columns) is within 0.1% of the
    /// optimum: the paper's criterion (not shift-invariant).
    pub rounds_within_0_1pct: Option<usize>,
    /// Round from which the relaxed objective stays within 0.1% until the end.
    pub rounds_settled_0_1pct: Option<usize>,
    /// Round from which every robot's own argmax is an optimal assignment until the end
    /// (shift-invariant).
    pub rounds_to_optimal_assignment: Option<usize>,
    /// Every round's objectives, when [`SolveConfig::trace`] asked for them (sim only).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub trace: Vec<TracePoint>,
}

/// The team's objectives after one round.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TracePoint {
    pub round: usize,
    /// `Σ_i α_iᵀ x_i` over the robots' own relaxed columns (the paper's Fig. 1 quantity).
    pub relaxed_cost: f64,
    /// Cost of the robots' own rounded choices, when they form a feasible assignment.
    pub assignment_cost: Option<f64>,
}

/// The outcome of a solve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolveReport {
    /// Task index per robot (always feasible).
    pub assignment: Vec<usize>,
    pub cost: f64,
    pub iterations: usize,
    /// The stop rule fired before the iteration limit.
    pub converged: bool,
    /// The robots' own choices conflicted and were repaired.
    pub repaired: bool,
    pub method: Method,
    pub transport: Transport,
    pub rho: f64,
    pub robots: usize,
    pub tasks: usize,
    pub case: u8,
    pub topology: String,
    /// Tie-breaking perturbation added to the costs (`null`: none).
    pub perturbation: Option<f64>,
    /// Mean Newton steps of the projection per robot and round.
    pub mean_projection_steps: f64,
    /// Bytes of one message (payload and header); every agent publishes one per round.
    pub message_bytes: usize,
    /// Messages each agent published (one per round; 0 for the centralized method).
    pub messages_per_agent: usize,
    /// `messages_per_agent · message_bytes`.
    pub bytes_per_agent: usize,
    pub wall_time_ms: f64,
    pub stop: StopRule,
    /// Round whose assignment the local stop certified (`iterations − diameter`).
    pub certified_round: Option<usize>,
    pub global_barrier: bool,
    /// Per-round latency percentiles of the agents (threads and ipc), in microseconds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub round_latency_us: Option<LatencySummary>,
    /// CPU time and context switches of all agents together over the recorded rounds
    /// (threads, ipc, uds).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub agent_usage: Option<ThreadUsage>,
    /// Time for all agent processes to start and connect (ipc).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub startup_ms: Option<f64>,
    /// The ipc run's id: its iceoryx2 prefix is `adta<id>_`, its directory
    /// `<tmp>/admm-ta-runs/<id>`; both are gone when the solve returns.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub run_id: Option<String>,
    /// Hash of each agent's last published payload (to compare transports).
    #[serde(skip)]
    pub iterate_digests: Vec<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<OracleCheck>,
    /// Set when a robot failed and the survivors re-solved without it: `assignment`,
    /// `robots`, `cost` and `check` are then the survivors'.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub degraded: Option<Degraded>,
}

/// Solves `problem` on `graph` as `config` says; with [`OnFailure::Continue`], a failed
/// agent process is dropped and the survivors re-solve without it (ipc).
pub fn solve(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    config: &SolveConfig,
) -> Result<SolveReport, SolveError> {
    let (first, failed, lost_rounds) = match solve_once(problem, graph, config) {
        Err(first @ SolveError::Launch(LaunchError::AgentFailed { index, round, .. }))
            if config.on_failure == OnFailure::Continue =>
        {
            (first, index, round)
        }
        other => return other,
    };
    match solve_without(problem, graph, config, failed) {
        Ok((survivors, mut report)) => {
            report.degraded = Some(Degraded {
                failure: first.to_string(),
                failed_robot: failed,
                survivors,
                lost_rounds,
            });
            Ok(report)
        }
        Err(reason) => Err(SolveError::CannotContinue {
            first: Box::new(first),
            reason,
        }),
    }
}

/// Re-solves without robot `failed` (fresh agents, cold start); returns the survivors'
/// original indices and their report.
fn solve_without(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    config: &SolveConfig,
    failed: usize,
) -> Result<(Vec<usize>, SolveReport), CannotContinue> {
    let survivors: Vec<usize> = (0..problem.robots()).filter(|&r| r != failed).collect();
    let (n, m) = (survivors.len(), problem.tasks());
    if n < m {
        return Err(CannotContinue::TooFewRobots {
            survivors: n,
            tasks: m,
        });
    }
    let values = survivors
        .iter()
        .flat_map(|&r| problem.costs().row(r).iter().copied())
        .collect();
    let costs = admm_ta_agents::problem::CostMatrix::new(n, m, values)
        .expect("rows of a valid matrix form a valid matrix");
    let reduced = TaskAssignmentProblem::new(costs, admm_ta_agents::problem::CaseChoice::Auto)
        .expect("n ≥ m survivors form a valid problem");
    let new_index = |r: usize| if r > failed { r - 1 } else { r };
    let edges: Vec<(usize, usize)> = graph
        .edges()
        .filter(|&(a, b)| a != failed && b != failed)
        .map(|(a, b)| (new_index(a), new_index(b)))
        .collect();
    let subgraph = Graph::from_edges(
        n,
        &edges,
        format!("{} without robot {failed}", graph.name()),
    )
    .ok()
    .filter(Graph::is_connected)
    .ok_or(CannotContinue::Disconnected { failed })?;
    let again = SolveConfig {
        on_failure: OnFailure::Abort,
        fault_injection: false,
        ..config.clone()
    };
    let report = solve_once(&reduced, &subgraph, &again)
        .map_err(|second| CannotContinue::ResolveFailed(Box::new(second)))?;
    Ok((survivors, report))
}

fn solve_once(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    config: &SolveConfig,
) -> Result<SolveReport, SolveError> {
    let (n, m) = (problem.robots(), problem.tasks());
    if graph.robots() != n {
        return Err(SolveError::SizeMismatch {
            graph: graph.robots(),
            problem: n,
        });
    }
    if config.max_iters == 0 {
        return Err(SolveError::NoIterations);
    }
    let bytes = 8.0 * 6.0 * (m * n) as f64 * n as f64;
    if bytes > MEMORY_LIMIT_BYTES {
        return Err(SolveError::TooLarge {
            robots: n,
            tasks: m,
            gib: bytes / (1u64 << 30) as f64,
        });
    }
    if config.method == Method::Hungarian && config.transport != Transport::Sim {
        return Err(SolveError::CentralizedMethod);
    }
    let prepared = prepare(problem, graph, config)?;
    let rho = prepared.rho;
    let optimum = (config.check || config.stop == StopRule::Oracle)
        .then(|| oracle::solve(problem).expect("validated costs have an optimum"));
    if config.global_barrier
        && matches!(
            config.transport,
            Transport::Sim | Transport::Uds | Transport::Zenoh
        )
    {
        return Err(SolveError::BarrierNeedsAgents);
    }
    if config.transport != Transport::Sim
        && matches!(
            config.stop,
            StopRule::Certified | StopRule::Agreement | StopRule::Oracle
        )
    {
        return Err(SolveError::CentralStop {
            stop: config.stop.name(),
        });
    }
    if config.method != Method::Primal
        && matches!(config.stop, StopRule::Certified | StopRule::Agreement)
    {
        return Err(SolveError::PrimalOnlyStop {
            stop: config.stop.name(),
        });
    }
    let started = Instant::now();
    let mut tracer = optimum.as_ref().map(|o| Tracer::new(problem, o));
    if let Some(t) = tracer.as_mut() {
        t.record = config.trace;
    }
    let run = if config.method == Method::Hungarian {
        tracer = None;
        let optimum = optimum
            .clone()
            .unwrap_or_else(|| oracle::solve(problem).expect("validated costs have an optimum"));
        RunResult::centralized(optimum)
    } else {
        run_agents(
            problem,
            graph,
            config,
            &prepared,
            &mut tracer,
            optimum.as_ref(),
        )?
    };
    let wall_time_ms = started.elapsed().as_secs_f64() * 1e3;
    let (message_bytes, messages_per_agent) = match config.method {
        Method::Hungarian => (0, 0),
        method => (
            8 * method.payload_len(n, m)
                + std::mem::size_of::<crate::exchange::header::RoundHeader>(),
            run.rounds,
        ),
    };
    let (assignment, repaired) = rounding::repair(problem, &run.decisions);
    let cost = problem
        .cost_of(&assignment)
        .expect("repaired assignment is in range");
    let check = match (tracer, optimum) {
        (Some(t), _) => Some(t.finish(cost)),
        (None, Some(o)) => Some(Tracer::new(problem, &o).finish(cost)),
        (None, None) => None,
    };
    Ok(SolveReport {
        degraded: None,
        assignment,
        cost,
        iterations: run.rounds,
        converged: run.converged,
        repaired,
        method: config.method,
        transport: config.transport,
        rho,
        robots: n,
        tasks: m,
        case: problem.case().number(),
        topology: graph.name().to_string(),
        perturbation: prepared.team.epsilon,
        mean_projection_steps: run.projection_steps as f64 / (n * run.rounds.max(1)) as f64,
        message_bytes,
        messages_per_agent,
        bytes_per_agent: message_bytes * messages_per_agent,
        wall_time_ms,
        stop: config.stop,
        certified_round: run.certified_round,
        global_barrier: config.global_barrier,
        round_latency_us: run.latency,
        agent_usage: run.usage,
        startup_ms: run.startup_ms,
        run_id: run.run_id,
        iterate_digests: run.iterate_digests,
        check,
    })
}

/// Runs the agents of a distributed method over the configured transport.
#[allow(clippy::too_many_arguments)]
fn run_agents(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    config: &SolveConfig,
    prepared: &Prepared<'_>,
    tracer: &mut Option<Tracer<'_>>,
    optimum: Option<&OptimalAssignment>,
) -> Result<RunResult, SolveError> {
    let n = problem.robots();
    let (team, tolerance, diameter) = (&prepared.team, prepared.tolerance, prepared.diameter);
    let local_stop = || LocalCertifiedStop::new(diameter, n, tolerance);
    let run = match config.transport {
        Transport::Sim => {
            let mut sim = LockstepSim::new(team.agents(), graph);
            let mut projection_steps = 0usize;
            let mut observer = |view: &RoundView<'_>| {
                projection_steps += view
                    .reports
                    .iter()
                    .map(|r| r.inner_iterations)
                    .sum::<usize>();
                if let Some(t) = tracer.as_mut() {
                    t.observe(view);
                }
            };
            let mut agreement = AgreementStop::new(config.stop_rounds);
            let mut certified = None;
            let outcome = match config.stop {
                StopRule::Agreement => sim.run(config.max_iters, &mut agreement, &mut observer),
                StopRule::MaxIters => sim.run(config.max_iters, &mut NeverStop, &mut observer),
                StopRule::Certified => {
                    run_until_certified(&mut sim, config.max_iters, tolerance, &mut observer)
                }
                StopRule::Oracle => {
                    // The paper's criterion, with the centralized optimum (experiments only).
                    let optimal_cost = optimum.expect("oracle stop has the optimum").cost;
                    sim.run_until(config.max_iters, &mut observer, |sim| {
                        within_0_1pct(relaxed_objective(problem, &sim.view()), optimal_cost)
                    })
                }
                StopRule::Local => {
                    let mut stops = vec![local_stop()?; n];
                    let local = sim.run_local_stop(&mut stops, config.max_iters, &mut observer);
                    certified = local.certified;
                    SimOutcome {
                        rounds: local.rounds,
                        stopped: certified.is_some(),
                    }
                }
            };
            let decisions = match certified {
                Some((_, ref tasks)) => tasks.clone(),
                None => sim.agents().iter().map(ConsensusAgent::decide).collect(),
            };
            RunResult {
                decisions,
                rounds: outcome.rounds,
                converged: outcome.stopped,
                certified_round: certified.map(|(r, _)| r),
                projection_steps,
                latency: None,
                usage: None,
                startup_ms: None,
                run_id: None,
                iterate_digests: (0..n).map(|i| payload_digest(sim.payload(i))).collect(),
            }
        }
        Transport::Threads => {
            let stop = match config.stop {
                StopRule::MaxIters => AgentStop::MaxIters,
                _ => AgentStop::Local(local_stop()?),
            };
            let plans: Vec<AgentPlan> = (0..n)
                .map(|index| AgentPlan {
                    index,
                    max_rounds: config.max_iters as u64,
                    stop: stop.clone(),
                    round_timeout: config.round_timeout,
                    global_barrier: config.global_barrier,
                    warmup_rounds: config.warmup_rounds,
                })
                .collect();
            let mut agents = team.agents();
            let outcomes = threads::run_threads_waiting(&mut agents, graph, &plans, config.wait)?;
            let mut latency = crate::latency::RoundLatency::new();
            for o in &outcomes {
                latency
                    .merge(&o.latency)
                    .expect("agents record every component");
            }
            RunResult::from_outcomes(&outcomes, Some(latency.summary()), None)
        }
        Transport::Ipc | Transport::Uds | Transport::Zenoh => {
            local_stop()?;
            let program = config
                .agent_program
                .clone()
                .ok_or(SolveError::NoAgentProgram)?;
            let scenario = scenario_of(problem, graph, config, prepared)?;
            let run = launcher::launch(
                scenario,
                &IpcOptions {
                    agent_program: program,
                    round_timeout: config.round_timeout,
                    startup_timeout: config.startup_timeout,
                    global_barrier: config.global_barrier,
                    fault_injection: config.fault_injection,
                },
            )?;
            if !run.leftovers.is_empty() {
                return Err(SolveError::Leftovers(run.leftovers));
            }
            RunResult {
                run_id: Some(run.run_id),
                ..RunResult::from_outcomes(
                    &run.outcomes,
                    Some(run.latency.summary()),
                    Some(run.startup.as_secs_f64() * 1e3),
                )
            }
        }
    };
    Ok(run)
}

/// What every transport's agents are built from.
struct Prepared<'a> {
    rho: f64,
    tolerance: f64,
    diameter: usize,
    team: Team<'a>,
}

/// ρ, γ, the tie-breaking perturbation, the stop tolerance and the agents' settings, as every
/// transport (and every independently started agent) computes them.
fn prepare<'a>(
    problem: &'a TaskAssignmentProblem,
    graph: &'a Graph,
    config: &SolveConfig,
) -> Result<Prepared<'a>, SolveError> {
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
        return Err(SolveError::BadRho(rho));
    }
    let gamma_factor = config
        .gamma_factor
        .unwrap_or(admm_ta_agents::dual::DEFAULT_GAMMA_FACTOR);
    if !(gamma_factor > 0.0 && gamma_factor.is_finite()) {
        return Err(SolveError::BadGamma(gamma_factor));
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
    let team = Team {
        problem,
        graph,
        settings,
        epsilon,
        seed: config.seed,
        schedule,
    };
    Ok(Prepared {
        rho,
        tolerance,
        diameter,
        team,
    })
}

/// The scenario an agent process of `problem` on `graph` runs with `config` (run id, prefix,
/// root and board name still to be filled in): what `solve --transport ipc` hands its
/// agents, and what an independently started agent (`admm-ta agent --team`) builds itself.
pub fn agent_scenario(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    config: &SolveConfig,
) -> Result<Scenario, SolveError> {
    let prepared = prepare(problem, graph, config)?;
    scenario_of(problem, graph, config, &prepared)
}

fn scenario_of(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    config: &SolveConfig,
    prepared: &Prepared<'_>,
) -> Result<Scenario, SolveError> {
    let (n, m) = (problem.robots(), problem.tasks());
    let team = &prepared.team;
    LocalCertifiedStop::new(prepared.diameter, n, prepared.tolerance)?;
    Ok(Scenario {
        run_id: String::new(),
        iceoryx_prefix: String::new(),
        iceoryx_root: PathBuf::new(),
        robots: n,
        tasks: m,
        case: problem.case(),
        cost_bits: problem
            .costs()
            .values()
            .iter()
            .map(|v| v.to_bits())
            .collect(),
        edges: graph.edges().collect(),
        topology: graph.name().to_string(),
        method: config.method,
        rho_bits: team.settings.rho.to_bits(),
        gamma_factor_bits: team.settings.gamma_factor.to_bits(),
        adaptive_rho: config.adaptive_rho,
        epsilon_bits: team.epsilon.map(f64::to_bits),
        seed: config.seed,
        qp_projection: config.projection == ProjectionPath::Qp,
        stop: match config.stop {
            StopRule::MaxIters => ScenarioStop::MaxIters,
            _ => ScenarioStop::Local {
                tolerance_bits: prepared.tolerance.to_bits(),
            },
        },
        max_rounds: config.max_iters as u64,
        diameter: prepared.diameter,
        round_timeout_ms: config.round_timeout.as_millis() as u64,
        startup_timeout_ms: config.startup_timeout.as_millis() as u64,
        board_shm: String::new(),
        global_barrier: config.global_barrier,
        workload: Default::default(),
        transport: ProcessTransport::for_transport(config.transport),
        wait: config.wait,
        warmup_rounds: config.warmup_rounds,
        zenoh: None,
        local_agents: None,
    })
}

/// What any transport's run yields, before rounding and checking.
struct RunResult {
    decisions: Vec<usize>,
    rounds: usize,
    converged: bool,
    certified_round: Option<usize>,
    projection_steps: usize,
    latency: Option<LatencySummary>,
    usage: Option<ThreadUsage>,
    startup_ms: Option<f64>,
    run_id: Option<String>,
    iterate_digests: Vec<u64>,
}

impl RunResult {
    /// The centralized Hungarian method: the optimum in one "round", no messages.
    fn centralized(optimum: OptimalAssignment) -> Self {
        Self {
            decisions: optimum.assignment,
            rounds: 1,
            converged: true,
            certified_round: None,
            projection_steps: 0,
            latency: None,
            usage: None,
            startup_ms: None,
            run_id: None,
            iterate_digests: Vec::new(),
        }
    }

    fn from_outcomes(
        outcomes: &[AgentOutcome],
        latency: Option<LatencySummary>,
        startup_ms: Option<f64>,
    ) -> Self {
        let first = &outcomes[0];
        Self {
            decisions: outcomes.iter().map(|o| o.task).collect(),
            rounds: first.rounds as usize,
            converged: first.converged,
            certified_round: first.certified_round.map(|r| r as usize),
            projection_steps: outcomes.iter().map(|o| o.projection_steps as usize).sum(),
            latency,
            usage: Some(
                outcomes
                    .iter()
                    .fold(ThreadUsage::default(), |sum, o| sum.plus(&o.usage)),
            ),
            startup_ms,
            run_id: None,
            iterate_digests: outcomes.iter().map(|o| o.iterate_digest).collect(),
        }
    }
}

/// One primal agent per robot of `graph`, each with its own (optionally perturbed) costs,
/// built as [`solve`] builds them (for examples and tests that drive a simulation).
pub fn primal_team(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    settings: PrimalSettings,
    epsilon: Option<f64>,
    seed: u64,
) -> Vec<MethodAgent> {
    let diameter = graph.diameter().unwrap_or(0);
    Team {
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

/// Rounds after which an agreement is first certified, and the spacing of later checks
/// (each check is one `m × n` assignment problem per robot).
const CERTIFY_AFTER: usize = 3;
const CERTIFY_EVERY: usize = 5;

/// Steps until the robots agree on one assignment whose certificate slacks sum to at most
/// `tolerance` (see [`admm_ta_agents::primal::PrimalAgent::certificate_slack`]), or
/// `max_rounds`.
fn run_until_certified(
    sim: &mut LockstepSim<MethodAgent>,
    max_rounds: usize,
    tolerance: f64,
    observer: &mut dyn FnMut(&RoundView<'_>),
) -> SimOutcome {
    // Agreement on one feasible assignment; near-integrality is not needed here.
    let mut streak = AgreementStreak::default();
    sim.run_until(max_rounds, observer, |sim| {
        let agreed_for = streak.observe(sim.view().reports, f64::MAX);
        agreed_for >= CERTIFY_AFTER
            && (agreed_for - CERTIFY_AFTER).is_multiple_of(CERTIFY_EVERY)
            && sim
                .agents()
                .iter()
                .map(ConsensusAgent::certificate_slack)
                .sum::<f64>()
                <= tolerance
    })
}

/// `Σ_i α_iᵀ x_i` over the robots' own relaxed columns.
fn relaxed_objective(problem: &TaskAssignmentProblem, view: &RoundView<'_>) -> f64 {
    (0..problem.robots())
        .map(|i| {
            view.columns
                .own_column(i)
                .iter()
                .zip(problem.costs().row(i))
                .map(|(x, a)| x * a)
                .sum::<f64>()
        })
        .sum()
}

/// `(value − optimum)/|optimum|` (absolute difference when the optimum is 0).
fn relative_gap(value: f64, optimum: f64) -> f64 {
    let diff = value - optimum;
    if optimum != 0.0 {
        diff / optimum.abs()
    } else {
        diff
    }
}

/// The paper's criterion: within 0.1% of the optimum.
fn within_0_1pct(value: f64, optimum: f64) -> bool {
    relative_gap(value, optimum).abs() <= 1e-3
}

/// Follows the run against the optimum (only when checking).
struct Tracer<'p> {
    problem: &'p TaskAssignmentProblem,
    optimal_cost: f64,
    first_within: Option<usize>,
    settled_within: Option<usize>,
    optimal_since: Option<usize>,
    decisions: Vec<usize>,
    record: bool,
    trace: Vec<TracePoint>,
}

impl<'p> Tracer<'p> {
    fn new(problem: &'p TaskAssignmentProblem, optimum: &OptimalAssignment) -> Self {
        Self {
            problem,
            optimal_cost: optimum.cost,
            first_within: None,
            settled_within: None,
            optimal_since: None,
            decisions: vec![0; problem.robots()],
            record: false,
            trace: Vec::new(),
        }
    }

    fn relative_gap(&self, cost: f64) -> f64 {
        relative_gap(cost, self.optimal_cost)
    }

    fn observe(&mut self, view: &RoundView<'_>) {
        for i in 0..self.problem.robots() {
            self.decisions[i] = rounding::argmax(view.columns.own_column(i));
        }
        let relaxed_cost = relaxed_objective(self.problem, view);
        if within_0_1pct(relaxed_cost, self.optimal_cost) {
            self.first_within.get_or_insert(view.round);
            self.settled_within.get_or_insert(view.round);
        } else {
            self.settled_within = None;
        }
        let assignment_cost = self
            .problem
            .is_feasible(&self.decisions)
            .then(|| self.problem.cost_of(&self.decisions).ok())
            .flatten();
        if self.record {
            self.trace.push(TracePoint {
                round: view.round,
                relaxed_cost,
                assignment_cost,
            });
        }
        let optimal = self.relative_gap(assignment_cost.unwrap_or(f64::INFINITY)) <= 1e-9;
        if optimal {
            self.optimal_since.get_or_insert(view.round);
        } else {
            self.optimal_since = None;
        }
    }

    fn finish(self, cost: f64) -> OracleCheck {
        let gap = self.relative_gap(cost);
        OracleCheck {
            optimal_cost: self.optimal_cost,
            gap,
            optimal: gap <= 1e-9,
            rounds_within_0_1pct: self.first_within,
            rounds_settled_0_1pct: self.settled_within,
            rounds_to_optimal_assignment: self.optimal_since,
            trace: self.trace,
        }
    }
}
