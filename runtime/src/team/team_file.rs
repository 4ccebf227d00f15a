//! The team file of agents started independently (`admm-ta agent --team FILE --robot I`, see
//! [`crate::team::membership`]): its format, its checks, and what every agent derives from it
//! alike — the problem, the graph, the settings, the hosts of a team across machines.
//!
//! ```toml
//! run = "demo"              # letters, digits, dashes: namespaces the shared memory
//! robots = 10
//! costs = "costs.csv"       # a CSV (relative to this file), "random" with tasks and seed,
//!                           # or "private" with tasks: each robot's program gives its own row
//!                           # (`admm-ta agent --serve`, [`crate::standing`])
//! forbidden = "pairs.txt"   # optional: robot,task pairs nobody may take (as solve --forbidden)
//! maximize = false          # true: the costs are profits (as solve --maximize)
//! topology = "ring"         # complete | chain | ring | star | grid | random:P | geometric:R | FILE.toml
//! method = "primal"
//! results = "results"       # each agent writes result-<id>.json here
//! startup_timeout = 30.0    # seconds to wait for the neighbours
//! ```
//!
//! A team across several machines names its hosts and how they talk (see
//! [`admm_ta_transport::zenoh_net`]): `transport = "zenoh"` (every agent a Zenoh client of its host's
//! router) or `"mixed"` (iceoryx2 among the agents of a host, Zenoh between hosts through
//! each host's bridge). Every host runs `admm-ta host --team FILE --name NAME` next to its
//! agents (needs a build with `--features zenoh`):
//!
//! ```toml
//! transport = "zenoh"
//! [[hosts]]
//! name = "alpha"
//! agents = [0, 1, 2, 3, 4]
//! endpoint = "tcp/192.168.1.10:7447"   # where alpha's router listens
//! [[hosts]]
//! name = "beta"
//! agents = [5, 6, 7, 8, 9]
//! endpoint = "tcp/192.168.1.11:7447"
//! ```
//!
//! When the cost file names its robots (a first column of names), a host's `agents` may list
//! them by name (`agents = ["uav1", "uav2", 2]`), a topology file may name them in its edges,
//! and `admm-ta agent --robot uav1` starts a robot by name.

use crate::options::error::ConfigError;
use crate::options::{SolveOptions, StopRule};
use crate::process::namespace::RunNamespace;
use crate::team::errors::{PrivateTeamError, TeamFileError};
pub use crate::team::hosts::{Deployment, HostEntry};
use crate::team::hosts::{check_hosts, cost_robot_names, number_host_agents};
use admm_ta_agents::method::settings::{GivenSettings, SettingValue};
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_agents::problem::{cost_file, forbidden, read_cost_text};
use admm_ta_topologies::{Graph, RobotRef, TopologySpec, file as topology_file};
use admm_ta_transport::zenoh_net::links::ZenohLinks;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The team file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeamFile {
    pub run: String,
    pub robots: usize,
    /// A cost CSV (one row per robot), or `random` (uniform [0, 1) from `seed`, `tasks` columns).
    pub costs: String,
    #[serde(default)]
    pub tasks: Option<usize>,
    #[serde(default)]
    pub seed: u64,
    /// A file of `robot,task` pairs that no robot may take (relative to this file), as
    /// `solve --forbidden`; `inf` in the CSV (`-inf` with `maximize`) marks them too.
    #[serde(default)]
    pub forbidden: Option<PathBuf>,
    /// The costs are profits to maximise (as `solve --maximize`).
    #[serde(default)]
    pub maximize: bool,
    #[serde(default = "complete")]
    pub topology: String,
    #[serde(default)]
    pub method: Method,
    #[serde(default = "results")]
    pub results: PathBuf,
    #[serde(default = "sixty")]
    pub startup_timeout: f64,
    #[serde(default = "thirty")]
    pub round_timeout: f64,
    #[serde(default = "five_thousand")]
    pub max_iters: usize,
    #[serde(default)]
    pub adaptive_rho: bool,
    /// The method's own settings, by their keys (`primal_variant = "paper"`,
    /// `gamma_factor = 0.7`: [`Method::all_settings`]); a setting of another method is
    /// refused.
    #[serde(skip)]
    pub settings: GivenSettings,
    /// How the team is deployed and what carries its messages.
    #[serde(default)]
    pub transport: Deployment,
    /// The machines of a zenoh or mixed team.
    #[serde(default)]
    pub hosts: Vec<HostEntry>,
    /// Every agent stamps its rounds; `collect` writes them to this file as Chrome trace
    /// JSON (relative to this file) and names the critical path (`solve --timeline`).
    #[serde(default)]
    pub timeline: Option<PathBuf>,
    /// A private team's episode deadline (seconds): how long the team waits for a robot's
    /// row before the episode goes on without it ([`crate::standing`]).
    #[serde(default)]
    pub episode_timeout: Option<f64>,
    /// A private team starts every episode from the last one's iterates (`false`: from
    /// zero); default true.
    #[serde(default)]
    pub warm_start: Option<bool>,
    /// A private team's episode when a robot gave no row in time: `abort` (nothing is
    /// solved; the default) or `continue` (the others solve it; that robot relays).
    #[serde(default)]
    pub on_failure: Option<crate::options::OnFailure>,
    /// A private team's answer to a robot whose leave would split the others: `refuse` (it
    /// stays and relays; the default) or `force` (it goes, and the team goes on in its
    /// largest connected part).
    #[serde(default)]
    pub leave: Option<crate::standing::roster::LeaveRule>,
}

fn complete() -> String {
    "complete".into()
}
fn results() -> PathBuf {
    "results".into()
}
fn sixty() -> f64 {
    60.0
}
fn thirty() -> f64 {
    30.0
}
fn five_thousand() -> usize {
    5000
}

/// A team file read with the directory its relative paths start from.
#[derive(Debug, Clone)]
pub struct Team {
    pub file: TeamFile,
    pub base: PathBuf,
}

impl Team {
    pub fn read(path: &Path) -> Result<Self, TeamFileError> {
        // A regular file of bounded size, like every input file.
        let text =
            admm_ta_agents::problem::read_bounded(path, 16 << 20).map_err(TeamFileError::Read)?;
        let syntax = |message: &str| TeamFileError::Syntax {
            path: path.to_path_buf(),
            message: message.to_string(),
        };
        let mut table: toml::Table = toml::from_str(&text).map_err(|e| syntax(e.message()))?;
        let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        number_host_agents(&mut table, &base, path)?;
        // The methods' own settings, by key; the rest is the team file's own keys.
        let mut settings = GivenSettings::default();
        for spec in Method::all_settings() {
            if let Some(value) = table.remove(spec.key) {
                let value = match value {
                    toml::Value::String(name) => SettingValue::Name(name),
                    toml::Value::Float(v) => SettingValue::Number(v),
                    toml::Value::Integer(v) => SettingValue::Number(v as f64),
                    other => {
                        return Err(TeamFileError::SettingKind {
                            path: path.to_path_buf(),
                            key: spec.key,
                            got: other.to_string(),
                        });
                    }
                };
                settings = settings.set(spec, value);
            }
        }
        let mut file: TeamFile = table
            .try_into()
            .map_err(|e: toml::de::Error| syntax(e.message()))?;
        file.settings = settings;
        RunNamespace::check_team_name(&file.run)?;
        check_hosts(&file.run, file.robots, file.transport, &file.hosts)?;
        let team = Self { file, base };
        // The settings' checks, named by the file's keys.
        let options = team
            .solve_options()
            .map_err(|error| TeamFileError::Settings {
                path: path.to_path_buf(),
                error,
            })?;
        team.check_private(&options)?;
        Ok(team)
    }

    /// A private team's episode deadline in seconds (default 60).
    pub fn episode_timeout(&self) -> f64 {
        self.file.episode_timeout.unwrap_or(60.0)
    }

    /// Whether the robots keep their costs (`costs = "private"`).
    pub fn is_private(&self) -> bool {
        self.file.costs == "private"
    }

    /// Refuses a private team that cannot run (with its `options`), with the reason.
    fn check_private(&self, options: &SolveOptions) -> Result<(), TeamFileError> {
        if !self.is_private() {
            let f = &self.file;
            let set = [
                ("on_failure", f.on_failure.is_some()),
                ("episode_timeout", f.episode_timeout.is_some()),
                ("warm_start", f.warm_start.is_some()),
                ("leave", f.leave.is_some()),
            ];
            if let Some((key, _)) = set.into_iter().find(|(_, set)| *set) {
                return Err(TeamFileError::Private(PrivateTeamError::NotPrivateKey {
                    key,
                }));
            }
            return Ok(());
        }
        let f = &self.file;
        let refuse = |e| Err(TeamFileError::Private(e));
        if f.tasks.is_none() {
            return refuse(PrivateTeamError::NeedsTasks);
        }
        let parts = options.method_setup().and_then(|setup| setup.parts());
        if parts.is_none() {
            return refuse(PrivateTeamError::Method {
                method: f.method.name(),
            });
        }
        if f.forbidden.is_some() {
            return refuse(PrivateTeamError::ForbiddenFile);
        }
        let timeout = self.episode_timeout();
        if !(timeout > 0.0 && timeout.is_finite()) {
            return Err(TeamFileError::Syntax {
                path: self.base.clone(),
                message: format!(
                    "episode_timeout must be a positive number of seconds, got {timeout}"
                ),
            });
        }
        Ok(())
    }

    /// The robots' names, when the cost file names them (read from the file).
    pub fn robot_names(&self) -> Result<Option<Vec<String>>, TeamFileError> {
        cost_robot_names(&self.base, &self.file.costs)
    }

    /// The number of the robot `robot` refers to: an index as it is, a name looked up in
    /// the cost file's robot names (`admm-ta agent --robot uav3`).
    pub fn robot(&self, robot: &RobotRef) -> Result<usize, TeamFileError> {
        match robot {
            RobotRef::Index(i) => Ok(*i),
            RobotRef::Name(_) => robot
                .resolve(self.robot_names()?.as_deref())
                .map_err(|e| TeamFileError::Id(Box::new(e))),
        }
    }

    /// The host agent `id` runs on (zenoh and mixed teams).
    pub fn host_of(&self, id: usize) -> Option<&HostEntry> {
        self.file.hosts.iter().find(|h| h.agents.contains(&id))
    }

    /// The names of the hosts with robots in `roster`.
    pub fn hosts_of(&self, roster: &crate::standing::roster::Roster) -> Vec<String> {
        self.file
            .hosts
            .iter()
            .filter(|h| h.agents.iter().any(|&a| roster.contains(a)))
            .map(|h| h.name.clone())
            .collect()
    }

    /// The host called `name`.
    pub fn host(&self, name: &str) -> Result<&HostEntry, TeamFileError> {
        self.file
            .hosts
            .iter()
            .find(|h| h.name == name)
            .ok_or_else(|| TeamFileError::NoHost {
                name: name.to_string(),
                hosts: self.file.hosts.iter().map(|h| h.name.clone()).collect(),
            })
    }

    /// The Zenoh links of an agent on `host` (or of its bridge): the host's router.
    pub fn zenoh_links(&self, host: &HostEntry) -> ZenohLinks {
        ZenohLinks {
            key_prefix: format!("admm-ta/team/{}", self.file.run),
            connect: vec![host.endpoint.clone()],
            hosts: self.file.hosts.iter().map(|h| h.name.clone()).collect(),
            epoch: None,
        }
    }

    fn path(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base.join(p)
        }
    }

    /// Where the agents write their results.
    pub fn results_dir(&self) -> PathBuf {
        self.path(&self.file.results)
    }

    /// Where `collect` writes the team's timeline, if the file asks for one.
    pub fn timeline_path(&self) -> Option<PathBuf> {
        self.file.timeline.as_deref().map(|p| self.path(p))
    }

    /// The problem and graph every agent derives from the file.
    pub fn problem_and_graph(&self) -> Result<(TaskAssignmentProblem, Graph), TeamFileError> {
        let f = &self.file;
        let in_file = |path: &Path| {
            let path = path.to_path_buf();
            move |source| TeamFileError::File { path, source }
        };
        // Pairs the cost file itself marks forbidden (JSON nulls).
        let mut marked = Vec::new();
        let costs = if self.is_private() {
            // No robot's costs: the team's shape (every agent is built from it and then
            // given its own normalised row, [`crate::standing`]).
            let tasks = f
                .tasks
                .ok_or(TeamFileError::Private(PrivateTeamError::NeedsTasks))?;
            CostMatrix::new(f.robots, tasks, vec![0.0; f.robots * tasks])?
        } else if f.costs == "random" {
            let tasks = f.tasks.ok_or(TeamFileError::RandomNeedsTasks)?;
            CostMatrix::uniform(f.robots, tasks, f.seed)?
        } else {
            let path = self.path(Path::new(&f.costs));
            let file = read_cost_text(&path)
                .and_then(|text| cost_file::parse(&text, None))
                .map_err(in_file(&path))?;
            marked = file.forbidden;
            file.costs
        };
        if costs.robots() != f.robots {
            return Err(TeamFileError::Robots {
                file: f.robots,
                costs: costs.robots(),
            });
        }
        // A team runs the paper's cases (1 and 2): every robot works.
        if costs.robots() < costs.tasks() {
            return Err(TeamFileError::TooFewRobots {
                robots: costs.robots(),
                tasks: costs.tasks(),
            });
        }
        if let Some(file) = &f.forbidden {
            let path = self.path(file);
            marked.extend(forbidden::read(&path, &costs).map_err(in_file(&path))?);
        }
        let costs = if marked.is_empty() {
            costs
        } else {
            forbidden::apply(&costs, &marked, f.maximize)?
        };
        let problem = if f.maximize {
            TaskAssignmentProblem::maximizing(costs, CaseChoice::Auto)
        } else {
            TaskAssignmentProblem::new(costs, CaseChoice::Auto)
        }?;
        let names = problem.costs().robot_names();
        let graph = if f.topology.ends_with(".toml") {
            let path = self.path(Path::new(&f.topology));
            let graph =
                topology_file::read_named(&path, names).map_err(TeamFileError::TopologyFile)?;
            if graph.robots() != f.robots {
                return Err(TeamFileError::TopologyRobots {
                    path,
                    found: graph.robots(),
                    robots: f.robots,
                });
            }
            graph
        } else {
            f.topology
                .parse::<TopologySpec>()
                .and_then(|t| t.build_named(f.robots, f.seed, names))
                .map_err(|source| TeamFileError::Topology {
                    spec: f.topology.clone(),
                    source,
                })?
        };
        Ok((problem, graph))
    }

    /// The settings every agent runs with, on its deployment's transport (a test may run
    /// the same problem on another), checked as the command line's are: a key the team
    /// never reads (`primal_variant` with market, `adaptive_rho = true` without ρ) is
    /// refused ([`crate::options::SolveOptionsBuilder::refuse_unread`]); [`ConfigError::in_terms_of`]
    /// names the file's keys.
    pub fn solve_options(&self) -> Result<SolveOptions, ConfigError> {
        let f = &self.file;
        SolveOptions::builder()
            .refuse_unread(true)
            .method(f.method)
            .settings(f.settings.clone())
            .transport(f.transport.agent_transport())
            .adaptive_rho(f.adaptive_rho)
            .max_iters(f.max_iters)
            .stop(StopRule::Local)
            .seed(f.seed)
            .round_timeout_secs(f.round_timeout)
            .startup_timeout_secs(f.startup_timeout)
            .timeline(f.timeline.is_some())
            .build()
    }
}
