//! Why a solve cannot start or complete.

use crate::exchange::ExchangeError;
use crate::process::launcher::LaunchError;
use crate::transport::{Execution, Transport};
use crate::workload::plan::PlanError;
use admm_ta_agents::local_stop::LocalStopError;
use std::path::PathBuf;

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

/// Reasons a solve cannot start or complete.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(
        "--stop {stop} needs the whole team's state: it runs on the {} transport only (use --stop local or max-iters)",
        Transport::names_where(|c| c.execution == Execution::Lockstep, "or")
    )]
    CentralStop { stop: &'static str },
    #[error(
        "--global-barrier needs the {} transport ({} have none)",
        Transport::names_where(|c| c.global_barrier, "or"),
        Transport::names_where(|c| !c.global_barrier, "and")
    )]
    BarrierNeedsAgents,
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
    LocalStop(#[from] LocalStopError),
    #[error(transparent)]
    Exchange(#[from] ExchangeError),
    #[error(transparent)]
    Launch(#[from] LaunchError),
    #[error("the run finished but could not remove its files: {0:?}")]
    Leftovers(Vec<PathBuf>),
    #[error("the topology has {graph} robots but the costs have {problem}")]
    SizeMismatch { graph: usize, problem: usize },
    #[error(transparent)]
    Plan(#[from] PlanError),
    #[error(
        "--method hungarian is the centralized solver: it runs in this process, with --transport {}",
        Transport::names_where(|c| c.execution == Execution::Lockstep, "or")
    )]
    CentralizedMethod,
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
