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

use crate::ipc::agent_process::{AgentReport, run_scenario};
use crate::ipc::namespace::RunNamespace;
use crate::ipc::transport::{Board, cleanup_dead_nodes, run_config};
use crate::solve::{self, Method, SolveConfig, StopRule, Transport};
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

fn seconds(name: &str, v: f64) -> Result<Duration, String> {
    if v.is_finite() && v > 0.0 && v < 1e6 {
        Ok(Duration::from_secs_f64(v))
    } else {
        Err(format!(
            "{name} must be a positive number of seconds, got {v}"
        ))
    }
}

impl Team {
    pub fn read(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read team file {}: {e}", path.display()))?;
        let file: TeamFile = toml::from_str(&text)
            .map_err(|e| format!("team file {}: {}", path.display(), e.message()))?;
        let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        RunNamespace::check_team_name(&file.run)?;
        seconds("startup_timeout", file.startup_timeout)?;
        seconds("round_timeout", file.round_timeout)?;
        Ok(Self { file, base })
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

    fn solve_config(&self) -> Result<SolveConfig, String> {
        let f = &self.file;
        Ok(SolveConfig {
            method: f.method,
            transport: Transport::Ipc,
            adaptive_rho: f.adaptive_rho,
            max_iters: f.max_iters,
            stop: StopRule::Local,
            seed: f.seed,
            round_timeout: seconds("round_timeout", f.round_timeout)?,
            startup_timeout: seconds("startup_timeout", f.startup_timeout)?,
            ..SolveConfig::default()
        })
    }
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
    let (problem, graph) = team.problem_and_graph()?;
    let config = team.solve_config()?;
    let mut scenario =
        solve::agent_scenario(&problem, &graph, &config).map_err(|e| e.to_string())?;
    let namespace = RunNamespace::for_team(&team.file.run)?;
    scenario.run_id = namespace.id.clone();
    scenario.iceoryx_prefix = namespace.prefix.clone();
    scenario.iceoryx_root = namespace.iceoryx_root();
    scenario.board_shm = namespace.board_shm();
    let results = team.results_dir();
    std::fs::create_dir_all(&results)
        .map_err(|e| format!("cannot create {}: {e}", results.display()))?;
    let result = member_result(&results, id);
    // A result of an earlier run must not pass for this one's.
    let _ = std::fs::remove_file(&result);
    let deadline = started + config.startup_timeout;
    let board = {
        let _lock = FileLock::acquire(&namespace.dir.join("lock"), deadline)?;
        let fresh = Board::open(&scenario.board_shm, n).is_err();
        let board = Board::open_or_create_for_team(
            &scenario.board_shm,
            n,
            scenario.tasks,
            scenario.payload_len(),
        )?;
        board.set_member_pid(id, std::process::id());
        std::fs::create_dir_all(&scenario.iceoryx_root)
            .map_err(|e| format!("cannot create {}: {e}", scenario.iceoryx_root.display()))?;
        if fresh {
            // Nodes of a dead team of this name.
            let _ = run_config(&scenario.iceoryx_prefix, &scenario.iceoryx_root)
                .map(|c| cleanup_dead_nodes(&c));
        }
        board
    };
    let report = run_scenario(&scenario, id, &namespace.dir, &result, false);
    if report.is_err() {
        // No launcher reports us: tell the others (the first mark wins, so an agent that
        // stopped because of another's failure changes nothing).
        let _ = board.mark_failed(id);
    }
    let deadline = Instant::now() + Duration::from_secs(5);
    let last = FileLock::acquire(&namespace.dir.join("lock"), deadline)
        .map(|_lock| board.member_left(id))
        .unwrap_or(false);
    if last {
        drop(board);
        let _ = namespace.cleanup();
    }
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
    })
}
