//! The methods (consensus ADMM, the baselines), and one agent type that runs any of the
//! distributed ones, so that runners and transports handle every method the same way.
//!
//! ```
//! use admm_ta_agents::agent::ConsensusAgent;
//! use admm_ta_agents::method::{AgentSettings, Method, MethodAgent};
//! use admm_ta_agents::problem::AssignmentCase;
//! let settings = AgentSettings::new(Method::Dual, 0.5, 1, 1e-9);
//! let agent = MethodAgent::new(0, vec![0.2, 0.7], 2, AssignmentCase::One, 1, settings);
//! assert_eq!(agent.payload_len(), 4); // ν: 2 robot rows + 2 task rows
//! ```

use crate::agent::{ConsensusAgent, Inbox, StepReport};
use crate::cbaa::CbaaAgent;
use crate::dist_hungarian::DistHungarianAgent;
use crate::dual::{DEFAULT_GAMMA_FACTOR, DualAgent, DualSettings, DualUpdate};
use crate::market::MarketAgent;
use crate::primal::{PrimalAgent, PrimalSettings, ProjectionPath};
use crate::problem::AssignmentCase;
use crate::rho::RhoSchedule;
use serde::{Deserialize, Serialize};

/// A consensus ADMM method of the paper.
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

impl Method {
    /// The consensus ADMM methods of the paper.
    pub const ADMM: [Method; 3] = [Method::Primal, Method::Dual, Method::InexactDual];
    /// Every method.
    pub const ALL: [Method; 7] = [
        Method::Primal,
        Method::Dual,
        Method::InexactDual,
        Method::Cbaa,
        Method::Market,
        Method::DistHungarian,
        Method::Hungarian,
    ];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Primal => "primal",
            Self::Dual => "dual",
            Self::InexactDual => "inexact-dual",
            Self::Cbaa => "cbaa",
            Self::Market => "market",
            Self::DistHungarian => "dist-hungarian",
            Self::Hungarian => "hungarian",
        }
    }

    /// A consensus ADMM method (it has a penalty ρ).
    pub fn is_admm(self) -> bool {
        Self::ADMM.contains(&self)
    }

    /// Length of the payload exchanged every round (0: no messages).
    pub fn payload_len(self, robots: usize, tasks: usize) -> usize {
        match self {
            Self::Primal | Self::DistHungarian => robots * tasks,
            Self::Dual | Self::InexactDual => robots + tasks,
            Self::Cbaa => 2 * tasks,
            Self::Market => MarketAgent::payload_len_for(robots),
            Self::Hungarian => 0,
        }
    }
}

/// Everything an agent needs besides its costs and its place in the graph.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AgentSettings {
    pub method: Method,
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
}

impl AgentSettings {
    pub fn new(method: Method, rho: f64, diameter: usize, tolerance: f64) -> Self {
        Self {
            method,
            rho,
            projection: ProjectionPath::Fast,
            gamma_factor: DEFAULT_GAMMA_FACTOR,
            diameter,
            tolerance,
        }
    }
}

/// An agent of any method, optionally following a ρ schedule (applied by the agent itself
/// before each step, so every transport changes ρ at the same round).
pub struct MethodAgent {
    algorithm: Algorithm,
    schedule: Option<RhoSchedule>,
    steps: u64,
}

enum Algorithm {
    Primal(PrimalAgent),
    Dual(DualAgent),
    Cbaa(CbaaAgent),
    Market(MarketAgent),
    DistHungarian(DistHungarianAgent),
}

impl MethodAgent {
    /// Robot `index` of `robots` with its own costs, `degree = |N(i)|`.
    ///
    /// # Panics
    /// For [`Method::Hungarian`], which has no agents (runners solve it centrally).
    pub fn new(
        index: usize,
        costs: Vec<f64>,
        robots: usize,
        case: AssignmentCase,
        degree: usize,
        settings: AgentSettings,
    ) -> Self {
        let dual = |update| DualSettings {
            rho: settings.rho,
            update,
            diameter: settings.diameter,
            tolerance: settings.tolerance,
        };
        let algorithm = match settings.method {
            Method::Primal => Algorithm::Primal(PrimalAgent::new(
                index,
                costs,
                robots,
                case,
                degree,
                PrimalSettings {
                    projection: settings.projection,
                    ..PrimalSettings::new(settings.rho)
                },
            )),
            Method::Dual => Algorithm::Dual(DualAgent::new(
                index,
                costs,
                robots,
                case,
                degree,
                dual(DualUpdate::Exact),
            )),
            Method::InexactDual => Algorithm::Dual(DualAgent::new(
                index,
                costs,
                robots,
                case,
                degree,
                dual(DualUpdate::Inexact {
                    gamma_factor: settings.gamma_factor,
                }),
            )),
            Method::Cbaa => Algorithm::Cbaa(CbaaAgent::new(index, costs)),
            Method::Market => {
                Algorithm::Market(MarketAgent::new(index, costs, robots, settings.diameter))
            }
            Method::DistHungarian => {
                Algorithm::DistHungarian(DistHungarianAgent::new(index, costs, robots, case))
            }
            Method::Hungarian => panic!("the centralized Hungarian method has no agents"),
        };
        Self {
            algorithm,
            schedule: None,
            steps: 0,
        }
    }

    /// Follow `schedule` (from the next step on, counted from the first step).
    pub fn with_schedule(mut self, schedule: Option<RhoSchedule>) -> Self {
        self.schedule = schedule;
        self
    }

    /// Changes ρ from the next step on; every robot must change it at the same round
    /// (no effect on methods without a ρ).
    pub fn set_rho(&mut self, rho: f64) {
        match &mut self.algorithm {
            Algorithm::Primal(a) => a.set_rho(rho),
            Algorithm::Dual(a) => a.set_rho(rho),
            Algorithm::Cbaa(_) | Algorithm::Market(_) | Algorithm::DistHungarian(_) => {}
        }
    }

    /// New own costs for the next episode of a repeated assignment, warm-started from the
    /// current iterates or (`warm = false`) from zero; primal consensus ADMM only.
    pub fn set_costs(&mut self, costs: &[f64], warm: bool) -> Result<(), String> {
        match &mut self.algorithm {
            Algorithm::Primal(a) if costs.len() == a.iterate().nrows() => {
                a.set_costs(costs);
                if !warm {
                    a.reset();
                }
                Ok(())
            }
            Algorithm::Primal(_) => Err(format!(
                "{} costs for a robot with another number of tasks",
                costs.len()
            )),
            _ => Err("repeated assignments with new costs run the primal method only".into()),
        }
    }

    /// The primal agent inside, if this is one.
    pub fn as_primal(&self) -> Option<&PrimalAgent> {
        match &self.algorithm {
            Algorithm::Primal(a) => Some(a),
            Algorithm::Dual(_)
            | Algorithm::Cbaa(_)
            | Algorithm::Market(_)
            | Algorithm::DistHungarian(_) => None,
        }
    }

    fn inner(&self) -> &dyn ConsensusAgent {
        match &self.algorithm {
            Algorithm::Primal(a) => a,
            Algorithm::Dual(a) => a,
            Algorithm::Cbaa(a) => a,
            Algorithm::Market(a) => a,
            Algorithm::DistHungarian(a) => a,
        }
    }
}

impl ConsensusAgent for MethodAgent {
    fn payload_len(&self) -> usize {
        self.inner().payload_len()
    }
    fn write_initial_payload(&self, out: &mut [f64]) {
        self.inner().write_initial_payload(out)
    }
    fn check_payload(&self, payload: &[f64]) -> Result<(), String> {
        self.inner().check_payload(payload)
    }
    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        if let Some(schedule) = self.schedule {
            self.set_rho(schedule.rho(self.steps));
        }
        self.steps += 1;
        match &mut self.algorithm {
            Algorithm::Primal(a) => a.step(inbox, out),
            Algorithm::Dual(a) => a.step(inbox, out),
            Algorithm::Cbaa(a) => a.step(inbox, out),
            Algorithm::Market(a) => a.step(inbox, out),
            Algorithm::DistHungarian(a) => a.step(inbox, out),
        }
    }
    fn decide(&self) -> usize {
        self.inner().decide()
    }
    fn rounded_task(&self) -> usize {
        self.inner().rounded_task()
    }
    fn certificate_slack(&self) -> f64 {
        self.inner().certificate_slack()
    }
    fn own_column(&self) -> &[f64] {
        self.inner().own_column()
    }
}
