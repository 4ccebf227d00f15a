//! One agent process's end of the `shm` transport.
//!
//! Round `k + 1` of agent `i` goes into its slot of parity `(k + 1) % 2`, written in place by
//! the agent's step; then `i` stores `k + 2` into its published-round word (release), counts
//! the message at each neighbour `j` (the board's arrival counter of `j` for the parity of
//! `k + 1`) and, if it was the last of `j`'s round-`k + 1` messages
//! ([`arrivals_target`]), bumps `j`'s wake-up word on the board and, if `j` sleeps,
//! futex-wakes it ([`futex::bump_and_wake`]): one wake-up per waiting agent per round, and no
//! system call at all for an agent that is not asleep. A waiting agent reads its wake-up
//! word, checks its neighbours' published-round words (acquire) and sleeps with
//! [`futex::wait_slice`], in slices of [`futex::FAILURE_CHECK_SLICE`], looking at the board's
//! failure mark and stop request in between (see [`crate::futex`] for the protocol and why
//! no wake-up is lost). The global barrier is the board's counting barrier with its futex
//! word.
//!
//! A neighbour is at most one round ahead (the neighbour barrier), so the slot of parity
//! `k % 2` still holds round `k` while anybody gathers it, and the own slot of parity
//! `(k + 1) % 2` held round `k − 1`, which every neighbour finished reading before it
//! published the round `k` that was gathered.

use crate::board::{Board, Rendezvous, arrivals_target};
use crate::endpoint::ConnectRequest;
use crate::error_text::one_line;
use crate::exchange::header::RoundHeader;
use crate::exchange::{Exchange, ExchangeError};
use crate::fault::Fault;
use crate::futex;
use crate::shm::table::{SlotTable, table_name};
use crate::wait::WaitPolicy;
use admm_ta_agents::agent::Inbox;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// One agent's end of the `shm` transport.
pub struct ShmExchange {
    index: usize,
    neighbours: Vec<usize>,
    /// Arrival targets' degrees, per neighbour (`degrees[k]` is neighbour `k`'s degree).
    neighbour_degrees: Vec<usize>,
    payload_len: usize,
    policy: WaitPolicy,
    table: SlotTable,
    board: Board,
    /// The round last gathered.
    gathered: u64,
    /// Fault injection (tests): misbehave when publishing after gathering its round.
    fault: Option<Fault>,
    /// The launcher's pid, for supervised agents: if it is gone, this agent stops.
    launcher: Option<u32>,
}

fn transport(agent: usize, what: impl Into<String>) -> ExchangeError {
    ExchangeError::Transport {
        agent,
        what: what.into(),
    }
}

/// What a waiter carries between its checks and its sleeps: the wake-up word's value read
/// before the last check, and the first neighbour not yet seen published.
#[derive(Default)]
struct Waiting {
    seen: u32,
    next: usize,
}

impl ShmExchange {
    /// Opens the run's board and slot table, then waits (until `deadline`) for the whole
    /// team to do the same, so that no round deadline starts while an agent is starting.
    pub fn connect(endpoint: &ConnectRequest, deadline: Instant) -> Result<Self, ExchangeError> {
        let i = endpoint.index;
        let agents = endpoint.agents();
        let board = Board::open(&endpoint.run.board_shm, agents)
            .and_then(|board| {
                board.check_shape(endpoint.tasks, endpoint.payload_len)?;
                Ok(board)
            })
            .map_err(|e| transport(i, one_line(&e)))?;
        board.set_registered(i);
        let table = SlotTable::open(
            &table_name(&endpoint.run.prefix),
            agents,
            endpoint.payload_len,
        )
        .map_err(|e| transport(i, one_line(&e)))?;
        board.set_connected(i);
        let started = Instant::now();
        board
            .await_connected(&endpoint.team(), deadline)
            .map_err(|waited| match waited {
                Rendezvous::Stopped(signal) => ExchangeError::Stopped { agent: i, signal },
                Rendezvous::Failed(failed) => ExchangeError::PeerFailed {
                    agent: i,
                    failed,
                    round: 0,
                    how: "failed during start-up".into(),
                },
                Rendezvous::NeverConnected(missing) => transport(
                    i,
                    format!(
                        "the team did not connect within {:.1?}; missing: agent(s) {missing:?} (not started, started too late, or stuck)",
                        started.elapsed()
                    ),
                ),
            })?;
        Ok(Self {
            index: i,
            neighbour_degrees: endpoint
                .neighbours
                .iter()
                .map(|&j| endpoint.degrees[j])
                .collect(),
            neighbours: endpoint.neighbours.clone(),
            payload_len: endpoint.payload_len,
            policy: endpoint.policy,
            table,
            board,
            gathered: 0,
            fault: endpoint.fault,
            launcher: endpoint.supervised.then(std::os::unix::process::parent_id),
        })
    }

    /// Fault injection (tests, [`crate::fault`]).
    pub fn inject(&mut self, fault: Option<Fault>) {
        self.fault = fault;
    }

    /// Marks agent `agent` as the one that failed (unless another was marked first).
    pub fn blame(&self, agent: usize) {
        let _ = self.board.mark_failed(agent);
    }

    /// The agent that published the fewest rounds: after a timeout, the one everybody is
    /// waiting for, directly or through a chain of blocked neighbours.
    pub fn laggard(&self) -> usize {
        self.board.laggard().unwrap_or(self.index)
    }

    /// Stops this agent on a stop request, a failure mark, or (looked at every 64 rounds
    /// and after a whole sleep slice, `slept`) a launcher that is gone or, with no launcher
    /// (an independently started team), a neighbour whose process died.
    fn check_peers(&self, round: u64, slept: bool) -> Result<(), ExchangeError> {
        self.board.check_team(self.index, round)?;
        if self.launcher.is_none()
            && slept
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
        if let Some(launcher) = self.launcher
            && (slept || round.is_multiple_of(64))
            && std::os::unix::process::parent_id() != launcher
        {
            return Err(transport(
                self.index,
                format!("stopped at round {round}: its launcher (pid {launcher}) is gone"),
            ));
        }
        Ok(())
    }

    /// Whether every neighbour published round `round`, from neighbour `waiting.next` on
    /// (publication is monotonic: those before it were seen already).
    fn all_published(&self, round: u64, waiting: &mut Waiting) -> bool {
        while let Some(&j) = self.neighbours.get(waiting.next) {
            if self.table.published(j).load(Ordering::Acquire) <= round {
                return false;
            }
            waiting.next += 1;
        }
        true
    }

    /// Checks the gathered round-`round` messages: round, sender and length.
    fn check_messages(&self, round: u64) -> Result<(), ExchangeError> {
        let parity = (round % 2) as usize;
        for &j in &self.neighbours {
            // SAFETY: `j` published round `round` (acquire in `gather`) and keeps the slot
            // until we publish our next round.
            let (header, len) = unsafe {
                (
                    self.table.header(j, parity),
                    self.table.written_len(j, parity),
                )
            };
            let agent = self.index;
            if header.sender as usize != j {
                return Err(ExchangeError::WrongSender {
                    agent,
                    neighbour: j,
                    got: header.sender,
                });
            }
            if header.round != round {
                return Err(ExchangeError::OutOfOrder {
                    agent,
                    neighbour: j,
                    expected: round,
                    got: header.round,
                });
            }
            if len != self.payload_len as u64 {
                return Err(ExchangeError::WrongLength {
                    agent,
                    neighbour: j,
                    expected: self.payload_len,
                    got: len as usize,
                });
            }
        }
        Ok(())
    }

    /// Publishes the own round-`round` slot (its payload already written) with `header`
    /// and `len` values, and wakes the neighbours whose round it completes.
    fn publish(&self, round: u64, header: RoundHeader, len: u64) {
        let (i, parity) = (self.index, (round % 2) as usize);
        // SAFETY: our own slot, which no neighbour reads before the release store below.
        unsafe { self.table.write_head(i, parity, header, len) };
        self.table.published(i).store(round + 1, Ordering::Release);
        self.board.set_published_round(i, round);
        for (&j, &degree) in self.neighbours.iter().zip(&self.neighbour_degrees) {
            let arrived = self.board.arrivals(j, round).fetch_add(1, Ordering::AcqRel) + 1;
            if arrived == arrivals_target(degree, round) {
                futex::bump_and_wake(self.board.wake_word(j));
            }
        }
    }
}

/// Neighbours' payloads of the gathered round, read in place from their slots.
struct SlotInbox<'a> {
    table: &'a SlotTable,
    neighbours: &'a [usize],
    parity: usize,
}

impl Inbox for SlotInbox<'_> {
    fn len(&self) -> usize {
        self.neighbours.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        // SAFETY: the neighbour published this round and does not rewrite the slot before
        // we publish our next one.
        unsafe { self.table.payload(self.neighbours[k], self.parity) }
    }
}

impl Exchange for ShmExchange {
    fn degree(&self) -> usize {
        self.neighbours.len()
    }

    fn publish_initial(
        &mut self,
        header: RoundHeader,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<(), ExchangeError> {
        // SAFETY: nobody reads slot 0 before it is published.
        write(unsafe { self.table.own_payload(self.index, 0) });
        self.publish(0, header, self.payload_len as u64);
        Ok(())
    }

    fn gather(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let started = Instant::now();
        self.check_peers(round, false)?;
        let word = self.board.wake_word(self.index);
        let mut waiting = Waiting::default();
        let held = self.policy.wait_until(
            &mut waiting,
            deadline,
            |waiting| {
                // The word before the check: a wake-up after it changes the word.
                waiting.seen = word.load(Ordering::Acquire);
                Ok(self.all_published(round, waiting))
            },
            |waiting, deadline| {
                let slept = futex::wait_slice(word, waiting.seen, deadline);
                self.check_peers(round, slept)
            },
        )?;
        if !held {
            return Err(ExchangeError::Timeout {
                agent: self.index,
                round,
                missing: self
                    .neighbours
                    .iter()
                    .copied()
                    .filter(|&j| self.table.published(j).load(Ordering::Acquire) <= round)
                    .collect(),
                waited: started.elapsed(),
            });
        }
        self.check_messages(round)?;
        self.gathered = round;
        Ok(())
    }

    fn neighbour_header(&self, k: usize) -> &RoundHeader {
        // SAFETY: as in `check_messages`, for the gathered round.
        unsafe {
            self.table
                .header(self.neighbours[k], (self.gathered % 2) as usize)
        }
    }

    fn neighbour_payload(&self, k: usize) -> &[f64] {
        // SAFETY: as in `check_messages`, for the gathered round.
        unsafe {
            self.table
                .payload(self.neighbours[k], (self.gathered % 2) as usize)
        }
    }

    fn compute_and_publish(
        &mut self,
        compute: &mut dyn FnMut(&dyn Inbox, &mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError> {
        let fault = self.fault.filter(|f| f.round == self.gathered);
        if let Some(fault) = fault {
            fault.strike();
        }
        let next = self.gathered + 1;
        let inbox = SlotInbox {
            table: &self.table,
            neighbours: &self.neighbours,
            parity: (self.gathered % 2) as usize,
        };
        // SAFETY: our slot of the next parity held round `next − 2`, which every neighbour
        // finished reading before it published the round `next − 1` we gathered.
        let out = unsafe { self.table.own_payload(self.index, (next % 2) as usize) };
        let mut header = compute(&inbox, out);
        let mut len = self.payload_len;
        if let Some(fault) = fault {
            // Fault injection only: corrupt in place, or claim a shorter payload.
            fault.corrupt(out, &mut header);
            len = fault.payload_len(len);
        }
        self.publish(next, header, len as u64);
        Ok(())
    }

    fn global_barrier(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let started = Instant::now();
        let released = self.board.global_barrier(self.policy, deadline, |slept| {
            self.check_peers(round, slept)
        })?;
        if released {
            Ok(())
        } else {
            Err(ExchangeError::BarrierTimeout {
                agent: self.index,
                round,
                arrived: self.board.barrier().arrived(),
                expected: self.board.agents(),
                waited: started.elapsed(),
            })
        }
    }
}
