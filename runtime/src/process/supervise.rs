//! The launcher's supervision of a run's agent processes: children reaped as they exit,
//! the first failure blamed on the right agent (stopped-state evidence, a killed agent, the
//! board's mark or the transport's announcement), the others given a grace period and then
//! killed; a stop request stops the team. What it saw becomes the launcher's error.

use crate::process::agent::log_path;
use crate::process::connect::{LauncherSupport, cleanup_dead, uses_board};
use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::process::stop::{reporter, stop_children, stopped_agent, stopped_by_signal};
use admm_ta_transport::board::Board;
use admm_ta_transport::signals;
use std::path::Path;
use std::process::{Child, ExitStatus};
use std::time::Duration;

/// How long the launcher lets a failed agent end by itself before it kills it (one that
/// was killed from outside may still be closing its files when its neighbours notice).
const CULPRIT_EXIT_WAIT: Duration = Duration::from_millis(100);

/// How long the other agents have to stop by themselves after a failure before they are
/// killed (they notice within a 20 ms sleep slice, or after their current step).
const FAILURE_GRACE: Duration = Duration::from_secs(2);

/// How long the launcher waits for an agent's announcement of whom it blames (agents that
/// do not use the board announce through their transport while they exit).
const ANNOUNCEMENT_WAIT: Duration = Duration::from_millis(300);

/// Children and namespace of a run; dropping it kills and reaps every child still running,
/// then removes the run's files.
pub(crate) struct RunGuard {
    pub(crate) namespace: RunNamespace,
    pub(crate) children: Vec<Option<Child>>,
    pub(crate) board: Option<Board>,
    /// What the transport needs (a router), stopped after the children are gone.
    pub(crate) support: Option<LauncherSupport>,
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
        // The transport's support (the run's services, a slot table, a router) before the
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

pub(crate) fn last_log_line(run_dir: &Path, index: usize) -> String {
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
fn stop_team(mut guard: RunGuard, (signal, by): (i32, Option<usize>)) -> Stopped {
    let (stopped, killed) = stop_children(&mut guard.children, guard.board.as_ref(), signal, by);
    let namespace = guard.namespace.clone();
    drop(guard);
    Stopped {
        signal,
        by,
        stopped,
        killed,
        leftovers: namespace.leftovers().len(),
    }
}

/// A run a termination signal stopped (to the launcher, or to agent `by`): nobody failed.
pub(crate) struct Stopped {
    pub(crate) signal: i32,
    pub(crate) by: Option<usize>,
    /// Agents that exited by themselves within the grace period.
    pub(crate) stopped: usize,
    /// Agents killed after it.
    pub(crate) killed: usize,
    pub(crate) leftovers: usize,
}

/// A run an agent's failure ended: who, how, at which round, who reported it, what
/// happened to the others.
pub(crate) struct AgentFailure {
    pub(crate) index: usize,
    pub(crate) status: String,
    pub(crate) round: Option<u64>,
    pub(crate) message: String,
    pub(crate) survivors: usize,
    pub(crate) killed: usize,
    pub(crate) dead_nodes: Option<usize>,
}

/// What supervision saw of a run's agents.
pub(crate) struct Supervision {
    /// How each child that failed ended.
    failures: Vec<Option<String>>,
    /// The agent the run blames.
    failed: Option<usize>,
    /// The agents that exited with a failure, in order.
    failure_order: Vec<usize>,
    /// When the other agents' grace period after the failure ends.
    grace_ends: Option<std::time::Instant>,
    /// Agents killed after the grace period.
    killed: usize,
    /// An agent found stopped (state T), the evidence of whom the others waited for.
    stopped_evidence: Option<usize>,
}

/// How supervision ended (a stop request ends it with an error).
pub(crate) enum Supervised {
    AllExited(RunGuard),
    Failed(RunGuard, Supervision),
}

/// Phase 3: reaps children as they exit until none is left; the first failure ends the
/// run (the culprit is named on the board, the others get a grace period, then SIGKILL).
pub(crate) fn supervise(mut guard: RunGuard, agents: usize) -> Result<Supervised, Stopped> {
    let mut seen = Supervision {
        failures: vec![None; agents],
        failed: None,
        failure_order: Vec::new(),
        grace_ends: None,
        killed: 0,
        stopped_evidence: None,
    };
    while guard.children.iter().any(Option::is_some) {
        if let Some(stop) = stop_request(&guard) {
            tracing::info!(?stop, "stopping the team");
            return Err(stop_team(guard, stop));
        }
        let (progressed, first_failure) = seen.reap_exited(&mut guard);
        if let Some(index) = first_failure {
            seen.name_culprit(&guard, index);
            tracing::warn!(first = index, blamed = ?seen.failed, "failure detected");
        }
        // The failed agent may still run (hung, or sending garbage): it is not waited for.
        if let Some(culprit) = seen.failed
            && let Some(child) = guard.children[culprit].take()
        {
            seen.failures[culprit] = Some(settle_culprit(child));
        }
        if let Some(ends) = seen.grace_ends
            && std::time::Instant::now() >= ends
        {
            seen.kill_the_rest(&mut guard);
        }
        if !progressed {
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    Ok(match seen.failed {
        Some(_) => Supervised::Failed(guard, seen),
        None => Supervised::AllExited(guard),
    })
}

impl Supervision {
    /// Reaps the children that exited; whether any did, and the first to fail (if it is the
    /// run's first failure). An agent that got a termination signal itself stops the team
    /// (on the board): nobody failed.
    fn reap_exited(&mut self, guard: &mut RunGuard) -> (bool, Option<usize>) {
        let mut progressed = false;
        let mut first_failure = None;
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
            match &how {
                None => tracing::debug!(agent = index, "agent exited"),
                Some(how) => tracing::info!(agent = index, how = %how, "agent exited"),
            }
            if let Some(signal) = how.as_deref().and_then(stopped_by_signal) {
                let board = guard.board.as_ref().expect("the board exists");
                let _ = board.request_stop(signal, Some(index));
                self.failures[index] = how;
                break;
            }
            if how.is_some() {
                self.failure_order.push(index);
                if self.failed.is_none() && first_failure.is_none() {
                    first_failure = Some(index);
                }
            }
            self.failures[index] = how;
        }
        (progressed, first_failure)
    }

    /// Decides whom the run blames after agent `index` failed first, marks it on the board,
    /// tells agents that do not read the board, and starts the others' grace period.
    fn name_culprit(&mut self, guard: &RunGuard, index: usize) {
        let board = guard.board.as_ref().expect("the board exists");
        // Evidence first: an agent stopped (SIGSTOP: state T in /proc) is the one its
        // neighbours timed out on. Else an agent may have found a dead or misbehaving peer
        // first (the board's mark): then that peer is the one.
        let culprit = match stopped_agent(&guard.children) {
            Some(stopped) => {
                let _ = board.mark_failed(stopped);
                self.stopped_evidence = Some(stopped);
                stopped
            }
            None => {
                // A killed agent is its own evidence; else what the agents announced.
                let killed = self.failures[index]
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
        self.failed = Some(culprit);
        if let Some(support) = &guard.support {
            support.announce_failure(culprit);
        }
        self.grace_ends = Some(std::time::Instant::now() + FAILURE_GRACE);
    }

    /// Kills and reaps every agent still running after the grace period.
    fn kill_the_rest(&mut self, guard: &mut RunGuard) {
        for (index, slot) in guard.children.iter_mut().enumerate() {
            if let Some(mut child) = slot.take() {
                let _ = child.kill();
                let _ = child.wait();
                self.failures[index] = Some("killed after the grace period".into());
                self.killed += 1;
            }
        }
    }
}

/// How the failed agent ended: it may be ending already (a neighbour saw its sockets close
/// before the kernel made it a zombie), so its own exit says how if it comes within a
/// moment; else it is killed.
fn settle_culprit(mut child: Child) -> String {
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
    match exited {
        Some(status) => describe_exit(status).unwrap_or_else(|| "exited with code 0".into()),
        None => {
            let _ = child.kill();
            let _ = child.wait();
            "killed by the launcher".into()
        }
    }
}

/// What a failed run says: who failed, how, at which round, who reported it (its last
/// log line), and what happened to the others.
pub(crate) fn failure(guard: &RunGuard, seen: &Supervision, scenario: &Scenario) -> AgentFailure {
    let index = seen.failed.expect("a failed run");
    let run_dir = &guard.namespace.dir;
    let board = guard.board.as_ref().expect("the board exists");
    let lines: Vec<(usize, String)> = seen
        .failure_order
        .iter()
        .map(|&i| (i, last_log_line(run_dir, i)))
        .collect();
    let evidence = seen.stopped_evidence == Some(index);
    let reporter = reporter(index, &lines, evidence);
    let status = match seen.failures[index].clone() {
        _ if evidence && reporter == index => "stopped: state T in /proc".to_string(),
        _ if evidence => format!("stopped: state T in /proc, reported by agent {reporter}"),
        Some(how) if index == reporter => how,
        _ => format!("reported by agent {reporter}"),
    };
    AgentFailure {
        index,
        status,
        round: uses_board(scenario).then(|| board.published_round(index)),
        message: last_log_line(run_dir, reporter)
            .trim_start_matches("error: ")
            .to_string(),
        // `killed` never counts the failed agent itself.
        survivors: scenario.robots - 1 - seen.killed,
        killed: seen.killed,
        dead_nodes: cleanup_dead(scenario, run_dir),
    }
}
