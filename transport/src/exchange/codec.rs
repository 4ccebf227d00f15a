//! Round messages coded against the sender's previous message, for the transports whose
//! bytes cross a network (Zenoh).
//!
//! A round's message differs from the same sender's last one in few words (a method's
//! claims, potentials and flags stay put for rounds), and a word that changed keeps its
//! sign, exponent and leading mantissa bits, and, for values on a coarse grid, its
//! trailing ones. So each word is sent as its XOR with the last message's: nothing but a
//! bit of the map for an unchanged word, and for a changed one a control byte (how many
//! zero bytes lead the XOR, how many bytes follow) and the XOR's bytes between its leading
//! and trailing zero bytes. A message the coding would not make smaller goes as it is.
//!
//! ```text
//! raw:   0x00, the words (8 bytes each, little-endian)
//! delta: 0x01, a bitmap of the changed words (⌈L/8⌉ bytes, word w in bit w % 8 of byte
//!        w / 8), then for each changed word in order: (leading << 4) | length, and the
//!        `length` bytes of its XOR without its `leading` high and `8 − leading − length`
//!        low zero bytes, least significant first
//! ```
//!
//! The coding is lossless, and safe only because the exchange is in lockstep: a receiver
//! decodes a neighbour's round `k` only after its round `k − 1` (a neighbour is never more
//! than a round ahead, and the round check refuses any other), so both ends hold the same
//! last message. A delta that does not fit the receiver's last message is an error
//! ([`CodecError`]), never a wrong payload.
//!
//! ```
//! use admm_ta_transport::exchange::codec::{Coder, decode};
//!
//! let mut coder = Coder::new(4);
//! let (first, second) = ([1.0, 2.0, 3.0, 4.0], [1.0, 2.5, 3.0, 4.0]);
//! let mut seen = [0.0; 4];
//! let mut coded = Vec::new();
//! coder.encode(&first, &mut coded);
//! decode(&coded, &mut seen).unwrap();
//! coded.clear();
//! coder.encode(&second, &mut coded);
//! assert!(coded.len() < 8); // one changed word: kind, map, control, 1–2 bytes
//! decode(&coded, &mut seen).unwrap();
//! assert_eq!(seen, second);
//! ```

/// The first byte of a raw message.
pub const RAW: u8 = 0;
/// The first byte of a delta.
const DELTA: u8 = 1;

/// Why a coded message cannot be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CodecError {
    #[error("a coded message of {got} bytes, expected {expected}")]
    Length { got: usize, expected: usize },
    #[error("a coded message of unknown kind {0}")]
    Kind(u8),
    #[error("a coded word with a bad control byte {0:#04x}")]
    Control(u8),
}

/// One sender's coder: its last message.
pub struct Coder {
    last: Vec<f64>,
    /// Whether `last` is a message the receivers hold (false before the first one).
    started: bool,
}

impl Coder {
    /// A coder of messages of `words` values.
    pub fn new(words: usize) -> Self {
        Self {
            last: vec![0.0; words],
            started: false,
        }
    }

    /// Appends the coded bytes of `message` to `out` (at most [`raw_len`] of them); the
    /// message becomes the last one. The first message goes raw: receivers hold nothing to
    /// decode a delta against.
    pub fn encode(&mut self, message: &[f64], out: &mut Vec<u8>) {
        assert_eq!(
            message.len(),
            self.last.len(),
            "a message of another length"
        );
        let start = out.len();
        if !(self.started && delta(&self.last, message, out)) {
            out.truncate(start);
            write_raw(message, out);
        }
        self.last.copy_from_slice(message);
        self.started = true;
    }

    /// Values of a message.
    pub fn words(&self) -> usize {
        self.last.len()
    }
}

/// Appends `message` raw to `out`.
pub fn write_raw(message: &[f64], out: &mut Vec<u8>) {
    out.push(RAW);
    for w in message {
        out.extend_from_slice(&w.to_bits().to_le_bytes());
    }
}

/// Room [`Coder::encode`] needs in its output for a message of `words` values (it writes
/// up to a word past what it keeps).
pub const fn capacity(words: usize) -> usize {
    raw_len(words) + 9
}

/// Bytes of a raw message of `words` values.
pub const fn raw_len(words: usize) -> usize {
    1 + 8 * words
}

/// Appends `message` as a delta against `last` to `out`; `false` if it would not be
/// shorter than the raw message (`out` then ends with a part of it). Each changed word's
/// bytes are written as a whole `u64` and the write position moves by those that count:
/// no copy of a variable length (a word costs a few nanoseconds, not a `memcpy` call).
fn delta(last: &[f64], message: &[f64], out: &mut Vec<u8>) -> bool {
    let start = out.len();
    let limit = raw_len(message.len());
    let map_len = message.len().div_ceil(8);
    // Room for one more word's control and 8 bytes past the limit.
    out.resize(start + capacity(message.len()), 0);
    let buf = &mut out[start..];
    buf[0] = DELTA;
    let mut at = 1 + map_len;
    // Without a branch on whether a word changed (half of a primal's words do, at random):
    // an unchanged word's control and bytes are written and then written over.
    for (w, (a, b)) in last.iter().zip(message).enumerate() {
        let x = a.to_bits() ^ b.to_bits();
        let changed = x != 0;
        buf[1 + w / 8] |= u8::from(changed) << (w % 8);
        let leading = x.leading_zeros() / 8;
        let trailing = x.trailing_zeros() / 8;
        let length = if changed { 8 - leading - trailing } else { 0 };
        buf[at] = ((leading as u8) << 4) | length as u8;
        buf[at + 1..at + 9].copy_from_slice(&x.wrapping_shr(8 * trailing).to_le_bytes());
        at += usize::from(changed) * (1 + length as usize);
        if at >= limit {
            return false;
        }
    }
    out.truncate(start + at);
    true
}

/// Decodes `coded` into `words`, which hold the sender's last message (its length is the
/// message's). On an error `words` may be changed.
pub fn decode(coded: &[u8], words: &mut [f64]) -> Result<(), CodecError> {
    let Some((&kind, body)) = coded.split_first() else {
        return Err(CodecError::Length {
            got: 0,
            expected: raw_len(words.len()),
        });
    };
    match kind {
        RAW => {
            if body.len() != 8 * words.len() {
                return Err(CodecError::Length {
                    got: coded.len(),
                    expected: raw_len(words.len()),
                });
            }
            for (w, b) in words.iter_mut().zip(body.chunks_exact(8)) {
                *w = f64::from_bits(u64::from_le_bytes(b.try_into().expect("8 bytes")));
            }
            Ok(())
        }
        DELTA => decode_delta(body, words),
        other => Err(CodecError::Kind(other)),
    }
}

fn decode_delta(body: &[u8], words: &mut [f64]) -> Result<(), CodecError> {
    let map_len = words.len().div_ceil(8);
    let short = |at: usize| CodecError::Length {
        got: 1 + body.len(),
        expected: 1 + at + 1,
    };
    if body.len() < map_len {
        return Err(short(body.len()));
    }
    if !words.len().is_multiple_of(8) && body[map_len - 1] >> (words.len() % 8) != 0 {
        return Err(CodecError::Control(body[map_len - 1]));
    }
    let mut at = map_len;
    for (byte, chunk) in body[..map_len].iter().zip(words.chunks_mut(8)) {
        let mut bits = *byte;
        while bits != 0 {
            let word = &mut chunk[bits.trailing_zeros() as usize];
            bits &= bits - 1;
            let Some(&control) = body.get(at) else {
                return Err(short(at));
            };
            let (leading, length) = (u32::from(control >> 4), u32::from(control & 0x0f));
            if length == 0 || leading + length > 8 {
                return Err(CodecError::Control(control));
            }
            let end = at + 1 + length as usize;
            if end > body.len() {
                return Err(short(end - 1));
            }
            // A whole `u64` where 8 bytes follow, its first `length` bytes counting.
            let v = match body.get(at + 1..at + 9) {
                Some(eight) => u64::from_le_bytes(eight.try_into().expect("8 bytes")),
                None => {
                    let mut eight = [0u8; 8];
                    eight[..length as usize].copy_from_slice(&body[at + 1..end]);
                    u64::from_le_bytes(eight)
                }
            };
            let v = v & (u64::MAX >> (64 - 8 * length));
            *word = f64::from_bits(word.to_bits() ^ (v << (8 * (8 - leading - length))));
            at = end;
        }
    }
    if at == body.len() {
        Ok(())
    } else {
        Err(CodecError::Length {
            got: 1 + body.len(),
            expected: 1 + at,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sequence of messages with every kind of change round-trips, bit for bit (NaN
    /// payloads, signed zeros, infinities included), and unchanged messages cost their map.
    #[test]
    fn messages_round_trip_bit_for_bit() {
        let words = 19;
        let mut coder = Coder::new(words);
        let mut seen = vec![7.0; words];
        let mut message: Vec<f64> = (0..words).map(|w| w as f64 * 0.37).collect();
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for round in 0..200 {
            for (w, v) in message.iter_mut().enumerate() {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                match (state % 9, w % 5) {
                    (0, _) => *v += 1e-9 * (state >> 40) as f64,
                    (1, 0) => *v = f64::from_bits(state),
                    (2, 1) => *v = -0.0,
                    (3, 2) => *v = f64::INFINITY,
                    (4, _) => *v = (*v as f32) as f64,
                    _ => {}
                }
            }
            let mut coded = Vec::new();
            coder.encode(&message, &mut coded);
            assert!(coded.len() <= raw_len(words), "round {round}");
            decode(&coded, &mut seen).unwrap();
            let bits = |m: &[f64]| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&seen), bits(&message), "round {round}");
        }
        let mut same = vec![9]; // appended after what `out` held
        coder.encode(&message.clone(), &mut same);
        assert_eq!(same.len(), 1 + 1 + words.div_ceil(8));
        decode(&same[1..], &mut seen).unwrap();
    }

    /// The first message is raw; a message whose every word changed entirely goes raw too.
    #[test]
    fn a_message_the_delta_would_not_shorten_goes_raw() {
        let mut coder = Coder::new(3);
        let mut coded = |message: &[f64]| {
            let mut out = Vec::new();
            coder.encode(message, &mut out);
            out
        };
        assert_eq!(coded(&[1.0, 2.0, 3.0])[0], RAW);
        let all = coded(&[-1.1e300, f64::from_bits(0x8000_0000_0000_0001), 3.3e-7]);
        assert_eq!((all[0], all.len()), (RAW, raw_len(3)));
        assert_eq!(coded(&[-1.1e300, 5.0, 3.3e-7])[0], DELTA);
    }

    /// Truncated, padded or malformed messages are errors, never a payload.
    #[test]
    fn malformed_messages_are_refused() {
        let mut coder = Coder::new(10);
        let mut seen = [0.0; 10];
        let mut first = Vec::new();
        coder.encode(&[1.0; 10], &mut first);
        decode(&first, &mut seen).unwrap();
        let mut next = [1.0; 10];
        next[3] = 1.5;
        next[9] = -2.0;
        let mut coded = Vec::new();
        coder.encode(&next, &mut coded);
        for cut in 0..coded.len() {
            assert!(
                decode(&coded[..cut], &mut seen.clone()).is_err(),
                "cut {cut}"
            );
        }
        let mut longer = coded.clone();
        longer.push(0);
        assert!(decode(&longer, &mut seen.clone()).is_err());
        let mut bad_kind = coded.clone();
        bad_kind[0] = 9;
        assert_eq!(
            decode(&bad_kind, &mut seen.clone()),
            Err(CodecError::Kind(9))
        );
        let mut stray_bit = coded.clone();
        stray_bit[2] |= 0x80; // word 15 of a message of 10
        assert!(decode(&stray_bit, &mut seen.clone()).is_err());
        decode(&coded, &mut seen).unwrap();
        assert_eq!(seen, next);
        assert!(decode(&[RAW, 1, 2, 3], &mut seen).is_err());
        assert!(decode(&[], &mut seen).is_err());
    }
}
