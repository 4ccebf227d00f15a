//! The `shm` transport: agent processes exchanging payloads through one shared-memory table
//! of fixed-size slots — the `threads` transport's protocol across processes, with nothing
//! between the data and the wake-up. It shows what a round between processes costs when
//! only the memory traffic and one futex wake-up per round remain, next to the layers
//! iceoryx2 (`ipc`), sockets (`uds`) and Zenoh add (`admm-ta bench rounds`).
//!
//! * [`table`]: the table (created by the launcher next to the run's board, owner-only,
//!   pre-faulted, removed with the run): per agent a published-round word and two slots
//!   (round parity), each a round header, a payload length and the payload.
//! * [`process`]: how the process orchestration runs it (the slot table before the agents,
//!   the agents' connection and blame);
//! * [`exchange`]: one agent's end: it writes its next payload in place into its own slot
//!   of the next parity, publishes it with a release store of its published-round word,
//!   counts it at every neighbour (the board's arrival counters) and futex-wakes only the
//!   neighbour whose round it completes; neighbours read the slots in place after an acquire
//!   load. Failures, deadlines, stop requests and blame work through the board as for `uds`.

pub mod exchange;
pub mod process;
pub mod table;

/// The `shm` transport's declaration.
pub const INFO: crate::endpoint::TransportInfo = crate::endpoint::TransportInfo {
    name: "shm",
    capabilities: crate::endpoint::Capabilities {
        global_barrier: true,
        fault_injection: true,
        ..crate::endpoint::Capabilities::PROCESSES
    },
    processes: Some(&process::ShmProcesses),
};
