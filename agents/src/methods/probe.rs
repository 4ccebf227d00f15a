//! Synthetic agents for latency benchmarks: a step of known, tunable cost over a payload of
//! any length, so that a benchmark can vary the payload size independently of the team size
//! and separate what the exchange costs from what the algorithm costs.
//!
//! * [`ProbeStep::Touch`] reads one value of each neighbour's payload and writes one value of
//!   its own: the round then costs the exchange alone (a copying transport still moves the
//!   whole payload; a zero-copy one does not touch it).
//! * [`ProbeStep::Average`] replaces the payload by the average of its own and its
//!   neighbours' payloads (consensus averaging): every value of every neighbour is read, as
//!   a real consensus step does.
//!
//! ```
//! use admm_ta_agents::agent::ConsensusAgent;
//! use admm_ta_agents::methods::probe::{ProbeAgent, ProbeStep};
//! let mut a = ProbeAgent::new(0, 4, ProbeStep::Average);
//! let b = ProbeAgent::new(1, 4, ProbeStep::Average);
//! let mut theirs = vec![0.0; 4];
//! b.write_initial_payload(&mut theirs);
//! let mut out = vec![0.0; 4];
//! a.step(&vec![theirs.as_slice()], &mut out);
//! assert_eq!(out[0], 0.5); // (0 + 1) / 2
//! ```

use crate::agent::{ConsensusAgent, Inbox, StepReport};
use serde::{Deserialize, Serialize};

/// What a [`ProbeAgent`] computes per round.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProbeStep {
    /// One value read per neighbour, one written: O(degree).
    Touch,
    /// Average of the own and the neighbours' payloads: O(payload · degree).
    Average,
}

impl ProbeStep {
    pub fn name(self) -> &'static str {
        match self {
            Self::Touch => "touch",
            Self::Average => "average",
        }
    }
}

/// A benchmark agent: payload of `len` values, step [`ProbeStep`], no task of its own.
#[derive(Debug, Clone)]
pub struct ProbeAgent {
    index: usize,
    step: ProbeStep,
    /// The agent's current payload (what it published last).
    state: Vec<f64>,
}

impl ProbeAgent {
    pub fn new(index: usize, len: usize, step: ProbeStep) -> Self {
        Self {
            index,
            step,
            state: vec![index as f64; len.max(1)],
        }
    }
}

impl ConsensusAgent for ProbeAgent {
    fn payload_len(&self) -> usize {
        self.state.len()
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        out.copy_from_slice(&self.state);
    }

    /// Length only: a full scan of every neighbour's payload (the default check) would make
    /// the `touch` step read every byte, hiding what a zero-copy exchange saves.
    fn check_payload(&self, payload: &[f64]) -> Result<(), crate::agent::PayloadError> {
        crate::agent::check_length(payload, self.state.len())
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        let weight = 1.0 / (inbox.len() + 1) as f64;
        match self.step {
            ProbeStep::Touch => {
                let last = self.state.len() - 1;
                let mut sum = self.state[last];
                for k in 0..inbox.len() {
                    sum += inbox.payload(k)[last];
                }
                self.state[last] = sum * weight;
                out[last] = self.state[last];
            }
            ProbeStep::Average => {
                for k in 0..inbox.len() {
                    for (s, v) in self.state.iter_mut().zip(inbox.payload(k)) {
                        *s += v;
                    }
                }
                for (o, s) in out.iter_mut().zip(self.state.iter_mut()) {
                    *s *= weight;
                    *o = *s;
                }
            }
        }
        StepReport::default()
    }

    fn decide(&self) -> usize {
        self.index
    }

    fn rounded_task(&self) -> usize {
        self.index
    }

    fn certificate_slack(&self) -> f64 {
        f64::INFINITY
    }

    fn own_column(&self) -> &[f64] {
        &[]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averaging_on_a_pair_meets_in_the_middle_and_touch_moves_one_value() {
        for step in [ProbeStep::Average, ProbeStep::Touch] {
            let mut a = ProbeAgent::new(0, 3, step);
            let mut b = ProbeAgent::new(2, 3, step);
            let (mut pa, mut pb) = (vec![0.0; 3], vec![0.0; 3]);
            a.write_initial_payload(&mut pa);
            b.write_initial_payload(&mut pb);
            let (mut na, mut nb) = (pa.clone(), pb.clone());
            a.step(&vec![pb.as_slice()], &mut na);
            b.step(&vec![pa.as_slice()], &mut nb);
            assert_eq!(na[2], 1.0);
            assert_eq!(nb[2], 1.0);
            let moved = if step == ProbeStep::Average { 1.0 } else { 0.0 };
            assert_eq!(na[0], moved, "{step:?}");
        }
    }
}
