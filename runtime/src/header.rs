//! The fixed-size header every round message carries next to its payload.

use admm_ta_agents::local_stop::{NeighbourState, Window};
use iceoryx2::prelude::ZeroCopySend;

/// Header of one round message: who sent it, which round, and what the stop protocol needs
/// (the sender's assignment digest and agreement window). `#[repr(C)]` so that it can live
/// in shared memory as an iceoryx2 user header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("AdmmTaRoundHeader")]
pub struct RoundHeader {
    pub round: u64,
    pub sender: u32,
    pub flags: u32,
    /// Hash of the sender's rounded view of the team's assignment.
    pub digest: u64,
    /// Agreement window of the decentralized stop ([`admm_ta_agents::local_stop`]).
    pub window: Window,
}

impl RoundHeader {
    /// The round-0 header of `sender` (nothing agreed yet).
    pub fn initial(sender: usize) -> Self {
        Self {
            sender: sender as u32,
            ..Self::default()
        }
    }

    /// What the stop protocol reads of this message.
    pub fn stop_state(&self) -> NeighbourState {
        NeighbourState {
            digest: self.digest,
            window: self.window,
        }
    }
}
