//! Settings no run can honour, and the one check of a timeout.

use crate::options::given::{Compact, FrontEnd, OptionId, OptionName, Setting, Value};
use admm_ta_agents::certify::stopping::StopRule;
use admm_ta_agents::method::settings::{SettingError, SettingKind};
use admm_ta_agents::method::team::{Refusal, RunOption};
use admm_ta_agents::methods::Method;
use admm_ta_transport::{Execution, Transport, ZenohNotBuilt};
use std::time::Duration;

/// Settings no run can honour. Errors name options by [`OptionId`]: `Display` spells them
/// as the command line does (`--max-iters`), [`ConfigError::in_terms_of`] as a front end
/// does (a team file's `max_iters`).
#[derive(Debug, Clone, PartialEq)]
pub enum ConfigError {
    Rho(f64),
    /// A timeout that is not a positive number of seconds (below 10⁶).
    Timeout {
        option: OptionId,
        seconds: f64,
    },
    NoFailureRecovery,
    NoIterations,
    CentralizedMethod {
        method: &'static str,
    },
    /// A method setting's value that the method cannot take.
    Setting(SettingError),
    BarrierNeedsAgents,
    NotBuilt(ZenohNotBuilt),
    CentralStop {
        stop: &'static str,
    },
    /// A stop rule the method does not honour (only the primal's payload is the `m × n`
    /// matrix the central rules read).
    UnsupportedStop {
        stop: StopRule,
        method: Method,
    },
    TraceNeedsCheck,
    /// An option of the run that the method's settings exclude (`--adaptive-rho` or
    /// `--stop agreement` with the fast primal variant: see the method's refusal).
    Refused(Refusal),
    /// An option the caller gave that the method never reads (it would be silently
    /// ignored); `applies`: the methods that read it.
    NotForMethod {
        option: Setting,
        method: &'static str,
        applies: Vec<&'static str>,
    },
    /// An option the caller gave that the transport never reads; `applies`: the transports
    /// that read it.
    NotForTransport {
        option: Setting,
        transport: &'static str,
        applies: Vec<&'static str>,
    },
    /// An option of the agreement stop with another stop rule.
    NotForStop {
        option: Setting,
        stop: &'static str,
    },
}

impl ConfigError {
    /// The message in the terms of `front` (the team file's keys, or the command line's
    /// flags).
    pub fn in_terms_of(&self, front: FrontEnd) -> String {
        let name = |id| front.name(id);
        let lockstep = || Transport::names_where(|c| c.execution == Execution::Lockstep, "or");
        match self {
            Self::Rho(rho) => format!(
                "{} (ρ) must be auto or a positive number, got '{rho}'",
                name(OptionId::Rho)
            ),
            Self::Timeout { option, seconds } => format!(
                "{} must be a positive number of seconds below 1000000, got {}",
                name(*option),
                Compact(*seconds)
            ),
            Self::NoFailureRecovery => format!(
                "{} continue applies to agent processes: use {} {}",
                name(OptionId::OnFailure),
                name(OptionId::Transport),
                Transport::names_where(|c| c.failure_recovery, "or")
            ),
            Self::NoIterations => format!("{} must be at least 1", name(OptionId::MaxIters)),
            Self::CentralizedMethod { method } => match front {
                FrontEnd::CommandLine => format!(
                    "--method {method} is the centralized solver: it runs in this process, with --transport {}",
                    lockstep()
                ),
                FrontEnd::TeamFile => format!(
                    "method = \"{method}\" is the centralized solver: it has no agents to start (give a team method, or solve the problem with admm-ta solve)"
                ),
            },
            Self::Setting(e) => setting_error(e, front),
            Self::BarrierNeedsAgents => format!(
                "{} needs the {} transport ({} have none)",
                name(OptionId::GlobalBarrier),
                Transport::names_where(|c| c.global_barrier, "or"),
                Transport::names_where(|c| !c.global_barrier, "and")
            ),
            Self::NotBuilt(e) => e.to_string(),
            Self::CentralStop { stop } => format!(
                "{} {stop} needs the whole team's state: it runs on the {} transport only (use {0} local or max-iters)",
                name(OptionId::Stop),
                lockstep()
            ),
            Self::UnsupportedStop { stop, method } => format!(
                "{} {} reads every robot's m×n matrix: it works with {} {} only (use {0} {})",
                name(OptionId::Stop),
                stop.name(),
                name(OptionId::Method),
                Method::names_where(|info| info.stops.contains(stop), "or"),
                method.info().stop_names("or")
            ),
            Self::TraceNeedsCheck => {
                "--trace needs --check: it follows the run against the centralized optimum".into()
            }
            Self::Refused(refusal) => refused_text(refusal, front),
            Self::NotForMethod { .. } | Self::NotForTransport { .. } | Self::NotForStop { .. } => {
                self.not_for_text(front)
            }
        }
    }
}

impl ConfigError {
    /// The message of an option given where it does not apply (a method, a transport or a
    /// stop rule that reads none of it), in the terms of `front`.
    fn not_for_text(&self, front: FrontEnd) -> String {
        let (option, to, works_with) = match self {
            Self::NotForMethod {
                option,
                method,
                applies,
            } => (
                option,
                Setting::new(OptionId::Method, Value::Name((*method).into())),
                front.choices(OptionId::Method, applies),
            ),
            Self::NotForTransport {
                option,
                transport,
                applies,
            } => (
                option,
                Setting::new(OptionId::Transport, Value::Name((*transport).into())),
                front.choices(OptionId::Transport, applies),
            ),
            Self::NotForStop { option, stop } => {
                return format!(
                    "{} does not apply to {}: it counts the rounds of {}",
                    front.setting(option),
                    front.setting(&Setting::new(OptionId::Stop, Value::Name((*stop).into()))),
                    front.setting(&Setting::new(
                        OptionId::Stop,
                        Value::Name(StopRule::Agreement.name().into())
                    ))
                );
            }
            other => return other.in_terms_of(front),
        };
        format!(
            "{} does not apply to {}: it works with {works_with}",
            front.setting(option),
            front.setting(&to),
        )
    }
}

/// The message of an option a method's variant refuses, in the terms of `front`.
fn refused_text(refusal: &Refusal, front: FrontEnd) -> String {
    let option = match refusal.option {
        RunOption::AdaptiveRho => Setting::new(OptionId::AdaptiveRho, Value::On),
        RunOption::Stop(stop) => Setting::new(OptionId::Stop, Value::Name(stop.name().into())),
    };
    format!(
        "{} applies to {}: add {}",
        front.setting(&option),
        refusal.because,
        front.setting(&Setting::new(
            OptionName::Method(refusal.needs),
            Value::Name(refusal.value.into())
        ))
    )
}

impl std::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.in_terms_of(FrontEnd::CommandLine))
    }
}

impl std::error::Error for ConfigError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            // Transparent: the message is the cause's.
            Self::NotBuilt(e) => e.source(),
            _ => None,
        }
    }
}

impl From<SettingError> for ConfigError {
    fn from(e: SettingError) -> Self {
        Self::Setting(e)
    }
}

impl From<ZenohNotBuilt> for ConfigError {
    fn from(e: ZenohNotBuilt) -> Self {
        Self::NotBuilt(e)
    }
}

/// A method setting's error in the terms of `front`.
fn setting_error(error: &SettingError, front: FrontEnd) -> String {
    let name = front.name(OptionName::Method(error.spec()));
    match error {
        SettingError::OutOfRange { spec, got } => {
            let what = match spec.kind {
                SettingKind::PositiveNumber { what } => what,
                SettingKind::Choice(_) => spec.key,
            };
            format!("{name} ({what}) must be a positive finite number, got {got}")
        }
        SettingError::NotANumber { got, .. } => format!("{name} must be a number, got '{got}'"),
        SettingError::NotAChoice { spec, got } => {
            let choices: Vec<String> = spec
                .choices()
                .iter()
                .map(|c| match front {
                    FrontEnd::TeamFile => format!("\"{c}\""),
                    FrontEnd::CommandLine => c.to_string(),
                })
                .collect();
            let choices: Vec<&str> = choices.iter().map(String::as_str).collect();
            format!(
                "{name} must be {}, got '{got}'",
                admm_ta_agents::method::info::join(&choices, "or")
            )
        }
        SettingError::NotOfMethod { .. } => format!("{name} is not a setting of this method"),
    }
}

/// `seconds` as a timeout: a positive number of seconds below 10⁶ (`option` names the setting
/// in the error).
pub fn seconds(option: OptionId, seconds: f64) -> Result<Duration, ConfigError> {
    if seconds > 0.0 && seconds.is_finite() && seconds < 1e6 {
        Ok(Duration::from_secs_f64(seconds))
    } else {
        Err(ConfigError::Timeout { option, seconds })
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
            seconds(OptionId::RoundTimeout, -1.0)
                .unwrap_err()
                .in_terms_of(FrontEnd::TeamFile),
            "round_timeout must be a positive number of seconds below 1000000, got -1"
        );
        assert_eq!(
            seconds(OptionId::RoundTimeout, 1e300)
                .unwrap_err()
                .to_string(),
            "--round-timeout must be a positive number of seconds below 1000000, got 1e300"
        );
        assert_eq!(
            seconds(OptionId::RoundTimeout, 1e9)
                .unwrap_err()
                .to_string(),
            "--round-timeout must be a positive number of seconds below 1000000, got 1e9"
        );
    }
}
