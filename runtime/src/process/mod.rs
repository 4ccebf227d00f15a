//! Process orchestration: everything about agents that run as OS processes, whatever
//! exchange carries their messages (`ipc`, `uds`, `zenoh`).
//!
//! * [`launcher`]: spawns, supervises and reaps the agent processes of a run;
//! * [`limits`]: open files and processes a team needs, checked before spawning;
//! * [`agent`]: the body of `admm-ta agent`;
//! * [`member_error`]: why an agent or host process ended without its result (refused or failed);
//! * [`connect`]: the one place that maps a process transport to its exchange;
//! * [`stop`]: how a run stops on a termination signal, and what children's states say;
//! * [`scenario`]: the file the launcher writes for its agents;
//! * [`namespace`]: a run's private iceoryx2 prefix and directory, and their cleanup;
//! * [`private_dir`]: the user's private base directory, exclusive files, verified reads;
//! * [`team_digest`]: a team's identity, checked by every agent before round 0;
//! * [`team_file`]: the team file of independently started agents, and what they derive from it;
//! * [`member`]: agents started independently from a team file (joining, leaving, collecting);
//! * `host` and `bridge` (feature `zenoh`): one machine of a multi-host team.

pub mod agent;
pub mod connect;
pub mod launcher;
pub mod limits;
pub mod member;
pub mod member_error;
pub mod namespace;
pub mod private_dir;
pub mod scenario;
pub mod stop;
pub mod team_digest;
pub mod team_file;

#[cfg(feature = "zenoh")]
pub mod bridge;
#[cfg(feature = "zenoh")]
pub mod host;
