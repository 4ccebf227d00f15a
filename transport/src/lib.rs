//! How a team's agents exchange their round messages: the registry of transports, every
//! transport, and the mechanisms they share. The orchestration crate (`admm-ta-runtime`:
//! options, launcher, solve, teams, hosts) sits above this one; nothing here knows of it.
//!
//! The modules, by layer, top to bottom; a module names modules of its own layer or of
//! lower ones only, no two files import each other (directly or around a circle), and no
//! transport names another (`tests/layout.rs` at the workspace root checks all three).
//!
//! **The registry**
//! * [`Transport`]: the one transport type users choose from (one line per transport) and
//!   what each can do ([`Capabilities`]).
//!
//! **Transports** (each independent of the others; each a folder of the same shape: its
//! declaration `INFO` in `mod.rs`, its `exchange` — one agent's end — and its `process` —
//! where its agents run and, for agent processes, how they connect and whom to blame)
//! * [`sim`]: the lockstep simulation — every agent in one thread, round by round, each
//!   reading only its neighbours' previous-round payloads; the deterministic reference the
//!   others must reproduce bit for bit;
//! * [`threads`]: one OS thread per agent, lock-free double-buffered slots;
//! * [`shm`]: agent processes sharing one table of double-buffered slots, futex wake-ups (the
//!   `threads` protocol across processes: a reference for what a process round costs);
//! * [`ipc`]: the iceoryx2 exchange of agent processes (services, nodes, zero-copy samples);
//! * [`uds`]: agent processes copying payloads through Unix-domain sockets (a baseline);
//! * [`zenoh_net`]: agent processes over Zenoh (feature `zenoh`), the multi-host transport.
//!
//! **Shared mechanisms**
//! * [`exchange`]: the `Exchange` trait every distributed transport implements, its errors,
//!   the per-agent round loop and the round header;
//! * [`board`]: a run's shared-memory board (arrival counters, published rounds, failure
//!   mark, member pids, global barrier);
//! * [`endpoint`]: what a transport declares, and the trait of process transports (how an
//!   agent connects, what a run needs, whom to blame);
//! * [`wait`]: how agents wait (spin, then sleep), and the counting barrier;
//! * [`futex`]: process-shared futex waits and wake-ups on words of shared memory;
//! * [`latency`]: round-latency histograms per component; [`usage`]: CPU time and context
//!   switches of an agent; [`timeline`]: every agent's round stamps and the critical path;
//! * [`signals`]: SIGINT, SIGTERM and SIGHUP recorded (not fatal) while a team runs;
//! * [`liveness`]: whether a process lives; [`fault`]: fault injection for tests;
//!   [`logging`]: the agents' log lines; [`error_text`]: errors as one line of text.

// The registry.
mod registry;
pub use endpoint::{Capabilities, Execution};
pub use registry::{Transport, UnknownTransport};
pub use zenoh_net::error::ZenohNotBuilt;

// Transports.
pub mod ipc;
pub mod shm;
pub mod sim;
pub mod threads;
pub mod uds;
pub mod zenoh_net;

// Shared mechanisms.
pub mod board;
pub mod endpoint;
pub mod error_text;
pub mod exchange;
pub mod fault;
pub mod futex;
pub mod latency;
pub mod liveness;
pub mod logging;
pub mod signals;
pub mod timeline;
pub mod usage;
pub mod wait;
