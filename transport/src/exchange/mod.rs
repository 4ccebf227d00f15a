//! The `Exchange` abstraction: how one agent publishes its round payload and gathers its
//! neighbours', and the per-agent round loop every distributed transport shares
//! ([`round_loop`]).
//!
//! A round `k` of agent `i` is:
//! 1. **gather** (neighbour barrier): block until the round-`k` messages of all neighbours
//!    are held, spinning briefly and then sleeping on the transport's wake-up mechanism,
//!    with a deadline;
//! 2. run the decentralized stop protocol on the headers (every agent reaches the same
//!    verdict at the same round, so nobody waits for a neighbour that stopped);
//! 3. **compute and publish**: the agent's `step` reads the neighbours' payloads in place
//!    and writes its round-`k+1` payload straight into the transport's outgoing buffer
//!    (a loaned shared-memory sample for iceoryx2), which is then published;
//! 4. optionally a **global barrier** (all agents reached round `k+1`), for lockstep
//!    latency benchmarks.
//!
//! Why this is safe with two buffers per agent: an agent publishes round `k+1` only after
//! holding all neighbours' round `k`, so a neighbour is never more than one round ahead and
//! the message of round `k−1` is no longer read by anybody when round `k+1` replaces it.

pub mod codec;
pub mod header;
pub mod round_loop;

use crate::exchange::header::RoundHeader;
use admm_ta_agents::agent::Inbox;
use std::time::{Duration, Instant};

/// Failures of an exchange operation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExchangeError {
    #[error(
        "agent {agent}: no round-{round} message from neighbour(s) {missing:?} within {waited:?}"
    )]
    Timeout {
        agent: usize,
        round: u64,
        missing: Vec<usize>,
        waited: Duration,
    },
    #[error(
        "agent {agent}: global barrier of round {round} timed out after {waited:?} ({arrived} of {expected} agents arrived)"
    )]
    BarrierTimeout {
        agent: usize,
        round: u64,
        arrived: usize,
        expected: usize,
        waited: Duration,
    },
    #[error("agent {agent}: expected round {expected} from neighbour {neighbour}, got round {got}")]
    OutOfOrder {
        agent: usize,
        neighbour: usize,
        expected: u64,
        got: u64,
    },
    #[error(
        "agent {agent}: neighbour {neighbour} sent a payload of {got} values, expected {expected}"
    )]
    WrongLength {
        agent: usize,
        neighbour: usize,
        expected: usize,
        got: usize,
    },
    #[error(
        "agent {agent}: the message on neighbour {neighbour}'s service claims to come from agent {got}"
    )]
    WrongSender {
        agent: usize,
        neighbour: usize,
        got: u32,
    },
    /// The transport itself failed (a service, a port, a socket, a session). `what` is the
    /// cause as one line with its sources ([`crate::error_text::one_line`]): an exchange
    /// error crosses threads and is compared (`Clone + PartialEq`), which the io and Zenoh
    /// errors behind it are not, and iceoryx2 has a distinct error type per call.
    #[error("agent {agent}: {what}")]
    Transport { agent: usize, what: String },
    /// Another agent of the run failed first.
    #[error("agent {agent}: stopped because another agent failed")]
    Aborted { agent: usize },
    /// A neighbour's message failed the method's payload check (NaN, out-of-range value).
    #[error("agent {agent}: rejected the round-{round} message of neighbour {neighbour}: {what}")]
    BadPayload {
        agent: usize,
        neighbour: usize,
        round: u64,
        what: admm_ta_agents::agent::PayloadError,
    },
    /// A neighbour's coded message did not decode ([`codec`]): refused, never used.
    #[error(
        "agent {agent}: the round-{round} message of neighbour {neighbour} did not decode: {what}"
    )]
    Undecodable {
        agent: usize,
        neighbour: usize,
        round: u64,
        what: codec::CodecError,
    },
    /// The team was asked to stop by a termination signal (to this process, to the launcher
    /// or host, or to another agent of the team): nobody failed.
    #[error("agent {agent}: stopped by {}", crate::signals::name(*signal))]
    Stopped { agent: usize, signal: i32 },
    /// Another agent of the run died (its process is gone); this one stopped cleanly.
    #[error("agent {agent}: stopped at round {round} because agent {failed} {how}")]
    PeerFailed {
        agent: usize,
        failed: usize,
        round: u64,
        how: String,
    },
    /// The running team (its first host, on Zenoh) has another team digest than this
    /// agent's team file: refused before round 0. The digest is in hex.
    #[error("agent {agent}'s team file differs from the running team's (digest {running})")]
    OtherTeam { agent: usize, running: String },
}

impl ExchangeError {
    /// The agent that raised the error.
    pub fn agent(&self) -> usize {
        match self {
            Self::Timeout { agent, .. }
            | Self::BarrierTimeout { agent, .. }
            | Self::OutOfOrder { agent, .. }
            | Self::WrongLength { agent, .. }
            | Self::WrongSender { agent, .. }
            | Self::Transport { agent, .. }
            | Self::Aborted { agent }
            | Self::Stopped { agent, .. }
            | Self::BadPayload { agent, .. }
            | Self::Undecodable { agent, .. }
            | Self::PeerFailed { agent, .. }
            | Self::OtherTeam { agent, .. } => *agent,
        }
    }
}

/// The error that ended a run: the first that is not a consequence of another.
pub fn root_cause(errors: impl IntoIterator<Item = ExchangeError>) -> Option<ExchangeError> {
    let mut fallback = None;
    for e in errors {
        if matches!(
            e,
            ExchangeError::Aborted { .. }
                | ExchangeError::PeerFailed { .. }
                | ExchangeError::Stopped { .. }
        ) {
            fallback.get_or_insert(e);
        } else {
            return Some(e);
        }
    }
    fallback
}

/// One agent's end of a transport.
pub trait Exchange {
    /// Number of neighbours.
    fn degree(&self) -> usize;
    /// Publishes the round-0 message; `write` fills the payload in place.
    fn publish_initial(
        &mut self,
        header: RoundHeader,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<(), ExchangeError>;
    /// Neighbour barrier: returns once the round-`round` messages of all neighbours are held.
    fn gather(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError>;
    /// Header of the `k`-th neighbour's gathered message.
    fn neighbour_header(&self, k: usize) -> &RoundHeader;
    /// Payload of the `k`-th neighbour's gathered message.
    fn neighbour_payload(&self, k: usize) -> &[f64];
    /// Runs `compute` on the gathered payloads and an outgoing buffer, then publishes that
    /// buffer with the header `compute` returns.
    fn compute_and_publish(
        &mut self,
        compute: &mut dyn FnMut(&dyn Inbox, &mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError>;
    /// Global barrier: returns once every agent of the team has called it for `round`.
    fn global_barrier(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError>;
    /// Bytes of round messages this end put on its transport so far, resends included, where
    /// the transport counts them (Zenoh, whose messages may be coded, [`codec`]); `None`
    /// where every message is one payload of the run's size a round.
    fn sent_bytes(&self) -> Option<u64> {
        None
    }
}
