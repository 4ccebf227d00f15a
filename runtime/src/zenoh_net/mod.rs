//! Multi-host teams over **Zenoh**: the same round messages as the `ipc` transport, carried
//! between machines by the network engine behind ROS 2's `rmw_zenoh`.
//!
//! * [`links`] (always built): where an agent's Zenoh session connects and listens, and the
//!   key expressions of a run — plain data that travels in the scenario.
//! * `exchange` (feature `zenoh`): [`ZenohExchange`](exchange::ZenohExchange), one agent's
//!   end: it publishes its payload on `admm-ta/<run>/round/<i>` and subscribes to its
//!   neighbours' keys; presence is a Zenoh liveliness token per agent.
//! * `router` (feature `zenoh`): the per-host Zenoh router the host's agents connect to (the
//!   launcher runs one on loopback for single-machine runs; `admm-ta host` runs one per
//!   machine of a multi-host team).
//!
//! * [`process`] (always built): how the process orchestration runs it (the launcher's
//!   loopback router, the agents' connection and blame, failures announced on Zenoh).
//!
//! The hosts of a multi-host team and the mixed mode's bridge (iceoryx2 within a host, Zenoh
//! between hosts) use both transports, so they live above them, in [`crate::team`].
//!
//! Built without the `zenoh` feature, every Zenoh entry point fails with [`ZenohNotBuilt`].

pub mod links;
pub mod process;

#[cfg(feature = "zenoh")]
pub mod exchange;
#[cfg(feature = "zenoh")]
pub mod router;
#[cfg(feature = "zenoh")]
pub(crate) mod session;

/// A Zenoh entry point in a build without the `zenoh` feature.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "this admm-ta was built without Zenoh support: rebuild with `cargo build --release --features zenoh`"
)]
pub struct ZenohNotBuilt;

/// What Zenoh refused, with Zenoh's own words.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what}: {detail}")]
pub struct ZenohError {
    /// What was tried.
    pub what: String,
    /// Zenoh's error, as its text (Zenoh's errors are neither `Clone` nor `PartialEq`).
    pub detail: String,
}

impl ZenohError {
    pub fn new(what: impl Into<String>, error: impl std::fmt::Display) -> Self {
        Self {
            what: what.into(),
            detail: error.to_string(),
        }
    }
}
