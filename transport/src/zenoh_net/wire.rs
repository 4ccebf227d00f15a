//! A round message as it travels on Zenoh (between agents, and between a mixed team's
//! bridges): the round and the sender (with the flags) as two plain little-endian words,
//! then the rest of the header and the payload coded against the sender's last message
//! ([`crate::exchange::codec`]). The two plain words let a receiver refuse a message of
//! another sender, or of a round it cannot decode, before decoding anything.
//!
//! A message is decoded against the sender's message of the round before: the receiver
//! must hold that one (it gathered it, in lockstep), or the message must be raw.
//!
//! A sender codes only where its messages cross a network (a team with hosts, and a mixed
//! team's bridges). On one machine, over the launcher's loopback router, coding costs CPU
//! and saves nothing: 200 primal agents on 2 cores (320 kB messages) took 2.1–2.7 s a
//! round (p50) coded, 1.9–2.3 s raw. Receivers read both kinds alike.

use crate::exchange::codec::{self, CodecError, Coder};
use crate::exchange::header::RoundHeader;

/// Words of a message sent plain: the round, and the sender with the flags.
const PLAIN_WORDS: usize = 2;
/// Bytes of the plain words.
pub const PLAIN_BYTES: usize = 8 * PLAIN_WORDS;

/// Why a received message cannot be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    #[error("a message of {got} bytes is shorter than its {PLAIN_BYTES} plain ones")]
    Short { got: usize },
    /// A raw message of another length: its payload's values (`got`, the header excluded).
    #[error("a payload of {got} values")]
    WrongLength { got: usize },
    #[error("round {round} is coded against round {}, which this receiver does not hold", round.wrapping_sub(1))]
    NotHeld { round: u64 },
    #[error(transparent)]
    Codec(#[from] CodecError),
}

/// The sender's coder of its messages (header words and payload, `words` in all).
pub struct WireCoder {
    coder: Coder,
    /// Whether messages are coded (else every one goes raw).
    coded: bool,
}

impl WireCoder {
    /// A coder of messages of `words` words: [`RoundHeader::WORDS`] and the payload; they
    /// go `coded` against the last one, or raw.
    pub fn new(words: usize, coded: bool) -> Self {
        Self {
            coder: Coder::new(words - PLAIN_WORDS),
            coded,
        }
    }

    /// The wire bytes of `message` (header words, then the payload), which becomes the last
    /// message sent. A message of another length (an injected fault) goes raw, and leaves
    /// the last message as it was.
    pub fn encode(&mut self, message: &[f64]) -> Vec<u8> {
        let (plain, rest) = message.split_at(PLAIN_WORDS);
        let mut bytes = Vec::with_capacity(PLAIN_BYTES + codec::capacity(rest.len()));
        for w in plain {
            bytes.extend_from_slice(&w.to_bits().to_le_bytes());
        }
        if self.coded && rest.len() == self.coder.words() {
            self.coder.encode(rest, &mut bytes);
        } else {
            codec::write_raw(rest, &mut bytes);
        }
        bytes
    }
}

/// The words of a raw message after its plain ones, as bytes (`None`: a delta, or too short).
pub fn raw_words(bytes: &[u8]) -> Option<&[u8]> {
    match bytes.get(PLAIN_BYTES) {
        Some(&codec::RAW) => Some(&bytes[PLAIN_BYTES + 1..]),
        _ => None,
    }
}

/// The round and the sender (with the flags) of a message's plain words.
pub fn plain(bytes: &[u8]) -> Result<(u64, u32), WireError> {
    if bytes.len() < PLAIN_BYTES {
        return Err(WireError::Short { got: bytes.len() });
    }
    let word = |k: usize| u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().expect("8"));
    Ok((word(0), (word(1) >> 32) as u32))
}

/// Decodes `bytes` into `message` (header words, then the payload), which holds the
/// sender's message of round `held` (`None`: none yet). Returns the message's header. On an
/// error `message` may be changed.
pub fn decode(
    bytes: &[u8],
    message: &mut [f64],
    held: Option<u64>,
) -> Result<RoundHeader, WireError> {
    let (round, _) = plain(bytes)?;
    let coded = &bytes[PLAIN_BYTES..];
    let words = message.len() - PLAIN_WORDS;
    if coded.first() == Some(&codec::RAW) && coded.len() != codec::raw_len(words) {
        let got = (coded.len() - 1) / 8;
        return Err(WireError::WrongLength {
            got: (got + PLAIN_WORDS).saturating_sub(RoundHeader::WORDS),
        });
    }
    if coded.first() != Some(&codec::RAW) && held.and_then(|r| r.checked_add(1)) != Some(round) {
        return Err(WireError::NotHeld { round });
    }
    for (k, w) in message[..PLAIN_WORDS].iter_mut().enumerate() {
        let word = u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().expect("8"));
        *w = f64::from_bits(word);
    }
    codec::decode(coded, &mut message[PLAIN_WORDS..])?;
    Ok(RoundHeader::from_words(&message[..RoundHeader::WORDS]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(round: u64, sender: usize, payload: &[f64]) -> Vec<f64> {
        let mut words = vec![0.0; RoundHeader::WORDS + payload.len()];
        let header = RoundHeader {
            round,
            digest: round / 3,
            ..RoundHeader::initial(sender)
        };
        header.write_words(&mut words);
        words[RoundHeader::WORDS..].copy_from_slice(payload);
        words
    }

    /// Messages decode in order; a delta whose round before the receiver does not hold is
    /// refused, and a raw message of another length is named by its payload's length.
    #[test]
    fn rounds_decode_in_order_and_nothing_else_does() {
        let mut coder = WireCoder::new(RoundHeader::WORDS + 4, true);
        let mut held = vec![0.0; RoundHeader::WORDS + 4];
        let first = coder.encode(&message(0, 3, &[1.0, 2.0, 3.0, 4.0]));
        assert_eq!(plain(&first), Ok((0, 3)));
        assert_eq!(decode(&first, &mut held, None).unwrap().sender, 3);
        let second = coder.encode(&message(1, 3, &[1.0, 2.5, 3.0, 4.0]));
        assert!(second.len() < first.len());
        assert_eq!(
            decode(&second, &mut held.clone(), None),
            Err(WireError::NotHeld { round: 1 })
        );
        assert_eq!(decode(&second, &mut held, Some(0)).unwrap().round, 1);
        assert_eq!(held, message(1, 3, &[1.0, 2.5, 3.0, 4.0]));
        let short = coder.encode(&message(2, 3, &[1.0, 2.5, 3.0]));
        assert_eq!(
            decode(&short, &mut held.clone(), Some(1)),
            Err(WireError::WrongLength { got: 3 })
        );
        // The short message did not become the last one: round 2 codes against round 1.
        let third = coder.encode(&message(2, 3, &[0.0, 2.5, 3.0, 4.0]));
        decode(&third, &mut held, Some(1)).unwrap();
        assert_eq!(held, message(2, 3, &[0.0, 2.5, 3.0, 4.0]));
        assert_eq!(
            decode(&third[..5], &mut held, Some(1)),
            Err(WireError::Short { got: 5 })
        );
    }

    /// A sender that does not code sends every message raw, and it decodes from anything.
    #[test]
    fn uncoded_messages_are_raw_and_decode_without_the_last() {
        let mut coder = WireCoder::new(RoundHeader::WORDS + 2, false);
        let raw = PLAIN_BYTES + codec::raw_len(RoundHeader::WORDS + 2 - PLAIN_WORDS);
        let _ = coder.encode(&message(0, 1, &[1.0, 2.0]));
        let second = coder.encode(&message(1, 1, &[1.0, 2.0]));
        assert_eq!(second.len(), raw);
        let mut held = vec![f64::NAN; RoundHeader::WORDS + 2];
        decode(&second, &mut held, None).unwrap();
        assert_eq!(held, message(1, 1, &[1.0, 2.0]));
    }
}
