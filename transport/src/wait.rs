//! Waiting without starving the machine: spin briefly, then sleep with a deadline.
//!
//! On a 2-core machine a team of 50 agents outnumbers the cores 25 to 1: an agent that spins
//! while waiting steals the core its neighbour needs to produce the message it waits for.
//! So agents spin only when there are at least as many cores as agents, and only briefly;
//! otherwise they go to sleep on the transport's wake-up mechanism at once.

use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// How a waiting agent passes the time: the choice a latency benchmark sweeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WaitStrategy {
    /// Spin-then-block when every agent can have a core of its own, else block at once
    /// (the default of every run).
    #[default]
    Auto,
    /// Sleep on the transport's wake-up mechanism at once.
    Block,
    /// Spin for [`SPIN_BEFORE_BLOCKING`], then sleep.
    SpinThenBlock,
    /// Never sleep: poll until the deadline, yielding the core between polls so that a team
    /// larger than the machine still makes progress (a pure busy loop would hold the core for
    /// a whole scheduler time slice while the message it waits for cannot be produced).
    Spin,
}

impl WaitStrategy {
    pub const ALL: [WaitStrategy; 4] = [Self::Auto, Self::Block, Self::SpinThenBlock, Self::Spin];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Block => "block",
            Self::SpinThenBlock => "spin-then-block",
            Self::Spin => "spin",
        }
    }
}

#[cfg(feature = "clap")]
admm_ta_agents::clap_value_enum!(WaitStrategy);

/// How long [`WaitStrategy::SpinThenBlock`] spins.
pub const SPIN_BEFORE_BLOCKING: Duration = Duration::from_micros(20);

/// How long a waiter spins before it sleeps, and whether it yields while spinning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WaitPolicy {
    pub spin: Duration,
    /// Yield the core between polls (the [`WaitStrategy::Spin`] strategy).
    pub yield_between_polls: bool,
}

impl WaitPolicy {
    /// The policy of `strategy` for a team of `agents` on this machine.
    pub fn new(strategy: WaitStrategy, agents: usize) -> Self {
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        let (spin, yield_between_polls) = match strategy {
            WaitStrategy::Auto if agents <= cores => (SPIN_BEFORE_BLOCKING, false),
            WaitStrategy::Auto | WaitStrategy::Block => (Duration::ZERO, false),
            WaitStrategy::SpinThenBlock => (SPIN_BEFORE_BLOCKING, false),
            WaitStrategy::Spin => (Duration::MAX, true),
        };
        Self {
            spin,
            yield_between_polls,
        }
    }
}

impl WaitPolicy {
    /// Polls `ready` until it holds: spinning within the policy, then sleeping with
    /// `sleep(deadline)`, which must return early when woken. `Ok(false)` at the deadline.
    /// Both closures get `state`, so a `ready` that needs it mutably can share it with `sleep`.
    pub fn wait_until<S: ?Sized, E>(
        self,
        state: &mut S,
        deadline: Instant,
        mut ready: impl FnMut(&mut S) -> Result<bool, E>,
        mut sleep: impl FnMut(&mut S, Instant) -> Result<(), E>,
    ) -> Result<bool, E> {
        let now = Instant::now();
        let spin_until = now.checked_add(self.spin).unwrap_or(deadline);
        loop {
            if ready(state)? {
                return Ok(true);
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(false);
            }
            if now < spin_until {
                if self.yield_between_polls {
                    std::thread::yield_now();
                } else {
                    std::hint::spin_loop();
                }
            } else {
                sleep(state, deadline)?;
            }
        }
    }
}

/// A sense-reversing counting barrier over two atomics; `#[repr(C)]` so that it can live in
/// shared memory between processes. Waking the sleepers is the caller's business.
#[repr(C)]
#[derive(Debug, Default)]
pub struct CountingBarrier {
    arrived: AtomicUsize,
    generation: AtomicU64,
}

/// What [`CountingBarrier::arrive`] tells its caller.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arrival {
    /// This caller arrived last and released everybody: wake the sleepers.
    Released,
    /// Wait until [`CountingBarrier::released`] says so for this ticket.
    Wait(u64),
}

impl CountingBarrier {
    /// Arrives at the barrier of a team of `parties`.
    pub fn arrive(&self, parties: usize) -> Arrival {
        // Read the generation before arriving: it cannot change until we have arrived.
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == parties {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
            Arrival::Released
        } else {
            Arrival::Wait(generation)
        }
    }

    /// Whether the barrier the ticket belongs to has released.
    pub fn released(&self, ticket: u64) -> bool {
        self.generation.load(Ordering::Acquire) != ticket
    }

    /// Agents arrived at the current barrier (for error messages).
    pub fn arrived(&self) -> usize {
        self.arrived.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_arrival_releases_the_others() {
        let barrier = CountingBarrier::default();
        let a = barrier.arrive(3);
        let b = barrier.arrive(3);
        let (Arrival::Wait(ta), Arrival::Wait(tb)) = (a, b) else {
            panic!("early release");
        };
        assert!(!barrier.released(ta));
        assert_eq!(barrier.arrived(), 2);
        assert_eq!(barrier.arrive(3), Arrival::Released);
        assert!(barrier.released(ta) && barrier.released(tb));
        // The next barrier starts from zero.
        assert!(matches!(barrier.arrive(3), Arrival::Wait(_)));
    }
}
