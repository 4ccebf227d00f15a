//! One agent type that runs any team method, so that runners and transports handle every
//! method the same way: the method's own agent, built by its team's
//! [`crate::method::team::TeamBuilder`], behind one dynamic call per step.
//!
//! ```
//! use admm_ta_agents::agent::ConsensusAgent;
//! use admm_ta_agents::method::agent::MethodAgent;
//! use admm_ta_agents::method::settings::GivenSettings;
//! use admm_ta_agents::method::team::{AgentInit, TeamContext, TeamParams};
//! use admm_ta_agents::methods::Method;
//! use admm_ta_agents::problem::{AssignmentCase, CaseChoice, CostMatrix, TaskAssignmentProblem};
//! let costs = CostMatrix::new(2, 2, vec![0.2, 0.7, 0.6, 0.1]).unwrap();
//! let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
//! let graph = admm_ta_topologies::generate::complete(2).unwrap();
//! let setup = Method::Dual.setup(&GivenSettings::default()).unwrap().expect("a team method");
//! let params = TeamParams { rho: 0.5, diameter: 1, tolerance: 1e-9 };
//! let team = setup.team(TeamContext { problem: &problem, graph: &graph, params });
//! let init = AgentInit { index: 0, costs: vec![0.2, 0.7], robots: 2, case: AssignmentCase::One, degree: 1 };
//! let agent = MethodAgent::new(team.agent(init));
//! // 2 task prices, the certificate (2 potentials, 2 packed claims) and Case 1's finish
//! // (2 packed tags, its window, alarm and bound).
//! assert_eq!(agent.payload_len(), 9);
//! ```

use crate::agent::{AgentAlgorithm, ConsensusAgent, Inbox, StepReport};
use crate::methods::rho::RhoSchedule;

/// An agent of any team method, optionally following a ρ schedule (applied by the agent
/// itself before each step, so every transport changes ρ at the same round).
pub struct MethodAgent {
    algorithm: Box<dyn AgentAlgorithm>,
    schedule: Option<RhoSchedule>,
    steps: u64,
}

impl MethodAgent {
    /// The agent `algorithm` (built by its team's builder).
    pub fn new(algorithm: Box<dyn AgentAlgorithm>) -> Self {
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
    /// current iterates or (`warm = false`) from zero; the methods that support it.
    pub fn set_costs(
        &mut self,
        costs: &[f64],
        warm: bool,
    ) -> Result<(), crate::agent::NewCostsError> {
        self.algorithm.set_costs(costs, warm)?;
        if !warm {
            // A cold start follows its ρ schedule from the beginning again.
            self.steps = 0;
        }
        Ok(())
    }
}

impl ConsensusAgent for MethodAgent {
    fn payload_len(&self) -> usize {
        self.algorithm.payload_len()
    }
    fn write_initial_payload(&self, out: &mut [f64]) {
        self.algorithm.write_initial_payload(out)
    }
    fn check_payload(&self, payload: &[f64]) -> Result<(), crate::agent::PayloadError> {
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
