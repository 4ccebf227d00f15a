//! Agents started independently, in any order, by any supervisor (systemd, a shell script, a
//! ROS launch file): `admm-ta agent --team FILE --id I`. No launcher: every agent reads the
//! same team file, derives the same problem, graph, settings and namespace from it, finds
//! its neighbours through iceoryx2 service discovery, waits for them until the start-up
//! deadline (naming the ones that never came), runs, and writes `result-I.json` into the
//! team's results directory; `admm-ta collect --team FILE` assembles the assignment.
//!
//! The run's shared board is created by whichever agent comes first (under a file lock in
//! the team's directory) and removed, with every other shared-memory file of the team, by the
//! last agent to leave. A board left by a dead team (no agent recorded on it is alive) is
//! taken over by the next team of that name. One team per name at a time.
//!
//! ```toml
//! run = "demo"              # letters, digits, dashes: namespaces the shared memory
//! robots = 10
//! costs = "costs.csv"       # a CSV (relative to this file), or "random" with tasks and seed
//! topology = "ring"         # complete | chain | ring | star | grid | random:P | geometric:R | FILE.toml
//! method = "primal"
//! results = "results"       # each agent writes result-<id>.json here
//! startup_timeout = 30.0    # seconds to wait for the neighbours
//! ```
//!
//! A team across several machines names its hosts and how they talk (see
//! [`crate::zenoh_net`]): `transport = "zenoh"` (every agent a Zenoh peer of its host's
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

use crate::board::Board;
use crate::error_text::one_line;
use crate::exchange::round_loop::{AgentStop, merge_outcomes};
use crate::ipc::nodes::{cleanup_dead_nodes, run_config};
use crate::latency::LatencySummary;
use crate::options::error::{ConfigError, seconds};
use crate::options::{SolveOptions, StopRule};
use crate::process::agent::{AgentReport, run_scenario};
use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::transport::Transport;
use crate::workload::Workload;
use crate::workload::plan::prepare;
use crate::zenoh_net::links::{ZenohLinks, check_endpoint};
use admm_ta_agents::local_stop::LocalCertifiedStop;
use admm_ta_agents::method::Method;
use admm_ta_agents::oracle;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::{Graph, TopologySpec, file as topology_file};
use serde::{Deserialize, Serialize};
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

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
    /// How the team is deployed and what carries its messages.
    #[serde(default)]
    pub transport: Deployment,
    /// The machines of a zenoh or mixed team.
    #[serde(default)]
    pub hosts: Vec<HostEntry>,
}

/// How an independently started team is deployed: on one machine or across several, and
/// what carries its messages (a team file's `transport` key).
///
/// It is not a [`Transport`]: `mixed` is two transports at once (iceoryx2 among the agents of
/// a host, Zenoh between hosts through each host's bridge), and a deployment decides more
/// than an agent's exchange — whether the team has hosts, a shared board per host, bridges.
/// [`Deployment::agent_transport`] is the exchange each agent runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Deployment {
    /// Every agent on this machine, iceoryx2 zero-copy (`iceoryx2`, or `ipc` as on the
    /// command line).
    #[default]
    #[serde(alias = "ipc")]
    Iceoryx2,
    /// Every agent a Zenoh peer of its host's router.
    Zenoh,
    /// iceoryx2 among the agents of a host; the host's bridge carries what crosses hosts.
    Mixed,
}

impl Deployment {
    /// The transport every agent's exchange runs.
    pub fn agent_transport(self) -> Transport {
        match self {
            Self::Iceoryx2 | Self::Mixed => Transport::Ipc,
            Self::Zenoh => Transport::Zenoh,
        }
    }

    /// The team spans machines, named by its `[[hosts]]`.
    pub fn across_hosts(self) -> bool {
        self != Self::Iceoryx2
    }

    /// The agents of a host share a board in shared memory (iceoryx2 and mixed teams); a
    /// Zenoh team's presence, failures and cleanup travel on Zenoh instead.
    pub fn host_board(self) -> bool {
        self != Self::Zenoh
    }

    /// Each host runs a bridge between its agents' iceoryx2 services and the other hosts.
    pub fn bridged(self) -> bool {
        self == Self::Mixed
    }
}

/// One machine of a multi-host team.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HostEntry {
    /// Letters, digits and dashes (`admm-ta host --name NAME`).
    pub name: String,
    /// The robots that run on it.
    pub agents: Vec<usize>,
    /// Where its Zenoh router listens, `tcp/ADDRESS:PORT`, reachable from the other hosts.
    pub endpoint: String,
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
    pub fn read(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read team file {}: {e}", path.display()))?;
        let file: TeamFile = toml::from_str(&text)
            .map_err(|e| format!("team file {}: {}", path.display(), e.message()))?;
        let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        RunNamespace::check_team_name(&file.run)?;
        seconds("startup_timeout", file.startup_timeout).map_err(|e| e.to_string())?;
        seconds("round_timeout", file.round_timeout).map_err(|e| e.to_string())?;
        check_hosts(&file)?;
        Ok(Self { file, base })
    }

    /// The host agent `id` runs on (zenoh and mixed teams).
    pub fn host_of(&self, id: usize) -> Option<&HostEntry> {
        self.file.hosts.iter().find(|h| h.agents.contains(&id))
    }

    /// The host called `name`.
    pub fn host(&self, name: &str) -> Result<&HostEntry, String> {
        self.file
            .hosts
            .iter()
            .find(|h| h.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = self.file.hosts.iter().map(|h| h.name.as_str()).collect();
                format!("the team file has no host '{name}' (hosts: {names:?})")
            })
    }

    /// The Zenoh links of an agent on `host` (or of its bridge): the host's router.
    pub fn zenoh_links(&self, host: &HostEntry) -> ZenohLinks {
        ZenohLinks {
            key_prefix: format!("admm-ta/team/{}", self.file.run),
            connect: vec![host.endpoint.clone()],
            hosts: self.file.hosts.iter().map(|h| h.name.clone()).collect(),
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

    /// The problem and graph every agent derives from the file.
    pub fn problem_and_graph(&self) -> Result<(TaskAssignmentProblem, Graph), String> {
        let f = &self.file;
        let costs = if f.costs == "random" {
            let tasks = f
                .tasks
                .ok_or("costs = \"random\" needs tasks = M in the team file")?;
            CostMatrix::uniform(f.robots, tasks, f.seed).map_err(|e| e.to_string())?
        } else {
            let path = self.path(Path::new(&f.costs));
            CostMatrix::read_csv(&path).map_err(|e| format!("{}: {e}", path.display()))?
        };
        if costs.robots() != f.robots {
            return Err(format!(
                "the team file says {} robots but the costs have {} rows",
                f.robots,
                costs.robots()
            ));
        }
        let problem =
            TaskAssignmentProblem::new(costs, CaseChoice::Auto).map_err(|e| e.to_string())?;
        let graph = if f.topology.ends_with(".toml") {
            let path = self.path(Path::new(&f.topology));
            let graph = topology_file::read(&path).map_err(|e| e.to_string())?;
            if graph.robots() != f.robots {
                return Err(format!(
                    "topology {} has {} robots, the team {}",
                    path.display(),
                    graph.robots(),
                    f.robots
                ));
            }
            graph
        } else {
            f.topology
                .parse::<TopologySpec>()
                .and_then(|t| t.build(f.robots, f.seed))
                .map_err(|e| format!("topology '{}': {e}", f.topology))?
        };
        Ok((problem, graph))
    }

    /// The settings every agent runs with, on its deployment's transport (a test may run
    /// the same problem on another).
    pub fn solve_options(&self) -> Result<SolveOptions, ConfigError> {
        let f = &self.file;
        SolveOptions::builder()
            .method(f.method)
            .transport(f.transport.agent_transport())
            .adaptive_rho(f.adaptive_rho)
            .max_iters(f.max_iters)
            .stop(StopRule::Local)
            .seed(f.seed)
            .round_timeout(seconds("round_timeout", f.round_timeout)?)
            .startup_timeout(seconds("startup_timeout", f.startup_timeout)?)
            .build()
    }
}

/// Checks the hosts of a team file: a zenoh or mixed team puts every robot on exactly one
/// named host with a distinct TCP endpoint; an iceoryx2 team has no hosts.
fn check_hosts(file: &TeamFile) -> Result<(), String> {
    if !file.transport.across_hosts() {
        if !file.hosts.is_empty() {
            return Err(
                "[[hosts]] are for teams across machines: add transport = \"zenoh\" or \"mixed\""
                    .into(),
            );
        }
        return Ok(());
    }
    if file.hosts.is_empty() {
        return Err(
            "a zenoh or mixed team needs [[hosts]] entries (name, agents, endpoint)".into(),
        );
    }
    let mut host_of = vec![None; file.robots];
    for (h, host) in file.hosts.iter().enumerate() {
        if RunNamespace::check_team_name(&host.name).is_err() {
            return Err(format!(
                "host name '{}': use 1 to 40 letters, digits and dashes",
                host.name
            ));
        }
        check_endpoint(&host.endpoint).map_err(|e| format!("host '{}': {e}", host.name))?;
        if let Some(other) = file.hosts[..h].iter().find(|o| o.name == host.name) {
            return Err(format!("two hosts are called '{}'", other.name));
        }
        if let Some(other) = file.hosts[..h].iter().find(|o| o.endpoint == host.endpoint) {
            return Err(format!(
                "hosts '{}' and '{}' have the same endpoint {}",
                other.name, host.name, host.endpoint
            ));
        }
        for &a in &host.agents {
            let slot = host_of.get_mut(a).ok_or_else(|| {
                format!(
                    "host '{}' lists robot {a}, but the team has {} robots (0..{})",
                    host.name, file.robots, file.robots
                )
            })?;
            if let Some(other) = slot.replace(h) {
                return Err(format!(
                    "robot {a} is on two hosts: '{}' and '{}'",
                    file.hosts[other].name, host.name
                ));
            }
        }
    }
    if file.transport.bridged()
        && let Some(host) = file
            .hosts
            .iter()
            .find(|h| file.run.len() + 1 + h.name.len() > 40)
    {
        return Err(format!(
            "a mixed team's run name and host name together must fit 40 characters ('{}-{}' does not): each host's shared memory is named after both",
            file.run, host.name
        ));
    }
    let homeless: Vec<usize> = (0..file.robots).filter(|&a| host_of[a].is_none()).collect();
    if !homeless.is_empty() {
        return Err(format!("robot(s) {homeless:?} are on no host"));
    }
    Ok(())
}

/// Path of agent `id`'s result in `results`.
pub fn member_result(results: &Path, id: usize) -> PathBuf {
    results.join(format!("result-{id}.json"))
}

/// An exclusive `flock` on a file, released when dropped.
struct FileLock(std::fs::File);

impl FileLock {
    fn acquire(path: &Path, deadline: Instant) -> Result<Self, String> {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(path)
            .map_err(|e| format!("cannot open the team lock {}: {e}", path.display()))?;
        loop {
            // SAFETY: flock on a descriptor this function owns.
            if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } == 0 {
                return Ok(Self(file));
            }
            if Instant::now() >= deadline {
                return Err(format!(
                    "the team lock {} stayed taken until the start-up deadline",
                    path.display()
                ));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

impl Drop for FileLock {
    fn drop(&mut self) {
        // SAFETY: unlocking the descriptor we locked.
        unsafe { libc::flock(self.0.as_raw_fd(), libc::LOCK_UN) };
    }
}

/// The scenario every agent of the team derives from the team file, in the iceoryx2
/// namespace of its machine (`host`, in a mixed team: each host has its own).
pub(crate) fn member_scenario(
    team: &Team,
    host: Option<&HostEntry>,
) -> Result<(Scenario, RunNamespace), String> {
    let (problem, graph) = team.problem_and_graph()?;
    let options = team.solve_options().map_err(|e| e.to_string())?;
    let plan = prepare(&problem, &graph, &options).map_err(|e| e.to_string())?;
    let stop = LocalCertifiedStop::new(plan.diameter, problem.robots(), plan.tolerance)
        .map_err(|e| e.to_string())?;
    let mut scenario = Scenario::new(
        Workload::Solve {
            plan: &plan,
            stop: &AgentStop::Local(stop),
            max_rounds: options.max_iters() as u64,
        },
        &graph,
        options.run(),
    );
    let namespace = match host {
        Some(host) => RunNamespace::for_team(&format!("{}-{}", team.file.run, host.name))?,
        None => RunNamespace::for_team(&team.file.run)?,
    };
    scenario.run_id = namespace.id.clone();
    scenario.iceoryx_prefix = namespace.prefix.clone();
    scenario.iceoryx_root = namespace.iceoryx_root();
    scenario.board_shm = namespace.board_shm();
    scenario.local_agents = host.map(|h| h.agents.clone());
    Ok((scenario, namespace))
}

/// A place on the team's board in shared memory: an agent's own slot, or (a mixed host's
/// bridge) the slots of the agents it stands in for. The board is created by whoever comes
/// first; the last member to leave removes every shared-memory file of the namespace.
pub(crate) struct Membership {
    board: Board,
    namespace: RunNamespace,
    slots: Vec<usize>,
}

impl Membership {
    /// Joins the board of `scenario` for `slots`, under the team's lock (until `deadline`).
    pub(crate) fn join(
        scenario: &Scenario,
        namespace: &RunNamespace,
        slots: &[usize],
        deadline: Instant,
    ) -> Result<Self, String> {
        let _lock = FileLock::acquire(&namespace.dir.join("lock"), deadline)?;
        let n = scenario.robots;
        let fresh = Board::open(&scenario.board_shm, n).is_err();
        let board = Board::open_or_create_for_team(
            &scenario.board_shm,
            n,
            scenario.tasks,
            scenario.payload_len(),
        )
        .map_err(|e| one_line(&e))?;
        for &slot in slots {
            board.set_member_pid(slot, std::process::id());
        }
        std::fs::create_dir_all(&scenario.iceoryx_root)
            .map_err(|e| format!("cannot create {}: {e}", scenario.iceoryx_root.display()))?;
        if fresh {
            // Nodes of a dead team of this name.
            let _ = run_config(&scenario.iceoryx_prefix, &scenario.iceoryx_root)
                .map(|c| cleanup_dead_nodes(&c));
        }
        Ok(Self {
            board,
            namespace: namespace.clone(),
            slots: slots.to_vec(),
        })
    }

    pub(crate) fn board(&self) -> &Board {
        &self.board
    }

    /// Counts the slots out; the last member of the team removes its namespace.
    pub(crate) fn leave(self) {
        let deadline = Instant::now() + Duration::from_secs(5);
        let last = FileLock::acquire(&self.namespace.dir.join("lock"), deadline)
            .map(|_lock| {
                let mut last = false;
                for &slot in &self.slots {
                    last |= self.board.member_left(slot);
                }
                last
            })
            .unwrap_or(false);
        if last {
            drop(self.board);
            let _ = self.namespace.cleanup();
        }
    }
}

/// Runs agent `id` of the team in `team_path` to the end; errors are one line.
pub fn run_member(team_path: &Path, id: usize) -> Result<AgentReport, String> {
    let started = Instant::now();
    let team = Team::read(team_path)?;
    let n = team.file.robots;
    if id >= n {
        return Err(format!(
            "--id {id} is out of range for a team of {n} robots"
        ));
    }
    let host = team
        .file
        .transport
        .bridged()
        .then(|| team.host_of(id))
        .flatten();
    let (mut scenario, namespace) = member_scenario(&team, host)?;
    let results = team.results_dir();
    std::fs::create_dir_all(&results)
        .map_err(|e| format!("cannot create {}: {e}", results.display()))?;
    let result = member_result(&results, id);
    // A result of an earlier run must not pass for this one's.
    let _ = std::fs::remove_file(&result);
    if !team.file.transport.host_board() {
        // No shared memory: presence, failures and cleanup are Zenoh's.
        let host = team.host_of(id).expect("checked: every robot is on a host");
        scenario.zenoh = Some(team.zenoh_links(host));
        let startup =
            Duration::from_millis(scenario.startup_timeout_ms).saturating_sub(started.elapsed());
        scenario.startup_timeout_ms = startup.as_millis() as u64;
        let report = run_scenario(&scenario, id, &results, &result, false);
        // Nothing of the run is in it (other agents of this host may still be starting:
        // only an empty directory goes).
        let _ = std::fs::remove_dir(&namespace.dir);
        return report;
    }
    let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
    let membership = Membership::join(&scenario, &namespace, &[id], deadline)?;
    let report = run_scenario(&scenario, id, &namespace.dir, &result, false);
    if report.is_err() {
        // No launcher reports us: tell the others (the first mark wins, so an agent that
        // stopped because of another's failure changes nothing).
        let _ = membership.board().mark_failed(id);
    }
    membership.leave();
    report
}

/// The team's assignment, assembled from the agents' results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TeamResult {
    pub run: String,
    pub assignment: Vec<usize>,
    pub cost: f64,
    /// Rounds every agent ran.
    pub iterations: u64,
    /// Every agent certified the same round.
    pub converged: bool,
    pub certified_round: Option<u64>,
    /// With `check`: the centralized optimum and whether the team found it.
    pub optimal_cost: Option<f64>,
    pub optimal: Option<bool>,
    /// Round latency over all agents' rounds (µs), on whatever carried the messages.
    pub round_latency_us: LatencySummary,
}

/// Reads every agent's result and checks they describe one feasible assignment.
pub fn collect(team_path: &Path, check: bool) -> Result<TeamResult, String> {
    let team = Team::read(team_path)?;
    let n = team.file.robots;
    let (problem, _) = team.problem_and_graph()?;
    let results = team.results_dir();
    let mut reports = Vec::with_capacity(n);
    let mut missing = Vec::new();
    for id in 0..n {
        let path = member_result(&results, id);
        match std::fs::read_to_string(&path) {
            Ok(text) => reports.push(
                serde_json::from_str::<AgentReport>(&text)
                    .map_err(|e| format!("{} is not an agent result: {e}", path.display()))?,
            ),
            Err(_) => missing.push(id),
        }
    }
    if !missing.is_empty() {
        return Err(format!(
            "agent(s) {missing:?} left no result in {} (still running, failed, or never started; see their output)",
            results.display()
        ));
    }
    let rounds: Vec<u64> = reports.iter().map(|r| r.outcome.rounds).collect();
    let certified: Vec<Option<u64>> = reports.iter().map(|r| r.outcome.certified_round).collect();
    if rounds.iter().any(|&r| r != rounds[0]) || certified.iter().any(|c| *c != certified[0]) {
        return Err(format!(
            "the results in {} come from different runs (rounds {rounds:?})",
            results.display()
        ));
    }
    let (latency, _) = merge_outcomes(reports.iter().map(|r| &r.outcome))
        .map_err(|e| format!("agent {}'s result: {}", e.agent, e.source))?;
    let assignment: Vec<usize> = reports.iter().map(|r| r.outcome.task).collect();
    if !problem.is_feasible(&assignment) {
        return Err(format!(
            "the agents' tasks {assignment:?} are not a feasible assignment"
        ));
    }
    let cost = problem.cost_of(&assignment).map_err(|e| e.to_string())?;
    let optimum = if check {
        Some(oracle::solve(&problem).map_err(|e| e.to_string())?.cost)
    } else {
        None
    };
    Ok(TeamResult {
        run: team.file.run.clone(),
        assignment,
        cost,
        iterations: rounds[0],
        converged: certified[0].is_some(),
        certified_round: certified[0],
        optimal_cost: optimum,
        optimal: optimum.map(|o| (cost - o).abs() <= 1e-9 * o.abs().max(1.0)),
        round_latency_us: latency.summary(),
    })
}
