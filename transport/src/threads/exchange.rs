//! One agent's end of the `threads` transport: its slots, its neighbours' slots read in
//! place, its wake-ups.

use crate::board::arrivals_target;
use crate::exchange::header::RoundHeader;
use crate::exchange::{Exchange, ExchangeError};
use crate::wait::{Arrival, CountingBarrier, WaitPolicy};
use admm_ta_agents::agent::Inbox;
use admm_ta_topologies::Graph;
use crossbeam::sync::{Parker, Unparker};
use crossbeam::utils::CachePadded;
use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// The longest a waiting agent thread sleeps before it looks for a termination signal again.
const SIGNAL_SLICE: Duration = Duration::from_millis(20);

struct Slot {
    header: UnsafeCell<RoundHeader>,
    payload: UnsafeCell<Box<[f64]>>,
}

struct AgentSlots {
    /// Rounds published: the latest round + 1 (0: nothing yet).
    published: CachePadded<AtomicU64>,
    /// Neighbour messages counted for rounds of each parity, cumulative; the last arrival of
    /// a round wakes the agent (one wake-up per round instead of one per neighbour; see
    /// [`crate::ipc::exchange`] for why this never loses a wake-up).
    arrivals: CachePadded<[AtomicU64; 2]>,
    slots: [Slot; 2],
}

/// Memory shared by the threads of one run.
pub(super) struct Fabric {
    agents: Vec<AgentSlots>,
    neighbours: Vec<Vec<usize>>,
    unparkers: Vec<Unparker>,
    barrier: CachePadded<CountingBarrier>,
    /// Set when an agent fails, so the others stop waiting at once.
    aborted: AtomicBool,
}

// SAFETY: slots are written only by their owner, for a round no neighbour reads any more,
// and read only after the owner's release-store of `published` (see the module docs).
unsafe impl Sync for Fabric {}

impl Fabric {
    /// The slots of a team on `graph` with payloads of `len` values; `unparkers[i]` wakes
    /// agent `i`.
    pub(super) fn new(graph: &Graph, len: usize, unparkers: Vec<Unparker>) -> Self {
        let n = graph.robots();
        Fabric {
            agents: (0..n)
                .map(|_| AgentSlots {
                    published: CachePadded::new(AtomicU64::new(0)),
                    arrivals: CachePadded::new([AtomicU64::new(0), AtomicU64::new(0)]),
                    slots: [(); 2].map(|_| Slot {
                        header: UnsafeCell::new(RoundHeader::default()),
                        payload: UnsafeCell::new(vec![0.0; len].into_boxed_slice()),
                    }),
                })
                .collect(),
            neighbours: (0..n).map(|i| graph.neighbours(i).to_vec()).collect(),
            unparkers,
            barrier: CachePadded::new(CountingBarrier::default()),
            aborted: AtomicBool::new(false),
        }
    }

    /// An agent failed: the others stop waiting at once.
    pub(super) fn abort(&self) {
        self.aborted.store(true, Ordering::Release);
        self.wake_all();
    }

    fn wake_all(&self) {
        self.unparkers.iter().for_each(Unparker::unpark);
    }
}

/// One agent's end of the `threads` transport.
pub struct ThreadExchange<'f> {
    fabric: &'f Fabric,
    index: usize,
    parker: Parker,
    policy: WaitPolicy,
    gathered: u64,
}

/// Neighbours' payloads of the gathered round, read in place from their slots.
struct SlotInbox<'a> {
    fabric: &'a Fabric,
    neighbours: &'a [usize],
    parity: usize,
}

impl Inbox for SlotInbox<'_> {
    fn len(&self) -> usize {
        self.neighbours.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        let slot = &self.fabric.agents[self.neighbours[k]].slots[self.parity];
        // SAFETY: the neighbour published this round (acquire in `gather`) and will not
        // rewrite this slot before we publish our next round.
        unsafe { &*slot.payload.get() }
    }
}

impl<'f> ThreadExchange<'f> {
    /// Agent `index`'s end of `fabric`, asleep on `parker` when it waits.
    pub(super) fn new(
        fabric: &'f Fabric,
        index: usize,
        parker: Parker,
        policy: WaitPolicy,
    ) -> Self {
        ThreadExchange {
            fabric,
            index,
            parker,
            policy,
            gathered: 0,
        }
    }
}

impl ThreadExchange<'_> {
    fn missing(&self, round: u64) -> Vec<usize> {
        self.fabric.neighbours[self.index]
            .iter()
            .copied()
            .filter(|&j| self.fabric.agents[j].published.load(Ordering::Acquire) <= round)
            .collect()
    }

    fn check_abort(&self) -> Result<(), ExchangeError> {
        if self.fabric.aborted.load(Ordering::Acquire) {
            return Err(ExchangeError::Aborted { agent: self.index });
        }
        if let Some(signal) = crate::signals::stop_requested() {
            return Err(ExchangeError::Stopped {
                agent: self.index,
                signal,
            });
        }
        Ok(())
    }

    /// Spins within the policy, then parks until `ready`, an abort or the deadline.
    fn wait_until(
        &self,
        deadline: Instant,
        ready: impl Fn() -> bool,
    ) -> Result<bool, ExchangeError> {
        self.policy.wait_until(
            &mut (),
            deadline,
            |()| {
                if ready() {
                    return Ok(true);
                }
                self.check_abort().map(|()| false)
            },
            |(), deadline| {
                // In slices, so that a termination signal stops a waiting team promptly.
                self.parker
                    .park_deadline(deadline.min(Instant::now() + SIGNAL_SLICE));
                Ok(())
            },
        )
    }
}

impl Exchange for ThreadExchange<'_> {
    fn degree(&self) -> usize {
        self.fabric.neighbours[self.index].len()
    }

    fn publish_initial(
        &mut self,
        header: RoundHeader,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<(), ExchangeError> {
        let own = &self.fabric.agents[self.index];
        // SAFETY: nobody reads slot 0 before the release-store below.
        unsafe {
            write(&mut *own.slots[0].payload.get());
            *own.slots[0].header.get() = header;
        }
        own.published.store(1, Ordering::Release);
        self.announce(0);
        Ok(())
    }

    fn gather(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let started = Instant::now();
        let fabric = self.fabric;
        let neighbours = &fabric.neighbours[self.index];
        let ready = || {
            neighbours
                .iter()
                .all(|&j| fabric.agents[j].published.load(Ordering::Acquire) > round)
        };
        if !self.wait_until(deadline, ready)? {
            return Err(ExchangeError::Timeout {
                agent: self.index,
                round,
                missing: self.missing(round),
                waited: started.elapsed(),
            });
        }
        self.gathered = round;
        for &j in neighbours {
            let header = self.fabric_header(j, round);
            if header.round != round {
                return Err(ExchangeError::OutOfOrder {
                    agent: self.index,
                    neighbour: j,
                    expected: round,
                    got: header.round,
                });
            }
        }
        Ok(())
    }

    fn neighbour_header(&self, k: usize) -> &RoundHeader {
        self.fabric_header(self.fabric.neighbours[self.index][k], self.gathered)
    }

    fn neighbour_payload(&self, k: usize) -> &[f64] {
        let j = self.fabric.neighbours[self.index][k];
        let slot = &self.fabric.agents[j].slots[(self.gathered % 2) as usize];
        // SAFETY: the neighbour published this slot (release) before we gathered it
        // (acquire), and does not overwrite it before we publish our next round.
        unsafe { &*slot.payload.get() }
    }

    fn compute_and_publish(
        &mut self,
        compute: &mut dyn FnMut(&dyn Inbox, &mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError> {
        let next = self.gathered + 1;
        let own = &self.fabric.agents[self.index];
        let slot = &own.slots[(next % 2) as usize];
        let inbox = SlotInbox {
            fabric: self.fabric,
            neighbours: &self.fabric.neighbours[self.index],
            parity: (self.gathered % 2) as usize,
        };
        // SAFETY: this slot held round `next − 2`, which every neighbour finished reading
        // before publishing the round `next − 1` we gathered.
        let header = compute(&inbox, unsafe { &mut *slot.payload.get() });
        unsafe { *slot.header.get() = header };
        own.published.store(next + 1, Ordering::Release);
        self.announce(next);
        Ok(())
    }

    fn global_barrier(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let started = Instant::now();
        let parties = self.fabric.agents.len();
        let barrier = &self.fabric.barrier;
        match barrier.arrive(parties) {
            Arrival::Released => {
                self.fabric.wake_all();
                Ok(())
            }
            Arrival::Wait(ticket) => {
                if self.wait_until(deadline, || barrier.released(ticket))? {
                    Ok(())
                } else {
                    Err(ExchangeError::BarrierTimeout {
                        agent: self.index,
                        round,
                        arrived: barrier.arrived(),
                        expected: parties,
                        waited: started.elapsed(),
                    })
                }
            }
        }
    }
}

impl ThreadExchange<'_> {
    /// Counts our round-`round` message at each neighbour and wakes those for which it was
    /// the last one missing.
    fn announce(&self, round: u64) {
        for &j in &self.fabric.neighbours[self.index] {
            let counter = &self.fabric.agents[j].arrivals[(round % 2) as usize];
            let arrived = counter.fetch_add(1, Ordering::AcqRel) + 1;
            if arrived == arrivals_target(self.fabric.neighbours[j].len(), round) {
                self.fabric.unparkers[j].unpark();
            }
        }
    }

    fn fabric_header(&self, j: usize, round: u64) -> &RoundHeader {
        // SAFETY: as for the payloads in `SlotInbox`.
        unsafe {
            &*self.fabric.agents[j].slots[(round % 2) as usize]
                .header
                .get()
        }
    }
}
