//! The `uds` baseline transport: one process per agent, like `ipc`, but every payload is
//! **copied** through Unix-domain stream sockets — serialised into the sender's buffer,
//! copied into the kernel once per neighbour, and copied out by each receiver. It exists to
//! show what iceoryx2's zero-copy exchange saves, side by side in one benchmark run; runs
//! use it through `admm-ta bench rounds --transports uds`.
//!
//! One stream per graph edge: agent `i` listens on `uds-i.sock` in the run directory,
//! connects to its lower-numbered neighbours (sending its index as a handshake) and accepts
//! its higher-numbered ones; the socket files are removed once everybody is connected. All
//! sockets are non-blocking. A message is 7 header words (round, sender and flags, digest,
//! the stop window) followed by the payload, both as `f64` words. Sending never blocks: what
//! the kernel does not take at once is written while the agent gathers the next round, so
//! two neighbours sending large messages to each other cannot deadlock; a gather completes
//! once every neighbour's message is read *and* the agent's own message is fully sent.
//! Waiting follows the [`WaitPolicy`](crate::wait::WaitPolicy): spin on non-blocking reads and/or sleep in `poll(2)`
//! in 20 ms slices, looking at the run's failure mark in between. A neighbour's end of file
//! is reported as its failure. There is no global barrier.
//!
//! * [`exchange`]: one agent's end (its links, its start-up, its rounds);
//! * [`process`]: how the process orchestration runs it (an agent's connection and blame).

pub mod exchange;
pub mod process;

/// The `uds` transport's declaration.
pub const INFO: crate::endpoint::TransportInfo = crate::endpoint::TransportInfo {
    name: "uds",
    capabilities: crate::endpoint::Capabilities::PROCESSES,
    processes: Some(&process::UdsProcesses),
};
