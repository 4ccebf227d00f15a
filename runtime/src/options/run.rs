//! How a team runs: the transport and everything about running agents on it, shared by
//! solves, latency probes and surveillance episodes.

use crate::options::error::{ConfigError, seconds};
use crate::options::given::OptionId;
use admm_ta_transport::wait::WaitStrategy;
use admm_ta_transport::{Transport, ZenohNotBuilt};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How a team runs: the transport and everything about running agents on it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOptions {
    transport: Transport,
    wait: WaitStrategy,
    global_barrier: bool,
    round_timeout: Duration,
    startup_timeout: Duration,
    agent_program: Option<AgentProgram>,
    fault_injection: bool,
    warmup_rounds: u64,
    timeline: bool,
}

impl Default for RunOptions {
    /// The lockstep simulation, default waiting, 30 s per round, 60 s to start, no fault
    /// injection.
    fn default() -> Self {
        Self {
            transport: Transport::Sim,
            wait: WaitStrategy::Auto,
            global_barrier: false,
            round_timeout: Duration::from_secs(30),
            startup_timeout: Duration::from_secs(60),
            agent_program: None,
            fault_injection: false,
            warmup_rounds: 0,
            timeline: false,
        }
    }
}

impl RunOptions {
    /// A builder starting from [`RunOptions::default`].
    pub fn builder() -> RunOptionsBuilder {
        Self::default().to_builder()
    }

    /// These options with fault injection on or off.
    pub(super) fn with_fault_injection(self, on: bool) -> Self {
        Self {
            fault_injection: on,
            ..self
        }
    }

    /// A builder starting from these options.
    pub fn to_builder(&self) -> RunOptionsBuilder {
        RunOptionsBuilder {
            transport: self.transport,
            wait: self.wait,
            global_barrier: self.global_barrier,
            round_timeout: self.round_timeout.as_secs_f64(),
            startup_timeout: self.startup_timeout.as_secs_f64(),
            agent_program: self.agent_program.clone(),
            fault_injection: self.fault_injection,
            warmup_rounds: self.warmup_rounds,
            timeline: self.timeline,
        }
    }

    /// What carries the messages.
    pub fn transport(&self) -> Transport {
        self.transport
    }

    /// How agents wait for their neighbours (threads and processes).
    pub fn wait(&self) -> WaitStrategy {
        self.wait
    }

    /// A global barrier after every round (transports with that capability).
    pub fn global_barrier(&self) -> bool {
        self.global_barrier
    }

    /// Deadline of every wait for a neighbour or the barrier.
    pub fn round_timeout(&self) -> Duration {
        self.round_timeout
    }

    /// Deadline for all agent processes to start and connect.
    pub fn startup_timeout(&self) -> Duration {
        self.startup_timeout
    }

    /// The `admm-ta` program agent processes are started from (process transports need
    /// one to run a team; options for independently started agents have none).
    pub fn agent_program(&self) -> Option<&AgentProgram> {
        self.agent_program.as_ref()
    }

    /// Agent processes honour the `ADMM_TA_FAULT` test switch ([`admm_ta_transport::fault`]).
    pub fn fault_injection(&self) -> bool {
        self.fault_injection
    }

    /// Rounds run before latency and CPU usage are recorded (benchmarks).
    pub fn warmup_rounds(&self) -> u64 {
        self.warmup_rounds
    }

    /// Every agent stamps its rounds into a timeline ([`admm_ta_transport::timeline`]).
    pub fn timeline(&self) -> bool {
        self.timeline
    }
}

/// Builds [`RunOptions`]; timeouts are kept as given until [`RunOptionsBuilder::build`]
/// checks them.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOptionsBuilder {
    pub(super) transport: Transport,
    pub(super) wait: WaitStrategy,
    global_barrier: bool,
    pub(super) round_timeout: f64,
    pub(super) startup_timeout: f64,
    agent_program: Option<AgentProgram>,
    fault_injection: bool,
    warmup_rounds: u64,
    pub(super) timeline: bool,
}

impl RunOptionsBuilder {
    pub fn transport(mut self, transport: Transport) -> Self {
        self.transport = transport;
        self
    }

    pub fn wait(mut self, wait: WaitStrategy) -> Self {
        self.wait = wait;
        self
    }

    pub fn global_barrier(mut self, on: bool) -> Self {
        self.global_barrier = on;
        self
    }

    pub fn round_timeout(self, timeout: Duration) -> Self {
        self.round_timeout_secs(timeout.as_secs_f64())
    }

    /// The round timeout in seconds, checked by `build` (the command line's
    /// `--round-timeout`).
    pub fn round_timeout_secs(mut self, seconds: f64) -> Self {
        self.round_timeout = seconds;
        self
    }

    pub fn startup_timeout(self, timeout: Duration) -> Self {
        self.startup_timeout_secs(timeout.as_secs_f64())
    }

    /// The start-up timeout in seconds, checked by `build` (`--startup-timeout`).
    pub fn startup_timeout_secs(mut self, seconds: f64) -> Self {
        self.startup_timeout = seconds;
        self
    }

    /// The program agent processes are started from: a path (the `admm-ta` binary), an
    /// [`AgentProgram`] with leading arguments, or `None`.
    pub fn agent_program(mut self, program: impl IntoAgentProgram) -> Self {
        self.agent_program = program.into_agent_program();
        self
    }

    pub fn fault_injection(mut self, on: bool) -> Self {
        self.fault_injection = on;
        self
    }

    pub fn warmup_rounds(mut self, rounds: u64) -> Self {
        self.warmup_rounds = rounds;
        self
    }

    /// Every agent stamps its rounds into a timeline (not the lockstep simulation).
    pub fn timeline(mut self, on: bool) -> Self {
        self.timeline = on;
        self
    }

    /// The timeouts, checked.
    pub(super) fn timeouts(&self) -> Result<(Duration, Duration), ConfigError> {
        Ok((
            seconds(OptionId::RoundTimeout, self.round_timeout)?,
            seconds(OptionId::StartupTimeout, self.startup_timeout)?,
        ))
    }

    /// The options, or why no transport could run them: a timeout that is not a positive
    /// number of seconds, a global barrier the transport has not, a transport this build
    /// does not carry.
    pub fn build(self) -> Result<RunOptions, ConfigError> {
        let (round_timeout, startup_timeout) = self.timeouts()?;
        let capabilities = self.transport.capabilities();
        if self.global_barrier && !capabilities.global_barrier {
            return Err(ConfigError::BarrierNeedsAgents);
        }
        if !capabilities.built {
            return Err(ZenohNotBuilt.into());
        }
        Ok(RunOptions {
            transport: self.transport,
            wait: self.wait,
            global_barrier: self.global_barrier,
            round_timeout,
            startup_timeout,
            agent_program: self.agent_program,
            fault_injection: self.fault_injection,
            warmup_rounds: self.warmup_rounds,
            timeline: self.timeline,
        })
    }
}

/// How agent processes are started: `PROGRAM [ARGS…] agent --run ID --robot I …`. The
/// `admm-ta` binary needs no leading arguments; a front end that carries the command line
/// in another program (the Python package: `python -c "..."`) gives them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AgentProgram {
    program: PathBuf,
    args: Vec<OsString>,
}

impl AgentProgram {
    /// `program` started with `args` before the agent's own command line.
    pub fn new(
        program: impl Into<PathBuf>,
        args: impl IntoIterator<Item = impl Into<OsString>>,
    ) -> Self {
        Self {
            program: program.into(),
            args: args.into_iter().map(Into::into).collect(),
        }
    }

    /// The program file.
    pub fn program(&self) -> &Path {
        &self.program
    }

    /// The arguments before `agent`.
    pub fn args(&self) -> &[OsString] {
        &self.args
    }
}

impl From<PathBuf> for AgentProgram {
    fn from(program: PathBuf) -> Self {
        Self::new(program, std::iter::empty::<OsString>())
    }
}

/// What [`RunOptionsBuilder::agent_program`] takes: a path (`PathBuf`, `&Path`, `&str`,
/// `String`), an [`AgentProgram`], or an `Option` of a path or of an [`AgentProgram`].
pub trait IntoAgentProgram {
    fn into_agent_program(self) -> Option<AgentProgram>;
}

impl IntoAgentProgram for AgentProgram {
    fn into_agent_program(self) -> Option<AgentProgram> {
        Some(self)
    }
}

impl IntoAgentProgram for Option<AgentProgram> {
    fn into_agent_program(self) -> Option<AgentProgram> {
        self
    }
}

impl IntoAgentProgram for PathBuf {
    fn into_agent_program(self) -> Option<AgentProgram> {
        Some(self.into())
    }
}

impl IntoAgentProgram for Option<PathBuf> {
    fn into_agent_program(self) -> Option<AgentProgram> {
        self.map(Into::into)
    }
}

impl IntoAgentProgram for &Path {
    fn into_agent_program(self) -> Option<AgentProgram> {
        Some(self.to_path_buf().into())
    }
}

impl IntoAgentProgram for &str {
    fn into_agent_program(self) -> Option<AgentProgram> {
        Some(PathBuf::from(self).into())
    }
}

impl IntoAgentProgram for String {
    fn into_agent_program(self) -> Option<AgentProgram> {
        Some(PathBuf::from(self).into())
    }
}
