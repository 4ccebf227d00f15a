//! What a team's agents are built from and what they compute.
//!
//! * [`plan`]: a solve's agents — ρ, γ, tolerance, perturbation and settings, computed once;
//! * [`surveillance`]: the surveillance robots' repeated assignments.
//!
//! [`Workload`] names what a team computes, for the team runner ([`crate::runner`]) and the
//! scenario of agent processes alike.

pub mod plan;
pub mod surveillance;

use crate::workload::plan::Plan;
use crate::workload::surveillance::EpisodeSettings;
use admm_ta_agents::methods::probe::ProbeStep;
use admm_ta_transport::exchange::round_loop::AgentStop;

/// What a team's agents compute.
#[derive(Clone, Copy)]
pub enum Workload<'a> {
    /// A method's agents solving a problem: built from `plan`, each stopping by `stop`
    /// within `max_rounds` rounds.
    Solve {
        plan: &'a Plan<'a>,
        stop: &'a AgentStop,
        max_rounds: u64,
    },
    /// Latency probes ([`admm_ta_agents::methods::probe::ProbeAgent`]): `payload_len` values per
    /// message, a step of known cost, `rounds` rounds (warm-up included).
    Probe {
        payload_len: usize,
        step: ProbeStep,
        rounds: u64,
    },
    /// Surveillance episodes, each within `max_rounds` rounds.
    Episodes {
        settings: &'a EpisodeSettings,
        max_rounds: u64,
    },
}

impl Workload<'_> {
    /// Agents of the team, if the workload says (a probe team is as large as its graph).
    pub fn robots(&self) -> Option<usize> {
        match self {
            Self::Solve { plan, .. } => Some(plan.agents.problem.robots()),
            Self::Probe { .. } => None,
            Self::Episodes { settings, .. } => Some(settings.model.robots),
        }
    }
}
