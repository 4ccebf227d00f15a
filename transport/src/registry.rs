//! What carries a team's messages: the one transport type users choose from, and what each
//! transport can do.
//!
//! Every "which transports can do X" question (a global barrier, round latency, agent
//! processes, fault injection, failure recovery, teams across machines) is answered by
//! [`Transport::capabilities`], never by listing variants. A new transport is one module
//! that declares its [`TransportInfo`] (and implements [`ProcessTransport`] if its agents
//! are processes) and one line in the registry below.

use crate::endpoint::{ProcessTransport, TransportInfo};
use serde::{Deserialize, Serialize};

use crate::endpoint::Capabilities;
#[cfg(test)]
use crate::endpoint::Execution;

/// The registry: one line per transport, `Variant => its module's INFO`, in the order of the
/// command line's help. Everything else about a transport is declared by its module.
macro_rules! transports {
    ($($(#[$doc:meta])* $variant:ident => $info:path,)+) => {
        /// What carries the messages.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
        #[serde(rename_all = "kebab-case")]
        pub enum Transport {
            #[default]
            $($(#[$doc])* $variant,)+
        }

        impl Transport {
            /// Every transport, in the order of the command line's help.
            pub const ALL: &'static [Transport] = &[$(Self::$variant,)+];

            /// What the transport declares about itself.
            pub fn info(self) -> &'static TransportInfo {
                match self {
                    $(Self::$variant => &$info,)+
                }
            }
        }
    };
}

transports! {
    /// Lockstep simulation in one thread ([`crate::sim`]).
    Sim => crate::sim::INFO,
    /// One OS thread per agent, lock-free slots, crossbeam parkers ([`crate::threads`]).
    Threads => crate::threads::INFO,
    /// One OS process per agent, payloads in one shared-memory table of slots read in place,
    /// futex wake-ups: the `threads` protocol across processes, a reference for what a
    /// round between processes costs ([`crate::shm`]).
    Shm => crate::shm::INFO,
    /// One OS process per agent, iceoryx2 zero-copy publish-subscribe ([`crate::ipc`]).
    Ipc => crate::ipc::INFO,
    /// One OS process per agent, every payload copied through Unix-domain sockets: the
    /// baseline that shows what zero-copy saves ([`crate::uds`]).
    Uds => crate::uds::INFO,
    /// One OS process per agent, Zenoh publish-subscribe through a router: the transport of
    /// multi-host teams ([`crate::zenoh_net`]; needs the `zenoh` feature).
    Zenoh => crate::zenoh_net::INFO,
}

impl Transport {
    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// What this transport can do.
    pub fn capabilities(self) -> Capabilities {
        self.info().capabilities
    }

    /// How its agent processes connect (`None`: its agents are not processes).
    pub fn processes(self) -> Option<&'static dyn ProcessTransport> {
        self.info().processes
    }

    /// The transports that have `capability`, for messages: `threads, shm or ipc`, `shm, ipc,
    /// uds and zenoh` (`conjunction` joins the last two).
    pub fn names_where(capability: impl Fn(Capabilities) -> bool, conjunction: &str) -> String {
        let names: Vec<&str> = Self::ALL
            .iter()
            .filter(|t| capability(t.capabilities()))
            .map(|t| t.name())
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
            .iter()
            .copied()
            .find(|t| t.name() == name)
            .ok_or_else(|| UnknownTransport {
                name: name.to_string(),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_lists_read_as_text() {
        for &t in Transport::ALL {
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
