//! Process orchestration: everything about agents that run as OS processes, whatever
//! transport carries their messages (each process transport is reached only through its
//! [`admm_ta_transport::endpoint::ProcessTransport`]).
//!
//! * [`launcher`]: spawns, supervises and reaps the agent processes of a run;
//! * [`supervise`]: the launcher's supervision of its agents (reaping, blame, grace period);
//! * [`limits`]: open files and processes a team needs, checked before spawning;
//! * [`agent`]: the body of `admm-ta agent`;
//! * [`member_error`]: why an agent or host process ended without its result (refused or failed);
//! * [`connect`]: how an agent connects its end of any process transport, and what a run's
//!   transport needs before and beside its agents;
//! * [`stop`]: how a run stops on a termination signal, and what children's states say;
//! * [`scenario`]: the file the launcher writes for its agents;
//! * [`namespace`]: a run's private prefix and directory, and their cleanup;
//! * [`private_dir`]: the user's private base directory, exclusive files, verified reads;
//! * [`team_digest`]: a team's identity, checked by every agent before round 0.

pub mod agent;
pub mod connect;
pub mod launcher;
pub mod limits;
pub mod member_error;
pub mod namespace;
pub mod private_dir;
pub mod scenario;
pub mod stop;
pub mod supervise;
pub mod team_digest;
