//! The lockstep exchange: every agent reads its neighbours' previous-round payloads in place
//! from the round buffer of the simulation.

use admm_ta_agents::agent::Inbox;

/// The neighbours' round-`k` payloads of one agent, read in place from the round buffer.
pub(super) struct SimInbox<'a> {
    pub(super) payloads: &'a [f64],
    pub(super) len: usize,
    pub(super) neighbours: &'a [usize],
}

impl Inbox for SimInbox<'_> {
    fn len(&self) -> usize {
        self.neighbours.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        let j = self.neighbours[k];
        &self.payloads[j * self.len..(j + 1) * self.len]
    }
}
