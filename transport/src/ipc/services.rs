//! The iceoryx2 services of a run: their names, their limits, who creates them and how
//! everybody else opens them.
//!
//! The launcher (or, in a team started without one, the first member under the team's lock)
//! creates every service of the run with [`RunServices::create`] *before* any agent starts,
//! and keeps them until the run ends; agents (and a mixed host's bridge) only `open` them.
//! So there is no open/create race between agents (iceoryx2 resolves one by sleeping and
//! retrying), and an agent never waits for a neighbour to create a service. Wake-ups are not
//! iceoryx2 events but futex words of the run's board ([`crate::board`]); the one event
//! service left wakes a mixed host's bridge.

use crate::exchange::header::RoundHeader;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError};
use iceoryx2::service::builder::publish_subscribe::{
    Builder as PubSubBuilder, PublishSubscribeCreateError, PublishSubscribeOpenError,
};
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use iceoryx2::service::service_name::ServiceNameError;

/// The iceoryx2 service flavour of every run (inter-process).
pub type Svc = ipc::Service;

/// An agent's round-message service.
pub type RoundService<S> = PubSubFactory<S, [f64], RoundHeader>;

/// Samples a subscriber may hold unread, and borrowed, at once: a neighbour is at most one
/// round ahead (the neighbour barrier), so an agent holds the current round's sample and at
/// most one of the next round (see [`crate::ipc::exchange`]).
pub const SUBSCRIBER_BUFFER: usize = 2;
pub const SUBSCRIBER_BORROWED: usize = 2;

/// Name of agent `i`'s round-message service.
pub fn round_service(i: usize) -> String {
    format!("admm-ta/{i}/round")
}

/// Event service waking a mixed-mode host's bridge ([`crate::zenoh_net`]): agents with
/// neighbours on other hosts notify it after every publish.
pub const BRIDGE_WAKE_SERVICE: &str = "admm-ta/bridge/wake";

/// A service of the run that cannot be created or opened.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ServiceError {
    #[error("bad service name {name}")]
    Name {
        name: String,
        #[source]
        source: ServiceNameError,
    },
    #[error("cannot open service {name} (the run's launcher creates it)")]
    Open {
        name: String,
        #[source]
        source: PublishSubscribeOpenError,
    },
    #[error("cannot create service {name}")]
    Create {
        name: String,
        #[source]
        source: PublishSubscribeCreateError,
    },
    #[error("cannot open service {name} (the run's launcher creates it)")]
    OpenEvent {
        name: String,
        #[source]
        source: EventOpenError,
    },
    #[error("cannot create service {name}")]
    CreateEvent {
        name: String,
        #[source]
        source: EventCreateError,
    },
    #[error("cannot create the iceoryx2 node that owns the run's services: {0}")]
    Node(String),
}

fn service_name(name: &str) -> Result<ServiceName, ServiceError> {
    ServiceName::new(name).map_err(|source| ServiceError::Name {
        name: name.to_string(),
        source,
    })
}

/// Agent `j`'s round-message service with its limits (`degree` is `j`'s): one publisher (the
/// agent, or a bridge standing in for it), one subscriber per neighbour, nodes: the
/// publisher's, the neighbours' and the creator's; no history, no safe overflow (a sample
/// that does not reach every subscriber is an error, never a silently lost round).
fn round_builder<S: iceoryx2::service::Service>(
    node: &Node<S>,
    name: &ServiceName,
    degree: usize,
) -> PubSubBuilder<[f64], RoundHeader, S> {
    node.service_builder(name)
        .publish_subscribe::<[f64]>()
        .user_header::<RoundHeader>()
        .max_publishers(1)
        .max_subscribers(degree.max(1))
        .max_nodes(degree + 2)
        .subscriber_max_buffer_size(SUBSCRIBER_BUFFER)
        .subscriber_max_borrowed_samples(SUBSCRIBER_BORROWED)
        .history_size(0)
        .enable_safe_overflow(false)
}

/// Opens agent `j`'s round-message service (created by the run's creator) from `node`;
/// `degree` is `j`'s.
pub fn open_round_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    j: usize,
    degree: usize,
) -> Result<RoundService<S>, ServiceError> {
    let name = round_service(j);
    round_builder(node, &service_name(&name)?, degree)
        .open()
        .map_err(|source| ServiceError::Open { name, source })
}

/// The bridge's wake-up service of a team of `agents`: one listener (the bridge), a notifier
/// per agent, nodes: the agents', the bridge's and the creator's.
fn bridge_wake_builder<S: iceoryx2::service::Service>(
    node: &Node<S>,
    name: &ServiceName,
    agents: usize,
) -> iceoryx2::service::builder::event::Builder<S> {
    node.service_builder(name)
        .event()
        .max_listeners(1)
        .max_notifiers(agents.max(1))
        .max_nodes(agents + 2)
}

/// Opens the bridge's wake-up service of a team of `agents` (created by the run's creator).
pub fn open_bridge_wake_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    agents: usize,
) -> Result<EventFactory<S>, ServiceError> {
    bridge_wake_builder(node, &service_name(BRIDGE_WAKE_SERVICE)?, agents)
        .open()
        .map_err(|source| ServiceError::OpenEvent {
            name: BRIDGE_WAKE_SERVICE.into(),
            source,
        })
}

/// Every iceoryx2 service of a run, created before its agents start and kept until they are
/// gone (a service lives while a node holds it): the launcher's, or a team's first member's.
pub struct RunServices {
    // Services first: they must drop before their node.
    _round: Vec<RoundService<Svc>>,
    _bridge: Option<EventFactory<Svc>>,
    _node: Node<Svc>,
}

impl RunServices {
    /// Creates, in the run of `config`, the round service of every agent (`degrees[j]` is
    /// agent `j`'s degree) and, with `bridge`, the bridge's wake-up service.
    pub fn create(config: &Config, degrees: &[usize], bridge: bool) -> Result<Self, ServiceError> {
        let node = NodeBuilder::new()
            .name(&NodeName::new("creator").map_err(|e| ServiceError::Node(format!("{e:?}")))?)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .config(config)
            .create::<Svc>()
            .map_err(|e| ServiceError::Node(format!("{e:?}")))?;
        let mut round = Vec::with_capacity(degrees.len());
        for (j, &degree) in degrees.iter().enumerate() {
            let name = round_service(j);
            round.push(
                round_builder(&node, &service_name(&name)?, degree)
                    .create()
                    .map_err(|source| ServiceError::Create { name, source })?,
            );
        }
        let bridge = if bridge {
            Some(
                bridge_wake_builder(&node, &service_name(BRIDGE_WAKE_SERVICE)?, degrees.len())
                    .create()
                    .map_err(|source| ServiceError::CreateEvent {
                        name: BRIDGE_WAKE_SERVICE.into(),
                        source,
                    })?,
            )
        } else {
            None
        };
        Ok(Self {
            _round: round,
            _bridge: bridge,
            _node: node,
        })
    }
}
