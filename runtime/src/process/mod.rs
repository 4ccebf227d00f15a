//! Process orchestration: everything about agents that run as OS processes, whatever
//! exchange carries their messages (`ipc`, `uds`, `zenoh`).
//!
//! * [`launcher`]: spawns, supervises and reaps the agent processes of a run;
//! * [`agent`]: the body of `admm-ta agent`;
//! * [`connect`]: the one place that maps a process transport to its exchange;
//! * [`scenario`]: the file the launcher writes for its agents;
//! * [`namespace`]: a run's private iceoryx2 prefix and directory, and their cleanup;
//! * [`member`]: agents started independently from a team file;
//! * `host` and `bridge` (feature `zenoh`): one machine of a multi-host team.

pub mod agent;
pub mod connect;
pub mod launcher;
pub mod member;
pub mod namespace;
pub mod scenario;

#[cfg(feature = "zenoh")]
pub mod bridge;
#[cfg(feature = "zenoh")]
pub mod host;
