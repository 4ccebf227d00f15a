//! A host's Zenoh router: the host's agents connect to it as clients, and it links to the
//! other hosts' routers; it relays every round message between its clients and to the other
//! hosts (see [`crate::zenoh_net::session`] for why agents are not peers).

use crate::zenoh_net::error::ZenohError;
use crate::zenoh_net::links::ZenohLinks;
use crate::zenoh_net::session::{self, Role};
use std::net::TcpListener;
use zenoh::{Session, Wait};

/// A running router; dropping it closes it.
pub struct HostRouter {
    /// Where the host's agents connect.
    pub endpoint: String,
    session: Session,
}

impl HostRouter {
    /// A router listening on `endpoint` and linking to the routers at `others` (retried in
    /// the background until they come up).
    pub fn open(endpoint: &str, others: &[String]) -> Result<Self, ZenohError> {
        let session = session::open(&Role::Router, &[endpoint.to_string()], others)?;
        Ok(Self {
            endpoint: endpoint.to_string(),
            session,
        })
    }

    /// A router on a free port of the loopback interface, for a single-machine run.
    pub fn open_on_loopback() -> Result<Self, ZenohError> {
        // The port is free when asked; another process may take it before Zenoh binds it,
        // so try a few.
        let mut last = None;
        for _ in 0..5 {
            let port = TcpListener::bind("127.0.0.1:0")
                .and_then(|l| l.local_addr())
                .map_err(|e| ZenohError::new("cannot find a free loopback port", e))?
                .port();
            match Self::open(&format!("tcp/127.0.0.1:{port}"), &[]) {
                Ok(router) => return Ok(router),
                Err(e) => last = Some(e),
            }
        }
        Err(last.expect("five tries"))
    }

    /// Announces `agent` as failed on the run of `links`, so that its Zenoh agents stop.
    pub fn announce_failure(&self, links: &ZenohLinks, agent: usize) {
        session::announce_failure(&self.session, links, agent);
    }

    /// Waits until this router has a direct link to `count` other routers, or `deadline`;
    /// returns how many it has. Routes between routers change as links come up (a message
    /// from a host reached over another host goes direct once their link is up), and a
    /// message in flight while routes change can be lost: a team starts once every host
    /// links every other directly.
    pub fn await_routers(&self, count: usize, deadline: std::time::Instant) -> usize {
        loop {
            let linked = self.session.info().routers_zid().wait().count();
            if linked >= count || std::time::Instant::now() >= deadline {
                return linked;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    }

    /// The router's session (the bridge of a mixed-mode host publishes through it).
    pub fn session(&self) -> &Session {
        &self.session
    }
}

impl Drop for HostRouter {
    fn drop(&mut self) {
        session::close(&self.session);
    }
}
