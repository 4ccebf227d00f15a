//! Why a solve cannot start or complete.

use crate::options::error::ConfigError;
use crate::runner::RunError;
use crate::workload::plan::BadRho;
use admm_ta_agents::certify::local_stop::LocalStopError;
use admm_ta_transport::error_text::one_line;

/// Why the survivors of a failure could not re-solve (`--on-failure continue`).
#[derive(Debug, thiserror::Error)]
pub enum CannotContinue {
    #[error(
        "the {survivors} surviving robots cannot cover the {tasks} tasks (dropping a robot from Case 1 leaves fewer robots than tasks)"
    )]
    TooFewRobots { survivors: usize, tasks: usize },
    #[error("without robot {failed} the communication graph is disconnected")]
    Disconnected { failed: usize },
    #[error("the survivors' problem: {0}")]
    Infeasible(String),
    #[error("the survivors' re-solve failed too: {}", one_line(.0.as_ref()))]
    ResolveFailed(Box<SolveError>),
}

/// Reasons a solve cannot start or complete.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// Options no solve can run (for callers that build them on the way).
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The method cannot take this problem (case or shape); names the methods that can.
    #[error("{0}")]
    Unsupported(String),
    /// The costs span more than the method resolves in floating point.
    #[error("{0}")]
    Unresolvable(String),
    /// A bug: a result that does not fit the problem (never reported as a solution).
    #[error("internal error: {0}")]
    Internal(String),
    #[error("the topology has {graph} robots but the costs have {problem}")]
    SizeMismatch { graph: usize, problem: usize },
    /// The method's memory estimate ([`admm_ta_agents::method::info::Memory`]) is above the limit:
    /// named by the user's shape (`robots × tasks`), with the shape the method would solve
    /// when it differs (`solved_as`: a problem with fewer robots than tasks is solved
    /// transposed, one agent per task).
    #[error(
        "a problem of {robots} robot{} × {tasks} task{} is too large for the {method} method: it would need about {gib:.1} GiB of {of} ({because}{}); the limit is 8 GiB",
        if *robots == 1 { "" } else { "s" },
        if *tasks == 1 { "" } else { "s" },
        solved_as.map_or(String::new(), |(rows, columns)| format!(
            "; this problem is solved transposed, as {rows} × {columns}: one row per task"
        ))
    )]
    TooLarge {
        robots: usize,
        tasks: usize,
        method: &'static str,
        solved_as: Option<(usize, usize)>,
        gib: f64,
        of: &'static str,
        because: &'static str,
    },
    #[error(transparent)]
    Rho(#[from] BadRho),
    #[error(transparent)]
    LocalStop(#[from] LocalStopError),
    #[error(transparent)]
    Run(#[from] RunError),
    /// An agent failed and, with `--on-failure continue`, the survivors could not go on.
    #[error("{first}; --on-failure continue: {reason}")]
    CannotContinue {
        first: Box<SolveError>,
        reason: CannotContinue,
    },
}
