//! Dual consensus ADMM (Algorithm 2 of the paper) and its inexact, proximal-gradient
//! variant: one robot's state machine.
//!
//! # The problem the robots solve
//! The relaxed assignment is Problem 2 with `f_i(x) = α_iᵀx`, `x_i ∈ [0, 1]^m` and
//! * Case 1: `Σ_i A_i x_i = b` with `A_i = [M_i; I_m]`, `b = 1_{n+m}` (`M_i` has ones in
//!   row `i`): every robot one task, every task one robot;
//! * Case 2: `Σ_i M_i x_i = 1_n` and `Σ_i C_i x_i ≤ d` with `C_i = −I_m`, `d = −1_m`:
//!   every task at least one robot (docs/notes.md, note 8: `b = 1_n`, not `1_m`).
//!
//! Each robot keeps its own copy `y_i = (ν_i, λ_i)` of the multipliers (`n + m` numbers in
//! both cases: Case 1 has `n + m` equality prices, Case 2 `n` equality prices and `m`
//! coverage prices `λ ≥ 0`) and the robots agree on them by consensus ADMM on the dual
//! (10). **The payload is `y_i`**, not an `m × n` matrix; the robot's decision is its own
//! column `x_i ∈ [0, 1]^m` only.
//!
//! # The equations implemented (derived again from the augmented Lagrangian of (10))
//! With the neighbours' round-`k` multipliers `y_j^k` and `d = |N(i)|`:
//!
//! ```text
//! p_i^{k+1} = p_i^k + ρ Σ_{j∈N(i)} (y_i^k − y_j^k)                (12: q_i and r_i stacked)
//! κ_i       = −b̃/(ρn) − p_i^{k+1}/ρ + Σ_{j∈N(i)} (y_i^k + y_j^k)    (b̃ = b, and −d for λ rows)
//! θ_i(x)    = Ã_i x / ρ + κ_i                                      (Ã_i = A_i, or C_i for λ rows)
//! x_i^{k+1} = argmin_{0≤x≤1} α_iᵀx + ρ/(4d) ‖θ_ν(x)‖² + ρ/(4d) ‖max(θ_λ(x), 0)‖²     (15)
//! ν_i^{k+1} = θ_ν(x_i^{k+1}) / (2d)                                                    (13)
//! λ_i^{k+1} = max(θ_λ(x_i^{k+1}) / (2d), 0)                                            (14)
//! ```
//!
//! Minimising (11) over `ν` for fixed `x` gives (13) with value `−ρ/(4d)‖θ‖²`; over
//! `λ ≥ 0` it gives (14) with value `−ρ d ‖max(θ_λ/(2d), 0)‖²`, so the outer problem in `x`
//! is (15) with the `λ` part as a squared hinge. The paper instead writes `½ λ_iᵀC_i x`
//! with the previous `λ`: the ½ does not follow from the derivation (docs/notes.md, note 8) and
//! a linear term makes Case 2's x-update non-unique, so we keep the exact hinge, whose
//! gradient `C_iᵀ λ` is what the paper's term approximates. `θ` is as printed: its sum
//! holds the *previous* round's `y_i + y_j` (note 8). `b̃/n` splits the right-hand side
//! evenly over the robots.
//!
//! **The exact x-update needs no QP.** Only one row of `A_i x` couples the entries
//! (`1ᵀx`, robot `i`'s own row). With `τ = 1ᵀx + ρ κ_{i,i}`, the KKT conditions of (15)
//! separate: `x_t(τ) = clip(c_t − τ, 0, 1)` in Case 1 (`c_t = −2dρα_t − ρκ_{n+t}`), and in
//! Case 2 `x_t(τ) = 1` for `τ < −2dρα_t`, `clip(ρκ_{n+t} − 2dρα_t − τ, 0, 1)` above (a
//! jump where the hinge switches off). `τ − ρκ_{i,i} − Σ_t x_t(τ) = 0` is increasing in `τ`
//! and piecewise linear with at most `3m` breakpoints in `[ρκ_{i,i}, ρκ_{i,i} + m]`: a sort
//! and a binary search find the exact root
//! ([`crate::methods::dual::coupled_box::solve_coupled_box`]).
//!
//! **Inexact dual** replaces (15) by one projected gradient step from `x^k` with the
//! proximal weight `γ_i` (the paper's closed-form clipped update, with the full gradient):
//!
//! ```text
//! x_i^{k+1} = clip( x_i^k − (α_i + A_iᵀθ_ν(x_i^k)/(2d) + C_iᵀ max(θ_λ(x_i^k), 0)/(2d)) / γ_i, 0, 1 )
//! ```
//!
//! The gradient's Lipschitz constant is `(m + 1)/(2dρ)`; we use
//! `γ_i = g (m + 1)/(2 d ρ)` with `g` = [`DEFAULT_GAMMA_FACTOR`] (measured, see that constant).
//!
//! **Forbidden pairs are bounds.** A robot's forbidden task `t` has `x_t = 0` in its own
//! problem (both updates, the rounding and the certificate leave it out), so the multipliers
//! never have to climb to the normalised penalty (with the penalty instead, sparse 40 × 40
//! matrices with 85% of the pairs forbidden ended at the round limit, repaired and not
//! optimal; as bounds both dual methods certify them in 300–2100 rounds). The costs are
//! centred on the allowed ones.
//!
//! # Certificate for the decentralized stop
//! A robot sees only its own column, so it cannot check the team's assignment; the dual
//! gives a different certificate. Let `π` be the robots' rounded tasks and `ȳ` any common
//! multiplier. Weak duality with the box (and the forbidden bounds) kept in the Lagrangian
//! gives `cost(π) − OPT ≤ Σ_i s_i(ȳ) + Σ_t λ̄_t (cover_t − 1)` for a feasible `π`, with the
//! local reduced-cost slack `s_i(y) = r_{π_i} − Σ_t min(0, r_t)` over allowed `t`,
//! `r_t = α_t + (Ã_iᵀ y)_t`.
//! * **Feasibility, locally:** the `p_i` sum to zero over the team (every edge adds
//!   `±ρ(y_i − y_j)`), so the local residuals `w_i = Ã_i e_{π_i} − b̃/n − p_i` sum to the team's
//!   constraint residual. They are integers plus zero, so if every robot sees
//!   `|w_i| ≤ 1/(2n)` on its equality rows (and `w_i ≤ 1/(2n)` on coverage rows), the
//!   team's `π` is exactly feasible. At a fixed point `w_i = A_i (e_{π_i} − x_i)`, so this
//!   holds once the robots' columns are near integral.
//! * **Own price free:** robot `i`'s price `ν̄_i` enters `s_i` alone, so the bound takes
//!   the best one, `ν̄_i = −r_π − R` below; only the task prices must be common.
//! * **Disagreement, by level:** every robot requires its largest neighbour disagreement on
//!   the task rows `δ_i ≤ δ*`, so every task price is within `R = D δ*` of `ȳ = y_c` (`D`
//!   the diameter). In Case 2 a task covered more than once has `Σ_i w_{i,t} ≤ −1`, so
//!   some robot sees `w_t < −1/(2n)`, which its check allows only where its `λ_t = 0`:
//!   every robot's `λ_t` is then within `R` of 0, and `ȳ` takes `λ̄_t = 0` there, so the
//!   coverage term vanishes. Over that ball `s_i ≤ Σ_{t≠π} max(0, r_π − r_t + 2R)`: zero
//!   when the robot's own task beats every other by `2R` at its own prices.
//!   `δ*` is a ladder the robots sweep together, one rung per round, coarse to fine
//!   ([`LEVELS`] rungs, [`LEVEL_STEP`] apart, the finest `tol / (8 n D)`): a team whose
//!   prices separate the optimum by a wide margin certifies at a coarse rung long before its
//!   multipliers agree to `tol`, and near-ties still certify at the finest.
//!
//! Each robot reports that bound as its certificate slack (∞ when a check fails); if every
//! robot's is at most `tol / n`, the team's assignment is within `tol` of the optimum — the
//! same contract as the primal's, so the same decentralized stop protocol runs on it, every
//! round (all robots are on the same rung at the same round).
//!
//! Size: one agent — the equations it implements, derived in these docs, and its exact and
//! inexact x-updates and certificate, which share its private state; about 140 lines are its
//! unit tests.

use crate::agent::{AgentAlgorithm, ConsensusAgent, Inbox, StepReport};
use crate::methods::dual::column;
use crate::methods::dual::coupled_box::solve_coupled_box;
use crate::problem::AssignmentCase;

/// The proximal weight factor `g` of the inexact dual: `γ = g (m+1)/(2dρ)` (`g = 1` is the
/// gradient's Lipschitz constant). Measured with `runtime/examples/dual_tuning.rs`, uniform
/// costs, complete graphs, ρ factor 10, 20 seeds — rounds to within 0.1% / optimal
/// assignment / certificate at 20×20: g = 0.15: 156 / 201 / 467, 0.3: 128 / 207 / 508,
/// 0.5: 143 / 258 / 708, 1.0: 161 / 279 / 812 (smaller is faster on average); but g = 0.15
/// diverged on the 5×5 oracle instance and on a random 8×8 one, g = 0.2 on the 5×5 too,
/// and g = 0.05 on every 20×20 instance. We take 0.5: over 1.6× away from every
/// divergence seen, at about 15% more rounds than 0.3.
pub const DEFAULT_GAMMA_FACTOR: f64 = 0.5;

/// How the x-update (15) is carried out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DualUpdate {
    /// Exact minimisation of (15) (Algorithm 2).
    Exact,
    /// One proximal-gradient step with weight `γ = gamma_factor · (m + 1)/(2 d ρ)`.
    Inexact { gamma_factor: f64 },
}

/// Parameters of one dual agent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualParams {
    /// ρ (the fast variant's `ρ₀`, from which its ρ grows).
    pub rho: f64,
    pub update: DualUpdate,
    /// Graph diameter: the paper variant's disagreement term, the fast one's snapshot
    /// period.
    pub diameter: usize,
    /// Total cost tolerance of the certificate (the decentralized stop's).
    pub tolerance: f64,
}

/// Robot `index`'s dual consensus ADMM state.
pub struct DualAgent {
    index: usize,
    tasks: usize,
    robots: usize,
    degree: usize,
    case: AssignmentCase,
    settings: DualParams,
    /// Own costs `α_i`, centred (minus their mean).
    costs: Vec<f64>,
    /// Own multipliers of the current round (the payload), `n` robot rows then `m` task rows.
    y: Vec<f64>,
    /// Accumulated consensus multipliers `p_i` (`q_i` and `r_i` stacked).
    p: Vec<f64>,
    /// `κ_i` of the current step.
    kappa: Vec<f64>,
    /// Own relaxed column `x_i`.
    x: Vec<f64>,
    /// Which of its tasks the robot may take: a forbidden pair is the bound `x_t = 0` of
    /// its own problem, not a penalty its multipliers must climb to.
    allowed: Vec<bool>,
    /// Scratch of the exact x-update.
    breakpoints: Vec<f64>,
    task: usize,
    slack: f64,
    /// Steps taken: the certificate's disagreement level is a schedule of the round, the
    /// same at every robot.
    steps: u64,
}

impl DualAgent {
    /// Robot `index` of `robots`, with its own costs `α_i`, `degree = |N(i)|`.
    pub fn new(
        index: usize,
        costs: Vec<f64>,
        robots: usize,
        case: AssignmentCase,
        degree: usize,
        settings: DualParams,
    ) -> Self {
        let tasks = costs.len();
        assert!(index < robots && tasks >= 1 && robots >= tasks);
        assert!(
            settings.rho > 0.0 && settings.rho.is_finite(),
            "ρ must be positive"
        );
        if let DualUpdate::Inexact { gamma_factor } = settings.update {
            assert!(
                gamma_factor > 0.0 && gamma_factor.is_finite(),
                "γ must be positive"
            );
        }
        // Each robot does exactly one task, so subtracting a constant from its own costs
        // changes every assignment's cost by the same amount: centring them makes the
        // iterates independent of cost shifts (as the primal's are), using only own data.
        let allowed = vec![true; tasks];
        let costs = column::centred(&costs, &allowed);
        let len = robots + tasks;
        Self {
            index,
            tasks,
            robots,
            degree,
            case,
            settings,
            costs,
            y: vec![0.0; len],
            p: vec![0.0; len],
            kappa: vec![0.0; len],
            x: vec![0.0; tasks],
            allowed,
            breakpoints: Vec::with_capacity(3 * tasks + 2),
            task: 0,
            slack: f64::INFINITY,
            steps: 0,
        }
    }

    /// The same robot with the pairs `allowed[t] == false` forbidden: bounds `x_t = 0` of
    /// its own problem (and out of its certificate and rounding). Its costs are centred on
    /// the allowed ones. At least one task must be allowed.
    pub fn with_allowed(mut self, allowed: Vec<bool>) -> Self {
        // Centred on the allowed costs (a shift of the robot's own costs again).
        self.costs = column::centred(&self.costs, &allowed);
        self.allowed = allowed;
        self
    }

    /// Own relaxed assignment vector `x_i`.
    pub fn column(&self) -> &[f64] {
        &self.x
    }

    /// Own multipliers `(ν_i, λ_i)` of the current round.
    pub fn multipliers(&self) -> &[f64] {
        &self.y
    }

    /// The proximal weight `γ_i` (inexact update only).
    pub fn gamma(&self) -> Option<f64> {
        match self.settings.update {
            DualUpdate::Exact => None,
            DualUpdate::Inexact { gamma_factor } => Some(
                gamma_factor * (self.tasks + 1) as f64
                    / (2.0 * self.degree.max(1) as f64 * self.settings.rho),
            ),
        }
    }

    /// Changes ρ from the next step on (every robot at the same round). `p` is kept
    /// unscaled (`p += ρ Σ (y_i − y_j)`), so it needs no rescaling.
    pub fn set_rho(&mut self, rho: f64) {
        assert!(rho > 0.0 && rho.is_finite(), "ρ must be positive");
        self.settings.rho = rho;
    }

    /// `b̃_c / n` of row `c`: `1/n` for equality rows, `−1/n` for Case 2 coverage rows.
    fn rhs(&self, c: usize) -> f64 {
        let sign = if c >= self.robots && self.case == AssignmentCase::Two {
            -1.0
        } else {
            1.0
        };
        sign / self.robots as f64
    }

    /// `(Ã_i x)_c` for a task row `c = n + t`.
    fn task_row(&self, x_t: f64) -> f64 {
        match self.case {
            AssignmentCase::One | AssignmentCase::Idle => x_t,
            AssignmentCase::Two => -x_t,
        }
    }

    /// Updates `p`, forms `κ`; returns the neighbour disagreement of the round's `y`, over
    /// every row and over the task rows alone.
    fn accumulate(&mut self, inbox: &dyn Inbox) -> (f64, f64) {
        let rho = self.settings.rho;
        let has_neighbours = !inbox.is_empty();
        let degree = inbox.len().max(1) as f64;
        let mut disagreement: f64 = 0.0;
        let mut task_disagreement: f64 = 0.0;
        let n = self.robots;
        self.kappa.fill(0.0);
        for k in 0..inbox.len() {
            let theirs = inbox.payload(k);
            assert_eq!(
                theirs.len(),
                self.y.len(),
                "neighbour payload has the wrong length"
            );
            for ((sum, mine), v) in self.kappa.iter_mut().zip(&self.y).zip(theirs) {
                *sum += v;
                disagreement = disagreement.max((mine - v).abs());
            }
            for (mine, v) in self.y[n..].iter().zip(&theirs[n..]) {
                task_disagreement = task_disagreement.max((mine - v).abs());
            }
        }
        if !has_neighbours {
            // A lone robot (n = 1) is its own neighbour, as in the primal agent.
            self.kappa.copy_from_slice(&self.y);
        }
        for c in 0..self.y.len() {
            let neighbour_sum = self.kappa[c];
            self.p[c] += rho * (degree * self.y[c] - neighbour_sum);
            self.kappa[c] =
                -self.rhs(c) / rho - self.p[c] / rho + degree * self.y[c] + neighbour_sum;
        }
        (disagreement, task_disagreement)
    }

    /// Gradient of (15)'s objective at `x` for task `t`, given `θ` of the own robot row.
    fn gradient(&self, t: usize, theta_own: f64) -> f64 {
        let two_d = 2.0 * self.degree.max(1) as f64;
        let c = self.robots + t;
        let theta_t = self.task_row(self.x[t]) / self.settings.rho + self.kappa[c];
        match self.case {
            AssignmentCase::One | AssignmentCase::Idle => {
                self.costs[t] + (theta_own + theta_t) / two_d
            }
            AssignmentCase::Two => self.costs[t] + theta_own / two_d - theta_t.max(0.0) / two_d,
        }
    }

    fn update_x(&mut self) {
        let rho = self.settings.rho;
        let two_d_rho = 2.0 * self.degree.max(1) as f64 * rho;
        let base = rho * self.kappa[self.index];
        match self.settings.update {
            DualUpdate::Exact => {
                let n = self.robots;
                let (costs, kappa, allowed) = (&self.costs, &self.kappa, &self.allowed);
                let response = |t: usize| match self.case {
                    // A forbidden pair: `x_t = 0` whatever `τ`.
                    _ if !allowed[t] => (f64::NEG_INFINITY, f64::NEG_INFINITY),
                    AssignmentCase::One | AssignmentCase::Idle => (
                        f64::NEG_INFINITY,
                        -two_d_rho * costs[t] - rho * kappa[n + t],
                    ),
                    AssignmentCase::Two => (
                        -two_d_rho * costs[t],
                        rho * kappa[n + t] - two_d_rho * costs[t],
                    ),
                };
                solve_coupled_box(
                    base,
                    self.tasks,
                    response,
                    &mut self.breakpoints,
                    &mut self.x,
                );
            }
            DualUpdate::Inexact { .. } => {
                let gamma = self.gamma().expect("inexact update has γ");
                let theta_own = self.x.iter().sum::<f64>() / rho + self.kappa[self.index];
                for t in 0..self.tasks {
                    self.x[t] = if self.allowed[t] {
                        let g = self.gradient(t, theta_own);
                        (self.x[t] - g / gamma).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                }
            }
        }
    }

    /// Writes `y^{k+1}` from `x^{k+1}` by (13) and (14).
    fn write_multipliers(&self, out: &mut [f64]) {
        let rho = self.settings.rho;
        let two_d = 2.0 * self.degree.max(1) as f64;
        let n = self.robots;
        for (c, o) in out.iter_mut().enumerate().take(n) {
            *o = self.kappa[c] / two_d;
        }
        out[self.index] += self.x.iter().sum::<f64>() / rho / two_d;
        for t in 0..self.tasks {
            let theta = self.task_row(self.x[t]) / rho + self.kappa[n + t];
            out[n + t] = match self.case {
                AssignmentCase::One | AssignmentCase::Idle => theta / two_d,
                AssignmentCase::Two => (theta / two_d).max(0.0),
            };
        }
    }

    /// The certificate slack of the module docs for the round-`k` multipliers `prices`
    /// (whose largest neighbour disagreement on the task rows is `task_disagreement`), the
    /// new rounded task and `p^{k+1}`, at the disagreement level `level`.
    fn certificate(&self, prices: &[f64], task_disagreement: f64, level: f64) -> f64 {
        let n = self.robots;
        if task_disagreement > level || !self.feasible(prices) {
            return f64::INFINITY;
        }
        let radius = self.settings.diameter as f64 * level;
        // Reduced costs without the own robot price, which the bound picks freely.
        let reduced = |t: usize| match self.case {
            AssignmentCase::One | AssignmentCase::Idle => self.costs[t] + prices[n + t],
            AssignmentCase::Two => self.costs[t] - prices[n + t],
        };
        // Worst case over every common task price within `radius` of ours.
        let own = reduced(self.task);
        (0..self.tasks)
            .filter(|&t| t != self.task && self.allowed[t])
            .map(|t| (own - reduced(t) + 2.0 * radius).max(0.0))
            .sum()
    }

    /// The team's rounded assignment is feasible as far as this robot can tell: its local
    /// residuals `w_i` are within `1/(2n)` (see the module docs).
    fn feasible(&self, prices: &[f64]) -> bool {
        let n = self.robots;
        let limit = 0.5 / n as f64;
        for (c, &price) in prices.iter().enumerate() {
            let a = if c == self.index || c == n + self.task {
                if c >= n { self.task_row(1.0) } else { 1.0 }
            } else {
                0.0
            };
            let w = a - self.rhs(c) - self.p[c];
            if c >= n && self.case == AssignmentCase::Two {
                if w > limit || (price > 0.0 && w < -limit) {
                    return false;
                }
            } else if w.abs() > limit {
                return false;
            }
        }
        true
    }

    /// The neighbour disagreement every robot must be within at step `step`: a ladder of
    /// [`LEVELS`] levels from `tolerance / (8 n D)` (where the bound alone certifies a
    /// tolerance-optimal assignment) up by factors of [`LEVEL_STEP`], swept from the top
    /// every [`LEVELS`] steps. Every robot takes the same level at the same step.
    fn level(&self, step: u64) -> f64 {
        let d = self.settings.diameter.max(1) as f64;
        let finest = self.settings.tolerance / (8.0 * self.robots as f64 * d);
        let rung = LEVELS - 1 - (step % LEVELS);
        finest * LEVEL_STEP.powi(rung as i32)
    }
}

/// Rungs of the certificate's disagreement ladder.
pub const LEVELS: u64 = 8;
/// Ratio of two rungs.
pub const LEVEL_STEP: f64 = 16.0;

impl ConsensusAgent for DualAgent {
    fn payload_len(&self) -> usize {
        self.y.len()
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        out.copy_from_slice(&self.y);
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        debug_assert_eq!(inbox.len(), self.degree, "inbox does not match the degree");
        let (disagreement, task_disagreement) = self.accumulate(inbox);
        self.update_x();
        self.write_multipliers(out);
        self.task = column::round(&self.x, &self.allowed);
        let level = self.level(self.steps);
        self.steps += 1;
        self.slack = self.certificate(&self.y, task_disagreement, level);
        let report = column::report(&self.x, self.task, disagreement, out, &self.y);
        self.y.copy_from_slice(out);
        report
    }

    fn decide(&self) -> usize {
        self.task
    }

    fn rounded_task(&self) -> usize {
        self.task
    }

    fn certificate_slack(&self) -> f64 {
        self.slack
    }

    fn own_column(&self) -> &[f64] {
        &self.x
    }
}

impl AgentAlgorithm for DualAgent {
    fn set_rho(&mut self, rho: f64) {
        DualAgent::set_rho(self, rho);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admm_ta_topologies::rng::SeededRng;

    /// (15)'s objective for robot 0 of a small team at its current κ.
    fn subproblem(agent: &DualAgent, x: &[f64]) -> f64 {
        let rho = agent.settings.rho;
        let d = agent.degree as f64;
        let n = agent.robots;
        let mut value: f64 = x.iter().zip(&agent.costs).map(|(a, b)| a * b).sum();
        let s: f64 = x.iter().sum();
        let mut theta2 = 0.0;
        for c in 0..n {
            let row = if c == agent.index { s } else { 0.0 };
            theta2 += (row / rho + agent.kappa[c]).powi(2);
        }
        for (t, xt) in x.iter().enumerate() {
            let theta = agent.task_row(*xt) / rho + agent.kappa[n + t];
            theta2 += match agent.case {
                AssignmentCase::One | AssignmentCase::Idle => theta * theta,
                AssignmentCase::Two => theta.max(0.0).powi(2),
            };
        }
        value += rho / (4.0 * d) * theta2;
        value
    }

    /// A forbidden pair is a bound `x_t = 0` of the robot's own problem: neither update puts
    /// weight on it, the robot never rounds to it, and its costs are centred on the allowed ones.
    #[test]
    fn forbidden_pairs_are_bounds() {
        let mut rng = SeededRng::new(3);
        for update in [DualUpdate::Exact, DualUpdate::Inexact { gamma_factor: 0.5 }] {
            let settings = DualParams {
                rho: 0.7,
                update,
                diameter: 1,
                tolerance: 1e-9,
            };
            // The cheapest task (0) is forbidden.
            let costs = vec![-5.0, 1.0, 2.0, 3.0];
            let allowed = vec![false, true, true, true];
            let mut agent =
                DualAgent::new(0, costs, 4, AssignmentCase::One, 2, settings).with_allowed(allowed);
            assert_eq!(agent.costs, [0.0, -1.0, 0.0, 1.0]);
            for _ in 0..50 {
                let theirs: Vec<Vec<f64>> = (0..2)
                    .map(|_| (0..8).map(|_| 2.0 * rng.uniform() - 1.0).collect())
                    .collect();
                let inbox: Vec<&[f64]> = theirs.iter().map(Vec::as_slice).collect();
                let mut out = vec![0.0; 8];
                agent.step(&inbox, &mut out);
                assert_eq!(agent.x[0], 0.0, "{update:?}: {:?}", agent.x);
                assert_ne!(agent.rounded_task(), 0, "{update:?}");
            }
        }
    }

    #[test]
    fn exact_update_minimises_the_subproblem() {
        let mut rng = SeededRng::new(5);
        for (case, robots, tasks) in [(AssignmentCase::One, 4, 4), (AssignmentCase::Two, 5, 3)] {
            for trial in 0..50 {
                let settings = DualParams {
                    rho: 0.5 + rng.uniform(),
                    update: DualUpdate::Exact,
                    diameter: 1,
                    tolerance: 1e-9,
                };
                let costs = (0..tasks).map(|_| rng.uniform()).collect();
                let mut agent = DualAgent::new(0, costs, robots, case, 2, settings);
                // Arbitrary state: random own and neighbour multipliers.
                for v in agent.y.iter_mut().chain(agent.p.iter_mut()) {
                    *v = 2.0 * rng.uniform() - 1.0;
                }
                let theirs: Vec<Vec<f64>> = (0..2)
                    .map(|_| {
                        (0..robots + tasks)
                            .map(|_| 2.0 * rng.uniform() - 1.0)
                            .collect()
                    })
                    .collect();
                let inbox: Vec<&[f64]> = theirs.iter().map(Vec::as_slice).collect();
                agent.accumulate(&inbox);
                agent.update_x();
                // (15)'s objective is convex and C¹ (the hinge is squared): the KKT
                // conditions of the box are necessary and sufficient.
                let theta_own =
                    agent.x.iter().sum::<f64>() / agent.settings.rho + agent.kappa[agent.index];
                let scale = agent.settings.rho.recip().max(1.0);
                for t in 0..tasks {
                    let g = agent.gradient(t, theta_own);
                    let x = agent.x[t];
                    let ok = if x <= 0.0 {
                        g >= -1e-9 * scale
                    } else if x >= 1.0 {
                        g <= 1e-9 * scale
                    } else {
                        g.abs() <= 1e-9 * scale
                    };
                    assert!(
                        ok,
                        "{case:?} trial {trial}: KKT fails at {t}: x {x}, gradient {g}"
                    );
                }
                let best = subproblem(&agent, &agent.x);
                for _ in 0..200 {
                    let probe: Vec<f64> = agent
                        .x
                        .iter()
                        .map(|v| (v + 0.2 * (rng.uniform() - 0.5)).clamp(0.0, 1.0))
                        .collect();
                    let value = subproblem(&agent, &probe);
                    assert!(
                        value >= best - 1e-10,
                        "{case:?} trial {trial}: {value} < {best} at {probe:?} vs {:?}",
                        agent.x
                    );
                }
            }
        }
    }
}
