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

/// Where a received message belongs, once it passed [`check_message`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// The round being gathered.
    Current,
    /// The next round (a neighbour may be one round ahead).
    Next,
}

/// Why a received message is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageFault {
    WrongLength { got: usize },
    WrongSender { got: u32 },
    OutOfOrder { got: u64 },
}

/// Checks a message received from `neighbour` while gathering `round`: its payload length,
/// its sender and its round (this round, or the next one if no next-round message is held
/// yet: a neighbour is never further ahead).
pub fn check_message(
    header: &RoundHeader,
    payload_len: usize,
    expected_len: usize,
    neighbour: usize,
    round: u64,
    next_is_free: bool,
) -> Result<Placement, MessageFault> {
    if payload_len != expected_len {
        return Err(MessageFault::WrongLength { got: payload_len });
    }
    if header.sender as usize != neighbour {
        return Err(MessageFault::WrongSender { got: header.sender });
    }
    if header.round == round {
        Ok(Placement::Current)
    } else if round.checked_add(1) == Some(header.round) && next_is_free {
        Ok(Placement::Next)
    } else {
        Err(MessageFault::OutOfOrder { got: header.round })
    }
}
