//! Dual consensus ADMM (Algorithm 2) and its inexact variant, each in two variants
//! (`--dual-variant`): `fast` (the default, [`fast`]: each robot's "one task" row is its own
//! constraint, `m` multipliers and a certificate that needs no agreement: flooded claims
//! and prices computed for them, [`snapshot`]) and `paper` (Algorithm 2 as published, [`agent`]: `n + m`
//! multipliers). The two registrations ([`DUAL`], [`INEXACT_DUAL`]) share the ρ rule and
//! schedule; the inexact method has its own setting (the γ factor). The fast variant's
//! `ρ₀` follows the costs' structure ([`structure`]).

pub mod agent;
pub mod column;
pub mod coupled_box;
pub mod fast;
pub mod finish;
pub mod snapshot;
pub mod structure;

pub use agent::{DEFAULT_GAMMA_FACTOR, DualAgent, DualParams, DualUpdate};
pub use fast::FastDualAgent;
pub use structure::structure_factor;

use crate::agent::AgentAlgorithm;
use crate::certify::stopping::StopRule;
use crate::method::info::{
    Certification, Fig2Graphs, Memory, MethodInfo, Numbers, OWN_STATE_STOPS, PaperFacts,
    ReportText, Role, TEAM_STATE, per_agent,
};
use crate::method::settings::{MethodSettings, Setting, SettingKind, SettingSpec, SettingValue};
use crate::method::team::PartLayout;
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

    /// The fast variant: its robots' constraints are their own, so a relay is an agent
    /// without a column ([`FastDualAgent::relay`]); the paper variant's robot rows are
    /// every robot's copy of every robot's constraint, and take no relays.
    fn parts(&self, settings: &S) -> Option<PartLayout> {
        (settings.variant() == DualVariant::Fast).then_some(PartLayout::Prefix)
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

impl DualTeam<'_> {
    fn params(&self) -> DualParams {
        DualParams {
            rho: self.params.rho,
            update: self.update,
            diameter: self.params.diameter,
            tolerance: self.params.tolerance,
        }
    }
}

impl TeamBuilder for DualTeam<'_> {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        let allowed: Vec<bool> = (0..self.costs.tasks())
            .map(|t| self.costs.is_allowed(init.index, t))
            .collect();
        let params = self.params();
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

    /// The fast variant's relay (the paper variant's team takes none: [`DualMethod::parts`];
    /// it gets the default, an agent at the first robot's place).
    fn relay(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        match self.variant {
            DualVariant::Fast => Box::new(FastDualAgent::relay(
                init.robots,
                init.costs.len(),
                init.case,
                init.degree,
                self.params(),
            )),
            DualVariant::Paper => {
                let costs = vec![0.0; init.costs.len()];
                self.agent(AgentInit { costs, ..init })
            }
        }
    }
}
