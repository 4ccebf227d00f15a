//! The central stop rules of a lockstep run: they read the whole team's state, which only
//! the simulation has in one place (`--stop certified`, `oracle`, `agreement`; sim only).

use crate::sim::{LockstepSim, RoundView, SimOutcome};
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::method::MethodAgent;
use admm_ta_agents::stopping::AgreementStreak;

/// Rounds after which an agreement is first certified, and the spacing of later checks
/// (each check is one `m × n` assignment problem per robot).
const CERTIFY_AFTER: usize = 3;
const CERTIFY_EVERY: usize = 5;

/// Steps until the robots agree on one assignment whose certificate slacks sum to at most
/// `tolerance` (see [`admm_ta_agents::primal::PrimalAgent::certificate_slack`]), or
/// `max_rounds`.
pub(crate) fn run_until_certified(
    sim: &mut LockstepSim<MethodAgent>,
    max_rounds: usize,
    tolerance: f64,
    observer: &mut dyn FnMut(&RoundView<'_>),
) -> SimOutcome {
    // Agreement on one feasible assignment; near-integrality is not needed here.
    let mut streak = AgreementStreak::default();
    sim.run_until(max_rounds, observer, |sim| {
        let agreed_for = streak.observe(sim.view().reports, f64::MAX);
        agreed_for >= CERTIFY_AFTER
            && (agreed_for - CERTIFY_AFTER).is_multiple_of(CERTIFY_EVERY)
            && sim
                .agents()
                .iter()
                .map(ConsensusAgent::certificate_slack)
                .sum::<f64>()
                <= tolerance
    })
}
