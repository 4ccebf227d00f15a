//! Validated settings: what a solve does ([`SolveOptions`]) and how a team runs
//! ([`run::RunOptions`], shared by solves, latency probes and surveillance episodes). Both are
//! built by a builder whose `build` refuses every combination no run could honour, for every
//! caller (the command line and team files only map their flags and keys onto the builder),
//! with the errors of [`error::ConfigError`], which name options by [`given::OptionId`]: each
//! front end renders them in its own terms (a flag, a team file's key). With
//! [`SolveOptionsBuilder::refuse_unread`] (the command line, team files, `admm_ta::Solver`),
//! `build` also refuses every option given that the run never reads (`unread`). Checks
//! that depend on the problem (sizes, memory, the ρ rule's value) are the solve's.
//!
//! Size: the two option sets, a setter and a getter per option, and the test of the
//! builder's refusals; splitting them would scatter one option's handling over files.

pub mod error;
pub mod given;
pub mod run;
mod unread;

use crate::options::error::ConfigError;
use crate::options::given::{Given, OptionId};
use crate::options::run::{RunOptions, RunOptionsBuilder};
pub use admm_ta_agents::certify::stopping::StopRule;
use admm_ta_agents::method::settings::{GivenSettings, Setting, SettingSpec, SettingValue};
use admm_ta_agents::method::team::MethodSetup;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::ties::Perturbation;
use admm_ta_transport::wait::WaitStrategy;
use admm_ta_transport::{Execution, Transport};
use serde::Serialize;
use std::time::Duration;

/// What the team does when an agent fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OnFailure {
    /// Stop every agent and report the failure (the default).
    #[default]
    Abort,
    /// The survivors drop the failed robot and re-solve without it, if they still can
    /// (connected graph, at least as many robots as tasks).
    Continue,
}

impl OnFailure {
    /// Both choices, in the order of the command line's help.
    pub const ALL: [OnFailure; 2] = [Self::Abort, Self::Continue];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Abort => "abort",
            Self::Continue => "continue",
        }
    }
}

#[cfg(feature = "clap")]
admm_ta_agents::clap_value_enum!(OnFailure);

/// Everything a solve needs besides the problem and the graph.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOptions {
    run: RunOptions,
    method: Method,
    rho: Option<f64>,
    adaptive_rho: bool,
    /// The method's own settings, as given.
    settings: GivenSettings,
    max_iters: usize,
    stop: StopRule,
    stop_rounds: usize,
    seed: u64,
    perturbation: Perturbation,
    check: bool,
    trace: bool,
    on_failure: OnFailure,
    given: Given,
    refuse_unread: bool,
}

impl Default for SolveOptions {
    /// Primal ADMM with the default ρ rule and the decentralized stop, at most 5000 rounds,
    /// on the lockstep simulation; agent processes honour the fault-injection test switch.
    fn default() -> Self {
        Self {
            run: RunOptions::default().with_fault_injection(true),
            method: Method::default(),
            rho: None,
            adaptive_rho: false,
            settings: GivenSettings::default(),
            max_iters: 5000,
            stop: StopRule::Local,
            stop_rounds: 10,
            seed: 0,
            perturbation: Perturbation::Auto,
            check: false,
            trace: false,
            on_failure: OnFailure::Abort,
            given: Given::default(),
            refuse_unread: false,
        }
    }
}

impl SolveOptions {
    /// A builder starting from [`SolveOptions::default`].
    pub fn builder() -> SolveOptionsBuilder {
        Self::default().to_builder()
    }

    /// A builder starting from these options.
    pub fn to_builder(&self) -> SolveOptionsBuilder {
        SolveOptionsBuilder {
            run: self.run.to_builder(),
            method: self.method,
            rho: self.rho,
            adaptive_rho: self.adaptive_rho,
            settings: self.settings.clone(),
            max_iters: self.max_iters,
            stop: self.stop,
            stop_rounds: self.stop_rounds,
            seed: self.seed,
            perturbation: self.perturbation,
            check: self.check,
            trace: self.trace,
            on_failure: self.on_failure,
            given: self.given,
            refuse_unread: self.refuse_unread,
        }
    }

    /// How the team runs.
    pub fn run(&self) -> &RunOptions {
        &self.run
    }

    /// What carries the messages (`self.run().transport()`).
    pub fn transport(&self) -> Transport {
        self.run.transport()
    }

    pub fn method(&self) -> Method {
        self.method
    }

    /// ρ as given; `None`: the scale-free default of the method's rule
    /// ([`admm_ta_agents::method::team::MethodSetup::default_rho`]).
    pub fn rho(&self) -> Option<f64> {
        self.rho
    }

    /// Anneal ρ by the schedule of [`admm_ta_agents::methods::rho::RhoSchedule`] (every agent applies
    /// it at the same round).
    pub fn adaptive_rho(&self) -> bool {
        self.adaptive_rho
    }

    /// The method's own settings, as given (a lenient builder's may include settings of
    /// other methods, which the method ignores).
    pub fn settings(&self) -> &GivenSettings {
        &self.settings
    }

    /// The method with its own settings (`None`: the centralized solver); the settings were
    /// checked by [`SolveOptionsBuilder::build`].
    pub fn method_setup(&self) -> Option<Box<dyn MethodSetup>> {
        let own = self.settings.only(self.method.settings());
        self.method
            .setup(&own)
            .expect("the options' build checked the method's settings")
    }

    /// Round limit.
    pub fn max_iters(&self) -> usize {
        self.max_iters
    }

    pub fn stop(&self) -> StopRule {
        self.stop
    }

    /// Rounds of agreement the `agreement` stop waits for.
    pub fn stop_rounds(&self) -> usize {
        self.stop_rounds
    }

    /// Seed of the tie-breaking perturbations.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    pub fn perturbation(&self) -> Perturbation {
        self.perturbation
    }

    /// Compare with the centralized optimum and trace convergence.
    pub fn check(&self) -> bool {
        self.check
    }

    /// With `check` on a lockstep run: record every round's objective in
    /// [`crate::solve::report::OracleCheck::trace`] (for convergence plots).
    pub fn trace(&self) -> bool {
        self.trace
    }

    /// What to do when an agent process fails.
    pub fn on_failure(&self) -> OnFailure {
        self.on_failure
    }
}

/// Builds [`SolveOptions`]: the run's settings and the solve's own.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOptionsBuilder {
    run: RunOptionsBuilder,
    method: Method,
    rho: Option<f64>,
    adaptive_rho: bool,
    settings: GivenSettings,
    max_iters: usize,
    stop: StopRule,
    stop_rounds: usize,
    seed: u64,
    perturbation: Perturbation,
    check: bool,
    trace: bool,
    on_failure: OnFailure,
    given: Given,
    refuse_unread: bool,
}

impl SolveOptionsBuilder {
    pub fn transport(mut self, transport: Transport) -> Self {
        self.given = self.given.with(OptionId::Transport);
        self.run = self.run.transport(transport);
        self
    }

    pub fn wait(mut self, wait: WaitStrategy) -> Self {
        self.given = self.given.with(OptionId::Wait);
        self.run = self.run.wait(wait);
        self
    }

    pub fn global_barrier(mut self, on: bool) -> Self {
        self.given = self.given.with(OptionId::GlobalBarrier);
        self.run = self.run.global_barrier(on);
        self
    }

    pub fn round_timeout(self, timeout: Duration) -> Self {
        self.round_timeout_secs(timeout.as_secs_f64())
    }

    pub fn round_timeout_secs(mut self, seconds: f64) -> Self {
        self.given = self.given.with(OptionId::RoundTimeout);
        self.run = self.run.round_timeout_secs(seconds);
        self
    }

    pub fn startup_timeout(self, timeout: Duration) -> Self {
        self.startup_timeout_secs(timeout.as_secs_f64())
    }

    pub fn startup_timeout_secs(mut self, seconds: f64) -> Self {
        self.given = self.given.with(OptionId::StartupTimeout);
        self.run = self.run.startup_timeout_secs(seconds);
        self
    }

    pub fn agent_program(mut self, program: impl crate::options::run::IntoAgentProgram) -> Self {
        self.run = self.run.agent_program(program);
        self
    }

    pub fn fault_injection(mut self, on: bool) -> Self {
        self.run = self.run.fault_injection(on);
        self
    }

    pub fn warmup_rounds(mut self, rounds: u64) -> Self {
        self.run = self.run.warmup_rounds(rounds);
        self
    }

    pub fn method(mut self, method: Method) -> Self {
        self.given = self.given.with(OptionId::Method);
        self.method = method;
        self
    }

    /// `None`: the method's default rule.
    pub fn rho(mut self, rho: Option<f64>) -> Self {
        self.given = self.given.with(OptionId::Rho);
        self.rho = rho;
        self
    }

    pub fn adaptive_rho(mut self, on: bool) -> Self {
        self.given = self.given.with(OptionId::AdaptiveRho);
        self.adaptive_rho = on;
        self
    }

    /// A method setting, typed: `.setting(PrimalVariant::Paper)`, `.setting(GammaFactor(0.7))`.
    pub fn setting<S: Setting>(self, setting: S) -> Self {
        self.setting_value(S::SPEC, setting.value())
    }

    /// A method setting by its spec (the command line and team files: see
    /// [`admm_ta_agents::methods::Method::all_settings`]).
    pub fn setting_value(mut self, spec: &'static SettingSpec, value: SettingValue) -> Self {
        self.settings = self.settings.set(spec, value);
        self
    }

    /// Every method setting at once (replacing those set before).
    pub fn settings(mut self, settings: GivenSettings) -> Self {
        self.settings = settings;
        self
    }

    pub fn max_iters(mut self, rounds: usize) -> Self {
        self.given = self.given.with(OptionId::MaxIters);
        self.max_iters = rounds;
        self
    }

    pub fn stop(mut self, stop: StopRule) -> Self {
        self.given = self.given.with(OptionId::Stop);
        self.stop = stop;
        self
    }

    pub fn stop_rounds(mut self, rounds: usize) -> Self {
        self.given = self.given.with(OptionId::StopRounds);
        self.stop_rounds = rounds;
        self
    }

    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    pub fn perturbation(mut self, perturbation: Perturbation) -> Self {
        self.given = self.given.with(OptionId::Perturb);
        self.perturbation = perturbation;
        self
    }

    pub fn check(mut self, on: bool) -> Self {
        self.check = on;
        self
    }

    pub fn trace(mut self, on: bool) -> Self {
        self.given = self.given.with(OptionId::Trace);
        self.trace = on;
        self
    }

    /// Every agent stamps its rounds: [`crate::solve::report::SolveReport::timeline`] and
    /// its critical path (threads and process transports).
    pub fn timeline(mut self, on: bool) -> Self {
        self.given = self.given.with(OptionId::Timeline);
        self.run = self.run.timeline(on);
        self
    }

    pub fn on_failure(mut self, on_failure: OnFailure) -> Self {
        self.given = self.given.with(OptionId::OnFailure);
        self.on_failure = on_failure;
        self
    }

    /// Refuse, in [`SolveOptionsBuilder::build`], every option given by a setter that this
    /// method or transport never reads (`unread`'s rule: `rho` with market, a
    /// `stop_rounds` without the agreement stop, a round timeout on the lockstep
    /// simulation, …) instead of ignoring it. The command line, team files and
    /// `admm_ta::Solver` turn it on; it is off by default for sweeps that set one value
    /// for every method (the experiments).
    pub fn refuse_unread(mut self, on: bool) -> Self {
        self.refuse_unread = on;
        self
    }

    /// The options, or the first reason no solve could run them (in the order the command
    /// line reports them): ρ or a timeout out of range, `--on-failure continue` on a
    /// transport that cannot name the failed agent, no rounds, a centralized method off
    /// the lockstep simulation, a method setting's value out of its range (γ), a global
    /// barrier the transport has not, a transport this build lacks, a central stop rule off
    /// the lockstep simulation, a stop rule the method does not honour (the method registry
    /// says which), a trace without a check; with [`SolveOptionsBuilder::refuse_unread`], an
    /// option given that the run never reads (a method setting of another method among
    /// them); last, an option the method's settings exclude (`--adaptive-rho` or `--stop
    /// agreement` with the fast primal variant).
    pub fn build(self) -> Result<SolveOptions, ConfigError> {
        if let Some(rho) = self.rho.filter(|r| !(*r > 0.0 && r.is_finite())) {
            return Err(ConfigError::Rho(rho));
        }
        self.run.timeouts()?;
        let capabilities = self.run.transport.capabilities();
        if self.on_failure == OnFailure::Continue && !capabilities.failure_recovery {
            return Err(ConfigError::NoFailureRecovery);
        }
        if self.max_iters == 0 {
            return Err(ConfigError::NoIterations);
        }
        let lockstep = capabilities.execution == Execution::Lockstep;
        if self.method.team().is_none() && !lockstep {
            return Err(ConfigError::CentralizedMethod {
                method: self.method.name(),
            });
        }
        // Every setting's value, whichever method it belongs to; then the method's own.
        for (spec, value) in self.settings.iter() {
            spec.check(value)?;
        }
        let setup = self
            .method
            .setup(&self.settings.only(self.method.settings()))?;
        // What the rule against unread options looks at (checked last).
        let chosen = self.refuse_unread.then_some(unread::Chosen {
            given: self.given,
            method: self.method,
            transport: self.run.transport,
            rho: self.rho,
            adaptive_rho: self.adaptive_rho,
            settings: &self.settings,
            max_iters: self.max_iters,
            perturbation: self.perturbation,
            stop: self.stop,
            stop_rounds: self.stop_rounds,
            trace: self.trace,
            wait: self.run.wait,
            round_timeout: self.run.round_timeout,
            startup_timeout: self.run.startup_timeout,
            timeline: self.run.timeline,
        });
        let run = self.run.build()?;
        if self.stop.is_central() && !lockstep {
            return Err(ConfigError::CentralStop {
                stop: self.stop.name(),
            });
        }
        if !self.method.supports(self.stop) {
            return Err(ConfigError::UnsupportedStop {
                stop: self.stop,
                method: self.method,
            });
        }
        if self.trace && !self.check {
            return Err(ConfigError::TraceNeedsCheck);
        }
        if let Some(chosen) = chosen {
            chosen.refuse_unread()?;
        }
        if let Some(setup) = &setup {
            setup
                .refuse(self.adaptive_rho, self.stop)
                .map_err(ConfigError::Refused)?;
        }
        Ok(SolveOptions {
            run,
            method: self.method,
            rho: self.rho,
            adaptive_rho: self.adaptive_rho,
            settings: self.settings,
            max_iters: self.max_iters,
            stop: self.stop,
            stop_rounds: self.stop_rounds,
            seed: self.seed,
            perturbation: self.perturbation,
            check: self.check,
            trace: self.trace,
            on_failure: self.on_failure,
            given: self.given,
            refuse_unread: self.refuse_unread,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admm_ta_agents::methods::dual::GammaFactor;
    use admm_ta_agents::methods::primal::PrimalVariant;

    #[test]
    fn defaults_are_valid_and_invalid_combinations_are_refused() {
        assert_eq!(SolveOptions::builder().build(), Ok(SolveOptions::default()));
        assert_eq!(RunOptions::builder().build(), Ok(RunOptions::default()));
        let refused = |b: SolveOptionsBuilder| b.build().unwrap_err();
        let b = SolveOptions::builder;
        assert_eq!(refused(b().rho(Some(-1.0))), ConfigError::Rho(-1.0));
        assert!(matches!(
            refused(b().round_timeout_secs(f64::NAN)),
            ConfigError::Timeout {
                option: OptionId::RoundTimeout,
                ..
            }
        ));
        assert_eq!(
            refused(b().startup_timeout(Duration::ZERO)),
            ConfigError::Timeout {
                option: OptionId::StartupTimeout,
                seconds: 0.0
            }
        );
        assert_eq!(
            refused(
                b().transport(Transport::Uds)
                    .on_failure(OnFailure::Continue)
            ),
            ConfigError::NoFailureRecovery
        );
        assert_eq!(refused(b().max_iters(0)), ConfigError::NoIterations);
        assert_eq!(
            refused(b().method(Method::Hungarian).transport(Transport::Threads)),
            ConfigError::CentralizedMethod {
                method: "hungarian"
            }
        );
        assert_eq!(
            refused(b().setting(GammaFactor(0.0))).to_string(),
            "--gamma-factor (the γ factor) must be a positive finite number, got 0"
        );
        assert_eq!(
            refused(b().global_barrier(true)),
            ConfigError::BarrierNeedsAgents
        );
        assert_eq!(
            refused(b().transport(Transport::Ipc).stop(StopRule::Oracle)),
            ConfigError::CentralStop { stop: "oracle" }
        );
        assert_eq!(
            refused(b().method(Method::Dual).stop(StopRule::Certified)),
            ConfigError::UnsupportedStop {
                stop: StopRule::Certified,
                method: Method::Dual
            }
        );
        assert_eq!(refused(b().trace(true)), ConfigError::TraceNeedsCheck);
        assert_eq!(
            refused(b().adaptive_rho(true)).to_string(),
            "--adaptive-rho applies to the paper's primal variant, not the fast one: add --primal-variant paper"
        );
        assert!(
            b().adaptive_rho(true)
                .setting(PrimalVariant::Paper)
                .build()
                .is_ok()
        );
        assert_eq!(
            b().transport(Transport::Zenoh).build().is_ok(),
            cfg!(feature = "zenoh")
        );
        let ok = b()
            .transport(Transport::Ipc)
            .global_barrier(true)
            .on_failure(OnFailure::Continue)
            .round_timeout_secs(2.5)
            .build()
            .unwrap();
        assert_eq!(ok.run().round_timeout(), Duration::from_millis(2500));
        assert_eq!(ok.to_builder().build(), Ok(ok));
    }
}
