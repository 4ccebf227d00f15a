//! The one rule against options that would be silently ignored: an option the caller gave
//! that the run never reads is refused, whichever front end gave it (the command line, a
//! team file, the library's `SolveOptionsBuilder::refuse_unread`). Only
//! given options count (a default is never refused), and only true no-ops: each check
//! below says what reads the option.

use crate::options::error::ConfigError;
use crate::options::given::{Given, OptionId, OptionName, Setting, Value};
use admm_ta_agents::certify::stopping::StopRule;
use admm_ta_agents::method::settings::GivenSettings;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::ties::Perturbation;
use admm_ta_transport::wait::WaitStrategy;
use admm_ta_transport::{Execution, Transport};

/// What a builder was given: the options it names and every setting's value.
pub(super) struct Chosen<'a> {
    pub given: Given,
    pub method: Method,
    pub transport: Transport,
    pub rho: Option<f64>,
    pub adaptive_rho: bool,
    /// The method settings given (of any method).
    pub settings: &'a GivenSettings,
    pub max_iters: usize,
    pub perturbation: Perturbation,
    pub stop: StopRule,
    pub stop_rounds: usize,
    pub trace: bool,
    pub wait: WaitStrategy,
    pub round_timeout: f64,
    pub startup_timeout: f64,
    pub timeline: bool,
}

impl Chosen<'_> {
    /// The first option given that the method or the transport never reads, refused.
    pub(super) fn refuse_unread(&self) -> Result<(), ConfigError> {
        refuse_unread(self)
    }
}

fn refuse_unread(b: &Chosen) -> Result<(), ConfigError> {
    let given = |id| b.given.contains(id);
    let method = b.method;
    let for_method = |option: Setting, reads: &dyn Fn(Method) -> bool| {
        if reads(method) {
            Ok(())
        } else {
            Err(ConfigError::NotForMethod {
                option,
                method: method.name(),
                applies: method_names(reads),
            })
        }
    };
    // ρ and its schedule: the ADMM methods (market, CBAA and the Hungarian methods have
    // no penalty; `workload::plan` sets ρ = 0 for them).
    if given(OptionId::Rho) {
        let value = b.rho.map_or(Value::Name("auto".into()), Value::Number);
        for_method(Setting::new(OptionId::Rho, value), &has_rho)?;
    }
    if given(OptionId::AdaptiveRho) && b.adaptive_rho {
        for_method(Setting::new(OptionId::AdaptiveRho, Value::On), &has_rho)?;
    }
    // A method's own settings: the methods that declare them.
    for (spec, value) in b.settings.iter() {
        let option = Setting::new(OptionName::Method(spec), Value::of(value));
        for_method(option, &|m| m.settings().iter().any(|s| s.key == spec.key))?;
    }
    // What only a team reads: the centralized solver runs no rounds and breaks no ties.
    if given(OptionId::MaxIters) {
        let option = Setting::new(OptionId::MaxIters, Value::Number(b.max_iters as f64));
        for_method(option, &|m| m.team().is_some())?;
    }
    if given(OptionId::Perturb) {
        let value = match b.perturbation {
            Perturbation::Auto => Value::Name("auto".into()),
            Perturbation::Off => Value::Name("off".into()),
            Perturbation::Fixed(eps) => Value::Number(eps),
        };
        for_method(Setting::new(OptionId::Perturb, value), &|m| {
            m.team().is_some()
        })?;
    }
    // The agreement stop alone counts rounds of agreement.
    if given(OptionId::StopRounds) && b.stop != StopRule::Agreement {
        return Err(ConfigError::NotForStop {
            option: Setting::new(OptionId::StopRounds, Value::Number(b.stop_rounds as f64)),
            stop: b.stop.name(),
        });
    }
    // The trace is recorded by the lockstep watch of a team's rounds.
    if given(OptionId::Trace) && b.trace {
        for_method(Setting::new(OptionId::Trace, Value::On), &|m| {
            m.team().is_some()
        })?;
        for_transport(b, Setting::new(OptionId::Trace, Value::On), |c| {
            c == Execution::Lockstep
        })?;
    }
    // Deadlines and waiting: the lockstep simulation waits for nobody; only processes
    // start up.
    if given(OptionId::RoundTimeout) {
        let option = Setting::new(OptionId::RoundTimeout, Value::Number(b.round_timeout));
        for_transport(b, option, |c| c != Execution::Lockstep)?;
    }
    if given(OptionId::Timeline) && b.timeline {
        let option = Setting::new(OptionId::Timeline, Value::On);
        for_transport(b, option, |c| c != Execution::Lockstep)?;
    }
    if given(OptionId::Wait) {
        let option = Setting::new(OptionId::Wait, Value::Name(b.wait.name().into()));
        for_transport(b, option, |c| c != Execution::Lockstep)?;
    }
    if given(OptionId::StartupTimeout) {
        let value = Value::Number(b.startup_timeout);
        let option = Setting::new(OptionId::StartupTimeout, value);
        for_transport(b, option, |c| c == Execution::Processes)?;
    }
    Ok(())
}

fn has_rho(method: Method) -> bool {
    method.penalty()
}

/// The methods `reads` holds for, in the registry's order.
fn method_names(reads: &dyn Fn(Method) -> bool) -> Vec<&'static str> {
    Method::ALL
        .into_iter()
        .filter(|m| reads(*m))
        .map(Method::name)
        .collect()
}

/// Refuses `option` unless the transport's execution is one `reads` holds for.
fn for_transport(
    b: &Chosen,
    option: Setting,
    reads: fn(Execution) -> bool,
) -> Result<(), ConfigError> {
    let transport = b.transport;
    if reads(transport.capabilities().execution) {
        return Ok(());
    }
    Err(ConfigError::NotForTransport {
        option,
        transport: transport.name(),
        applies: Transport::ALL
            .iter()
            .copied()
            .filter(|t| reads(t.capabilities().execution))
            .map(Transport::name)
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::super::SolveOptions;
    use super::super::given::FrontEnd;
    use admm_ta_agents::certify::stopping::StopRule;
    use admm_ta_agents::methods::Method;
    use admm_ta_transport::Transport;

    fn refused(b: super::super::SolveOptionsBuilder) -> String {
        b.refuse_unread(true).build().unwrap_err().to_string()
    }

    #[test]
    fn defaults_and_options_that_are_read_pass() {
        let b = || SolveOptions::builder().refuse_unread(true);
        for method in Method::ALL {
            assert!(b().method(method).build().is_ok(), "{method:?}");
        }
        for transport in [Transport::Sim, Transport::Threads, Transport::Ipc] {
            assert!(b().transport(transport).build().is_ok(), "{transport:?}");
        }
        let read = b()
            .transport(Transport::Threads)
            .rho(Some(3.0))
            .round_timeout_secs(5.0)
            .max_iters(10)
            .build();
        assert!(read.is_ok(), "{read:?}");
        // Off by default: a sweep may set one value for every method.
        let sweep = SolveOptions::builder()
            .method(Method::Market)
            .rho(Some(3.0));
        assert!(sweep.build().is_ok());
    }

    #[test]
    fn a_given_option_the_run_never_reads_is_refused() {
        let b = SolveOptions::builder;
        assert_eq!(
            refused(b().method(Method::Market).rho(Some(3.0))),
            "--rho 3 does not apply to --method market: it works with --method primal, dual or inexact-dual"
        );
        assert_eq!(
            refused(b().method(Method::Cbaa).rho(None)),
            "--rho auto does not apply to --method cbaa: it works with --method primal, dual or inexact-dual"
        );
        assert!(refused(b().method(Method::Hungarian).rho(Some(1.0))).starts_with("--rho 1"));
        assert!(refused(b().method(Method::DistHungarian).rho(Some(1.0))).starts_with("--rho 1"));
        assert_eq!(
            refused(b().stop_rounds(5)),
            "--stop-rounds 5 does not apply to --stop local: it counts the rounds of --stop agreement"
        );
        assert!(refused(b().method(Method::Hungarian).max_iters(9)).starts_with("--max-iters 9"));
        assert!(
            refused(
                b().method(Method::Hungarian)
                    .perturbation(admm_ta_agents::problem::ties::Perturbation::Fixed(0.1))
            )
            .starts_with("--perturb 0.1")
        );
        assert_eq!(
            refused(b().transport(Transport::Threads).check(true).trace(true)),
            "--trace does not apply to --transport threads: it works with --transport sim"
        );
        assert!(refused(b().round_timeout_secs(5.0)).starts_with("--round-timeout 5"));
        assert!(
            refused(b().wait(admm_ta_transport::wait::WaitStrategy::Spin))
                .starts_with("--wait spin")
        );
        assert!(
            refused(b().transport(Transport::Threads).startup_timeout_secs(5.0))
                .starts_with("--startup-timeout 5 does not apply to --transport threads")
        );
        assert!(
            refused(
                b().method(Method::Dual)
                    .setting(admm_ta_agents::methods::primal::ProjectionPath::Fast)
            )
            .starts_with("--projection fast does not apply")
        );
    }

    #[test]
    fn a_team_file_hears_its_own_keys() {
        let error = SolveOptions::builder()
            .refuse_unread(true)
            .method(Method::Market)
            .setting(admm_ta_agents::methods::primal::PrimalVariant::Paper)
            .build()
            .unwrap_err();
        assert_eq!(
            error.in_terms_of(FrontEnd::TeamFile),
            "primal_variant = \"paper\" does not apply to method = \"market\": it works with method = \"primal\""
        );
        let zero = SolveOptions::builder().max_iters(0).build().unwrap_err();
        assert_eq!(
            zero.in_terms_of(FrontEnd::TeamFile),
            "max_iters must be at least 1"
        );
        assert_eq!(zero.to_string(), "--max-iters must be at least 1");
        let stop = SolveOptions::builder()
            .refuse_unread(true)
            .stop(StopRule::Agreement)
            .build()
            .unwrap_err();
        assert_eq!(
            stop.in_terms_of(FrontEnd::TeamFile),
            "--stop agreement applies to the paper's primal variant, not the fast one: add primal_variant = \"paper\""
        );
    }
}
