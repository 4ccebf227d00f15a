//! The launcher: writes the scenario, spawns one process per agent, supervises them, reaps
//! every child and removes everything of the run.
//!
//! A failing agent (non-zero exit, crash, `kill -9`, timeout) ends the run at once: the
//! launcher marks it failed on the run's board, so every other agent stops cleanly at its
//! next wait (within a 20 ms sleep slice) with an error naming the failed agent and its
//! round, releasing its transport's ports; agents that have not exited after a grace period
//! are killed. Every child is reaped (`waitpid`: an unreaped child keeps its locks), what
//! the dead agents left is removed by their transport's cleanup, and the error
//! is one line: who failed, how, at which round, and what happened to the others. Whatever
//! happens, the run's namespace ([`RunNamespace`]) is removed when the launcher returns.

use crate::options::run::AgentProgram;
use crate::process::agent::{AgentReport, log_path, result_path};
use crate::process::connect::LauncherSupport;
use crate::process::namespace::RunNamespace;
use crate::process::private_dir::{create_private_file, sha256_hex, write_private_file};
use crate::process::scenario::Scenario;
use crate::process::supervise::{AgentFailure, RunGuard, Stopped, Supervised, failure, supervise};
use crate::process::team_digest::TeamDigest;
use crate::workload::surveillance::EpisodeRecord;
use admm_ta_transport::board::{Board, BoardError};
use admm_ta_transport::endpoint::SupportError;
use admm_ta_transport::exchange::round_loop::AgentOutcome;
use admm_ta_transport::signals;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// Failures of a multi-process run.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    #[error("cannot prepare the run directory")]
    RunDirectory(#[source] std::io::Error),
    /// The open-file or process limits cannot hold the team.
    #[error(transparent)]
    Limits(#[from] crate::process::limits::LimitError),
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
        /// rounds on the board).
        round: Option<u64>,
        message: String,
        /// Agents that stopped by themselves after the failure.
        survivors: usize,
        /// Agents killed after the grace period.
        killed: usize,
        /// Dead agents' leftovers the transport removed itself (iceoryx2 nodes; `None`: the
        /// transport leaves nothing such).
        dead_nodes: Option<usize>,
    },
    /// A termination signal stopped the run (to the launcher, or to agent `by`): nobody
    /// failed.
    #[error(
        "stopped by {}{}: {stopped} agent(s) stopped, {killed} killed, {}",
        admm_ta_transport::signals::name(*signal),
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
    pub episodes: Vec<Vec<EpisodeRecord>>,
}

impl From<Stopped> for LaunchError {
    fn from(s: Stopped) -> Self {
        Self::Stopped {
            signal: s.signal,
            by: s.by,
            stopped: s.stopped,
            killed: s.killed,
            leftovers: s.leftovers,
        }
    }
}

impl From<AgentFailure> for LaunchError {
    fn from(f: AgentFailure) -> Self {
        Self::AgentFailed {
            index: f.index,
            status: f.status,
            round: f.round,
            message: f.message,
            survivors: f.survivors,
            killed: f.killed,
            dead_nodes: f.dead_nodes,
        }
    }
}

fn unix_ns() -> u128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos())
}

/// Runs `scenario` (its run id, prefix, root and board are filled in here) with one process
/// per agent started from `agent_program` (the `admm-ta` binary); `fault_injection`: pass
/// the `ADMM_TA_FAULT` test switch on to the agents.
///
/// Four phases: prepare the run (limits, namespace, board, the transport's support, the
/// scenario file), spawn the agents, supervise them until every one has exited (the first
/// failure ends the run), and read their results.
pub fn launch(
    mut scenario: Scenario,
    agent_program: &AgentProgram,
    fault_injection: bool,
) -> Result<ProcessRun, LaunchError> {
    let _signals = signals::install();
    let (mut guard, scenario_file) = prepare(&mut scenario)?;
    let _span = tracing::info_span!("launcher", run = %scenario.run_id).entered();
    tracing::debug!(dir = %guard.namespace.dir.display(), robots = scenario.robots, "run prepared");
    let spawned_unix_ns = unix_ns();
    spawn_agents(&mut guard, &scenario_file, agent_program, fault_injection)?;
    let guard = match supervise(guard, scenario.robots)? {
        Supervised::AllExited(guard) => guard,
        Supervised::Failed(guard, supervision) => {
            let error = LaunchError::from(failure(&guard, &supervision, &scenario));
            tracing::warn!(%error, "the team failed");
            return Err(error);
        }
    };
    let run_dir = guard.namespace.dir.clone();
    let namespace = guard.namespace.clone();
    let (outcomes, episodes, connected) = read_results(&run_dir, scenario.robots)?;
    let startup = Duration::from_nanos(connected.saturating_sub(spawned_unix_ns) as u64);
    tracing::info!(
        startup_ms = startup.as_secs_f64() * 1e3,
        rounds = outcomes.first().map_or(0, |o| o.rounds),
        "every agent exited with its result"
    );
    drop(guard);
    tracing::debug!("run files removed");
    Ok(ProcessRun {
        run_id: namespace.id.clone(),
        outcomes,
        startup,
        leftovers: namespace.leftovers(),
        episodes,
    })
}

/// The scenario file the agents read, and its digest.
struct ScenarioFile {
    path: PathBuf,
    digest: String,
}

/// Phase 1: checks the limits before anything is created, then makes the run's namespace,
/// board, transport root and support, fills in the scenario's names and writes it.
fn prepare(scenario: &mut Scenario) -> Result<(RunGuard, ScenarioFile), LaunchError> {
    let degrees: Vec<usize> = match scenario.graph() {
        Ok(g) => (0..g.robots()).map(|i| g.degree(i)).collect(),
        Err(_) => vec![scenario.robots.saturating_sub(1); scenario.robots],
    };
    let max_degree = degrees.iter().copied().max().unwrap_or(0);
    crate::process::limits::check(scenario.transport, scenario.robots, max_degree)?;
    let header = admm_ta_transport::exchange::header::RoundHeader::WORDS;
    crate::process::limits::check_relay(
        scenario.transport,
        crate::process::limits::RoundLoad {
            messages: degrees.iter().sum::<usize>() as u64,
            message_bytes: ((header + scenario.payload_len()) * 8) as u64,
            round_timeout: Duration::from_millis(scenario.round_timeout_ms),
        },
    )?;
    let namespace = RunNamespace::create().map_err(LaunchError::RunDirectory)?;
    let mut guard = RunGuard {
        namespace: namespace.clone(),
        children: Vec::new(),
        board: None,
        support: None,
    };
    scenario.run_id = namespace.id.clone();
    scenario.prefix = namespace.prefix.clone();
    scenario.transport_root = namespace.transport_root();
    scenario.board_shm = namespace.board_shm();
    let board = Board::create(
        &scenario.board_shm,
        scenario.robots,
        scenario.tasks,
        scenario.payload_len(),
    )
    .map_err(LaunchError::Board)?;
    guard.board = Some(board);
    // Everything the agents open (the run's services) before the first agent starts.
    namespace
        .create_transport_root()
        .map_err(LaunchError::RunDirectory)?;
    guard.support = Some(LauncherSupport::start(scenario, &namespace.dir)?);
    let path = namespace.dir.join("scenario.json");
    let text = serde_json::to_string(&scenario).expect("a scenario serialises");
    // Exclusively, mode 0600; agents check owner, mode and this digest before reading it.
    write_private_file(&path, text.as_bytes()).map_err(LaunchError::RunDirectory)?;
    let digest = sha256_hex(text.as_bytes());
    // The team's identity, checked by every agent before it opens anything of the run.
    TeamDigest::of(scenario).publish(guard.board.as_ref().expect("the board exists"));
    Ok((guard, ScenarioFile { path, digest }))
}

/// Phase 2: starts one `admm-ta agent` process per agent, each with its own private log.
fn spawn_agents(
    guard: &mut RunGuard,
    scenario: &ScenarioFile,
    agent_program: &AgentProgram,
    fault_injection: bool,
) -> Result<(), LaunchError> {
    let agents = guard.board.as_ref().expect("the board exists").agents();
    let run_dir = guard.namespace.dir.clone();
    // With logs on, every agent writes its log lines to this process's standard error (a
    // copy kept close-on-exec here, made the agent's descriptor 3), its own standard error
    // staying its private log file.
    let log_fd = admm_ta_transport::logging::filter().and_then(|_| {
        // SAFETY: duplicating our standard error to a close-on-exec descriptor.
        let fd = unsafe { libc::fcntl(2, libc::F_DUPFD_CLOEXEC, 10) };
        (fd >= 0).then_some(fd)
    });
    let _close_log_fd = CloseOnDrop(log_fd);
    tracing::debug!(agents, program = %agent_program.program().display(), "starting the agents");
    for index in 0..agents {
        let log =
            create_private_file(&log_path(&run_dir, index)).map_err(LaunchError::RunDirectory)?;
        let mut command = Command::new(agent_program.program());
        command.args(agent_program.args());
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
                if let Some(fd) = log_fd
                    && libc::dup2(fd, admm_ta_transport::logging::CHILD_LOG_FD) < 0
                {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        if let (Some(filter), Some(_)) = (admm_ta_transport::logging::filter(), log_fd) {
            command.env("RUST_LOG", filter).env(
                admm_ta_transport::logging::LOG_FD_ENV,
                admm_ta_transport::logging::CHILD_LOG_FD.to_string(),
            );
        }
        if let Some(variable) = guard.support.as_ref().and_then(|s| s.unset_for_agents()) {
            command.env_remove(variable);
        }
        #[cfg(feature = "fault-injection")]
        if !fault_injection {
            command.env_remove(admm_ta_transport::fault::FAULT_ENV);
        }
        #[cfg(not(feature = "fault-injection"))]
        let _ = fault_injection;
        let child = command
            .arg("agent")
            .args(["--run", &guard.namespace.id])
            .args(["--robot", &index.to_string()])
            .arg("--scenario")
            .arg(&scenario.path)
            .args(["--scenario-digest", &scenario.digest])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .map_err(|source| LaunchError::Spawn {
                index,
                program: agent_program.program().to_path_buf(),
                source,
            })?;
        guard.children.push(Some(child));
    }
    Ok(())
}

/// Closes a descriptor of ours when dropped.
struct CloseOnDrop(Option<libc::c_int>);

impl Drop for CloseOnDrop {
    fn drop(&mut self) {
        if let Some(fd) = self.0 {
            // SAFETY: a descriptor this launcher opened and nobody else closes.
            unsafe { libc::close(fd) };
        }
    }
}

/// Every agent's outcome and episodes, in agent order, and when the last one had all its
/// neighbours connected (unix ns).
type Results = (Vec<AgentOutcome>, Vec<Vec<EpisodeRecord>>, u128);

/// Phase 4: the agents' [`Results`].
fn read_results(run_dir: &Path, agents: usize) -> Result<Results, LaunchError> {
    let mut outcomes = Vec::with_capacity(agents);
    let mut episodes = Vec::with_capacity(agents);
    let mut connected = 0u128;
    for index in 0..agents {
        let path = result_path(run_dir, index);
        let text = std::fs::read_to_string(&path)
            .map_err(|source| LaunchError::MissingResult { index, source })?;
        let report: AgentReport = serde_json::from_str(&text)
            .map_err(|source| LaunchError::MalformedResult { index, source })?;
        connected = connected.max(report.connected_unix_ns);
        outcomes.push(report.outcome);
        episodes.push(report.episodes);
    }
    Ok((outcomes, episodes, connected))
}
