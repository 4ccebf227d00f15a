//! What one robot saw of an episode of its standing team ([`Outcome`]) and the answer it
//! makes of it; why an episode's agreement leaves nothing to solve.

use crate::options::OnFailure;
use crate::standing::agreement::{Closing, Opening, RosterNews};
use crate::standing::answer::Answer;
use crate::standing::roster::Change;
use std::time::Duration;

/// What one robot saw of an episode.
pub(super) struct Outcome {
    pub(super) opening: Opening,
    /// How the roster changes after it.
    pub(super) change: Change,
    /// Its task (`None`: it relayed, or nothing was solved).
    pub(super) task: Option<usize>,
    pub(super) certified: bool,
    pub(super) rounds: u64,
    pub(super) agreement_rounds: u64,
    /// Bytes of round messages it sent.
    pub(super) sent_bytes: u64,
    pub(super) closing: Option<Closing>,
    /// Why nothing was solved.
    pub(super) unsolved: Option<String>,
    /// The episode has no feasible assignment.
    pub(super) infeasible: bool,
}

impl Outcome {
    /// The robot's answer (`row`: the row it gave; `news`: the roster's changes since its
    /// last answer).
    pub(super) fn answer(
        self,
        episode: u64,
        robot: usize,
        row: Option<&[Option<f64>]>,
        took: Duration,
        mut news: RosterNews,
    ) -> Answer {
        let total = self.closing.as_ref().and_then(Closing::total);
        // A forbidden pair in the certified optimum: the rows have no feasible assignment
        // (at the round limit a robot on a forbidden pair proves nothing).
        let forbidden_pair = total.is_some_and(|t| !t.is_finite());
        let infeasible = self.infeasible || (self.certified && forbidden_pair);
        let feasible = !infeasible;
        let solved = feasible && self.unsolved.is_none();
        let cost = self
            .task
            .map(|t| row.and_then(|r| r[t]).unwrap_or(f64::INFINITY));
        Answer {
            episode,
            robot,
            task: self.task.filter(|_| solved),
            certified: self.certified && solved,
            rounds: self.rounds,
            agreement_rounds: self.agreement_rounds,
            sent_bytes: self.sent_bytes,
            cost: cost.filter(|c| c.is_finite() && solved),
            total_cost: total.filter(|t| t.is_finite()),
            assignment: self
                .closing
                .as_ref()
                .and_then(Closing::assignment)
                .filter(|_| solved),
            feasible,
            unsolved: self.unsolved.or_else(|| {
                (!feasible)
                    .then(|| "infeasible: no assignment avoids every forbidden pair".to_string())
            }),
            missing: self.opening.missing(),
            unavailable: self.opening.unavailable(),
            left: self.change.left,
            leave_refused: self.change.refused,
            lost: {
                news.merge(&RosterNews {
                    lost: self.change.lost,
                    ..RosterNews::default()
                });
                news.lost
            },
            joined: news.joined,
            crashed: news.crashed,
            ms: took.as_secs_f64() * 1e3,
        }
    }
}

/// Why the episode's agreement leaves nothing to solve, if it does (every robot reaches the
/// same verdict: they hold the same opening).
pub(super) fn nothing_to_solve(opening: &Opening, on_failure: OnFailure) -> Option<String> {
    let missing = opening.missing();
    if !missing.is_empty() && on_failure == OnFailure::Abort {
        return Some(format!(
            "robot(s) {missing:?} gave no costs within the episode deadline"
        ));
    }
    let Some((shortest, longest)) = opening.lengths() else {
        return Some("no robot gave costs".into());
    };
    if shortest != longest {
        return Some(format!(
            "the robots gave rows of {shortest} to {longest} costs: every row needs one cost per task of the episode"
        ));
    }
    None
}
