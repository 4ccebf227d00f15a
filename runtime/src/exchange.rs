//! The `Exchange` abstraction: how one agent publishes its round payload and gathers its
//! neighbours', and the per-agent round loop every distributed transport shares.
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

use crate::header::RoundHeader;
use crate::latency::{Component, LatencyBuckets, RoundLatency};
use crate::usage::ThreadUsage;
use admm_ta_agents::agent::{ConsensusAgent, Inbox};
use admm_ta_agents::local_stop::{LocalCertifiedStop, Verdict};
use serde::{Deserialize, Serialize};
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
        what: String,
    },
    /// Another agent of the run died (its process is gone); this one stopped cleanly.
    #[error("agent {agent}: stopped at round {round} because agent {failed} {how}")]
    PeerFailed {
        agent: usize,
        failed: usize,
        round: u64,
        how: String,
    },
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
            | Self::BadPayload { agent, .. }
            | Self::PeerFailed { agent, .. } => *agent,
        }
    }
}

/// The error that ended a run: the first that is not a consequence of another.
pub fn root_cause(errors: impl IntoIterator<Item = ExchangeError>) -> Option<ExchangeError> {
    let mut fallback = None;
    for e in errors {
        if matches!(
            e,
            ExchangeError::Aborted { .. } | ExchangeError::PeerFailed { .. }
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
}

/// When an agent stops.
#[derive(Debug, Clone)]
pub enum AgentStop {
    /// The decentralized certified stop (or the round limit).
    Local(LocalCertifiedStop),
    /// Always the round limit.
    MaxIters,
}

/// What one agent's loop needs besides its algorithm and its exchange.
#[derive(Debug, Clone)]
pub struct AgentPlan {
    pub index: usize,
    pub max_rounds: u64,
    pub stop: AgentStop,
    /// Deadline of every wait (neighbour messages, global barrier).
    pub round_timeout: Duration,
    pub global_barrier: bool,
    /// Rounds run before latency and resource usage are recorded (benchmarks).
    pub warmup_rounds: u64,
}

/// What one agent reports at the end of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AgentOutcome {
    pub index: usize,
    /// The robot's task: the certified one, or its own rounding at the round limit.
    pub task: usize,
    /// Rounds computed.
    pub rounds: u64,
    /// The stop protocol certified an assignment (as opposed to the round limit).
    pub converged: bool,
    /// The round whose assignment was certified.
    pub certified_round: Option<u64>,
    /// Hash of the bits of the last payload the agent published (to compare transports).
    pub iterate_digest: u64,
    pub projection_steps: u64,
    pub latency: LatencyBuckets,
    /// CPU time and context switches of the agent's thread over the recorded rounds.
    #[serde(default)]
    pub usage: ThreadUsage,
}

/// FNV-1a over the bits of a payload.
pub fn payload_digest(payload: &[f64]) -> u64 {
    payload.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
        (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Runs one agent to the end of the run over `exchange`.
pub fn run_agent<A: ConsensusAgent + ?Sized>(
    agent: &mut A,
    exchange: &mut dyn Exchange,
    plan: &AgentPlan,
) -> Result<AgentOutcome, ExchangeError> {
    let mut rounds = RoundLoop::start(agent, exchange, plan)?;
    let (task, certified_round) = rounds.run(agent, exchange, plan, plan.stop.clone())?;
    Ok(rounds.outcome(plan.index, task, certified_round))
}

/// One agent's round loop, resumable: after a stop, the team may go on with the next
/// episode (new costs, a fresh stop rule) from the round it stopped at, every agent at the
/// same round, without publishing anything in between.
pub struct RoundLoop {
    latency: RoundLatency,
    mine: RoundHeader,
    iterate_digest: u64,
    projection_steps: u64,
    usage_from: ThreadUsage,
    /// The round last gathered (the next to compute from).
    round: u64,
    /// A stop ended the last [`RoundLoop::run`]: the next one computes from the gathered
    /// round at once.
    stopped: bool,
}

impl RoundLoop {
    /// Publishes the agent's round-0 message.
    pub fn start<A: ConsensusAgent + ?Sized>(
        agent: &mut A,
        exchange: &mut dyn Exchange,
        plan: &AgentPlan,
    ) -> Result<Self, ExchangeError> {
        let mine = RoundHeader::initial(plan.index);
        let mut iterate_digest = 0;
        exchange.publish_initial(mine, &mut |out| {
            agent.write_initial_payload(out);
            iterate_digest = payload_digest(out);
        })?;
        Ok(Self {
            latency: RoundLatency::new(),
            mine,
            iterate_digest,
            projection_steps: 0,
            usage_from: ThreadUsage::now(),
            round: 0,
            stopped: false,
        })
    }

    /// The round last gathered.
    pub fn round(&self) -> u64 {
        self.round
    }

    /// Runs rounds until `stop` certifies or `plan.max_rounds` rounds of this run have passed;
    /// returns the agent's task and the certified round (`None` at the round limit).
    pub fn run<A: ConsensusAgent + ?Sized>(
        &mut self,
        agent: &mut A,
        exchange: &mut dyn Exchange,
        plan: &AgentPlan,
        mut stop: AgentStop,
    ) -> Result<(usize, Option<u64>), ExchangeError> {
        let degree = exchange.degree();
        let first = self.round;
        // After a stop the neighbours' gathered messages are still held: compute from them.
        let mut resume = std::mem::take(&mut self.stopped);
        loop {
            let round = self.round;
            if round == plan.warmup_rounds && round > 0 {
                self.usage_from = ThreadUsage::now();
            }
            let started = Instant::now();
            if !resume {
                exchange.gather(round, started + plan.round_timeout)?;
            }
            let gathered = Instant::now();
            if !resume {
                for k in 0..degree {
                    if let Err(what) = agent.check_payload(exchange.neighbour_payload(k)) {
                        return Err(ExchangeError::BadPayload {
                            agent: plan.index,
                            neighbour: exchange.neighbour_header(k).sender as usize,
                            round,
                            what,
                        });
                    }
                }
                let verdict = match &mut stop {
                    AgentStop::Local(rule) => {
                        let ex = &*exchange;
                        rule.observe(
                            round,
                            self.mine.stop_state(),
                            (0..degree).map(|k| ex.neighbour_header(k).stop_state()),
                            agent.rounded_task(),
                            || agent.certificate_slack(),
                        )
                    }
                    AgentStop::MaxIters => Verdict::Continue,
                };
                let finished = match verdict {
                    Verdict::Certified {
                        certified_round,
                        task,
                    } => Some((task, Some(certified_round))),
                    Verdict::Continue if round - first >= plan.max_rounds => {
                        Some((agent.decide(), None))
                    }
                    Verdict::Continue => None,
                };
                if let Some(finished) = finished {
                    self.stopped = true;
                    return Ok(finished);
                }
            }
            resume = false;
            let next_window = match &stop {
                AgentStop::Local(rule) => rule.next_window(),
                AgentStop::MaxIters => Default::default(),
            };
            let mut computed = gathered;
            let (mut digest, mut steps, mut mine) = (0, 0, self.mine);
            exchange.compute_and_publish(&mut |inbox, out| {
                let report = agent.step(inbox, out);
                steps = report.inner_iterations as u64;
                digest = payload_digest(out);
                mine = RoundHeader {
                    round: round + 1,
                    sender: plan.index as u32,
                    flags: 0,
                    digest: report.assignment_digest,
                    window: next_window,
                };
                computed = Instant::now();
                mine
            })?;
            self.mine = mine;
            self.iterate_digest = digest;
            self.projection_steps += steps;
            let published = Instant::now();
            if plan.global_barrier {
                exchange.global_barrier(round + 1, published + plan.round_timeout)?;
            }
            let done = Instant::now();
            if round >= plan.warmup_rounds {
                let latency = &mut self.latency;
                latency.record(Component::Wait, gathered - started);
                latency.record(Component::Compute, computed - gathered);
                latency.record(Component::Publish, published - computed);
                if plan.global_barrier {
                    latency.record(Component::Barrier, done - published);
                }
                latency.record(Component::Round, done - started);
                latency.record(
                    Component::Overhead,
                    (done - started) - (computed - gathered),
                );
            }
            self.round += 1;
        }
    }

    /// The agent's report after its last run.
    pub fn outcome(&self, index: usize, task: usize, certified_round: Option<u64>) -> AgentOutcome {
        AgentOutcome {
            index,
            task,
            rounds: self.round,
            converged: certified_round.is_some(),
            certified_round,
            iterate_digest: self.iterate_digest,
            projection_steps: self.projection_steps,
            latency: self.latency.to_buckets(),
            usage: ThreadUsage::now().since(&self.usage_from),
        }
    }
}
