//! What carries a team's messages: the one transport type users choose from.

use serde::Serialize;

/// What carries the messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Transport {
    /// Lockstep simulation in one thread.
    #[default]
    Sim,
    /// One OS thread per agent, lock-free slots, crossbeam parkers.
    Threads,
    /// One OS process per agent, iceoryx2 zero-copy publish-subscribe.
    Ipc,
    /// One OS process per agent, every payload copied through Unix-domain sockets: the
    /// baseline that shows what zero-copy saves ([`crate::uds`]).
    Uds,
    /// One OS process per agent, Zenoh publish-subscribe through a router: the transport of
    /// multi-host teams ([`crate::zenoh_net`]; needs the `zenoh` feature).
    Zenoh,
}

impl Transport {
    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sim => "sim",
            Self::Threads => "threads",
            Self::Ipc => "ipc",
            Self::Uds => "uds",
            Self::Zenoh => "zenoh",
        }
    }
}
