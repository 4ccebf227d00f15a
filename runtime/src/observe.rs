//! What `admm-ta top` shows: this user's running teams and, per agent, its round and state,
//! read only from what the team already shares — the run's board in shared memory (every
//! agent's last published round, who connected, who failed, a stop request), the run's
//! private directory (its scenario: the graph; the agents' result files) and `/proc` (the
//! agent processes' CPU time). Nothing here writes to a team or waits for one: a snapshot
//! maps the board, loads its atomics and unmaps it.
//!
//! Teams of agent processes started by a launcher (`solve --transport ipc|uds|…`) and
//! independently started teams (`agent --team`) are both listed; a team of threads or the
//! lockstep simulation has no board and is not. An agent waits for the neighbours that have
//! not yet published the round it gathers (its own last published round); one whose
//! neighbours all have is computing.

use crate::process::agent::result_path;
use crate::process::namespace::runs_dir;
use crate::process::private_dir::euid;
use crate::process::scenario::Scenario;
use admm_ta_transport::board::Board;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One snapshot of every running team.
#[derive(Debug, Clone, Serialize)]
pub struct Snapshot {
    pub teams: Vec<TeamView>,
}

/// A running team.
#[derive(Debug, Clone, Serialize)]
pub struct TeamView {
    /// The run id (a launcher's run) or `team-NAME` (an independently started team).
    pub run: String,
    /// `launcher` or `team`.
    pub kind: &'static str,
    pub robots: usize,
    /// The launcher's process (a launcher's run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub launcher_pid: Option<u32>,
    /// The topology's name, when the run's scenario tells it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub topology: Option<String>,
    /// A stop request on the board: the signal's name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stop_requested: Option<String>,
    pub agents: Vec<AgentView>,
}

/// One agent of a running team.
#[derive(Debug, Clone, Serialize)]
pub struct AgentView {
    pub agent: usize,
    /// The last round it published.
    pub round: u64,
    /// `starting`, `computing`, `waiting`, `finished` or `failed`.
    pub state: &'static str,
    /// The neighbours it waits for (`waiting`; known when the graph is).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub waiting_for: Vec<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pid: Option<u32>,
    /// Milliseconds per round since the previous snapshot (agents that advanced).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub round_ms: Option<f64>,
    /// CPU use since the previous snapshot, percent of one core.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cpu_percent: Option<f64>,
}

/// Successive snapshots: rates (round time, CPU) come from the previous one.
#[derive(Debug, Default)]
pub struct Observer {
    /// Per `(run, agent)`: the round and CPU ticks at the previous snapshot.
    previous: BTreeMap<(String, usize), (u64, Option<u64>)>,
    taken: Option<Instant>,
}

impl Observer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Every running team of this user now.
    pub fn snapshot(&mut self) -> Snapshot {
        let now = Instant::now();
        let elapsed = self.taken.map(|t| now.duration_since(t).as_secs_f64());
        self.taken = Some(now);
        let mut teams = launcher_runs();
        teams.extend(independent_teams());
        let mut previous = BTreeMap::new();
        for team in &mut teams {
            for agent in &mut team.agents {
                let ticks = agent.pid.and_then(cpu_ticks);
                let key = (team.run.clone(), agent.agent);
                if let (Some(elapsed), Some((round, before))) = (elapsed, self.previous.get(&key)) {
                    let advanced = agent.round.saturating_sub(*round);
                    if advanced > 0 {
                        agent.round_ms = Some(1e3 * elapsed / advanced as f64);
                    }
                    if let (Some(now), Some(before)) = (ticks, before) {
                        let per_second = clock_ticks_per_second();
                        agent.cpu_percent =
                            Some(100.0 * now.saturating_sub(*before) as f64 / per_second / elapsed);
                    }
                }
                previous.insert(key, (agent.round, ticks));
            }
        }
        self.previous = previous;
        Snapshot { teams }
    }
}

/// The user's launcher runs with a live launcher.
fn launcher_runs() -> Vec<TeamView> {
    let Ok(entries) = std::fs::read_dir(runs_dir()) else {
        return Vec::new();
    };
    let mut teams: Vec<TeamView> = entries
        .flatten()
        .filter_map(|entry| launcher_run(&entry.path()))
        .collect();
    teams.sort_by(|a, b| a.run.cmp(&b.run));
    teams
}

fn launcher_run(dir: &Path) -> Option<TeamView> {
    let run = dir.file_name()?.to_str()?.to_string();
    let launcher_pid: u32 = std::fs::read_to_string(dir.join("launcher.pid"))
        .ok()?
        .trim()
        .parse()
        .ok()?;
    if !admm_ta_transport::liveness::process_alive(launcher_pid) {
        return None;
    }
    let bytes = std::fs::read(dir.join("scenario.json")).ok()?;
    let scenario = Scenario::parse(&bytes, &dir.join("scenario.json"), &run).ok()?;
    let board = Board::open(&scenario.board_shm, scenario.robots).ok()?;
    let graph = scenario.graph().ok();
    let pids = agent_pids(launcher_pid, &run);
    let agents = (0..scenario.robots)
        .map(|i| {
            let finished = result_path(dir, i).exists();
            let neighbours = graph.as_ref().map(|g| g.neighbours(i).to_vec());
            agent_view(
                &board,
                i,
                finished,
                neighbours.as_deref(),
                pids.get(&i).copied(),
            )
        })
        .collect();
    Some(TeamView {
        run,
        kind: "launcher",
        robots: scenario.robots,
        launcher_pid: Some(launcher_pid),
        topology: Some(scenario.topology.clone()),
        stop_requested: board
            .stop_requested()
            .map(|(signal, _)| admm_ta_transport::signals::name(signal)),
        agents,
    })
}

/// Independently started teams: their boards in `/dev/shm` (`adtat<uid>-<name>_board`).
fn independent_teams() -> Vec<TeamView> {
    let prefix = format!("adtat{}-", euid());
    let Ok(entries) = std::fs::read_dir("/dev/shm") else {
        return Vec::new();
    };
    let mut teams = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(team) = name
            .strip_prefix(&prefix)
            .and_then(|rest| rest.strip_suffix("_board"))
        else {
            continue;
        };
        let Some(board) = Board::open_sized(&name) else {
            continue;
        };
        let mut agents: Vec<AgentView> = (0..board.agents())
            .filter(|&i| board.registered(i) || board.connected(i))
            .map(|i| {
                // A member that left cleared its pid; one whose process is gone died.
                let pid = board.member_pid(i);
                let gone = pid.is_none_or(|p| !admm_ta_transport::liveness::process_alive(p));
                agent_view(&board, i, gone, None, pid)
            })
            .collect();
        // The graph is the team file's (not on the board): before every member has
        // connected, the connected ones wait for the others to start.
        let missing: Vec<usize> = (0..board.agents())
            .filter(|&i| !board.connected(i))
            .collect();
        if !missing.is_empty() {
            for agent in agents.iter_mut().filter(|a| a.state == "computing") {
                agent.state = "waiting";
                agent.waiting_for = missing.clone();
            }
        }
        teams.push(TeamView {
            run: format!("team-{team}"),
            kind: "team",
            robots: board.agents(),
            launcher_pid: None,
            topology: None,
            stop_requested: board
                .stop_requested()
                .map(|(signal, _)| admm_ta_transport::signals::name(signal)),
            agents,
        });
    }
    teams.sort_by(|a, b| a.run.cmp(&b.run));
    teams
}

fn agent_view(
    board: &Board,
    agent: usize,
    finished: bool,
    neighbours: Option<&[usize]>,
    pid: Option<u32>,
) -> AgentView {
    let round = board.published_round(agent);
    let mut waiting_for = Vec::new();
    let state = if board.failed() == Some(agent) {
        "failed"
    } else if finished {
        "finished"
    } else if !board.connected(agent) {
        "starting"
    } else {
        if let Some(neighbours) = neighbours {
            waiting_for = neighbours
                .iter()
                .copied()
                .filter(|&j| board.published_round(j) < round)
                .collect();
        }
        if waiting_for.is_empty() {
            "computing"
        } else {
            "waiting"
        }
    };
    AgentView {
        agent,
        round,
        state,
        waiting_for,
        pid,
        round_ms: None,
        cpu_percent: None,
    }
}

/// The agent processes of launcher `launcher` for run `run`, by agent index (from their
/// command lines: `… agent --run RUN --robot I …`).
fn agent_pids(launcher: u32, run: &str) -> BTreeMap<usize, u32> {
    let mut pids = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return pids;
    };
    for entry in entries.flatten() {
        let Some(pid) = entry
            .file_name()
            .to_str()
            .and_then(|s| s.parse::<u32>().ok())
        else {
            continue;
        };
        let proc_dir = PathBuf::from("/proc").join(pid.to_string());
        let Ok(stat) = std::fs::read_to_string(proc_dir.join("stat")) else {
            continue;
        };
        let parent = stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().nth(1))
            .and_then(|p| p.parse::<u32>().ok());
        if parent != Some(launcher) {
            continue;
        }
        let Ok(cmdline) = std::fs::read(proc_dir.join("cmdline")) else {
            continue;
        };
        let args: Vec<&[u8]> = cmdline.split(|&b| b == 0).collect();
        let value = |flag: &[u8]| {
            args.windows(2)
                .find(|w| w[0] == flag)
                .and_then(|w| std::str::from_utf8(w[1]).ok())
        };
        if value(b"--run") == Some(run)
            && let Some(index) = value(b"--robot").and_then(|i| i.parse().ok())
        {
            pids.insert(index, pid);
        }
    }
    pids
}

/// User and system CPU time of process `pid`, in clock ticks.
fn cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    // After the command: state (0), ppid (1), … utime (11), stime (12).
    Some(fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?)
}

fn clock_ticks_per_second() -> f64 {
    // SAFETY: sysconf only reads a system constant.
    let ticks = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
    if ticks > 0 { ticks as f64 } else { 100.0 }
}
