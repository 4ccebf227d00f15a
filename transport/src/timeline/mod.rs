//! Per-round timelines of a team (`--timeline FILE`): every agent stamps each round —
//! when it started waiting, when its neighbours' messages were all in, when it had computed
//! and published, when the global barrier let it go — into a buffer allocated before the
//! first round ([`TimelineRecorder`]: no allocation or I/O inside a round); the runner
//! merges them, [`critical_path`] names the agent each round waited for, and
//! [`chrome_trace`] writes the Chrome trace-event JSON that Perfetto and `chrome://tracing`
//! open.
//!
//! **Clocks.** Stamps are `CLOCK_MONOTONIC` nanoseconds: one clock for every process of one
//! machine, so stamps of agent processes and threads compare directly. A team across
//! machines has one clock per host, with unknown offsets: [`clocks`] estimates them from the
//! round messages themselves (a message arrives after it was sent, both ways over every edge
//! between two hosts) and shifts every host's stamps onto one clock, with the uncertainty
//! of each offset said in the trace and the report.
//!
//! **Whom an agent waited for.** Agent `j`'s round-`r` message is published when `j`
//! finishes computing round `r − 1`; agent `i` can compute round `r` once the last of its
//! neighbours' round-`r` messages is in. So the neighbour with the latest publish stamp of
//! round `r − 1` is the one `i` waited for, if `i` was waiting by then; the time `i` spent
//! waiting in that round is charged to it. No exchange has to tell who came last.

pub mod clocks;

use admm_ta_topologies::Graph;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The most rounds an agent records (later rounds are not recorded): 40 bytes a round, so
/// at most 8 MB per agent.
pub const MAX_RECORDED_ROUNDS: u64 = 200_000;

/// One agent's stamps of one round, `CLOCK_MONOTONIC` nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct RoundStamp {
    pub round: u64,
    /// Started waiting for the neighbours' messages of `round`.
    pub wait: u64,
    /// Every neighbour's message was in.
    pub gathered: u64,
    /// The step was computed.
    pub computed: u64,
    /// The round-`round + 1` message was published.
    pub published: u64,
    /// Released by the global barrier (`published` without one).
    pub done: u64,
}

/// `CLOCK_MONOTONIC` now, in nanoseconds.
fn monotonic_ns() -> u64 {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut now) };
    now.tv_sec as u64 * 1_000_000_000 + now.tv_nsec as u64
}

/// One agent's stamps, in a buffer sized before the first round.
#[derive(Debug, Clone)]
pub struct TimelineRecorder {
    /// An `Instant` and the monotonic clock read together: stamps are `Instant`s mapped
    /// through them (both are `CLOCK_MONOTONIC` on Linux).
    base: Instant,
    base_ns: u64,
    stamps: Vec<RoundStamp>,
}

impl TimelineRecorder {
    /// A recorder for up to `rounds` rounds (at most [`MAX_RECORDED_ROUNDS`]).
    pub fn new(rounds: u64) -> Self {
        let base = Instant::now();
        let base_ns = monotonic_ns();
        Self {
            base,
            base_ns,
            stamps: Vec::with_capacity(rounds.min(MAX_RECORDED_ROUNDS) as usize),
        }
    }

    fn ns(&self, t: Instant) -> u64 {
        self.base_ns + t.saturating_duration_since(self.base).as_nanos() as u64
    }

    /// Records a round; a round beyond the buffer is dropped (never a reallocation).
    pub fn record(
        &mut self,
        round: u64,
        [wait, gathered, computed, published, done]: [Instant; 5],
    ) {
        if self.stamps.len() == self.stamps.capacity() {
            return;
        }
        let stamp = RoundStamp {
            round,
            wait: self.ns(wait),
            gathered: self.ns(gathered),
            computed: self.ns(computed),
            published: self.ns(published),
            done: self.ns(done),
        };
        self.stamps.push(stamp);
    }

    /// The recorded rounds.
    pub fn into_stamps(self) -> Vec<RoundStamp> {
        self.stamps
    }
}

/// Who the team waited for, round by round, and what it cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CriticalPath {
    /// For every recorded round from 1 on, the agent most of the others waited for in it
    /// (`None`: nobody waited).
    pub rounds: Vec<Option<usize>>,
    /// The agents most often waited for, most charged first (at most five).
    pub top: Vec<CriticalAgent>,
    /// The share of all agents' round time spent waiting for a late neighbour.
    pub waiting_share: f64,
    /// For every agent, the share of all agents' round time spent waiting for it.
    pub by_agent: Vec<f64>,
}

/// One agent's part in the team's waiting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CriticalAgent {
    pub agent: usize,
    /// Rounds in which this agent was the one most of the others waited for.
    pub rounds: usize,
    /// Agent-rounds in which a neighbour waited for this agent's message last.
    pub waited_for: usize,
    /// The share of all agents' round time spent waiting for this agent.
    pub waiting_share: f64,
}

/// The neighbour agent `i` waited for in round `r ≥ 1`: the one whose round-`r` message
/// (published at the end of its round `r − 1`) came last, if `i` was waiting by then.
fn late_neighbour(
    graph: &Graph,
    timelines: &[Vec<RoundStamp>],
    i: usize,
    r: usize,
) -> Option<usize> {
    let late = graph
        .neighbours(i)
        .iter()
        .copied()
        .filter(|&j| j < timelines.len())
        .max_by_key(|&j| (timelines[j][r - 1].published, j))?;
    (timelines[late][r - 1].published > timelines[i][r].wait).then_some(late)
}

/// The critical path of a team's rounds: `timelines[i]` is agent `i`'s stamps.
pub fn critical_path(graph: &Graph, timelines: &[Vec<RoundStamp>]) -> CriticalPath {
    let n = timelines.len();
    let rounds = timelines.iter().map(Vec::len).min().unwrap_or(0);
    let mut per_round = Vec::with_capacity(rounds.saturating_sub(1));
    let mut charged = vec![0u64; n];
    let mut waited_for = vec![0usize; n];
    let mut leading = vec![0usize; n];
    let mut total_round_ns = 0u64;
    let mut votes = vec![0usize; n];
    for r in 1..rounds {
        votes.iter_mut().for_each(|v| *v = 0);
        for i in 0..n {
            let mine = &timelines[i][r];
            total_round_ns += mine.done.saturating_sub(mine.wait);
            if let Some(j) = late_neighbour(graph, timelines, i, r) {
                charged[j] += mine.gathered.saturating_sub(mine.wait);
                waited_for[j] += 1;
                votes[j] += 1;
            }
        }
        let critical = (0..n)
            .filter(|&j| votes[j] > 0)
            .max_by_key(|&j| (votes[j], timelines[j][r - 1].published));
        if let Some(j) = critical {
            leading[j] += 1;
        }
        per_round.push(critical);
    }
    let share = |ns: u64| {
        if total_round_ns == 0 {
            0.0
        } else {
            ns as f64 / total_round_ns as f64
        }
    };
    let mut top: Vec<CriticalAgent> = (0..n)
        .filter(|&j| waited_for[j] > 0)
        .map(|j| CriticalAgent {
            agent: j,
            rounds: leading[j],
            waited_for: waited_for[j],
            waiting_share: share(charged[j]),
        })
        .collect();
    top.sort_by(|a, b| {
        b.waiting_share
            .total_cmp(&a.waiting_share)
            .then(a.agent.cmp(&b.agent))
    });
    top.truncate(5);
    CriticalPath {
        rounds: per_round,
        top,
        waiting_share: share(charged.iter().sum()),
        by_agent: charged.iter().map(|&ns| share(ns)).collect(),
    }
}

/// The team's timelines as Chrome trace-event JSON: one process track per agent (`pid` the
/// agent, named `agent I`), a complete event per phase of each round (`wait`, `compute`,
/// `publish`, `barrier`, the round in `args`), and a flow from the publish of the neighbour
/// each agent waited for to the end of its wait. Times in µs from the first stamp.
pub fn chrome_trace(graph: &Graph, timelines: &[Vec<RoundStamp>]) -> serde_json::Value {
    chrome_trace_named(graph, timelines, &|agent| format!("agent {agent}"))
}

/// [`chrome_trace`] with each agent's track named by `name` (e.g. with its host).
pub fn chrome_trace_named(
    graph: &Graph,
    timelines: &[Vec<RoundStamp>],
    name: &dyn Fn(usize) -> String,
) -> serde_json::Value {
    let origin = timelines
        .iter()
        .flat_map(|t| t.first())
        .map(|s| s.wait)
        .min()
        .unwrap_or(0);
    let us = |ns: u64| ns.saturating_sub(origin) as f64 / 1e3;
    let mut events = Vec::new();
    for (agent, stamps) in timelines.iter().enumerate() {
        events.push(serde_json::json!({
            "name": "process_name", "ph": "M", "pid": agent, "tid": 0,
            "args": {"name": name(agent)},
        }));
        events.push(serde_json::json!({
            "name": "process_sort_index", "ph": "M", "pid": agent, "tid": 0,
            "args": {"sort_index": agent},
        }));
        for s in stamps {
            for (name, from, to) in [
                ("wait", s.wait, s.gathered),
                ("compute", s.gathered, s.computed),
                ("publish", s.computed, s.published),
                ("barrier", s.published, s.done),
            ] {
                if to > from || name != "barrier" {
                    events.push(serde_json::json!({
                        "name": name, "cat": "round", "ph": "X", "pid": agent, "tid": 0,
                        "ts": us(from), "dur": us(to) - us(from),
                        "args": {"round": s.round},
                    }));
                }
            }
        }
    }
    // The message each agent waited for last, as a flow from its publish.
    let rounds = timelines.iter().map(Vec::len).min().unwrap_or(0);
    let mut id = 0u64;
    for r in 1..rounds {
        for (i, mine) in timelines.iter().enumerate().map(|(i, t)| (i, &t[r])) {
            let Some(j) = late_neighbour(graph, timelines, i, r) else {
                continue;
            };
            let sent = timelines[j][r - 1].published;
            id += 1;
            events.push(serde_json::json!({
                "name": "message", "cat": "message", "ph": "s", "id": id,
                "pid": j, "tid": 0, "ts": us(sent),
                "args": {"round": mine.round, "from": j, "to": i},
            }));
            events.push(serde_json::json!({
                "name": "message", "cat": "message", "ph": "f", "bp": "e", "id": id,
                "pid": i, "tid": 0, "ts": us(mine.gathered),
            }));
        }
    }
    serde_json::json!({
        "traceEvents": events,
        "displayTimeUnit": "ms",
        "otherData": {"clock": "CLOCK_MONOTONIC, µs from the first stamp"},
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamp(round: u64, wait: u64, gathered: u64, published: u64) -> RoundStamp {
        RoundStamp {
            round,
            wait,
            gathered,
            computed: published - 1,
            published,
            done: published,
        }
    }

    /// A chain 0 – 1 – 2 in which agent 2 is slow: 1 waits for it every round.
    #[test]
    fn the_slow_agent_is_on_the_critical_path() {
        let graph = Graph::from_edges(3, &[(0, 1), (1, 2)], "chain").unwrap();
        let mut timelines = vec![Vec::new(), Vec::new(), Vec::new()];
        for r in 0..4u64 {
            // Agent 2 publishes round r at b − 100 + 1000; agent 1 is ready long before.
            let b = 1000 * (r + 1);
            timelines[0].push(stamp(r, b - 40, b - 30, b - 20));
            timelines[1].push(stamp(r, b - 700, b - 90, b - 50));
            timelines[2].push(stamp(r, b, b + 10, b + 900));
        }
        let path = critical_path(&graph, &timelines);
        assert_eq!(path.rounds, [Some(2), Some(2), Some(2)]);
        assert_eq!(path.top[0].agent, 2);
        assert!(path.top[0].waiting_share > 0.0 && path.waiting_share <= 1.0);
        assert_eq!(path.by_agent.len(), 3);
        assert_eq!(path.by_agent[2], path.top[0].waiting_share);
        assert_eq!(path.by_agent[0], 0.0);
        let trace = chrome_trace(&graph, &timelines);
        let events = trace["traceEvents"].as_array().unwrap();
        assert!(events.iter().any(|e| e["ph"] == "s" && e["pid"] == 2));
        assert_eq!(
            events
                .iter()
                .filter(|e| e["name"] == "wait" && e["pid"] == 1)
                .count(),
            4
        );
    }

    #[test]
    fn a_full_buffer_drops_rounds_without_reallocating() {
        let mut recorder = TimelineRecorder::new(2);
        let now = Instant::now();
        for r in 0..5 {
            recorder.record(r, [now; 5]);
        }
        assert_eq!(recorder.into_stamps().len(), 2);
    }
}
