//! One end-to-end solve: build the agents, run them, round, repair, check.
//!
//! * [`error`]: why a solve fails; [`report`]: what it reports;
//! * [`trace`]: the oracle tracer of a checked solve;
//! * [`lockstep`]: the central stop rules of the simulation.

pub mod error;
pub(crate) mod lockstep;
pub mod report;
pub(crate) mod trace;

use crate::exchange::round_loop::{AgentOutcome, AgentPlan, AgentStop, payload_digest};
use crate::latency::LatencySummary;
use crate::options::{OnFailure, SolveConfig, StopRule};
use crate::process::launcher::{self, IpcOptions, LaunchError};
use crate::process::scenario::scenario_of;
use crate::sim::{LockstepSim, RoundView, SimOutcome};
use crate::solve::error::{CannotContinue, SolveError};
use crate::solve::lockstep::run_until_certified;
use crate::solve::report::{Degraded, SolveReport};
use crate::solve::trace::{Tracer, relaxed_objective, within_0_1pct};
use crate::threads;
use crate::transport::Execution;
use crate::usage::ThreadUsage;
use crate::workload::plan::{Plan, prepare};
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::local_stop::LocalCertifiedStop;
use admm_ta_agents::oracle::{self, OptimalAssignment};
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_agents::rounding;
use admm_ta_agents::stopping::{AgreementStop, NeverStop};
use admm_ta_topologies::Graph;
use std::time::Instant;

/// Agent state plus round buffers above this many bytes is refused up front.
pub const MEMORY_LIMIT_BYTES: f64 = 8.0 * (1u64 << 30) as f64;

pub use admm_ta_agents::method::Method;

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
    let capabilities = config.transport.capabilities();
    if config.method == Method::Hungarian && capabilities.execution != Execution::Lockstep {
        return Err(SolveError::CentralizedMethod);
    }
    let prepared = prepare(problem, graph, config)?;
    let rho = prepared.rho;
    let optimum = (config.check || config.stop == StopRule::Oracle)
        .then(|| oracle::solve(problem).expect("validated costs have an optimum"));
    if config.global_barrier && !capabilities.global_barrier {
        return Err(SolveError::BarrierNeedsAgents);
    }
    if capabilities.execution != Execution::Lockstep
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
        perturbation: prepared.agents.epsilon,
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
    prepared: &Plan<'_>,
    tracer: &mut Option<Tracer<'_>>,
    optimum: Option<&OptimalAssignment>,
) -> Result<RunResult, SolveError> {
    let n = problem.robots();
    let (team, tolerance, diameter) = (&prepared.agents, prepared.tolerance, prepared.diameter);
    let local_stop = || LocalCertifiedStop::new(diameter, n, tolerance);
    let run = match config.transport.capabilities().execution {
        Execution::Lockstep => {
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
        Execution::Threads => {
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
        Execution::Processes => {
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
