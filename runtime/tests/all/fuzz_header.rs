//! Fuzzing the validation of received message headers (as property tests that run in CI):
//! any header, length and state gets a verdict, never a panic, and only a message of the
//! right length, from the right sender, for this round or (once) the next is accepted.

use admm_ta_transport::exchange::header::{MessageFault, Placement, RoundHeader, check_message};
use proptest::prelude::*;

proptest! {
    #[test]
    fn only_well_formed_messages_of_this_or_the_next_round_pass(
        round in prop_oneof![any::<u64>(), 0u64..5, Just(u64::MAX)],
        offset in prop_oneof![any::<u64>(), 0u64..3],
        sender in prop_oneof![any::<u32>(), 0u32..4],
        neighbour in 0usize..4,
        len in 0usize..6,
        expected_len in 0usize..6,
        next_is_free in any::<bool>(),
        digest in any::<u64>(),
    ) {
        let header = RoundHeader {
            round: round.wrapping_add(offset),
            sender,
            flags: 0,
            digest,
            window: Default::default(),
        };
        let verdict = check_message(&header, len, expected_len, neighbour, round, next_is_free);
        match verdict {
            Ok(Placement::Current) => {
                prop_assert_eq!(header.round, round);
            }
            Ok(Placement::Next) => {
                prop_assert!(next_is_free);
                prop_assert_eq!(Some(header.round), round.checked_add(1));
            }
            Err(MessageFault::WrongLength { got }) => prop_assert_ne!(got, expected_len),
            Err(MessageFault::WrongSender { got }) => prop_assert_ne!(got as usize, neighbour),
            Err(MessageFault::OutOfOrder { got }) => {
                prop_assert!(got != round && !(next_is_free && round.checked_add(1) == Some(got)));
            }
        }
        if verdict.is_ok() {
            prop_assert_eq!(len, expected_len);
            prop_assert_eq!(sender as usize, neighbour);
        }
    }
}
