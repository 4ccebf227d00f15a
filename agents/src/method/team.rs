//! How a method's team is built: the trait each team method implements once
//! ([`TeamMethod`], typed by its settings), and what runners hold of it — the method with its
//! settings ([`MethodSetup`]) and a builder of every robot's agent ([`TeamBuilder`]), which
//! carries whatever the team shares (set up once per team, e.g. the fast primal variant's
//! readout filter). Runners never name a method: they ask these.

use crate::agent::AgentAlgorithm;
use crate::certify::local_stop::{CHECK_AFTER, CHECK_EVERY};
use crate::certify::stopping::StopRule;
use crate::method::settings::{GivenSettings, MethodSettings, SettingError, SettingSpec};
use crate::methods::rho::RhoSchedule;
use crate::problem::{AssignmentCase, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::Graph;

/// What every agent of a team is given besides its own costs: the same numbers at every
/// robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TeamParams {
    /// The penalty ρ (0 for the methods without one).
    pub rho: f64,
    /// The graph's diameter (the dual methods' certificate and the market's phases need it).
    pub diameter: usize,
    /// Total cost tolerance of the optimality certificate (`∞`: no certificate).
    pub tolerance: f64,
}

/// The team a builder makes agents for: the (normalised) problem the agents solve, their
/// graph and the team's numbers.
#[derive(Clone, Copy)]
pub struct TeamContext<'a> {
    pub problem: &'a TaskAssignmentProblem,
    pub graph: &'a Graph,
    pub params: TeamParams,
}

/// Robot `index`'s start: its own costs and its place in the graph.
#[derive(Debug, Clone, PartialEq)]
pub struct AgentInit {
    pub index: usize,
    /// Its own costs, one per task.
    pub costs: Vec<f64>,
    pub robots: usize,
    pub case: AssignmentCase,
    /// `|N(i)|`.
    pub degree: usize,
}

/// Builds every robot's agent of one team, with whatever the team shares.
pub trait TeamBuilder: Send + Sync {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm>;

    /// An agent that relays for the team (a standing team's robot that takes no task in an
    /// episode, [`crate::method::masked`]): it exchanges like the others and adds nothing
    /// to the team's costs. `init` is the first robot's (its costs are not used). By default
    /// that robot's agent, to be given zero costs ([`PartLayout::Block`]'s relay).
    fn relay(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        let costs = vec![0.0; init.costs.len()];
        self.agent(AgentInit { costs, ..init })
    }
}

/// How the robots of a method decide their own task, for observers of a lockstep run (the
/// paper's 0.1 % criterion on decisions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decisions {
    /// The largest entry of the robot's own relaxed column.
    OwnColumn,
    /// The robot's own task in its readout of the team's assignment.
    Readout,
}

/// An option of the run that a method's settings exclude.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunOption {
    AdaptiveRho,
    Stop(StopRule),
}

/// Why a method's settings refuse an option of the run: it needs `needs` set to `value`
/// (`because`: `the paper's primal variant, not the fast one`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refusal {
    pub option: RunOption,
    pub needs: &'static SettingSpec,
    pub value: &'static str,
    pub because: &'static str,
}

/// How a method's message of a part sits in the team's message ([`crate::method::masked`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PartLayout {
    /// The message is the team's `m × n` assignment matrix (column-major tasks × robots):
    /// the part's block, in place.
    Block,
    /// The part's own message (never longer than the whole team's: the method's payload
    /// grows with robots and tasks) as the first values of the team's.
    Prefix,
}

/// A method whose team of agents solves the problem, implemented once per method; runners
/// see it through [`AnyTeamMethod`] and [`MethodSetup`].
pub trait TeamMethod: Sync + 'static {
    /// Its own settings ([`crate::method::settings::NoSettings`] when it has none).
    type Settings: MethodSettings;

    /// Whether it has a penalty ρ (`--rho` and `--adaptive-rho` apply to it).
    const PENALTY: bool;

    /// Values of the payload exchanged every round with these settings, for
    /// `(robots, tasks)`.
    fn payload_len(&self, settings: &Self::Settings, robots: usize, tasks: usize) -> usize;

    /// The default ρ for these costs on a graph with this mean degree (methods with a
    /// penalty; 0 for the others).
    fn default_rho(&self, _settings: &Self::Settings, _costs: &CostMatrix, _degree: f64) -> f64 {
        0.0
    }

    /// Its `--adaptive-rho` schedule from `initial`, if these settings follow one.
    fn schedule(&self, _settings: &Self::Settings, _initial: f64) -> Option<RhoSchedule> {
        None
    }

    /// Refuses an option of the run these settings never honour.
    fn refuse(
        &self,
        _settings: &Self::Settings,
        _adaptive_rho: bool,
        _stop: StopRule,
    ) -> Result<(), Refusal> {
        Ok(())
    }

    /// The decentralized stop's cadence: check every `.0` rounds after `.1` rounds of
    /// agreement.
    fn stop_cadence(&self, _settings: &Self::Settings) -> (u64, u32) {
        (CHECK_EVERY, CHECK_AFTER)
    }

    fn decisions(&self, _settings: &Self::Settings) -> Decisions {
        Decisions::OwnColumn
    }

    /// Whether a standing team whose robots keep their costs private may run it with these
    /// settings, and how its message of part of the team sits in the team's
    /// ([`crate::method::masked`]): its agents take new own costs between episodes
    /// ([`crate::agent::AgentAlgorithm::set_costs`]) and relay
    /// ([`TeamBuilder::relay`]). `None`: it may not.
    fn parts(&self, _settings: &Self::Settings) -> Option<PartLayout> {
        None
    }

    /// The builder of `team`'s agents.
    fn team<'a>(
        &'static self,
        settings: &Self::Settings,
        team: TeamContext<'a>,
    ) -> Box<dyn TeamBuilder + 'a>;
}

/// A team method as the registry holds it, whatever its settings type.
pub trait AnyTeamMethod: Sync {
    /// Its own settings.
    fn settings(&self) -> &'static [SettingSpec];
    fn penalty(&self) -> bool;
    /// A private standing team may run it with its default settings ([`TeamMethod::parts`]).
    fn parts(&self) -> Option<PartLayout>;
    /// Values of the payload with the method's default settings.
    fn payload_len(&self, robots: usize, tasks: usize) -> usize;
    /// The method with the `given` settings (each must be one of its own), checked.
    fn configure(
        &'static self,
        given: &GivenSettings,
    ) -> Result<Box<dyn MethodSetup>, SettingError>;
    /// The method with settings as [`MethodSetup::settings_json`] wrote them.
    fn configure_json(
        &'static self,
        json: &serde_json::Value,
    ) -> Result<Box<dyn MethodSetup>, serde_json::Error>;
}

/// A team method with its settings: everything a runner asks of it.
pub trait MethodSetup: std::fmt::Debug + Send + Sync {
    fn payload_len(&self, robots: usize, tasks: usize) -> usize;
    /// The settings, as the scenario file of agent processes carries them.
    fn settings_json(&self) -> serde_json::Value;
    /// The default ρ (`None`: no penalty).
    fn default_rho(&self, costs: &CostMatrix, mean_degree: f64) -> Option<f64>;
    fn schedule(&self, initial: f64) -> Option<RhoSchedule>;
    fn refuse(&self, adaptive_rho: bool, stop: StopRule) -> Result<(), Refusal>;
    fn stop_cadence(&self) -> (u64, u32);
    fn decisions(&self) -> Decisions;
    /// A private standing team may run it with these settings ([`TeamMethod::parts`]).
    fn parts(&self) -> Option<PartLayout>;
    fn team<'a>(&self, team: TeamContext<'a>) -> Box<dyn TeamBuilder + 'a>;
}

/// A [`TeamMethod`] with its settings.
struct Setup<M: TeamMethod> {
    method: &'static M,
    settings: M::Settings,
}

impl<M: TeamMethod> std::fmt::Debug for Setup<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Setup")
            .field("settings", &self.settings)
            .finish()
    }
}

impl<M: TeamMethod> MethodSetup for Setup<M> {
    fn payload_len(&self, robots: usize, tasks: usize) -> usize {
        self.method.payload_len(&self.settings, robots, tasks)
    }
    fn settings_json(&self) -> serde_json::Value {
        serde_json::to_value(&self.settings).expect("settings serialise")
    }
    fn default_rho(&self, costs: &CostMatrix, mean_degree: f64) -> Option<f64> {
        M::PENALTY.then(|| self.method.default_rho(&self.settings, costs, mean_degree))
    }
    fn schedule(&self, initial: f64) -> Option<RhoSchedule> {
        self.method.schedule(&self.settings, initial)
    }
    fn refuse(&self, adaptive_rho: bool, stop: StopRule) -> Result<(), Refusal> {
        self.method.refuse(&self.settings, adaptive_rho, stop)
    }
    fn stop_cadence(&self) -> (u64, u32) {
        self.method.stop_cadence(&self.settings)
    }
    fn decisions(&self) -> Decisions {
        self.method.decisions(&self.settings)
    }
    fn parts(&self) -> Option<PartLayout> {
        self.method.parts(&self.settings)
    }
    fn team<'a>(&self, team: TeamContext<'a>) -> Box<dyn TeamBuilder + 'a> {
        self.method.team(&self.settings, team)
    }
}

impl<M: TeamMethod> AnyTeamMethod for M {
    fn settings(&self) -> &'static [SettingSpec] {
        M::Settings::SPECS
    }
    fn penalty(&self) -> bool {
        M::PENALTY
    }
    fn parts(&self) -> Option<PartLayout> {
        TeamMethod::parts(self, &M::Settings::default())
    }
    fn payload_len(&self, robots: usize, tasks: usize) -> usize {
        TeamMethod::payload_len(self, &M::Settings::default(), robots, tasks)
    }
    fn configure(
        &'static self,
        given: &GivenSettings,
    ) -> Result<Box<dyn MethodSetup>, SettingError> {
        Ok(Box::new(Setup {
            method: self,
            settings: M::Settings::from_given(given)?,
        }))
    }
    fn configure_json(
        &'static self,
        json: &serde_json::Value,
    ) -> Result<Box<dyn MethodSetup>, serde_json::Error> {
        Ok(Box::new(Setup {
            method: self,
            settings: serde_json::from_value(json.clone())?,
        }))
    }
}
