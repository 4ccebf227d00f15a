//! One agent's round loop over any [`Exchange`]: gather, stop protocol, compute and
//! publish, optional global barrier, each part timed (see [`crate::exchange`] for the round
//! and why two buffers per agent suffice).

use crate::exchange::header::RoundHeader;
use crate::exchange::{Exchange, ExchangeError};
use crate::latency::{BucketsMismatch, Component, LatencyBuckets, RoundLatency};
use crate::timeline::{RoundStamp, TimelineRecorder};
use crate::usage::ThreadUsage;
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::local_stop::{LocalCertifiedStop, Verdict};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

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
    /// Stamp every round into a timeline ([`crate::timeline`]).
    pub timeline: bool,
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
    /// Every round's stamps, when the plan asked for a timeline.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub timeline: Vec<RoundStamp>,
}

/// An agent's outcome whose latency histograms do not merge with the others'.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("agent {agent} exited without a readable result")]
pub struct UnreadableOutcome {
    pub agent: usize,
    #[source]
    pub source: BucketsMismatch,
}

/// The team's round latency (every agent's recorded rounds merged) and CPU usage (summed).
pub fn merge_outcomes<'a>(
    outcomes: impl IntoIterator<Item = &'a AgentOutcome>,
) -> Result<(RoundLatency, ThreadUsage), UnreadableOutcome> {
    let mut latency = RoundLatency::new();
    let mut usage = ThreadUsage::default();
    for outcome in outcomes {
        latency
            .merge(&outcome.latency)
            .map_err(|source| UnreadableOutcome {
                agent: outcome.index,
                source,
            })?;
        usage = usage.plus(&outcome.usage);
    }
    Ok((latency, usage))
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
    let mut rounds = RoundLoop::start(agent, exchange, plan, 1)?;
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
    /// The rounds' stamps, when the plan asks for a timeline (sized before round 0).
    timeline: Option<TimelineRecorder>,
}

impl RoundLoop {
    /// Publishes the agent's round-0 message. `runs` is how many runs (episodes) of up to
    /// `plan.max_rounds` rounds will follow: a timeline is sized for all of them (up to
    /// [`crate::timeline::MAX_RECORDED_ROUNDS`]).
    pub fn start<A: ConsensusAgent + ?Sized>(
        agent: &mut A,
        exchange: &mut dyn Exchange,
        plan: &AgentPlan,
        runs: u64,
    ) -> Result<Self, ExchangeError> {
        Self::start_with(exchange, plan, runs, &mut |out| {
            agent.write_initial_payload(out)
        })
    }

    /// [`RoundLoop::start`] with a round-0 message that `write` fills: a standing team's
    /// first agreement round ([`RoundLoop::side_round`] gathers it).
    pub fn start_with(
        exchange: &mut dyn Exchange,
        plan: &AgentPlan,
        runs: u64,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<Self, ExchangeError> {
        let mine = RoundHeader::initial(plan.index);
        let mut iterate_digest = 0;
        exchange.publish_initial(mine, &mut |out| {
            write(out);
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
            timeline: plan.timeline.then(|| {
                TimelineRecorder::new(
                    plan.max_rounds
                        .saturating_mul(runs.max(1))
                        .saturating_add(1),
                )
            }),
        })
    }

    /// The round last gathered.
    pub fn round(&self) -> u64 {
        self.round
    }

    /// One round whose messages carry something other than the method's iterate (a
    /// standing team's agreement on its scale, or its iterate again after one): publishes
    /// the next round with `write` (after [`RoundLoop::start_with`], round 0 is already
    /// published), gathers it until `deadline` and hands the exchange, holding the
    /// neighbours' messages, to `read`. The next [`RoundLoop::run`] computes from the
    /// messages gathered here. Side rounds are not timed.
    pub fn side_round(
        &mut self,
        exchange: &mut dyn Exchange,
        plan: &AgentPlan,
        deadline: Instant,
        write: &mut dyn FnMut(&mut [f64]),
        read: &mut dyn FnMut(&dyn Exchange),
    ) -> Result<(), ExchangeError> {
        if self.stopped {
            let header = RoundHeader {
                round: self.round + 1,
                ..RoundHeader::initial(plan.index)
            };
            exchange.compute_and_publish(&mut |_, out| {
                write(out);
                header
            })?;
            self.mine = header;
            self.round += 1;
        }
        exchange.gather(self.round, deadline)?;
        read(exchange);
        self.stopped = true;
        Ok(())
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
            if !resume
                && let Some(finished) =
                    self.verdict(agent, &*exchange, plan, &mut stop, round - first)?
            {
                self.stopped = true;
                return Ok(finished);
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
            // The hot loop logs only at `trace` (one atomic load when that is off).
            tracing::trace!(
                round,
                wait_us = gathered.duration_since(started).as_secs_f64() * 1e6,
                compute_us = computed.duration_since(gathered).as_secs_f64() * 1e6,
                publish_us = published.duration_since(computed).as_secs_f64() * 1e6,
                "round"
            );
            if plan.global_barrier {
                exchange.global_barrier(round + 1, published + plan.round_timeout)?;
            }
            self.record(plan, round, [started, gathered, computed, published]);
            self.round += 1;
        }
    }

    /// On the round just gathered (the `ran`-th of this run): the neighbours' payloads
    /// checked, then the stop protocol on their headers; the agent's task and the certified
    /// round when the run ends here (`None` round: the round limit).
    #[inline]
    fn verdict<A: ConsensusAgent + ?Sized>(
        &self,
        agent: &mut A,
        exchange: &dyn Exchange,
        plan: &AgentPlan,
        stop: &mut AgentStop,
        ran: u64,
    ) -> Result<Option<(usize, Option<u64>)>, ExchangeError> {
        let round = self.round;
        let degree = exchange.degree();
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
        let verdict = match stop {
            AgentStop::Local(rule) => rule.observe(
                round,
                self.mine.stop_state(),
                (0..degree).map(|k| exchange.neighbour_header(k).stop_state()),
                agent.rounded_task(),
                || agent.certificate_slack(),
            ),
            AgentStop::MaxIters => Verdict::Continue,
        };
        let finished = match verdict {
            Verdict::Certified {
                certified_round,
                task,
            } => Some((task, Some(certified_round))),
            Verdict::Continue if ran >= plan.max_rounds => Some((agent.decide(), None)),
            Verdict::Continue => None,
        };
        match finished {
            Some((task, Some(certified_round))) => tracing::debug!(
                round,
                certified_round,
                task,
                "the stop protocol certified the assignment"
            ),
            Some((_, None)) => tracing::debug!(round, "the round limit ended the run"),
            None => {}
        }
        Ok(finished)
    }

    /// Records round `round`'s times (`[started, gathered, computed, published]`, and now:
    /// the barrier's end) in the timeline and, past the warm-up, the latency histograms.
    #[inline]
    fn record(&mut self, plan: &AgentPlan, round: u64, at: [Instant; 4]) {
        let [started, gathered, computed, published] = at;
        let done = Instant::now();
        if let Some(timeline) = &mut self.timeline {
            timeline.record(round, [started, gathered, computed, published, done]);
        }
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
            timeline: self
                .timeline
                .clone()
                .map(TimelineRecorder::into_stamps)
                .unwrap_or_default(),
        }
    }
}
