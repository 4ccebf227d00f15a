//! What a transport declares, and the trait through which an agent process reaches its end
//! of a process transport.
//!
//! A transport is one module that declares one [`TransportInfo`] (its name, what it can do
//! and, if its agents are OS processes, its [`ProcessTransport`]) and one line in the
//! registry of this crate ([`crate::Transport`]). The process orchestration (the runtime's
//! `process`) only speaks to the trait: the open files and threads an agent needs, what a run
//! must create before its agents start, what a launcher keeps running beside them, how an agent
//! connects, whom it blames when the run fails, and which dead agents' leftovers the
//! transport itself can clean up. Nothing there names a transport.

use crate::exchange::{Exchange, ExchangeError};
use crate::fault::Fault;
use crate::wait::WaitPolicy;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How a transport runs a team's agents.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Execution {
    /// All agents in one thread, round by round: the run sees the whole team after every
    /// round (central stop rules, the oracle trace) but measures no round latency.
    Lockstep,
    /// One OS thread per agent in this process.
    Threads,
    /// One OS process per agent, started by a launcher from the `admm-ta` binary (or
    /// independently, from a team file).
    Processes,
}

/// What a transport can do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Capabilities {
    pub execution: Execution,
    /// A global barrier after every round (lockstep rounds for latency benchmarks).
    pub global_barrier: bool,
    /// Agents on several machines.
    pub multi_host: bool,
    /// Agent processes honour the `ADMM_TA_FAULT` test switch ([`crate::fault`]).
    pub fault_injection: bool,
    /// When an agent fails, the launcher learns which one (the agents mark the culprit on the
    /// run's shared board), so the survivors can re-solve without it (`--on-failure
    /// continue`).
    pub failure_recovery: bool,
    /// This build carries the transport (Zenoh needs the `zenoh` feature).
    pub built: bool,
}

impl Capabilities {
    /// A process transport that can do nothing more than run its agents.
    pub const PROCESSES: Self = Self {
        execution: Execution::Processes,
        global_barrier: false,
        multi_host: false,
        fault_injection: false,
        failure_recovery: false,
        built: true,
    };
}

/// Everything a transport declares about itself.
#[derive(Clone, Copy)]
pub struct TransportInfo {
    /// The name on the command line and in JSON.
    pub name: &'static str,
    pub capabilities: Capabilities,
    /// How its agent processes connect (`None`: its agents are not processes).
    pub processes: Option<&'static dyn ProcessTransport>,
}

/// Where a run lives: its names, made by whoever starts the run (the launcher, or the
/// members of an independently started team).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunPlace {
    /// Prefix of every shared-memory object and transport file of the run.
    pub prefix: String,
    /// The run's private root directory for transport files (created before the agents).
    pub root: PathBuf,
    /// The run directory (scenario, logs, results, sockets).
    pub dir: PathBuf,
    /// Shared memory of the run's board.
    pub board_shm: String,
}

/// What an agent process asks of its transport when it connects.
#[derive(Debug, Clone)]
pub struct ConnectRequest {
    pub index: usize,
    pub neighbours: Vec<usize>,
    /// Every agent's degree (the team's size is its length).
    pub degrees: Vec<usize>,
    pub payload_len: usize,
    /// Tasks of the team's problem (checked against the board's shape).
    pub tasks: usize,
    pub policy: WaitPolicy,
    pub run: RunPlace,
    /// A global barrier after every round.
    pub global_barrier: bool,
    /// A launcher started this agent: it stops when the launcher is gone.
    pub supervised: bool,
    /// The agents on this host, in a team whose hosts are bridged (`None`: every agent is
    /// here).
    pub local_agents: Option<Vec<usize>>,
    /// The robots that take part (a standing team's roster); `None`: every agent.
    pub roster: Option<Vec<usize>>,
    /// What the transport put into the scenario for its agents ([`RunSupport::scenario_config`]
    /// or a team's host), as its own type serialises it.
    pub config: Option<serde_json::Value>,
    /// The team's identity (hex), for transports that check it themselves (no board).
    pub team_digest: String,
    /// Fault injection (tests, [`crate::fault`]).
    pub fault: Option<Fault>,
}

impl ConnectRequest {
    /// The team's size.
    pub fn agents(&self) -> usize {
        self.degrees.len()
    }

    /// The agents whose connection this agent waits for at start-up: those of the roster
    /// (every agent without one) on its host (every host's, when they are not bridged).
    pub fn team(&self) -> Vec<usize> {
        (0..self.agents())
            .filter(|a| self.roster.as_ref().is_none_or(|r| r.contains(a)))
            .filter(|a| self.local_agents.as_ref().is_none_or(|l| l.contains(a)))
            .collect()
    }

    /// Whether a neighbour lives on another host (reached through the host's bridge).
    pub fn has_remote_neighbour(&self) -> bool {
        self.local_agents
            .as_ref()
            .is_some_and(|local| self.neighbours.iter().any(|j| !local.contains(j)))
    }
}

/// Why an agent could not connect its end of the transport.
#[derive(Debug, thiserror::Error)]
pub enum ConnectError {
    /// The exchange failed while connecting (a deadline, a stop request, a failed peer,
    /// another team's agent).
    #[error(transparent)]
    Exchange(#[from] ExchangeError),
    /// This build or this scenario cannot run the transport: nothing was tried.
    #[error(transparent)]
    Refused(Box<dyn std::error::Error + Send + Sync>),
    /// What the transport needs could not be set up (its configuration, the board, a
    /// socket).
    #[error(transparent)]
    Setup(Box<dyn std::error::Error + Send + Sync>),
}

impl ConnectError {
    /// A set-up failure from anything that is an error.
    pub fn setup(error: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        Self::Setup(error.into())
    }
}

/// Why what a run needs could not be created or started.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct SupportError(pub Box<dyn std::error::Error + Send + Sync>);

impl SupportError {
    pub fn new(error: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        Self(error.into())
    }
}

/// What a run's transport needs for the team it is created for.
#[derive(Debug, Clone)]
pub struct RunRequest {
    pub run: RunPlace,
    /// The run's id (names what the transport publishes, such as Zenoh keys).
    pub run_id: String,
    pub degrees: Vec<usize>,
    pub payload_len: usize,
    /// The hosts of the team are bridged (a host's agents wake its bridge).
    pub bridged: bool,
}

/// Something a run keeps alive until its agents are gone (dropped afterwards).
pub trait Resource {}

impl<T> Resource for T {}

/// What a launcher keeps running beside its agents (a router), and how it learns and
/// passes on failures the agents do not record on the board.
pub trait RunSupport {
    /// What the agents need to find it, put into the scenario for [`ConnectRequest::config`].
    fn scenario_config(&self) -> Option<serde_json::Value> {
        None
    }

    /// The agent the agents announced as failed, if any, waiting up to `within` for the
    /// announcement. `None` at once for transports whose agents mark it on the board.
    fn announced_failure(&self, within: Duration) -> Option<usize> {
        let _ = within;
        None
    }

    /// Tells agents that do not read the board that `agent` failed.
    fn announce_failure(&self, agent: usize) {
        let _ = agent;
    }

    /// An environment variable the support set for this process alone: the launcher
    /// removes it from the agents it starts.
    fn unset_for_agents(&self) -> Option<&'static str> {
        None
    }
}

/// Support of a transport that needs none.
pub struct NoSupport;

impl RunSupport for NoSupport {}

/// One agent's connected end of a process transport.
pub trait AgentEndpoint {
    /// The exchange the agent's round loop drives.
    fn exchange(&mut self) -> &mut dyn Exchange;

    /// Tells agents that do not read the board that this agent got termination signal
    /// `signal` (the others learn it from the stop request on the board).
    fn announce_stop(&self, signal: i32) {
        let _ = signal;
    }

    /// Points the launcher and the other agents at the agent that caused `error`.
    fn blame_for(&self, error: &ExchangeError);

    /// Between runs (a standing team's robot waiting for its next row): a failure or a stop
    /// request the run's agents announced, for transports whose agents do not read a board
    /// (those that do read it there).
    fn check(&self) -> Result<(), ExchangeError> {
        Ok(())
    }
}

/// A transport whose agents are OS processes.
pub trait ProcessTransport: Sync {
    /// Open files an agent process with `degree` neighbours needs.
    fn files_per_agent(&self, degree: usize) -> u64;

    /// Threads an agent process runs.
    fn threads_per_agent(&self) -> u64 {
        1
    }

    /// Bytes a second everything the team sends passes through at least, where one relay
    /// (a router) carries every message of a run (`None`: agents reach each other directly).
    /// A team whose round this relay cannot carry within half its round deadline is refused
    /// before it starts.
    fn relay_bytes_per_second(&self) -> Option<f64> {
        None
    }

    /// The agents use the run's shared board: they check the team's digest on it before
    /// connecting and publish their rounds on it (`false`: presence and failures travel on
    /// the transport itself).
    fn uses_board(&self) -> bool {
        true
    }

    /// Creates what the agents open but do not create, before the first agent starts (by
    /// the launcher, or a team's first member under the team's lock); kept until the agents
    /// are gone.
    fn create_resources(
        &self,
        run: &RunRequest,
    ) -> Result<Option<Box<dyn Resource>>, SupportError> {
        let _ = run;
        Ok(None)
    }

    /// Starts what a launcher keeps running beside its agents.
    fn start_support(&self, run: &RunRequest) -> Result<Box<dyn RunSupport>, SupportError> {
        let _ = run;
        Ok(Box::new(NoSupport))
    }

    /// Connects agent `request.index` to its neighbours, waiting for them until `deadline`.
    fn connect(
        &self,
        request: &ConnectRequest,
        deadline: Instant,
    ) -> Result<Box<dyn AgentEndpoint>, ConnectError>;

    /// Removes what dead agents of the run left behind that the transport can clean up
    /// itself; how many (`None`: the transport leaves nothing such).
    fn cleanup_dead(&self, run: &RunPlace) -> Option<usize> {
        let _ = run;
        None
    }
}

/// The neighbour an exchange error is the fault of, if any.
pub fn culprit(error: &ExchangeError) -> Option<usize> {
    match error {
        ExchangeError::BadPayload { neighbour, .. }
        | ExchangeError::WrongLength { neighbour, .. }
        | ExchangeError::OutOfOrder { neighbour, .. }
        | ExchangeError::WrongSender { neighbour, .. }
        | ExchangeError::Undecodable { neighbour, .. } => Some(*neighbour),
        _ => None,
    }
}

/// The agent a transport that reads the board blames for `error`: after a timeout the one
/// everybody waits for, directly or through blocked neighbours (`laggard`); else the
/// error's own culprit.
pub fn board_culprit(error: &ExchangeError, laggard: impl FnOnce() -> usize) -> Option<usize> {
    match error {
        ExchangeError::Timeout { .. } => Some(laggard()),
        e => culprit(e),
    }
}
