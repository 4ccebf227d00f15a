//! The fast dual variant's certificate: one common price vector and the team's claims,
//! flooded with the multipliers.
//!
//! # Why a snapshot
//! A robot sees its own cost row only, so optimality has to be proved by prices. Weak
//! duality needs *one* price vector `ȳ` for the whole team, but every robot holds its own
//! copy of the multipliers, and they agree only in the limit. Instead of waiting for them
//! to agree (the paper variant's certificate asks the neighbours' prices to agree within a
//! margin), the team floods a copy of one robot's prices: every `P = max(D, 1)` rounds (`D`
//! the diameter) the *leader* (the builder picks a centre of the graph) puts the prices it
//! has just sent into the snapshot, and every robot puts in its claim — its own rounded task
//! (the smallest robot number claiming a task is kept). Each round a robot merges its
//! neighbours' snapshots into its own, so `P ≥ D` rounds later every robot holds the same
//! prices and the same claims: the snapshot *settles*, at the same round everywhere.
//!
//! # The bound
//! Let `π` be the claimed assignment (every robot's task at the snapshot's round), `α_i`
//! robot `i`'s costs and `r_t = α_t ± ȳ_t` its reduced costs at the common prices (`+` for
//! Case 1's equality prices, `−` for Case 2's coverage prices `ȳ ≥ 0`). Relaxing the task
//! constraints with `ȳ` (each robot keeps "exactly one allowed task" as its own constraint)
//! gives the lower bound `OPT ≥ Σ_i min_t r_{i,t} ∓ Σ_t ȳ_t`, so
//!
//! ```text
//! cost(π) − OPT ≤ Σ_i [ r_{i,π_i} − min_t r_{i,t} ]  +  Σ_t ȳ_t (cover_t − 1)   (Case 2)
//! ```
//!
//! and the last term is 0 in Case 1 when every task is covered once. The claims settle to
//! the smallest claimer of every task, so a robot knows whether it is that claimer: the
//! *other* claimers of a task number exactly `cover_t − 1`, and each adds its task's price to
//! its own slack. Robot `i`'s slack is therefore `r_{π_i} − min_t r_t` (+ `ȳ_{π_i}` when it
//! is an extra claimer in Case 2; ∞ when it is one in Case 1, or a task is unclaimed, or its
//! task changed since the snapshot): the slacks sum to the bound exactly, so every slack at
//! most `tol / n` proves the common assignment within `tol` of the optimum — the contract of
//! the decentralized stop ([`crate::certify::local_stop`]), whatever the multipliers, the
//! x-iterates or the leader's choice (a different leader only changes how soon it fires).
//!
//! # Layout of the payload section
//! `[has_prices, ȳ_0 … ȳ_{m−1}, claim_0 … claim_{m−1}]` (`has_prices` 1 or 0; a claim is the
//! smallest claiming robot's number, or −1 when nobody claimed the task yet).

use crate::problem::AssignmentCase;

/// Values of the snapshot's payload section for `tasks` tasks.
pub const fn words(tasks: usize) -> usize {
    1 + 2 * tasks
}

/// No claim yet.
const UNCLAIMED: f64 = -1.0;

/// The snapshot being flooded and the last settled one.
#[derive(Debug, Clone)]
pub struct Snapshot {
    index: usize,
    leader: bool,
    period: u64,
    flooding: Part,
    settled: Part,
}

/// The contents of one snapshot.
#[derive(Debug, Clone)]
struct Part {
    has_prices: bool,
    prices: Vec<f64>,
    claims: Vec<f64>,
    /// The robot's own task when the snapshot started.
    task: Option<usize>,
}

impl Part {
    fn empty(tasks: usize) -> Self {
        Self {
            has_prices: false,
            prices: vec![0.0; tasks],
            claims: vec![UNCLAIMED; tasks],
            task: None,
        }
    }
}

impl Snapshot {
    /// Robot `index`'s side, `leader` if its prices are the team's, on a graph of diameter
    /// `diameter`.
    pub fn new(index: usize, tasks: usize, leader: bool, diameter: usize) -> Self {
        Self {
            index,
            leader,
            period: diameter.max(1) as u64,
            flooding: Part::empty(tasks),
            settled: Part::empty(tasks),
        }
    }

    /// The section of a message sent before any snapshot started.
    pub fn write_empty(out: &mut [f64]) {
        out[0] = 0.0;
        let tasks = (out.len() - 1) / 2;
        out[1..=tasks].fill(0.0);
        out[1 + tasks..].fill(UNCLAIMED);
    }

    /// Merges a neighbour's section of the round gathered at step `step` (ignored at step
    /// 0: those are the initial messages, sent before the first snapshot).
    pub fn merge(&mut self, step: u64, theirs: &[f64]) {
        if step == 0 {
            return;
        }
        let tasks = self.flooding.claims.len();
        debug_assert_eq!(theirs.len(), words(tasks));
        if theirs[0] == 1.0 && !self.flooding.has_prices {
            self.flooding.has_prices = true;
            self.flooding.prices.copy_from_slice(&theirs[1..=tasks]);
        }
        for (mine, &claim) in self.flooding.claims.iter_mut().zip(&theirs[1 + tasks..]) {
            if claim >= 0.0 && (*mine < 0.0 || claim < *mine) {
                *mine = claim;
            }
        }
    }

    /// After merging step `step`'s messages and deciding the robot's `task`: settles the
    /// snapshot that has flooded for `P` rounds and starts the next one (with `prices`, the
    /// multipliers this robot sent in the round just gathered, if it leads). Every robot
    /// does both at the same steps.
    pub fn advance(&mut self, step: u64, task: usize, prices: &[f64]) {
        if !step.is_multiple_of(self.period) {
            return;
        }
        if step > 0 {
            std::mem::swap(&mut self.settled, &mut self.flooding);
        }
        let next = &mut self.flooding;
        next.has_prices = self.leader;
        if self.leader {
            next.prices.copy_from_slice(prices);
        }
        next.claims.fill(UNCLAIMED);
        next.claims[task] = self.index as f64;
        next.task = Some(task);
    }

    /// Writes the snapshot being flooded into the message's section.
    pub fn write(&self, out: &mut [f64]) {
        let part = &self.flooding;
        let tasks = part.claims.len();
        out[0] = if part.has_prices { 1.0 } else { 0.0 };
        out[1..=tasks].copy_from_slice(&part.prices);
        out[1 + tasks..].copy_from_slice(&part.claims);
    }

    /// The robot's certificate slack (module docs) for its current `task`, with its own
    /// (centred) `costs` and `allowed` tasks; ∞ when the settled snapshot proves nothing.
    pub fn slack(&self, task: usize, costs: &[f64], allowed: &[bool], case: AssignmentCase) -> f64 {
        let part = &self.settled;
        if part.task != Some(task) || !part.has_prices || part.claims.iter().any(|&c| c < 0.0) {
            return f64::INFINITY;
        }
        let coverage = case == AssignmentCase::Two;
        let extra = part.claims[task] != self.index as f64;
        if extra && !coverage {
            return f64::INFINITY;
        }
        let reduced = |t: usize| {
            if coverage {
                costs[t] - part.prices[t]
            } else {
                costs[t] + part.prices[t]
            }
        };
        let best = (0..costs.len())
            .filter(|&t| allowed[t])
            .map(reduced)
            .fold(f64::INFINITY, f64::min);
        let own = reduced(task) - best;
        if extra {
            own + part.prices[task].max(0.0)
        } else {
            own
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Floods the snapshots of a chain of robots through their written sections, one step
    /// at a time, as the transports do.
    fn run_chain(tasks_of: &[usize], prices: &[f64], steps: u64) -> Vec<Snapshot> {
        let n = tasks_of.len();
        let m = prices.len();
        let mut robots: Vec<Snapshot> = (0..n)
            .map(|i| Snapshot::new(i, m, i == n / 2, n - 1))
            .collect();
        let mut sections = vec![vec![0.0; words(m)]; n];
        for s in &mut sections {
            Snapshot::write_empty(s);
        }
        for step in 0..steps {
            let gathered = sections.clone();
            for (i, robot) in robots.iter_mut().enumerate() {
                for j in [i.wrapping_sub(1), i + 1] {
                    if j < n {
                        robot.merge(step, &gathered[j]);
                    }
                }
                robot.advance(step, tasks_of[i], prices);
                robot.write(&mut sections[i]);
            }
        }
        robots
    }

    /// After `D` rounds every robot holds the leader's prices and every task's smallest
    /// claimer; before, nothing is settled.
    #[test]
    fn a_snapshot_settles_everywhere_after_the_diameter() {
        let costs = [0.0, 0.0, 0.0];
        let allowed = [true; 3];
        let tasks_of = [2, 0, 1, 0, 2];
        let early = run_chain(&tasks_of, &[0.5, 0.25, 0.0], 4);
        assert!(early.iter().all(|r| r.settled.task.is_none()));
        let robots = run_chain(&tasks_of, &[0.5, 0.25, 0.0], 5);
        for (i, robot) in robots.iter().enumerate() {
            assert!(robot.settled.has_prices, "robot {i}");
            assert_eq!(robot.settled.prices, [0.5, 0.25, 0.0]);
            assert_eq!(robot.settled.claims, [1.0, 2.0, 0.0]);
            assert_eq!(robot.settled.task, Some(tasks_of[i]));
        }
        // Case 1: two robots share tasks 0 and 2, so the extra claimers (3 and 4) cannot
        // certify; Case 2 charges them their task's price.
        assert!(
            robots[3]
                .slack(0, &costs, &allowed, AssignmentCase::One)
                .is_infinite()
        );
        assert_eq!(
            robots[0].slack(2, &costs, &allowed, AssignmentCase::One),
            0.0
        );
        assert_eq!(
            robots[1].slack(0, &costs, &allowed, AssignmentCase::One),
            0.5
        );
        assert_eq!(
            robots[3].slack(0, &costs, &allowed, AssignmentCase::Two),
            0.5
        );
        assert_eq!(
            robots[4].slack(2, &costs, &allowed, AssignmentCase::Two),
            0.5
        );
        // A robot whose task changed since the snapshot proves nothing.
        assert!(
            robots[1]
                .slack(1, &costs, &allowed, AssignmentCase::Two)
                .is_infinite()
        );
    }

    /// An unclaimed task proves nothing; a forbidden task is no robot's best.
    #[test]
    fn unclaimed_tasks_and_forbidden_pairs() {
        let robots = run_chain(&[0, 0, 1], &[0.0, 0.0, 0.0], 3);
        let allowed = [true, true, true];
        assert!(
            robots[0]
                .slack(0, &[0.0, 0.0, 0.0], &allowed, AssignmentCase::Two)
                .is_infinite()
        );
        let robots = run_chain(&[0, 1], &[0.0, 0.0], 2);
        let costs = [1.0, -5.0];
        assert_eq!(
            robots[0].slack(0, &costs, &[true, false], AssignmentCase::One),
            0.0
        );
        assert_eq!(
            robots[0].slack(0, &costs, &[true, true], AssignmentCase::One),
            6.0
        );
    }
}
