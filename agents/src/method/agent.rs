//! One agent type that runs any team method, so that runners and transports handle every
//! method the same way: the method's own agent, built by its registration in
//! [`crate::methods`], behind one dynamic call per step.
//!
//! ```
//! use admm_ta_agents::agent::ConsensusAgent;
//! use admm_ta_agents::methods::{AgentMethod, AgentSettings};
//! use admm_ta_agents::method::agent::MethodAgent;
//! use admm_ta_agents::problem::AssignmentCase;
//! let settings = AgentSettings::new(AgentMethod::Dual, 0.5, 1, 1e-9);
//! let agent = MethodAgent::new(0, vec![0.2, 0.7], 2, AssignmentCase::One, 1, settings);
//! assert_eq!(agent.payload_len(), 4); // ν: 2 robot rows + 2 task rows
//! ```

use crate::agent::{AgentAlgorithm, ConsensusAgent, Inbox, StepReport};
use crate::methods::primal::agent::PrimalAgent;
use crate::methods::primal::readout_filter::ReadoutFilter;
use crate::methods::rho::RhoSchedule;
use crate::methods::{AgentInit, AgentSettings};
use crate::problem::AssignmentCase;
use std::sync::Arc;

/// An agent of any team method, optionally following a ρ schedule (applied by the agent
/// itself before each step, so every transport changes ρ at the same round).
pub struct MethodAgent {
    algorithm: Box<dyn AgentAlgorithm>,
    schedule: Option<RhoSchedule>,
    steps: u64,
}

impl MethodAgent {
    /// Robot `index` of `robots` with its own costs, `degree = |N(i)|`, of the team method
    /// `settings.method`.
    pub fn new(
        index: usize,
        costs: Vec<f64>,
        robots: usize,
        case: AssignmentCase,
        degree: usize,
        settings: AgentSettings,
    ) -> Self {
        let algorithm = (settings.method.info().build)(AgentInit {
            index,
            costs,
            robots,
            case,
            degree,
            settings: &settings,
        });
        Self {
            algorithm,
            schedule: None,
            steps: 0,
        }
    }

    /// Follow `schedule` (from the next step on, counted from the first step).
    pub fn with_schedule(mut self, schedule: Option<RhoSchedule>) -> Self {
        self.schedule = schedule;
        self
    }

    /// Changes ρ from the next step on; every robot must change it at the same round
    /// (no effect on methods without a ρ).
    pub fn set_rho(&mut self, rho: f64) {
        self.algorithm.set_rho(rho);
    }

    /// New own costs for the next episode of a repeated assignment, warm-started from the
    /// current iterates or (`warm = false`) from zero; primal consensus ADMM only.
    pub fn set_costs(&mut self, costs: &[f64], warm: bool) -> Result<(), String> {
        self.algorithm.set_costs(costs, warm)
    }

    /// Gives the fast primal variant's agent the team's readout filter (no effect on other
    /// methods, on the paper's variant or with `None`).
    pub fn with_readout_filter(mut self, filter: Option<Arc<ReadoutFilter>>) -> Self {
        if let Some(filter) = filter {
            let any: &mut dyn std::any::Any = self.algorithm.as_mut();
            if let Some(primal) = any.downcast_mut::<PrimalAgent>() {
                primal.set_readout_filter(filter);
            }
        }
        self
    }

    /// The primal agent inside, if this is one.
    pub fn as_primal(&self) -> Option<&PrimalAgent> {
        let any: &dyn std::any::Any = self.algorithm.as_ref();
        any.downcast_ref()
    }
}

impl ConsensusAgent for MethodAgent {
    fn payload_len(&self) -> usize {
        self.algorithm.payload_len()
    }
    fn write_initial_payload(&self, out: &mut [f64]) {
        self.algorithm.write_initial_payload(out)
    }
    fn check_payload(&self, payload: &[f64]) -> Result<(), String> {
        self.algorithm.check_payload(payload)
    }
    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        if let Some(schedule) = self.schedule {
            self.algorithm.set_rho(schedule.rho(self.steps));
        }
        self.steps += 1;
        self.algorithm.step(inbox, out)
    }
    fn decide(&self) -> usize {
        self.algorithm.decide()
    }
    fn rounded_task(&self) -> usize {
        self.algorithm.rounded_task()
    }
    fn certificate_slack(&self) -> f64 {
        self.algorithm.certificate_slack()
    }
    fn own_column(&self) -> &[f64] {
        self.algorithm.own_column()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::AgentMethod;

    #[test]
    fn only_the_primal_agent_is_a_primal_agent_and_takes_new_costs() {
        for method in AgentMethod::ALL {
            let settings = AgentSettings::new(method, 0.5, 1, 1e-9);
            let mut agent =
                MethodAgent::new(0, vec![0.2, 0.7], 2, AssignmentCase::One, 1, settings);
            assert_eq!(agent.payload_len(), method.payload_len(2, 2));
            let primal = method == AgentMethod::Primal;
            assert_eq!(agent.as_primal().is_some(), primal, "{method:?}");
            assert_eq!(agent.set_costs(&[0.1, 0.3], true).is_ok(), primal);
        }
    }
}
