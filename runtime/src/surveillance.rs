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
//! [`run_surveillance_agent`](crate::workload::surveillance::run_surveillance_agent).
//!
//! **Why this is not a standing team fed by a surveillance row source** ([`crate::standing`]
//! runs episodes too): a standing episode is another computation, and each difference
//! changes the rounds per episode, which is what this case study measures (warm against
//! cold, `admm-ta experiment surveillance`). A standing episode opens with an agreement
//! flood (the team's scale, missing rows, leaves and joins: diameter-many extra rounds);
//! it normalises every row onto the agreed scale of that episode and perturbs it with that
//! scale's tie-breaking ε, where surveillance solves the mission's own costs with the
//! mission's fixed tie-break; its ρ and stop tolerance follow the normalised costs of each
//! episode, where surveillance fixes ρ once from the first episode's costs (and its cold
//! start comparison uses that ρ); and it warm-starts only when no cost moved by more than a
//! tenth of the range, where surveillance always warm-starts. What the two share is below
//! the episode: the agent's new costs with or without a warm start
//! (`MethodAgent::set_costs`), the round loop and the decentralized certified stop.

use crate::options::run::RunOptions;
use crate::runner::{RunError, run_team};
use crate::workload::Workload;
use crate::workload::surveillance::{EpisodeRecord, EpisodeSettings};
use admm_ta_topologies::Graph;
use admm_ta_transport::Transport;
use admm_ta_transport::latency::LatencySummary;
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
    pub timeline: Vec<Vec<admm_ta_transport::timeline::RoundStamp>>,
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
