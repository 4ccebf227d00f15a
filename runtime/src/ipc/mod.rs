//! The `ipc` transport: one OS process per agent over iceoryx2 zero-copy publish-subscribe.
//!
//! * [`transport`]: an agent's iceoryx2 ports (the [`crate::exchange::Exchange`]).

pub mod transport;
