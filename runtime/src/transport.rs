//! What carries a team's messages: the one transport type users choose from, and what each
//! transport can do.
//!
//! Every "which transports can do X" question (a global barrier, round latency, agent
//! processes, fault injection, failure recovery, teams across machines) is answered by
//! [`Transport::capabilities`], never by listing variants. A new transport is one module,
//! one variant here with its capabilities, and — if it runs agent processes — one arm in
//! [`crate::process::connect`].

use serde::{Deserialize, Serialize};

/// What carries the messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Transport {
    /// Lockstep simulation in one thread ([`crate::sim`]).
    #[default]
    Sim,
    /// One OS thread per agent, lock-free slots, crossbeam parkers ([`crate::threads`]).
    Threads,
    /// One OS process per agent, payloads in one shared-memory table of slots read in place,
    /// futex wake-ups: the `threads` protocol across processes, a reference for what a
    /// round between processes costs ([`crate::shm`]).
    Shm,
    /// One OS process per agent, iceoryx2 zero-copy publish-subscribe ([`crate::ipc`]).
    Ipc,
    /// One OS process per agent, every payload copied through Unix-domain sockets: the
    /// baseline that shows what zero-copy saves ([`crate::uds`]).
    Uds,
    /// One OS process per agent, Zenoh publish-subscribe through a router: the transport of
    /// multi-host teams ([`crate::zenoh_net`]; needs the `zenoh` feature).
    Zenoh,
}

/// How a transport runs a team's agents.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Execution {
    /// All agents in one thread, round by round: the run sees the whole team after every
    /// round (central stop rules, the oracle trace) but measures no round latency.
    Lockstep,
    /// One OS thread per agent in this process.
    Threads,
    /// One OS process per agent, started by a launcher from the `admm-ta` binary (or
    /// independently, from a team file).
    Processes,
}

/// What a transport can do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Capabilities {
    pub execution: Execution,
    /// A global barrier after every round (lockstep rounds for latency benchmarks).
    pub global_barrier: bool,
    /// Agents on several machines.
    pub multi_host: bool,
    /// Agent processes honour the `ADMM_TA_FAULT` test switch ([`crate::fault`]).
    pub fault_injection: bool,
    /// When an agent fails, the launcher learns which one (the agents mark the culprit on the
    /// run's shared board), so the survivors can re-solve without it (`--on-failure
    /// continue`).
    pub failure_recovery: bool,
    /// This build carries the transport (Zenoh needs the `zenoh` feature).
    pub built: bool,
}

impl Transport {
    /// Every transport, in the order of the command line's help.
    pub const ALL: [Transport; 6] = [
        Self::Sim,
        Self::Threads,
        Self::Shm,
        Self::Ipc,
        Self::Uds,
        Self::Zenoh,
    ];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sim => "sim",
            Self::Threads => "threads",
            Self::Shm => "shm",
            Self::Ipc => "ipc",
            Self::Uds => "uds",
            Self::Zenoh => "zenoh",
        }
    }

    /// What this transport can do.
    pub fn capabilities(self) -> Capabilities {
        let none = Capabilities {
            execution: Execution::Processes,
            global_barrier: false,
            multi_host: false,
            fault_injection: false,
            failure_recovery: false,
            built: true,
        };
        match self {
            Self::Sim => Capabilities {
                execution: Execution::Lockstep,
                ..none
            },
            Self::Threads => Capabilities {
                execution: Execution::Threads,
                global_barrier: true,
                ..none
            },
            Self::Shm => Capabilities {
                global_barrier: true,
                fault_injection: true,
                ..none
            },
            Self::Ipc => Capabilities {
                global_barrier: true,
                fault_injection: true,
                failure_recovery: true,
                ..none
            },
            Self::Uds => none,
            Self::Zenoh => Capabilities {
                multi_host: true,
                fault_injection: true,
                built: cfg!(feature = "zenoh"),
                ..none
            },
        }
    }

    /// The transports that have `capability`, for messages: `threads, shm or ipc`, `shm, ipc,
    /// uds and zenoh` (`conjunction` joins the last two).
    pub fn names_where(capability: impl Fn(Capabilities) -> bool, conjunction: &str) -> String {
        let names: Vec<&str> = Self::ALL
            .into_iter()
            .filter(|t| capability(t.capabilities()))
            .map(Self::name)
            .collect();
        match names.split_last() {
            None => String::new(),
            Some((last, [])) => (*last).to_string(),
            Some((last, rest)) => format!("{} {conjunction} {last}", rest.join(", ")),
        }
    }
}

impl std::fmt::Display for Transport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(feature = "clap")]
admm_ta_agents::clap_value_enum!(Transport);

/// A name that is no transport.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown transport '{name}' (use {})", Transport::names_where(|_| true, "or"))]
pub struct UnknownTransport {
    pub name: String,
}

impl std::str::FromStr for Transport {
    type Err = UnknownTransport;

    fn from_str(name: &str) -> Result<Self, UnknownTransport> {
        Self::ALL
            .into_iter()
            .find(|t| t.name() == name)
            .ok_or_else(|| UnknownTransport {
                name: name.to_string(),
            })
    }
}

/// A Zenoh entry point in a build without the `zenoh` feature.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "this admm-ta was built without Zenoh support: rebuild with `cargo build --release --features zenoh`"
)]
pub struct ZenohNotBuilt;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_lists_read_as_text() {
        for t in Transport::ALL {
            assert_eq!(t.name().parse::<Transport>(), Ok(t));
            assert_eq!(
                serde_json::to_string(&t).unwrap(),
                format!("\"{}\"", t.name())
            );
        }
        assert!("pigeon".parse::<Transport>().is_err());
        assert_eq!(
            Transport::names_where(|c| c.global_barrier, "or"),
            "threads, shm or ipc"
        );
        assert_eq!(
            Transport::names_where(|c| c.execution == Execution::Processes, "and"),
            "shm, ipc, uds and zenoh"
        );
        assert_eq!(Transport::names_where(|c| c.failure_recovery, "or"), "ipc");
    }
}
