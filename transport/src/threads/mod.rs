//! The `threads` transport: one OS thread per agent, exchanging payloads through a
//! lock-free double-buffered slot per agent and waking each other with crossbeam parkers.
//!
//! Each agent owns two slots (round parity). It writes round `k+1` into slot `(k+1) % 2`
//! and then publishes by storing `k+2` into its `published` counter (release); a neighbour
//! that sees the counter (acquire) reads the slot in place. The neighbour barrier makes this
//! safe without locks: see [`crate::exchange`].
//!
//! * [`exchange`]: one agent's end (its slots, its wake-ups);
//! * [`process`]: where its agents run (a thread each, spawned and joined).

pub mod exchange;
pub mod process;

/// The `threads` transport's declaration (its agents are not processes).
pub const INFO: crate::endpoint::TransportInfo = crate::endpoint::TransportInfo {
    name: "threads",
    capabilities: crate::endpoint::Capabilities {
        execution: crate::endpoint::Execution::Threads,
        global_barrier: true,
        ..crate::endpoint::Capabilities::PROCESSES
    },
    processes: None,
};
