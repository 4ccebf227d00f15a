//! Exit codes of the command line, from typed outcomes and errors (never from message text):
//!
//! | code | meaning |
//! | --- | --- |
//! | 0 | success: a certified/optimal assignment, or a run that finished as asked |
//! | 1 | unexpected internal error, or the output cannot be written (a full disk) |
//! | 2 | bad input or bad options, or a system limit the team does not fit (`ulimit -n`) |
//! | 3 | infeasible problem (no assignment avoids the forbidden pairs) |
//! | 4 | agent or transport failure (also `--on-failure continue` giving up) |
//! | 5 | round limit reached without a certified assignment (the best one is printed) |
//! | 6 | `--check` found the result not optimal |

use crate::agents::numerics::lsap::LsapError;
use crate::agents::problem::ProblemError;
use crate::runtime::process::launcher::LaunchError;
use crate::runtime::process::member_error::MemberError;
use crate::runtime::runner::RunError;
use crate::runtime::solve::report::SolveReport;
use crate::runtime::team::errors::CollectError;
use crate::runtime::team::errors::TeamFileError;
use crate::topologies::RobotNameError;
use crate::transport::ZenohNotBuilt;
use crate::{ConfigError, SolveError, StopRule, TopologyError};

/// A bad command line or input found by the command itself (exit 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// Runs of a command that ran many (bench cases, stress runs) failed (exit 4).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct RunsFailed(pub String);

/// A collected team result that the centralized check found not optimal (exit 6).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct NotOptimal(pub String);

/// Returns early with a [`UsageError`] formatted as by `format!`.
macro_rules! usage_bail {
    ($($arg:tt)*) => {
        return Err(anyhow::Error::from($crate::command_line::exit::UsageError(format!($($arg)*))))
    };
}
pub(crate) use usage_bail;

/// How a solve that printed its report ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    Success,
    /// The round limit ended the run before any certificate (exit 5).
    Uncertified,
    /// `--check` found the assignment not optimal (exit 6).
    NotOptimal,
}

impl Outcome {
    /// The outcome of a report: with `--check`, the centralized optimum decides; otherwise a
    /// run that hit the round limit without its stop rule firing is uncertified (unless the
    /// user asked for exactly that many rounds with `--stop max-iters`).
    pub fn of(report: &SolveReport) -> Self {
        match &report.check {
            Some(check) if !check.optimal => Self::NotOptimal,
            Some(_) => Self::Success,
            None if !report.converged && report.stop != StopRule::MaxIters => Self::Uncertified,
            None => Self::Success,
        }
    }

    pub fn code(self) -> u8 {
        match self {
            Self::Success => 0,
            Self::Uncertified => 5,
            Self::NotOptimal => 6,
        }
    }
}

/// The exit code of an error: the first typed cause found in its chain decides.
pub fn code_of(error: &anyhow::Error) -> u8 {
    for cause in error.chain() {
        if let Some(e) = cause.downcast_ref::<ProblemError>() {
            return match e {
                ProblemError::Infeasible(_) => 3,
                _ => 2,
            };
        }
        if let Some(e) = cause.downcast_ref::<SolveError>() {
            return match e {
                // Refused before anything was spawned: the user's limits or temporary
                // directory, not a failure.
                SolveError::Run(RunError::Launch(
                    LaunchError::Limits(_) | LaunchError::RunDirectory(_),
                )) => 2,
                SolveError::Run(_) | SolveError::CannotContinue { .. } => 4,
                SolveError::Internal(_) => 1,
                _ => 2,
            };
        }
        if let Some(LsapError::Infeasible) = cause.downcast_ref::<LsapError>() {
            return 3;
        }
        // An option this build cannot honour (`host` without `--features zenoh`) is a usage
        // error like any other.
        if cause.is::<ConfigError>()
            || cause.is::<TopologyError>()
            || cause.is::<UsageError>()
            || cause.is::<crate::request::RequestError>()
            || cause.is::<ZenohNotBuilt>()
            || cause.is::<CollectError>()
            || cause.is::<TeamFileError>()
            || cause.is::<RobotNameError>()
        {
            return 2;
        }
        if let Some(e) = cause.downcast_ref::<MemberError>() {
            return if e.is_refusal() { 2 } else { 4 };
        }
        if cause.is::<RunsFailed>() {
            return 4;
        }
        if cause.is::<NotOptimal>() {
            return 6;
        }
    }
    1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typed_causes_decide_the_exit_code_anywhere_in_the_chain() {
        let not_built = anyhow::Error::from(ZenohNotBuilt).context("host alpha");
        assert_eq!(code_of(&not_built), 2);
        let refused = anyhow::Error::from(MemberError::Refused("bad team file".into()));
        assert_eq!(code_of(&refused), 2);
        let failed = anyhow::Error::from(MemberError::Failed("agent 3 died".into()));
        assert_eq!(code_of(&failed), 4);
        assert_eq!(code_of(&anyhow::anyhow!("an untyped error")), 1);
    }
}
