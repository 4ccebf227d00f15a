//! The clock offsets of a team across hosts, estimated from its own round messages.
//!
//! Every host stamps with its own `CLOCK_MONOTONIC`; two machines' monotonic clocks differ by
//! an unknown offset (their boot times, to begin with). No extra message is needed to
//! estimate it: agent `j` on host B sends its round-`r` message after it computed round
//! `r − 1` (stamp `computed`, B's clock), and agent `i` on host A has it by the time it
//! gathered round `r` (stamp `gathered`, A's clock). Since a message arrives after it was
//! sent, `θ = clock_A − clock_B ≤ gathered_i(r) − computed_j(r − 1)`; the same edge the other
//! way bounds `θ` from below. Over every edge between A and B and every round, the tightest
//! bounds give an interval (the minimum-delay filter of NTP, with one-way delays measured in
//! both directions); its midpoint is the offset and its half-width the uncertainty.
//! Hosts without a direct edge chain through others (offsets add, uncertainties too), along
//! the chain of least uncertainty from the reference host (the first one).
//!
//! If the bounds cross (lower above upper: the clocks drifted apart during the run, or an
//! agent's stamps are wrong), the midpoint is still used and the host is marked
//! `consistent: false`.

use crate::timeline::RoundStamp;
use admm_ta_topologies::Graph;
use serde::{Deserialize, Serialize};

/// How one host's stamps map onto the reference host's clock.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HostClock {
    /// Add to this host's stamps to read them on the reference host's clock, ns.
    pub offset_ns: i64,
    /// Half-width of the interval the offset lies in (summed along a chain of hosts), ns.
    pub uncertainty_ns: u64,
    /// The offset was estimated (some chain of edges with recorded rounds reaches the
    /// reference host); otherwise it is 0 and the host's stamps are not aligned.
    pub estimated: bool,
    /// The bounds along the chain did not cross.
    pub consistent: bool,
}

/// Bounds on `clock_a − clock_b` from every edge between hosts `a` and `b`.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    low: i128,
    high: i128,
}

impl Bounds {
    fn midpoint(&self) -> i128 {
        (self.low + self.high).div_euclid(2)
    }

    fn half_width(&self) -> u64 {
        ((self.high - self.low).unsigned_abs() / 2) as u64
    }
}

/// Estimates every host's offset to host 0 from the agents' stamps: `host_of[i]` is agent
/// `i`'s host (`0..hosts`), `timelines[i]` its stamps from round 0.
pub fn estimate(
    graph: &Graph,
    timelines: &[Vec<RoundStamp>],
    host_of: &[usize],
    hosts: usize,
) -> Vec<HostClock> {
    // bounds[a][b]: clock_a − clock_b.
    let mut bounds: Vec<Vec<Option<Bounds>>> = vec![vec![None; hosts]; hosts];
    for i in 0..timelines.len().min(host_of.len()) {
        for &j in graph.neighbours(i) {
            let (a, b) = (host_of[i], host_of.get(j).copied().unwrap_or(usize::MAX));
            if a == b || a >= hosts || b >= hosts || j >= timelines.len() {
                continue;
            }
            // i (on a) received j's (on b) messages: clock_a − clock_b ≤ gathered − computed.
            let rounds = timelines[i].len().min(timelines[j].len());
            let Some(high) = (1..rounds)
                .map(|r| timelines[i][r].gathered as i128 - timelines[j][r - 1].computed as i128)
                .min()
            else {
                continue;
            };
            // The same bound read from b's side: clock_b − clock_a ≤ high.
            for (x, y, value) in [(a, b, Some(high)), (b, a, None)] {
                let entry = bounds[x][y].get_or_insert(Bounds {
                    low: i128::MIN,
                    high: i128::MAX,
                });
                match value {
                    Some(h) => entry.high = entry.high.min(h),
                    None => entry.low = entry.low.max(-high),
                }
            }
        }
    }
    // Only pairs bounded from both sides give an offset.
    let usable =
        |a: usize, b: usize| bounds[a][b].filter(|bd| bd.low != i128::MIN && bd.high != i128::MAX);
    let mut clocks = vec![
        HostClock {
            offset_ns: 0,
            uncertainty_ns: 0,
            estimated: false,
            consistent: true,
        };
        hosts
    ];
    if hosts == 0 {
        return clocks;
    }
    clocks[0].estimated = true;
    // Dijkstra on uncertainty from host 0 (a handful of hosts: a linear scan suffices).
    let mut done = vec![false; hosts];
    loop {
        let next = (0..hosts)
            .filter(|&h| !done[h] && clocks[h].estimated)
            .min_by_key(|&h| clocks[h].uncertainty_ns);
        let Some(a) = next else { break };
        done[a] = true;
        for b in 0..hosts {
            if done[b] {
                continue;
            }
            // t_a = t_b + (clock_a − clock_b): b's stamps on a's clock, then on the reference's.
            let Some(bd) = usable(a, b) else { continue };
            let uncertainty = clocks[a].uncertainty_ns.saturating_add(bd.half_width());
            if !clocks[b].estimated || uncertainty < clocks[b].uncertainty_ns {
                clocks[b] = HostClock {
                    offset_ns: (clocks[a].offset_ns as i128 + bd.midpoint())
                        .clamp(i64::MIN as i128, i64::MAX as i128)
                        as i64,
                    uncertainty_ns: uncertainty,
                    estimated: true,
                    consistent: clocks[a].consistent && bd.low <= bd.high,
                };
            }
        }
    }
    clocks
}

/// Shifts every agent's stamps onto the reference host's clock.
pub fn align(timelines: &mut [Vec<RoundStamp>], host_of: &[usize], clocks: &[HostClock]) {
    for (stamps, host) in timelines.iter_mut().zip(host_of) {
        let Some(clock) = clocks.get(*host).filter(|c| c.estimated) else {
            continue;
        };
        let shift = |t: &mut u64| {
            *t = (*t as i128 + clock.offset_ns as i128).clamp(0, u64::MAX as i128) as u64;
        };
        for s in stamps {
            for t in [
                &mut s.wait,
                &mut s.gathered,
                &mut s.computed,
                &mut s.published,
                &mut s.done,
            ] {
                shift(t);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ring of four agents on two hosts; host 1's clock reads `skew` ns ahead of host 0's,
    /// messages take 50–150 ns each way. The estimate brackets the true offset.
    #[test]
    fn the_offset_of_a_skewed_host_is_bracketed() {
        let graph = Graph::from_edges(4, &[(0, 1), (1, 2), (2, 3), (3, 0)], "ring").unwrap();
        let host_of = [0, 0, 1, 1];
        let skew: i64 = 5_000_000_000;
        let mut timelines = vec![Vec::new(); 4];
        for r in 0..20u64 {
            // True times: every agent computes at 1000 r + 10 i, gathers 150 ns after the
            // latest neighbour's compute (one delay of 50 ns in some rounds).
            for (i, stamps) in timelines.iter_mut().enumerate() {
                let t = 1000 * (r + 1) + 10 * i as u64;
                let delay = if r % 3 == 0 { 50 } else { 150 };
                let gathered = 1000 * r + 30 + delay;
                let on_host = |v: u64| (v as i64 + if host_of[i] == 1 { skew } else { 0 }) as u64;
                stamps.push(RoundStamp {
                    round: r,
                    wait: on_host(gathered - 10),
                    gathered: on_host(gathered),
                    computed: on_host(t),
                    published: on_host(t + 5),
                    done: on_host(t + 5),
                });
            }
        }
        let clocks = estimate(&graph, &timelines, &host_of, 2);
        assert!(clocks[0].estimated && clocks[1].estimated && clocks[1].consistent);
        // Host 1's stamps need −skew to read on host 0's clock.
        let error = (clocks[1].offset_ns + skew).unsigned_abs();
        assert!(
            error <= clocks[1].uncertainty_ns,
            "{error} > ±{}",
            clocks[1].uncertainty_ns
        );
        assert!(clocks[1].uncertainty_ns < 1_000, "{clocks:?}");
        let before = timelines[2][5].computed;
        align(&mut timelines, &host_of, &clocks);
        assert_eq!(
            timelines[2][5].computed as i64,
            before as i64 + clocks[1].offset_ns
        );
    }

    #[test]
    fn a_host_without_recorded_rounds_is_not_estimated() {
        let graph = Graph::from_edges(2, &[(0, 1)], "pair").unwrap();
        let clocks = estimate(&graph, &[Vec::new(), Vec::new()], &[0, 1], 2);
        assert!(clocks[0].estimated && !clocks[1].estimated);
    }
}
