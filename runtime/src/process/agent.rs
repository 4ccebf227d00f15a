//! The body of `admm-ta agent --run ID --robot I --scenario FILE`: one agent process.
//!
//! It rebuilds its agent from the scenario, connects its end of the run's transport
//! ([`crate::process::connect`]), runs the shared
//! round loop and writes its outcome as `result-I.json` into the run directory. It always
//! returns (never `process::exit`), so iceoryx2's `Drop`s release its shared memory.

use crate::process::connect::connect;
use crate::process::member_error::MemberError;
use crate::process::scenario::{Scenario, ScenarioWorkload};
use crate::workload::surveillance::{EpisodeRecord, run_surveillance_agent};
use admm_ta_transport::endpoint::AgentEndpoint;
use admm_ta_transport::exchange::ExchangeError;
use admm_ta_transport::exchange::round_loop::{AgentOutcome, run_agent};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// What an agent process leaves for the launcher.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AgentReport {
    pub outcome: AgentOutcome,
    /// When the agent had all its neighbours connected (ns since the Unix epoch).
    pub connected_unix_ns: u128,
    /// When the agent started (ns since the Unix epoch).
    pub started_unix_ns: u128,
    /// Its episodes, in a repeated-assignment run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub episodes: Vec<EpisodeRecord>,
    /// An independently started agent: the digest of its team
    /// ([`crate::process::team_digest::TeamDigest`], hex), so that `collect` refuses the
    /// result of another team written to the same directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub team: Option<String>,
}

/// Path of agent `index`'s result file in the run directory.
pub fn result_path(run_dir: &Path, index: usize) -> PathBuf {
    run_dir.join(format!("result-{index}.json"))
}

/// Path of agent `index`'s log (its standard error) in the run directory.
pub fn log_path(run_dir: &Path, index: usize) -> PathBuf {
    run_dir.join(format!("agent-{index}.log"))
}

fn unix_ns() -> u128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos())
}

/// After a failed start-up: a stop request on the team's board (a termination signal to
/// another process of the team) is this process's too.
fn record_stop(scenario: &Scenario) {
    if admm_ta_transport::signals::received().is_none()
        && let Ok(board) =
            admm_ta_transport::board::Board::open(&scenario.board_shm, scenario.robots)
        && let Some((signal, _)) = board.stop_requested()
    {
        admm_ta_transport::signals::record(signal);
    }
}

/// Runs agent `index` of run `run_id` (started by the launcher) from the scenario file the
/// launcher wrote, whose SHA-256 is `scenario_digest`; errors are one line for the log.
pub fn run(
    run_id: &str,
    index: usize,
    scenario_path: &Path,
    scenario_digest: &str,
) -> Result<(), MemberError> {
    let _signals = admm_ta_transport::signals::install();
    let _span = tracing::info_span!("agent", run = %run_id, agent = index).entered();
    // Not a symlink, ours, mode 0600, and what the launcher wrote (its digest).
    let bytes = crate::process::private_dir::read_verified(scenario_path, scenario_digest)
        .map_err(MemberError::refused)?;
    let scenario = Scenario::parse(&bytes, scenario_path, run_id).map_err(MemberError::refused)?;
    let run_dir = scenario_path.parent().unwrap_or(Path::new("."));
    run_scenario(
        &scenario,
        index,
        run_dir,
        &result_path(run_dir, index),
        true,
        None,
    )
    .map(|_| ())
}

/// Runs agent `index` of `scenario` and writes its report to `result` (atomically);
/// `supervised`: a launcher started it (it stops if the launcher dies). `run_dir` holds the
/// uds sockets; `team`: the team's digest an independently started agent records.
pub fn run_scenario(
    scenario: &Scenario,
    index: usize,
    run_dir: &Path,
    result: &Path,
    supervised: bool,
    team: Option<String>,
) -> Result<AgentReport, MemberError> {
    let started_unix_ns = unix_ns();
    let started = Instant::now();
    let graph = scenario.graph().map_err(MemberError::refused)?;
    let plan = scenario.plan(index).map_err(MemberError::refused)?;
    let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
    tracing::debug!(
        transport = scenario.transport.name(),
        neighbours = ?graph.neighbours(index),
        "scenario read, connecting"
    );
    let mut endpoint = connect(scenario, &graph, index, run_dir, supervised, deadline)
        .inspect_err(|e| {
            tracing::warn!(error = %e.text(), "could not connect");
            record_stop(scenario)
        })?;
    let connected_unix_ns = unix_ns();
    tracing::debug!(
        ms = started.elapsed().as_secs_f64() * 1e3,
        "connected to every neighbour"
    );
    let ran = match &scenario.workload {
        ScenarioWorkload::Episodes(settings) => {
            let mut agent = settings.agent(index, &graph);
            run_surveillance_agent(&mut agent, endpoint.exchange(), &plan, settings)
                .map(|(records, outcome)| (outcome, records))
        }
        _ => {
            let mut agent = scenario
                .workload_agent(index)
                .map_err(MemberError::refused)?;
            run_agent(&mut *agent, endpoint.exchange(), &plan).map(|o| (o, Vec::new()))
        }
    };
    let (outcome, episodes) = ran.map_err(|e| {
        tracing::warn!(error = %e, "stopped");
        let board =
            admm_ta_transport::board::Board::open(&scenario.board_shm, scenario.robots).ok();
        tell_the_team(&*endpoint, board.as_ref(), index, &e);
        MemberError::failed(e)
    })?;
    // Finished, not dead: a neighbour that scans the run's nodes while this one's node goes
    // away must not take it for a failure (the board of a team with one; Zenoh teams have
    // none).
    if let Ok(board) = admm_ta_transport::board::Board::open(&scenario.board_shm, scenario.robots) {
        board.set_finished(index);
    }
    // Release the ports before reporting: once the launcher sees the result it may clean up.
    drop(endpoint);
    tracing::info!(
        rounds = outcome.rounds,
        task = outcome.task,
        certified_round = outcome.certified_round,
        converged = outcome.converged,
        "finished"
    );
    let report = AgentReport {
        outcome,
        connected_unix_ns,
        started_unix_ns,
        episodes,
        team,
    };
    let partial = result.with_extension("json.partial");
    let text = serde_json::to_string(&report).expect("a report serialises");
    std::fs::write(&partial, text)
        .and_then(|()| std::fs::rename(&partial, result))
        .map_err(|source| {
            MemberError::failed(CannotWrite {
                path: result.to_path_buf(),
                source,
            })
        })?;
    Ok(report)
}

/// After agent `index`'s run ended with `error`: a termination signal to this process stops
/// the rest of the team too (nobody failed): the stop request goes on the `board` first (the
/// first request wins), where the other agents and a launcher read who got it, then to
/// agents that do not read the board; the process then ends as if it had got the signal
/// itself, whoever got it. Any other error points the others at the agent to blame.
pub(crate) fn tell_the_team(
    endpoint: &dyn AgentEndpoint,
    board: Option<&admm_ta_transport::board::Board>,
    index: usize,
    error: &ExchangeError,
) {
    if let ExchangeError::Stopped { signal, .. } = *error {
        if admm_ta_transport::signals::received().is_some() {
            if let Some(board) = board {
                let _ = board.request_stop(signal, Some(index));
            }
            endpoint.announce_stop(signal);
        }
        admm_ta_transport::signals::record(signal);
    } else {
        endpoint.blame_for(error);
    }
}

/// The agent's result could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {}", path.display())]
struct CannotWrite {
    path: std::path::PathBuf,
    #[source]
    source: std::io::Error,
}
