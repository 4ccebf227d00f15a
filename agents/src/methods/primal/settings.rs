//! Settings of the primal consensus ADMM: the method's own settings as the user gives them
//! ([`PrimalSettings`]: which variant runs, [`PrimalVariant`], and the x-update's solver,
//! [`ProjectionPath`]) and every number a robot's
//! [`crate::methods::primal::agent::PrimalAgent`] needs ([`PrimalParams`]).
//!
//! Two variants share one agent:
//!
//! * [`PrimalVariant::Paper`]: Algorithm 1 of the paper as published — every robot rounds
//!   its own iterate column by column, ρ follows [`crate::methods::rho::default_rho`], the
//!   certificate is checked every [`crate::certify::local_stop::CHECK_EVERY`] rounds, and
//!   `--adaptive-rho` anneals ρ.
//! * [`PrimalVariant::Fast`] (the default of `solve` and the experiments): the same
//!   messages (`X_i`, `m × n`) and the same optimality certificate, but each robot reads
//!   the team's assignment from its certificate matrix `G_i = Q_i + α_i e_iᵀ` by a local
//!   linear sum assignment ([`crate::methods::primal::readout`]), ρ is large ([`fast_rho`]), the consensus
//!   step is over-relaxed and anchored to the polytope's centre with weights from the graph
//!   diameter ([`FastTuning::for_diameter`]), the certificate is checked every round, and
//!   the readout extrapolates over the last rounds' certificate matrices
//!   ([`crate::methods::primal::readout_filter`], set by the team's builder). On 50×50 complete graphs with
//!   uniform costs (seeds 1–30) this takes the median decentralized certified stop from 286
//!   rounds to 3 (see docs/algorithms.md).

use crate::method::settings::{MethodSettings, Setting, SettingKind, SettingSpec, SettingValue};
use serde::{Deserialize, Serialize};

/// The primal method's own settings (`--primal-variant`, `--projection`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PrimalSettings {
    pub primal_variant: PrimalVariant,
    pub projection: ProjectionPath,
}

/// `--primal-variant`: the setting that picks the variant.
pub const VARIANT: SettingSpec = SettingSpec {
    key: "primal_variant",
    flag: "--primal-variant",
    value_name: "PRIMAL_VARIANT",
    help: "Primal method: fast (each robot reads the assignment from its certificate matrix by a local assignment problem, large ρ, over-relaxed and anchored steps, certificate every round) or paper (Algorithm 1 as published; refused with the other methods) [default: fast]",
    kind: SettingKind::Choice(|| PrimalVariant::ALL.iter().map(|v| v.name()).collect()),
};

/// `--projection`: the x-update's solver.
pub const PROJECTION: SettingSpec = SettingSpec {
    key: "projection",
    flag: "--projection",
    value_name: "PROJECTION",
    help: "Primal method's x-update solver: fast (Newton projection) or qp (clarabel; slow cross-check; refused with the other methods) [default: fast]",
    kind: SettingKind::Choice(|| ProjectionPath::ALL.iter().map(|v| v.name()).collect()),
};

impl MethodSettings for PrimalSettings {
    const SPECS: &'static [SettingSpec] = &[VARIANT, PROJECTION];
}

impl Setting for PrimalVariant {
    const SPEC: &'static SettingSpec = &VARIANT;
    fn value(self) -> SettingValue {
        SettingValue::Name(self.name().to_string())
    }
}

impl Setting for ProjectionPath {
    const SPEC: &'static SettingSpec = &PROJECTION;
    fn value(self) -> SettingValue {
        SettingValue::Name(self.name().to_string())
    }
}

/// Which solver carries out the x-update (8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProjectionPath {
    /// Semismooth Newton projection (default).
    #[default]
    Fast,
    /// clarabel QP (cross-check; orders of magnitude slower).
    Qp,
}

impl ProjectionPath {
    /// Both paths, in the order of the command line's help.
    pub const ALL: [ProjectionPath; 2] = [Self::Fast, Self::Qp];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fast => "fast",
            Self::Qp => "qp",
        }
    }
}

#[cfg(feature = "clap")]
crate::clap_value_enum!(ProjectionPath);

/// Which primal consensus ADMM runs (`--primal-variant`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PrimalVariant {
    /// Algorithm 1 of the paper, unchanged (own-column readout, the paper's ρ rule, a
    /// certificate check every 5 rounds, `--adaptive-rho` honoured).
    Paper,
    /// The G readout with a large ρ, over-relaxation and an anchor (module docs).
    #[default]
    Fast,
}

impl PrimalVariant {
    /// Both variants, in the order of the command line's help.
    pub const ALL: [PrimalVariant; 2] = [Self::Paper, Self::Fast];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Fast => "fast",
        }
    }
}

#[cfg(feature = "clap")]
crate::clap_value_enum!(PrimalVariant);

/// `K` of the fast variant's `ρ = K · spread / (2 d̄)`.
///
/// With the G readout nothing needs `X_i` at a vertex, so ρ can be large: once
/// `2ρd ≫ spread` the iteration is linear in `(X, Q)` and no longer depends on ρ (the
/// `X_i` stay near the centre of the polytope and the `G_i` converge to a consensus whose
/// assignment is the optimum). 50×50 complete, uniform costs, seeds 1–3: 6 / 5 / 6 rounds
/// to the certified stop for every `K` of 10, 30, 100, 1000 and 10⁵; 100 leaves margin.
pub const FAST_RHO_FACTOR: f64 = 100.0;

/// The fast variant's ρ for costs of this shift-free spread on a graph of this mean degree.
pub fn fast_rho(spread: f64, mean_degree: f64) -> f64 {
    FAST_RHO_FACTOR * spread / (2.0 * mean_degree.max(1.0))
}

/// Largest anchor weight `c` (complete graphs).
pub const MAX_ANCHOR: f64 = 0.85;

/// The consensus step's shape in the fast variant: over-relaxation `α` and anchor `c`.
///
/// With the anchor the projection input is
/// `(1 − c) · (relaxed neighbourhood average) + c · (1/m) − G_i / (2ρ d_i)`: the iterate is
/// pulled toward the centre of the polytope, which damps the oscillation of the consensus
/// multipliers. `Q` (and so the certificate) is untouched. In the linear large-ρ regime
/// every eigenvalue `s` of the graph's normalised Laplacian is a mode of the iteration;
/// `c = min(0.85, π / (D + 1))` and `α = 1.9 − 0.5 c / 0.85` critically damp the slowest
/// mode of a graph of diameter `D` (near nilpotent on complete graphs, `c = 0.85`,
/// `α = 1.4`). With these values and the extrapolated readout of
/// [`crate::methods::primal::readout_filter`]: 50×50 complete, uniform costs, seeds 1–30, median 3 rounds to
/// the certified stop (6 without the filter); 50×30 chain 99 (120.5 without; the paper's
/// variant: 286 and 869).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FastTuning {
    /// Over-relaxation `α ∈ [1.4, 1.9]` of the consensus step (1: plain ADMM).
    pub relaxation: f64,
    /// Anchor weight `c ∈ (0, 0.85]`.
    pub anchor: f64,
}

impl FastTuning {
    /// The values for a graph of this diameter (every robot knows it: the stop protocol
    /// needs it too).
    pub fn for_diameter(diameter: usize) -> Self {
        let anchor = (std::f64::consts::PI / (diameter + 1) as f64).min(MAX_ANCHOR);
        Self {
            relaxation: 1.9 - 0.5 * anchor / MAX_ANCHOR,
            anchor,
        }
    }
}

/// Parameters of one primal agent. Every robot of a team must use the same values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrimalParams {
    /// The penalty ρ.
    pub rho: f64,
    /// x-update solver.
    pub projection: ProjectionPath,
    /// `None`: the paper's Algorithm 1. `Some`: the fast variant with these settings.
    pub fast: Option<FastParams>,
}

/// What the fast variant adds to Algorithm 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FastParams {
    /// Over-relaxation and anchor.
    pub tuning: FastTuning,
    /// Size `ε` of the tie-break matrix `E` (entries `ε · U[0, 1)`, the same at every
    /// robot) added to `G_i` by the readout: with exact ties (duplicate robots, integer
    /// costs) robots could read different optima forever without it (every duplicate-robot
    /// instance of `runtime/tests/all/fast_primal.rs` certifies with it). The readout then minimises `G_i + E` exactly, so its
    /// certificate slack for `G_i` is at most `n ε`; [`FastParams::new`] takes
    /// `ε = tolerance / (2 n²)`, half of a robot's share `tolerance / n`. 0: no tie-break
    /// (and no certificate, for runs without a tolerance).
    pub tie_break: f64,
    /// Try the closed-form projection first (exact when no entry is clipped, which is the
    /// rule in the large-ρ regime): no Newton iterations in most rounds.
    pub interior_projection: bool,
}

impl FastParams {
    /// The defaults for a team of `robots` on a graph of `diameter`, certifying to the total
    /// cost `tolerance` (infinite: no certificate, no tie-break).
    pub fn new(diameter: usize, robots: usize, tolerance: f64) -> Self {
        let n = robots.max(1) as f64;
        Self {
            tuning: FastTuning::for_diameter(diameter),
            tie_break: if tolerance.is_finite() && tolerance > 0.0 {
                tolerance / (2.0 * n * n)
            } else {
                0.0
            },
            interior_projection: true,
        }
    }
}

impl PrimalParams {
    /// The paper's Algorithm 1 with this ρ.
    pub fn new(rho: f64) -> Self {
        Self {
            rho,
            projection: ProjectionPath::Fast,
            fast: None,
        }
    }

    /// The variant's settings with this ρ, for a team of `robots` on a graph of `diameter`
    /// certifying to `tolerance`.
    pub fn for_variant(
        variant: PrimalVariant,
        rho: f64,
        diameter: usize,
        robots: usize,
        tolerance: f64,
    ) -> Self {
        Self {
            fast: (variant == PrimalVariant::Fast)
                .then(|| FastParams::new(diameter, robots, tolerance)),
            ..Self::new(rho)
        }
    }

    /// The variant these settings run.
    pub fn variant(&self) -> PrimalVariant {
        match self.fast {
            Some(_) => PrimalVariant::Fast,
            None => PrimalVariant::Paper,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tuning_follows_the_diameter() {
        let complete = FastTuning::for_diameter(1);
        assert_eq!(complete.anchor, MAX_ANCHOR);
        assert!((complete.relaxation - 1.4).abs() < 1e-12);
        let chain = FastTuning::for_diameter(49);
        assert!((chain.anchor - std::f64::consts::PI / 50.0).abs() < 1e-12);
        assert!(chain.relaxation > 1.8 && chain.relaxation < 1.9);
        assert_eq!(FastParams::new(1, 10, f64::INFINITY).tie_break, 0.0);
        assert!((FastParams::new(1, 10, 2e-9).tie_break - 1e-11).abs() < 1e-24);
        assert_eq!(
            PrimalParams::for_variant(PrimalVariant::Paper, 1.0, 3, 4, 1e-9),
            PrimalParams::new(1.0)
        );
    }
}
