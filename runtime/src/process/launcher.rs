//! The launcher: writes the scenario, spawns one process per agent, supervises them, reaps
//! every child and removes everything of the run.
//!
//! A failing agent (non-zero exit, crash, `kill -9`, timeout) ends the run at once: the
//! launcher marks it failed on the run's board, so every other agent stops cleanly at its
//! next wait (within a 20 ms sleep slice) with an error naming the failed agent and its
//! round, releasing its iceoryx2 ports; agents that have not exited after a grace period
//! are killed. Every child is reaped (`waitpid`: an unreaped child keeps its iceoryx2 locks),
//! the dead agents' iceoryx2 nodes are removed by iceoryx2's dead-node cleanup, and the error
//! is one line: who failed, how, at which round, and what happened to the others. Whatever
//! happens, the run's namespace ([`RunNamespace`]) is removed when the launcher returns.

use crate::board::{Board, BoardError};
use crate::exchange::round_loop::AgentOutcome;
use crate::ipc::nodes::{cleanup_dead_nodes, run_config};
use crate::process::agent::{AgentReport, log_path, result_path};
use crate::process::connect::{LauncherSupport, SupportError};
use crate::process::namespace::RunNamespace;
use crate::process::private_dir::{create_private_file, sha256_hex, write_private_file};
use crate::process::scenario::Scenario;
use crate::process::stop::{reporter, stop_children, stopped_agent, stopped_by_signal};
use crate::process::team_digest::TeamDigest;
use crate::signals;
use crate::transport::Transport;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// How long the launcher lets a failed agent end by itself before it kills it (one that
/// was killed from outside may still be closing its files when its neighbours notice).
const CULPRIT_EXIT_WAIT: Duration = Duration::from_millis(100);

/// Failures of a multi-process run.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    #[error("cannot prepare the run directory")]
    RunDirectory(#[source] std::io::Error),
    /// The open-file or process limits cannot hold the team.
    #[error("{0}")]
    Limits(String),
    #[error("cannot create the run's shared board")]
    Board(#[source] BoardError),
    #[error(transparent)]
    Support(#[from] SupportError),
    #[error("cannot start agent process {index} ({program})")]
    Spawn {
        index: usize,
        program: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "agent {index} failed ({status}){}: {message}; {survivors} other agent(s) stopped cleanly, {killed} had to be killed{}",
        round.map_or(String::new(), |r| format!(" after publishing round {r}")),
        dead_nodes.map_or(String::new(), |d| format!("; {d} dead iceoryx2 node(s) cleaned up"))
    )]
    AgentFailed {
        index: usize,
        status: String,
        /// Last round the failed agent published (`None`: its transport does not record
        /// rounds on the board, as Zenoh's agents).
        round: Option<u64>,
        message: String,
        /// Agents that stopped by themselves after the failure.
        survivors: usize,
        /// Agents killed after the grace period.
        killed: usize,
        /// Dead iceoryx2 nodes removed by the dead-node cleanup (`None`: the run has no
        /// iceoryx2 nodes).
        dead_nodes: Option<usize>,
    },
    /// A termination signal stopped the run (to the launcher, or to agent `by`): nobody
    /// failed.
    #[error(
        "stopped by {}{}: {stopped} agent(s) stopped, {killed} killed, {}",
        crate::signals::name(*signal),
        by.map_or(String::new(), |a| format!(" to agent {a}")),
        if *leftovers == 0 { "run files removed".to_string() } else { format!("{leftovers} run file(s) left") }
    )]
    Stopped {
        signal: i32,
        by: Option<usize>,
        /// Agents that exited by themselves within the grace period.
        stopped: usize,
        /// Agents killed after it.
        killed: usize,
        leftovers: usize,
    },
    #[error("agent {index} exited without a readable result")]
    MissingResult {
        index: usize,
        #[source]
        source: std::io::Error,
    },
    #[error("agent {index} left a malformed result")]
    MalformedResult {
        index: usize,
        #[source]
        source: serde_json::Error,
    },
}

/// What a multi-process run produced.
#[derive(Debug, Clone)]
pub struct ProcessRun {
    pub run_id: String,
    /// Every agent's outcome, in agent order.
    pub outcomes: Vec<AgentOutcome>,
    /// From the first spawn until every agent had all its neighbours connected.
    pub startup: Duration,
    /// Files of the run still present after cleanup (should be none).
    pub leftovers: Vec<PathBuf>,
    /// Each agent's episodes, in a repeated-assignment run.
    pub episodes: Vec<Vec<crate::workload::episode::EpisodeRecord>>,
}

/// How long the other agents have to stop by themselves after a failure before they are
/// killed (they notice within a 20 ms sleep slice, or after their current step).
const FAILURE_GRACE: Duration = Duration::from_secs(2);

/// How long the launcher waits for an agent's announcement of whom it blames (Zenoh agents
/// announce through the router while they exit).
const ANNOUNCEMENT_WAIT: Duration = Duration::from_millis(300);

/// Children and namespace of a run; dropping it kills and reaps every child still running,
/// then removes the run's files.
struct RunGuard {
    namespace: RunNamespace,
    children: Vec<Option<Child>>,
    board: Option<Board>,
    /// What the transport needs (a Zenoh run's router), stopped after the children are gone.
    support: Option<LauncherSupport>,
}

impl Drop for RunGuard {
    fn drop(&mut self) {
        for child in self.children.iter_mut().flatten() {
            let _ = child.kill();
        }
        for child in self.children.iter_mut() {
            if let Some(mut c) = child.take() {
                let _ = c.wait();
            }
        }
        self.board = None;
        // The transport's support (the run's services, an shm run's slot table) before the
        // files under them.
        self.support = None;
        if std::env::var_os("ADMM_TA_STARTUP_TRACE").is_some() {
            for i in 0..self.children.len() {
                eprintln!("{}", last_log_line(&self.namespace.dir, i));
            }
        }
        let _ = self.namespace.cleanup();
    }
}

fn unix_ns() -> u128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos())
}

fn last_log_line(run_dir: &Path, index: usize) -> String {
    std::fs::read_to_string(log_path(run_dir, index))
        .ok()
        .and_then(|log| {
            log.lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .map(str::to_string)
        })
        .unwrap_or_else(|| "no message".into())
}

/// `None` for a successful exit, else how the process ended.
fn describe_exit(status: ExitStatus) -> Option<String> {
    use std::os::unix::process::ExitStatusExt;
    if status.success() {
        return None;
    }
    Some(match (status.code(), status.signal()) {
        (Some(code), _) => format!("exit code {code}"),
        (None, Some(signal)) => format!("killed by signal {signal}"),
        _ => status.to_string(),
    })
}

/// A stop request: a termination signal to the launcher, or one an agent got (on the board);
/// the signal and the agent it went to.
fn stop_request(guard: &RunGuard) -> Option<(i32, Option<usize>)> {
    if let Some(signal) = signals::received() {
        return Some((signal, None));
    }
    guard.board.as_ref()?.stop_requested()
}

/// Stops every agent after `stop`: the request on the board (and the signal forwarded to
/// each child, for agents that do not read the board), a grace period to leave cleanly
/// (cut short by a second termination signal), then SIGKILL; every child is reaped and the
/// run's files removed.
fn stop_team(mut guard: RunGuard, (signal, by): (i32, Option<usize>)) -> LaunchError {
    let (stopped, killed) = stop_children(&mut guard.children, guard.board.as_ref(), signal, by);
    let namespace = guard.namespace.clone();
    drop(guard);
    LaunchError::Stopped {
        signal,
        by,
        stopped,
        killed,
        leftovers: namespace.leftovers().len(),
    }
}

/// Runs `scenario` (its run id, prefix, root and board are filled in here) with one process
/// per agent started from `agent_program` (the `admm-ta` binary); `fault_injection`: pass
/// the `ADMM_TA_FAULT` test switch on to the agents.
pub fn launch(
    mut scenario: Scenario,
    agent_program: &Path,
    fault_injection: bool,
) -> Result<ProcessRun, LaunchError> {
    let _signals = signals::install();
    // Before anything is created or spawned.
    let max_degree = scenario
        .graph()
        .map(|g| (0..g.robots()).map(|i| g.degree(i)).max().unwrap_or(0))
        .unwrap_or(scenario.robots.saturating_sub(1));
    crate::process::limits::check(scenario.transport, scenario.robots, max_degree)
        .map_err(LaunchError::Limits)?;
    let namespace = RunNamespace::create().map_err(LaunchError::RunDirectory)?;
    let mut guard = RunGuard {
        namespace: namespace.clone(),
        children: Vec::new(),
        board: None,
        support: None,
    };
    scenario.run_id = namespace.id.clone();
    scenario.iceoryx_prefix = namespace.prefix.clone();
    scenario.iceoryx_root = namespace.iceoryx_root();
    scenario.board_shm = namespace.board_shm();
    guard.board = Some(
        Board::create(
            &scenario.board_shm,
            scenario.robots,
            scenario.tasks,
            scenario.payload_len(),
        )
        .map_err(LaunchError::Board)?,
    );
    // Every service of the run before the first agent starts (agents only open them).
    namespace
        .create_iceoryx_root()
        .map_err(LaunchError::RunDirectory)?;
    guard.support = Some(LauncherSupport::start(&mut scenario, &namespace)?);
    let run_dir = namespace.dir.clone();
    let scenario_path = run_dir.join("scenario.json");
    let text = serde_json::to_string(&scenario).expect("a scenario serialises");
    // Exclusively, mode 0600; agents check owner, mode and this digest before reading it.
    write_private_file(&scenario_path, text.as_bytes()).map_err(LaunchError::RunDirectory)?;
    let scenario_digest = sha256_hex(text.as_bytes());
    // The team's identity, checked by every agent before it opens a service.
    TeamDigest::of(&scenario).publish(guard.board.as_ref().expect("the board exists"));

    let spawned_unix_ns = unix_ns();
    for index in 0..scenario.robots {
        let log =
            create_private_file(&log_path(&run_dir, index)).map_err(LaunchError::RunDirectory)?;
        let mut command = Command::new(agent_program);
        let launcher_pid = std::process::id() as libc::pid_t;
        // SAFETY: only async-signal-safe calls between fork and exec.
        unsafe {
            command.pre_exec(move || {
                // The agent gets SIGTERM (and stops cleanly) when the launcher dies, even by
                // SIGKILL; a launcher that died before this line is caught by the pid check.
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0
                    || libc::getppid() != launcher_pid
                {
                    return Err(std::io::Error::other("the launcher is gone"));
                }
                Ok(())
            });
        }
        #[cfg(feature = "fault-injection")]
        if !fault_injection {
            command.env_remove(crate::fault::FAULT_ENV);
        }
        #[cfg(not(feature = "fault-injection"))]
        let _ = fault_injection;
        let child = command
            .arg("agent")
            .args(["--run", &namespace.id])
            .args(["--index", &index.to_string()])
            .arg("--scenario")
            .arg(&scenario_path)
            .args(["--scenario-digest", &scenario_digest])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .map_err(|source| LaunchError::Spawn {
                index,
                program: agent_program.to_path_buf(),
                source,
            })?;
        guard.children.push(Some(child));
    }

    // Supervise: reap children as they exit; the first failure ends the run.
    // How each child that failed ended.
    let mut failures: Vec<Option<String>> = vec![None; scenario.robots];
    // The agent that failed, and the agents that exited with a failure, in order.
    let mut failed: Option<usize> = None;
    let mut failure_order = Vec::new();
    let mut grace_ends = None;
    let mut killed = 0;
    let mut stopped_evidence = None;
    let mut first_failure = None;
    while guard.children.iter().any(Option::is_some) {
        if let Some(stop) = stop_request(&guard) {
            return Err(stop_team(guard, stop));
        }
        let mut progressed = false;
        for (index, slot) in guard.children.iter_mut().enumerate() {
            let Some(child) = slot.as_mut() else {
                continue;
            };
            let how = match child.try_wait() {
                Ok(None) => continue,
                Ok(Some(status)) => describe_exit(status),
                Err(e) => {
                    let _ = child.kill();
                    let _ = child.wait();
                    Some(format!("cannot wait for the process: {e}"))
                }
            };
            *slot = None;
            progressed = true;
            if let Some(signal) = how.as_deref().and_then(stopped_by_signal) {
                // The agent got a termination signal itself: the team stops, nobody failed.
                let board = guard.board.as_ref().expect("the board exists");
                let _ = board.request_stop(signal, Some(index));
                failures[index] = how;
                break;
            }
            if how.is_some() {
                failure_order.push(index);
            }
            if how.is_some() && failed.is_none() && first_failure.is_none() {
                first_failure = Some(index);
            }
            failures[index] = how;
        }
        if let Some(index) = first_failure.take() {
            let board = guard.board.as_ref().expect("the board exists");
            // Evidence first: an agent stopped (SIGSTOP: state T in /proc) is the one its
            // neighbours timed out on. Else an agent may have found a dead or misbehaving
            // peer first (the board's mark): then that peer is the one.
            let culprit = match stopped_agent(&guard.children) {
                Some(stopped) => {
                    let _ = board.mark_failed(stopped);
                    stopped_evidence = Some(stopped);
                    stopped
                }
                None => {
                    // A killed agent is its own evidence; else what the agents announced.
                    let killed = failures[index]
                        .as_deref()
                        .is_some_and(|h| h.starts_with("killed by signal"));
                    let announced = guard
                        .support
                        .as_ref()
                        .filter(|_| !killed)
                        .and_then(|s| s.announced_failure(ANNOUNCEMENT_WAIT));
                    let marked = board.mark_failed(announced.unwrap_or(index));
                    marked.or(announced).unwrap_or(index)
                }
            };
            failed = Some(culprit);
            // Agents that do not read the board (Zenoh's) learn it another way.
            if let Some(support) = &guard.support {
                support.announce_failure(culprit);
            }
            grace_ends = Some(std::time::Instant::now() + FAILURE_GRACE);
        }
        // The failed agent may still run (hung, or sending garbage): it is not waited for.
        if let Some(culprit) = failed
            && let Some(mut child) = guard.children[culprit].take()
        {
            // It may be ending already (a neighbour saw its sockets close before the kernel
            // made it a zombie): its own exit says how, if it comes within a moment.
            let exited = {
                let until = std::time::Instant::now() + CULPRIT_EXIT_WAIT;
                loop {
                    match child.try_wait() {
                        Ok(None) if std::time::Instant::now() < until => {
                            std::thread::sleep(Duration::from_millis(1));
                        }
                        Ok(status) => break status,
                        Err(_) => break None,
                    }
                }
            };
            failures[culprit] = match exited {
                Some(status) => describe_exit(status).or_else(|| Some("exited with code 0".into())),
                None => {
                    let _ = child.kill();
                    let _ = child.wait();
                    Some("killed by the launcher".into())
                }
            };
        }
        if let Some(ends) = grace_ends
            && std::time::Instant::now() >= ends
        {
            for (index, slot) in guard.children.iter_mut().enumerate() {
                if let Some(mut child) = slot.take() {
                    let _ = child.kill();
                    let _ = child.wait();
                    failures[index] = Some("killed after the grace period".into());
                    killed += 1;
                }
            }
        }
        if !progressed {
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    if let Some(index) = failed {
        let board = guard.board.as_ref().expect("the board exists");
        let lines: Vec<(usize, String)> = failure_order
            .iter()
            .map(|&i| (i, last_log_line(&run_dir, i)))
            .collect();
        let reporter = reporter(index, &lines, stopped_evidence == Some(index));
        let status = match failures[index].take() {
            _ if stopped_evidence == Some(index) && reporter == index => {
                "stopped: state T in /proc".to_string()
            }
            _ if stopped_evidence == Some(index) => {
                format!("stopped: state T in /proc, reported by agent {reporter}")
            }
            Some(how) if index == reporter => how,
            _ => format!("reported by agent {reporter}"),
        };
        // `killed` never counts the failed agent itself.
        let survivors = scenario.robots - 1 - killed;
        // Only iceoryx2's agents have nodes; Zenoh's do not publish rounds on the board.
        let dead_nodes = (scenario.transport == Transport::Ipc).then(|| {
            run_config(&namespace.prefix, &namespace.iceoryx_root())
                .map(|config| cleanup_dead_nodes(&config))
                .unwrap_or(0)
        });
        return Err(LaunchError::AgentFailed {
            index,
            status,
            round: (scenario.transport != Transport::Zenoh).then(|| board.published_round(index)),
            message: last_log_line(&run_dir, reporter)
                .trim_start_matches("error: ")
                .to_string(),
            survivors,
            killed,
            dead_nodes,
        });
    }

    let mut outcomes = Vec::with_capacity(scenario.robots);
    let mut episodes = Vec::with_capacity(scenario.robots);
    let mut connected = 0u128;
    for index in 0..scenario.robots {
        let path = result_path(&run_dir, index);
        let text = std::fs::read_to_string(&path)
            .map_err(|source| LaunchError::MissingResult { index, source })?;
        let report: AgentReport = serde_json::from_str(&text)
            .map_err(|source| LaunchError::MalformedResult { index, source })?;
        connected = connected.max(report.connected_unix_ns);
        outcomes.push(report.outcome);
        episodes.push(report.episodes);
    }
    let startup = Duration::from_nanos(connected.saturating_sub(spawned_unix_ns) as u64);
    drop(guard);
    Ok(ProcessRun {
        run_id: namespace.id.clone(),
        outcomes,
        startup,
        leftovers: namespace.leftovers(),
        episodes,
    })
}
