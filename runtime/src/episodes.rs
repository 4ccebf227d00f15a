//! Repeated assignments: one team of agents, alive across many episodes (the persistent
//! surveillance case study, [`admm_ta_agents::problem::surveillance`]).
//!
//! Every episode each robot computes its own cost row from its own state, the team runs
//! primal consensus ADMM to the decentralized certified stop, and each robot moves to its
//! station, updating its position and battery. The agents are not restarted: after the
//! stop (all robots stop at the same round), the next episode goes on from that round with
//! the new costs, **warm-started** from the current iterates and multipliers
//! ([`admm_ta_agents::method::agent::MethodAgent::set_costs`]) and a fresh stop rule. Threads and
//! processes (one per robot for the whole run) run the same agent function on the team
//! runner ([`crate::runner`]),
//! [`run_surveillance_agent`](crate::workload::episode::run_surveillance_agent).

use crate::latency::LatencySummary;
use crate::options::run::RunOptions;
use crate::runner::{RunError, run_team};
use crate::transport::Transport;
use crate::workload::Workload;
use crate::workload::episode::{EpisodeRecord, EpisodeSettings};
use admm_ta_topologies::Graph;
use std::time::{Duration, Instant};

/// How a surveillance team runs.
#[derive(Debug, Clone)]
pub struct EpisodeRunConfig {
    /// Round limit of each episode.
    pub max_rounds: u64,
    /// The transport (threads or processes, one per robot for the whole run), waiting,
    /// timeouts and agent program.
    pub options: RunOptions,
}

impl Default for EpisodeRunConfig {
    /// 5000 rounds per episode, one ipc process per robot.
    fn default() -> Self {
        Self {
            max_rounds: 5000,
            options: RunOptions::builder()
                .transport(Transport::Ipc)
                .build()
                .expect("ipc runs with the default settings"),
        }
    }
}

/// What a surveillance team did.
#[derive(Debug, Clone)]
pub struct EpisodeRun {
    /// Per robot, its episodes in order.
    pub records: Vec<Vec<EpisodeRecord>>,
    pub latency: LatencySummary,
    pub startup: Option<Duration>,
    pub wall: Duration,
    /// Every agent's round stamps over all episodes (`options.timeline()` on).
    pub timeline: Vec<Vec<crate::timeline::RoundStamp>>,
}

/// Runs `settings.episodes` episodes with one agent per robot on `graph`, alive for the whole
/// run.
pub fn run_episodes(
    settings: &EpisodeSettings,
    graph: &Graph,
    config: &EpisodeRunConfig,
) -> Result<EpisodeRun, RunError> {
    let started = Instant::now();
    let team = run_team(
        Workload::Episodes {
            settings,
            max_rounds: config.max_rounds,
        },
        graph,
        &config.options,
    )?;
    Ok(EpisodeRun {
        records: team.episodes,
        latency: team.latency.summary(),
        startup: team.startup,
        wall: started.elapsed(),
        timeline: team.outcomes.into_iter().map(|o| o.timeline).collect(),
    })
}
