//! The scenario file the launcher writes into the run directory: everything an agent
//! process needs to rebuild its own agent, its plan and its end of the transport: the
//! problem, the graph, the method with its own settings (its settings type, serialised), the
//! team's numbers and the run's names and limits.

use crate::options::run::RunOptions;
use crate::workload::Workload;
use crate::workload::plan::AgentFactory;
use crate::workload::surveillance::EpisodeSettings;
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::local_stop::LocalCertifiedStop;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::team::{MethodSetup, TeamParams};
use admm_ta_agents::methods::Method;
use admm_ta_agents::methods::probe::{ProbeAgent, ProbeStep};
use admm_ta_agents::problem::{AssignmentCase, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::Graph;
use admm_ta_transport::Transport;
use admm_ta_transport::endpoint::RunPlace;
use admm_ta_transport::exchange::round_loop::{AgentPlan, AgentStop};
use admm_ta_transport::wait::WaitStrategy;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// What the agents compute.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScenarioWorkload {
    /// The scenario's method on its problem.
    #[default]
    Method,
    /// A benchmark probe ([`ProbeAgent`]) with a payload of `payload_len` values.
    Probe { payload_len: usize, step: ProbeStep },
    /// Repeated surveillance episodes ([`crate::surveillance`]).
    Episodes(Box<EpisodeSettings>),
}

/// One run, as the agents see it. Numbers travel as JSON numbers, which serde_json writes
/// and reads back exactly (its `float_roundtrip`), so every process computes with exactly
/// the same numbers as the lockstep simulation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    pub run_id: String,
    /// Prefix of the run's shared memory and transport files.
    pub prefix: String,
    /// The run's private root directory for transport files.
    pub transport_root: PathBuf,
    pub robots: usize,
    pub tasks: usize,
    pub case: AssignmentCase,
    /// Row-major `n × m` costs as f64 bits.
    pub cost_bits: Vec<u64>,
    pub edges: Vec<(usize, usize)>,
    pub topology: String,
    /// The team's method (`None`: latency probes).
    pub method: Option<Method>,
    /// The method's own settings, as its settings type serialises them.
    #[serde(default)]
    pub settings: serde_json::Value,
    /// The penalty ρ (0 for the methods without one).
    pub rho: f64,
    /// Follow the method's `--adaptive-rho` schedule from `rho`.
    pub adaptive_rho: bool,
    /// The tie-breaking perturbation's size.
    pub epsilon: Option<f64>,
    pub seed: u64,
    /// Total cost tolerance of the optimality certificate.
    pub tolerance: f64,
    /// The decentralized certified stop (`false`: the round limit).
    pub local_stop: bool,
    /// The decentralized stop's cadence.
    pub stop_cadence: (u64, u32),
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
    /// Every agent stamps its rounds ([`admm_ta_transport::timeline`]).
    #[serde(default)]
    pub timeline: bool,
    /// What the transport put here for its agents (a Zenoh run's router links), as its own
    /// type serialises it.
    #[serde(default)]
    pub transport_config: Option<serde_json::Value>,
    /// The agents on this host, in a mixed team (the others are reached through the host's
    /// bridge); `None`: every agent is here.
    #[serde(default)]
    pub local_agents: Option<Vec<usize>>,
    /// The robots that take part in this run of a team whose robots come and go (a
    /// standing team's roster: [`Scenario::graph`] is the graph they induce, and nobody
    /// waits for the others); `None`: every robot. One run's, not the team's: the team's
    /// digest leaves it out.
    #[serde(default)]
    pub roster: Option<Vec<usize>>,
    /// Values of every round message when they are more than the method's payload (a
    /// private standing team: its agreements need room, and an episode's part of the team
    /// runs inside the team's messages); `None`: the payload.
    #[serde(default)]
    pub message_len: Option<usize>,
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
    /// say; the run's names (id, prefix, transport root, board) are left to whoever starts
    /// the run (the launcher, or the members of an independently started team).
    pub fn new(workload: Workload<'_>, graph: &Graph, options: &RunOptions) -> Self {
        let robots = graph.robots();
        // A team of `tasks` tasks and nothing else decided yet: zero costs, no method, run
        // to the round limit.
        let blank = |tasks: usize| Self {
            run_id: String::new(),
            prefix: String::new(),
            transport_root: PathBuf::new(),
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
            method: None,
            settings: serde_json::Value::Null,
            rho: 0.0,
            adaptive_rho: false,
            epsilon: None,
            seed: 0,
            tolerance: 0.0,
            local_stop: false,
            stop_cadence: (1, 0),
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
            timeline: options.timeline(),
            transport_config: None,
            local_agents: None,
            roster: None,
            message_len: None,
        };
        let bits = |values: &[f64]| values.iter().map(|v| v.to_bits()).collect();
        match workload {
            Workload::Solve {
                plan,
                stop,
                max_rounds,
            } => {
                let factory = &plan.agents;
                let problem = factory.problem;
                Self {
                    case: problem.case(),
                    cost_bits: bits(problem.costs().values()),
                    method: Some(plan.method),
                    settings: factory.setup.settings_json(),
                    rho: plan.rho,
                    adaptive_rho: factory.schedule.is_some(),
                    epsilon: factory.epsilon,
                    seed: factory.seed,
                    tolerance: plan.tolerance,
                    local_stop: matches!(stop, AgentStop::Local(_)),
                    stop_cadence: plan.stop_cadence,
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
                cost_bits: bits(&settings.model.initial_costs()),
                method: Some(settings.method),
                settings: settings.settings.clone(),
                rho: settings.rho,
                tolerance: settings.tolerance,
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

    /// Where the run lives, for its transport (`dir`: the run directory).
    pub fn place(&self, dir: &Path) -> RunPlace {
        RunPlace {
            prefix: self.prefix.clone(),
            root: self.transport_root.clone(),
            dir: dir.to_path_buf(),
            board_shm: self.board_shm.clone(),
        }
    }

    /// The team's graph: the one its roster induces, when robots come and go.
    pub fn graph(&self) -> Result<Graph, ScenarioError> {
        let graph = Graph::from_edges(self.robots, &self.edges, self.topology.clone())
            .map_err(|e| ScenarioError::Inconsistent(e.to_string()))?;
        Ok(match &self.roster {
            Some(roster) => graph.induced(roster),
            None => graph,
        })
    }

    /// The team's method with its settings.
    pub fn method_setup(&self) -> Result<Box<dyn MethodSetup>, ScenarioError> {
        let team = self.method.and_then(Method::team).ok_or_else(|| {
            ScenarioError::Inconsistent("a team scenario without a team method".into())
        })?;
        team.configure_json(&self.settings)
            .map_err(|e| ScenarioError::Inconsistent(format!("the method's settings: {e}")))
    }

    /// What every agent shares.
    pub fn params(&self) -> TeamParams {
        TeamParams {
            rho: self.rho,
            diameter: self.diameter,
            tolerance: self.tolerance,
        }
    }

    /// Agent `index`'s plan.
    pub fn plan(&self, index: usize) -> Result<AgentPlan, ScenarioError> {
        let stop = if self.local_stop {
            AgentStop::Local(
                LocalCertifiedStop::new(self.diameter, self.robots, self.tolerance)
                    .map_err(|e| ScenarioError::Inconsistent(e.to_string()))?
                    .with_cadence(self.stop_cadence),
            )
        } else {
            AgentStop::MaxIters
        };
        Ok(AgentPlan {
            index,
            max_rounds: self.max_rounds,
            stop,
            round_timeout: Duration::from_millis(self.round_timeout_ms),
            global_barrier: self.global_barrier,
            warmup_rounds: self.warmup_rounds,
            timeline: self.timeline,
        })
    }

    /// Values of every round message's payload.
    pub fn payload_len(&self) -> usize {
        if let Some(len) = self.message_len {
            return len;
        }
        match self.workload {
            // The payload may depend on the settings (the dual methods' variants).
            ScenarioWorkload::Method | ScenarioWorkload::Episodes(_) => match self.method_setup() {
                Ok(setup) => setup.payload_len(self.robots, self.tasks),
                Err(_) => self
                    .method
                    .map_or(0, |m| m.payload_len(self.robots, self.tasks)),
            },
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
        let setup = self.method_setup()?;
        let schedule = self
            .adaptive_rho
            .then(|| setup.schedule(self.rho))
            .flatten();
        let team = AgentFactory::new(
            &problem,
            &graph,
            setup,
            self.params(),
            self.epsilon,
            self.seed,
            schedule,
        );
        Ok(team.agent(index))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::{SolveOptions, StopRule};
    use crate::workload::plan::prepare;
    use admm_ta_agents::agent::ConsensusAgent;
    use admm_ta_agents::methods::Method;
    use admm_ta_agents::methods::dual::GammaFactor;
    use admm_ta_agents::methods::primal::{PrimalVariant, ProjectionPath};
    use admm_ta_agents::problem::CaseChoice;

    /// The agents an agent process rebuilds from the scenario file compute exactly what the
    /// lockstep simulation's compute: the method's settings (and every number of the team)
    /// survive the file bit for bit.
    #[test]
    fn agents_rebuilt_from_the_scenario_file_step_identically() {
        let costs = CostMatrix::uniform(5, 4, 3).unwrap();
        let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        let graph = admm_ta_topologies::generate::ring(5).unwrap();
        let cases = [
            SolveOptions::builder()
                .method(Method::InexactDual)
                .setting(GammaFactor(0.1 + 0.2))
                .rho(Some(1.0 / 3.0)),
            SolveOptions::builder()
                .method(Method::Primal)
                .setting(PrimalVariant::Paper)
                .setting(ProjectionPath::Qp)
                .adaptive_rho(true),
            SolveOptions::builder().method(Method::Primal),
            SolveOptions::builder().method(Method::Market),
        ];
        for options in cases {
            let options = options.build().unwrap();
            let internal = problem.internal();
            let plan =
                prepare(internal, &graph, &options, options.method_setup().unwrap()).unwrap();
            let stop = AgentStop::MaxIters;
            let scenario = Scenario::new(
                Workload::Solve {
                    plan: &plan,
                    stop: &stop,
                    max_rounds: 10,
                },
                &graph,
                options.run(),
            );
            let text = serde_json::to_string(&scenario).unwrap();
            let read = Scenario::parse(text.as_bytes(), Path::new("scenario.json"), "").unwrap();
            assert_eq!(read, scenario);
            assert_eq!(read.stop_cadence, plan.stop_cadence);
            assert!(options.stop() == StopRule::Local && !read.local_stop);
            let mut ours = plan.agents.agents();
            let mut theirs: Vec<MethodAgent> = (0..5).map(|i| read.agent(i).unwrap()).collect();
            let len = ours[0].payload_len();
            let mut payloads = vec![vec![0.0; len]; 5];
            for (i, p) in payloads.iter_mut().enumerate() {
                ours[i].write_initial_payload(p);
            }
            for _ in 0..6 {
                let mut next = vec![vec![0.0; len]; 5];
                let mut again = vec![vec![0.0; len]; 5];
                for i in 0..5 {
                    let inbox: Vec<&[f64]> = graph
                        .neighbours(i)
                        .iter()
                        .map(|&j| payloads[j].as_slice())
                        .collect();
                    ours[i].step(&inbox, &mut next[i]);
                    theirs[i].step(&inbox, &mut again[i]);
                }
                let bits = |v: &Vec<Vec<f64>>| -> Vec<u64> {
                    v.iter().flatten().map(|x| x.to_bits()).collect()
                };
                assert_eq!(bits(&next), bits(&again), "{:?}", options.method());
                payloads = next;
            }
        }
    }
}
