//! The `zenoh` transport as the process orchestration sees it. Its agents do not use the
//! run's shared board: a launcher runs a router on loopback for them (its links go into the
//! scenario), and failures and stop requests travel on Zenoh, so the launcher listens for
//! the agents' announcements and announces its own verdict there.
//!
//! Open files per agent process about `64 + degree` (the threads and sockets of Zenoh's
//! runtime), and 16 threads.

use crate::endpoint::{
    AgentEndpoint, ConnectError, ConnectRequest, ProcessTransport, RunRequest, RunSupport,
    SupportError,
};
use std::time::Instant;

/// The `zenoh` transport's processes.
pub struct ZenohProcesses;

impl ProcessTransport for ZenohProcesses {
    fn files_per_agent(&self, degree: usize) -> u64 {
        64 + degree as u64
    }

    fn threads_per_agent(&self) -> u64 {
        16
    }

    fn uses_board(&self) -> bool {
        false
    }

    /// Every message goes through the run's router.
    fn relay_bytes_per_second(&self) -> Option<f64> {
        Some(super::relay::RELAY_BYTES_PER_SECOND)
    }

    #[cfg(feature = "zenoh")]
    fn start_support(&self, run: &RunRequest) -> Result<Box<dyn RunSupport>, SupportError> {
        Ok(Box::new(built::LoopbackRouter::start(
            &run.run_id,
            run.degrees.len(),
        )?))
    }

    #[cfg(not(feature = "zenoh"))]
    fn start_support(&self, _run: &RunRequest) -> Result<Box<dyn RunSupport>, SupportError> {
        Err(SupportError::new(RouterNotBuilt(
            super::error::ZenohNotBuilt,
        )))
    }

    #[cfg(feature = "zenoh")]
    fn connect(
        &self,
        request: &ConnectRequest,
        deadline: Instant,
    ) -> Result<Box<dyn AgentEndpoint>, ConnectError> {
        let links: super::links::ZenohLinks = request
            .config
            .clone()
            .and_then(|config| serde_json::from_value(config).ok())
            .ok_or(ConnectError::setup(
                "scenario is inconsistent: a Zenoh run without Zenoh endpoints",
            ))?;
        Ok(Box::new(super::exchange::ZenohExchange::connect(
            request, &links, deadline,
        )?))
    }

    #[cfg(not(feature = "zenoh"))]
    fn connect(
        &self,
        _request: &ConnectRequest,
        _deadline: Instant,
    ) -> Result<Box<dyn AgentEndpoint>, ConnectError> {
        Err(ConnectError::Refused(Box::new(super::error::ZenohNotBuilt)))
    }
}

/// A launcher's Zenoh router in a build without Zenoh.
#[derive(Debug, thiserror::Error)]
#[error("cannot start the run's Zenoh router")]
pub struct RouterNotBuilt(#[source] pub super::error::ZenohNotBuilt);

/// The router could not be started.
#[derive(Debug, thiserror::Error)]
#[error("cannot start the run's Zenoh router: {0}")]
pub struct RouterFailed(pub super::error::ZenohError);

#[cfg(feature = "zenoh")]
mod built {
    use super::{RouterFailed, RunSupport, SupportError};
    use crate::endpoint::AgentEndpoint;
    use crate::endpoint::culprit;
    use crate::exchange::{Exchange, ExchangeError};
    use crate::zenoh_net::exchange::ZenohExchange;
    use crate::zenoh_net::links::ZenohLinks;
    use crate::zenoh_net::router::HostRouter;
    use crate::zenoh_net::session::{self, watch_failures};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::{Duration, Instant};

    /// A launcher's router on loopback, and the first failure the agents announced on it.
    pub(super) struct LoopbackRouter {
        router: HostRouter,
        links: ZenohLinks,
        /// The first agent announced as failed, `usize::MAX` if none.
        first: Arc<AtomicUsize>,
        /// This process sized its Zenoh runtime for the router (not for its agents).
        sized: bool,
        _subscriber: zenoh::pubsub::Subscriber<()>,
    }

    impl LoopbackRouter {
        /// The router of a run of `agents` agents, each one link to it.
        ///
        /// Its receive runtime gets a worker per link where this process may still set
        /// its environment ([`session::size_router_runtime_if_alone`]): a router forwards
        /// on the receiving link's worker, and a push into a congested agent's link blocks
        /// that worker. With Zenoh's two workers, 200 agents of 320 kB messages blocked both
        /// and the router read no link for 10 s: it expired the agents' leases, their
        /// tokens vanished and their reconnected sessions' messages were misrouted
        /// (issue 49).
        pub(super) fn start(run_id: &str, agents: usize) -> Result<Self, SupportError> {
            let failed = |e| SupportError::new(RouterFailed(e));
            let sized = session::size_router_runtime_if_alone(agents);
            if !sized {
                tracing::debug!(
                    agents,
                    "the run's Zenoh router keeps the process's receive runtime (ZENOH_RUNTIME set, or other threads run)"
                );
            }
            let router = HostRouter::open_on_loopback().map_err(failed)?;
            let links = ZenohLinks {
                key_prefix: format!("admm-ta/run/{run_id}"),
                connect: vec![router.endpoint.clone()],
                hosts: Vec::new(),
                epoch: None,
            };
            let first = Arc::new(AtomicUsize::new(usize::MAX));
            let subscriber = {
                let first = Arc::clone(&first);
                watch_failures(router.session(), &links, move |a, _| {
                    let _ =
                        first.compare_exchange(usize::MAX, a, Ordering::AcqRel, Ordering::Acquire);
                })
                .map_err(failed)?
            };
            Ok(Self {
                router,
                links,
                first,
                sized,
                _subscriber: subscriber,
            })
        }
    }

    impl RunSupport for LoopbackRouter {
        fn scenario_config(&self) -> Option<serde_json::Value> {
            serde_json::to_value(&self.links).ok()
        }

        /// The announcement travels through the router while the announcing agent exits.
        fn announced_failure(&self, within: Duration) -> Option<usize> {
            let until = Instant::now() + within;
            loop {
                let agent = self.first.load(Ordering::Acquire);
                if agent != usize::MAX {
                    return Some(agent);
                }
                if Instant::now() >= until {
                    return None;
                }
                std::thread::sleep(Duration::from_millis(2));
            }
        }

        fn announce_failure(&self, agent: usize) {
            self.router.announce_failure(&self.links, agent);
        }

        fn unset_for_agents(&self) -> Option<&'static str> {
            self.sized.then_some(session::RUNTIME_VARIABLE)
        }
    }

    impl AgentEndpoint for ZenohExchange {
        fn exchange(&mut self) -> &mut dyn Exchange {
            self
        }

        fn announce_stop(&self, signal: i32) {
            self.request_stop(signal);
        }

        /// No launcher sees every host: whoever fails first tells the others. After a
        /// timeout, not before the network had a lease to say who is gone
        /// ([`ZenohExchange::timeout_culprit`]): the neighbour waited for may be waiting
        /// itself for an agent cut off.
        fn blame_for(&self, error: &ExchangeError) {
            let culprit = match error {
                ExchangeError::Aborted { .. } => return,
                // Possibly seen only by us (its token vanished): pass it on.
                ExchangeError::PeerFailed { failed, .. } => Some(*failed),
                ExchangeError::Timeout { round, .. } => match self.timeout_culprit(*round) {
                    Some(culprit) => Some(culprit),
                    // Another agent or a host named the failure first.
                    None => return,
                },
                e => culprit(e),
            };
            self.blame(culprit.unwrap_or(error.agent()));
        }

        fn check(&self) -> Result<(), ExchangeError> {
            self.announced()
        }
    }
}
