//! Consensus-based auction algorithm (CBAA; Choi, Brunet & How, IEEE T-RO 2009), one robot's
//! state machine — a baseline: fast, conflict-free, not optimal.
//!
//! Every robot keeps, for each task `j`, the highest bid `y_j` it knows and its winner `z_j`
//! (`−∞` and "nobody" at first), and at most one task of its own. The payload is
//! `(y_1 … y_m, z_1 … z_m)`: `2m` numbers. One round, after receiving the neighbours'
//! lists:
//!
//! 1. **Consensus**: for every task keep the best `(y_j, z_j)` among its own and its
//!    neighbours', best meaning the higher bid, and on equal bids the lower robot index. This
//!    order is total and the same at every robot, and a task's best bid never decreases, so
//!    it is a max-consensus: correct over any number of hops (no robot needs a neighbour to
//!    have seen the bid first). A robot whose task now has another winner drops it.
//! 2. **Auction**: a robot without a task bids on the task with the highest score
//!    `c_j = −α_j` (cheapest) among those its bid would win (`c_j > y_j`, or equal with a
//!    lower index), and records itself as the winner.
//!
//! A bid that lost somewhere reaches everybody within the graph diameter `D`, so when no
//! robot's lists change in a round, no list changes any more (the step is deterministic):
//! the certificate slack is 0 exactly in rounds where the robot's lists did not change,
//! and the decentralized stop protocol ([`crate::certify::local_stop`]) stops every robot at the
//! same round once all lists agreed and stood still. With `n = m` every robot ends with a
//! task (an unassigned robot always sees an unclaimed task, whose bid is `−∞`); in Case 2
//! the `m` winners cover the tasks and every other robot takes its cheapest task.
//! Scores are the negated costs, so bids are shift- and scale-free like the costs.
//!
//! CBAA is greedy: each task goes to the robot that bids highest for it, in an order set by
//! the bids, which is not the optimal assignment in general (the paper's Section 4.3: it
//! never was in their trials). Its optimality gap is reported by `solve --check`.

use crate::agent::{AgentAlgorithm, ConsensusAgent, Inbox, PayloadError, PayloadPart, StepReport};
use crate::method::info::{
    Certification, Fig2Graphs, Memory, MethodInfo, Numbers, OWN_STATE_STOPS, PaperFacts,
    ReportText, Role, TEAM_STATE, per_agent,
};
use crate::method::settings::NoSettings;
use crate::method::team::{AgentInit, TeamBuilder, TeamContext, TeamMethod};

/// No winner (as stored in the payload).
const NOBODY: f64 = -1.0;

/// Robot `index`'s CBAA state.
pub struct CbaaAgent {
    index: usize,
    tasks: usize,
    costs: Vec<f64>,
    /// Its cheapest task: what it does without a task of its own (Case 2 extras).
    cheapest: usize,
    /// Own lists `(y, z)` of the current round: the payload.
    lists: Vec<f64>,
    /// The task this robot holds.
    task: Option<usize>,
    /// Own relaxed column: the indicator of the task it would do.
    column: Vec<f64>,
    /// The last step changed nothing.
    settled: bool,
}

impl CbaaAgent {
    pub fn new(index: usize, costs: Vec<f64>) -> Self {
        let tasks = costs.len();
        assert!(tasks >= 1);
        let mut lists = vec![f64::NEG_INFINITY; 2 * tasks];
        lists[tasks..].fill(NOBODY);
        let cheapest = crate::certify::oracle::argmin(&costs);
        let mut agent = Self {
            index,
            tasks,
            costs,
            cheapest,
            lists,
            task: None,
            column: vec![0.0; tasks],
            settled: false,
        };
        agent.refresh_column();
        agent
    }

    /// The task this robot holds, if any.
    pub fn task(&self) -> Option<usize> {
        self.task
    }

    /// The task it does: the one it holds, or (unassigned, Case 2 extras) its cheapest.
    fn chosen(&self) -> usize {
        self.task.unwrap_or(self.cheapest)
    }

    fn refresh_column(&mut self) {
        let task = self.chosen();
        self.column.fill(0.0);
        self.column[task] = 1.0;
    }

    /// `(bid, winner)` `a` beats `b`: higher bid, or equal bids and a lower winner index
    /// ("nobody" loses every tie).
    fn beats(a: (f64, f64), b: (f64, f64)) -> bool {
        a.0 > b.0 || (a.0 == b.0 && a.1 != NOBODY && (b.1 == NOBODY || a.1 < b.1))
    }
}

impl ConsensusAgent for CbaaAgent {
    fn payload_len(&self) -> usize {
        2 * self.tasks
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        out.copy_from_slice(&self.lists);
    }

    /// Bids finite or `−∞` (none yet); winners "nobody" or a robot index (an integer).
    fn check_payload(&self, payload: &[f64]) -> Result<(), PayloadError> {
        let m = self.tasks;
        crate::agent::check_length(payload, 2 * m)?;
        for j in 0..m {
            let (bid, winner) = (payload[j], payload[m + j]);
            if bid.is_nan() || bid == f64::INFINITY {
                return Err(PayloadError::BadValue {
                    part: PayloadPart::at("bid on task", j),
                    value: bid,
                });
            }
            if winner != NOBODY && !(winner >= 0.0 && winner.fract() == 0.0 && winner < 1e9) {
                return Err(PayloadError::BadValue {
                    part: PayloadPart::at("winner of task", j),
                    value: winner,
                });
            }
        }
        Ok(())
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        let m = self.tasks;
        out.copy_from_slice(&self.lists);
        let mut disagreement: f64 = 0.0;
        // Consensus on the best (bid, winner) per task.
        for k in 0..inbox.len() {
            let theirs = inbox.payload(k);
            assert_eq!(
                theirs.len(),
                2 * m,
                "neighbour payload has the wrong length"
            );
            for j in 0..m {
                let (bid, winner) = (theirs[j], theirs[m + j]);
                if winner != self.lists[m + j] || bid != self.lists[j] {
                    disagreement = 1.0;
                }
                if Self::beats((bid, winner), (out[j], out[m + j])) {
                    out[j] = bid;
                    out[m + j] = winner;
                }
            }
        }
        let me = self.index as f64;
        if let Some(t) = self.task
            && out[m + t] != me
        {
            self.task = None;
        }
        // Auction: bid for the best task this robot would win.
        if self.task.is_none() {
            let best = (0..m)
                .filter(|&j| Self::beats((-self.costs[j], me), (out[j], out[m + j])))
                .max_by(|&a, &b| (-self.costs[a]).total_cmp(&-self.costs[b]).then(b.cmp(&a)));
            if let Some(j) = best {
                out[j] = -self.costs[j];
                out[m + j] = me;
                self.task = Some(j);
            }
        }
        let changed = out
            .iter()
            .zip(&self.lists)
            .any(|(a, b)| a.to_bits() != b.to_bits());
        self.settled = !changed;
        self.lists.copy_from_slice(out);
        self.refresh_column();
        let digest = self.lists.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
            (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3)
        });
        StepReport {
            disagreement,
            change: if changed { 1.0 } else { 0.0 },
            inner_iterations: 0,
            inner_converged: true,
            integrality_gap: 0.0,
            own_integrality_gap: 0.0,
            assignment_digest: digest,
        }
    }

    fn decide(&self) -> usize {
        self.chosen()
    }

    fn rounded_task(&self) -> usize {
        self.chosen()
    }

    /// 0 when the last step changed nothing (with every robot's lists equal and still, the
    /// auction has ended), ∞ otherwise. Not an optimality certificate: CBAA is greedy.
    fn certificate_slack(&self) -> f64 {
        if self.settled { 0.0 } else { f64::INFINITY }
    }

    fn own_column(&self) -> &[f64] {
        &self.column
    }
}

/// No penalty, one problem: the defaults.
impl AgentAlgorithm for CbaaAgent {}

/// The CBAA baseline's registration.
pub const INFO: MethodInfo = MethodInfo {
    name: "cbaa",
    summary: "the consensus-based auction baseline: fast, conflict-free, not optimal",
    role: Role::Baseline,
    team: Some(&CbaaMethod),
    variants: None,
    stops: OWN_STATE_STOPS,
    // Costs, bids and winners, the own column, two round buffers of 2m.
    memory: Memory {
        bytes: |n, m| per_agent(n, 8.0 * m as f64),
        of: TEAM_STATE,
        because: "each robot holds 2m bids and winners",
    },
    certification: Certification::Never {
        because: "CBAA is a heuristic",
    },
    numbers: Numbers::Normalised,
    report: ReportText { inner_steps: None },
    paper: Some(PaperFacts {
        label: "CBAA (not optimal)",
        proposed: false,
        table1: None,
        fig1: None,
        fig2: Fig2Graphs {
            complete: true,
            random: false,
        },
        variant: None,
    }),
};

/// CBAA as a team method.
pub struct CbaaMethod;

impl TeamMethod for CbaaMethod {
    type Settings = NoSettings;
    const PENALTY: bool = false;

    fn payload_len(&self, _: &NoSettings, _robots: usize, tasks: usize) -> usize {
        2 * tasks
    }

    fn team<'a>(&'static self, _: &NoSettings, _: TeamContext<'a>) -> Box<dyn TeamBuilder + 'a> {
        Box::new(CbaaTeam)
    }
}

struct CbaaTeam;

impl TeamBuilder for CbaaTeam {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        Box::new(CbaaAgent::new(init.index, init.costs))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ties_go_to_the_lower_index_and_nobody_loses() {
        assert!(CbaaAgent::beats((1.0, 2.0), (0.5, 0.0)));
        assert!(CbaaAgent::beats((1.0, 0.0), (1.0, 2.0)));
        assert!(!CbaaAgent::beats((1.0, 2.0), (1.0, 0.0)));
        assert!(CbaaAgent::beats(
            (f64::NEG_INFINITY, 3.0),
            (f64::NEG_INFINITY, NOBODY)
        ));
        assert!(!CbaaAgent::beats(
            (f64::NEG_INFINITY, NOBODY),
            (f64::NEG_INFINITY, NOBODY)
        ));
    }
}
