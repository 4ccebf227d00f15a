//! The `sim` transport: lockstep simulation of a team of agents in one thread — every agent
//! reading only its neighbours' previous-round payloads; the deterministic reference the
//! other transports must reproduce bit for bit.
//!
//! * [`exchange`]: how an agent reads its neighbours' payloads (in place, from the round
//!   buffer);
//! * [`process`]: where its agents run (the calling thread, round by round).

pub mod exchange;
pub mod process;

/// The `sim` transport's declaration (its agents are not processes).
pub const INFO: crate::endpoint::TransportInfo = crate::endpoint::TransportInfo {
    name: "sim",
    capabilities: crate::endpoint::Capabilities {
        execution: crate::endpoint::Execution::Lockstep,
        ..crate::endpoint::Capabilities::PROCESSES
    },
    processes: None,
};
