//! The method registry: every method the user can choose ([`Method`]: the consensus ADMM
//! methods, the baselines, the centralized optimum) and, in one place, what each one needs
//! and supports ([`MethodInfo`]): its name and one-line summary (the command line's help),
//! how it runs (a team of agents, or centrally in the caller's process), the stop rules it
//! honours and the memory a solve needs. A method a team of agents runs is an
//! [`AgentMethod`], whose [`AgentMethodInfo`] gives its payload length, its penalty rule
//! and how to build a robot's agent.
//!
//! Runners, option checks and the command line read these tables and never list methods. A
//! new method is one module (its agent implements [`crate::agent::AgentAlgorithm`]) plus
//! one registration here: a variant of [`Method`] (and of [`AgentMethod`] if it runs as
//! agents) and its entries in [`Method::info`] and [`AgentMethod::info`].
//!
//! ```
//! use admm_ta_agents::methods::{AgentMethod, Method};
//! assert_eq!(Method::Dual.agent_method(), Some(AgentMethod::Dual));
//! assert_eq!(Method::Hungarian.agent_method(), None); // solved centrally, no agents
//! assert_eq!(AgentMethod::Dual.payload_len(2, 2), 4); // ν and λ: 2 robot + 2 task prices
//! assert_eq!(Method::Dual.info().summary, "Algorithm 2, exchanges n+m multipliers");
//! ```
//!
//! Size: the types of the registry and its entries, one per method with its builder: apart,
//! the entries and the types they fill would import each other.

pub mod cbaa;
pub mod dist_hungarian;
pub mod dual;
pub mod market;
pub mod primal;
pub mod probe;
pub mod rho;

use crate::agent::AgentAlgorithm;
use crate::certify::local_stop::{CHECK_AFTER, CHECK_EVERY};
use crate::certify::stopping::StopRule;
use crate::methods::cbaa::CbaaAgent;
use crate::methods::dist_hungarian::DistHungarianAgent;
use crate::methods::dual::agent::{DEFAULT_GAMMA_FACTOR, DualAgent, DualSettings, DualUpdate};
use crate::methods::market::MarketAgent;
use crate::methods::primal::agent::{PrimalAgent, PrimalSettings, ProjectionPath};
use crate::methods::primal::readout_filter;
use crate::methods::primal::settings::PrimalVariant;
use crate::methods::rho::{DUAL_RHO_FACTOR, INEXACT_DUAL_RHO_FACTOR, RhoRule, RhoSchedule};
use crate::problem::{AssignmentCase, CostMatrix};
use serde::{Deserialize, Serialize};

/// What solves the problem: the user's choice (`--method`, the JSON's `method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Primal consensus ADMM (Algorithm 1): robots exchange `m × n` matrices.
    #[default]
    Primal,
    /// Dual consensus ADMM (Algorithm 2): robots exchange `n + m` multipliers.
    Dual,
    /// Dual consensus ADMM with the proximal-gradient x-update (no inner solve).
    InexactDual,
    /// Consensus-based auction algorithm (Choi, Brunet & How 2009): a greedy baseline.
    Cbaa,
    /// Market with strategic pricing (Liu & Shell 2013), replicated over the graph: optimal.
    Market,
    /// Distributed Hungarian as the paper runs it: flood the cost rows, solve locally.
    DistHungarian,
    /// The centralized optimum (one "round", no agents): the reference row.
    Hungarian,
}

/// A method a team of agents runs: what [`crate::method::agent::MethodAgent::new`] accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum AgentMethod {
    #[default]
    Primal,
    Dual,
    InexactDual,
    Cbaa,
    Market,
    DistHungarian,
}

/// What a method needs and supports.
#[derive(Debug)]
pub struct MethodInfo {
    /// The name used on the command line and in JSON.
    pub name: &'static str,
    /// One line for the command line's help.
    pub summary: &'static str,
    /// The agents a team runs, or `None`: solved centrally, in the caller's process (on a
    /// lockstep transport only).
    pub agents: Option<AgentMethod>,
    /// The stop rules it honours.
    pub stops: &'static [StopRule],
    /// The memory a solve needs.
    pub memory: Memory,
}

impl MethodInfo {
    /// The stop rules it honours, for messages: `local, oracle or max-iters`.
    pub fn stop_names(&self, conjunction: &str) -> String {
        let names: Vec<&str> = self.stops.iter().map(|s| s.name()).collect();
        join(&names, conjunction)
    }
}

/// The memory a solve of a method needs, refused up front when too large.
#[derive(Debug)]
pub struct Memory {
    /// Bytes for `(robots, tasks)`: every agent's state and round buffers, or the
    /// centralized solver's working memory.
    pub bytes: fn(usize, usize) -> f64,
    /// What the bytes are, for messages: `agent state`.
    pub of: &'static str,
    /// Why, for messages: `each robot holds an m×n matrix`.
    pub because: &'static str,
}

/// What a team's agents of a method need.
pub struct AgentMethodInfo {
    /// The method the user chose.
    pub method: Method,
    /// Values of the payload exchanged every round, for `(robots, tasks)`.
    pub payload_len: fn(usize, usize) -> usize,
    /// The penalty's default rule and `--adaptive-rho` schedule; `None`: no penalty.
    pub rho: Option<RhoRule>,
    /// Builds robot `index`'s agent.
    pub build: fn(AgentInit) -> Box<dyn AgentAlgorithm>,
}

impl std::fmt::Debug for AgentMethodInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AgentMethodInfo")
            .field("method", &self.method)
            .field("rho", &self.rho)
            .finish_non_exhaustive()
    }
}

/// Everything a registration's `build` gets: robot `index` of `robots` with its own costs,
/// `degree = |N(i)|`.
pub struct AgentInit<'a> {
    pub index: usize,
    pub costs: Vec<f64>,
    pub robots: usize,
    pub case: AssignmentCase,
    pub degree: usize,
    pub settings: &'a AgentSettings,
}

/// Everything an agent needs besides its costs and its place in the graph.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AgentSettings {
    pub method: AgentMethod,
    pub rho: f64,
    /// x-update solver of the primal method.
    pub projection: ProjectionPath,
    /// `g` of the inexact dual's `γ = g (m+1)/(2dρ)`.
    pub gamma_factor: f64,
    /// Graph diameter (the dual methods' certificate and the market's phases need it).
    pub diameter: usize,
    /// Total cost tolerance of the optimality certificate (the dual methods check their
    /// multipliers' agreement against it).
    pub tolerance: f64,
    /// Which primal consensus ADMM the primal method runs (ignored by the others).
    pub primal_variant: PrimalVariant,
}

impl AgentSettings {
    /// The settings with the paper's primal variant (solves choose theirs through
    /// [`AgentSettings::primal_variant`]).
    pub fn new(method: AgentMethod, rho: f64, diameter: usize, tolerance: f64) -> Self {
        Self {
            method,
            rho,
            projection: ProjectionPath::Fast,
            gamma_factor: DEFAULT_GAMMA_FACTOR,
            diameter,
            tolerance,
            primal_variant: PrimalVariant::Paper,
        }
    }

    /// The fast primal variant's certificate is a by-product of its readout: checked every
    /// round as soon as a robot agrees with its neighbours (`(1, 0)`: a 5-round cadence
    /// and a 3-round streak would add several rounds to a 6-round solve). Every
    /// other method: every [`CHECK_EVERY`] rounds after [`CHECK_AFTER`] rounds of agreement.
    pub fn stop_cadence(&self) -> (u64, u32) {
        if self.method == AgentMethod::Primal && self.primal_variant == PrimalVariant::Fast {
            (1, 0)
        } else {
            (CHECK_EVERY, CHECK_AFTER)
        }
    }
}

/// Every stop rule.
const ALL_STOPS: &[StopRule] = &[
    StopRule::Local,
    StopRule::Agreement,
    StopRule::Certified,
    StopRule::Oracle,
    StopRule::MaxIters,
];
/// The stop rules that do not read every robot's `m × n` matrix.
const OWN_STATE_STOPS: &[StopRule] = &[StopRule::Local, StopRule::Oracle, StopRule::MaxIters];

/// `8 · values` bytes for each of `robots` agents.
fn per_agent(robots: usize, values: f64) -> f64 {
    8.0 * robots as f64 * values
}

/// Values of the `n × n` matrix the exact assignment solves in Case 2 (0 in Case 1).
fn case_two_expansion(robots: usize, tasks: usize) -> f64 {
    if robots > tasks {
        (robots * robots) as f64
    } else {
        0.0
    }
}

const TEAM_STATE: &str = "agent state";

// The registrations: one `MethodInfo` per method, one `AgentMethodInfo` per team method.

const PRIMAL: MethodInfo = MethodInfo {
    name: "primal",
    summary: "Algorithm 1, exchanges m×n matrices",
    agents: Some(AgentMethod::Primal),
    stops: ALL_STOPS,
    // X, Q, Z, the projection's workspace and two round buffers: six m×n matrices; the fast
    // variant's integer multipliers, edge sums and tie-break matrix: three more; the
    // certificate's minimiser of `G_i`: one more; the readout filter's `Q̂` and exact sums
    // (three) and its history (at most `MAX_WINDOW − 1` matrices and `HISTORY_BUDGET`).
    memory: Memory {
        bytes: |n, m| {
            let values = (m * n) as f64;
            let history = (values * (readout_filter::MAX_WINDOW - 1) as f64)
                .min(readout_filter::HISTORY_BUDGET as f64);
            per_agent(n, 13.0 * values + history)
        },
        of: TEAM_STATE,
        because: "each robot holds an m×n matrix",
    },
};
const PRIMAL_AGENTS: AgentMethodInfo = AgentMethodInfo {
    method: Method::Primal,
    payload_len: |n, m| n * m,
    rho: Some(RhoRule::Primal),
    build: |a| {
        Box::new(PrimalAgent::new(
            a.index,
            a.costs,
            a.robots,
            a.case,
            a.degree,
            PrimalSettings {
                projection: a.settings.projection,
                ..PrimalSettings::for_variant(
                    a.settings.primal_variant,
                    a.settings.rho,
                    a.settings.diameter,
                    a.robots,
                    a.settings.tolerance,
                )
            },
        ))
    },
};

/// y, p, κ and two round buffers of `n + m`; costs, x and the x-update's breakpoints.
const DUAL_MEMORY: Memory = Memory {
    bytes: |n, m| per_agent(n, (5 * (n + m) + 5 * m + 2) as f64),
    of: TEAM_STATE,
    because: "each robot holds n+m multipliers",
};
const DUAL: MethodInfo = MethodInfo {
    name: "dual",
    summary: "Algorithm 2, exchanges n+m multipliers",
    agents: Some(AgentMethod::Dual),
    stops: OWN_STATE_STOPS,
    memory: DUAL_MEMORY,
};
const DUAL_AGENTS: AgentMethodInfo = AgentMethodInfo {
    method: Method::Dual,
    payload_len: |n, m| n + m,
    rho: Some(RhoRule::Dual {
        factor: DUAL_RHO_FACTOR,
    }),
    build: |a| Box::new(dual_agent(a, DualUpdate::Exact)),
};

const INEXACT_DUAL: MethodInfo = MethodInfo {
    name: "inexact-dual",
    summary: "proximal-gradient x-update, no inner solve",
    agents: Some(AgentMethod::InexactDual),
    stops: OWN_STATE_STOPS,
    memory: DUAL_MEMORY,
};
const INEXACT_DUAL_AGENTS: AgentMethodInfo = AgentMethodInfo {
    method: Method::InexactDual,
    payload_len: |n, m| n + m,
    rho: Some(RhoRule::Dual {
        factor: INEXACT_DUAL_RHO_FACTOR,
    }),
    build: |a| {
        let gamma_factor = a.settings.gamma_factor;
        Box::new(dual_agent(a, DualUpdate::Inexact { gamma_factor }))
    },
};

fn dual_agent(a: AgentInit, update: DualUpdate) -> DualAgent {
    let s = a.settings;
    DualAgent::new(
        a.index,
        a.costs,
        a.robots,
        a.case,
        a.degree,
        DualSettings {
            rho: s.rho,
            update,
            diameter: s.diameter,
            tolerance: s.tolerance,
        },
    )
}

const CBAA: MethodInfo = MethodInfo {
    name: "cbaa",
    summary: "the consensus-based auction baseline: fast, conflict-free, not optimal",
    agents: Some(AgentMethod::Cbaa),
    stops: OWN_STATE_STOPS,
    // Costs, bids and winners, the own column, two round buffers of 2m.
    memory: Memory {
        bytes: |n, m| per_agent(n, 8.0 * m as f64),
        of: TEAM_STATE,
        because: "each robot holds 2m bids and winners",
    },
};
const CBAA_AGENTS: AgentMethodInfo = AgentMethodInfo {
    method: Method::Cbaa,
    payload_len: |_, m| 2 * m,
    rho: None,
    build: |a| Box::new(CbaaAgent::new(a.index, a.costs)),
};

const MARKET: MethodInfo = MethodInfo {
    name: "market",
    summary: "Liu & Shell's price-escalation market replicated over the graph: optimal, 2·diameter rounds per price raise, sends demand bits only",
    agents: Some(AgentMethod::Market),
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
};
const MARKET_AGENTS: AgentMethodInfo = AgentMethodInfo {
    method: Method::Market,
    payload_len: |n, _| MarketAgent::payload_len_for(n),
    rho: None,
    build: |a| {
        Box::new(MarketAgent::new(
            a.index,
            a.costs,
            a.robots,
            a.settings.diameter,
        ))
    },
};

const DIST_HUNGARIAN: MethodInfo = MethodInfo {
    name: "dist-hungarian",
    summary: "robots flood their cost rows and solve locally: optimal after a graph diameter",
    agents: Some(AgentMethod::DistHungarian),
    stops: OWN_STATE_STOPS,
    // The known rows, two round buffers and the copy solved; Case 2's n×n expansion.
    memory: Memory {
        bytes: |n, m| per_agent(n, 4.0 * (n * m) as f64 + case_two_expansion(n, m)),
        of: TEAM_STATE,
        because: "each robot holds the n×m cost rows",
    },
};
const DIST_HUNGARIAN_AGENTS: AgentMethodInfo = AgentMethodInfo {
    method: Method::DistHungarian,
    payload_len: |n, m| n * m,
    rho: None,
    build: |a| Box::new(DistHungarianAgent::new(a.index, a.costs, a.robots, a.case)),
};

const HUNGARIAN: MethodInfo = MethodInfo {
    name: "hungarian",
    summary: "the centralized optimum, one round, sim only",
    agents: None,
    stops: OWN_STATE_STOPS,
    // The solver's copy of the costs (Case 2: its n×n expansion) and its O(n + m) arrays.
    memory: Memory {
        bytes: |n, m| 8.0 * ((n * m) as f64 + case_two_expansion(n, m) + 8.0 * (n + m) as f64),
        of: "working memory",
        because: "the centralized solver holds the n×m costs, n×n in Case 2",
    },
};

impl Method {
    /// The consensus ADMM methods of the paper.
    pub const ADMM: [Method; 3] = [Method::Primal, Method::Dual, Method::InexactDual];
    /// Every method, in the order of the command line's help.
    pub const ALL: [Method; 7] = [
        Method::Primal,
        Method::Dual,
        Method::InexactDual,
        Method::Cbaa,
        Method::Market,
        Method::DistHungarian,
        Method::Hungarian,
    ];

    /// What this method needs and supports.
    pub fn info(self) -> &'static MethodInfo {
        match self {
            Self::Primal => &PRIMAL,
            Self::Dual => &DUAL,
            Self::InexactDual => &INEXACT_DUAL,
            Self::Cbaa => &CBAA,
            Self::Market => &MARKET,
            Self::DistHungarian => &DIST_HUNGARIAN,
            Self::Hungarian => &HUNGARIAN,
        }
    }

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The agents a team runs, or `None` for the centralized solver.
    pub fn agent_method(self) -> Option<AgentMethod> {
        self.info().agents
    }

    /// A consensus ADMM method (it has a penalty ρ).
    pub fn is_admm(self) -> bool {
        self.rho_rule().is_some()
    }

    /// The penalty's rule, if the method has one.
    pub fn rho_rule(self) -> Option<RhoRule> {
        self.agent_method().and_then(AgentMethod::rho_rule)
    }

    /// Whether `--adaptive-rho` applies (see [`AgentMethod::has_schedule`]).
    pub fn has_schedule(self, variant: PrimalVariant) -> bool {
        self.agent_method().is_some_and(|a| a.has_schedule(variant))
    }

    /// The default ρ for these costs on a graph with this mean degree (0 for the methods
    /// without a penalty); the primal method's depends on its variant.
    pub fn default_rho(self, costs: &CostMatrix, mean_degree: f64, variant: PrimalVariant) -> f64 {
        self.rho_rule()
            .map_or(0.0, |rule| rule.rho_for(costs, mean_degree, variant))
    }

    /// Length of the payload exchanged every round (0: no messages).
    pub fn payload_len(self, robots: usize, tasks: usize) -> usize {
        self.agent_method()
            .map_or(0, |a| a.payload_len(robots, tasks))
    }

    /// Whether it honours `stop`.
    pub fn supports(self, stop: StopRule) -> bool {
        self.info().stops.contains(&stop)
    }

    /// The methods whose entry satisfies `test`, for messages: `primal`, `dual or
    /// inexact-dual` (`conjunction` joins the last two).
    pub fn names_where(test: impl Fn(&MethodInfo) -> bool, conjunction: &str) -> String {
        let names: Vec<&str> = Self::ALL
            .into_iter()
            .filter(|m| test(m.info()))
            .map(Self::name)
            .collect();
        join(&names, conjunction)
    }

    /// The command line's help of `--method`: every method with its summary.
    pub fn help() -> String {
        let entries: Vec<String> = Self::ALL
            .into_iter()
            .map(|m| format!("{} ({})", m.name(), m.info().summary))
            .collect();
        let entries: Vec<&str> = entries.iter().map(String::as_str).collect();
        join(&entries, "or")
    }
}

/// `a, b and c` (`conjunction` between the last two).
fn join(items: &[&str], conjunction: &str) -> String {
    match items.split_last() {
        None => String::new(),
        Some((last, [])) => (*last).to_string(),
        Some((last, rest)) => format!("{} {conjunction} {last}", rest.join(", ")),
    }
}

impl AgentMethod {
    /// Every team method.
    pub const ALL: [AgentMethod; 6] = [
        Self::Primal,
        Self::Dual,
        Self::InexactDual,
        Self::Cbaa,
        Self::Market,
        Self::DistHungarian,
    ];

    /// What its agents need.
    pub fn info(self) -> &'static AgentMethodInfo {
        match self {
            Self::Primal => &PRIMAL_AGENTS,
            Self::Dual => &DUAL_AGENTS,
            Self::InexactDual => &INEXACT_DUAL_AGENTS,
            Self::Cbaa => &CBAA_AGENTS,
            Self::Market => &MARKET_AGENTS,
            Self::DistHungarian => &DIST_HUNGARIAN_AGENTS,
        }
    }

    /// The method the user chose.
    pub fn method(self) -> Method {
        self.info().method
    }

    pub fn name(self) -> &'static str {
        self.method().name()
    }

    /// Length of the payload exchanged every round.
    pub fn payload_len(self, robots: usize, tasks: usize) -> usize {
        (self.info().payload_len)(robots, tasks)
    }

    /// The penalty's rule, if the method has one.
    pub fn rho_rule(self) -> Option<RhoRule> {
        self.info().rho
    }

    /// The `--adaptive-rho` schedule from `initial`, if the method has a penalty.
    pub fn schedule(self, initial: f64) -> Option<RhoSchedule> {
        self.rho_rule().map(|rule| rule.schedule(initial))
    }

    /// Whether `--adaptive-rho` applies: a method with a penalty, and for the primal
    /// method the paper's variant only (the fast variant runs in a regime where ρ drops
    /// out of the iteration; the schedule was measured for the paper's readout).
    pub fn has_schedule(self, variant: PrimalVariant) -> bool {
        self.rho_rule().is_some() && !(self == Self::Primal && variant == PrimalVariant::Fast)
    }
}

#[cfg(feature = "clap")]
crate::clap_value_enum!(Method);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_registry_is_consistent() {
        for method in Method::ALL {
            let json = serde_json::to_string(&method).unwrap();
            assert_eq!(json, format!("\"{}\"", method.name()));
            if let Some(agents) = method.agent_method() {
                assert_eq!(agents.method(), method);
                assert_eq!(serde_json::to_string(&agents).unwrap(), json);
            }
            assert!(method.supports(StopRule::Local) && method.supports(StopRule::MaxIters));
        }
        for agents in AgentMethod::ALL {
            assert_eq!(agents.method().agent_method(), Some(agents));
        }
        assert_eq!(
            Method::ALL
                .iter()
                .filter(|m| m.agent_method().is_none())
                .count(),
            1
        );
        assert_eq!(
            Method::ALL
                .into_iter()
                .filter(|m| m.is_admm())
                .collect::<Vec<_>>(),
            Method::ADMM
        );
        assert_eq!(
            Method::names_where(|i| i.stops.contains(&StopRule::Certified), "or"),
            "primal"
        );
        assert!(Method::help().starts_with("primal (Algorithm 1, exchanges m×n matrices), dual ("));
        assert!(
            Method::help()
                .ends_with(" or hungarian (the centralized optimum, one round, sim only)")
        );
    }

    #[test]
    fn memory_estimates_follow_what_each_method_holds() {
        let gib =
            |m: Method, n: usize, t: usize| (m.info().memory.bytes)(n, t) / (1u64 << 30) as f64;
        // The primal's m×n matrix per robot: 5000 × 5000 is far beyond 8 GiB …
        assert!(gib(Method::Primal, 5000, 5000) > 5000.0);
        // … the dual's n + m multipliers and the centralized solver are not.
        assert!(gib(Method::Dual, 5000, 5000) < 8.0);
        assert!(gib(Method::Hungarian, 5000, 5000) < 1.0);
        assert!(
            gib(Method::Hungarian, 100_000, 2) > 8.0,
            "Case 2's n×n expansion"
        );
    }
}
