//! Dual consensus ADMM (Algorithm 2) and its inexact variant, each in two variants
//! (`--dual-variant`): `fast` (the default, [`fast`]: each robot's "one task" row is its own
//! constraint, `m` multipliers and a certificate that needs no agreement: flooded claims
//! and prices computed for them, [`snapshot`]) and `paper` (Algorithm 2 as published, [`agent`]: `n + m`
//! multipliers). The two registrations ([`DUAL`], [`INEXACT_DUAL`]) share the ρ rule and
//! schedule; the inexact method has its own setting (the γ factor).

pub mod agent;
pub mod column;
pub mod coupled_box;
pub mod fast;
pub mod snapshot;

pub use agent::{DEFAULT_GAMMA_FACTOR, DualAgent, DualParams, DualUpdate};
pub use fast::FastDualAgent;

use crate::agent::AgentAlgorithm;
use crate::certify::stopping::StopRule;
use crate::method::info::{
    Certification, Fig2Graphs, Memory, MethodInfo, Numbers, OWN_STATE_STOPS, PaperFacts,
    ReportText, Role, TEAM_STATE, per_agent,
};
use crate::method::settings::{MethodSettings, Setting, SettingKind, SettingSpec, SettingValue};
use crate::method::team::{
    AgentInit, Refusal, RunOption, TeamBuilder, TeamContext, TeamMethod, TeamParams,
};
use crate::methods::rho::{DUAL_RHO_FACTOR, INEXACT_DUAL_RHO_FACTOR, RhoRule, RhoSchedule};
use crate::problem::CostMatrix;
use serde::{Deserialize, Serialize};
use std::marker::PhantomData;

/// The paper variant's y, p, κ and two round buffers of `n + m`, costs, x and the
/// x-update's breakpoints (the fast variant holds less: `m` multipliers, two snapshots).
const DUAL_MEMORY: Memory = Memory {
    bytes: |n, m| per_agent(n, (5 * (n + m) + 5 * m + 2) as f64),
    of: TEAM_STATE,
    because: "each robot holds n+m multipliers (paper variant; fast: 2m values and m packed claims a round)",
};

/// The dual method's registration.
pub const DUAL: MethodInfo = MethodInfo {
    name: "dual",
    summary: "Algorithm 2, exchanges m multipliers and a certificate of m potentials and m packed claims (paper variant: n+m multipliers)",
    role: Role::Admm,
    team: Some(&DualMethod::<DualSettings>(PhantomData)),
    variants: Some(&VARIANT),
    stops: OWN_STATE_STOPS,
    memory: DUAL_MEMORY,
    certification: Certification::WhenStopProves,
    numbers: Numbers::Normalised,
    report: ReportText { inner_steps: None },
    paper: Some(PaperFacts {
        label: "dual",
        proposed: false,
        table1: Some(159.0),
        fig1: None,
        fig2: Fig2Graphs {
            complete: false,
            random: false,
        },
        variant: Some("paper"),
    }),
};

/// The inexact dual's registration.
pub const INEXACT_DUAL: MethodInfo = MethodInfo {
    name: "inexact-dual",
    summary: "proximal-gradient x-update, no inner solve",
    role: Role::Admm,
    team: Some(&DualMethod::<InexactDualSettings>(PhantomData)),
    variants: Some(&VARIANT),
    stops: OWN_STATE_STOPS,
    memory: DUAL_MEMORY,
    certification: Certification::WhenStopProves,
    numbers: Numbers::Normalised,
    report: ReportText { inner_steps: None },
    paper: Some(PaperFacts {
        label: "inexact dual",
        proposed: false,
        table1: Some(387.0),
        fig1: None,
        fig2: Fig2Graphs {
            complete: false,
            random: false,
        },
        variant: Some("paper"),
    }),
};

/// `--dual-variant`: which variant of the dual methods runs.
pub const VARIANT: SettingSpec = SettingSpec {
    key: "dual_variant",
    flag: "--dual-variant",
    value_name: "DUAL_VARIANT",
    help: "Dual methods: fast (each robot's one-task row is its own constraint, m multipliers, relaxed steps and a ρ growing from a start set by the costs' structure; flooded claims and prices computed for them certify) or paper (Algorithm 2 as published, n+m multipliers; refused with the other methods) [default: fast]",
    kind: SettingKind::Choice(|| DualVariant::ALL.iter().map(|v| v.name()).collect()),
};

/// The variants of the dual methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DualVariant {
    /// Algorithm 2 as published ([`agent`]).
    Paper,
    /// Own robot rows and the snapshot certificate ([`fast`]).
    #[default]
    Fast,
}

impl DualVariant {
    /// Both variants, in the order of the command line's help.
    pub const ALL: [DualVariant; 2] = [Self::Paper, Self::Fast];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Fast => "fast",
        }
    }

    fn payload_len(self, robots: usize, tasks: usize) -> usize {
        match self {
            Self::Paper => robots + tasks,
            Self::Fast => fast::payload_len(robots, tasks),
        }
    }
}

impl Setting for DualVariant {
    const SPEC: &'static SettingSpec = &VARIANT;
    fn value(self) -> SettingValue {
        SettingValue::Name(self.name().to_string())
    }
}

/// The dual method's own settings (`--dual-variant`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DualSettings {
    pub dual_variant: DualVariant,
}

impl MethodSettings for DualSettings {
    const SPECS: &'static [SettingSpec] = &[VARIANT];
}

/// The fast variant's `g` of `γ = g/(2dρ)`: see [`fast`] and bench/README.md.
pub const FAST_GAMMA_FACTOR: f64 = 1.0;

/// The inexact dual's own settings (`--gamma-factor`, `--dual-variant`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InexactDualSettings {
    /// `g` of the proximal weight (`None`: the variant's default).
    pub gamma_factor: Option<f64>,
    pub dual_variant: DualVariant,
}

impl InexactDualSettings {
    /// The x-update these settings give.
    pub fn update(&self) -> DualUpdate {
        let default = match self.dual_variant {
            DualVariant::Paper => DEFAULT_GAMMA_FACTOR,
            DualVariant::Fast => FAST_GAMMA_FACTOR,
        };
        DualUpdate::Inexact {
            gamma_factor: self.gamma_factor.unwrap_or(default),
        }
    }
}

/// `--gamma-factor`.
pub const GAMMA_FACTOR: SettingSpec = SettingSpec {
    key: "gamma_factor",
    flag: "--gamma-factor",
    value_name: "GAMMA_FACTOR",
    help: "Inexact dual: g of the proximal weight γ = g/(2·|N(i)|·ρ) (fast variant, default 1) or g·(m+1)/(2·|N(i)|·ρ) (paper variant, default 0.5); refused with the other methods",
    kind: SettingKind::PositiveNumber {
        what: "the γ factor",
    },
};

impl MethodSettings for InexactDualSettings {
    const SPECS: &'static [SettingSpec] = &[GAMMA_FACTOR, VARIANT];
}

/// A value of `--gamma-factor`, for the library's typed setter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GammaFactor(pub f64);

impl Setting for GammaFactor {
    const SPEC: &'static SettingSpec = &GAMMA_FACTOR;
    fn value(self) -> SettingValue {
        SettingValue::Number(self.0)
    }
}

/// What tells the two dual methods apart: their settings, their x-update and the factor
/// of their ρ rule.
pub trait DualKind: MethodSettings {
    /// The paper variant's `c` of `ρ = c / (spread · d̄)`.
    const RHO_FACTOR: f64;
    fn variant(&self) -> DualVariant;
    fn update(&self) -> DualUpdate;
}

impl DualKind for DualSettings {
    const RHO_FACTOR: f64 = DUAL_RHO_FACTOR;
    fn variant(&self) -> DualVariant {
        self.dual_variant
    }
    fn update(&self) -> DualUpdate {
        DualUpdate::Exact
    }
}

impl DualKind for InexactDualSettings {
    const RHO_FACTOR: f64 = INEXACT_DUAL_RHO_FACTOR;
    fn variant(&self) -> DualVariant {
        self.dual_variant
    }
    fn update(&self) -> DualUpdate {
        InexactDualSettings::update(self)
    }
}

/// A dual method as a team method: Algorithm 2 with `DualSettings`, the inexact dual with
/// `InexactDualSettings`.
pub struct DualMethod<S>(PhantomData<fn() -> S>);

impl<S: DualKind> TeamMethod for DualMethod<S> {
    type Settings = S;
    const PENALTY: bool = true;

    fn payload_len(&self, settings: &S, robots: usize, tasks: usize) -> usize {
        settings.variant().payload_len(robots, tasks)
    }

    fn default_rho(&self, settings: &S, costs: &CostMatrix, degree: f64) -> f64 {
        let rho = rule(settings.variant(), S::RHO_FACTOR).rho(costs, degree);
        match settings.variant() {
            DualVariant::Paper => rho,
            DualVariant::Fast => rho * structure_factor(costs),
        }
    }

    fn schedule(&self, settings: &S, initial: f64) -> Option<RhoSchedule> {
        // The paper variant's `--adaptive-rho` schedule; the fast one grows its ρ itself.
        (settings.variant() == DualVariant::Paper)
            .then(|| rule(DualVariant::Paper, S::RHO_FACTOR).schedule(initial))
    }

    fn refuse(&self, settings: &S, adaptive_rho: bool, _: StopRule) -> Result<(), Refusal> {
        if settings.variant() == DualVariant::Fast && adaptive_rho {
            return Err(Refusal {
                option: RunOption::AdaptiveRho,
                needs: &VARIANT,
                value: DualVariant::Paper.name(),
                because: "the paper's dual variant, not the fast one (whose ρ grows by its own schedule)",
            });
        }
        Ok(())
    }

    fn team<'a>(&'static self, settings: &S, team: TeamContext<'a>) -> Box<dyn TeamBuilder + 'a> {
        Box::new(DualTeam::new(team, settings.update(), settings.variant()))
    }

    fn stop_cadence(&self, _: &S) -> (u64, u32) {
        CADENCE
    }
}

/// The certificate is checked every round: its disagreement level changes every round (see
/// [`agent`]), and a robot never sees the team's assignment, so there is no agreement
/// streak to wait for.
const CADENCE: (u64, u32) = (1, 0);

/// The fast variant's `ρ₀` is this many times the paper variant's dual ρ (for both fast
/// methods), times [`structure_factor`]; its ρ then grows (see [`fast::RHO_GROWTH`];
/// bench/README.md, "The dual methods, second pass" and "third pass").
pub const FAST_RHO_SCALE: f64 = 0.1;

/// The fast variant's `ρ₀` follows the costs' structure ([`structure_factor`]): at most
/// this many times its rule …
pub const FAST_STRUCTURE_MAX: f64 = 3.0;
/// … and at least this share of it.
pub const FAST_STRUCTURE_MIN: f64 = 0.5;

/// The fast variant's factor on `ρ₀` for these costs, from `h`: the mean over robots (with
/// two allowed tasks or more) of the gap between their two cheapest allowed costs times
/// their number of allowed tasks, over the costs' spread. Tasks whose allowed costs are
/// the same for every robot (the idle columns of a normalised problem), and robots whose
/// allowed costs are all the same (its idle rows), tell nothing about the competition and
/// are left out (of the gaps, the counts and the spread).
///
/// Independent, uniform costs give `h` between 0.8 and 1.3 at any size (the two smallest
/// of `k` uniform draws are `1/(k+1)` apart); distance costs more (1.6 at 20 × 20 on
/// average, 2.3 at 50 × 50, 3.0 at 100 × 100, 3.1 at 120 × 120, 4.3 at 200 × 200: a
/// robot's nearest tasks are `1/√k` apart); costs whose spread says little about the
/// competition less (tasks in far-apart clusters 0.1–0.25, points on a line 0.5–0.9,
/// rows of different scales 0.35–0.75, few distinct values 0). The factor is
/// [`FAST_STRUCTURE_MAX`] in the band of independent costs (`0.8 ≤ h ≤ 1.25`), the rule
/// as it is (1) below 0.7 and from 1.4, falling to [`FAST_STRUCTURE_MIN`] at `h = 2`,
/// linear in between ([`factor_of`]; basic operations only, so every machine of a team
/// computes the same ρ).
///
/// Measured (fast dual, seeds 1–10, rounds to the certified stop, the rule's ρ times a
/// constant): uniform costs certify faster with 3× (50 × 50 complete 183 → 124, 120 × 120
/// complete 434 → 390) and the 100 × 100 chain every run (9/10 → 10/10); distance costs
/// want less: at 1× the 120 × 120 complete graph certified 5 of 10 runs and at 2× the
/// 100 × 100 one 1 of 10, at ½ every run of every size from 50 to 120. Clustered costs
/// (three far-apart clusters, 40 × 40) are why the band is narrow: they certified at 1×
/// and never at 3×.
pub fn structure_factor(costs: &CostMatrix) -> f64 {
    let (n, m) = (costs.robots(), costs.tasks());
    let allowed = |i: usize, t: usize| costs.is_allowed(i, t).then(|| costs.get(i, t));
    // Tasks and robots whose allowed costs differ somewhere (not an idle column or row).
    let column = |t: usize| varies((0..n).filter_map(|i| allowed(i, t)));
    let columns: Vec<bool> = (0..m).map(column).collect();
    let counted = |i: usize| {
        (0..m)
            .filter(|&t| columns[t])
            .filter_map(move |t| allowed(i, t))
    };
    let rows: Vec<bool> = (0..n).map(|i| varies(counted(i))).collect();
    let values = || (0..n).filter(|&i| rows[i]).flat_map(counted);
    // The spread (as `CostMatrix::spread`) of those costs only.
    let count = values().count().max(1) as f64;
    let mean = values().sum::<f64>() / count;
    let spread = (12.0 * values().map(|v| (v - mean) * (v - mean)).sum::<f64>() / count).sqrt();
    let spread = if spread > 0.0 && spread.is_finite() {
        spread
    } else {
        1.0
    };
    let (mut sum, mut robots) = (0.0, 0usize);
    for i in (0..n).filter(|&i| rows[i]) {
        let (mut first, mut second, mut tasks) = (f64::INFINITY, f64::INFINITY, 0usize);
        for v in counted(i) {
            tasks += 1;
            if v < first {
                second = first;
                first = v;
            } else if v < second {
                second = v;
            }
        }
        // Each gap over the spread first: no overflow for costs near the largest double.
        sum += (second / spread - first / spread) * tasks as f64;
        robots += 1;
    }
    if robots == 0 {
        return 1.0;
    }
    factor_of(sum / robots as f64)
}

/// The factor for `h` (see [`structure_factor`]): [`FAST_STRUCTURE_MAX`] in the band of
/// independent costs, 1 (the rule as it is) below it, falling to [`FAST_STRUCTURE_MIN`]
/// above it; linear between, basic operations only.
fn factor_of(h: f64) -> f64 {
    let (max, min) = (FAST_STRUCTURE_MAX, FAST_STRUCTURE_MIN);
    let ramp = |x: f64, from: f64, to: f64, a: f64, b: f64| a + (b - a) * (x - from) / (to - from);
    match h {
        h if !h.is_finite() || h < 0.7 => 1.0,
        h if h < 0.8 => ramp(h, 0.7, 0.8, 1.0, max),
        h if h <= 1.25 => max,
        h if h <= 1.4 => ramp(h, 1.25, 1.4, max, 1.0),
        h if h <= 2.0 => ramp(h, 1.4, 2.0, 1.0, min),
        _ => min,
    }
}

/// Whether not all of `values` are equal (false for none or one).
fn varies(mut values: impl Iterator<Item = f64>) -> bool {
    values
        .next()
        .is_some_and(|first| values.any(|v| v != first))
}

/// The ρ rule of a variant, from the paper variant's factor.
fn rule(variant: DualVariant, factor: f64) -> RhoRule {
    let factor = match variant {
        DualVariant::Paper => factor,
        // One factor for both fast methods: without the robot rows their x-updates
        // coincide in Case 1 (`fast`), and the inexact's larger factor failed on distance
        // costs (100 × 100 complete: 1 of 10 runs certified).
        DualVariant::Fast => FAST_RHO_SCALE * DUAL_RHO_FACTOR,
    };
    RhoRule::Dual { factor }
}

/// Builds a dual team's agents.
struct DualTeam<'a> {
    params: TeamParams,
    update: DualUpdate,
    variant: DualVariant,
    /// The team's costs, for each robot's own forbidden pairs.
    costs: &'a CostMatrix,
}

impl<'a> DualTeam<'a> {
    fn new(team: TeamContext<'a>, update: DualUpdate, variant: DualVariant) -> Self {
        Self {
            params: team.params,
            update,
            variant,
            costs: team.problem.costs(),
        }
    }
}

impl TeamBuilder for DualTeam<'_> {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        let allowed: Vec<bool> = (0..self.costs.tasks())
            .map(|t| self.costs.is_allowed(init.index, t))
            .collect();
        let params = DualParams {
            rho: self.params.rho,
            update: self.update,
            diameter: self.params.diameter,
            tolerance: self.params.tolerance,
        };
        let (index, robots, case, degree) = (init.index, init.robots, init.case, init.degree);
        match self.variant {
            DualVariant::Fast => Box::new(FastDualAgent::new(
                index,
                &init.costs,
                allowed,
                robots,
                case,
                degree,
                params,
            )),
            DualVariant::Paper => Box::new(
                DualAgent::new(index, init.costs, robots, case, degree, params)
                    .with_allowed(allowed),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::cost_model::geometric;

    /// Uniform costs get the largest factor at every size, distance costs (nearly) the
    /// smallest from 50 robots on; the factor ignores shifts and scales of the costs and the idle columns
    /// of a normalised problem; costs that say nothing leave ρ₀ as it is (one allowed task
    /// per robot) or get the largest factor (constant costs: any assignment is optimal).
    #[test]
    fn structure_factor_follows_the_costs() {
        for n in [20, 50, 120] {
            let uniform = CostMatrix::uniform(n, n, 3).unwrap();
            assert!(structure_factor(&uniform) > 2.0, "{n}");
            if n >= 50 {
                for seed in 1..=5 {
                    let distance = geometric(n, n, seed).unwrap();
                    let factor = structure_factor(&distance);
                    assert!(factor <= 0.7, "{n} {seed}: {factor}");
                }
            }
            let moved = CostMatrix::new(
                n,
                n,
                uniform.values().iter().map(|c| 250.0 * c - 1e6).collect(),
            )
            .unwrap();
            let (a, b) = (structure_factor(&uniform), structure_factor(&moved));
            assert!((a - b).abs() <= 1e-6 * a, "{a} {b}");
            // Idle columns (cost 0 for everyone, real costs above): the same factor.
            let tasks = n / 2;
            let real = CostMatrix::uniform(n, tasks, 4).unwrap();
            let idle = CostMatrix::new(
                n,
                tasks + n - tasks,
                (0..n)
                    .flat_map(|i| {
                        let row: Vec<f64> = real.row(i).iter().map(|c| 1.0 + c).collect();
                        row.into_iter().chain(std::iter::repeat_n(0.0, n - tasks))
                    })
                    .collect(),
            )
            .unwrap();
            let (with, without) = (structure_factor(&idle), structure_factor(&real));
            assert!(
                (with - without).abs() <= 1e-9 * without,
                "{n}: {with} {without}"
            );
        }
        // Tasks and robots in three far-apart clusters: the spread is the clusters' distance,
        // not the competition's scale; the rule stays as it is.
        let mut rng = admm_ta_topologies::rng::SeededRng::new(3);
        let mut point = || {
            (
                10.0 * (rng.uniform() * 3.0).floor() + rng.uniform(),
                rng.uniform(),
            )
        };
        let (robots, tasks): (Vec<_>, Vec<_>) = (
            (0..40).map(|_| point()).collect(),
            (0..40).map(|_| point()).collect(),
        );
        let clustered = CostMatrix::new(
            40,
            40,
            robots
                .iter()
                .flat_map(|r| tasks.iter().map(move |t| f64::hypot(r.0 - t.0, r.1 - t.1)))
                .collect(),
        )
        .unwrap();
        assert_eq!(structure_factor(&clustered), 1.0);
        for (h, factor) in [
            (0.5, 1.0),
            (0.75, 2.0),
            (1.0, 3.0),
            (1.4, 1.0),
            (1.7, 0.75),
            (9.0, 0.5),
        ] {
            assert!((factor_of(h) - factor).abs() < 1e-12, "{h}");
        }
        let constant = CostMatrix::new(3, 3, vec![2.0; 9]).unwrap();
        assert_eq!(structure_factor(&constant), 1.0);
        let inf = f64::INFINITY;
        let single = CostMatrix::new(2, 2, vec![1.0, inf, inf, 5.0]).unwrap();
        assert_eq!(structure_factor(&single), 1.0);
        let huge = CostMatrix::new(2, 2, vec![1e307, -1e307, -1e307, 1e307]).unwrap();
        assert!(structure_factor(&huge).is_finite());
    }
}
