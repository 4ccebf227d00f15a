//! A host's census: once its team is ending, the host asks the network which agents are
//! alive (a liveliness query), and an agent listed alive that two answers in a row miss is
//! taken as gone — a token whose removal never reached this router must not keep the host
//! waiting.

use std::time::{Duration, Instant};

/// How often a host whose team is ending asks the network which agents are alive (a token
/// whose removal never reached this router must not keep it waiting).
const CENSUS_EVERY: Duration = Duration::from_secs(1);

/// The host's periodic question "which agents are alive?", and whom the last answer missed.
pub(crate) struct Census {
    last: Option<Instant>,
    missed: Vec<bool>,
}

impl Census {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            last: None,
            missed: vec![false; n],
        }
    }

    /// Time for the next question (at most every [`CENSUS_EVERY`]).
    pub(crate) fn due(&mut self) -> bool {
        let due = self.last.is_none_or(|t| t.elapsed() >= CENSUS_EVERY);
        if due {
            self.last = Some(Instant::now());
        }
        due
    }

    /// The agents listed alive that this answer and the one before both missed.
    pub(crate) fn gone(&mut self, alive_now: &[usize], listed: &[bool]) -> Vec<usize> {
        let mut gone = Vec::new();
        for (a, missed) in self.missed.iter_mut().enumerate() {
            let missing = listed[a] && !alive_now.contains(&a);
            if missing && *missed {
                gone.push(a);
            }
            *missed = missing;
        }
        gone
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_agent_is_gone_after_two_answers_without_it() {
        let mut census = Census::new(3);
        assert!(census.due() && !census.due());
        let listed = [true, true, false];
        assert!(census.gone(&[0], &listed).is_empty());
        // Agent 1 missed twice: gone; agent 2 was not listed.
        assert_eq!(census.gone(&[0], &listed), [1]);
        // An agent back in an answer starts over.
        assert!(census.gone(&[0, 1], &listed).is_empty());
        assert!(census.gone(&[0], &listed).is_empty());
    }
}
