//! The fast variant of the dual methods (the default; `--dual-variant paper` runs
//! Algorithm 2 as published, [`crate::methods::dual::agent`]).
//!
//! Three changes, each measured in bench/README.md ("The dual methods, second pass"):
//!
//! * **A robot's "one task" row is its own constraint.** In the paper every robot keeps a
//!   copy of all `n + m` multipliers, but the robot rows `Σ_t x_{i,t} = 1` involve robot `i`
//!   alone; their consensus only spreads, slowly, what robot `i` knows already. Here
//!   `x_i` lives on the allowed simplex `{x ∈ [0, 1]^m : Σ_t x_t = 1, x_t = 0 forbidden}` and
//!   the robots agree on the `m` task multipliers only (Case 1: equality prices; Case 2:
//!   coverage prices `λ ≥ 0`). The equations of [`crate::methods::dual::agent`] with the
//!   robot rows removed:
//!
//!   ```text
//!   p_i  += ρ Σ_{j∈N(i)} (y_i − y_j)
//!   κ_i   = −b̃/(ρn) − p_i/ρ + Σ_{j∈N(i)} (y_i + y_j)
//!   x_i   = argmin_{x ∈ simplex} α_iᵀx + ρ/(4d) ‖θ(x)‖²    (Case 2: the squared hinge)
//!   y_i   = θ(x_i)/(2d)                                      (Case 2: max(·, 0))
//!   ```
//!
//!   with `θ(x) = ±x/ρ + κ_i`. The exact update is a root of `Σ_t x_t(τ) = 1` with the
//!   same per-entry responses as the paper's ([`solve_simplex_box`]); the inexact one is a
//!   gradient step projected onto the simplex with `γ = g/(2dρ)` (the gradient's Lipschitz
//!   constant is `1/(2dρ)` without the robot row). In Case 1 the quadratic is separable
//!   with exactly that curvature, so with `g = 1` (its default) the step *is* the exact
//!   minimiser: with one ρ rule for both (`ρ₀` from the costs' structure,
//!   [`crate::methods::dual::structure_factor`]) the two methods run the same iterates in
//!   Case 1; Case 2's hinge keeps them apart.
//! * **A certificate that needs no agreement** ([`crate::methods::dual::snapshot`]): the
//!   team's claims are flooded in snapshots, and common prices that price them are computed
//!   beside the multipliers by a distributed Bellman–Ford (a min-flood with each robot
//!   relaxing its own constraints). The paper variant's certificate needs the multipliers
//!   to agree within a margin and each robot's consensus residual to round to its task;
//!   here the certificate fires a few rounds after the claims of an optimal assignment
//!   settle, whatever the multipliers.
//! * **Relaxed, with a growing ρ.** The consensus step is over-relaxed
//!   (Eckstein–Bertsekas relaxation of the edge variables, [`RELAXATION`]; in this
//!   decentralized form only their sum per robot is kept), and ρ grows from a small `ρ₀`
//!   by [`RHO_GROWTH`] a round up to [`RHO_MAX_GROWTH`] `ρ₀` (every robot from the round
//!   number alone). `ρ₀` is, for both methods, a tenth of the paper variant's dual rule
//!   (`c = 5`) times a factor from the costs' structure: 3 for independent costs, ½ for
//!   distance-like ones (less for large teams), 1 where it is unclear
//!   ([`crate::methods::dual::structure_factor`]).
//!
//! * **An augmenting finish** (Case 1, [`crate::methods::dual::finish`]): when the
//!   claims leave tasks claimed twice and tasks claimed by nobody, the robots compute
//!   shortest augmenting paths on the frozen claims beside the iteration and move whole
//!   chains at once; a full assignment comes with prices that the certificate starts from.
//!   1000 × 1000 uniform, `random:0.02`, seeds 1 / 2: 1824 / 3601 rounds to the certified
//!   stop without it, 657 / 793 with it (bench/README.md). Owners on a negative cycle
//!   of the frozen claims move round it, so a standing team's warm episode, which starts
//!   from the last optimum, runs the finish too ([`Finish::restart`]).
//!
//! * **Multipliers on a grid of 12 fraction bits** ([`MULTIPLIER_BITS`]): what a robot
//!   sends and keeps, so that over a network, where messages are coded against the
//!   sender's last, a changed multiplier costs 3–4 bytes; the rounds did not change.
//!
//! The payload is `m` multipliers and the certificate's `m` potentials and `m` claims,
//! several claims packed into one value ([`snapshot::claims_per_word`]: 7 for 100
//! robots): `2m + ⌈m/k⌉`, 215 values at 100 × 100 (the paper's is `n + m`); the finish
//! adds its `m` tags packed alike and three values, its window, alarm and bound (its
//! moves travel in the potentials' place while it computes labels): 233 at 100 × 100. Teams of more
//! robots than tasks carry that section too, as zeros: a standing team's episode with
//! robots away may be a Case 1 problem inside the team's messages.
//!
//! Size: one agent — its equations, both x-updates and the step share its private state;
//! about 150 lines are its unit tests.

use crate::agent::{
    AgentAlgorithm, ConsensusAgent, Inbox, NewCostsError, PayloadError, PayloadPart, StepReport,
    first_not_finite,
};
use crate::methods::dual::agent::{DualParams, DualUpdate};
use crate::methods::dual::column;
use crate::methods::dual::coupled_box::solve_simplex_box;
use crate::methods::dual::finish::{self, Finish};
use crate::methods::dual::snapshot::{self, Snapshot};
use crate::methods::rho::RhoSchedule;
use crate::problem::AssignmentCase;

/// Over-relaxation `α` of the consensus step (relaxed ADMM converges for `α ∈ (0, 2)`).
/// 50×50 complete, uniform costs, seeds 1–3, rounds to the certified stop: α = 1 / 1.5 /
/// 1.8: 325 / 230 / 213 (distance costs 704 / 615 / 552).
pub const RELAXATION: f64 = 1.8;

/// ρ grows by this factor every round, from `ρ₀` …
pub const RHO_GROWTH: f64 = 1.01;
/// … up to this many times `ρ₀`. A small ρ lets the prices move fast while the robots'
/// responses are soft; a large one sharpens the responses and pulls the copies together.
pub const RHO_MAX_GROWTH: f64 = 300.0;

/// Values of a fast dual message for `robots` robots and `tasks` tasks.
pub const fn payload_len(robots: usize, tasks: usize) -> usize {
    tasks + snapshot::words(robots, tasks) + finish::words(robots, tasks)
}

/// Fraction bits of the multipliers a robot sends and keeps (of an `f64`'s 52): a relative
/// precision of `2⁻¹³`. The certificate and the finish compute from the costs, so the
/// multipliers' precision only paces the iteration. With 12 bits every one-shot case of
/// the suite in bench/README.md took the same rounds as with 52 (rings, 50 × 50 uniform
/// and distance, 200 × 200, integer and forbidden costs; 6 bits too), and over Zenoh, whose
/// messages are coded against the sender's last (the transport crate's `exchange::codec`),
/// a multiplier that changed costs 3–4 bytes instead of 7–9.
pub const MULTIPLIER_BITS: u32 = 12;

/// `value` rounded to [`MULTIPLIER_BITS`] fraction bits (to nearest, halves away from 0);
/// an infinite or NaN value as it is, and a value that would round past `f64::MAX`.
pub fn round_multiplier(value: f64) -> f64 {
    const DROPPED: u32 = 52 - MULTIPLIER_BITS;
    if !value.is_finite() {
        return value;
    }
    // Finite: the sign bit is not carried into, so the addition cannot overflow.
    let rounded = f64::from_bits((value.to_bits() + (1 << (DROPPED - 1))) & (u64::MAX << DROPPED));
    if rounded.is_finite() { rounded } else { value }
}

/// Robot `index`'s state of the fast dual variant.
pub struct FastDualAgent {
    tasks: usize,
    robots: usize,
    degree: usize,
    case: AssignmentCase,
    params: DualParams,
    /// Own costs, centred on the allowed ones (a shift of the robot's own costs changes
    /// every assignment's cost alike).
    costs: Vec<f64>,
    allowed: Vec<bool>,
    /// Own task multipliers of the current round (the first `m` values of the payload).
    y: Vec<f64>,
    /// Accumulated consensus multipliers.
    p: Vec<f64>,
    kappa: Vec<f64>,
    /// `Σ_j z_ij`, the sum of the robot's relaxed edge variables.
    edges: Vec<f64>,
    /// The ρ of the current step.
    rho: f64,
    /// Own relaxed column `x_i` on the allowed simplex.
    x: Vec<f64>,
    /// The inexact update's gradient step before its projection.
    step_point: Vec<f64>,
    /// Scratch of the simplex root.
    breakpoints: Vec<f64>,
    snapshot: Snapshot,
    /// Case 1's augmenting finish: it may freeze or move the robot's claim.
    finish: Finish,
    task: usize,
    slack: f64,
    /// Steps since the agent's ρ schedule started.
    steps: u64,
    /// Steps since its costs were last set (the certificate's round numbers).
    episode_steps: u64,
    /// It relays for the team: no column of its own (`x ≡ 0`), no share of the task rows'
    /// right-hand side, no claim ([`FastDualAgent::relay`]).
    relay: bool,
}

impl FastDualAgent {
    /// Robot `index` of `robots` with its own `costs` and `allowed` tasks (at least one),
    /// `degree = |N(i)|`.
    pub fn new(
        index: usize,
        costs: &[f64],
        allowed: Vec<bool>,
        robots: usize,
        case: AssignmentCase,
        degree: usize,
        params: DualParams,
    ) -> Self {
        let tasks = costs.len();
        assert!(index < robots && tasks >= 1 && allowed.len() == tasks);
        assert!(allowed.iter().any(|&a| a), "a robot needs an allowed task");
        assert!(
            params.rho > 0.0 && params.rho.is_finite(),
            "ρ must be positive"
        );
        if let DualUpdate::Inexact { gamma_factor } = params.update {
            assert!(
                gamma_factor > 0.0 && gamma_factor.is_finite(),
                "γ must be positive"
            );
        }
        let costs = column::centred(costs, &allowed);
        let first = allowed.iter().position(|&a| a).expect("an allowed task");
        let epsilon = params.tolerance / (10.0 * robots as f64);
        Self {
            tasks,
            robots,
            degree,
            case,
            params,
            costs,
            allowed,
            y: vec![0.0; tasks],
            p: vec![0.0; tasks],
            kappa: vec![0.0; tasks],
            edges: vec![0.0; tasks],
            rho: params.rho,
            x: vec![0.0; tasks],
            step_point: vec![0.0; tasks],
            breakpoints: Vec::with_capacity(3 * tasks + 2),
            // Every slack of a stable potential is at most ε: a tenth of what the stop allows.
            snapshot: Snapshot::new(index, robots, tasks, case, params.diameter, epsilon),
            finish: Finish::new(index, robots, tasks, case, params.diameter, epsilon),
            task: first,
            slack: f64::INFINITY,
            steps: 0,
            episode_steps: 0,
            relay: false,
        }
    }

    /// An agent that relays for a team of `robots` robots and `tasks` tasks (a standing
    /// team's robot that takes no task in an episode): it takes part in the consensus on
    /// the task prices and floods the certificate with no column, no share of the task
    /// rows and no claim of its own, so that `Σ_i x_i` and the right-hand sides stay those
    /// of the robots that take part; its slack is 0 once the certificate holds.
    pub fn relay(
        robots: usize,
        tasks: usize,
        case: AssignmentCase,
        degree: usize,
        params: DualParams,
    ) -> Self {
        let mut agent = Self::new(
            0,
            &vec![0.0; tasks],
            vec![true; tasks],
            robots,
            case,
            degree,
            params,
        );
        agent.relay = true;
        agent
    }

    /// New own costs (`+∞` or a penalty for a forbidden pair as the team's normalisation
    /// gives them; a relay's are not used): the certificate starts again; the prices, the
    /// consensus sums and the column stay (`warm`) or start from zero with the ρ schedule.
    fn take_costs(&mut self, costs: &[f64], warm: bool) -> Result<(), NewCostsError> {
        if costs.len() != self.tasks {
            return Err(NewCostsError::WrongLength { got: costs.len() });
        }
        if !self.relay {
            for (allowed, cost) in self.allowed.iter_mut().zip(costs) {
                *allowed = cost.is_finite();
            }
            if !self.allowed.contains(&true) {
                return Err(NewCostsError::NoAllowedTask);
            }
            self.costs = column::centred(costs, &self.allowed);
            self.task = column::round(&self.x, &self.allowed);
        }
        if !warm {
            for v in [
                &mut self.y,
                &mut self.p,
                &mut self.kappa,
                &mut self.edges,
                &mut self.x,
            ] {
                v.fill(0.0);
            }
        }
        // Warm or cold, ρ follows its schedule from ρ₀ again: a warm episode's prices must
        // still move. Drifting costs, warm episodes' median rounds, ρ from ρ₀ / ρ going on
        // from the last episode / cold: 10-robot ring 58 / 39 / 75, 50 robots `random:0.1`
        // 246 / 316 / 372, 200 robots 502 / 1398 / 442 (bench/README.md: at 200 robots a
        // drift moves half of the optimal tasks, and warm is no better than cold).
        self.steps = 0;
        self.snapshot.restart();
        self.finish.restart();
        self.episode_steps = 0;
        self.slack = f64::INFINITY;
        Ok(())
    }

    /// Own relaxed column `x_i`.
    pub fn column(&self) -> &[f64] {
        &self.x
    }

    /// Own task multipliers of the current round.
    pub fn multipliers(&self) -> &[f64] {
        &self.y
    }

    /// `2 d` with a lone robot its own neighbour.
    fn two_d(&self) -> f64 {
        2.0 * self.degree.max(1) as f64
    }

    /// `±1/n`: the share of a task row's right-hand side (negative for coverage rows; a
    /// relay has none).
    fn rhs(&self) -> f64 {
        if self.relay {
            return 0.0;
        }
        let share = 1.0 / self.robots as f64;
        if self.case == AssignmentCase::Two {
            -share
        } else {
            share
        }
    }

    /// Updates `p` and `κ` from the neighbours' multipliers; returns their largest
    /// disagreement with this robot's.
    fn accumulate(&mut self, inbox: &dyn Inbox) -> f64 {
        let rho = self.rho;
        let m = self.tasks;
        let mut disagreement: f64 = 0.0;
        self.kappa.fill(0.0);
        for k in 0..inbox.len() {
            let theirs = inbox.payload(k);
            assert_eq!(
                theirs.len(),
                payload_len(self.robots, m),
                "neighbour payload has the wrong length"
            );
            disagreement = disagreement.max(add_and_spread(&mut self.kappa, &self.y, &theirs[..m]));
        }
        let degree = if inbox.is_empty() {
            // A lone robot (n = 1) is its own neighbour, as in the other agents.
            self.kappa.copy_from_slice(&self.y);
            1.0
        } else {
            inbox.len() as f64
        };
        let rhs = self.rhs();
        let alpha = RELAXATION;
        for t in 0..m {
            let neighbour_sum = self.kappa[t];
            // Relaxed: z_ij ← α (y_i + y_j)/2 + (1 − α) z_ij, summed over the edges; the
            // multiplier moves by α ρ (y_i − y_j) (α = 1 is the paper's step).
            self.p[t] += alpha * rho * (degree * self.y[t] - neighbour_sum);
            self.edges[t] =
                alpha * 0.5 * (degree * self.y[t] + neighbour_sum) + (1.0 - alpha) * self.edges[t];
            self.kappa[t] = -rhs / rho - self.p[t] / rho + 2.0 * self.edges[t];
        }
        disagreement
    }

    fn update_x(&mut self) {
        if self.relay {
            // No column: x ≡ 0.
            return;
        }
        let rho = self.rho;
        let two_d_rho = self.two_d() * rho;
        let (costs, kappa, allowed, case) = (&self.costs, &self.kappa, &self.allowed, self.case);
        match self.params.update {
            DualUpdate::Exact => {
                // The paper's responses (see `agent`), on the simplex.
                let response = |t: usize| match case {
                    _ if !allowed[t] => (f64::NEG_INFINITY, f64::NEG_INFINITY),
                    AssignmentCase::Two => {
                        (-two_d_rho * costs[t], rho * kappa[t] - two_d_rho * costs[t])
                    }
                    AssignmentCase::One | AssignmentCase::Idle => {
                        (f64::NEG_INFINITY, -two_d_rho * costs[t] - rho * kappa[t])
                    }
                };
                solve_simplex_box(self.tasks, response, &mut self.breakpoints, &mut self.x);
            }
            DualUpdate::Inexact { gamma_factor } => {
                let gamma = gamma_factor / two_d_rho;
                let two_d = self.two_d();
                for (((point, &x), &cost), &kappa) in self
                    .step_point
                    .iter_mut()
                    .zip(&self.x)
                    .zip(costs)
                    .zip(kappa)
                {
                    let theta = theta(case, rho, kappa, x);
                    let gradient = match case {
                        AssignmentCase::Two => cost - theta.max(0.0) / two_d,
                        AssignmentCase::One | AssignmentCase::Idle => cost + theta / two_d,
                    };
                    *point = x - gradient / gamma;
                }
                let (point, allowed) = (&self.step_point, &self.allowed);
                solve_simplex_box(
                    self.tasks,
                    |t| {
                        if allowed[t] {
                            (f64::NEG_INFINITY, point[t])
                        } else {
                            (f64::NEG_INFINITY, f64::NEG_INFINITY)
                        }
                    },
                    &mut self.breakpoints,
                    &mut self.x,
                );
            }
        }
    }

    /// ρ of every step: `ρ₀ · min(RHO_GROWTH^k, RHO_MAX_GROWTH)`.
    fn schedule(&self) -> RhoSchedule {
        RhoSchedule {
            initial: self.params.rho,
            start: 1.0,
            rate: RHO_GROWTH,
            min: 1.0,
            max: RHO_MAX_GROWTH,
        }
    }
}

/// Adds `theirs` to `sums` and returns the largest `|mine − theirs|`: four running maxima,
/// not one, so that the maxima do not wait on each other (a fifth of the fast dual's round
/// at 500 robots was the one chain of them).
fn add_and_spread(sums: &mut [f64], mine: &[f64], theirs: &[f64]) -> f64 {
    const LANES: usize = 4;
    debug_assert!(sums.len() == mine.len() && mine.len() == theirs.len());
    let mut spread = [0.0f64; LANES];
    let mut sum_chunks = sums.chunks_exact_mut(LANES);
    let (mut mine_chunks, mut their_chunks) =
        (mine.chunks_exact(LANES), theirs.chunks_exact(LANES));
    for ((sum, mine), theirs) in (&mut sum_chunks)
        .zip(&mut mine_chunks)
        .zip(&mut their_chunks)
    {
        for k in 0..LANES {
            sum[k] += theirs[k];
            spread[k] = spread[k].max((mine[k] - theirs[k]).abs());
        }
    }
    let rest = sum_chunks.into_remainder().iter_mut();
    for ((sum, mine), theirs) in rest
        .zip(mine_chunks.remainder())
        .zip(their_chunks.remainder())
    {
        *sum += theirs;
        spread[0] = spread[0].max((mine - theirs).abs());
    }
    spread.into_iter().fold(0.0, f64::max)
}

/// `θ_t = ±x_t/ρ + κ_t` (`−` for Case 2's coverage rows).
fn theta(case: AssignmentCase, rho: f64, kappa: f64, x: f64) -> f64 {
    let row = if case == AssignmentCase::Two { -x } else { x };
    row / rho + kappa
}

impl ConsensusAgent for FastDualAgent {
    fn payload_len(&self) -> usize {
        payload_len(self.robots, self.tasks)
    }

    /// Finite multipliers and potentials; claims packed as this team's codes only; the
    /// finish's section as [`Finish::check`] wants it.
    fn check_payload(&self, payload: &[f64]) -> Result<(), PayloadError> {
        crate::agent::check_length(payload, self.payload_len())?;
        let m = self.tasks;
        if let Some(t) = first_not_finite(&payload[..m]) {
            return Err(PayloadError::NotFinite {
                index: t,
                value: payload[t],
            });
        }
        let end = m + snapshot::words(self.robots, m);
        let bad = |k: usize, part: PayloadPart| PayloadError::BadValue {
            part,
            value: payload[k],
        };
        self.snapshot.check(&payload[m..end]).map_err(|k| {
            let part = if k < m {
                PayloadPart::at("potential of task", k)
            } else {
                PayloadPart::at("packed claims", k - m)
            };
            bad(m + k, part)
        })?;
        self.finish
            .check(&payload[end..])
            .map_err(|k| bad(end + k, PayloadPart::at("finish value", k)))
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        out[..self.tasks].copy_from_slice(&self.y);
        Snapshot::write_empty(&mut out[self.tasks..]);
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        debug_assert_eq!(inbox.len(), self.degree, "inbox does not match the degree");
        let m = self.tasks;
        let end = m + snapshot::words(self.robots, m);
        self.rho = self.schedule().rho(self.steps);
        let disagreement = self.accumulate(inbox);
        // While the finish computes labels its moves travel in the potentials' place.
        self.snapshot.begin(self.finish.labelling());
        self.finish.begin();
        for k in 0..inbox.len() {
            let theirs = inbox.payload(k);
            self.snapshot.merge(self.episode_steps, &theirs[m..end]);
            self.finish.merge(&theirs[m..2 * m], &theirs[end..]);
        }
        self.update_x();
        let (two_d, rho, case) = (self.two_d(), self.rho, self.case);
        for ((o, &x), &kappa) in out[..m].iter_mut().zip(&self.x).zip(&self.kappa) {
            let value = theta(case, rho, kappa, x) / two_d;
            *o = round_multiplier(if case == AssignmentCase::Two {
                value.max(0.0)
            } else {
                value
            });
        }
        let rounded = (!self.relay).then(|| column::round(&self.x, &self.allowed));
        let (costs, allowed) = (&self.costs, &self.allowed);
        let own = self
            .finish
            .claim(self.episode_steps, rounded, costs, allowed);
        self.task = own.unwrap_or(self.task);
        if let Some(prices) = self.finish.prices() {
            self.snapshot.seed(prices);
        }
        self.snapshot
            .advance(self.episode_steps, own, costs, allowed);
        self.finish.observe(self.episode_steps, &self.snapshot);
        self.snapshot.write(&mut out[m..end]);
        let (head, section) = out.split_at_mut(end);
        self.finish.write(&mut head[m..2 * m], section);
        self.slack = match own {
            Some(task) => self.snapshot.slack(task, costs, allowed, self.case),
            None => self.snapshot.relay_slack(),
        };
        let report = column::report(&self.x, self.task, disagreement, &out[..m], &self.y);
        self.y.copy_from_slice(&out[..m]);
        self.steps += 1;
        self.episode_steps += 1;
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

impl AgentAlgorithm for FastDualAgent {
    /// Sets `ρ₀` (the schedule then grows from it).
    fn set_rho(&mut self, rho: f64) {
        assert!(rho > 0.0 && rho.is_finite(), "ρ must be positive");
        self.params.rho = rho;
    }

    fn set_costs(&mut self, costs: &[f64], warm: bool) -> Result<(), NewCostsError> {
        self.take_costs(costs, warm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Multipliers are rounded to nearest on a grid of 12 fraction bits: within half a
    /// step, idempotent, symmetric in sign, carrying into the exponent.
    #[test]
    fn multipliers_are_rounded_to_their_grid() {
        let step = 2f64.powi(-(MULTIPLIER_BITS as i32));
        for &v in &[
            0.0,
            1.0,
            -3.0,
            0.1,
            -0.123_456_789,
            7.7e-9,
            1.0 - 1e-9,
            5.0e3,
        ] {
            let r = round_multiplier(v);
            assert!((r - v).abs() <= 0.5 * step * v.abs(), "{v} → {r}");
            assert_eq!(round_multiplier(r), r);
            assert_eq!(round_multiplier(-v), -r);
            assert_eq!(r.to_bits() & ((1 << (52 - MULTIPLIER_BITS)) - 1), 0);
        }
        assert_eq!(round_multiplier(1.0 - 1e-9), 1.0);
        assert!(round_multiplier(f64::NAN).is_nan());
        assert!(round_multiplier(f64::from_bits(u64::MAX)).is_nan());
        assert_eq!(round_multiplier(-f64::MAX), -f64::MAX);
        assert_eq!(round_multiplier(f64::INFINITY), f64::INFINITY);
    }
    use admm_ta_topologies::rng::SeededRng;

    /// The subproblem's objective at `x` for the agent's current κ.
    fn objective(agent: &FastDualAgent, x: &[f64]) -> f64 {
        let rho = agent.rho;
        let d = agent.degree as f64;
        let mut value: f64 = x.iter().zip(&agent.costs).map(|(a, b)| a * b).sum();
        let mut theta2 = 0.0;
        for (t, &xt) in x.iter().enumerate() {
            let theta = theta(agent.case, rho, agent.kappa[t], xt);
            theta2 += if agent.case == AssignmentCase::Two {
                theta.max(0.0).powi(2)
            } else {
                theta * theta
            };
        }
        value += rho / (4.0 * d) * theta2;
        value
    }

    /// The exact update minimises its subproblem over the allowed simplex: no random
    /// feasible point (nor any move of mass between two entries) does better.
    #[test]
    fn exact_update_minimises_the_subproblem_on_the_simplex() {
        let mut rng = SeededRng::new(7);
        for (case, robots, tasks) in [(AssignmentCase::One, 4, 4), (AssignmentCase::Two, 6, 4)] {
            for trial in 0..60 {
                let params = DualParams {
                    rho: 0.3 + rng.uniform(),
                    update: DualUpdate::Exact,
                    diameter: 1,
                    tolerance: 1e-9,
                };
                let costs: Vec<f64> = (0..tasks).map(|_| rng.uniform()).collect();
                let mut allowed = vec![true; tasks];
                if trial % 3 == 0 {
                    allowed[1] = false;
                }
                let mut agent =
                    FastDualAgent::new(0, &costs, allowed.clone(), robots, case, 2, params);
                for v in agent.y.iter_mut().chain(agent.p.iter_mut()) {
                    *v = 2.0 * rng.uniform() - 1.0;
                }
                let theirs: Vec<Vec<f64>> = (0..2)
                    .map(|_| {
                        let mut message = vec![0.0; payload_len(robots, tasks)];
                        for v in &mut message[..tasks] {
                            *v = 2.0 * rng.uniform() - 1.0;
                        }
                        Snapshot::write_empty(&mut message[tasks..]);
                        message
                    })
                    .collect();
                let inbox: Vec<&[f64]> = theirs.iter().map(Vec::as_slice).collect();
                agent.accumulate(&inbox);
                agent.update_x();
                let x = agent.x.clone();
                assert!((x.iter().sum::<f64>() - 1.0).abs() < 1e-9, "{x:?}");
                assert!(x.iter().zip(&allowed).all(|(v, a)| *a || *v == 0.0));
                let best = objective(&agent, &x);
                for _ in 0..300 {
                    // Move mass from one allowed entry to another.
                    let (a, b) = (rng.below(tasks), rng.below(tasks));
                    if a == b || !allowed[a] || !allowed[b] {
                        continue;
                    }
                    let shift = (0.3 * rng.uniform()).min(x[a]);
                    let mut probe = x.clone();
                    probe[a] -= shift;
                    probe[b] += shift;
                    if probe[b] > 1.0 {
                        continue;
                    }
                    let value = objective(&agent, &probe);
                    assert!(
                        value >= best - 1e-10,
                        "{case:?} trial {trial}: {value} < {best} at {probe:?} vs {x:?}"
                    );
                }
            }
        }
    }

    /// Two robots on one edge find and certify the cheaper of the two assignments.
    #[test]
    fn two_robots_certify_the_optimum() {
        for update in [DualUpdate::Exact, DualUpdate::Inexact { gamma_factor: 1.0 }] {
            let costs = [[0.0, 1.0], [0.0, 3.0]];
            let mut agents: Vec<FastDualAgent> = (0..2)
                .map(|i| {
                    let params = DualParams {
                        rho: 0.5,
                        update,
                        diameter: 1,
                        tolerance: 1e-9,
                    };
                    FastDualAgent::new(
                        i,
                        &costs[i],
                        vec![true; 2],
                        2,
                        AssignmentCase::One,
                        1,
                        params,
                    )
                })
                .collect();
            let mut messages = vec![vec![0.0; payload_len(2, 2)]; 2];
            for (agent, message) in agents.iter().zip(&mut messages) {
                agent.write_initial_payload(message);
            }
            let mut certified = None;
            for round in 0..2000 {
                let gathered = messages.clone();
                for (i, agent) in agents.iter_mut().enumerate() {
                    agent.step(&vec![gathered[1 - i].as_slice()], &mut messages[i]);
                }
                if agents.iter().all(|a| a.certificate_slack() <= 1e-12) {
                    certified = Some(round);
                    break;
                }
            }
            assert!(certified.is_some(), "{update:?}: never certified");
            assert_eq!(
                (agents[0].decide(), agents[1].decide()),
                (1, 0),
                "{update:?}"
            );
        }
    }

    /// Steps a chain of agents (each the next one's neighbour) until every slack is 0;
    /// returns the round, or `None` after `limit` rounds.
    fn certify_chain(agents: &mut [FastDualAgent], limit: usize) -> Option<usize> {
        let n = agents.len();
        let len = agents[0].payload_len();
        let mut messages = vec![vec![0.0; len]; n];
        for (agent, message) in agents.iter().zip(&mut messages) {
            agent.write_initial_payload(message);
        }
        for round in 0..limit {
            let gathered = messages.clone();
            for (i, agent) in agents.iter_mut().enumerate() {
                let inbox: Vec<&[f64]> = [i.wrapping_sub(1), i + 1]
                    .into_iter()
                    .filter(|&j| j < n)
                    .map(|j| gathered[j].as_slice())
                    .collect();
                agent.step(&inbox, &mut messages[i]);
            }
            if agents.iter().all(|a| a.certificate_slack() <= 1e-12) {
                return Some(round);
            }
        }
        None
    }

    /// A relay between two robots (a chain robot–relay–robot) adds nothing: the two robots
    /// certify their optimum, the relay's slack is 0 with theirs; new costs (warm and
    /// cold) are certified again, the warm start from the last prices.
    #[test]
    fn a_relay_carries_prices_and_claims_and_new_costs_certify_again() {
        for case in [AssignmentCase::One, AssignmentCase::Two] {
            let tasks = if case == AssignmentCase::One { 2 } else { 1 };
            let params = DualParams {
                rho: 0.5,
                update: DualUpdate::Exact,
                diameter: 2,
                tolerance: 1e-9,
            };
            let robot = |i: usize, costs: &[f64]| {
                FastDualAgent::new(i, costs, vec![true; tasks], 2, case, 1, params)
            };
            let (first, second) = ([0.0, 1.0], [0.0, 3.0]);
            let mut agents = vec![
                robot(0, &first[..tasks]),
                FastDualAgent::relay(2, tasks, case, 2, params),
                robot(1, &second[..tasks]),
            ];
            assert!(certify_chain(&mut agents, 2000).is_some(), "{case:?}");
            if case == AssignmentCase::One {
                // Robot 1 loses less by taking task 1.
                assert_eq!((agents[0].decide(), agents[2].decide()), (1, 0));
                // Swapped costs, warm and cold: the other assignment.
                for warm in [true, false] {
                    agents[0].set_costs(&second, warm).unwrap();
                    agents[1].set_costs(&[0.0, 0.0], warm).unwrap();
                    agents[2].set_costs(&first, warm).unwrap();
                    assert!(certify_chain(&mut agents, 2000).is_some(), "warm {warm}");
                    assert_eq!((agents[0].decide(), agents[2].decide()), (0, 1));
                }
                assert_eq!(
                    agents[0].set_costs(&[1.0], true),
                    Err(NewCostsError::WrongLength { got: 1 })
                );
            }
        }
    }

    /// Case 1 teams on a path graph (a long diameter: the prices resolve chains slowly):
    /// every one certifies the optimum, and on some the augmenting finish moved paths.
    #[test]
    fn the_finish_moves_chains_and_the_optimum_is_certified() {
        use crate::certify::oracle;
        use crate::problem::CostMatrix;
        let mut rng = SeededRng::new(5);
        let mut finished = 0;
        for trial in 0..12 {
            let n = 8 + trial % 5;
            let values: Vec<f64> = (0..n * n).map(|_| rng.uniform()).collect();
            let params = DualParams {
                rho: 0.05,
                update: DualUpdate::Exact,
                diameter: n - 1,
                tolerance: 1e-9,
            };
            let mut agents: Vec<FastDualAgent> = (0..n)
                .map(|i| {
                    let row = &values[i * n..(i + 1) * n];
                    let degree = if i == 0 || i == n - 1 { 1 } else { 2 };
                    FastDualAgent::new(
                        i,
                        row,
                        vec![true; n],
                        n,
                        AssignmentCase::One,
                        degree,
                        params,
                    )
                })
                .collect();
            assert!(
                certify_chain(&mut agents, 20_000).is_some(),
                "trial {trial}"
            );
            let costs = CostMatrix::new(n, n, values.clone()).unwrap();
            let optimal = oracle::solve_costs(&costs, AssignmentCase::One).unwrap();
            let cost = |tasks: &[usize]| -> f64 {
                tasks
                    .iter()
                    .enumerate()
                    .map(|(i, &t)| values[i * n + t])
                    .sum()
            };
            let decided: Vec<usize> = agents.iter().map(|a| a.decide()).collect();
            assert!(
                (cost(&decided) - cost(&optimal)).abs() < 1e-9,
                "trial {trial}: {decided:?} against {optimal:?}"
            );
            finished += usize::from(agents.iter().any(|a| a.finish.paths() > 0));
        }
        assert!(finished > 0, "the finish never moved a path");
    }
}
