//! Stop rules: the user's choice ([`StopRule`]) and the rules over the team's step reports.
//!
//! [`AgreementStop`] stops once, for `rounds` consecutive rounds, every robot's iterate is
//! near-integral (every entry within the integrality tolerance of a feasible assignment) and
//! all robots round to the *same* assignment. Near-integrality is what keeps it from stopping on a
//! fractional face where robots merely agree (docs/notes.md, note 12: residual-only rules stopped
//! at wrong assignments; adding near-integrality gave none). It reads the whole team's
//! reports, so it is the reference rule of the lockstep simulation; a neighbour-only
//! version with an agreement protocol belongs to the runtime's distributed transports.

use crate::agent::StepReport;
use serde::{Deserialize, Serialize};

/// When a run ends: the choice of `--stop` (which methods honour which rule is declared by
/// each method's entry in [`crate::methods`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum StopRule {
    /// All robots agree on one near-integral assignment for some rounds (default 10).
    Agreement,
    /// All robots round to the same assignment and their optimality-certificate slacks
    /// ([`crate::methods::primal::agent::PrimalAgent::certificate_slack`]) sum to at most `1e-9 ·` its cost
    /// scale: the assignment is then provably optimal to that tolerance. Checked centrally
    /// (sim only).
    Certified,
    /// The same certificate, decentralized: each robot checks its own slack and agreement
    /// with its neighbours, and a header protocol makes all robots stop at the same round
    /// (see [`crate::certify::local_stop`]); costs about a graph diameter of extra rounds. Works on
    /// every transport (default).
    #[default]
    Local,
    /// Run to the iteration limit.
    MaxIters,
    /// The paper's criterion, for experiments only: stop at the first round whose relaxed
    /// objective (the robots' own columns) is within 0.1% of the centralized optimum. It
    /// needs the optimum, which no robot has (sim only).
    Oracle,
}

impl StopRule {
    /// Every rule, in the order of the command line's help.
    pub const ALL: [StopRule; 5] = [
        Self::Local,
        Self::Agreement,
        Self::Certified,
        Self::MaxIters,
        Self::Oracle,
    ];

    /// Rules that read the whole team's state, which only a lockstep run has in one place.
    pub fn is_central(self) -> bool {
        matches!(self, Self::Agreement | Self::Certified | Self::Oracle)
    }

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Agreement => "agreement",
            Self::Certified => "certified",
            Self::Local => "local",
            Self::MaxIters => "max-iters",
            Self::Oracle => "oracle",
        }
    }
}

#[cfg(feature = "clap")]
crate::clap_value_enum!(StopRule);

/// Something that decides, round by round, whether the team is done.
pub trait TeamStopRule {
    /// Called after every round with every robot's report; `true` stops the run.
    fn should_stop(&mut self, reports: &[StepReport]) -> bool;
}

/// Counts the consecutive rounds in which every robot rounded to the same assignment
/// (with every robot's iterate within `tolerance` of it), the same one as the round before.
#[derive(Debug, Clone, Default)]
pub struct AgreementStreak {
    rounds: usize,
    digest: u64,
}

impl AgreementStreak {
    /// Feeds one round's reports; returns the length of the current streak (0: no agreement).
    pub fn observe(&mut self, reports: &[StepReport], tolerance: f64) -> usize {
        let Some(first) = reports.first() else {
            return 0;
        };
        let digest = first.assignment_digest;
        let agreed = reports
            .iter()
            .all(|r| r.integrality_gap <= tolerance && r.assignment_digest == digest);
        self.rounds = match (agreed, self.rounds > 0 && digest == self.digest) {
            (false, _) => 0,
            (true, true) => self.rounds + 1,
            (true, false) => 1,
        };
        self.digest = digest;
        self.rounds
    }
}

/// Stop when all robots agree on one near-integral assignment for `rounds` rounds.
#[derive(Debug, Clone)]
pub struct AgreementStop {
    pub rounds: usize,
    /// Largest [`StepReport::integrality_gap`] accepted.
    pub tolerance: f64,
    streak: AgreementStreak,
}

impl AgreementStop {
    /// Default tolerance 0.2. Measured with `runtime/examples/stop_rules.rs` (10 rounds,
    /// uniform costs): 0 wrong stops in 110 runs (20×20 complete, 30×12 random, 15×15 chain),
    /// stopping 2.5× later than the round the assignment became optimal on average, where
    /// 0.05 (docs/notes.md, note 12) also made no wrong stop but took 3.5× longer.
    pub fn new(rounds: usize) -> Self {
        Self::with_tolerance(rounds, 0.2)
    }

    pub fn with_tolerance(rounds: usize, tolerance: f64) -> Self {
        Self {
            rounds: rounds.max(1),
            tolerance,
            streak: AgreementStreak::default(),
        }
    }
}

impl Default for AgreementStop {
    fn default() -> Self {
        Self::new(10)
    }
}

impl TeamStopRule for AgreementStop {
    fn should_stop(&mut self, reports: &[StepReport]) -> bool {
        reports.is_empty() || self.streak.observe(reports, self.tolerance) >= self.rounds
    }
}

/// Never stops (run to the iteration limit).
#[derive(Debug, Clone, Copy, Default)]
pub struct NeverStop;

impl TeamStopRule for NeverStop {
    fn should_stop(&mut self, _: &[StepReport]) -> bool {
        false
    }
}
