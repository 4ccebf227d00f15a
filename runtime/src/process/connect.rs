//! How an agent process connects its end of the run's transport, and what a run's transport
//! needs before and beside its agents — whatever the transport: everything specific to one
//! is behind its [`ProcessTransport`] (see [`admm_ta_transport::endpoint`]).

use crate::process::member_error::MemberError;
use crate::process::scenario::{Scenario, ScenarioError};
use crate::process::team_digest::TeamDigest;
use admm_ta_topologies::Graph;
use admm_ta_transport::board::Board;
use admm_ta_transport::endpoint::{
    AgentEndpoint, ConnectError, ConnectRequest, ProcessTransport, Resource, RunRequest,
    RunSupport, SupportError,
};
use admm_ta_transport::exchange::ExchangeError;
use admm_ta_transport::fault::{FaultKind, fault_for};
use admm_ta_transport::wait::WaitPolicy;
use std::path::Path;
use std::time::{Duration, Instant};

/// The process side of `scenario`'s transport; a scenario of a transport whose agents are
/// not processes is refused.
fn processes_of(scenario: &Scenario) -> Result<&'static dyn ProcessTransport, MemberError> {
    scenario.transport.processes().ok_or_else(|| {
        MemberError::refused(ScenarioError::Inconsistent(format!(
            "the {} transport runs no agent processes",
            scenario.transport
        )))
    })
}

/// Connects agent `index` of `scenario` (on `graph`) to its neighbours, waiting for them
/// until `deadline`; `supervised`: a launcher started it (it stops when the launcher is
/// gone). `run_dir` is the run directory. Errors are one line.
pub(crate) fn connect(
    scenario: &Scenario,
    graph: &Graph,
    index: usize,
    run_dir: &Path,
    supervised: bool,
    deadline: Instant,
) -> Result<Box<dyn AgentEndpoint>, MemberError> {
    let any_fault = fault_for(index).map_err(MemberError::failed)?;
    if let Some(fault) = any_fault.filter(|f| f.kind == FaultKind::NeverStart) {
        // Fault injection: this agent never connects (until a signal or its launcher ends).
        fault.strike();
        while admm_ta_transport::signals::received().is_none() {
            std::thread::sleep(Duration::from_millis(20));
        }
        return Err(MemberError::failed(recorded(ExchangeError::Stopped {
            agent: index,
            signal: admm_ta_transport::signals::received().unwrap_or(libc::SIGTERM),
        })));
    }
    let processes = processes_of(scenario)?;
    let digest = TeamDigest::of(scenario);
    if processes.uses_board() {
        // Another team's agent is refused by name before it opens anything of the run.
        let board =
            Board::open(&scenario.board_shm, scenario.robots).map_err(MemberError::failed)?;
        digest.check(&board, index).map_err(MemberError::refused)?;
    }
    let request = ConnectRequest {
        index,
        neighbours: graph.neighbours(index).to_vec(),
        degrees: (0..graph.robots()).map(|j| graph.degree(j)).collect(),
        payload_len: scenario.payload_len(),
        tasks: scenario.tasks,
        policy: WaitPolicy::new(scenario.wait, scenario.robots),
        run: scenario.place(run_dir),
        global_barrier: scenario.global_barrier,
        supervised,
        local_agents: scenario.local_agents.clone(),
        roster: scenario.roster.clone(),
        config: scenario.transport_config.clone(),
        team_digest: digest.to_hex(),
        fault: any_fault.filter(|_| scenario.transport.capabilities().fault_injection),
    };
    processes
        .connect(&request, deadline)
        .map_err(|error| match error {
            // Another team's agent is refused by name, naming the parts.
            ConnectError::Exchange(ExchangeError::OtherTeam { running, agent }) => {
                match TeamDigest::from_hex(&running)
                    .and_then(|running| digest.compare(&running, &format!("agent {index}")).err())
                {
                    Some(other) => MemberError::refused(other),
                    None => MemberError::refused(ExchangeError::OtherTeam { agent, running }),
                }
            }
            ConnectError::Exchange(e) => MemberError::failed(recorded(e)),
            ConnectError::Refused(e) => MemberError::Refused(e),
            ConnectError::Setup(e) => MemberError::Failed(e),
        })
}

/// A start-up error; a stop request (termination signal) is recorded as this process's, so
/// that it ends as if it had got the signal.
fn recorded(error: ExchangeError) -> ExchangeError {
    if let ExchangeError::Stopped { signal, .. } = error {
        admm_ta_transport::signals::record(signal);
    }
    error
}

/// What `scenario`'s run asks of its transport (the run directory is `run_dir`).
fn run_request(scenario: &Scenario, run_dir: &Path) -> Result<RunRequest, SupportError> {
    let graph = scenario.graph().map_err(SupportError::new)?;
    Ok(RunRequest {
        run: scenario.place(run_dir),
        run_id: scenario.run_id.clone(),
        degrees: (0..graph.robots()).map(|j| graph.degree(j)).collect(),
        payload_len: scenario.payload_len(),
        bridged: scenario.local_agents.is_some(),
    })
}

/// What a process transport's agents open but do not create, made before the first agent
/// starts (by the launcher, or a team's first member under the team's lock) and kept until
/// the agents are gone (the iceoryx2 services of an `ipc` run, an `shm` run's slot table).
pub(crate) struct RunResources {
    _resource: Option<Box<dyn Resource>>,
}

impl RunResources {
    /// Creates the resources of `scenario`'s run in `run_dir` (its transport root must
    /// exist).
    pub(crate) fn create(scenario: &Scenario, run_dir: &Path) -> Result<Self, SupportError> {
        let Some(processes) = scenario.transport.processes() else {
            return Ok(Self { _resource: None });
        };
        Ok(Self {
            _resource: processes.create_resources(&run_request(scenario, run_dir)?)?,
        })
    }
}

/// What a launcher's run needs besides the agents and the board, kept running until every
/// agent is gone: the transport's [`RunResources`] and its [`RunSupport`] (the loopback
/// router of a Zenoh run).
pub(crate) struct LauncherSupport {
    _resources: RunResources,
    support: Box<dyn RunSupport>,
}

impl LauncherSupport {
    /// Starts what `scenario`'s transport needs in the run directory `run_dir`, and tells
    /// the scenario where to find it (its transport root must exist).
    pub(crate) fn start(scenario: &mut Scenario, run_dir: &Path) -> Result<Self, SupportError> {
        let resources = RunResources::create(scenario, run_dir)?;
        let support = match scenario.transport.processes() {
            Some(processes) => processes.start_support(&run_request(scenario, run_dir)?)?,
            None => Box::new(admm_ta_transport::endpoint::NoSupport),
        };
        if let Some(config) = support.scenario_config() {
            scenario.transport_config = Some(config);
        }
        Ok(Self {
            _resources: resources,
            support,
        })
    }

    /// The agent that agents which do not read the board announced as failed, if any:
    /// waits up to `within` for the announcement. `None` at once for transports that use
    /// the board.
    pub(crate) fn announced_failure(&self, within: Duration) -> Option<usize> {
        self.support.announced_failure(within)
    }

    /// Tells agents that do not read the run's board that `agent` failed.
    pub(crate) fn announce_failure(&self, agent: usize) {
        self.support.announce_failure(agent);
    }

    /// An environment variable set for this process's support alone, not for its agents.
    pub(crate) fn unset_for_agents(&self) -> Option<&'static str> {
        self.support.unset_for_agents()
    }
}

/// Whether `scenario`'s agents record their rounds on the run's board.
pub(crate) fn uses_board(scenario: &Scenario) -> bool {
    scenario
        .transport
        .processes()
        .is_some_and(|p| p.uses_board())
}

/// Removes what the dead agents of `scenario`'s run (in `run_dir`) left that its transport
/// cleans up itself; how many (`None`: the transport leaves nothing such).
pub(crate) fn cleanup_dead(scenario: &Scenario, run_dir: &Path) -> Option<usize> {
    scenario
        .transport
        .processes()
        .and_then(|p| p.cleanup_dead(&scenario.place(run_dir)))
}
