//! The team runner: one team of agents computing a [`Workload`] on a graph, on the
//! transport its [`RunOptions`] name. A solve, the surveillance episodes and the latency
//! probe all run their teams here, so this is the only place that dispatches on how a
//! transport executes (lockstep, threads, processes) and the only place that merges the
//! agents' round latency and CPU usage.

use crate::options::run::RunOptions;
use crate::process::launcher::{self, LaunchError};
use crate::process::scenario::Scenario;
use crate::workload::Workload;
use crate::workload::surveillance::{EpisodeRecord, run_surveillance_agent};
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::methods::probe::ProbeAgent;
use admm_ta_topologies::Graph;
use admm_ta_transport::exchange::ExchangeError;
use admm_ta_transport::exchange::round_loop::{
    AgentOutcome, AgentPlan, AgentStop, UnreadableOutcome, merge_outcomes, payload_digest,
};
use admm_ta_transport::latency::RoundLatency;
use admm_ta_transport::sim::process::{LockstepSim, RoundView};
use admm_ta_transport::threads;
use admm_ta_transport::usage::ThreadUsage;
use admm_ta_transport::{Execution, Transport};
use std::path::PathBuf;
use std::time::Duration;

/// What a team's run yields.
#[derive(Debug, Clone)]
pub struct TeamRun {
    /// Every agent's outcome, in agent order.
    pub outcomes: Vec<AgentOutcome>,
    /// Every agent's recorded rounds merged (empty in a lockstep run, which measures none).
    pub latency: RoundLatency,
    /// All agents' CPU time and context switches over the recorded rounds (zero in a
    /// lockstep run).
    pub usage: ThreadUsage,
    /// From the first agent process's spawn until all were connected (processes).
    pub startup: Option<Duration>,
    /// The process run's id: its iceoryx2 prefix is `adta<id>_`, its directory
    /// `<runs>/<id>` (the user's private runs directory); both are gone when the run returns.
    pub run_id: Option<String>,
    /// Per agent, its episodes in order (an episode workload).
    pub episodes: Vec<Vec<EpisodeRecord>>,
}

/// Why a team's run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("the topology has {graph} robots but the team has {team}")]
    SizeMismatch { graph: usize, team: usize },
    #[error(
        "round latency is measured on a distributed transport: {}",
        Transport::names_where(|c| c.execution != Execution::Lockstep, "or")
    )]
    NotDistributed,
    #[error(
        "the {} transports need the admm-ta binary to start agents from",
        Transport::names_where(|c| c.execution == Execution::Processes, "and")
    )]
    NoAgentProgram,
    #[error(transparent)]
    Exchange(#[from] ExchangeError),
    #[error(transparent)]
    Launch(#[from] LaunchError),
    #[error(transparent)]
    Unreadable(#[from] UnreadableOutcome),
    #[error("the run finished but could not remove its files: {0:?}")]
    Leftovers(Vec<PathBuf>),
    /// A termination signal stopped a team running inside this process (while a
    /// [`admm_ta_transport::signals::install`] guard lived).
    #[error("stopped by {}", admm_ta_transport::signals::name(*signal))]
    Stopped { signal: i32 },
}

/// What a solve sees of a lockstep run, and of no other: only the simulation has the whole
/// team in one place after every round.
pub trait LockstepWatch {
    /// Called after every round.
    fn observe(&mut self, view: &RoundView<'_>);

    /// Called after every round (after [`LockstepWatch::observe`]) of a team whose agents
    /// run to the round limit ([`AgentStop::MaxIters`]): `true` ends the run. A stop rule
    /// that reads the whole team (certified, oracle, agreement) answers here.
    fn stop(&mut self, sim: &LockstepSim<MethodAgent>) -> bool;
}

/// Runs a team computing `workload` on `graph` as `options` say.
pub fn run_team(
    workload: Workload<'_>,
    graph: &Graph,
    options: &RunOptions,
) -> Result<TeamRun, RunError> {
    run_team_watched(workload, graph, options, None)
}

/// [`run_team`], with `watch` seeing every round of a lockstep run (other runs ignore it).
pub fn run_team_watched(
    workload: Workload<'_>,
    graph: &Graph,
    options: &RunOptions,
    watch: Option<&mut dyn LockstepWatch>,
) -> Result<TeamRun, RunError> {
    if let Some(team) = workload.robots().filter(|&n| n != graph.robots()) {
        return Err(RunError::SizeMismatch {
            graph: graph.robots(),
            team,
        });
    }
    match options.transport().capabilities().execution {
        Execution::Lockstep => lockstep(workload, graph, watch),
        Execution::Threads => on_threads(workload, graph, options),
        Execution::Processes => in_processes(workload, graph, options),
    }
}

/// Every agent's plan: `max_rounds` rounds at most, stopping by `stop`.
fn plans(n: usize, max_rounds: u64, stop: &AgentStop, options: &RunOptions) -> Vec<AgentPlan> {
    (0..n)
        .map(|index| AgentPlan {
            index,
            max_rounds,
            stop: stop.clone(),
            round_timeout: options.round_timeout(),
            global_barrier: options.global_barrier(),
            warmup_rounds: options.warmup_rounds(),
            timeline: options.timeline(),
        })
        .collect()
}

/// A solve's team in one thread, round by round.
fn lockstep(
    workload: Workload<'_>,
    graph: &Graph,
    mut watch: Option<&mut dyn LockstepWatch>,
) -> Result<TeamRun, RunError> {
    let Workload::Solve {
        plan,
        stop,
        max_rounds,
    } = workload
    else {
        return Err(RunError::NotDistributed);
    };
    let n = graph.robots();
    let max_rounds = max_rounds as usize;
    let mut sim = LockstepSim::new(plan.agents.agents(), graph);
    let mut steps = vec![0u64; n];
    let mut observe = |view: &RoundView<'_>, watch: &mut Option<&mut dyn LockstepWatch>| {
        for (total, report) in steps.iter_mut().zip(view.reports) {
            *total += report.inner_iterations as u64;
        }
        if let Some(w) = watch.as_mut() {
            w.observe(view);
        }
    };
    let (rounds, converged, certified) = match stop {
        AgentStop::Local(rule) => {
            let mut stops = vec![rule.clone(); n];
            let local = sim.run_local_stop(&mut stops, max_rounds, &mut |view| {
                observe(view, &mut watch)
            });
            (local.rounds, local.certified.is_some(), local.certified)
        }
        AgentStop::MaxIters => {
            let outcome = sim.run_until(max_rounds, &mut |_| {}, |sim| {
                observe(&sim.view(), &mut watch);
                watch.as_mut().is_some_and(|w| w.stop(sim))
            });
            (outcome.rounds, outcome.stopped, None)
        }
    };
    if let Some(signal) = admm_ta_transport::signals::stop_requested() {
        return Err(RunError::Stopped { signal });
    }
    let decisions: Vec<usize> = match &certified {
        Some((_, tasks)) => tasks.clone(),
        None => sim.agents().iter().map(ConsensusAgent::decide).collect(),
    };
    let outcomes = (0..n)
        .map(|index| AgentOutcome {
            index,
            task: decisions[index],
            rounds: rounds as u64,
            converged,
            certified_round: certified.as_ref().map(|(r, _)| *r as u64),
            iterate_digest: payload_digest(sim.payload(index)),
            projection_steps: steps[index],
            latency: RoundLatency::new().to_buckets(),
            usage: ThreadUsage::default(),
            timeline: Vec::new(),
        })
        .collect();
    Ok(TeamRun {
        outcomes,
        latency: RoundLatency::new(),
        usage: ThreadUsage::default(),
        startup: None,
        run_id: None,
        episodes: Vec::new(),
    })
}

/// One thread per agent.
fn on_threads(
    workload: Workload<'_>,
    graph: &Graph,
    options: &RunOptions,
) -> Result<TeamRun, RunError> {
    let n = graph.robots();
    let (outcomes, episodes) = match workload {
        Workload::Solve {
            plan,
            stop,
            max_rounds,
        } => {
            let mut agents = plan.agents.agents();
            let plans = plans(n, max_rounds, stop, options);
            let outcomes =
                threads::process::run_threads_waiting(&mut agents, graph, &plans, options.wait())?;
            (outcomes, Vec::new())
        }
        Workload::Probe {
            payload_len,
            step,
            rounds,
        } => {
            let mut agents: Vec<ProbeAgent> = (0..n)
                .map(|i| ProbeAgent::new(i, payload_len, step))
                .collect();
            let plans = plans(n, rounds, &AgentStop::MaxIters, options);
            let outcomes =
                threads::process::run_threads_waiting(&mut agents, graph, &plans, options.wait())?;
            (outcomes, Vec::new())
        }
        Workload::Episodes {
            settings,
            max_rounds,
        } => {
            let mut agents: Vec<MethodAgent> = (0..n).map(|i| settings.agent(i, graph)).collect();
            let plans = plans(n, max_rounds, &AgentStop::MaxIters, options);
            let results = threads::process::run_threads_with(
                &mut agents,
                graph,
                &plans,
                options.wait(),
                &|agent, exchange, plan| run_surveillance_agent(agent, exchange, plan, settings),
            )?;
            results
                .into_iter()
                .map(|(records, outcome)| (outcome, records))
                .unzip()
        }
    };
    let (latency, usage) = merge_outcomes(&outcomes)?;
    Ok(TeamRun {
        outcomes,
        latency,
        usage,
        startup: None,
        run_id: None,
        episodes,
    })
}

/// One process per agent, started by the launcher.
fn in_processes(
    workload: Workload<'_>,
    graph: &Graph,
    options: &RunOptions,
) -> Result<TeamRun, RunError> {
    let program = options.agent_program().ok_or(RunError::NoAgentProgram)?;
    let scenario = Scenario::new(workload, graph, options);
    let run = launcher::launch(scenario, program, options.fault_injection())?;
    if !run.leftovers.is_empty() {
        return Err(RunError::Leftovers(run.leftovers));
    }
    let (latency, usage) = merge_outcomes(&run.outcomes)?;
    Ok(TeamRun {
        outcomes: run.outcomes,
        latency,
        usage,
        startup: Some(run.startup),
        run_id: Some(run.run_id),
        episodes: run.episodes,
    })
}
