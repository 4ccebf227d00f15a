//! What a solve watches of a lockstep run: the oracle tracer of a checked solve, and the
//! central stop rules (`--stop certified`, `oracle`, `agreement`), which read the whole
//! team's state that only the simulation has in one place.

use crate::options::{SolveOptions, StopRule};
use crate::runner::LockstepWatch;
use crate::solve::trace::{Affine, Tracer, decides_by_readout, relaxed_objective, within_0_1pct};
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::oracle::OptimalAssignment;
use admm_ta_agents::certify::stopping::{AgreementStop, AgreementStreak, TeamStopRule};
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_transport::sim::process::{LockstepSim, RoundView};

/// Rounds after which an agreement is first certified, and the spacing of later checks
/// (each check is one `m × n` assignment problem per robot).
const CERTIFY_AFTER: usize = 3;
const CERTIFY_EVERY: usize = 5;

/// A stop rule that reads the whole team.
enum Central<'p> {
    /// The agents' own rule decides (local, max-iters).
    None,
    Agreement(AgreementStop),
    /// The robots agree on one assignment whose certificate slacks sum to at most
    /// `tolerance` (see [`admm_ta_agents::methods::primal::agent::PrimalAgent::certificate_slack`]).
    Certified {
        streak: AgreementStreak,
        tolerance: f64,
    },
    /// The paper's criterion, with the centralized optimum (experiments only); on the
    /// robots' decisions when they decide by readout (the fast primal variant, whose
    /// relaxed columns stay near the polytope's centre).
    Oracle {
        problem: &'p TaskAssignmentProblem,
        affine: Affine,
        optimal_cost: f64,
        decisions: Option<Vec<usize>>,
    },
}

/// A solve's watch over a lockstep run.
pub(crate) struct SolveWatch<'p> {
    /// Follows the run against the optimum (checked solves).
    pub(crate) tracer: Option<Tracer<'p>>,
    central: Central<'p>,
}

impl<'p> SolveWatch<'p> {
    /// The watch of a solve of `problem` with `options`; `tolerance` is the plan's, `optimum`
    /// the centralized one (known when checking or stopping by the oracle).
    pub(crate) fn new(
        problem: &'p TaskAssignmentProblem,
        options: &SolveOptions,
        tolerance: f64,
        tracer: Option<Tracer<'p>>,
        optimum: Option<&OptimalAssignment>,
        affine: Affine,
    ) -> Self {
        let central = match options.stop() {
            StopRule::Agreement => Central::Agreement(AgreementStop::new(options.stop_rounds())),
            StopRule::Certified => Central::Certified {
                // Agreement on one feasible assignment; near-integrality is not needed here.
                streak: AgreementStreak::default(),
                tolerance,
            },
            StopRule::Oracle => match optimum {
                Some(optimum) => Central::Oracle {
                    problem,
                    affine,
                    optimal_cost: affine.apply(optimum.cost),
                    decisions: decides_by_readout(options).then(|| vec![0; problem.robots()]),
                },
                None => Central::None,
            },
            StopRule::Local | StopRule::MaxIters => Central::None,
        };
        Self { tracer, central }
    }
}

impl LockstepWatch for SolveWatch<'_> {
    fn observe(&mut self, view: &RoundView<'_>) {
        if let Some(t) = self.tracer.as_mut() {
            t.observe(view);
        }
    }

    fn stop(&mut self, sim: &LockstepSim<MethodAgent>) -> bool {
        match &mut self.central {
            Central::None => false,
            Central::Agreement(rule) => rule.should_stop(sim.view().reports),
            Central::Certified { streak, tolerance } => {
                let agreed_for = streak.observe(sim.view().reports, f64::MAX);
                agreed_for >= CERTIFY_AFTER
                    && (agreed_for - CERTIFY_AFTER).is_multiple_of(CERTIFY_EVERY)
                    && sim
                        .agents()
                        .iter()
                        .map(ConsensusAgent::certificate_slack)
                        .sum::<f64>()
                        <= *tolerance
            }
            Central::Oracle {
                problem,
                affine,
                optimal_cost,
                decisions: None,
            } => within_0_1pct(
                affine.apply(relaxed_objective(problem, &sim.view())),
                *optimal_cost,
            ),
            Central::Oracle {
                problem,
                affine,
                optimal_cost,
                decisions: Some(decisions),
            } => {
                for (d, agent) in decisions.iter_mut().zip(sim.agents()) {
                    *d = agent.rounded_task();
                }
                problem.is_feasible(decisions)
                    && problem
                        .cost_of(decisions)
                        .is_ok_and(|c| within_0_1pct(affine.apply(c), *optimal_cost))
            }
        }
    }
}
