//! The mixed mode's per-host bridge: the agents of one host exchange their messages over
//! iceoryx2 exactly as in a one-machine team, and the bridge forwards only the messages that
//! cross hosts. The agents' code is unchanged: on this host the bridge *is* the remote
//! agents — it publishes their messages on their iceoryx2 services, counts their arrivals on
//! the board and wakes the local agents, and it subscribes to every local agent that has a
//! remote neighbour (once per remote neighbour, so the agent's start-up rendezvous and its
//! delivery check count it like the neighbours it stands in for).
//!
//! Two threads, each with its own iceoryx2 node (ports stay in the thread that made them):
//! * **out**: sleeps on the bridge's wake-up service, which local agents with remote
//!   neighbours notify after every publish; reads their samples in place and puts each once
//!   on the agent's Zenoh key (`<run>/round/<i>`), coded against the agent's last message
//!   as the `zenoh` transport's agents code theirs (`admm_ta_transport::zenoh_net::wire`);
//! * **in**: receives the remote agents' messages from Zenoh (through a channel fed by
//!   Zenoh's callbacks) and publishes each into the remote agent's local service, once all
//!   of the agent's local neighbours subscribe (so round 0 is not lost to a late starter).
//!
//! Start-up order, so that no round-0 message is lost between hosts: Zenoh subscriptions
//! first, then the host's liveliness token (declared by the host after [`Bridge::start`]),
//! then — once every other host's token is seen — the local subscriptions that let local
//! agents start. Presence: the bridge declares a liveliness token `<run>/alive/<i>` for each
//! local agent while it is on the board, so every host sees the whole team come and go.
//! Failures cross hosts both ways: a failure marked on the local board is announced on the
//! run's failure key, and an announced one is marked on the local board.
//!
//! Size: one running bridge — its start-up and its two forwarding threads share the
//! private `Forwarder` state and `Layout` (tested here); split, they would have to expose
//! them to each other.

use crate::process::member_error::MemberError;
use crate::process::scenario::Scenario;
use crate::team::membership::{Membership, member_scenario};
use crate::team::team_file::{HostEntry, Team};
use admm_ta_transport::board::{Board, arrivals_target};
use admm_ta_transport::exchange::header::RoundHeader;
use admm_ta_transport::ipc::nodes::run_config;
use admm_ta_transport::ipc::services::{
    RoundService, ServiceError, Svc, open_bridge_wake_service, open_round_service,
};
use admm_ta_transport::zenoh_net::links::ZenohLinks;
use admm_ta_transport::zenoh_net::router::HostRouter;
use admm_ta_transport::zenoh_net::session::{announce_failure, missing_hosts, watch_failures};
use admm_ta_transport::zenoh_net::wire::{self, WireCoder, WireError};
use crossbeam::channel::{Receiver, RecvTimeoutError, unbounded};
use iceoryx2::port::listener::ListenerWaitError;
use iceoryx2::prelude::*;
use std::collections::{HashMap, HashSet, VecDeque};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use zenoh::bytes::ZBytes;
use zenoh::qos::CongestionControl;
use zenoh::sample::Sample;
use zenoh::{Session, Wait};

/// Longest sleep of either thread between two looks at failures and the stop flag.
const SLICE: Duration = Duration::from_millis(20);

/// Why a mixed host's bridge stopped.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    #[error("bridge")]
    Board(#[source] admm_ta_transport::board::BoardError),
    #[error("bridge")]
    Service(#[source] ServiceError),
    #[error(transparent)]
    Names(#[from] admm_ta_transport::ipc::nodes::RunNameError),
    #[error(transparent)]
    Zenoh(#[from] admm_ta_transport::zenoh_net::error::ZenohError),
    #[error("bridge: cannot start a thread")]
    Thread(#[source] std::io::Error),
    /// An iceoryx2 or Zenoh call failed (their errors, as their text).
    #[error("bridge: {what}: {detail}")]
    Call { what: String, detail: String },
    #[error("bridge: host(s) {0:?} did not come up within the start-up deadline")]
    HostsMissing(Vec<String>),
    #[error("bridge: agent {agent} sent {got} values, expected {expected}")]
    WrongLength {
        agent: usize,
        got: usize,
        expected: usize,
    },
    #[error(
        "bridge: the local neighbours {local:?} of agent {agent} did not all start within the start-up deadline"
    )]
    LocalNeighbours { agent: usize, local: Vec<usize> },
    #[error("bridge: agent {agent}'s message did not decode")]
    Undecodable {
        agent: usize,
        #[source]
        what: WireError,
    },
}

/// A bridge that stops ends its host's run as a failure.
impl From<BridgeError> for MemberError {
    fn from(error: BridgeError) -> Self {
        MemberError::failed(error)
    }
}

fn call(what: String, detail: String) -> BridgeError {
    BridgeError::Call { what, detail }
}

/// No agent failed yet (in [`Shared::announced`]).
const NONE: usize = usize::MAX;

/// What the bridge's threads and Zenoh's callbacks share.
struct Shared {
    stop: AtomicBool,
    /// The first failure announced on Zenoh.
    announced: AtomicUsize,
    error: Mutex<Option<BridgeError>>,
    forwarded_out: AtomicU64,
    forwarded_in: AtomicU64,
}

impl Shared {
    fn fail(&self, what: BridgeError) {
        self.error
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get_or_insert(what);
        self.stop.store(true, Ordering::Release);
    }
}

/// A running bridge.
pub struct Bridge {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
    membership: Option<Membership>,
    _subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    /// The bridge's token: subscribed to the other hosts' agents.
    _token: Option<zenoh::liveliness::LivelinessToken>,
}

/// Who is where, from the bridge's point of view.
#[derive(Clone)]
struct Layout {
    local: Vec<usize>,
    neighbours: Vec<Vec<usize>>,
    degrees: Vec<usize>,
    payload_len: usize,
}

impl Layout {
    fn is_local(&self, a: usize) -> bool {
        self.local.contains(&a)
    }
    /// Local agents with a neighbour on another host.
    fn local_senders(&self) -> Vec<usize> {
        self.local
            .iter()
            .copied()
            .filter(|&i| self.neighbours[i].iter().any(|&j| !self.is_local(j)))
            .collect()
    }
    /// Remote agents with a neighbour on this host.
    fn remote_senders(&self) -> Vec<usize> {
        (0..self.degrees.len())
            .filter(|&r| !self.is_local(r) && self.neighbours[r].iter().any(|&j| self.is_local(j)))
            .collect()
    }
    fn local_neighbours(&self, a: usize) -> Vec<usize> {
        self.neighbours[a]
            .iter()
            .copied()
            .filter(|&j| self.is_local(j))
            .collect()
    }
    fn remote_neighbours(&self, a: usize) -> usize {
        self.neighbours[a]
            .iter()
            .filter(|&&j| !self.is_local(j))
            .count()
    }
}

/// One run a host bridges: its scenario and namespace on this host, its Zenoh keys, the
/// host's agents in it, the hosts it spans and the deadline of its start-up.
pub(crate) struct BridgeRun {
    pub(crate) scenario: Scenario,
    pub(crate) namespace: crate::process::namespace::RunNamespace,
    pub(crate) links: ZenohLinks,
    /// This host.
    pub(crate) host: String,
    /// The hosts with agents in the run: their bridges subscribe to this host's agents
    /// before these start.
    pub(crate) hosts: Vec<String>,
    /// The run's agents on this host.
    pub(crate) local: Vec<usize>,
    pub(crate) deadline: Instant,
}

impl Bridge {
    /// Joins the host's board for the remote agents, subscribes to their Zenoh keys and
    /// starts the two forwarding threads (a mixed team's one run).
    pub fn start(team: &Team, host: &HostEntry, router: &HostRouter) -> Result<Self, MemberError> {
        let started = Instant::now();
        let (scenario, namespace) = member_scenario(team, Some(host))?;
        let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
        let run = BridgeRun {
            scenario,
            namespace,
            links: team.zenoh_links(host),
            host: host.name.clone(),
            hosts: team.file.hosts.iter().map(|h| h.name.clone()).collect(),
            local: host.agents.clone(),
            deadline,
        };
        Self::start_run(run, router.session().clone())
    }

    /// Bridges `run` over `session` (see [`Bridge::start`]); once subscribed to the other
    /// hosts' agents, says so with the bridge's token.
    pub(crate) fn start_run(run: BridgeRun, session: Session) -> Result<Self, MemberError> {
        let BridgeRun {
            scenario,
            namespace,
            links,
            host,
            hosts,
            local,
            deadline,
        } = run;
        let graph = scenario.graph().map_err(MemberError::failed)?;
        let n = scenario.robots;
        let layout = Layout {
            local,
            neighbours: (0..n).map(|a| graph.neighbours(a).to_vec()).collect(),
            degrees: (0..n).map(|a| graph.degree(a)).collect(),
            payload_len: scenario.payload_len(),
        };
        let in_run = |a: &usize| scenario.roster.as_ref().is_none_or(|r| r.contains(a));
        let remote: Vec<usize> = (0..n)
            .filter(|a| !layout.is_local(*a) && in_run(a))
            .collect();
        let membership = Membership::join(&scenario, &namespace, &remote, deadline)
            .map_err(MemberError::failed)?;
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            announced: AtomicUsize::new(NONE),
            error: Mutex::new(None),
            forwarded_out: AtomicU64::new(0),
            forwarded_in: AtomicU64::new(0),
        });
        // Zenoh side first: the remote agents' messages, failures, and the other hosts.
        // The samples' buffers travel by reference count: copied once, into iceoryx2.
        let (to_in, inbox) = unbounded::<(usize, ZBytes)>();
        let mut subscribers = Vec::new();
        for r in layout.remote_senders() {
            let to_in = to_in.clone();
            subscribers.push(
                session
                    .declare_subscriber(links.round_key(r))
                    .callback(move |sample: Sample| {
                        let _ = to_in.send((r, sample.payload().clone()));
                    })
                    .wait()
                    .map_err(|e| call(format!("cannot subscribe to agent {r}"), e.to_string()))?,
            );
        }
        {
            let shared = Arc::clone(&shared);
            subscribers.push(
                watch_failures(&session, &links, move |failed, _| {
                    let _ = shared.announced.compare_exchange(
                        NONE,
                        failed,
                        Ordering::AcqRel,
                        Ordering::Acquire,
                    );
                })
                .map_err(BridgeError::from)?,
            );
        }
        let token = session
            .liveliness()
            .declare_token(links.bridge_key(&host))
            .wait()
            .map_err(|e| call("cannot declare the bridge's token".into(), e.to_string()))?;
        let forwarder = Forwarder {
            shared: Arc::clone(&shared),
            session,
            links,
            scenario,
            layout,
            hosts,
        };
        let threads = vec![
            forwarder
                .clone()
                .spawn("bridge-out", move |f| f.forward_out(deadline))?,
            forwarder.spawn("bridge-in", move |f| f.forward_in(&inbox, deadline))?,
        ];
        Ok(Self {
            shared,
            threads,
            membership: Some(membership),
            _subscribers: subscribers,
            _token: Some(token),
        })
    }

    /// The first error of a forwarding thread.
    pub fn check(&self) -> Result<(), BridgeError> {
        match self
            .shared
            .error
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
        {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The agent marked failed on this host's board, if any (a local failure, or one
    /// announced by another host).
    pub fn failed(&self) -> Option<usize> {
        self.membership.as_ref().and_then(|m| m.board().failed())
    }

    /// Stops the threads (after a last forwarding pass), leaves the board; returns the
    /// messages forwarded out and in.
    pub fn finish(mut self) -> (u64, u64) {
        self.stop_threads();
        if let Some(m) = self.membership.take() {
            m.leave();
        }
        (
            self.shared.forwarded_out.load(Ordering::Relaxed),
            self.shared.forwarded_in.load(Ordering::Relaxed),
        )
    }

    fn stop_threads(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for Bridge {
    fn drop(&mut self) {
        self.stop_threads();
        if let Some(m) = self.membership.take() {
            m.leave();
        }
    }
}

fn node(scenario: &Scenario, name: &str) -> Result<Node<Svc>, BridgeError> {
    let config = run_config(&scenario.prefix, &scenario.transport_root)?;
    let name = NodeName::new(name).map_err(|e| call("bad node name".into(), format!("{e:?}")))?;
    NodeBuilder::new()
        .name(&name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .config(&config)
        .create::<Svc>()
        .map_err(|e| call("cannot create an iceoryx2 node".into(), format!("{e:?}")))
}

fn board(scenario: &Scenario) -> Result<Board, BridgeError> {
    Board::open(&scenario.board_shm, scenario.robots).map_err(BridgeError::Board)
}

/// An iceoryx2 subscriber to a local agent's round messages.
type RoundSubscriber = iceoryx2::port::subscriber::Subscriber<Svc, [f64], RoundHeader>;

/// A local agent's subscribers (one per remote neighbour), its Zenoh publisher, the coder
/// of its messages and room for one (header words and payload, allocated once).
type Sender = (
    Vec<RoundSubscriber>,
    zenoh::pubsub::Publisher<'static>,
    WireCoder,
    Vec<f64>,
);

/// A remote agent's round service, the publisher standing in for it, its local neighbours.
type StandIn = (RoundService<Svc>, StandInPublisher, Vec<usize>);

/// The publisher that stands in for a remote agent on its local service.
type StandInPublisher = iceoryx2::port::publisher::Publisher<Svc, [f64], RoundHeader>;

/// A remote agent's last message (header words and payload) and its round, to decode the
/// next one against.
type Held = (Vec<f64>, Option<u64>);

/// What the two forwarding threads own.
#[derive(Clone)]
struct Forwarder {
    shared: Arc<Shared>,
    session: Session,
    links: ZenohLinks,
    scenario: Scenario,
    layout: Layout,
    /// The hosts whose bridges must be subscribed to this host's agents first.
    hosts: Vec<String>,
}

impl Forwarder {
    /// Runs `body` on a thread of its own; its error stops the bridge.
    fn spawn(
        self,
        name: &str,
        body: impl FnOnce(&Self) -> Result<(), BridgeError> + Send + 'static,
    ) -> Result<JoinHandle<()>, BridgeError> {
        std::thread::Builder::new()
            .name(name.into())
            .spawn(move || {
                if let Err(e) = body(&self) {
                    self.shared.fail(e);
                }
            })
            .map_err(BridgeError::Thread)
    }

    /// Local agents' messages out to Zenoh.
    fn forward_out(&self, deadline: Instant) -> Result<(), BridgeError> {
        if !self.await_other_bridges(deadline)? {
            return Ok(());
        }
        let node = node(&self.scenario, "bridge-out")?;
        let board = board(&self.scenario)?;
        let listener = open_bridge_wake_service(&node, self.scenario.robots)
            .map_err(BridgeError::Service)?
            .listener_builder()
            .create()
            .map_err(|e| call("cannot create its listener".into(), format!("{e:?}")))?;
        let mut senders = self.senders(&node)?;
        let mut announced_local = false;
        loop {
            let stopping = self.shared.stop.load(Ordering::Acquire);
            for (subscribers, publisher, coder, message) in &mut senders {
                self.forward_agent(subscribers, publisher, (coder, message))?;
            }
            if !announced_local && let Some(failed) = board.failed() {
                // A local failure (or one we marked from an announcement: harmless echo).
                announce_failure(&self.session, &self.links, failed);
                announced_local = true;
            }
            if stopping {
                return Ok(());
            }
            match listener.timed_wait(|_| {}, SLICE) {
                Ok(_) | Err(ListenerWaitError::InterruptSignal) => {}
                Err(e) => return Err(call("waiting failed".into(), format!("{e:?}"))),
            }
        }
    }

    /// Waits until every other bridge of the run subscribed to our agents, before we let
    /// them start: a bridge declares its token after its subscriptions, and its host
    /// declares its own once its team file is found the running team's. `false`: stopping,
    /// or a failure announced meanwhile (a host lost before the team was up: the board has
    /// it, `forward_in` marks it), nothing will be forwarded.
    fn await_other_bridges(&self, deadline: Instant) -> Result<bool, BridgeError> {
        loop {
            let up = admm_ta_transport::zenoh_net::session::alive_keys(
                &self.session,
                self.links.bridge_key("*"),
            )?;
            let mut missing = missing_hosts(&self.session, &self.links)?;
            missing.extend(
                self.hosts
                    .iter()
                    .filter(|h| !up.contains(&self.links.bridge_key(h)))
                    .cloned(),
            );
            if missing.is_empty() {
                return Ok(true);
            }
            if self.shared.stop.load(Ordering::Acquire)
                || self.shared.announced.load(Ordering::Acquire) != NONE
            {
                return Ok(false);
            }
            if Instant::now() >= deadline {
                return Err(BridgeError::HostsMissing(missing));
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Per local agent with remote neighbours: one subscriber per remote neighbour, and its
    /// Zenoh publisher.
    fn senders(&self, node: &Node<Svc>) -> Result<Vec<Sender>, BridgeError> {
        let mut senders = Vec::new();
        for i in self.layout.local_senders() {
            let service = open_round_service(node, i, self.layout.degrees[i])
                .map_err(BridgeError::Service)?;
            let subscribers = (0..self.layout.remote_neighbours(i))
                .map(|_| {
                    service
                        .subscriber_builder()
                        .buffer_size(2)
                        .create()
                        .map_err(|e| {
                            call(format!("cannot subscribe to agent {i}"), format!("{e:?}"))
                        })
                })
                .collect::<Result<Vec<_>, _>>()?;
            let publisher = self
                .session
                .declare_publisher(self.links.round_key(i))
                .congestion_control(CongestionControl::Block)
                .express(true)
                .wait()
                .map_err(|e| {
                    call(
                        format!("cannot publish agent {i}'s messages"),
                        e.to_string(),
                    )
                })?;
            let words = RoundHeader::WORDS + self.layout.payload_len;
            let coder = WireCoder::new(words, true);
            senders.push((subscribers, publisher, coder, vec![0.0; words]));
        }
        Ok(senders)
    }

    /// Forwards what one local agent published: every remote neighbour's copy arrives and
    /// one goes out. The spare copies are dropped first: the agent may publish again as
    /// soon as one is forwarded, and a spare queue still holding two samples would then be
    /// full (the sample discarded, the agent's delivery check failing).
    fn forward_agent(
        &self,
        subscribers: &[RoundSubscriber],
        publisher: &zenoh::pubsub::Publisher<'_>,
        (coder, message): (&mut WireCoder, &mut [f64]),
    ) -> Result<(), BridgeError> {
        let (first, spares) = subscribers.split_first().expect("one per remote neighbour");
        for spare in spares {
            while spare
                .receive()
                .map_err(|e| call("receive failed".into(), format!("{e:?}")))?
                .is_some()
            {}
        }
        while let Some(sample) = first
            .receive()
            .map_err(|e| call("receive failed".into(), format!("{e:?}")))?
        {
            let payload = sample.payload();
            if payload.len() != self.layout.payload_len {
                return Err(BridgeError::WrongLength {
                    agent: sample.user_header().sender as usize,
                    got: payload.len(),
                    expected: self.layout.payload_len,
                });
            }
            // From the shared-memory sample, coded into the buffer Zenoh owns.
            let (header, rest) = message.split_at_mut(RoundHeader::WORDS);
            sample.user_header().write_words(header);
            rest.copy_from_slice(payload);
            publisher
                .put(coder.encode(message))
                .wait()
                .map_err(|e| call("forwarding failed".into(), e.to_string()))?;
            self.shared.forwarded_out.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    }

    /// Remote agents' messages in from Zenoh.
    fn forward_in(
        &self,
        inbox: &Receiver<(usize, ZBytes)>,
        deadline: Instant,
    ) -> Result<(), BridgeError> {
        let node = node(&self.scenario, "bridge-in")?;
        let board = board(&self.scenario)?;
        let publishers = self.stand_ins(&node)?;
        let words = RoundHeader::WORDS + self.layout.payload_len;
        let mut held: HashMap<usize, Held> = publishers
            .keys()
            .map(|&r| (r, (vec![0.0; words], None)))
            .collect();
        let mut pending: VecDeque<(usize, ZBytes)> = VecDeque::new();
        let mut tokens: HashMap<usize, zenoh::liveliness::LivelinessToken> = HashMap::new();
        let mut marked = false;
        loop {
            match inbox.recv_timeout(SLICE) {
                Ok(message) => pending.push_back(message),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return Ok(()),
            }
            pending.extend(inbox.try_iter());
            // In arrival order; a remote agent whose local neighbours are not all subscribed
            // yet waits (only at start-up), and so do its later messages.
            let mut blocked = HashSet::new();
            let mut kept = VecDeque::new();
            while let Some((r, message)) = pending.pop_front() {
                let Some((service, publisher, local)) = publishers.get(&r) else {
                    continue;
                };
                if blocked.contains(&r)
                    || service.dynamic_config().number_of_subscribers() < local.len()
                {
                    if Instant::now() >= deadline {
                        return Err(BridgeError::LocalNeighbours {
                            agent: r,
                            local: local.clone(),
                        });
                    }
                    blocked.insert(r);
                    kept.push_back((r, message));
                    continue;
                }
                let held = held.get_mut(&r).expect("one per stand-in");
                self.publish_remote(&board, r, &message, held, (publisher, local))?;
            }
            pending = kept;
            self.tell_presence(&board, &mut tokens)?;
            let announced = self.shared.announced.load(Ordering::Acquire);
            if !marked && announced != NONE {
                let _ = board.mark_failed(announced);
                marked = true;
            }
            if self.shared.stop.load(Ordering::Acquire) {
                return Ok(());
            }
        }
    }

    /// For every remote agent with a neighbour here: its round service, a publisher that
    /// stands in for it, and its local neighbours.
    fn stand_ins(&self, node: &Node<Svc>) -> Result<HashMap<usize, StandIn>, BridgeError> {
        let layout = &self.layout;
        let mut publishers = HashMap::new();
        for r in layout.remote_senders() {
            let service =
                open_round_service(node, r, layout.degrees[r]).map_err(BridgeError::Service)?;
            let publisher = service
                .publisher_builder()
                .initial_max_slice_len(layout.payload_len)
                .allocation_strategy(AllocationStrategy::Static)
                .create()
                .map_err(|e| call(format!("cannot publish for agent {r}"), format!("{e:?}")))?;
            publishers.insert(r, (service, publisher, layout.local_neighbours(r)));
        }
        Ok(publishers)
    }

    /// Publishes remote agent `r`'s `message`, decoded against its last one (`held`), on its
    /// local service (through the `publisher` standing in for it), counts its arrival for
    /// its `local` neighbours on the board and wakes them, as a local neighbour would.
    fn publish_remote(
        &self,
        board: &Board,
        r: usize,
        message: &ZBytes,
        held: &mut Held,
        (publisher, local): (&StandInPublisher, &[usize]),
    ) -> Result<(), BridgeError> {
        let layout = &self.layout;
        let (last, last_round) = held;
        let header = match wire::decode(&message.to_bytes(), last, *last_round) {
            Ok(header) => header,
            Err(what) => {
                // The sender is at fault: every host's agents stop naming it.
                let _ = board.mark_failed(r);
                announce_failure(&self.session, &self.links, r);
                return Err(BridgeError::Undecodable { agent: r, what });
            }
        };
        *last_round = Some(header.round);
        let payload = &last[RoundHeader::WORDS..];
        let mut sample = publisher
            .loan_slice_uninit(layout.payload_len)
            .map_err(|e| call("cannot loan a sample".into(), format!("{e:?}")))?
            .write_from_slice(payload);
        *sample.user_header_mut() = header;
        sample
            .send()
            .map_err(|e| call("send failed".into(), format!("{e:?}")))?;
        board.set_published_round(r, header.round);
        for &j in local {
            let arrived = board
                .arrivals(j, header.round)
                .fetch_add(1, Ordering::AcqRel)
                + 1;
            if arrived == arrivals_target(layout.degrees[j], header.round) {
                // As a local neighbour would: bump j's wake word, then wake it.
                admm_ta_transport::futex::bump_and_wake(board.wake_word(j));
            }
        }
        self.shared.forwarded_in.fetch_add(1, Ordering::Relaxed);
        Ok(())
    }

    /// The local agents' presence, for the other hosts: a token per local agent alive on
    /// the board (`tokens`, by agent).
    fn tell_presence(
        &self,
        board: &Board,
        tokens: &mut HashMap<usize, zenoh::liveliness::LivelinessToken>,
    ) -> Result<(), BridgeError> {
        for &i in &self.layout.local {
            let alive = board.member_alive(i);
            if alive && !tokens.contains_key(&i) {
                let token = self
                    .session
                    .liveliness()
                    .declare_token(self.links.alive_key(i))
                    .wait()
                    .map_err(|e| {
                        call(format!("cannot declare agent {i}'s token"), e.to_string())
                    })?;
                tokens.insert(i, token);
            } else if !alive && let Some(token) = tokens.remove(&i) {
                let _ = token.undeclare().wait();
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_of_a_ring_over_two_hosts() {
        // Ring 0-1-2-3-0, agents 0 and 1 here.
        let layout = Layout {
            local: vec![0, 1],
            neighbours: vec![vec![1, 3], vec![0, 2], vec![1, 3], vec![2, 0]],
            degrees: vec![2; 4],
            payload_len: 1,
        };
        assert_eq!(layout.local_senders(), vec![0, 1]);
        assert_eq!(layout.remote_senders(), vec![2, 3]);
        assert_eq!(layout.local_neighbours(3), vec![0]);
        assert_eq!(layout.remote_neighbours(0), 1);
    }
}
