//! The `ipc` transport: one OS process per agent over iceoryx2 zero-copy publish-subscribe.
//!
//! * [`transport`]: an agent's iceoryx2 ports (the [`crate::exchange::Exchange`]);
//! * [`namespace`]: a run's private iceoryx2 prefix and directory, and their cleanup;
//! * [`scenario`]: the file the launcher writes for its agents;
//! * [`launcher`]: spawns, supervises and reaps the agent processes;
//! * [`agent_process`]: the body of `admm-ta agent`;
//! * [`fault`]: fault injection for tests.

pub mod agent_process;
pub mod fault;
pub mod launcher;
pub mod member;
pub mod namespace;
pub mod scenario;
pub mod transport;
