//! The one place that maps a process transport to its exchange: how an agent process
//! connects its end of the run's transport (and whom it blames when the run fails), and
//! what a launcher keeps running for the transport while its agents run (the Zenoh router).
//!
//! A new process transport adds one arm to each `match` here; nothing else in the process
//! orchestration names a transport.

use crate::board::Board;
use crate::error_text::one_line;
use crate::exchange::{Exchange, ExchangeError};
use crate::fault::{FaultKind, fault_for};
use crate::ipc::exchange::{IpcEndpoint, IpcExchange};
use crate::ipc::nodes::run_config;
use crate::ipc::services::RunServices;
use crate::process::member_error::MemberError;
use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::process::team_digest::TeamDigest;
use crate::shm::exchange::{ShmEndpoint, ShmExchange};
use crate::shm::table::{SlotTable, TableError, table_name};
use crate::transport::Transport;
use crate::uds::{UdsEndpoint, UdsExchange};
use crate::wait::WaitPolicy;
use admm_ta_topologies::Graph;
use std::path::Path;
use std::time::Instant;

/// This agent's end of the run's transport.
pub(crate) enum Endpoint {
    // Boxed: they are large, and the enum is built once.
    Ipc(Box<IpcExchange>),
    Shm(Box<ShmExchange>),
    Uds(Box<UdsExchange>),
    #[cfg(feature = "zenoh")]
    Zenoh(Box<crate::zenoh_net::exchange::ZenohExchange>),
}

/// Connects agent `index` of `scenario` (on `graph`) to its neighbours, waiting for them
/// until `deadline`; `supervised`: a launcher started it (it stops when the launcher is
/// gone). `run_dir` holds the uds sockets. Errors are one line.
pub(crate) fn connect(
    scenario: &Scenario,
    graph: &Graph,
    index: usize,
    run_dir: &Path,
    supervised: bool,
    deadline: Instant,
) -> Result<Endpoint, MemberError> {
    let any_fault = fault_for(index)?;
    if let Some(fault) = any_fault.filter(|f| f.kind == FaultKind::NeverStart) {
        // Fault injection: this agent never connects (until a signal or its launcher ends).
        fault.strike();
        while crate::signals::received().is_none() {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        return Err(stop_or_text(ExchangeError::Stopped {
            agent: index,
            signal: crate::signals::received().unwrap_or(libc::SIGTERM),
        })
        .into());
    }
    let fault = if scenario.transport.capabilities().fault_injection {
        any_fault
    } else {
        None
    };
    let policy = WaitPolicy::new(scenario.wait, scenario.robots);
    let neighbours = graph.neighbours(index).to_vec();
    if matches!(
        scenario.transport,
        Transport::Ipc | Transport::Shm | Transport::Uds
    ) {
        // Another team's agent is refused by name before it opens a service.
        let board = Board::open(&scenario.board_shm, scenario.robots).map_err(|e| one_line(&e))?;
        TeamDigest::of(scenario)
            .check(&board, index)
            .map_err(MemberError::Refused)?;
    }
    match scenario.transport {
        Transport::Ipc => {
            let config = run_config(&scenario.iceoryx_prefix, &scenario.iceoryx_root)?;
            let endpoint = IpcEndpoint {
                index,
                degrees: (0..graph.robots()).map(|j| graph.degree(j)).collect(),
                payload_len: scenario.payload_len(),
                tasks: scenario.tasks,
                policy,
                board_shm: scenario.board_shm.clone(),
                global_barrier: scenario.global_barrier,
                supervised,
                notify_bridge: scenario
                    .local_agents
                    .as_ref()
                    .is_some_and(|local| neighbours.iter().any(|j| !local.contains(j))),
                local_agents: scenario.local_agents.clone(),
                neighbours,
            };
            let mut exchange =
                IpcExchange::connect(&endpoint, &config, deadline).map_err(stop_or_text)?;
            exchange.inject(fault);
            Ok(Endpoint::Ipc(Box::new(exchange)))
        }
        Transport::Shm => {
            let endpoint = ShmEndpoint {
                index,
                neighbours,
                degrees: (0..graph.robots()).map(|j| graph.degree(j)).collect(),
                payload_len: scenario.payload_len(),
                tasks: scenario.tasks,
                policy,
                board_shm: scenario.board_shm.clone(),
                table_shm: table_name(&scenario.iceoryx_prefix),
                supervised,
            };
            let mut exchange = ShmExchange::connect(&endpoint, deadline).map_err(stop_or_text)?;
            exchange.inject(fault);
            Ok(Endpoint::Shm(Box::new(exchange)))
        }
        Transport::Uds => {
            let endpoint = UdsEndpoint {
                index,
                neighbours,
                payload_len: scenario.payload_len(),
                policy,
                socket_dir: run_dir.to_path_buf(),
                board_shm: scenario.board_shm.clone(),
                agents: scenario.robots,
            };
            Ok(Endpoint::Uds(Box::new(UdsExchange::connect(
                &endpoint, deadline,
            )?)))
        }
        #[cfg(feature = "zenoh")]
        Transport::Zenoh => {
            let endpoint = crate::zenoh_net::exchange::ZenohEndpoint {
                index,
                neighbours,
                payload_len: scenario.payload_len(),
                policy,
                links: scenario
                    .zenoh
                    .clone()
                    .ok_or("scenario is inconsistent: a Zenoh run without Zenoh endpoints")?,
                supervised,
                team_digest: Some(TeamDigest::of(scenario).to_hex()),
            };
            let mut exchange = crate::zenoh_net::exchange::ZenohExchange::connect(
                &endpoint, deadline,
            )
            .map_err(|e| match &e {
                // Another team's agent is refused by name, naming the parts.
                ExchangeError::OtherTeam { running, .. } => MemberError::Refused(
                    TeamDigest::from_hex(running)
                        .and_then(|running| {
                            TeamDigest::of(scenario)
                                .compare(&running, &format!("agent {index}"))
                                .err()
                        })
                        .unwrap_or_else(|| e.to_string()),
                ),
                _ => MemberError::Failed(stop_or_text(e)),
            })?;
            exchange.inject(fault);
            Ok(Endpoint::Zenoh(Box::new(exchange)))
        }
        #[cfg(not(feature = "zenoh"))]
        Transport::Zenoh => Err(MemberError::Refused(
            crate::transport::ZenohNotBuilt.to_string(),
        )),
        Transport::Sim | Transport::Threads => Err(MemberError::Refused(format!(
            "scenario is inconsistent: the {} transport runs no agent processes",
            scenario.transport
        ))),
    }
}

/// A start-up error as one line; a stop request (termination signal) is recorded as this
/// process's, so that it ends as if it had got the signal.
fn stop_or_text(error: ExchangeError) -> String {
    if let ExchangeError::Stopped { signal, .. } = error {
        crate::signals::record(signal);
    }
    error.to_string()
}

/// The neighbour an exchange error is the fault of, if any.
fn culprit(error: &ExchangeError) -> Option<usize> {
    match error {
        ExchangeError::BadPayload { neighbour, .. }
        | ExchangeError::WrongLength { neighbour, .. }
        | ExchangeError::OutOfOrder { neighbour, .. }
        | ExchangeError::WrongSender { neighbour, .. } => Some(*neighbour),
        _ => None,
    }
}

impl Endpoint {
    pub(crate) fn exchange(&mut self) -> &mut dyn Exchange {
        match self {
            Self::Ipc(e) => e.as_mut(),
            Self::Shm(e) => e.as_mut(),
            Self::Uds(e) => e.as_mut(),
            #[cfg(feature = "zenoh")]
            Self::Zenoh(e) => e.as_mut(),
        }
    }

    /// Tells agents that do not read the board (Zenoh's) that this agent got termination
    /// signal `signal`: the others learn it from the stop request on the board.
    #[cfg_attr(not(feature = "zenoh"), allow(unused_variables))]
    pub(crate) fn announce_stop(&self, signal: i32) {
        match self {
            Self::Ipc(_) | Self::Shm(_) | Self::Uds(_) => {}
            #[cfg(feature = "zenoh")]
            Self::Zenoh(exchange) => exchange.request_stop(signal),
        }
    }

    /// Points the launcher and the other agents at the agent that caused `error`.
    pub(crate) fn blame_for(&self, error: &ExchangeError) {
        match self {
            Self::Ipc(exchange) => {
                if let Some(culprit) = board_culprit(error, || exchange.laggard()) {
                    exchange.blame(culprit);
                }
            }
            Self::Shm(exchange) => {
                if let Some(culprit) = board_culprit(error, || exchange.laggard()) {
                    exchange.blame(culprit);
                }
            }
            Self::Uds(exchange) => {
                let culprit = match error {
                    // A neighbour that closed or reset its socket is gone.
                    ExchangeError::PeerFailed { failed, .. } => Some(*failed),
                    e => board_culprit(e, || exchange.laggard()),
                };
                if let Some(culprit) = culprit {
                    exchange.blame(culprit);
                }
            }
            // No launcher sees every host: whoever fails first tells the others.
            #[cfg(feature = "zenoh")]
            Self::Zenoh(exchange) => {
                let culprit = match error {
                    ExchangeError::Aborted { .. } => return,
                    // Possibly seen only by us (its token vanished): pass it on.
                    ExchangeError::PeerFailed { failed, .. } => Some(*failed),
                    ExchangeError::Timeout { round, .. } => exchange.first_missing(*round),
                    e => culprit(e),
                };
                exchange.blame(culprit.unwrap_or(error.agent()));
            }
        }
    }
}

/// The agent a transport that reads the board blames for `error`: after a timeout the one
/// everybody waits for, directly or through blocked neighbours (`laggard`); else the
/// error's own culprit.
fn board_culprit(error: &ExchangeError, laggard: impl FnOnce() -> usize) -> Option<usize> {
    match error {
        ExchangeError::Timeout { .. } => Some(laggard()),
        e => culprit(e),
    }
}

/// What a process transport's agents open but do not create, made before the first agent
/// starts (by the launcher, or a team's first member under the team's lock) and kept until
/// the agents are gone: the iceoryx2 services of an `ipc` run (every agent's round service,
/// and a mixed host's bridge wake-up).
pub(crate) struct RunResources {
    _ipc: Option<RunServices>,
}

impl RunResources {
    /// Creates the resources of `scenario`'s run (its iceoryx2 root directory must exist).
    pub(crate) fn create(scenario: &Scenario) -> Result<Self, String> {
        match scenario.transport {
            Transport::Ipc => {
                let config = run_config(&scenario.iceoryx_prefix, &scenario.iceoryx_root)?;
                let graph = scenario.graph().map_err(|e| e.to_string())?;
                let degrees: Vec<usize> = (0..graph.robots()).map(|j| graph.degree(j)).collect();
                let services =
                    RunServices::create(&config, &degrees, scenario.local_agents.is_some())
                        .map_err(|e| one_line(&e))?;
                Ok(Self {
                    _ipc: Some(services),
                })
            }
            Transport::Sim
            | Transport::Threads
            | Transport::Shm
            | Transport::Uds
            | Transport::Zenoh => Ok(Self { _ipc: None }),
        }
    }
}

/// What a launcher's run needs besides the agents and the board, kept running until every
/// agent is gone: the transport's [`RunResources`], the slot table of an shm run, the
/// loopback router of a Zenoh run.
pub(crate) struct LauncherSupport {
    _resources: RunResources,
    /// The slot table of an shm run (removed when dropped).
    _slots: Option<SlotTable>,
    #[cfg(feature = "zenoh")]
    router: Option<(
        crate::zenoh_net::router::HostRouter,
        crate::zenoh_net::links::ZenohLinks,
    )>,
    /// The first agent announced as failed by an agent that does not use the board (Zenoh's
    /// blame), `usize::MAX` if none; with the subscription that sets it.
    #[cfg(feature = "zenoh")]
    announced: Option<(
        std::sync::Arc<std::sync::atomic::AtomicUsize>,
        zenoh::pubsub::Subscriber<()>,
    )>,
}

/// Why a launcher could not start what its run's transport needs.
#[derive(Debug, thiserror::Error)]
pub enum SupportError {
    #[error("cannot create the run's slot table")]
    Slots(#[source] TableError),
    #[error("cannot start the run's Zenoh router: {0}")]
    ZenohRouter(String),
    #[error("cannot start the run's Zenoh router")]
    NotBuilt(#[from] crate::transport::ZenohNotBuilt),
    #[error("{0}")]
    Resources(String),
}

impl LauncherSupport {
    /// Starts what `scenario`'s transport needs in the run of `namespace`, and tells the
    /// scenario where to find it (its iceoryx2 root directory must exist).
    pub(crate) fn start(
        scenario: &mut Scenario,
        namespace: &RunNamespace,
    ) -> Result<Self, SupportError> {
        let resources = RunResources::create(scenario).map_err(SupportError::Resources)?;
        match scenario.transport {
            #[cfg(feature = "zenoh")]
            Transport::Zenoh => {
                let router = crate::zenoh_net::router::HostRouter::open_on_loopback()
                    .map_err(SupportError::ZenohRouter)?;
                let links = crate::zenoh_net::links::ZenohLinks {
                    key_prefix: format!("admm-ta/run/{}", namespace.id),
                    connect: vec![router.endpoint.clone()],
                    hosts: Vec::new(),
                };
                scenario.zenoh = Some(links.clone());
                let first = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(usize::MAX));
                let subscriber = {
                    let first = std::sync::Arc::clone(&first);
                    crate::zenoh_net::session::watch_failures(router.session(), &links, move |a| {
                        let _ = first.compare_exchange(
                            usize::MAX,
                            a,
                            std::sync::atomic::Ordering::AcqRel,
                            std::sync::atomic::Ordering::Acquire,
                        );
                    })
                    .map_err(SupportError::ZenohRouter)?
                };
                Ok(Self {
                    _resources: resources,
                    _slots: None,
                    router: Some((router, links)),
                    announced: Some((first, subscriber)),
                })
            }
            #[cfg(not(feature = "zenoh"))]
            Transport::Zenoh => {
                let _ = (namespace, resources);
                Err(crate::transport::ZenohNotBuilt.into())
            }
            Transport::Shm => Ok(Self {
                _resources: resources,
                _slots: Some(
                    SlotTable::create(
                        &table_name(&namespace.prefix),
                        scenario.robots,
                        scenario.payload_len(),
                    )
                    .map_err(SupportError::Slots)?,
                ),
                #[cfg(feature = "zenoh")]
                router: None,
                #[cfg(feature = "zenoh")]
                announced: None,
            }),
            Transport::Sim | Transport::Threads | Transport::Ipc | Transport::Uds => Ok(Self {
                _resources: resources,
                _slots: None,
                #[cfg(feature = "zenoh")]
                router: None,
                #[cfg(feature = "zenoh")]
                announced: None,
            }),
        }
    }

    /// The agent that agents which do not read the board (Zenoh's) announced as failed, if
    /// any: waits up to `within` for the announcement (it travels through the router while
    /// the announcing agent exits). `None` at once for transports that use the board.
    pub(crate) fn announced_failure(&self, within: std::time::Duration) -> Option<usize> {
        #[cfg(feature = "zenoh")]
        if let Some((first, _)) = &self.announced {
            let until = std::time::Instant::now() + within;
            loop {
                let agent = first.load(std::sync::atomic::Ordering::Acquire);
                if agent != usize::MAX {
                    return Some(agent);
                }
                if std::time::Instant::now() >= until {
                    return None;
                }
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
        }
        let _ = within;
        None
    }

    /// Tells agents that do not read the run's board (Zenoh agents) that `agent` failed.
    pub(crate) fn announce_failure(&self, agent: usize) {
        #[cfg(feature = "zenoh")]
        if let Some((router, links)) = &self.router {
            router.announce_failure(links, agent);
        }
        #[cfg(not(feature = "zenoh"))]
        let _ = agent;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ipc::services::{Svc, open_round_service};
    use iceoryx2::prelude::*;

    #[test]
    fn agents_only_open_the_services_their_creator_made() {
        let namespace = RunNamespace::create().unwrap();
        namespace.create_iceoryx_root().unwrap();
        let config = run_config(&namespace.prefix, &namespace.iceoryx_root()).unwrap();
        let node = NodeBuilder::new()
            .config(&config)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .unwrap();
        // Before the creator: nothing to open (an agent never creates a service).
        assert!(open_round_service(&node, 0, 2).is_err());
        let degrees = [2, 2, 2];
        let services = RunServices::create(&config, &degrees, false).unwrap();
        for (j, &degree) in degrees.iter().enumerate() {
            let service = open_round_service(&node, j, degree).unwrap();
            assert_eq!(service.static_config().max_subscribers(), 2);
        }
        // One creator per run.
        assert!(RunServices::create(&config, &degrees, false).is_err());
        drop(services);
        drop(node);
        namespace.cleanup().unwrap();
        assert!(
            namespace.leftovers().is_empty(),
            "{:?}",
            namespace.leftovers()
        );
    }
}
