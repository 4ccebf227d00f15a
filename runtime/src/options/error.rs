//! Settings no run can honour, and the one check of a timeout.

use crate::transport::{Execution, Transport, ZenohNotBuilt};
use admm_ta_agents::method::Method;
use admm_ta_agents::primal::ProjectionPath;
use admm_ta_agents::primal_settings::PrimalVariant;
use admm_ta_agents::stopping::StopRule;
use std::time::Duration;

/// Settings no run can honour.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    #[error("--rho (ρ) must be auto or a positive number, got '{0}'")]
    Rho(f64),
    /// A timeout that is not a positive number of seconds (below 10⁶); `option` is the
    /// command line's flag or the team file's key.
    #[error(
        "{option} must be a positive number of seconds below 1000000, got {}",
        Compact(*seconds)
    )]
    Timeout { option: &'static str, seconds: f64 },
    #[error(
        "--on-failure continue applies to agent processes: use --transport {}",
        Transport::names_where(|c| c.failure_recovery, "or")
    )]
    NoFailureRecovery,
    #[error("--max-iters must be at least 1")]
    NoIterations,
    #[error(
        "--method {method} is the centralized solver: it runs in this process, with --transport {}",
        Transport::names_where(|c| c.execution == Execution::Lockstep, "or")
    )]
    CentralizedMethod { method: &'static str },
    #[error("the γ factor must be a positive finite number, got {0}")]
    Gamma(f64),
    #[error(
        "--global-barrier needs the {} transport ({} have none)",
        Transport::names_where(|c| c.global_barrier, "or"),
        Transport::names_where(|c| !c.global_barrier, "and")
    )]
    BarrierNeedsAgents,
    #[error(transparent)]
    NotBuilt(#[from] ZenohNotBuilt),
    #[error(
        "--stop {stop} needs the whole team's state: it runs on the {} transport only (use --stop local or max-iters)",
        Transport::names_where(|c| c.execution == Execution::Lockstep, "or")
    )]
    CentralStop { stop: &'static str },
    /// A stop rule the method does not honour (only the primal's payload is the `m × n`
    /// matrix the central rules read).
    #[error(
        "--stop {} reads every robot's m×n matrix: it works with --method {} only (use --stop {})",
        stop.name(),
        Method::names_where(|info| info.stops.contains(stop), "or"),
        method.info().stop_names("or")
    )]
    UnsupportedStop { stop: StopRule, method: Method },
    #[error("--trace needs --check: it follows the run against the centralized optimum")]
    TraceNeedsCheck,
    /// An option of the paper's primal variant with the fast one: `--adaptive-rho` (the
    /// fast iteration runs where ρ drops out; the schedule was measured for the paper's
    /// readout) or `--stop agreement` (it waits for near-integral iterates, which the fast
    /// variant's never are: they stay inside the polytope).
    #[error(
        "{0} applies to the paper's primal variant, not the fast one: add --primal-variant paper"
    )]
    PaperOnly(&'static str),
    /// An option the user gave that the method never reads (it would be silently ignored).
    #[error("{option} does not apply to --method {method}: it works with --method {applies}")]
    NotForMethod {
        option: &'static str,
        method: &'static str,
        applies: &'static str,
    },
}

/// The options a user gave (set away from their defaults) that only some methods read.
#[derive(Debug, Clone, Copy)]
pub struct MethodOptions {
    pub adaptive_rho: bool,
    pub gamma_factor: Option<f64>,
    pub projection: ProjectionPath,
    pub primal_variant: PrimalVariant,
}

impl Default for MethodOptions {
    /// Nothing given: every method runs with these.
    fn default() -> Self {
        Self {
            adaptive_rho: false,
            gamma_factor: None,
            projection: ProjectionPath::Fast,
            primal_variant: PrimalVariant::Fast,
        }
    }
}

/// Refuses an option given with a method that ignores it: `--adaptive-rho` with a method
/// without a penalty ρ, `--gamma-factor` but with the inexact dual method, `--projection qp`
/// or `--primal-variant paper` but with the primal method. The library's builder does not
/// check this (experiments set one variant for every method); the command line does.
pub fn method_options(method: Method, given: MethodOptions) -> Result<(), ConfigError> {
    let refuse = |option, applies| {
        Err(ConfigError::NotForMethod {
            option,
            method: method.name(),
            applies,
        })
    };
    if given.adaptive_rho && method.rho_rule().is_none() {
        refuse("--adaptive-rho", "primal, dual or inexact-dual")
    } else if given.gamma_factor.is_some() && method != Method::InexactDual {
        refuse("--gamma-factor", "inexact-dual")
    } else if given.projection != ProjectionPath::Fast && method != Method::Primal {
        refuse("--projection qp", "primal")
    } else if given.primal_variant != PrimalVariant::Fast && method != Method::Primal {
        refuse("--primal-variant paper", "primal")
    } else {
        Ok(())
    }
}

/// Refuses the paper variant's options with the fast primal variant: `--adaptive-rho` and
/// `--stop agreement`.
pub fn paper_only(
    method: Method,
    variant: PrimalVariant,
    adaptive_rho: bool,
    stop: StopRule,
) -> Result<(), ConfigError> {
    if method != Method::Primal || variant != PrimalVariant::Fast {
        Ok(())
    } else if adaptive_rho {
        Err(ConfigError::PaperOnly("--adaptive-rho"))
    } else if stop == StopRule::Agreement {
        Err(ConfigError::PaperOnly("--stop agreement"))
    } else {
        Ok(())
    }
}

/// `seconds` as a timeout: a positive number of seconds below 10⁶ (`option` names the setting
/// in the error).
pub fn seconds(option: &'static str, seconds: f64) -> Result<Duration, ConfigError> {
    if seconds > 0.0 && seconds.is_finite() && seconds < 1e6 {
        Ok(Duration::from_secs_f64(seconds))
    } else {
        Err(ConfigError::Timeout { option, seconds })
    }
}

/// A number as typed, or in scientific notation when that is far shorter (1e300, 1e-9).
struct Compact(f64);

impl std::fmt::Display for Compact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let plain = self.0.to_string();
        let scientific = format!("{:e}", self.0);
        f.write_str(if scientific.len() < plain.len() {
            &scientific
        } else {
            &plain
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_flags_and_the_transports_that_can() {
        assert_eq!(
            ConfigError::BarrierNeedsAgents.to_string(),
            "--global-barrier needs the threads, shm or ipc transport (sim, uds and zenoh have none)"
        );
        assert_eq!(
            ConfigError::NoFailureRecovery.to_string(),
            "--on-failure continue applies to agent processes: use --transport ipc"
        );
        assert_eq!(
            ConfigError::UnsupportedStop {
                stop: StopRule::Agreement,
                method: Method::Dual
            }
            .to_string(),
            "--stop agreement reads every robot's m×n matrix: it works with --method primal only (use --stop local, oracle or max-iters)"
        );
        assert_eq!(
            ConfigError::CentralizedMethod {
                method: "hungarian"
            }
            .to_string(),
            "--method hungarian is the centralized solver: it runs in this process, with --transport sim"
        );
        assert_eq!(
            ConfigError::Rho(-1.0).to_string(),
            "--rho (ρ) must be auto or a positive number, got '-1'"
        );
        assert_eq!(
            seconds("round_timeout", -1.0).unwrap_err().to_string(),
            "round_timeout must be a positive number of seconds below 1000000, got -1"
        );
        assert_eq!(
            seconds("--round-timeout", 1e300).unwrap_err().to_string(),
            "--round-timeout must be a positive number of seconds below 1000000, got 1e300"
        );
        assert_eq!(
            seconds("--round-timeout", 1e9).unwrap_err().to_string(),
            "--round-timeout must be a positive number of seconds below 1000000, got 1e9"
        );
    }

    #[test]
    fn options_a_method_never_reads_are_refused_and_defaults_pass() {
        for method in Method::ALL {
            assert_eq!(method_options(method, MethodOptions::default()), Ok(()));
        }
        let adaptive = MethodOptions {
            adaptive_rho: true,
            ..MethodOptions::default()
        };
        assert_eq!(method_options(Method::Dual, adaptive), Ok(()));
        assert_eq!(
            method_options(Method::Market, adaptive)
                .unwrap_err()
                .to_string(),
            "--adaptive-rho does not apply to --method market: it works with --method primal, dual or inexact-dual"
        );
        let gamma = MethodOptions {
            gamma_factor: Some(0.5),
            ..MethodOptions::default()
        };
        assert_eq!(method_options(Method::InexactDual, gamma), Ok(()));
        assert!(method_options(Method::Dual, gamma).is_err());
        let qp = MethodOptions {
            projection: ProjectionPath::Qp,
            ..MethodOptions::default()
        };
        assert_eq!(method_options(Method::Primal, qp), Ok(()));
        assert!(method_options(Method::Cbaa, qp).is_err());
        let paper = MethodOptions {
            primal_variant: PrimalVariant::Paper,
            ..MethodOptions::default()
        };
        assert_eq!(method_options(Method::Primal, paper), Ok(()));
        assert!(method_options(Method::Hungarian, paper).is_err());
    }
}
