//! The iceoryx2 services of a run: their names, and how every participant (agents, the
//! mixed mode's bridge) opens them with the same limits (iceoryx2 refuses mismatched ones).

use crate::exchange::header::RoundHeader;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::EventOpenOrCreateError;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenOrCreateError;
use iceoryx2::service::service_name::ServiceNameError;

/// The iceoryx2 service flavour of every run (inter-process).
pub(crate) type Svc = ipc::Service;

/// Samples a subscriber may hold unread and borrowed at once (see [`crate::ipc::exchange`]).
pub(crate) const SUBSCRIBER_BUFFER: usize = 2;
const SUBSCRIBER_BORROWED: usize = 2;

/// Name of agent `i`'s round-message service.
pub fn round_service(i: usize) -> String {
    format!("admm-ta/{i}/round")
}

/// Name of agent `i`'s wake-up event service.
pub fn wake_service(i: usize) -> String {
    format!("admm-ta/{i}/wake")
}

const BARRIER_SERVICE: &str = "admm-ta/barrier";

/// Event service waking a mixed-mode host's bridge ([`crate::zenoh_net`]): agents with
/// neighbours on other hosts notify it after every publish.
pub const BRIDGE_WAKE_SERVICE: &str = "admm-ta/bridge/wake";

/// A service of the run that cannot be opened.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ServiceError {
    #[error("bad service name {name}")]
    Name {
        name: String,
        #[source]
        source: ServiceNameError,
    },
    #[error("cannot open service {name}")]
    PublishSubscribe {
        name: String,
        #[source]
        source: PublishSubscribeOpenOrCreateError,
    },
    #[error("cannot open service {name}")]
    Event {
        name: String,
        #[source]
        source: EventOpenOrCreateError,
    },
}

impl ServiceError {
    /// A race with another process opening, creating or removing the same service (under
    /// load, its creation can outlast iceoryx2's creation timeout): worth retrying.
    pub(crate) fn is_transient(&self) -> bool {
        let text = format!("{self:?}");
        [
            "DoesNotExist",
            "IsBeingCreatedByAnotherInstance",
            "HangsInCreation",
            "IsMarkedForDestruction",
            "AlreadyExists",
            "SystemInFlux",
            "InitializationNotYetFinalized",
        ]
        .iter()
        .any(|race| text.contains(race))
    }
}

/// Calls `open` until it succeeds, fails for good, or `deadline` passes (transient races
/// are retried).
pub(crate) fn retry_until<T>(
    deadline: std::time::Instant,
    mut open: impl FnMut() -> Result<T, ServiceError>,
) -> Result<T, ServiceError> {
    loop {
        match open() {
            Err(e) if e.is_transient() && std::time::Instant::now() < deadline => {
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
            done => return done,
        }
    }
}

/// Opens (or creates) agent `j`'s round-message service from `node`; `degree` is `j`'s.
/// Every participant opens it with these limits (iceoryx2 refuses mismatched ones).
pub(crate) fn open_round_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    j: usize,
    degree: usize,
) -> Result<
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<S, [f64], RoundHeader>,
    ServiceError,
> {
    let name = round_service(j);
    let service = ServiceName::new(&name).map_err(|source| ServiceError::Name {
        name: name.clone(),
        source,
    })?;
    node.service_builder(&service)
        .publish_subscribe::<[f64]>()
        .user_header::<RoundHeader>()
        .max_publishers(1)
        .max_subscribers(degree.max(1))
        .max_nodes(degree + 1)
        .subscriber_max_buffer_size(SUBSCRIBER_BUFFER)
        .subscriber_max_borrowed_samples(SUBSCRIBER_BORROWED)
        .history_size(0)
        .enable_safe_overflow(false)
        .open_or_create()
        .map_err(|source| ServiceError::PublishSubscribe { name, source })
}

/// Opens (or creates) an event service `name` for `notifiers` notifiers, `listeners`
/// listeners and `nodes` nodes.
fn open_event_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    name: String,
    listeners: usize,
    notifiers: usize,
    nodes: usize,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<S>, ServiceError> {
    let service = ServiceName::new(&name).map_err(|source| ServiceError::Name {
        name: name.clone(),
        source,
    })?;
    node.service_builder(&service)
        .event()
        .max_listeners(listeners)
        .max_notifiers(notifiers)
        .max_nodes(nodes)
        .open_or_create()
        .map_err(|source| ServiceError::Event { name, source })
}

/// Opens (or creates) agent `j`'s wake-up event service from `node`; `degree` is `j`'s.
pub(crate) fn open_wake_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    j: usize,
    degree: usize,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<S>, ServiceError> {
    open_event_service(node, wake_service(j), 1, degree.max(1), degree + 1)
}

/// Opens (or creates) the bridge's wake-up service of a team of `agents`.
pub(crate) fn open_bridge_wake_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    agents: usize,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<S>, ServiceError> {
    open_event_service(
        node,
        BRIDGE_WAKE_SERVICE.into(),
        1,
        agents.max(1),
        agents + 1,
    )
}

/// Opens (or creates) the run's global-barrier event service for `parties` agents.
pub(crate) fn open_barrier_service(
    node: &Node<Svc>,
    parties: usize,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<Svc>, ServiceError> {
    open_event_service(node, BARRIER_SERVICE.into(), parties, parties, parties)
}
