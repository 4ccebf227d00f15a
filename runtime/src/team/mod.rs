//! Teams of independently started agents: a team file names the team, its method, its
//! transport and (across machines) its hosts; each agent, host and bridge derives its run
//! from it.
//!
//! * [`team_file`]: the team file, and what every member derives from it;
//! * [`errors`]: their errors, one type per operation;
//! * `hosts`: a team file's hosts (robots by name or number, one host per robot);
//! * [`member`]: agents started independently from a team file (joining, leaving, collecting);
//! * [`team_timeline`]: the trace `collect` writes, hosts' clocks aligned;
//! * `host` and `bridge` (feature `zenoh`): one machine of a multi-host team — its Zenoh
//!   router, and the bridge that carries a mixed team's messages between a host's iceoryx2
//!   services and the other hosts (the one place that uses two transports at once); with
//!   `presence` (what a host knows of its team), `priority` (a host runs ahead of its
//!   agents), `census` and `host_digest`.

pub mod errors;
mod hosts;
pub mod member;
pub mod team_file;
pub mod team_timeline;
pub(crate) mod zenoh_plane;

#[cfg(feature = "zenoh")]
pub mod bridge;
#[cfg(feature = "zenoh")]
mod census;
#[cfg(feature = "zenoh")]
pub mod host;
#[cfg(feature = "zenoh")]
mod host_digest;
#[cfg(feature = "zenoh")]
mod presence;
#[cfg(feature = "zenoh")]
mod priority;
#[cfg(feature = "zenoh")]
mod standing_host;
