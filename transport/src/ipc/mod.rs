//! The `ipc` transport: one OS process per agent over iceoryx2 zero-copy publish-subscribe.
//!
//! * [`exchange`]: an agent's iceoryx2 ports (the [`crate::exchange::Exchange`]);
//! * [`services`]: the run's iceoryx2 services, created by the launcher (or a team's first
//!   member) before the agents start and only opened by them;
//! * [`process`]: how the process orchestration runs it (the services before the agents,
//!   the agents' connection and blame, the dead nodes' cleanup);
//! * [`nodes`]: the run's iceoryx2 configuration, node names and dead-node scans.
//!
//! The run's shared board lives in [`crate::board`] (the `uds` transport and the process
//! orchestration use it too).

pub mod exchange;
pub mod nodes;
pub mod process;
pub mod services;

/// The `ipc` transport's declaration.
pub const INFO: crate::endpoint::TransportInfo = crate::endpoint::TransportInfo {
    name: "ipc",
    capabilities: crate::endpoint::Capabilities {
        global_barrier: true,
        fault_injection: true,
        failure_recovery: true,
        ..crate::endpoint::Capabilities::PROCESSES
    },
    processes: Some(&process::IpcProcesses),
};
