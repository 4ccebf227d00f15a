//! The iceoryx2 end of one agent process: one publish-subscribe service per agent carrying
//! its round messages (`[f64]` payload + [`RoundHeader`] user header), created by the run's
//! launcher before the agents start ([`crate::ipc::services`]), and the run-wide *board* in
//! shared memory ([`crate::board`]: arrival counters, futex wake-up words, the optional
//! global barrier).
//!
//! Agent `i` publishes on `admm-ta/i/round`; each neighbour subscribes to it. The payload is
//! written in place into the loaned sample and read in place by the neighbours: no copy on
//! either side. A waiting agent receives only from the neighbours whose message of the round
//! it does not hold yet (a "still missing" list, no scan of every subscriber per wake-up),
//! keeps the header and payload of every held sample at hand, spins briefly (only when it
//! has a core of its own) and then sleeps on its futex wake-up word until the deadline, in
//! slices between which it looks for failed agents.
//!
//! Wake-ups: after publishing round `r`, `i` increments each neighbour `j`'s arrival counter
//! for the parity of `r` on the board, and wakes `j` (bumps `j`'s wake word, then
//! `FUTEX_WAKE` if `j` sleeps: [`futex::bump_and_wake`]) only if the count reached `deg(j) · (⌊r/2⌋ + 1)`, i.e. it was the last of
//! `j`'s round-`r` messages to be counted. So a waiting agent is woken about once per round,
//! not once per neighbour: on a complete graph of 50 agents sharing 2 cores, waking every
//! agent 49 times per round cost more than the algorithm. The counts are cumulative, never
//! reset: a message is counted after it is delivered, so a reset could race with a late
//! count and lose a wake-up. Counts of round `r + 2` can precede late counts of round `r`,
//! but the count that completes round `r + 2` is always one of round `r + 2` (a neighbour
//! counts its round `r` before its round `r + 2`), so a wake-up is never lost; at worst one
//! is spurious. The waiter reads its wake word *before* it looks at its subscribers and
//! sleeps only while the word still holds that value, so a wake-up in between is not lost
//! (the protocol of [`crate::futex`]: an agent that is not asleep costs its waker no system
//! call).
//!
//! Buffers: a neighbour is at most one round ahead (neighbour barrier), so each subscriber
//! holds at most two unread samples and borrows at most two; safe overflow is off, and a
//! sample that does not reach every subscriber is an error, never a silently lost round.
//!
//! The start-up (node, ports, rendezvous) is in `connect`, in named phases.
//!
//! Size: one type, `IpcExchange` — its receive and send paths and its `Exchange`
//! implementation all work on the same private ports, samples and board; split, they would
//! have to expose them to each other.

use crate::board::{Board, arrivals_target};
use crate::exchange::header::{MessageFault, Placement, RoundHeader, check_message};
use crate::exchange::{Exchange, ExchangeError};
use crate::fault::Fault;
use crate::futex;
use crate::ipc::nodes::scan_dead_agents;
use crate::ipc::services::Svc;
use crate::wait::WaitPolicy;
use admm_ta_agents::agent::Inbox;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

mod connect;

type RoundSample = Sample<Svc, [f64], RoundHeader>;

/// A waiting agent of a team of fewer than 40 scans the run's iceoryx2 nodes for dead ones once
/// it has waited this long for a round, and again at this interval (larger teams: see
/// [`dead_node_scan_every`]). Scans read every node of the run, so they are kept off the
/// normal path: with 100 agents on 2 cores, scanning after 100 ms slowed rounds a
/// hundredfold. (Under the launcher a dead agent is found within milliseconds by `waitpid`
/// anyway; the scan is for agents started without one.)
const DEAD_NODE_SCAN_EVERY: Duration = Duration::from_millis(500);

/// How often an agent of a team of `agents` without a launcher scans the run's nodes for a
/// dead one while it waits, at start-up and in rounds: a scan reads every node of the run
/// and every waiting agent scans, so the interval grows with the team (0.5 s per 20
/// agents): the team scans as often in all at any size. (With a fixed 0.5 s, 200 agents
/// scanning took most of the 2 cores while the last agents started, and in a standing team
/// of 200 sidecars a round that took over 0.5 s set every agent scanning, which kept the
/// rounds that slow: episodes of 35 s took 290 s, 371 s and once over 10 minutes,
/// bench/README.md.) One agent that finds a dead node marks it on the board for all, so the
/// team still looks far more often than each agent.
fn dead_node_scan_every(agents: usize) -> Duration {
    DEAD_NODE_SCAN_EVERY * (agents / 20).max(1) as u32
}

/// A neighbour's sample of the gathered round with its header and payload at hand: read
/// once when it arrives, not re-derived from the shared memory at every use.
struct Held {
    sample: Option<RoundSample>,
    header: RoundHeader,
    /// The sample's payload (`len` values), valid while `sample` is held.
    payload: *const f64,
    len: usize,
}

impl Held {
    fn empty() -> Self {
        Self {
            sample: None,
            header: RoundHeader::default(),
            payload: std::ptr::null(),
            len: 0,
        }
    }

    fn hold(&mut self, sample: RoundSample) {
        self.header = *sample.user_header();
        let payload = sample.payload();
        (self.payload, self.len) = (payload.as_ptr(), payload.len());
        self.sample = Some(sample);
    }

    fn payload(&self) -> &[f64] {
        if self.sample.is_none() {
            return &[];
        }
        // SAFETY: `payload` and `len` describe the payload of `sample`, which is held (its
        // shared memory stays mapped and untouched by the publisher) as long as `self` is
        // not changed, and `&self` keeps it so for the returned slice's lifetime.
        unsafe { std::slice::from_raw_parts(self.payload, self.len) }
    }
}

/// One agent's iceoryx2 ports.
pub struct IpcExchange {
    index: usize,
    neighbours: Vec<usize>,
    payload_len: usize,
    policy: WaitPolicy,
    publisher: Publisher<Svc, [f64], RoundHeader>,
    subscribers: Vec<Subscriber<Svc, [f64], RoundHeader>>,
    /// Wakes the host's bridge (agents with neighbours on other hosts).
    bridge: Option<Notifier<Svc>>,
    held: Vec<Held>,
    pending: Vec<Option<RoundSample>>,
    /// Neighbours (indices into `neighbours`) whose message of the round being gathered is
    /// not held yet (capacity: the degree; never reallocated).
    missing: Vec<usize>,
    /// The value of this agent's wake word read before its last look at the subscribers.
    wake_seen: u32,
    gathered: u64,
    degrees: Vec<usize>,
    board: Board,
    global_barrier: bool,
    /// Looks for a failed peer, a stop request or a gone launcher while the agent waits.
    watch: PeerWatch,
    /// Fault injection (tests): misbehave when publishing after gathering its round.
    fault: Option<Fault>,
    // Ports first: they must drop before the node.
    _node: Node<Svc>,
}

fn transport(agent: usize, what: impl std::fmt::Display) -> ExchangeError {
    ExchangeError::Transport {
        agent,
        what: what.to_string(),
    }
}

impl IpcExchange {
    /// Marks agent `agent` as the one that failed (unless another was marked first), so that
    /// the launcher and every agent blame it.
    pub fn blame(&self, agent: usize) {
        let _ = self.board.mark_failed(agent);
    }

    /// The agent that published the fewest rounds: after a timeout, the one everybody is
    /// waiting for, directly or through a chain of blocked neighbours.
    pub fn laggard(&self) -> usize {
        self.board.laggard().unwrap_or(self.index)
    }

    /// Fault injection (tests, [`crate::fault`]).
    pub fn inject(&mut self, fault: Option<Fault>) {
        self.fault = fault;
    }

    /// Stops this agent if another agent failed ([`PeerWatch::check`]).
    fn check_peers(&mut self, round: u64, waited: Duration) -> Result<(), ExchangeError> {
        self.watch.check(&self.board, round, waited)?;
        // Without a launcher (an independently started team), a neighbour whose process the
        // board records is gone: at once, not at the next scan of the nodes.
        if self.watch.launcher.is_none()
            && !waited.is_zero()
            && let Some(&failed) = self.neighbours.iter().find(|&&j| self.board.member_died(j))
        {
            let _ = self.board.mark_failed(failed);
            return Err(ExchangeError::PeerFailed {
                agent: self.index,
                failed,
                round,
                how: "died (its process is gone)".into(),
            });
        }
        Ok(())
    }

    /// Moves neighbour `k`'s round-`round` message into `held[k]`; `false` if not there yet.
    fn advance(&mut self, k: usize, round: u64) -> Result<bool, ExchangeError> {
        if self.held[k].sample.is_some() && self.held[k].header.round == round {
            return Ok(true);
        }
        if let Some(next) = self.pending[k].take() {
            if next.user_header().round == round {
                self.held[k].hold(next);
                return Ok(true);
            }
            self.pending[k] = Some(next);
        }
        loop {
            let sample = self.subscribers[k]
                .receive()
                .map_err(|e| transport(self.index, format!("receive failed: {e:?}")))?;
            let Some(sample) = sample else {
                return Ok(false);
            };
            let (agent, neighbour) = (self.index, self.neighbours[k]);
            let placement = check_message(
                sample.user_header(),
                sample.payload().len(),
                self.payload_len,
                neighbour,
                round,
                self.pending[k].is_none(),
            )
            .map_err(|fault| match fault {
                MessageFault::WrongLength { got } => ExchangeError::WrongLength {
                    agent,
                    neighbour,
                    expected: self.payload_len,
                    got,
                },
                MessageFault::WrongSender { got } => ExchangeError::WrongSender {
                    agent,
                    neighbour,
                    got,
                },
                MessageFault::OutOfOrder { got } => ExchangeError::OutOfOrder {
                    agent,
                    neighbour,
                    expected: round,
                    got,
                },
            })?;
            match placement {
                Placement::Current => {
                    self.held[k].hold(sample);
                    return Ok(true);
                }
                Placement::Next => self.pending[k] = Some(sample),
            }
        }
    }

    /// Receives from the neighbours still missing for `round`; `true` once every
    /// neighbour's message is held. Reads this agent's wake word first (see the module's
    /// wake-ups: a neighbour counts its arrival after delivering its sample, and the count
    /// that completes the round is the one that wakes this agent).
    ///
    /// Until every message of the round is counted on the board, nothing is received (an
    /// empty receive costs about as much as a full one, and so does a look at every
    /// neighbour's published round), unless `look_at_each` (once per failure-check slice of
    /// a wait): then every missing neighbour that published the round (or, faulty, a round
    /// of the wrong parity ahead, which is never counted for this round) is received from,
    /// so that such a message is refused instead of waited for.
    fn all_held(&mut self, round: u64, look_at_each: bool) -> Result<bool, ExchangeError> {
        self.wake_seen = self.board.wake_word(self.index).load(Ordering::Acquire);
        let counted = self
            .board
            .arrivals(self.index, round)
            .load(Ordering::Acquire)
            >= arrivals_target(self.degrees[self.index], round);
        if !counted && !look_at_each {
            return Ok(false);
        }
        let mut at = 0;
        while at < self.missing.len() {
            let k = self.missing[at];
            if !counted && self.board.published_round(self.neighbours[k]) < round {
                at += 1;
                continue;
            }
            if self.advance(k, round)? {
                self.missing.swap_remove(at);
            } else {
                at += 1;
            }
        }
        Ok(self.missing.is_empty())
    }

    /// Publishes the payload `compute` writes in place, as `fault` (tests) says if any.
    fn send(
        &mut self,
        fault: Option<Fault>,
        compute: &mut dyn FnMut(&mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError> {
        let i = self.index;
        let len = fault.map_or(self.payload_len, |f| f.payload_len(self.payload_len));
        // Zero-filled once (the loan is uninitialised memory), then written in place.
        let mut sample = self
            .publisher
            .loan_slice_uninit(len)
            .map_err(|e| transport(i, format!("cannot loan a sample: {e:?}")))?
            .write_from_fn(|_| 0.0);
        let header = match fault {
            None => compute(sample.payload_mut()),
            Some(fault) => {
                // Fault injection only: compute in full, then corrupt and cut.
                let mut full = vec![0.0; self.payload_len];
                let mut header = compute(&mut full);
                fault.corrupt(&mut full, &mut header);
                sample.payload_mut().copy_from_slice(&full[..len]);
                header
            }
        };
        *sample.user_header_mut() = header;
        let delivered = sample
            .send()
            .map_err(|e| transport(i, format!("send failed: {e:?}")))?;
        if delivered < self.subscribers.len() {
            // A neighbour gone because another agent failed: that failure is the cause.
            // (`MAX`: scan the nodes now, launcher or not: a subscriber vanished.)
            self.check_peers(header.round, Duration::MAX)?;
            return Err(transport(
                i,
                format!(
                    "round {} reached {delivered} of {} neighbours",
                    header.round,
                    self.subscribers.len()
                ),
            ));
        }
        self.board.set_published_round(i, header.round);
        for &j in &self.neighbours {
            let arrived = self
                .board
                .arrivals(j, header.round)
                .fetch_add(1, Ordering::AcqRel)
                + 1;
            if arrived == arrivals_target(self.degrees[j], header.round) {
                futex::bump_and_wake(self.board.wake_word(j));
            }
        }
        if let Some(bridge) = &self.bridge {
            bridge
                .notify()
                .map_err(|e| transport(i, format!("notifying the bridge failed: {e:?}")))?;
        }
        Ok(())
    }
}

/// Neighbours' payloads of the gathered round, read in place from the received samples.
struct SampleInbox<'a> {
    held: &'a [Held],
}

impl Inbox for SampleInbox<'_> {
    fn len(&self) -> usize {
        self.held.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        self.held[k].payload()
    }
}

impl Exchange for IpcExchange {
    fn degree(&self) -> usize {
        self.subscribers.len()
    }

    fn publish_initial(
        &mut self,
        header: RoundHeader,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<(), ExchangeError> {
        self.send(None, &mut |out| {
            write(out);
            header
        })
    }

    fn gather(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let started = Instant::now();
        self.check_peers(round, Duration::ZERO)?;
        self.missing.clear();
        self.missing.extend(0..self.neighbours.len());
        // Every failure-check slice without the round complete, look at each neighbour once.
        let mut next_look = started + futex::FAILURE_CHECK_SLICE;
        let held = self.policy.wait_until(
            self,
            deadline,
            |s| {
                let look_at_each = Instant::now() >= next_look;
                if look_at_each {
                    next_look += futex::FAILURE_CHECK_SLICE;
                }
                s.all_held(round, look_at_each)
            },
            |s, deadline| {
                // Sleep in slices, looking for failed agents in between; a wake-up since
                // `all_held` read the word ends the sleep at once.
                futex::wait_slice(s.board.wake_word(s.index), s.wake_seen, deadline);
                s.check_peers(round, started.elapsed())
            },
        )?;
        if !held {
            let mut missing: Vec<usize> =
                self.missing.iter().map(|&k| self.neighbours[k]).collect();
            missing.sort_unstable();
            return Err(ExchangeError::Timeout {
                agent: self.index,
                round,
                missing,
                waited: started.elapsed(),
            });
        }
        self.gathered = round;
        Ok(())
    }

    fn neighbour_header(&self, k: usize) -> &RoundHeader {
        &self.held[k].header
    }

    fn neighbour_payload(&self, k: usize) -> &[f64] {
        self.held[k].payload()
    }

    fn compute_and_publish(
        &mut self,
        compute: &mut dyn FnMut(&dyn Inbox, &mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError> {
        let fault = self.fault.filter(|f| f.round == self.gathered);
        if let Some(fault) = fault {
            fault.strike();
        }
        let held = std::mem::take(&mut self.held);
        let result = self.send(fault, &mut |out| compute(&SampleInbox { held: &held }, out));
        self.held = held;
        result
    }

    fn global_barrier(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let i = self.index;
        if !self.global_barrier {
            return Err(transport(i, "this run has no global barrier"));
        }
        let started = Instant::now();
        // The same watch as a round's wait: a failed or stopped team ends the barrier too.
        let (board, watch) = (&self.board, &mut self.watch);
        let released = board.global_barrier(self.policy, deadline, |slept| {
            let waited = if slept {
                started.elapsed()
            } else {
                Duration::ZERO
            };
            watch.check(board, round, waited)
        })?;
        if released {
            Ok(())
        } else {
            Err(ExchangeError::BarrierTimeout {
                agent: i,
                round,
                arrived: self.board.barrier().arrived(),
                expected: self.board.agents(),
                waited: started.elapsed(),
            })
        }
    }
}

/// What an ipc agent watches while it waits: the board's stop request and failure mark, its
/// launcher, and (without a launcher) the run's iceoryx2 nodes for a dead one.
struct PeerWatch {
    index: usize,
    /// The run's iceoryx2 configuration (to scan its nodes for dead ones).
    config: Config,
    last_dead_node_scan: Instant,
    /// [`dead_node_scan_every`] of the team.
    scan_every: Duration,
    /// The launcher's pid, for supervised agents: if this process is orphaned (the
    /// launcher died), it stops.
    launcher: Option<u32>,
}

impl PeerWatch {
    /// Stops this agent if another agent failed: marked on the board (by the launcher or a
    /// peer), or found dead among the run's iceoryx2 nodes (scanned in waits at least
    /// [`PeerWatch::scan_every`] long, at most that often; a dead node's stale resources are
    /// removed on the way).
    fn check(&mut self, board: &Board, round: u64, waited: Duration) -> Result<(), ExchangeError> {
        board.check_team(self.index, round)?;
        // A system call: every 64 rounds and in long waits, not in every round.
        let look_for_launcher = round.is_multiple_of(64) || !waited.is_zero();
        if let Some(launcher) = self.launcher
            && look_for_launcher
            && std::os::unix::process::parent_id() != launcher
        {
            return Err(transport(
                self.index,
                format!("stopped at round {round}: its launcher (pid {launcher}) is gone"),
            ));
        }
        // Under a launcher, `waitpid` finds a dead agent; the scan is for agents started
        // without one, and for a subscriber that vanished (`waited` = `MAX`). (It can also mistake a neighbour that is just finishing — its node's
        // token released before its files are gone — for a dead one.)
        if (self.launcher.is_none() || waited == Duration::MAX)
            && waited >= self.scan_every
            && self.last_dead_node_scan.elapsed() >= self.scan_every
        {
            self.last_dead_node_scan = Instant::now();
            if let Some(agent) = scan_dead_agents(&self.config, self.index, board) {
                return Err(ExchangeError::PeerFailed {
                    agent: self.index,
                    failed: agent,
                    round,
                    how: "died (its iceoryx2 node is dead)".into(),
                });
            }
        }
        Ok(())
    }
}
