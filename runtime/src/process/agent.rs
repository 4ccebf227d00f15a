//! The body of `admm-ta agent --run ID --index I --scenario FILE`: one agent process.
//!
//! It rebuilds its agent from the scenario, connects its iceoryx2 ports, runs the shared
//! round loop and writes its outcome as `result-I.json` into the run directory. It always
//! returns (never `process::exit`), so iceoryx2's `Drop`s release its shared memory.

use crate::exchange::round_loop::{AgentOutcome, run_agent};
use crate::exchange::{Exchange, ExchangeError};
use crate::ipc::exchange::IpcExchange;
use crate::ipc::nodes::run_config;
use crate::process::scenario::{ProcessTransport, Scenario, Workload};
use crate::uds::UdsExchange;
use crate::workload::episode::{EpisodeRecord, run_surveillance_agent};
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

/// Runs agent `index` of run `run_id` (started by the launcher); errors are one line for
/// the log.
pub fn run(run_id: &str, index: usize, scenario_path: &Path) -> Result<(), String> {
    let scenario = Scenario::read(scenario_path, run_id).map_err(|e| e.to_string())?;
    let run_dir = scenario_path.parent().unwrap_or(Path::new("."));
    run_scenario(
        &scenario,
        index,
        run_dir,
        &result_path(run_dir, index),
        true,
    )
    .map(|_| ())
}

/// This agent's end of the transport.
enum Endpoint {
    // Boxed: both are large, and the enum is built once.
    Ipc(Box<IpcExchange>),
    Uds(Box<UdsExchange>),
    #[cfg(feature = "zenoh")]
    Zenoh(Box<crate::zenoh_net::exchange::ZenohExchange>),
}

impl Endpoint {
    fn exchange(&mut self) -> &mut dyn Exchange {
        match self {
            Self::Ipc(e) => e.as_mut(),
            Self::Uds(e) => e.as_mut(),
            #[cfg(feature = "zenoh")]
            Self::Zenoh(e) => e.as_mut(),
        }
    }

    /// Points the launcher and the other agents at the agent that caused `error`.
    fn blame_for(&self, error: &ExchangeError) {
        match self {
            Self::Ipc(exchange) => {
                let culprit = match error {
                    // Blocked neighbours time out too: blame the agent everybody waits for.
                    ExchangeError::Timeout { .. } => Some(exchange.laggard()),
                    e => culprit(e),
                };
                if let Some(culprit) = culprit {
                    exchange.blame(culprit);
                }
            }
            Self::Uds(_) => {}
            // No launcher sees every host: whoever fails first tells the others.
            #[cfg(feature = "zenoh")]
            Self::Zenoh(exchange) => {
                let culprit = match error {
                    ExchangeError::Aborted { .. } => return,
                    // Possibly seen only by us (its token vanished): pass it on.
                    ExchangeError::PeerFailed { failed, .. } => Some(*failed),
                    ExchangeError::Timeout { round, .. } => exchange.first_missing(*round),
                    e => culprit(e),
                };
                exchange.blame(culprit.unwrap_or(error.agent()));
            }
        }
    }
}

/// Runs agent `index` of `scenario` and writes its report to `result` (atomically);
/// `supervised`: a launcher started it (it stops if the launcher dies). `run_dir` holds the
/// uds sockets.
pub fn run_scenario(
    scenario: &Scenario,
    index: usize,
    run_dir: &Path,
    result: &Path,
    supervised: bool,
) -> Result<AgentReport, String> {
    let started_unix_ns = unix_ns();
    let started = Instant::now();
    let graph = scenario.graph().map_err(|e| e.to_string())?;
    let plan = scenario.plan(index).map_err(|e| e.to_string())?;
    let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
    let mut endpoint = match scenario.transport {
        ProcessTransport::Iceoryx2 => {
            let config = run_config(&scenario.iceoryx_prefix, &scenario.iceoryx_root)?;
            let fault = crate::fault::fault_for(index)?;
            let mut exchange = IpcExchange::connect(
                &scenario.endpoint(&graph, index, supervised),
                &config,
                deadline,
            )
            .map_err(|e| e.to_string())?;
            exchange.inject(fault);
            Endpoint::Ipc(Box::new(exchange))
        }
        ProcessTransport::Uds => Endpoint::Uds(Box::new(UdsExchange::connect(
            &scenario.uds_endpoint(&graph, index, run_dir),
            deadline,
        )?)),
        #[cfg(feature = "zenoh")]
        ProcessTransport::Zenoh => {
            let endpoint = scenario
                .zenoh_endpoint(&graph, index, supervised)
                .map_err(|e| e.to_string())?;
            let mut exchange =
                crate::zenoh_net::exchange::ZenohExchange::connect(&endpoint, deadline)
                    .map_err(|e| e.to_string())?;
            exchange.inject(crate::fault::fault_for(index)?);
            Endpoint::Zenoh(Box::new(exchange))
        }
        #[cfg(not(feature = "zenoh"))]
        ProcessTransport::Zenoh => return Err(crate::zenoh_net::not_built()),
    };
    let connected_unix_ns = unix_ns();
    let ran = match &scenario.workload {
        Workload::Episodes(settings) => {
            let mut agent = settings.agent(index, graph.degree(index));
            run_surveillance_agent(&mut agent, endpoint.exchange(), &plan, settings)
                .map(|(records, outcome)| (outcome, records))
        }
        _ => {
            let mut agent = scenario.workload_agent(index).map_err(|e| e.to_string())?;
            run_agent(&mut *agent, endpoint.exchange(), &plan).map(|o| (o, Vec::new()))
        }
    };
    let (outcome, episodes) = ran.map_err(|e| {
        endpoint.blame_for(&e);
        e.to_string()
    })?;
    // Release the ports before reporting: once the launcher sees the result it may clean up.
    drop(endpoint);
    let report = AgentReport {
        outcome,
        connected_unix_ns,
        started_unix_ns,
        episodes,
    };
    let partial = result.with_extension("json.partial");
    let text = serde_json::to_string(&report).map_err(|e| e.to_string())?;
    std::fs::write(&partial, text)
        .and_then(|()| std::fs::rename(&partial, result))
        .map_err(|e| format!("cannot write {}: {e}", result.display()))?;
    Ok(report)
}
