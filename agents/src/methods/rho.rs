//! The penalty parameter ρ: the scale-free default rules of the consensus ADMM methods
//! ([`RhoRule`], which each method's registration names) and the
//! `--adaptive-rho` schedules ([`RhoSchedule`]).
//!
//! **The primal rule** (of the paper's variant; the fast variant's default takes a ρ about
//! 10⁴ times larger, `fast_rho` of the primal method's settings, where the iteration no longer
//! depends on it).
//! The x-update depends on the costs only through `α/ρ` and is unchanged by adding a
//! constant to a robot's costs (its column sum is fixed), so a ρ proportional to a shift-free
//! spread of the costs makes the whole iteration scale- and shift-free: costs in metres or
//! in [0, 1) give the same iterates. The rest of the rule is empirical, for uniform costs:
//!
//! `ρ = 0.5 · spread · √((n − 1) / d̄) / (2 · d̄ · n)`, `d̄` the mean degree.
//!
//! On complete graphs (`d̄ = n − 1`) it is the measured optimum of docs/notes.md, note 10,
//! (0.5 … 1) / (2 d̄ n); we take 0.5, which over 50 seeded 20×20 instances reached the
//! optimal assignment as fast as 0.75 and 1.0 and settled markedly sooner. Sparse graphs
//! want a larger ρ than `1/d̄` alone gives; the density factor `√((n − 1)/d̄)` cut the mean
//! rounds to the optimal assignment from 246 to 148 (15×15 chain, 20 seeds), from ≈1450 (half
//! the runs within 3000 rounds) to 561 (50×30 chain) and from 259 to 132 (50×30, random:0.1).

use crate::problem::CostMatrix;

/// The `0.5` of the rule.
pub const RHO_FACTOR: f64 = 0.5;

/// The default ρ for these costs on a graph with this mean degree.
pub fn default_rho(costs: &CostMatrix, mean_degree: f64) -> f64 {
    let n = costs.robots() as f64;
    let degree = mean_degree.max(1.0);
    let density_correction = ((n - 1.0).max(1.0) / degree).sqrt();
    RHO_FACTOR * costs.spread() * density_correction / (2.0 * degree * n)
}

/// `c` of the dual methods' rule `ρ = c / (spread · d̄)`: their multipliers are prices in
/// cost units, so ρ scales like 1/cost. 20×20 complete graph, uniform costs, 20 seeds
/// (`runtime/examples/dual_tuning.rs`, robots centring their own costs), rounds to within
/// 0.1% / to the optimal assignment / to the certificate: exact dual c = 2: 122 / 113 / 505,
/// c = 3: 114 / 114 / 495, c = 5: 102 / 138 / 385, c = 8: 104 / 144 / 326; inexact dual
/// (γ factor 0.5) c = 5: 154 / 231 / 875, c = 10: 150 / 269 / 711, c = 20: 155 / 307 / 579.
/// Larger c makes the multipliers agree (and the certificate fire) sooner but the
/// assignment settle later; we take the middle.
pub const DUAL_RHO_FACTOR: f64 = 5.0;
/// The inexact dual's `c` in the paper variant (it needs a larger ρ than the exact one to
/// stay stable; the fast variant uses [`DUAL_RHO_FACTOR`] for both).
pub const INEXACT_DUAL_RHO_FACTOR: f64 = 10.0;

/// How a method with a penalty picks its default ρ and its `--adaptive-rho` schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RhoRule {
    /// [`default_rho`], and the schedule that shrinks ρ (see [`RhoSchedule`]).
    Primal,
    /// `ρ = factor / (spread · d̄)` (multipliers are prices in cost units), and the schedule
    /// that grows ρ.
    Dual { factor: f64 },
}

impl RhoRule {
    /// The default ρ for these costs on a graph with this mean degree.
    pub fn rho(self, costs: &CostMatrix, mean_degree: f64) -> f64 {
        match self {
            Self::Primal => default_rho(costs, mean_degree),
            Self::Dual { factor } => factor / (costs.spread() * mean_degree.max(1.0)),
        }
    }

    /// The measured schedule from `initial` (the default or a given ρ).
    pub fn schedule(self, initial: f64) -> RhoSchedule {
        match self {
            Self::Primal => RhoSchedule {
                initial,
                start: 3.0,
                rate: 0.98,
                min: 0.6,
                max: 3.0,
            },
            Self::Dual { .. } => RhoSchedule {
                initial,
                start: 0.5,
                rate: 1.01,
                min: 1.0,
                max: 10.0,
            },
        }
    }
}

/// The `--adaptive-rho` schedule: `ρ_k = ρ_0 · clamp(start · rate^k, min, max)`.
///
/// Every robot computes it from the round number alone, so all change ρ at the same round
/// and nothing is exchanged: the consensus multipliers (`Q`, `p`) are kept unscaled
/// (`Q += ρ Σ (X_i − X_j)`), so they stay antisymmetric over the edges whatever ρ does.
/// Residual balancing (Boyd et al. §3.4.1) would need the team's residuals, a max-consensus
/// over the graph diameter before every change; the schedules do what it would do here,
/// per method:
///
/// * **primal**: start at 3 ρ_0 (fast agreement) and shrink 2% per round to 0.6 ρ_0 (the
///   costs then dominate and the iterate settles on a vertex);
/// * **dual, inexact dual**: keep ρ_0 for about 70 rounds, then grow 1% per round to
///   10 ρ_0: a larger ρ pulls the robots' multipliers together, which is what their
///   certificate waits for.
///
/// Measured with `admm-ta experiment table1 --adaptive-rho` (20×20 complete, 30 seeds,
/// mean rounds to the decentralized stop, fixed → scheduled): primal 128 → 70, dual
/// 382 → 241, inexact dual 660 → 406 (every run certified); and for the primal over 3 seeds
/// each (`solve --adaptive-rho`): 50×50 complete 329 → 191, 50×30 complete 184 → 116,
/// 50×30 random:0.1 158 → 87, 50×30 chain 1051 → 784, 12×12 ring (5 seeds) 59 → 53.
/// Other shapes measured worse: the primal at 1 ρ_0 shrinking 0.5% per round to 0.3
/// (stop 101) or starting at 4–5 ρ_0 (the 0.1% criterion came much later); the duals with
/// the primal's schedule (stop 440 and 777) or growing 2% per round (inexact: 996).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RhoSchedule {
    pub initial: f64,
    pub start: f64,
    pub rate: f64,
    pub min: f64,
    pub max: f64,
}

impl RhoSchedule {
    /// ρ of step `round` (0 for the first step).
    pub fn rho(&self, round: u64) -> f64 {
        let exponent = round.min(i32::MAX as u64) as i32;
        self.initial * (self.start * self.rate.powi(exponent)).clamp(self.min, self.max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_and_shift_free() {
        let costs = CostMatrix::uniform(10, 10, 3).unwrap();
        let scaled = CostMatrix::new(
            10,
            10,
            costs.values().iter().map(|c| 250.0 * c + 40.0).collect(),
        )
        .unwrap();
        let ratio = default_rho(&scaled, 9.0) / default_rho(&costs, 9.0);
        assert!((ratio - 250.0).abs() < 1e-9);
        for factor in [DUAL_RHO_FACTOR, INEXACT_DUAL_RHO_FACTOR] {
            let rule = RhoRule::Dual { factor };
            let ratio = rule.rho(&costs, 9.0) / rule.rho(&scaled, 9.0);
            assert!((ratio - 250.0).abs() < 1e-9, "dual ρ scales like 1/cost");
        }
    }

    #[test]
    fn schedules_stay_within_their_bounds() {
        let primal = RhoRule::Primal.schedule(2.0);
        assert_eq!(primal.rho(0), 6.0);
        assert!((primal.rho(10) - 6.0 * 0.98f64.powi(10)).abs() < 1e-12);
        assert_eq!(primal.rho(100_000), 1.2);
        assert_eq!(primal.rho(u64::MAX), 1.2);
        let dual = RhoRule::Dual {
            factor: DUAL_RHO_FACTOR,
        }
        .schedule(2.0);
        assert_eq!(dual.rho(0), 2.0);
        assert_eq!(dual.rho(60), 2.0);
        assert!(dual.rho(200) > 2.0 && dual.rho(200) < 20.0);
        assert_eq!(dual.rho(100_000), 20.0);
    }
}
