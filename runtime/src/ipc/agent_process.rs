//! The body of `admm-ta agent --run ID --index I --scenario FILE`: one agent process.
//!
//! It rebuilds its agent from the scenario, connects its iceoryx2 ports, runs the shared
//! round loop and writes its outcome as `result-I.json` into the run directory. It always
//! returns (never `process::exit`), so iceoryx2's `Drop`s release its shared memory.

use crate::exchange::{AgentOutcome, ExchangeError, run_agent};
use crate::ipc::scenario::{ProcessTransport, Scenario};
use crate::ipc::transport::{IpcExchange, run_config};
use crate::uds::UdsExchange;
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
}

/// Path of agent `index`'s result file in the run directory.
pub fn result_path(run_dir: &Path, index: usize) -> PathBuf {
    run_dir.join(format!("result-{index}.json"))
}

/// Path of agent `index`'s log (its standard error) in the run directory.
pub fn log_path(run_dir: &Path, index: usize) -> PathBuf {
    run_dir.join(format!("agent-{index}.log"))
}

/// The neighbour an exchange error is the fault of, if any.
fn culprit(error: &ExchangeError) -> Option<usize> {
    match error {
        ExchangeError::BadPayload { neighbour, .. }
        | ExchangeError::WrongLength { neighbour, .. }
        | ExchangeError::OutOfOrder { neighbour, .. }
        | ExchangeError::WrongSender { neighbour, .. } => Some(*neighbour),
        _ => None,
    }
}

fn unix_ns() -> u128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos())
}

/// Runs agent `index` of run `run_id`; errors are one line for the log.
pub fn run(run_id: &str, index: usize, scenario_path: &Path) -> Result<(), String> {
    let started_unix_ns = unix_ns();
    let started = Instant::now();
    let scenario = Scenario::read(scenario_path, run_id).map_err(|e| e.to_string())?;
    let graph = scenario.graph().map_err(|e| e.to_string())?;
    let mut agent = scenario.workload_agent(index).map_err(|e| e.to_string())?;
    let plan = scenario.plan(index).map_err(|e| e.to_string())?;
    let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
    let run_dir = scenario_path.parent().unwrap_or(Path::new("."));
    let (outcome, connected_unix_ns) = match scenario.transport {
        ProcessTransport::Iceoryx2 => {
            let config = run_config(&scenario.iceoryx_prefix, &scenario.iceoryx_root)?;
            let fault = crate::ipc::fault::fault_for(index)?;
            let mut exchange =
                IpcExchange::connect(&scenario.endpoint(&graph, index), &config, deadline)
                    .map_err(|e| e.to_string())?;
            exchange.inject(fault);
            let connected_unix_ns = unix_ns();
            let outcome = run_agent(&mut *agent, &mut exchange, &plan).map_err(|e| {
                // Point the launcher and the other agents at the agent that caused it.
                let culprit = match &e {
                    // Blocked neighbours time out too: blame the agent everybody waits for.
                    ExchangeError::Timeout { .. } => Some(exchange.laggard()),
                    e => culprit(e),
                };
                if let Some(culprit) = culprit {
                    exchange.blame(culprit);
                }
                e.to_string()
            })?;
            (outcome, connected_unix_ns)
        }
        ProcessTransport::Uds => {
            let mut exchange =
                UdsExchange::connect(&scenario.uds_endpoint(&graph, index, run_dir), deadline)?;
            let connected_unix_ns = unix_ns();
            let outcome =
                run_agent(&mut *agent, &mut exchange, &plan).map_err(|e| e.to_string())?;
            (outcome, connected_unix_ns)
        }
    };
    // The ports were released when the exchange went out of scope: once the launcher sees
    // the result it may clean up.
    let report = AgentReport {
        outcome,
        connected_unix_ns,
        started_unix_ns,
    };
    let path = result_path(run_dir, index);
    let partial = path.with_extension("json.partial");
    let text = serde_json::to_string(&report).map_err(|e| e.to_string())?;
    std::fs::write(&partial, text)
        .and_then(|()| std::fs::rename(&partial, &path))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}
