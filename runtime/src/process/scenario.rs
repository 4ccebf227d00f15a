//! The scenario file the launcher writes into the run directory: everything an agent
//! process needs to rebuild its own agent, its plan and its end of the transport. Floating-point
//! values travel as their bit patterns, so every process computes with exactly the same
//! numbers as the lockstep simulation.

use crate::exchange::round_loop::{AgentPlan, AgentStop};
use crate::options::run::RunOptions;
use crate::transport::Transport;
use crate::wait::WaitStrategy;
use crate::workload::Workload;
use crate::workload::episode::EpisodeSettings;
use crate::workload::plan::AgentFactory;
use crate::zenoh_net::links::ZenohLinks;
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::local_stop::LocalCertifiedStop;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::methods::primal::agent::ProjectionPath;
use admm_ta_agents::methods::primal::settings::PrimalVariant;
use admm_ta_agents::methods::probe::{ProbeAgent, ProbeStep};
use admm_ta_agents::methods::{AgentMethod, AgentSettings};
use admm_ta_agents::problem::{AssignmentCase, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::Graph;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How agents stop, as written in the scenario.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScenarioStop {
    /// Decentralized certified stop with this total tolerance (bits of an f64).
    Local {
        tolerance_bits: u64,
    },
    MaxIters,
}

/// What the agents compute.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScenarioWorkload {
    /// The scenario's method on its problem.
    #[default]
    Method,
    /// A benchmark probe ([`ProbeAgent`]) with a payload of `payload_len` values.
    Probe { payload_len: usize, step: ProbeStep },
    /// Repeated surveillance episodes with the primal method ([`crate::episodes`]).
    Episodes(Box<EpisodeSettings>),
}

/// One run, as the agents see it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    pub run_id: String,
    pub iceoryx_prefix: String,
    pub iceoryx_root: PathBuf,
    pub robots: usize,
    pub tasks: usize,
    pub case: AssignmentCase,
    /// Row-major `n × m` costs as f64 bits.
    pub cost_bits: Vec<u64>,
    pub edges: Vec<(usize, usize)>,
    pub topology: String,
    pub method: AgentMethod,
    pub rho_bits: u64,
    pub gamma_factor_bits: u64,
    /// Follow the `--adaptive-rho` schedule from `rho_bits`.
    pub adaptive_rho: bool,
    pub epsilon_bits: Option<u64>,
    pub seed: u64,
    pub qp_projection: bool,
    /// The primal method's variant.
    #[serde(default)]
    pub primal_variant: PrimalVariant,
    pub stop: ScenarioStop,
    pub max_rounds: u64,
    pub diameter: usize,
    pub round_timeout_ms: u64,
    pub startup_timeout_ms: u64,
    /// Shared memory of the run's board (arrival counters, global barrier).
    pub board_shm: String,
    pub global_barrier: bool,
    #[serde(default)]
    pub workload: ScenarioWorkload,
    /// A process transport.
    pub transport: Transport,
    #[serde(default)]
    pub wait: WaitStrategy,
    /// Rounds before latency is recorded.
    #[serde(default)]
    pub warmup_rounds: u64,
    /// Where the agents' Zenoh sessions connect (the Zenoh transport).
    #[serde(default)]
    pub zenoh: Option<ZenohLinks>,
    /// The agents on this host, in a mixed team (the others are reached through the host's
    /// bridge); `None`: every agent is here.
    #[serde(default)]
    pub local_agents: Option<Vec<usize>>,
}

/// A scenario that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    #[error("scenario {path} is malformed")]
    Parse {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("scenario {path} belongs to run {found}, not {expected}")]
    WrongRun {
        path: PathBuf,
        found: String,
        expected: String,
    },
    #[error("agent index {index} is out of range for {robots} robots")]
    BadIndex { index: usize, robots: usize },
    #[error("scenario is inconsistent: {0}")]
    Inconsistent(String),
}

impl Scenario {
    /// The scenario of agent processes computing `workload` on `graph`, run as `options`
    /// say; the run's names (id, iceoryx2 prefix and root, board) are left to whoever starts
    /// the run (the launcher, or the members of an independently started team).
    pub fn new(workload: Workload<'_>, graph: &Graph, options: &RunOptions) -> Self {
        let robots = graph.robots();
        // A team of `tasks` tasks and nothing else decided yet: zero costs, the primal
        // method, run to the round limit.
        let blank = |tasks: usize| Self {
            run_id: String::new(),
            iceoryx_prefix: String::new(),
            iceoryx_root: PathBuf::new(),
            robots,
            tasks,
            case: if robots == tasks {
                AssignmentCase::One
            } else {
                AssignmentCase::Two
            },
            cost_bits: vec![0; robots * tasks],
            edges: graph.edges().collect(),
            topology: graph.name().to_string(),
            method: AgentMethod::Primal,
            rho_bits: 0,
            gamma_factor_bits: 0,
            adaptive_rho: false,
            epsilon_bits: None,
            seed: 0,
            qp_projection: false,
            primal_variant: PrimalVariant::Paper,
            stop: ScenarioStop::MaxIters,
            max_rounds: 0,
            diameter: graph.diameter().unwrap_or(0),
            round_timeout_ms: options.round_timeout().as_millis() as u64,
            startup_timeout_ms: options.startup_timeout().as_millis() as u64,
            board_shm: String::new(),
            global_barrier: options.global_barrier(),
            workload: ScenarioWorkload::Method,
            transport: options.transport(),
            wait: options.wait(),
            warmup_rounds: options.warmup_rounds(),
            zenoh: None,
            local_agents: None,
        };
        match workload {
            Workload::Solve {
                plan,
                stop,
                max_rounds,
            } => {
                let problem = plan.agents.problem;
                let settings = &plan.agents.settings;
                Self {
                    case: problem.case(),
                    cost_bits: problem
                        .costs()
                        .values()
                        .iter()
                        .map(|v| v.to_bits())
                        .collect(),
                    method: settings.method,
                    rho_bits: settings.rho.to_bits(),
                    gamma_factor_bits: settings.gamma_factor.to_bits(),
                    adaptive_rho: plan.agents.schedule.is_some(),
                    epsilon_bits: plan.agents.epsilon.map(f64::to_bits),
                    seed: plan.agents.seed,
                    qp_projection: settings.projection == ProjectionPath::Qp,
                    primal_variant: settings.primal_variant,
                    stop: match stop {
                        AgentStop::MaxIters => ScenarioStop::MaxIters,
                        AgentStop::Local(_) => ScenarioStop::Local {
                            tolerance_bits: plan.tolerance.to_bits(),
                        },
                    },
                    max_rounds,
                    diameter: plan.diameter,
                    ..blank(problem.tasks())
                }
            }
            Workload::Probe {
                payload_len,
                step,
                rounds,
            } => Self {
                max_rounds: rounds,
                workload: ScenarioWorkload::Probe { payload_len, step },
                ..blank(1)
            },
            Workload::Episodes {
                settings,
                max_rounds,
            } => Self {
                case: AssignmentCase::Two,
                cost_bits: settings
                    .model
                    .initial_costs()
                    .iter()
                    .map(|v| v.to_bits())
                    .collect(),
                rho_bits: settings.rho.to_bits(),
                max_rounds,
                diameter: settings.diameter,
                workload: ScenarioWorkload::Episodes(Box::new(settings.clone())),
                ..blank(settings.model.tasks())
            },
        }
    }

    /// The scenario of run `run_id` in `bytes` (read from `path`).
    pub fn parse(bytes: &[u8], path: &Path, run_id: &str) -> Result<Self, ScenarioError> {
        let scenario: Self =
            serde_json::from_slice(bytes).map_err(|source| ScenarioError::Parse {
                path: path.to_path_buf(),
                source,
            })?;
        if scenario.run_id != run_id {
            return Err(ScenarioError::WrongRun {
                path: path.to_path_buf(),
                found: scenario.run_id,
                expected: run_id.to_string(),
            });
        }
        Ok(scenario)
    }

    pub fn problem(&self) -> Result<TaskAssignmentProblem, ScenarioError> {
        let values = self.cost_bits.iter().map(|&b| f64::from_bits(b)).collect();
        let costs = CostMatrix::new(self.robots, self.tasks, values)
            .map_err(|e| ScenarioError::Inconsistent(e.to_string()))?;
        TaskAssignmentProblem::internal_from(costs, self.case)
            .map_err(|e| ScenarioError::Inconsistent(e.to_string()))
    }

    pub fn graph(&self) -> Result<Graph, ScenarioError> {
        Graph::from_edges(self.robots, &self.edges, self.topology.clone())
            .map_err(|e| ScenarioError::Inconsistent(e.to_string()))
    }

    pub fn settings(&self) -> AgentSettings {
        let tolerance = match self.stop {
            ScenarioStop::Local { tolerance_bits } => f64::from_bits(tolerance_bits),
            ScenarioStop::MaxIters => f64::INFINITY,
        };
        AgentSettings {
            projection: if self.qp_projection {
                ProjectionPath::Qp
            } else {
                ProjectionPath::Fast
            },
            gamma_factor: f64::from_bits(self.gamma_factor_bits),
            primal_variant: self.primal_variant,
            ..AgentSettings::new(
                self.method,
                f64::from_bits(self.rho_bits),
                self.diameter,
                tolerance,
            )
        }
    }

    /// Agent `index`'s plan.
    pub fn plan(&self, index: usize) -> Result<AgentPlan, ScenarioError> {
        let stop = match self.stop {
            ScenarioStop::MaxIters => AgentStop::MaxIters,
            ScenarioStop::Local { tolerance_bits } => AgentStop::Local(
                LocalCertifiedStop::new(self.diameter, self.robots, f64::from_bits(tolerance_bits))
                    .map_err(|e| ScenarioError::Inconsistent(e.to_string()))?
                    .with_cadence(self.settings().stop_cadence()),
            ),
        };
        Ok(AgentPlan {
            index,
            max_rounds: self.max_rounds,
            stop,
            round_timeout: Duration::from_millis(self.round_timeout_ms),
            global_barrier: self.global_barrier,
            warmup_rounds: self.warmup_rounds,
        })
    }

    /// Values of every round message's payload.
    pub fn payload_len(&self) -> usize {
        match self.workload {
            ScenarioWorkload::Method | ScenarioWorkload::Episodes(_) => {
                self.method.payload_len(self.robots, self.tasks)
            }
            ScenarioWorkload::Probe { payload_len, .. } => payload_len.max(1),
        }
    }

    /// Agent `index` of a one-shot workload: the method's agent or a benchmark probe
    /// (episode runs build theirs from [`EpisodeSettings::agent`], to change its costs).
    pub fn workload_agent(&self, index: usize) -> Result<Box<dyn ConsensusAgent>, ScenarioError> {
        match self.workload {
            ScenarioWorkload::Method => Ok(Box::new(self.agent(index)?)),
            ScenarioWorkload::Probe { payload_len, step } if index < self.robots => {
                Ok(Box::new(ProbeAgent::new(index, payload_len, step)))
            }
            ScenarioWorkload::Probe { .. } => Err(ScenarioError::BadIndex {
                index,
                robots: self.robots,
            }),
            ScenarioWorkload::Episodes(_) => Err(ScenarioError::Inconsistent(
                "an episode run's agents come from its episode settings".into(),
            )),
        }
    }

    /// Builds agent `index` exactly as the other transports do.
    pub fn agent(&self, index: usize) -> Result<MethodAgent, ScenarioError> {
        if index >= self.robots {
            return Err(ScenarioError::BadIndex {
                index,
                robots: self.robots,
            });
        }
        let problem = self.problem()?;
        let graph = self.graph()?;
        let team = AgentFactory {
            problem: &problem,
            graph: &graph,
            settings: self.settings(),
            epsilon: self.epsilon_bits.map(f64::from_bits),
            seed: self.seed,
            schedule: self
                .adaptive_rho
                .then(|| self.method.schedule(f64::from_bits(self.rho_bits)))
                .flatten(),
            readout_filter: std::sync::OnceLock::new(),
        };
        Ok(team.agent(index))
    }
}
