//! The iceoryx2 services of a run: their names, and how every participant (agents, the
//! mixed mode's bridge) opens them with the same limits (iceoryx2 refuses mismatched ones).

use crate::exchange::header::RoundHeader;
use iceoryx2::prelude::*;

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

/// Opens (or creates) agent `j`'s round-message service from `node`; `degree` is `j`'s.
/// Every participant opens it with these limits (iceoryx2 refuses mismatched ones).
pub(crate) fn open_round_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    j: usize,
    degree: usize,
) -> Result<
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<S, [f64], RoundHeader>,
    String,
> {
    let name =
        ServiceName::new(&round_service(j)).map_err(|e| format!("bad service name: {e:?}"))?;
    node.service_builder(&name)
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
        .map_err(|e| format!("cannot open service {}: {e:?}", round_service(j)))
}

/// Opens (or creates) agent `j`'s wake-up event service from `node`; `degree` is `j`'s.
pub(crate) fn open_wake_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    j: usize,
    degree: usize,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<S>, String> {
    let name =
        ServiceName::new(&wake_service(j)).map_err(|e| format!("bad service name: {e:?}"))?;
    node.service_builder(&name)
        .event()
        .max_listeners(1)
        .max_notifiers(degree.max(1))
        .max_nodes(degree + 1)
        .open_or_create()
        .map_err(|e| format!("cannot open service {}: {e:?}", wake_service(j)))
}

/// Opens (or creates) the bridge's wake-up service of a team of `agents`.
pub(crate) fn open_bridge_wake_service<S: iceoryx2::service::Service>(
    node: &Node<S>,
    agents: usize,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<S>, String> {
    let name =
        ServiceName::new(BRIDGE_WAKE_SERVICE).map_err(|e| format!("bad service name: {e:?}"))?;
    node.service_builder(&name)
        .event()
        .max_listeners(1)
        .max_notifiers(agents.max(1))
        .max_nodes(agents + 1)
        .open_or_create()
        .map_err(|e| format!("cannot open service {BRIDGE_WAKE_SERVICE}: {e:?}"))
}

/// Opens (or creates) the run's global-barrier event service for `parties` agents.
pub(crate) fn open_barrier_service(
    node: &Node<Svc>,
    parties: usize,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<Svc>, String> {
    let name = ServiceName::new(BARRIER_SERVICE).map_err(|e| format!("bad service name: {e:?}"))?;
    node.service_builder(&name)
        .event()
        .max_listeners(parties)
        .max_notifiers(parties)
        .max_nodes(parties)
        .open_or_create()
        .map_err(|e| format!("cannot open the barrier service: {e:?}"))
}
