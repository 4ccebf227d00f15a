//! One end-to-end solve: build the agents, run them, round, repair, check.
//!
//! * [`error`]: why a solve fails; [`report`]: what it reports;
//! * `trace`: the oracle tracer of a checked solve; `memory`: the refusal of a solve too
//!   large for the machine;
//! * `lockstep`: what a solve watches of a lockstep run (the tracer, the central stop
//!   rules).

pub mod error;
pub(crate) mod lockstep;
mod memory;
pub mod report;
pub(crate) mod trace;
pub(crate) mod user;

use crate::options::{OnFailure, SolveOptions, StopRule};
use crate::process::launcher::LaunchError;
use crate::runner::{RunError, TeamRun, run_team_watched};
use crate::solve::error::{CannotContinue, SolveError};
use crate::solve::lockstep::SolveWatch;
pub use crate::solve::memory::MEMORY_LIMIT_BYTES;
use crate::solve::memory::check_size;
use crate::solve::report::{Degraded, SolveReport};
use crate::solve::trace::{Affine, Tracer, decides_by_readout};
use crate::workload::Workload;
use crate::workload::plan::{Plan, prepare};
use admm_ta_agents::certify::local_stop::LocalCertifiedStop;
use admm_ta_agents::certify::oracle::{self, OptimalAssignment};
use admm_ta_agents::certify::rounding;
use admm_ta_agents::method::info::Numbers;
use admm_ta_agents::problem::ties;
use admm_ta_agents::problem::{
    AssignmentCase, CaseChoice, CostMatrix, IDLE, TaskAssignmentProblem,
};
use admm_ta_topologies::Graph;
use admm_ta_transport::Execution;
use admm_ta_transport::exchange::header::RoundHeader;
use admm_ta_transport::exchange::round_loop::AgentStop;
use admm_ta_transport::latency::LatencySummary;
use admm_ta_transport::usage::ThreadUsage;
use std::time::Instant;

/// Solves `problem` on `graph` as `options` say; with [`OnFailure::Continue`], a failed
/// agent process is dropped and the survivors re-solve without it. The agents solve the
/// normalised problem ([`TaskAssignmentProblem::internal`]); the report is in the user's
/// numbers.
pub fn solve(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    options: &SolveOptions,
) -> Result<SolveReport, SolveError> {
    let (first, failed, lost_rounds) = match solve_user(problem, graph, options) {
        Err(
            first @ SolveError::Run(RunError::Launch(LaunchError::AgentFailed {
                index, round, ..
            })),
        ) if options.on_failure() == OnFailure::Continue
            // The transposed problem's agents are tasks: no robot to drop.
            && problem.internal().robots() == problem.robots() =>
        {
            (first, index, round.unwrap_or(0))
        }
        other => return other,
    };
    match solve_without(problem, graph, options, failed) {
        Ok((survivors, mut report)) => {
            // In the user's numbering: the failed robot has no task (`null` in JSON).
            let mut assignment = vec![IDLE; problem.robots()];
            for (k, &robot) in survivors.iter().enumerate() {
                assignment[robot] = report.assignment[k];
            }
            report.assignment = assignment;
            report.idle_robots = report.idle_robots.iter().map(|&k| survivors[k]).collect();
            report.robots = problem.robots();
            report.robot_names = problem.costs().robot_names().map(<[String]>::to_vec);
            report.task_names = problem.costs().task_names().map(<[String]>::to_vec);
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
    options: &SolveOptions,
    failed: usize,
) -> Result<(Vec<usize>, SolveReport), CannotContinue> {
    let survivors: Vec<usize> = (0..problem.robots()).filter(|&r| r != failed).collect();
    let (n, m) = (survivors.len(), problem.tasks());
    let idle = problem.case() == AssignmentCase::Idle;
    if n < m && !idle {
        return Err(CannotContinue::TooFewRobots {
            survivors: n,
            tasks: m,
        });
    }
    let values = survivors
        .iter()
        .flat_map(|&r| problem.costs().row(r).iter().copied())
        .collect();
    let choice = if idle {
        CaseChoice::Forced(AssignmentCase::Idle)
    } else {
        CaseChoice::Auto
    };
    let reduced = CostMatrix::new(n.max(1), m, values)
        .and_then(|costs| {
            if problem.maximize() {
                TaskAssignmentProblem::maximizing(costs, choice)
            } else {
                TaskAssignmentProblem::new(costs, choice)
            }
        })
        .map_err(|e| CannotContinue::Infeasible(e.to_string()))?;
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
    let again = options
        .to_builder()
        .on_failure(OnFailure::Abort)
        .fault_injection(false)
        .build()
        .map_err(|e| CannotContinue::ResolveFailed(Box::new(SolveError::Config(e))))?;
    let report = solve_user(&reduced, &subgraph, &again).map_err(|mut second| {
        // The re-solve numbers the survivors 0..n-1: name the robot by its own number.
        if let SolveError::Run(RunError::Launch(LaunchError::AgentFailed {
            index, message, ..
        })) = &mut second
        {
            let survivor = *index;
            *index = survivors[survivor];
            *message = format!(
                "{message} (in the survivors' re-solve, where robot {} was agent {survivor})",
                *index
            );
        }
        CannotContinue::ResolveFailed(Box::new(second))
    })?;
    Ok((survivors, report))
}

/// One run of the user's problem: refuse what the method cannot solve faithfully, run the
/// normalised problem, report in the user's numbers.
fn solve_user(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    options: &SolveOptions,
) -> Result<SolveReport, SolveError> {
    user::check_supported(problem, options.method())?;
    // Refused before anything large is built (the exact optimum, the tasks' graph).
    check_size(problem, graph, options.method())?;
    let centralized = options.method().team().is_none();
    let needs_optimum = centralized || options.check() || options.stop() == StopRule::Oracle;
    let started = Instant::now();
    let exact = if needs_optimum {
        Some(oracle::solve(problem).map_err(|e| SolveError::Internal(e.to_string()))?)
    } else {
        None
    };
    let oracle_ms = started.elapsed().as_secs_f64() * 1e3;
    let exact_team = !centralized && options.method().info().numbers == Numbers::Exact;
    let report = if exact_team {
        // A team that solves the user's own numbers (the distributed Hungarian: no
        // perturbation, every robot solves the same matrix the same way).
        let exact_problem = problem
            .exact()
            .map_err(|e| SolveError::Internal(e.to_string()))?;
        let optimum = match &exact {
            Some(exact) => Some(OptimalAssignment {
                assignment: exact.assignment.clone(),
                cost: exact_problem
                    .cost_of(&exact.assignment)
                    .map_err(|e| SolveError::Internal(e.to_string()))?,
            }),
            None => None,
        };
        let unperturbed = options
            .to_builder()
            .perturbation(admm_ta_agents::problem::ties::Perturbation::Off)
            .build()?;
        solve_once(
            &exact_problem,
            graph,
            &unperturbed,
            optimum,
            Affine::IDENTITY,
        )?
    } else {
        let internal_optimum = match &exact {
            Some(exact) => Some(user::internal_optimum(problem, exact)?),
            None => None,
        };
        // The centralized solver has no team: no graph to lift onto the tasks.
        let internal_graph = if centralized {
            graph.clone()
        } else {
            user::internal_graph(problem, graph)?
        };
        solve_once(
            problem.internal(),
            &internal_graph,
            options,
            internal_optimum,
            user::affine(problem),
        )?
    };
    let mut report = user::to_user(problem, report, exact.as_ref())?;
    report.topology = graph.name().to_string();
    report.robot_names = problem.costs().robot_names().map(<[String]>::to_vec);
    report.task_names = problem.costs().task_names().map(<[String]>::to_vec);
    if centralized {
        // The centralized solver's work is the exact optimum.
        report.wall_time_ms += oracle_ms;
    }
    Ok(report)
}

/// The team of `plan` (or, with none, the centralized solver) on `problem`: what it yields,
/// with the `tracer` the watch kept.
fn run_solve<'p>(
    problem: &'p TaskAssignmentProblem,
    graph: &Graph,
    options: &SolveOptions,
    plan: Option<&Plan<'_>>,
    tracer: &mut Option<Tracer<'p>>,
    optimum: &Option<OptimalAssignment>,
    affine: Affine,
) -> Result<RunResult, SolveError> {
    let n = problem.robots();
    Ok(match plan {
        None => {
            *tracer = None;
            let optimum = match optimum.clone() {
                Some(optimum) => optimum,
                None => oracle::solve(problem).map_err(|e| SolveError::Internal(e.to_string()))?,
            };
            RunResult::centralized(optimum)
        }
        Some(plan) => {
            // The central rules (certified, oracle, agreement) are the watch's; the agents
            // run to the round limit under them.
            let stop = match options.stop() {
                StopRule::Local => AgentStop::Local(
                    LocalCertifiedStop::new(plan.diameter, n, plan.tolerance)?
                        .with_cadence(plan.stop_cadence),
                ),
                _ => AgentStop::MaxIters,
            };
            let mut watch = SolveWatch::new(
                problem,
                options,
                plan.tolerance,
                tracer.take(),
                optimum.as_ref(),
                affine,
            );
            let team = run_team_watched(
                Workload::Solve {
                    plan,
                    stop: &stop,
                    max_rounds: options.max_iters() as u64,
                },
                graph,
                options.run(),
                Some(&mut watch),
            )?;
            *tracer = watch.tracer;
            let distributed = options.transport().capabilities().execution != Execution::Lockstep;
            RunResult::of_team(team, distributed)
        }
    })
}

/// The oracle tracer of a solve that checks its answer or stops at the oracle's criterion.
fn tracer_of<'p>(
    problem: &'p TaskAssignmentProblem,
    options: &SolveOptions,
    optimum: Option<&OptimalAssignment>,
    affine: Affine,
) -> Option<Tracer<'p>> {
    let mut tracer = optimum
        .filter(|_| options.check() || options.stop() == StopRule::Oracle)
        .map(|o| Tracer::new(problem, o, affine));
    if let Some(t) = tracer.as_mut() {
        t.record = options.trace();
        t.readout_decisions = decides_by_readout(options);
    }
    tracer
}

fn solve_once(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    options: &SolveOptions,
    optimum: Option<OptimalAssignment>,
    affine: Affine,
) -> Result<SolveReport, SolveError> {
    let (n, m) = (problem.robots(), problem.tasks());
    let setup = options.method_setup();
    if setup.is_some() && graph.robots() != n {
        return Err(SolveError::SizeMismatch {
            graph: graph.robots(),
            problem: n,
        });
    }
    // The user's problem passed [`check_size`] on the shape solved here.
    // A team method's plan (ρ, tolerance, agents); `None`: the centralized solver.
    let plan = match setup {
        Some(setup) => Some(prepare(problem, graph, options, setup)?),
        None => None,
    };
    let started = Instant::now();
    let mut tracer = tracer_of(problem, options, optimum.as_ref(), affine);
    let run = run_solve(
        problem,
        graph,
        options,
        plan.as_ref(),
        &mut tracer,
        &optimum,
        affine,
    )?;
    let wall_time_ms = started.elapsed().as_secs_f64() * 1e3;
    let (message_bytes, messages_per_agent) = match &plan {
        None => (0, 0),
        Some(plan) => (
            8 * plan.agents.setup.payload_len(n, m) + std::mem::size_of::<RoundHeader>(),
            run.rounds,
        ),
    };
    let (assignment, repaired) = rounding::repair(problem, &run.decisions);
    let cost = problem
        .cost_of(&assignment)
        .map_err(|e| SolveError::Internal(format!("the repaired assignment: {e}")))?;
    let check = match (tracer, optimum) {
        (Some(t), _) => Some(t.finish(cost)),
        (None, Some(o)) if options.check() => Some(Tracer::new(problem, &o, affine).finish(cost)),
        _ => None,
    };
    Ok(SolveReport {
        degraded: None,
        // The user's problem names them (`solve_user`).
        robot_names: None,
        task_names: None,
        assignment,
        cost,
        iterations: run.rounds,
        converged: run.converged,
        repaired,
        method: options.method(),
        transport: options.transport(),
        rho: plan.as_ref().map_or(0.0, |p| p.rho),
        robots: n,
        tasks: m,
        case: problem.case(),
        maximize: false,
        certified: false,
        idle_robots: Vec::new(),
        unserved_tasks: Vec::new(),
        topology: graph.name().to_string(),
        // The centralized solver reports the perturbation a team would have used.
        perturbation: plan.as_ref().map_or_else(
            || ties::epsilon(problem.costs(), options.perturbation()),
            |p| p.agents.epsilon,
        ),
        mean_projection_steps: run.projection_steps as f64 / (n * run.rounds.max(1)) as f64,
        message_bytes,
        messages_per_agent,
        bytes_per_agent: message_bytes * messages_per_agent,
        wall_time_ms,
        stop: options.stop(),
        certified_round: run.certified_round,
        global_barrier: options.run().global_barrier(),
        round_latency_us: run.latency,
        agent_usage: run.usage,
        startup_ms: run.startup_ms,
        run_id: run.run_id,
        iterate_digests: run.iterate_digests,
        critical_path: options
            .run()
            .timeline()
            .then(|| admm_ta_transport::timeline::critical_path(graph, &run.timeline)),
        timeline: run.timeline,
        check,
    })
}

/// What the team's run yields, before rounding and checking.
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
    timeline: Vec<Vec<admm_ta_transport::timeline::RoundStamp>>,
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
            timeline: Vec::new(),
        }
    }

    /// A team's run; `distributed`: its agents ran concurrently, so their round latency and
    /// CPU usage are reported.
    fn of_team(team: TeamRun, distributed: bool) -> Self {
        let first = &team.outcomes[0];
        Self {
            decisions: team.outcomes.iter().map(|o| o.task).collect(),
            rounds: first.rounds as usize,
            converged: first.converged,
            certified_round: first.certified_round.map(|r| r as usize),
            projection_steps: team
                .outcomes
                .iter()
                .map(|o| o.projection_steps as usize)
                .sum(),
            latency: distributed.then(|| team.latency.summary()),
            usage: distributed.then_some(team.usage),
            startup_ms: team.startup.map(|d| d.as_secs_f64() * 1e3),
            iterate_digests: team.outcomes.iter().map(|o| o.iterate_digest).collect(),
            timeline: team.outcomes.into_iter().map(|o| o.timeline).collect(),
            run_id: team.run_id,
        }
    }
}
