//! Multi-host teams over **Zenoh**: the same round messages as the `ipc` transport, carried
//! between machines by the network engine behind ROS 2's `rmw_zenoh`.
//!
//! * [`error`] (always built): what Zenoh refused, and a build without it;
//! * [`links`] (always built): where an agent's Zenoh session connects and listens, and the
//!   key expressions of a run — plain data that travels in the scenario.
//! * `exchange` (feature `zenoh`): `ZenohExchange`, one agent's
//!   end: it publishes its payload on `admm-ta/<run>/round/<i>` and subscribes to its
//!   neighbours' keys; presence is a Zenoh liveliness token per agent.
//! * `router` (feature `zenoh`): the per-host Zenoh router the host's agents connect to (the
//!   launcher runs one on loopback for single-machine runs; `admm-ta host` runs one per
//!   machine of a multi-host team).
//!
//! * [`process`] (always built): how the process orchestration runs it (the launcher's
//!   loopback router, the agents' connection and blame, failures announced on Zenoh).
//! * [`relay`] (always built): the rate a router relays, which bounds a team's round.
//! * [`wire`] (always built): a round message on Zenoh, coded against the sender's last.
//!
//! The hosts of a multi-host team and the mixed mode's bridge (iceoryx2 within a host, Zenoh
//! between hosts) use both transports, so they live above them, in the runtime (`admm_ta_runtime::host`).
//!
//! Built without the `zenoh` feature, every Zenoh entry point fails with
//! [`ZenohNotBuilt`](error::ZenohNotBuilt).

pub mod error;
pub mod links;
pub mod process;
pub mod relay;
pub mod wire;

#[cfg(feature = "zenoh")]
pub mod exchange;
#[cfg(feature = "zenoh")]
pub mod router;
#[cfg(feature = "zenoh")]
pub mod session;

/// The `zenoh` transport's declaration.
pub const INFO: crate::endpoint::TransportInfo = crate::endpoint::TransportInfo {
    name: "zenoh",
    capabilities: crate::endpoint::Capabilities {
        multi_host: true,
        fault_injection: true,
        built: cfg!(feature = "zenoh"),
        ..crate::endpoint::Capabilities::PROCESSES
    },
    processes: Some(&process::ZenohProcesses),
};
