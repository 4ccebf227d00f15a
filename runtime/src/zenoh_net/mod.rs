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
//! The hosts of a multi-host team and the mixed mode's bridge (iceoryx2 within a host, Zenoh
//! between hosts) use both transports, so they live above them, in [`crate::process`].
//!
//! Built without the `zenoh` feature, every Zenoh entry point fails with
//! [`crate::transport::ZenohNotBuilt`].

pub mod links;

#[cfg(feature = "zenoh")]
pub mod exchange;
#[cfg(feature = "zenoh")]
pub mod router;
#[cfg(feature = "zenoh")]
pub(crate) mod session;
