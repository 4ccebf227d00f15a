//! One agent's end of the Zenoh transport.
//!
//! Agent `i` publishes each round message on `<run>/round/<i>` and subscribes to its
//! neighbours' keys. A message is the round header and the payload, coded against the
//! agent's last message in a team of hosts ([`crate::zenoh_net::wire`]: a word unchanged
//! since the last round costs a bit), as they are on one machine. Zenoh delivers it on one
//! of its threads into a per-neighbour slot chosen by the round's parity — a neighbour is
//! never more than one round ahead, so two slots suffice and a late duplicate cannot
//! displace a message not yet read — and wakes the agent through a condition variable.
//! Gathering takes the slot's bytes and, with the lock released, decodes them into the
//! agent's copy of the neighbour's last message, in round order (a message that does not
//! decode against it is refused, never used); the step then reads the neighbours' payloads
//! there exactly as over iceoryx2, and writes its own payload in place. Publishing codes
//! the message once into the buffer Zenoh takes ownership of.
//!
//! Presence and failures, with no shared memory between hosts:
//! * every agent holds a liveliness token `<run>/alive/<i>`, declared once every host of a
//!   multi-host team is up (so every host sees the whole run) and after the agent's
//!   subscriptions (so a neighbour that sees it can send to it); start-up waits until every
//!   neighbour's token is seen and names the neighbours that never came;
//! * a neighbour whose token vanishes while its message is still awaited has died or lost
//!   the network (a killed process closes its links at once; a vanished machine is noticed
//!   after Zenoh's lease, 10 s by default): the agent stops with an error naming it;
//! * an agent that fails announces the culprit on `<run>/failed`; everybody else stops at
//!   its next wait with an error naming that agent.
//!
//! There is no global barrier: use `ipc` or `threads` for lockstep benchmarks.
//!
//! Size: one type, `ZenohExchange` — its start-up, the state Zenoh's callbacks fill, its
//! resends and its `Exchange` implementation share the same private slots and session;
//! split, they would have to expose them to each other.

use crate::endpoint::ConnectRequest;
use crate::exchange::header::{RoundHeader, words_as_bytes_mut};
use crate::exchange::{Exchange, ExchangeError};
use crate::fault::Fault;
use crate::wait::WaitPolicy;
use crate::zenoh_net::error::ZenohError;
use crate::zenoh_net::links::ZenohLinks;
use crate::zenoh_net::relay::RELAY_BYTES_PER_SECOND;
use crate::zenoh_net::session::{
    self, Role, alive_agents, alive_keys, announce_failure, missing_hosts, watch_failures,
    watch_stops,
};
use crate::zenoh_net::wire::{self, WireCoder, WireError};
use admm_ta_agents::agent::Inbox;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};
use zenoh::bytes::ZBytes;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::sample::{Sample, SampleKind};
use zenoh::{Session, Wait};

/// Longest sleep between two looks at the launcher and the failure announcements.
const FAILURE_CHECK_SLICE: Duration = Duration::from_millis(20);

/// How long a neighbour's message may still arrive after its liveliness token vanished (the
/// token and the message may travel different links).
const DEPARTURE_GRACE: Duration = Duration::from_millis(300);

/// A gather of the first rounds (below [`RESEND_ROUNDS`]) that waits this long sends the
/// agent's last two messages again, then again at doubling intervals up to
/// [`RESEND_AT_MOST_EVERY`]. Zenoh propagates a new subscription asynchronously, so a
/// message published right after start-up can find no route yet and be dropped (round-0
/// messages were lost so while a team's routers were still starting). A neighbour waiting
/// on the lost message cannot send what this agent waits for, so the waiter re-sends;
/// duplicates are harmless (a message lands in the slot of its round's parity and is taken
/// only for its own round). Later rounds travel routes that carried a message already, on
/// reliable links with blocking congestion control: nothing is dropped there, and resending
/// a slow round's messages only adds load where a team is already slow (at 100 agents on 2
/// cores every round waited past 50 ms and every agent re-sent, doubling the router's
/// traffic).
const RESEND_AFTER: Duration = Duration::from_millis(50);
const RESEND_ROUNDS: u64 = 2;

const RESEND_AT_MOST_EVERY: Duration = Duration::from_secs(1);

/// The first resend waits at least this many times the time the team's round takes to
/// relay (issue 49: with a fixed 50 ms every agent of a 200-agent team of 320 kB messages
/// re-sent a dozen times in its first rounds, and those rounds took 16–22 s instead of 1.5).
const RESEND_PATIENCE: f64 = 5.0;

/// When a gather of the first rounds sends again: after [`RESEND_AFTER`], or after
/// [`RESEND_PATIENCE`] times what the routers need to relay one round of the team whose
/// agents have `degrees` neighbours and send messages of `message_words` values, if longer.
fn resend_after(degrees: &[usize], message_words: usize) -> Duration {
    let team_bytes = degrees.iter().sum::<usize>() as f64 * (message_words * 8) as f64;
    RESEND_AFTER.max(Duration::from_secs_f64(
        RESEND_PATIENCE * team_bytes / RELAY_BYTES_PER_SECOND,
    ))
}

/// After a timeout, how long an agent waits for the network to say who is gone before it
/// names the neighbour it waited for: a Zenoh lease (10 s) and a little more. A neighbour
/// that waits for an agent cut off from the network sends nothing either, and must not be
/// the one named: the cut-off agent's token vanishes within the lease, or a host announces
/// its host lost.
const VERDICT_WITHIN: Duration = Duration::from_secs(11);

/// How often start-up asks which neighbours are present.
const PRESENCE_POLL: Duration = Duration::from_millis(50);

/// A received message in its parity slot: a raw one as its words (header and payload,
/// swapped into place when gathered, as before coding), a delta as it came.
struct Slot {
    words: Vec<f64>,
    bytes: Vec<u8>,
    /// Whether the message is a delta (in `bytes`), not raw (in `words`).
    delta: bool,
    round: Option<u64>,
}

/// What Zenoh's threads deliver, guarded by one mutex.
struct Inbound {
    /// Per neighbour, the slots of even and odd rounds.
    slots: Vec<[Slot; 2]>,
    /// Per neighbour: its token was seen, and when it vanished.
    present: Vec<bool>,
    departed: Vec<Option<Instant>>,
    /// The agent announced as failed on the run's failure key (the first announcement).
    failed: Option<usize>,
    /// A stop request (termination signal) announced on the run's failure key.
    stopped: Option<i32>,
    /// A message refused at receipt (wrong length, sender or round): the first one.
    fault: Option<ExchangeError>,
    /// Bumped on every delivery, so that a waiter never sleeps past one.
    generation: u64,
    /// Values of a payload (to name a message's wrong length).
    payload_len: usize,
    /// The last round this agent published: a neighbour is never past the next one (it
    /// sends round `k + 1` only after it holds this agent's round `k`).
    published: u64,
}

struct Shared {
    inbound: Mutex<Inbound>,
    wake: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Inbound> {
        // A panic in a Zenoh callback poisons nothing we cannot still read.
        self.inbound.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn deliver(&self, change: impl FnOnce(&mut Inbound)) {
        let mut inbound = self.lock();
        change(&mut inbound);
        inbound.generation += 1;
        drop(inbound);
        self.wake.notify_all();
    }
}

/// One agent's end of the Zenoh transport.
pub struct ZenohExchange {
    index: usize,
    neighbours: Vec<usize>,
    policy: WaitPolicy,
    shared: Arc<Shared>,
    /// The gathered messages (header words + payload), decoded from the slots.
    held: Vec<Vec<f64>>,
    /// Per neighbour, its message of the round being gathered as it came (swapped out of
    /// its slot), and which neighbours' came in the last look.
    coded: Vec<Vec<u8>>,
    taken: Vec<usize>,
    held_round: Vec<Option<u64>>,
    headers: Vec<RoundHeader>,
    /// Header words + payload of the own message.
    outbox: Vec<f64>,
    /// The own last two messages as sent, by round parity, to send again (a `ZBytes` clone
    /// shares the buffer: putting it again copies nothing).
    sent: [(Option<u64>, ZBytes); 2],
    coder: WireCoder,
    /// Bytes of round messages put on Zenoh, resends included.
    sent_bytes: u64,
    /// Messages sent again, and how long a gather of the first rounds waits before it
    /// sends again ([`resend_after`]).
    resent: u64,
    resend_after: Duration,
    /// The round last gathered, and the fault to inject (tests, [`crate::fault`]).
    gathered: u64,
    fault: Option<Fault>,
    /// Generation of the inbound state when last looked at.
    seen: u64,
    launcher: Option<u32>,
    links: ZenohLinks,
    publisher: Publisher<'static>,
    /// One per neighbour (in order), then the stop and failure watches.
    _subscribers: Vec<Subscriber<()>>,
    _token: LivelinessToken,
    session: Session,
}

fn transport(agent: usize, what: impl Into<String>) -> ExchangeError {
    ExchangeError::Transport {
        agent,
        what: what.into(),
    }
}

/// Puts a received round message of neighbour `k` (agent `neighbour`) into its slot, as it
/// came: it is decoded when gathered, in round order.
fn receive(inbound: &mut Inbound, agent: usize, k: usize, neighbour: usize, bytes: &[u8]) {
    let (round, sender) = match wire::plain(bytes) {
        Ok(plain) => plain,
        Err(_) => {
            inbound.fault.get_or_insert(ExchangeError::WrongLength {
                agent,
                neighbour,
                expected: inbound.payload_len,
                got: 0,
            });
            return;
        }
    };
    if sender as usize != neighbour {
        inbound.fault.get_or_insert(ExchangeError::WrongSender {
            agent,
            neighbour,
            got: sender,
        });
        return;
    }
    if round > inbound.published.saturating_add(1) {
        inbound.fault.get_or_insert(ExchangeError::OutOfOrder {
            agent,
            neighbour,
            expected: inbound.published.saturating_add(1),
            got: round,
        });
        return;
    }
    let slot = &mut inbound.slots[k][(round % 2) as usize];
    // A copy sent again two rounds ago can arrive after the neighbour's newer message of the
    // same parity (it queued behind large messages on another link): it must not replace it.
    if slot.round.is_some_and(|r| r > round) {
        return;
    }
    match wire::raw_words(bytes) {
        Some(words) if words.len() == 8 * slot.words.len() - wire::PLAIN_BYTES => {
            let into = words_as_bytes_mut(&mut slot.words);
            into[..wire::PLAIN_BYTES].copy_from_slice(&bytes[..wire::PLAIN_BYTES]);
            into[wire::PLAIN_BYTES..].copy_from_slice(words);
            slot.delta = false;
        }
        Some(words) => {
            let got = (words.len() + wire::PLAIN_BYTES) / 8;
            inbound.fault.get_or_insert(ExchangeError::WrongLength {
                agent,
                neighbour,
                expected: inbound.payload_len,
                got: got.saturating_sub(RoundHeader::WORDS),
            });
            return;
        }
        None => {
            slot.bytes.clear();
            slot.bytes.extend_from_slice(bytes);
            slot.delta = true;
        }
    }
    slot.round = Some(round);
}

/// Subscribes agent `i` to its neighbour `j` (its `k`-th): every message lands in `shared`.
fn subscribe_round(
    session: &Session,
    links: &ZenohLinks,
    shared: &Arc<Shared>,
    i: usize,
    k: usize,
    j: usize,
) -> zenoh::Result<Subscriber<()>> {
    let shared = Arc::clone(shared);
    session
        .declare_subscriber(links.round_key(j))
        .callback(move |sample: Sample| {
            let bytes = sample.payload().to_bytes();
            shared.deliver(|inbound| receive(inbound, i, k, j, &bytes));
        })
        .wait()
}

/// The running team's digest (hex): that of the host that started first, if any host
/// announced one.
fn running_digest(session: &Session, links: &ZenohLinks) -> Result<Option<String>, ZenohError> {
    Ok(alive_keys(session, links.digest_all())?
        .iter()
        .filter_map(|k| links.of_digest_key(k))
        .min_by(|a, b| (a.1, &a.2).cmp(&(b.1, &b.2)))
        .map(|(hex, _, _)| hex))
}

/// Agent `endpoint.index`'s subscriptions, each delivering into `shared`: one per
/// neighbour (in order), then the run's stop requests, its failure announcements and the
/// neighbours' presence.
fn subscribe(
    session: &Session,
    links: &ZenohLinks,
    shared: &Arc<Shared>,
    endpoint: &ConnectRequest,
) -> Result<Vec<Subscriber<()>>, ExchangeError> {
    let i = endpoint.index;
    let err = |what: String| transport(i, what);
    let mut subscribers = Vec::with_capacity(endpoint.neighbours.len() + 3);
    for (k, &j) in endpoint.neighbours.iter().enumerate() {
        subscribers.push(
            subscribe_round(session, links, shared, i, k, j)
                .map_err(|e| err(format!("cannot subscribe to agent {j}: {e}")))?,
        );
    }
    {
        let shared = Arc::clone(shared);
        subscribers.push(
            watch_stops(session, links, move |signal| {
                shared.deliver(|inbound| {
                    inbound.stopped.get_or_insert(signal);
                });
            })
            .map_err(|e| err(e.to_string()))?,
        );
    }
    {
        let shared = Arc::clone(shared);
        subscribers.push(
            watch_failures(session, links, move |failed, _| {
                shared.deliver(|inbound| {
                    inbound.failed.get_or_insert(failed);
                });
            })
            .map_err(|e| err(e.to_string()))?,
        );
    }
    let shared = Arc::clone(shared);
    let links = links.clone();
    let neighbours = endpoint.neighbours.clone();
    subscribers.push(
        session
            .liveliness()
            .declare_subscriber(links.alive_all())
            .history(true)
            .callback(move |sample: Sample| {
                let Some(k) = links
                    .agent_of_alive_key(sample.key_expr().as_str())
                    .and_then(|j| neighbours.iter().position(|&n| n == j))
                else {
                    return;
                };
                let kind = sample.kind();
                shared.deliver(|inbound| match kind {
                    SampleKind::Put => {
                        inbound.present[k] = true;
                        inbound.departed[k] = None;
                    }
                    SampleKind::Delete => inbound.departed[k] = Some(Instant::now()),
                });
            })
            .wait()
            .map_err(|e| err(format!("cannot watch the agents' presence: {e}")))?,
    );
    Ok(subscribers)
}

/// Waits until every host of the run is up (each watches the whole run from its start), a
/// stop or a failure announced meanwhile (a host lost before the team was up), or
/// `deadline`.
fn await_hosts(
    session: &Session,
    links: &ZenohLinks,
    shared: &Shared,
    i: usize,
    deadline: Instant,
) -> Result<(), ExchangeError> {
    loop {
        let missing = missing_hosts(session, links).map_err(|e| transport(i, e.to_string()))?;
        if missing.is_empty() {
            return Ok(());
        }
        let (stopped, failed) = {
            let inbound = shared.lock();
            (inbound.stopped, inbound.failed)
        };
        if let Some(signal) = stopped.or_else(crate::signals::received) {
            return Err(ExchangeError::Stopped { agent: i, signal });
        }
        if let Some(failed) = failed {
            return Err(ExchangeError::PeerFailed {
                agent: i,
                failed,
                round: 0,
                how: "failed during start-up".into(),
            });
        }
        if Instant::now() >= deadline {
            return Err(transport(
                i,
                format!(
                    "the team's host(s) {missing:?} did not come up before the start-up deadline (start `admm-ta host --team FILE --name NAME` on each machine)"
                ),
            ));
        }
        std::thread::sleep(PRESENCE_POLL);
    }
}

impl ZenohExchange {
    /// Opens this agent's Zenoh session, declares its subscriptions, publisher and token,
    /// and waits (until `deadline`) for every neighbour's token.
    pub fn connect(
        endpoint: &ConnectRequest,
        links: &ZenohLinks,
        deadline: Instant,
    ) -> Result<Self, ExchangeError> {
        let i = endpoint.index;
        let err = |what: String| transport(i, what);
        let session = session::open(
            &Role::Agent {
                within: deadline.saturating_duration_since(Instant::now()),
            },
            &[],
            &links.connect,
        )
        .map_err(|e| err(e.to_string()))?;
        let degree = endpoint.neighbours.len();
        let message_words = RoundHeader::WORDS + endpoint.payload_len;
        let coded_bytes = wire::PLAIN_BYTES + 1 + 8 * message_words;
        let slot = || Slot {
            words: vec![0.0; message_words],
            bytes: Vec::with_capacity(coded_bytes),
            delta: false,
            round: None,
        };
        let shared = Arc::new(Shared {
            inbound: Mutex::new(Inbound {
                slots: (0..degree).map(|_| [slot(), slot()]).collect(),
                present: vec![false; degree],
                departed: vec![None; degree],
                failed: None,
                stopped: None,
                fault: None,
                generation: 0,
                payload_len: endpoint.payload_len,
                published: 0,
            }),
            wake: Condvar::new(),
        });
        let subscribers = subscribe(&session, links, &shared, endpoint)?;
        let publisher = session
            .declare_publisher(links.round_key(i))
            .congestion_control(CongestionControl::Block)
            .express(true)
            .wait()
            .map_err(|e| err(format!("cannot declare the publisher: {e}")))?;
        await_hosts(&session, links, &shared, i, deadline)?;
        if let Some(running) = running_digest(&session, links).map_err(|e| err(e.to_string()))?
            && running != endpoint.team_digest
        {
            return Err(ExchangeError::OtherTeam { agent: i, running });
        }
        // Subscriptions first: a neighbour that sees our token can send to us.
        let token = session
            .liveliness()
            .declare_token(links.alive_key(i))
            .wait()
            .map_err(|e| err(format!("cannot declare the liveliness token: {e}")))?;
        let exchange = Self {
            index: i,
            neighbours: endpoint.neighbours.clone(),
            policy: endpoint.policy,
            shared,
            held: (0..degree).map(|_| vec![0.0; message_words]).collect(),
            coded: (0..degree)
                .map(|_| Vec::with_capacity(coded_bytes))
                .collect(),
            taken: Vec::with_capacity(degree),
            held_round: vec![None; degree],
            headers: vec![RoundHeader::default(); degree],
            outbox: vec![0.0; message_words],
            sent: [(None, ZBytes::new()), (None, ZBytes::new())],
            // Coded where the messages cross a network: a team of hosts.
            coder: WireCoder::new(message_words, !links.hosts.is_empty()),
            sent_bytes: 0,
            resent: 0,
            resend_after: resend_after(&endpoint.degrees, message_words),
            gathered: 0,
            fault: endpoint.fault,
            seen: 0,
            launcher: endpoint.supervised.then(std::os::unix::process::parent_id),
            links: links.clone(),
            publisher,
            _subscribers: subscribers,
            _token: token,
            session,
        };
        exchange.await_neighbours(deadline, links)?;
        Ok(exchange)
    }

    /// Start-up rendezvous: every neighbour's token seen.
    fn await_neighbours(&self, deadline: Instant, links: &ZenohLinks) -> Result<(), ExchangeError> {
        let started = Instant::now();
        let mut inbound = self.shared.lock();
        loop {
            // The subscriber may miss tokens declared while it propagated: ask as well.
            drop(inbound);
            let alive = alive_agents(&self.session, links)
                .map_err(|e| transport(self.index, e.to_string()))?;
            inbound = self.shared.lock();
            for (k, j) in self.neighbours.iter().enumerate() {
                inbound.present[k] |= alive.contains(j);
            }
            if let Some(signal) = inbound.stopped.or_else(crate::signals::received) {
                return Err(ExchangeError::Stopped {
                    agent: self.index,
                    signal,
                });
            }
            if let Some(failed) = inbound.failed {
                return Err(ExchangeError::PeerFailed {
                    agent: self.index,
                    failed,
                    round: 0,
                    how: "failed during start-up".into(),
                });
            }
            if inbound.present.iter().all(|&p| p) {
                return Ok(());
            }
            let now = Instant::now();
            if now >= deadline {
                let missing: Vec<usize> = self
                    .neighbours
                    .iter()
                    .zip(&inbound.present)
                    .filter(|(_, p)| !**p)
                    .map(|(&j, _)| j)
                    .collect();
                return Err(transport(
                    self.index,
                    format!(
                        "only {} of {} neighbours joined the Zenoh network within {:.1?}; missing: agent(s) {missing:?} (not started, started too late, or their host's router unreachable)",
                        self.neighbours.len() - missing.len(),
                        self.neighbours.len(),
                        started.elapsed()
                    ),
                ));
            }
            inbound = self
                .shared
                .wake
                .wait_timeout(inbound, (deadline - now).min(PRESENCE_POLL))
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
    }

    /// Asks every agent and host of the run to stop: this agent got termination signal
    /// `signal`.
    pub fn request_stop(&self, signal: i32) {
        session::announce_stop(&self.session, &self.links, signal);
    }

    /// A failure or a stop request announced on the run (between runs: a standing team's
    /// robot waiting for its next row).
    pub fn announced(&self) -> Result<(), ExchangeError> {
        let inbound = self.shared.lock();
        if let Some(signal) = inbound.stopped {
            return Err(ExchangeError::Stopped {
                agent: self.index,
                signal,
            });
        }
        match inbound.failed {
            Some(failed) => Err(ExchangeError::PeerFailed {
                agent: self.index,
                failed,
                round: self.gathered,
                how: "failed".into(),
            }),
            None => Ok(()),
        }
    }

    /// Announces `agent` as the one that failed, so that every agent of the run stops.
    pub fn blame(&self, agent: usize) {
        announce_failure(&self.session, &self.links, agent);
    }

    /// Whom to name after a timeout in round `round`: a neighbour whose message is missing
    /// and whose token vanished meanwhile; nobody (`None`) when another agent or a host
    /// announced a failure or a stop first (the first announcement is the team's verdict);
    /// else, once the network had `VERDICT_WITHIN` to say, the first missing neighbour.
    pub fn timeout_culprit(&self, round: u64) -> Option<usize> {
        let until = Instant::now() + VERDICT_WITHIN;
        let mut inbound = self.shared.lock();
        loop {
            if inbound.failed.is_some() || inbound.stopped.is_some() {
                return None;
            }
            let departed = (0..self.neighbours.len())
                .find(|&k| self.held_round[k] != Some(round) && inbound.departed[k].is_some());
            if let Some(k) = departed {
                return Some(self.neighbours[k]);
            }
            let now = Instant::now();
            if now >= until || crate::signals::received().is_some() {
                break;
            }
            inbound = self
                .shared
                .wake
                .wait_timeout(inbound, (until - now).min(FAILURE_CHECK_SLICE))
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
        drop(inbound);
        self.first_missing(round)
    }

    /// The first neighbour whose round-`round` message is missing (after a timeout).
    pub fn first_missing(&self, round: u64) -> Option<usize> {
        self.held_round
            .iter()
            .position(|&r| r != Some(round))
            .map(|k| self.neighbours[k])
    }

    /// Moves every neighbour's round-`round` message that arrived into `held`; `true` once
    /// all are held. Fails on a malformed message, an announced failure, or a neighbour that
    /// left while its message is awaited.
    fn take_arrived(&mut self, round: u64) -> Result<bool, ExchangeError> {
        self.taken.clear();
        let mut inbound = self.shared.lock();
        self.seen = inbound.generation;
        if let Some(fault) = inbound.fault.take() {
            return Err(fault);
        }
        if let Some(signal) = inbound.stopped {
            return Err(ExchangeError::Stopped {
                agent: self.index,
                signal,
            });
        }
        if let Some(failed) = inbound.failed {
            return Err(ExchangeError::PeerFailed {
                agent: self.index,
                failed,
                round,
                how: if failed == self.index {
                    "was reported failed by a neighbour".into()
                } else {
                    "failed".into()
                },
            });
        }
        let parity = (round % 2) as usize;
        let mut all = true;
        for k in 0..self.neighbours.len() {
            if self.held_round[k] == Some(round) {
                continue;
            }
            let slot = &mut inbound.slots[k][parity];
            if slot.round == Some(round) {
                slot.round = None;
                if slot.delta {
                    // Decoded once the lock is released: Zenoh's threads deliver meanwhile.
                    std::mem::swap(&mut slot.bytes, &mut self.coded[k]);
                    self.taken.push(k);
                } else {
                    std::mem::swap(&mut slot.words, &mut self.held[k]);
                    self.headers[k] = RoundHeader::from_words(&self.held[k]);
                    self.held_round[k] = Some(round);
                }
                continue;
            }
            if let Some(slot_round) = slot.round
                && slot_round > round
            {
                return Err(ExchangeError::OutOfOrder {
                    agent: self.index,
                    neighbour: self.neighbours[k],
                    expected: round,
                    got: slot_round,
                });
            }
            if inbound.departed[k].is_some_and(|t| t.elapsed() >= DEPARTURE_GRACE) {
                return Err(ExchangeError::PeerFailed {
                    agent: self.index,
                    failed: self.neighbours[k],
                    round,
                    how: "left the Zenoh network (its liveliness token vanished)".into(),
                });
            }
            all = false;
        }
        drop(inbound);
        for t in 0..self.taken.len() {
            let k = self.taken[t];
            self.headers[k] = wire::decode(&self.coded[k], &mut self.held[k], self.held_round[k])
                .map_err(|e| self.undecodable(k, round, e))?;
            self.held_round[k] = Some(round);
        }
        Ok(all)
    }

    /// The error of neighbour `k`'s round-`round` message that did not decode.
    fn undecodable(&self, k: usize, round: u64, error: WireError) -> ExchangeError {
        let (agent, neighbour) = (self.index, self.neighbours[k]);
        match error {
            WireError::Short { .. } => ExchangeError::WrongLength {
                agent,
                neighbour,
                expected: self.outbox.len() - RoundHeader::WORDS,
                got: 0,
            },
            WireError::WrongLength { got } => ExchangeError::WrongLength {
                agent,
                neighbour,
                expected: self.outbox.len() - RoundHeader::WORDS,
                got,
            },
            WireError::NotHeld { .. } => ExchangeError::OutOfOrder {
                agent,
                neighbour,
                expected: self.held_round[k].map_or(0, |r| r + 1),
                got: round,
            },
            WireError::Codec(what) => ExchangeError::Undecodable {
                agent,
                neighbour,
                round,
                what,
            },
        }
    }

    /// Sleeps until a delivery, `until`, or a failure-check slice.
    fn sleep(&mut self, until: Instant, round: u64) -> Result<(), ExchangeError> {
        let until = until.min(Instant::now() + FAILURE_CHECK_SLICE);
        let mut inbound = self.shared.lock();
        while inbound.generation == self.seen {
            let now = Instant::now();
            if now >= until {
                break;
            }
            inbound = self
                .shared
                .wake
                .wait_timeout(inbound, until - now)
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
        drop(inbound);
        self.check_launcher(round)
    }

    fn check_launcher(&self, round: u64) -> Result<(), ExchangeError> {
        if let Some(signal) = crate::signals::received() {
            return Err(ExchangeError::Stopped {
                agent: self.index,
                signal,
            });
        }
        match self.launcher {
            Some(launcher) if std::os::unix::process::parent_id() != launcher => Err(transport(
                self.index,
                format!("stopped at round {round}: its launcher (pid {launcher}) is gone"),
            )),
            _ => Ok(()),
        }
    }

    /// Fault injection (tests, [`crate::fault`]).
    pub fn inject(&mut self, fault: Option<Fault>) {
        self.fault = fault;
    }

    /// Sends the header and the first `payload_len` values of the outbox.
    fn send(&mut self, header: RoundHeader, payload_len: usize) -> Result<(), ExchangeError> {
        header.write_words(&mut self.outbox[..RoundHeader::WORDS]);
        // Zenoh takes ownership of what it sends: the one copy of the message, coded.
        let bytes = self
            .coder
            .encode(&self.outbox[..RoundHeader::WORDS + payload_len]);
        self.sent_bytes += bytes.len() as u64;
        self.sent[(header.round % 2) as usize] = (Some(header.round), ZBytes::from(bytes));
        // Before the put: a neighbour's answer to it may come at once.
        self.shared.lock().published = header.round;
        self.put(header.round)
    }

    /// Puts the kept message of `round`.
    fn put(&self, round: u64) -> Result<(), ExchangeError> {
        self.publisher
            .put(self.sent[(round % 2) as usize].1.clone())
            .wait()
            .map_err(|e| transport(self.index, format!("publishing round {round} failed: {e}")))
    }

    /// Sends the own messages of rounds `round − 1` and `round` again (see [`RESEND_AFTER`] and
    /// [`resend_after`]).
    fn resend(&mut self, round: u64) -> Result<(), ExchangeError> {
        for r in [round.checked_sub(1), Some(round)].into_iter().flatten() {
            if self.sent[(r % 2) as usize].0 == Some(r) {
                self.put(r)?;
                self.resent += 1;
                self.sent_bytes += self.sent[(r % 2) as usize].1.len() as u64;
            }
        }
        Ok(())
    }
}

impl Drop for ZenohExchange {
    fn drop(&mut self) {
        if self.resent > 0 {
            // In the agent's log: a sign of start-up races or a lossy network.
            eprintln!(
                "agent {}: sent {} message(s) again after waiting {:?} or more",
                self.index, self.resent, self.resend_after
            );
        }
        // Flushes what is queued and tells the peers we left (our token vanishes).
        session::close(&self.session);
    }
}

/// Neighbours' payloads of the gathered round, as decoded.
struct HeldInbox<'a> {
    held: &'a [Vec<f64>],
}

impl Inbox for HeldInbox<'_> {
    fn len(&self) -> usize {
        self.held.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        &self.held[k][RoundHeader::WORDS..]
    }
}

impl Exchange for ZenohExchange {
    fn degree(&self) -> usize {
        self.neighbours.len()
    }

    fn publish_initial(
        &mut self,
        header: RoundHeader,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<(), ExchangeError> {
        write(&mut self.outbox[RoundHeader::WORDS..]);
        self.send(header, self.outbox.len() - RoundHeader::WORDS)
    }

    fn gather(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let started = Instant::now();
        if round.is_multiple_of(64) {
            self.check_launcher(round)?;
        }
        // Later rounds never resend: their wait is the deadline's alone.
        let mut resend_at = if round < RESEND_ROUNDS {
            started + self.resend_after
        } else {
            deadline
        };
        let mut resend_every = self.resend_after;
        let at_most_every = RESEND_AT_MOST_EVERY.max(self.resend_after);
        let held = self.policy.wait_until(
            self,
            deadline,
            |s| s.take_arrived(round),
            |s, deadline| {
                if round < RESEND_ROUNDS && Instant::now() >= resend_at {
                    s.resend(round)?;
                    resend_every = (resend_every * 2).min(at_most_every);
                    resend_at = Instant::now() + resend_every;
                }
                s.sleep(deadline.min(resend_at), round)
            },
        )?;
        if held {
            self.gathered = round;
            return Ok(());
        }
        Err(ExchangeError::Timeout {
            agent: self.index,
            round,
            missing: self
                .held_round
                .iter()
                .zip(&self.neighbours)
                .filter(|(r, _)| **r != Some(round))
                .map(|(_, &j)| j)
                .collect(),
            waited: started.elapsed(),
        })
    }

    fn neighbour_header(&self, k: usize) -> &RoundHeader {
        &self.headers[k]
    }

    fn neighbour_payload(&self, k: usize) -> &[f64] {
        &self.held[k][RoundHeader::WORDS..]
    }

    fn compute_and_publish(
        &mut self,
        compute: &mut dyn FnMut(&dyn Inbox, &mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError> {
        let fault = self.fault.filter(|f| f.round == self.gathered);
        if let Some(fault) = fault {
            fault.strike();
        }
        let payload = &mut self.outbox[RoundHeader::WORDS..];
        let mut header = compute(&HeldInbox { held: &self.held }, payload);
        let mut len = payload.len();
        if let Some(fault) = fault {
            fault.corrupt(payload, &mut header);
            len = fault.payload_len(len);
        }
        self.send(header, len)
    }

    fn sent_bytes(&self) -> Option<u64> {
        Some(self.sent_bytes)
    }

    fn global_barrier(&mut self, _round: u64, _deadline: Instant) -> Result<(), ExchangeError> {
        Err(transport(
            self.index,
            "the Zenoh transport has no global barrier (use ipc or threads)",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small team re-sends after 50 ms as before; a team whose round is 1.28 GB waits
    /// five times the 1.28 s its router needs to relay it.
    #[test]
    fn the_first_resend_waits_for_what_the_round_takes_to_relay() {
        let ring = vec![2; 10];
        assert_eq!(resend_after(&ring, RoundHeader::WORDS + 100), RESEND_AFTER);
        let big = vec![20; 200];
        let waited = resend_after(&big, RoundHeader::WORDS + 200 * 200);
        let relayed = 4000.0 * ((RoundHeader::WORDS + 40_000) * 8) as f64 / 1e9;
        assert!((waited.as_secs_f64() - RESEND_PATIENCE * relayed).abs() < 1e-6);
        assert!(waited > Duration::from_secs(6));
    }
}
