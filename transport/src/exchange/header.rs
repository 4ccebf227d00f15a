//! The fixed-size header every round message carries next to its payload.

use admm_ta_agents::certify::local_stop::{NeighbourState, Window};
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
    /// Agreement window of the decentralized stop ([`admm_ta_agents::certify::local_stop`]).
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

    /// Words of the header on a byte stream (the copying transports: uds, Zenoh).
    pub const WORDS: usize = 7;

    /// Writes the header as [`Self::WORDS`] `f64` words (bit patterns), ahead of a payload.
    pub fn write_words(&self, words: &mut [f64]) {
        let w = [
            self.round,
            (u64::from(self.sender) << 32) | u64::from(self.flags),
            self.digest,
            self.window[0],
            self.window[1],
            self.window[2],
            self.window[3],
        ];
        for (slot, v) in words.iter_mut().zip(w) {
            *slot = f64::from_bits(v);
        }
    }

    /// Reads a header written by [`Self::write_words`].
    pub fn from_words(words: &[f64]) -> Self {
        let w = |k: usize| words[k].to_bits();
        Self {
            round: w(0),
            sender: (w(1) >> 32) as u32,
            flags: w(1) as u32,
            digest: w(2),
            window: [w(3), w(4), w(5), w(6)],
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

/// The bytes of `words` (for writing a message to a byte stream).
pub fn words_as_bytes(words: &[f64]) -> &[u8] {
    // SAFETY: any f64 is 8 initialised bytes; u8 has no alignment requirement.
    unsafe { std::slice::from_raw_parts(words.as_ptr().cast::<u8>(), std::mem::size_of_val(words)) }
}

/// The bytes of `words`, writable (for reading a message from a byte stream).
pub fn words_as_bytes_mut(words: &mut [f64]) -> &mut [u8] {
    // SAFETY: as above, and every byte pattern is a valid f64.
    unsafe {
        std::slice::from_raw_parts_mut(
            words.as_mut_ptr().cast::<u8>(),
            std::mem::size_of_val(words),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_words_round_trip() {
        let header = RoundHeader {
            round: u64::MAX - 3,
            sender: 41,
            flags: 0xdead_beef,
            digest: 0x0123_4567_89ab_cdef,
            window: [1, u64::MAX, 0, 7],
        };
        let mut words = [0.0; RoundHeader::WORDS];
        header.write_words(&mut words);
        assert_eq!(RoundHeader::from_words(&words), header);
    }
}
