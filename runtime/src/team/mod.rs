//! Teams of independently started agents: a team file names the team, its method, its
//! transport and (across machines) its hosts; each agent derives its run from it.
//!
//! * [`team_file`]: the team file, and what every member derives from it;
//! * [`errors`]: their errors, one type per operation;
//! * `hosts`: a team file's hosts (robots by name or number, one host per robot);
//! * [`membership`]: agents started independently from a team file (joining, running,
//!   leaving);
//! * [`collect`]: the team's assignment assembled from their results;
//! * [`team_timeline`]: the trace `collect` writes, hosts' clocks aligned.
//!
//! The machines of a multi-host team (their routers and bridges) are the `host` module
//! (feature `zenoh`).

pub mod collect;
pub mod errors;
mod hosts;
pub mod membership;
pub mod team_file;
pub mod team_timeline;
