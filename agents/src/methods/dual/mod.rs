//! Dual consensus ADMM (Algorithm 2) and its inexact variant — the agent ([`agent`]) and
//! the two registrations ([`DUAL`], [`INEXACT_DUAL`]): payload `n + m` multipliers, the dual
//! ρ rule and schedule, and the inexact variant's own setting (the γ factor).

pub mod agent;

pub use agent::{DEFAULT_GAMMA_FACTOR, DualAgent, DualParams, DualUpdate};

use crate::agent::AgentAlgorithm;
use crate::method::info::{
    Certification, Fig2Graphs, Memory, MethodInfo, Numbers, OWN_STATE_STOPS, PaperFacts,
    ReportText, Role, TEAM_STATE, per_agent,
};
use crate::method::settings::{
    MethodSettings, NoSettings, Setting, SettingKind, SettingSpec, SettingValue,
};
use crate::method::team::{AgentInit, TeamBuilder, TeamContext, TeamMethod, TeamParams};
use crate::methods::rho::{DUAL_RHO_FACTOR, INEXACT_DUAL_RHO_FACTOR, RhoRule, RhoSchedule};
use crate::problem::CostMatrix;
use serde::{Deserialize, Serialize};

/// y, p, κ and two round buffers of `n + m`; costs, x and the x-update's breakpoints.
const DUAL_MEMORY: Memory = Memory {
    bytes: |n, m| per_agent(n, (5 * (n + m) + 5 * m + 2) as f64),
    of: TEAM_STATE,
    because: "each robot holds n+m multipliers",
};

/// The dual method's registration.
pub const DUAL: MethodInfo = MethodInfo {
    name: "dual",
    summary: "Algorithm 2, exchanges n+m multipliers",
    role: Role::Admm,
    team: Some(&DualMethod),
    variants: None,
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
        variant: None,
    }),
};

/// The inexact dual's registration.
pub const INEXACT_DUAL: MethodInfo = MethodInfo {
    name: "inexact-dual",
    summary: "proximal-gradient x-update, no inner solve",
    role: Role::Admm,
    team: Some(&InexactDualMethod),
    variants: None,
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
        variant: None,
    }),
};

/// The inexact dual's own settings (`--gamma-factor`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InexactDualSettings {
    /// `g` of the proximal weight `γ = g (m+1)/(2dρ)`.
    pub gamma_factor: f64,
}

impl Default for InexactDualSettings {
    fn default() -> Self {
        Self {
            gamma_factor: DEFAULT_GAMMA_FACTOR,
        }
    }
}

/// `--gamma-factor`.
pub const GAMMA_FACTOR: SettingSpec = SettingSpec {
    key: "gamma_factor",
    flag: "--gamma-factor",
    value_name: "GAMMA_FACTOR",
    help: "Inexact dual: g of the proximal weight γ = g·(m+1)/(2·|N(i)|·ρ) (default 0.5); refused with the other methods",
    kind: SettingKind::PositiveNumber {
        what: "the γ factor",
    },
};

impl MethodSettings for InexactDualSettings {
    const SPECS: &'static [SettingSpec] = &[GAMMA_FACTOR];
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

/// Dual consensus ADMM (Algorithm 2) as a team method.
pub struct DualMethod;

/// The inexact dual as a team method.
pub struct InexactDualMethod;

impl TeamMethod for DualMethod {
    type Settings = NoSettings;
    const PENALTY: bool = true;

    fn payload_len(&self, robots: usize, tasks: usize) -> usize {
        robots + tasks
    }

    fn default_rho(&self, _: &NoSettings, costs: &CostMatrix, degree: f64) -> f64 {
        RULE.rho(costs, degree)
    }

    fn schedule(&self, _: &NoSettings, initial: f64) -> Option<RhoSchedule> {
        Some(RULE.schedule(initial))
    }

    fn team<'a>(&'static self, _: &NoSettings, team: TeamContext<'a>) -> Box<dyn TeamBuilder + 'a> {
        Box::new(DualTeam::new(team, DualUpdate::Exact))
    }

    fn stop_cadence(&self, _: &NoSettings) -> (u64, u32) {
        CADENCE
    }
}

impl TeamMethod for InexactDualMethod {
    type Settings = InexactDualSettings;
    const PENALTY: bool = true;

    fn payload_len(&self, robots: usize, tasks: usize) -> usize {
        robots + tasks
    }

    fn default_rho(&self, _: &InexactDualSettings, costs: &CostMatrix, degree: f64) -> f64 {
        INEXACT_RULE.rho(costs, degree)
    }

    fn schedule(&self, _: &InexactDualSettings, initial: f64) -> Option<RhoSchedule> {
        Some(INEXACT_RULE.schedule(initial))
    }

    fn team<'a>(
        &'static self,
        settings: &InexactDualSettings,
        team: TeamContext<'a>,
    ) -> Box<dyn TeamBuilder + 'a> {
        Box::new(DualTeam::new(
            team,
            DualUpdate::Inexact {
                gamma_factor: settings.gamma_factor,
            },
        ))
    }

    fn stop_cadence(&self, _: &InexactDualSettings) -> (u64, u32) {
        CADENCE
    }
}

/// The certificate is checked every round: its disagreement level changes every round (see
/// [`agent`]), and a robot never sees the team's assignment, so there is no agreement
/// streak to wait for.
const CADENCE: (u64, u32) = (1, 0);

const RULE: RhoRule = RhoRule::Dual {
    factor: DUAL_RHO_FACTOR,
};
const INEXACT_RULE: RhoRule = RhoRule::Dual {
    factor: INEXACT_DUAL_RHO_FACTOR,
};

/// Builds a dual team's agents.
struct DualTeam<'a> {
    params: TeamParams,
    update: DualUpdate,
    /// The team's costs, for each robot's own forbidden pairs.
    costs: &'a CostMatrix,
}

impl<'a> DualTeam<'a> {
    fn new(team: TeamContext<'a>, update: DualUpdate) -> Self {
        Self {
            params: team.params,
            update,
            costs: team.problem.costs(),
        }
    }
}

impl TeamBuilder for DualTeam<'_> {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        let allowed = (0..self.costs.tasks())
            .map(|t| self.costs.is_allowed(init.index, t))
            .collect();
        Box::new(
            DualAgent::new(
                init.index,
                init.costs,
                init.robots,
                init.case,
                init.degree,
                DualParams {
                    rho: self.params.rho,
                    update: self.update,
                    diameter: self.params.diameter,
                    tolerance: self.params.tolerance,
                },
            )
            .with_allowed(allowed),
        )
    }
}
