//! Market-based task allocation with strategic pricing (Liu & Shell, RSS 2013), run as a
//! consensus protocol on any connected graph: an optimal baseline.
//!
//! # The market
//! Tasks are goods with prices `p_t` (all 0 at first); robot `i` *demands* the tasks that
//! are cheapest for it at those prices, `D_i = argmin_t (c_it + p_t)`, and its surplus is
//! `u_i = min_t (c_it + p_t)`. The market clears when every robot can get one task it
//! demands, i.e. the *demand graph* (robot `i` — task `t` for `t ∈ D_i`) has a perfect
//! matching; that matching is then an optimal assignment (the prices and surpluses are dual
//! variables with complementary slackness: the LP optimality conditions). While it does not
//! clear, a maximum matching of the demand graph leaves robots unmatched, and the robots
//! reachable from them by alternating paths (Liu & Shell's *clique of customers* `S`)
//! demand only the too few tasks `N(S)`, `|N(S)| < |S|`. The merchant raises the prices of
//! `N(S)` by the smallest amount that makes some robot of `S` also demand a task outside,
//!
//! ```text
//! δ = min_{i ∈ S, t ∉ N(S)} (c_it + p_t − u_i)  > 0,
//! ```
//!
//! which keeps every matched edge demanded (the partners of `N(S)` are in `S`). Each raise
//! either opens an augmenting path or adds a robot to `S`, so at most `n` raises separate two
//! augmentations and the market clears after at most `n²` raises: the Hungarian method seen
//! as price escalation, exact (no bidding increment `ε` as in Bertsekas' auction).
//!
//! # Distributing it over a connected graph (our construction)
//! Liu & Shell run the merchant on a complete graph (every robot hears every demand); the
//! ADMM-TA paper notes it "was not amenable to arbitrary graphs". Here it is, on any
//! connected graph with diameter `D`, with no merchant and no robot ever revealing its costs:
//! the market state (prices, matching, clique) is *replicated*: every robot computes it from
//! the same data with the same deterministic rules, so all copies stay bit-identical. One
//! price raise takes `2D` rounds:
//!
//! 1. **Demand flood** (`D` rounds): every robot publishes its demand set (a bit row) and
//!    forwards the rows it learnt; after `D` rounds every robot holds the whole demand graph.
//!    Each then augments the previous matching to a maximum one (Kuhn's augmenting paths, in
//!    index order) and, if it is perfect, the market has cleared: the assignment is optimal
//!    and every robot knows it at the same round. Otherwise it finds `S` and `N(S)`.
//! 2. **Raise by min-consensus** (`D` rounds): each robot of `S` proposes its own
//!    `δ_i = min_{t ∉ N(S)} (c_it + p_t) − u_i` (robots outside `S`, `+∞`); after `D` rounds of
//!    taking minima, all hold `δ = min_i δ_i` and add it to the prices of `N(S)`.
//!
//! A robot only ever sends demand bits and one price increment, never a cost. The demand rows
//! are packed 48 bits per payload number (integers below `2⁵³` are exact in an `f64`), so the
//! payload is `n` row flags, `n ⌈n/48⌉` packed words and `δ`: `n + n⌈n/48⌉ + 1` numbers (151
//! for `n = 50`, against `nm = 2500` for the primal ADMM).
//!
//! **Case 2** (`n > m`): each robot extends its cost row with `n − m` "spare" columns priced
//! at its own cheapest cost, `min_t c_it`: a square `n × n` market whose optimum is the Case 2
//! optimum (the `m` real columns cover every task once; a robot on a spare column does its
//! cheapest task, which adds a robot to a covered task). Each robot extends its own row, so
//! nothing else changes.
//!
//! Demand uses a tolerance of `10⁻¹²` of the robot's cost range (so rounding in the price
//! sums never drops a matched edge); the assignment's cost is optimal to within `n` times
//! that.
//!
//! Size: one agent — the market, its distribution over the graph (both explained above) and
//! the matching and clique search of its replicated state; about 100 lines are its unit tests.

use crate::agent::{AgentAlgorithm, ConsensusAgent, Inbox, PayloadError, PayloadPart, StepReport};
use crate::method::info::{
    Certification, Fig2Graphs, Memory, MethodInfo, Numbers, OWN_STATE_STOPS, PaperFacts,
    ReportText, Role, TEAM_STATE, per_agent,
};
use crate::method::settings::NoSettings;
use crate::method::team::{AgentInit, TeamBuilder, TeamContext, TeamMethod, TeamParams};

/// Demand bits per payload number: integers up to `2⁴⁸` are exact in an `f64`.
const BITS_PER_WORD: usize = 48;
/// No partner in the matching.
const NONE: usize = usize::MAX;

/// Which half of a price raise the next step performs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Flooding demand rows: `k` flood steps done in this raise.
    Flood(usize),
    /// Min-consensus on the raise: `k` steps done.
    Raise(usize),
    /// The market has cleared: the matching is optimal.
    Cleared,
}

/// Robot `index`'s copy of the market.
pub struct MarketAgent {
    index: usize,
    robots: usize,
    tasks: usize,
    diameter: usize,
    /// Own costs, extended with the Case 2 spare columns (length `n`).
    costs: Vec<f64>,
    /// Demand tolerance.
    tight: f64,
    /// Replicated: prices of the `n` columns.
    prices: Vec<f64>,
    /// Replicated: the matching, column → robot and robot → column.
    owner: Vec<usize>,
    column_of: Vec<usize>,
    /// Replicated: the clique `S` (robots) and its demanded columns `N(S)` of this raise.
    in_clique: Vec<bool>,
    raised: Vec<bool>,
    phase: Phase,
    /// Payload being built: row flags, packed rows, δ.
    payload: Vec<f64>,
    /// Scratch of the matching search.
    visited: Vec<bool>,
    stack: Vec<(usize, usize)>,
    queue: Vec<usize>,
    /// Own relaxed column (indicator of the task it would do now).
    column: Vec<f64>,
}

impl MarketAgent {
    /// Robot `index` of `robots` with its own `costs` (one per task) on a graph of diameter
    /// `diameter` (at least 1 when `robots > 1`).
    /// Case 1 and 2 need no distinction: both are the same square market (spare columns when
    /// `n > m`).
    pub fn new(index: usize, costs: Vec<f64>, robots: usize, diameter: usize) -> Self {
        let tasks = costs.len();
        assert!(index < robots && tasks >= 1 && tasks <= robots);
        assert!(robots == 1 || diameter >= 1, "a team needs a diameter ≥ 1");
        let cheapest = costs.iter().copied().fold(f64::INFINITY, f64::min);
        let dearest = costs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut extended = costs;
        extended.resize(robots, cheapest);
        let mut agent = Self {
            index,
            robots,
            tasks,
            diameter,
            costs: extended,
            tight: 1e-12
                * (dearest - cheapest)
                    .max(dearest.abs())
                    .max(f64::MIN_POSITIVE),
            prices: vec![0.0; robots],
            owner: vec![NONE; robots],
            column_of: vec![NONE; robots],
            in_clique: vec![false; robots],
            raised: vec![false; robots],
            phase: Phase::Flood(0),
            payload: vec![0.0; Self::payload_len_for(robots)],
            visited: vec![false; robots],
            stack: Vec::with_capacity(2 * robots),
            queue: Vec::with_capacity(robots),
            column: vec![0.0; tasks],
        };
        agent.start_flood();
        if robots == 1 {
            // Alone: the whole demand graph is known already.
            agent.settle_demand_graph();
        }
        agent.refresh_column();
        agent
    }

    /// Payload length for a team of `robots`.
    pub fn payload_len_for(robots: usize) -> usize {
        robots + robots * robots.div_ceil(BITS_PER_WORD) + 1
    }

    /// Whether the market has cleared (the assignment is optimal).
    pub fn cleared(&self) -> bool {
        self.phase == Phase::Cleared
    }

    fn words(&self) -> usize {
        self.robots.div_ceil(BITS_PER_WORD)
    }

    fn delta_slot(&self) -> usize {
        self.payload.len() - 1
    }

    /// Demand bit of `(robot, column)` in the payload being built.
    fn demands(&self, robot: usize, column: usize) -> bool {
        let word = self.payload[self.robots + robot * self.words() + column / BITS_PER_WORD];
        (word as u64 >> (column % BITS_PER_WORD)) & 1 == 1
    }

    /// A new raise: only the own demand row is known.
    fn start_flood(&mut self) {
        let n = self.robots;
        let words = self.words();
        let surplus = self.surplus();
        self.payload.fill(0.0);
        self.payload[self.index] = 1.0;
        let row = n + self.index * words;
        for w in 0..words {
            let mut bits = 0u64;
            for b in 0..BITS_PER_WORD.min(n - w * BITS_PER_WORD) {
                let t = w * BITS_PER_WORD + b;
                if self.costs[t] + self.prices[t] <= surplus + self.tight {
                    bits |= 1 << b;
                }
            }
            self.payload[row + w] = bits as f64;
        }
        let delta = self.delta_slot();
        self.payload[delta] = f64::INFINITY;
        self.phase = Phase::Flood(0);
    }

    /// `u_i = min_t (c_it + p_t)`.
    fn surplus(&self) -> f64 {
        self.costs
            .iter()
            .zip(&self.prices)
            .map(|(c, p)| c + p)
            .fold(f64::INFINITY, f64::min)
    }

    /// With the whole demand graph known: drop matched edges no longer demanded, augment to a
    /// maximum matching, then either clear or find the clique and propose this robot's `δ_i`.
    fn settle_demand_graph(&mut self) {
        let n = self.robots;
        for r in 0..n {
            let c = self.column_of[r];
            if c != NONE && !self.demands(r, c) {
                self.column_of[r] = NONE;
                self.owner[c] = NONE;
            }
        }
        for r in 0..n {
            if self.column_of[r] == NONE {
                self.visited.fill(false);
                self.augment_from(r);
            }
        }
        if self.column_of.iter().all(|&c| c != NONE) {
            self.phase = Phase::Cleared;
            return;
        }
        // The clique: robots reachable from the unmatched ones by alternating paths.
        self.in_clique.fill(false);
        self.raised.fill(false);
        self.queue.clear();
        for r in 0..n {
            if self.column_of[r] == NONE {
                self.in_clique[r] = true;
                self.queue.push(r);
            }
        }
        let mut head = 0;
        while head < self.queue.len() {
            let r = self.queue[head];
            head += 1;
            for c in 0..n {
                if self.demands(r, c) && !self.raised[c] {
                    self.raised[c] = true;
                    let partner = self.owner[c];
                    // A maximum matching leaves no reachable column unmatched.
                    debug_assert!(partner != NONE);
                    if partner != NONE && !self.in_clique[partner] {
                        self.in_clique[partner] = true;
                        self.queue.push(partner);
                    }
                }
            }
        }
        let own = if self.in_clique[self.index] {
            let surplus = self.surplus();
            (0..n)
                .filter(|&c| !self.raised[c])
                .map(|c| self.costs[c] + self.prices[c] - surplus)
                .fold(f64::INFINITY, f64::min)
        } else {
            f64::INFINITY
        };
        let delta = self.delta_slot();
        self.payload[delta] = own;
        self.phase = Phase::Raise(0);
    }

    /// Kuhn's augmenting path from unmatched robot `root` (iterative DFS, columns in index
    /// order); flips the path if it reaches an unmatched column.
    fn augment_from(&mut self, root: usize) {
        self.stack.clear();
        self.stack.push((root, 0));
        while let Some(&(robot, start)) = self.stack.last() {
            let found = (start..self.robots).find(|&c| !self.visited[c] && self.demands(robot, c));
            if let Some(top) = self.stack.last_mut() {
                top.1 = found.map_or(self.robots, |c| c + 1);
            }
            let Some(c) = found else {
                self.stack.pop();
                continue;
            };
            self.visited[c] = true;
            let partner = self.owner[c];
            if partner == NONE {
                // Flip the path: each robot on the stack takes the column it went through.
                let mut column = c;
                while let Some((r, _)) = self.stack.pop() {
                    let previous = self.column_of[r];
                    self.column_of[r] = column;
                    self.owner[column] = r;
                    column = previous;
                }
                return;
            }
            self.stack.push((partner, 0));
        }
    }

    /// The task this robot would do now: its matched column (a spare column means its own
    /// cheapest task), or its cheapest demanded task while unmatched.
    fn chosen(&self) -> usize {
        let column = self.column_of[self.index];
        let column = if column == NONE {
            let surplus = self.surplus();
            (0..self.robots)
                .find(|&c| self.costs[c] + self.prices[c] <= surplus + self.tight)
                .unwrap_or(0)
        } else {
            column
        };
        if column < self.tasks {
            column
        } else {
            crate::certify::oracle::argmin(&self.costs[..self.tasks])
        }
    }

    fn refresh_column(&mut self) {
        let task = self.chosen();
        self.column.fill(0.0);
        self.column[task] = 1.0;
    }

    fn digest(&self) -> u64 {
        let cleared = u64::from(self.phase == Phase::Cleared);
        self.column_of
            .iter()
            .fold(0xcbf2_9ce4_8422_2325u64 ^ cleared, |h, &c| {
                (h ^ c as u64).wrapping_mul(0x0100_0000_01b3)
            })
    }
}

impl ConsensusAgent for MarketAgent {
    fn payload_len(&self) -> usize {
        self.payload.len()
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        out.copy_from_slice(&self.payload);
    }

    /// Row flags 0 or 1, packed words integers below `2⁴⁸`, the raise positive or `+∞`.
    fn check_payload(&self, payload: &[f64]) -> Result<(), PayloadError> {
        let n = self.robots;
        crate::agent::check_length(payload, self.payload.len())?;
        if let Some(r) = payload[..n].iter().position(|&f| f != 0.0 && f != 1.0) {
            return Err(PayloadError::BadValue {
                part: PayloadPart::at("row flag", r),
                value: payload[r],
            });
        }
        let words = &payload[n..payload.len() - 1];
        if let Some(w) = words
            .iter()
            .position(|&w| !(0.0..(1u64 << BITS_PER_WORD) as f64).contains(&w) || w.fract() != 0.0)
        {
            return Err(PayloadError::BadValue {
                part: PayloadPart::at("demand word", w),
                value: words[w],
            });
        }
        let delta = payload[payload.len() - 1];
        if delta.is_nan() || delta <= 0.0 {
            return Err(PayloadError::BadValue {
                part: PayloadPart::named("price raise"),
                value: delta,
            });
        }
        Ok(())
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        let n = self.robots;
        let words = self.words();
        for k in 0..inbox.len() {
            assert_eq!(
                inbox.payload(k).len(),
                self.payload.len(),
                "neighbour payload has the wrong length"
            );
        }
        let mut changed = false;
        match self.phase {
            Phase::Flood(done) => {
                for k in 0..inbox.len() {
                    let theirs = inbox.payload(k);
                    for r in 0..n {
                        if self.payload[r] == 0.0 && theirs[r] == 1.0 {
                            self.payload[r] = 1.0;
                            let row = n + r * words..n + (r + 1) * words;
                            self.payload[row.clone()].copy_from_slice(&theirs[row]);
                            changed = true;
                        }
                    }
                }
                if done + 1 == self.diameter {
                    debug_assert!(self.payload[..n].iter().all(|&f| f == 1.0));
                    self.settle_demand_graph();
                    changed = true;
                } else {
                    self.phase = Phase::Flood(done + 1);
                }
            }
            Phase::Raise(done) => {
                let slot = self.delta_slot();
                for k in 0..inbox.len() {
                    let theirs = inbox.payload(k)[slot];
                    if theirs < self.payload[slot] {
                        self.payload[slot] = theirs;
                        changed = true;
                    }
                }
                if done + 1 == self.diameter {
                    let delta = self.payload[slot];
                    debug_assert!(delta.is_finite() && delta > 0.0);
                    for c in 0..n {
                        if self.raised[c] {
                            self.prices[c] += delta;
                        }
                    }
                    self.start_flood();
                    changed = true;
                } else {
                    self.phase = Phase::Raise(done + 1);
                }
            }
            Phase::Cleared => {}
        }
        self.refresh_column();
        out.copy_from_slice(&self.payload);
        let cleared = self.phase == Phase::Cleared;
        StepReport {
            disagreement: if cleared { 0.0 } else { 1.0 },
            change: if changed { 1.0 } else { 0.0 },
            inner_iterations: 0,
            inner_converged: true,
            integrality_gap: 0.0,
            own_integrality_gap: 0.0,
            // Every robot holds the same replicated market state.
            assignment_digest: self.digest(),
        }
    }

    fn decide(&self) -> usize {
        self.chosen()
    }

    fn rounded_task(&self) -> usize {
        self.chosen()
    }

    /// 0 once the market has cleared (the matching is optimal), ∞ before.
    fn certificate_slack(&self) -> f64 {
        if self.phase == Phase::Cleared {
            0.0
        } else {
            f64::INFINITY
        }
    }

    fn own_column(&self) -> &[f64] {
        &self.column
    }
}

/// No penalty, one problem: the defaults.
impl AgentAlgorithm for MarketAgent {}

/// The market baseline's registration.
pub const INFO: MethodInfo = MethodInfo {
    name: "market",
    summary: "Liu & Shell's price-escalation market replicated over the graph: optimal, 2·diameter rounds per price raise, sends demand bits only",
    role: Role::Baseline,
    team: Some(&MarketMethod),
    variants: None,
    stops: OWN_STATE_STOPS,
    // The replicated market (prices, matching, clique, search scratch: about 10n), the own
    // column, and the payload being built plus two round buffers.
    memory: Memory {
        bytes: |n, m| {
            let payload = MarketAgent::payload_len_for(n);
            per_agent(n, (10 * n + m + 3 * payload) as f64)
        },
        of: TEAM_STATE,
        because: "each robot holds the team's demand bits",
    },
    certification: Certification::WhenFinished,
    numbers: Numbers::Normalised,
    report: ReportText { inner_steps: None },
    paper: Some(PaperFacts {
        label: "market",
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

/// The market as a team method.
pub struct MarketMethod;

impl TeamMethod for MarketMethod {
    type Settings = NoSettings;
    const PENALTY: bool = false;

    fn payload_len(&self, _: &NoSettings, robots: usize, _tasks: usize) -> usize {
        MarketAgent::payload_len_for(robots)
    }

    fn team<'a>(&'static self, _: &NoSettings, team: TeamContext<'a>) -> Box<dyn TeamBuilder + 'a> {
        Box::new(MarketTeam(team.params))
    }
}

struct MarketTeam(TeamParams);

impl TeamBuilder for MarketTeam {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        Box::new(MarketAgent::new(
            init.index,
            init.costs,
            init.robots,
            self.0.diameter,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};

    /// Runs a team in lockstep on `neighbours` until every robot's market clears; returns
    /// each robot's task.
    fn run(
        problem: &TaskAssignmentProblem,
        neighbours: &[Vec<usize>],
        diameter: usize,
    ) -> Vec<usize> {
        let n = problem.robots();
        let mut agents: Vec<MarketAgent> = (0..n)
            .map(|i| MarketAgent::new(i, problem.costs().row(i).to_vec(), n, diameter))
            .collect();
        let len = agents[0].payload_len();
        let mut payloads = vec![vec![0.0; len]; n];
        for (agent, payload) in agents.iter().zip(&mut payloads) {
            agent.write_initial_payload(payload);
        }
        let mut rounds = 0;
        while !agents.iter().any(MarketAgent::cleared) {
            assert!(rounds < 100_000, "the market did not clear");
            let mut next = vec![vec![0.0; len]; n];
            for (i, agent) in agents.iter_mut().enumerate() {
                let inbox: Vec<&[f64]> = neighbours[i].iter().map(|&j| &payloads[j][..]).collect();
                agent.step(&inbox, &mut next[i]);
            }
            payloads = next;
            rounds += 1;
        }
        assert!(
            agents.iter().all(MarketAgent::cleared),
            "robots cleared at different rounds"
        );
        agents.iter().map(MarketAgent::decide).collect()
    }

    fn complete(n: usize) -> Vec<Vec<usize>> {
        (0..n)
            .map(|i| (0..n).filter(|&j| j != i).collect())
            .collect()
    }

    fn chain(n: usize) -> Vec<Vec<usize>> {
        (0..n)
            .map(|i| {
                [i.checked_sub(1), (i + 1 < n).then_some(i + 1)]
                    .into_iter()
                    .flatten()
                    .collect()
            })
            .collect()
    }

    #[test]
    fn clears_at_the_optimum_on_complete_and_chain_graphs_case_1_and_2() {
        for seed in 0..20 {
            for (n, m) in [(6, 6), (9, 5), (12, 12)] {
                let costs = CostMatrix::uniform(n, m, seed).unwrap();
                let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
                let best = crate::certify::oracle::solve(&problem).unwrap().cost;
                for (graph, diameter) in [(complete(n), 1), (chain(n), n - 1)] {
                    let tasks = run(&problem, &graph, diameter);
                    assert!(
                        problem.is_feasible(&tasks),
                        "seed {seed} {n}x{m}: {tasks:?}"
                    );
                    let cost = problem.cost_of(&tasks).unwrap();
                    assert!(
                        (cost - best).abs() <= 1e-9,
                        "seed {seed} {n}x{m}: cost {cost} vs optimum {best}"
                    );
                }
            }
        }
    }

    #[test]
    fn ties_everywhere_still_clear() {
        // Every robot has the same costs: maximal degeneracy.
        let n = 7;
        let row: Vec<f64> = (0..n).map(|t| t as f64).collect();
        let costs = CostMatrix::new(n, n, row.repeat(n)).unwrap();
        let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        let tasks = run(&problem, &complete(n), 1);
        assert!(problem.is_feasible(&tasks), "{tasks:?}");
    }

    #[test]
    fn a_lone_robot_takes_its_cheapest_task_at_once() {
        let agent = MarketAgent::new(0, vec![3.0], 1, 0);
        assert!(agent.cleared());
        assert_eq!(agent.decide(), 0);
    }

    #[test]
    fn payload_packs_demand_rows() {
        let agent = MarketAgent::new(0, vec![0.5; 50], 50, 1);
        assert_eq!(agent.payload_len(), 50 + 50 * 2 + 1);
    }
}
