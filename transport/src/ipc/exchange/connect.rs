//! An `ipc` agent's start-up, in phases: join the run's board (an agent of another team
//! shape must not touch the run's services), open its node and ports on the services the
//! launcher created, wait until every neighbour subscribed to it, connect its publisher to
//! them, then wait for the whole team (the second half of the rendezvous, on the board).

use super::{IpcExchange, PeerWatch, transport};
use crate::board::{Board, BoardError, Rendezvous};
use crate::endpoint::ConnectRequest;
use crate::error_text::one_line;
use crate::exchange::ExchangeError;
use crate::exchange::header::RoundHeader;
use crate::ipc::nodes::{node_name, scan_dead_agents};
use crate::ipc::services::{
    RoundService, SUBSCRIBER_BUFFER, ServiceError, Svc, open_bridge_wake_service,
    open_round_service,
};
use iceoryx2::port::DegradationAction;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

use super::{Held, dead_node_scan_every};

impl IpcExchange {
    /// Creates this agent's node and its ports on the services its launcher created, then
    /// waits (until `deadline`) for every neighbour to subscribe, so that the round-0 message
    /// reaches everybody.
    pub fn connect(
        endpoint: &ConnectRequest,
        config: &Config,
        deadline: Instant,
    ) -> Result<Self, ExchangeError> {
        let i = endpoint.index;
        let t0 = Instant::now();
        let board = join_board(endpoint)?;
        let mut ports = Ports::open(endpoint, config, t0)?;
        let started = Instant::now();
        ports.await_subscribers(endpoint, config, &board, deadline, started)?;
        ports.connect_publisher(endpoint, deadline)?;
        board.set_connected(i);
        await_team(endpoint, &board, deadline, started)?;
        if std::env::var_os("ADMM_TA_STARTUP_TRACE").is_some() {
            let [node, own, all] = ports.opened;
            eprintln!(
                "startup agent {i}: node {node:?} own {own:?} ports {all:?} rendezvous {:?}",
                t0.elapsed()
            );
        }
        Ok(ports.into_exchange(endpoint, config, board))
    }
}

/// Phase 1: opens the run's board, checks the team's shape and registers this agent.
fn join_board(endpoint: &ConnectRequest) -> Result<Board, ExchangeError> {
    let board_err = |e: BoardError| transport(endpoint.index, one_line(&e));
    let board = Board::open(&endpoint.run.board_shm, endpoint.agents()).map_err(board_err)?;
    board
        .check_shape(endpoint.tasks, endpoint.payload_len)
        .map_err(board_err)?;
    board.set_registered(endpoint.index);
    Ok(board)
}

/// An agent's node and ports while it starts.
struct Ports {
    own_round: RoundService<Svc>,
    /// `None` only while it is replaced.
    publisher: Option<Publisher<Svc, [f64], RoundHeader>>,
    subscribers: Vec<Subscriber<Svc, [f64], RoundHeader>>,
    /// Kept to name the neighbours that never show up.
    neighbour_services: Vec<RoundService<Svc>>,
    bridge: Option<Notifier<Svc>>,
    /// When the node, the own publisher and every port were ready (since the start).
    opened: [Duration; 3],
    // Ports first: they must drop before the node.
    node: Node<Svc>,
}

/// A publisher on `service` for payloads of `payload_len` values. A connection to a
/// subscriber that cannot be established is an error here (the default only warns and
/// skips that subscriber for good): the rendezvous retries.
fn new_publisher(
    service: &RoundService<Svc>,
    payload_len: usize,
    agent: usize,
) -> Result<Publisher<Svc, [f64], RoundHeader>, ExchangeError> {
    service
        .publisher_builder()
        .initial_max_slice_len(payload_len)
        .allocation_strategy(AllocationStrategy::Static)
        .backpressure_strategy(BackpressureStrategy::DiscardData)
        .set_degradation_handler(|_, _| DegradationAction::DegradeAndFail)
        .create()
        .map_err(|e| transport(agent, format!("cannot create the publisher: {e:?}")))
}

impl Ports {
    /// Phase 2: the node, this agent's publisher, a subscriber per neighbour and (with
    /// neighbours on other hosts) the bridge's notifier. The services exist (the launcher
    /// created them before starting us): they are only opened.
    fn open(
        endpoint: &ConnectRequest,
        config: &Config,
        t0: Instant,
    ) -> Result<Self, ExchangeError> {
        let i = endpoint.index;
        let err = |what: String| transport(i, what);
        let name =
            NodeName::new(&node_name(i)).map_err(|e| err(format!("bad node name: {e:?}")))?;
        let node = NodeBuilder::new()
            .name(&name)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .config(config)
            .create::<Svc>()
            .map_err(|e| err(format!("cannot create the iceoryx2 node: {e:?}")))?;
        let service_err = |e: ServiceError| err(one_line(&e));
        let round_of = |j: usize| open_round_service(&node, j, endpoint.degrees[j]);
        let t_node = t0.elapsed();
        let own_round = round_of(i).map_err(service_err)?;
        let publisher = new_publisher(&own_round, endpoint.payload_len, i)?;
        let t_own = t0.elapsed();
        let mut subscribers = Vec::with_capacity(endpoint.neighbours.len());
        let mut neighbour_services = Vec::with_capacity(endpoint.neighbours.len());
        for &j in &endpoint.neighbours {
            let service = round_of(j).map_err(service_err)?;
            subscribers.push(
                service
                    .subscriber_builder()
                    .buffer_size(SUBSCRIBER_BUFFER)
                    .create()
                    .map_err(|e| err(format!("cannot subscribe to agent {j}: {e:?}")))?,
            );
            neighbour_services.push(service);
        }
        let bridge = if endpoint.has_remote_neighbour() {
            Some(
                open_bridge_wake_service(&node, endpoint.agents())
                    .map_err(service_err)?
                    .notifier_builder()
                    .create()
                    .map_err(|e| err(format!("cannot create the bridge's notifier: {e:?}")))?,
            )
        } else {
            None
        };
        Ok(Self {
            own_round,
            publisher: Some(publisher),
            subscribers,
            neighbour_services,
            bridge,
            opened: [t_node, t_own, t0.elapsed()],
            node,
        })
    }

    /// Phase 3: waits until every neighbour subscribed to this agent, backing off; stops on
    /// a stop request, a failure mark or (without a launcher, see [`dead_node_scan_every`]) a
    /// dead node, and at `deadline` names the neighbours that never started.
    fn await_subscribers(
        &self,
        endpoint: &ConnectRequest,
        config: &Config,
        board: &Board,
        deadline: Instant,
        started: Instant,
    ) -> Result<(), ExchangeError> {
        let i = endpoint.index;
        let degree = endpoint.neighbours.len();
        let subscribed = || self.own_round.dynamic_config().number_of_subscribers();
        let mut last_scan = Instant::now();
        let mut poll = Duration::from_micros(500);
        while subscribed() < degree {
            if let Some(signal) = board.stop_signal() {
                return Err(ExchangeError::Stopped { agent: i, signal });
            }
            if let Some(failed) = board.failed() {
                return Err(ExchangeError::PeerFailed {
                    agent: i,
                    failed,
                    round: 0,
                    how: "failed during start-up".into(),
                });
            }
            if let Some(&failed) = endpoint.neighbours.iter().find(|&&j| board.member_died(j)) {
                let _ = board.mark_failed(failed);
                return Err(ExchangeError::PeerFailed {
                    agent: i,
                    failed,
                    round: 0,
                    how: "died during start-up".into(),
                });
            }
            if !endpoint.supervised
                && last_scan.elapsed() >= dead_node_scan_every(endpoint.agents())
            {
                last_scan = Instant::now();
                if let Some(failed) = scan_dead_agents(config, i, board) {
                    return Err(ExchangeError::PeerFailed {
                        agent: i,
                        failed,
                        round: 0,
                        how: "died during start-up".into(),
                    });
                }
            }
            if Instant::now() >= deadline {
                // Marks the one to blame: an agent that never started, not its neighbours.
                let _ = board.never_connected(&endpoint.team());
                // A neighbour that started has published its service.
                let missing: Vec<usize> = endpoint
                    .neighbours
                    .iter()
                    .zip(&self.neighbour_services)
                    .filter(|(_, s)| s.dynamic_config().number_of_publishers() == 0)
                    .map(|(&j, _)| j)
                    .collect();
                return Err(transport(
                    i,
                    format!(
                        "only {} of {degree} neighbours connected within {:.1?}; missing: agent(s) {missing:?} (not started, or started too late)",
                        subscribed(),
                        started.elapsed()
                    ),
                ));
            }
            // Backing off (0.5 to 4 ms): while the last agents of a large team start, the
            // waiting ones must not take their cores.
            std::thread::sleep(poll);
            poll = (poll * 2).min(Duration::from_millis(4));
        }
        Ok(())
    }

    /// Phase 4: every subscriber is there: connects to all of them now (not lazily in the
    /// first send), recreating the publisher if a connection cannot be established.
    fn connect_publisher(
        &mut self,
        endpoint: &ConnectRequest,
        deadline: Instant,
    ) -> Result<(), ExchangeError> {
        let i = endpoint.index;
        while let Err(e) = self
            .publisher
            .as_ref()
            .expect("a publisher")
            .update_connections()
        {
            if Instant::now() >= deadline {
                return Err(transport(
                    i,
                    format!(
                        "cannot connect to the neighbours' subscribers before the start-up deadline: {e:?}"
                    ),
                ));
            }
            // The old publisher goes before its replacement is made.
            self.publisher = None;
            std::thread::sleep(Duration::from_millis(2));
            self.publisher = Some(new_publisher(&self.own_round, endpoint.payload_len, i)?);
        }
        for subscriber in &self.subscribers {
            let _ = subscriber.update_connections();
        }
        Ok(())
    }

    /// The agent's exchange, from its ports and the board.
    fn into_exchange(
        self,
        endpoint: &ConnectRequest,
        config: &Config,
        board: Board,
    ) -> IpcExchange {
        let degree = endpoint.neighbours.len();
        IpcExchange {
            index: endpoint.index,
            neighbours: endpoint.neighbours.clone(),
            payload_len: endpoint.payload_len,
            policy: endpoint.policy,
            publisher: self.publisher.expect("a publisher"),
            subscribers: self.subscribers,
            bridge: self.bridge,
            held: (0..degree).map(|_| Held::empty()).collect(),
            pending: (0..degree).map(|_| None).collect(),
            missing: Vec::with_capacity(degree),
            wake_seen: 0,
            gathered: 0,
            degrees: endpoint.degrees.clone(),
            board,
            global_barrier: endpoint.global_barrier,
            watch: PeerWatch {
                index: endpoint.index,
                config: config.clone(),
                last_dead_node_scan: Instant::now(),
                scan_every: dead_node_scan_every(endpoint.agents()),
                launcher: endpoint.supervised.then(std::os::unix::process::parent_id),
            },
            fault: endpoint.fault,
            _node: self.node,
        }
    }
}

/// Phase 5: the second half of the start-up rendezvous ([`Board::await_connected`]) as an
/// exchange error.
fn await_team(
    endpoint: &ConnectRequest,
    board: &Board,
    deadline: Instant,
    started: Instant,
) -> Result<(), ExchangeError> {
    board
        .await_connected(&endpoint.team(), deadline)
        .map_err(|waited| rendezvous_error(endpoint.index, waited, started))
}

/// The error of an agent whose start-up rendezvous ended as `waited` says.
fn rendezvous_error(agent: usize, waited: Rendezvous, started: Instant) -> ExchangeError {
    match waited {
        Rendezvous::Stopped(signal) => ExchangeError::Stopped { agent, signal },
        Rendezvous::Failed(failed) => ExchangeError::PeerFailed {
            agent,
            failed,
            round: 0,
            how: "failed during start-up".into(),
        },
        Rendezvous::NeverConnected(missing) => transport(
            agent,
            format!(
                "the team did not connect within {:.1?}; missing: agent(s) {missing:?} (not started, started too late, or stuck)",
                started.elapsed()
            ),
        ),
    }
}
