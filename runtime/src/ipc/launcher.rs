//! The launcher: writes the scenario, spawns one process per agent, supervises them, reaps
//! every child and removes everything of the run.
//!
//! A failing agent (non-zero exit, crash, timeout) ends the run at once: the launcher kills
//! the others, reaps all of them (`waitpid`: an unreaped child keeps its iceoryx2 locks), and
//! reports the failing agent's last log line. Whatever happens, the run's namespace
//! ([`RunNamespace`]) is removed when the launcher returns.

use crate::exchange::AgentOutcome;
use crate::ipc::agent_process::{AgentReport, log_path, result_path};
use crate::ipc::namespace::RunNamespace;
use crate::ipc::scenario::Scenario;
use crate::ipc::transport::board_size;
use crate::latency::RoundLatency;
use iceoryx2::prelude::{FileName, SemanticString};
use iceoryx2_bb_posix::creation_mode::CreationMode;
use iceoryx2_bb_posix::permission::Permission;
use iceoryx2_bb_posix::shared_memory::{SharedMemory, SharedMemoryBuilder};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// How to run the agent processes.
#[derive(Debug, Clone, PartialEq)]
pub struct IpcOptions {
    /// The `admm-ta` binary (it has the `agent` subcommand).
    pub agent_program: PathBuf,
    pub round_timeout: Duration,
    pub startup_timeout: Duration,
    pub global_barrier: bool,
}

/// Failures of a multi-process run.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    #[error("cannot prepare the run directory: {0}")]
    RunDirectory(std::io::Error),
    #[error("cannot create the run's shared board: {0}")]
    Board(String),
    #[error("cannot start agent process {index} ({program}): {source}")]
    Spawn {
        index: usize,
        program: PathBuf,
        source: std::io::Error,
    },
    #[error("agent {index} failed ({status}): {message}")]
    AgentFailed {
        index: usize,
        status: String,
        message: String,
    },
    #[error("agent {index} exited without a readable result: {message}")]
    MissingResult { index: usize, message: String },
}

/// What a multi-process run produced.
#[derive(Debug, Clone)]
pub struct IpcRun {
    pub run_id: String,
    pub outcomes: Vec<AgentOutcome>,
    pub latency: RoundLatency,
    /// From the first spawn until every agent had all its neighbours connected.
    pub startup: Duration,
    /// Files of the run still present after cleanup (should be none).
    pub leftovers: Vec<PathBuf>,
}

/// Children and namespace of a run; dropping it kills and reaps every child still running,
/// then removes the run's files.
struct RunGuard {
    namespace: RunNamespace,
    children: Vec<Option<Child>>,
    _board: Option<SharedMemory>,
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
        self._board = None;
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

fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exit code {code}"),
        (None, Some(signal)) => format!("killed by signal {signal}"),
        _ => status.to_string(),
    }
}

/// Runs `scenario` (its run id, prefix and root are filled in here) with one process per
/// agent.
pub fn launch(mut scenario: Scenario, options: &IpcOptions) -> Result<IpcRun, LaunchError> {
    let namespace = RunNamespace::create().map_err(LaunchError::RunDirectory)?;
    let mut guard = RunGuard {
        namespace: namespace.clone(),
        children: Vec::new(),
        _board: None,
    };
    scenario.run_id = namespace.id.clone();
    scenario.iceoryx_prefix = namespace.prefix.clone();
    scenario.iceoryx_root = namespace.iceoryx_root();
    scenario.round_timeout_ms = options.round_timeout.as_millis() as u64;
    scenario.startup_timeout_ms = options.startup_timeout.as_millis() as u64;
    scenario.global_barrier = options.global_barrier;
    scenario.board_shm = namespace.board_shm();
    let file = FileName::new(scenario.board_shm.as_bytes())
        .map_err(|e| LaunchError::Board(format!("{e:?}")))?;
    let board = SharedMemoryBuilder::new(&file)
        .is_memory_locked(false)
        .creation_mode(CreationMode::PurgeAndCreate)
        .size(board_size(scenario.robots))
        .permission(Permission::OWNER_READ_WRITE)
        .zero_memory(true)
        .has_ownership(true)
        .create()
        .map_err(|e| LaunchError::Board(format!("{e:?}")))?;
    guard._board = Some(board);
    let run_dir = namespace.dir.clone();
    let scenario_path = run_dir.join("scenario.json");
    let text = serde_json::to_string(&scenario).expect("a scenario serialises");
    std::fs::write(&scenario_path, text).map_err(LaunchError::RunDirectory)?;
    std::fs::create_dir_all(namespace.iceoryx_root()).map_err(LaunchError::RunDirectory)?;

    let spawned_unix_ns = unix_ns();
    for index in 0..scenario.robots {
        let log =
            std::fs::File::create(log_path(&run_dir, index)).map_err(LaunchError::RunDirectory)?;
        let child = Command::new(&options.agent_program)
            .arg("agent")
            .args(["--run", &namespace.id])
            .args(["--index", &index.to_string()])
            .arg("--scenario")
            .arg(&scenario_path)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .map_err(|source| LaunchError::Spawn {
                index,
                program: options.agent_program.clone(),
                source,
            })?;
        guard.children.push(Some(child));
    }

    // Supervise: reap children as they exit; the first failure ends the run.
    let mut running = scenario.robots;
    while running > 0 {
        let mut progressed = false;
        for index in 0..guard.children.len() {
            let Some(child) = guard.children[index].as_mut() else {
                continue;
            };
            match child.try_wait() {
                Ok(None) => {}
                Ok(Some(status)) => {
                    guard.children[index] = None;
                    running -= 1;
                    progressed = true;
                    if !status.success() {
                        return Err(LaunchError::AgentFailed {
                            index,
                            status: describe(status),
                            message: last_log_line(&run_dir, index),
                        });
                    }
                }
                Err(e) => {
                    return Err(LaunchError::AgentFailed {
                        index,
                        status: "unknown".into(),
                        message: format!("cannot wait for the process: {e}"),
                    });
                }
            }
        }
        if !progressed {
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    let mut outcomes = Vec::with_capacity(scenario.robots);
    let mut latency = RoundLatency::new();
    let mut connected = 0u128;
    for index in 0..scenario.robots {
        let path = result_path(&run_dir, index);
        let report: AgentReport = std::fs::read_to_string(&path)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
            .map_err(|message| LaunchError::MissingResult { index, message })?;
        latency
            .merge(&report.outcome.latency)
            .map_err(|e| LaunchError::MissingResult {
                index,
                message: e.to_string(),
            })?;
        connected = connected.max(report.connected_unix_ns);
        outcomes.push(report.outcome);
    }
    let startup = Duration::from_nanos(connected.saturating_sub(spawned_unix_ns) as u64);
    drop(guard);
    Ok(IpcRun {
        run_id: namespace.id.clone(),
        outcomes,
        latency,
        startup,
        leftovers: namespace.leftovers(),
    })
}
