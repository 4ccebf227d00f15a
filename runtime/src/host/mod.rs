//! `admm-ta host --team FILE --name NAME`: what one machine of a multi-host team runs next to
//! its agents. It runs the host's Zenoh router (listening on the host's endpoint, linking
//! to the other hosts' routers) and, in a mixed team, the host's bridge. It watches the
//! team's liveliness tokens: once every agent of the team has shown up and left again, the
//! run is over and it returns; a failure announced by any agent is reported. Agents declare
//! their tokens only once every host's token is up, and a host declares its token after its
//! subscriptions, so no agent can come and go unseen.
//!
//! Before its token, a host announces its team file's digest and start time and waits for
//! the other hosts' announcements: a host whose file differs from that of a host that started
//! earlier is refused by name (as an `ipc` agent of another team is by the board's digest),
//! and agents compare theirs with the first host's before they join.
//!
//! Its start-up is here, in named steps. The rest of the folder:
//!
//! * `run_watch`: its watch of a team's one run; `standing_watch`: of a standing team's life;
//! * [`bridge`]: a mixed team's bridge between the host's iceoryx2 services and the other
//!   hosts (the one place that uses two transports at once);
//! * `presence`: what a host knows of its team; `census`: the agents it counted;
//! * `same_team`: the team-digest check between hosts; `priority`: a host runs ahead of
//!   its agents.

use crate::host::presence::watch_team;
use crate::host::priority::{Prepared, prepare_host_process};
pub use crate::host::run_watch::HostReport;
use crate::host::run_watch::HostRun;
use crate::host::same_team::check_team_digest;
use crate::process::member_error::MemberError;
use crate::team::errors::HostError;
use crate::team::team_file::{HostEntry, Team};
use admm_ta_transport::zenoh_net::error::ZenohError;
use admm_ta_transport::zenoh_net::links::ZenohLinks;
use admm_ta_transport::zenoh_net::router::HostRouter;
use std::path::Path;
use std::time::{Duration, Instant};
use zenoh::Wait;

pub mod bridge;
mod census;
mod presence;
mod priority;
mod run_watch;
mod same_team;
mod standing_watch;

/// How long a host waits, once every other host is up, for its router's direct link to
/// each of them (Zenoh retries a connection every 1–4 s).
const DIRECT_LINKS_WITHIN: Duration = Duration::from_secs(10);

/// Runs host `name` of the team in `team_path` until the team's run is over. The team
/// file, the host's name and a team file that differs from the running team's are refused
/// ([`MemberError::Refused`]); what fails once the host runs is a failure.
///
/// Called first thing in a process (`admm-ta host`), it sizes Zenoh's receive runtime for
/// the router and raises the process's priority; in a process already running other
/// threads it leaves both alone and says so.
pub fn run_host(team_path: &Path, name: &str) -> Result<HostReport, MemberError> {
    let started = Instant::now();
    let team = Team::read(team_path).map_err(MemberError::refused)?;
    let prepared = prepare_process(&team, name);
    let _signals = admm_ta_transport::signals::install();
    let _span = tracing::info_span!("host", run = %team.file.run, host = name).entered();
    say_prepared(prepared);
    tracing::debug!(team = %team_path.display(), "starting the host");
    if !team.file.transport.across_hosts() {
        return Err(MemberError::refused(HostError::NoHosts));
    }
    let host = team.host(name).map_err(MemberError::refused)?.clone();
    let router = open_router(&team, &host)?;
    let links: ZenohLinks = team.zenoh_links(&host);
    let session = router.session();
    let (watch, _watches) = watch_team(&team, &host, session, &links)?;
    // A standing team's hosts bridge each roster on its own (`standing_host`).
    let bridge = if team.file.transport.bridged() && !team.is_private() {
        Some(crate::host::bridge::Bridge::start(&team, &host, &router)?)
    } else {
        None
    };
    // The team's identity: the later of two hosts whose team files differ is refused by
    // name before it declares its host token (so no agent of the team starts with it).
    let startup_deadline = started + Duration::from_secs_f64(team.file.startup_timeout);
    let _digest = check_team_digest(&team, &host.name, &links, session, startup_deadline)?;
    link_routers(&team, &router, startup_deadline);
    // After the bridge's subscriptions: the other hosts wait for this token before they let
    // their agents publish to ours.
    let _token = session
        .liveliness()
        .declare_token(links.host_key(&host.name))
        .wait()
        .map_err(|e| {
            MemberError::failed(ZenohError::new(
                "cannot declare the host's liveliness token",
                e,
            ))
        })?;
    // Dropped before the token (whatever way this function returns): the other hosts then
    // know this host left on purpose.
    let _goodbye = Goodbye {
        session,
        key: links.goodbye_key(&host.name),
    };
    if team.is_private() {
        let served = crate::host::standing_watch::serve_standing_team(
            &team,
            &host,
            session,
            &links,
            &watch,
            startup_deadline,
        )?;
        return Ok(HostReport {
            host: host.name,
            agents_seen: served.robots_seen,
            forwarded_out: served.forwarded.0,
            forwarded_in: served.forwarded.1,
        });
    }
    let run = HostRun {
        team: &team,
        host: &host,
        session,
        links: &links,
        watch: &watch,
        started,
        startup_deadline,
    };
    run.serve(bridge)
}

/// Sizes Zenoh's receive runtime for the router's links (this host's Zenoh agents — a
/// mixed team's agents use iceoryx2 and its bridge is in this process — and the other
/// hosts' routers) and raises the process's priority. Before any thread: the threads
/// started later (Zenoh's, the bridge's) inherit what it sets.
fn prepare_process(team: &Team, name: &str) -> Prepared {
    let router_links = team.host(name).map_or(0, |me| {
        let clients = if team.file.transport.bridged() {
            0
        } else {
            me.agents.len()
        };
        clients + team.file.hosts.len().saturating_sub(1)
    });
    prepare_host_process(router_links)
}

/// Says in the log what [`prepare_process`] could do.
fn say_prepared(prepared: Prepared) {
    match prepared {
        Prepared::Ahead(nice) => tracing::debug!(nice, "the host runs ahead of its agents"),
        Prepared::NotRaised(e) => tracing::debug!(
            error = %e,
            "cannot raise the host's priority: busy agents may slow its relaying"
        ),
        Prepared::Shared => tracing::warn!(
            "the host runs in a process with other threads: its priority is not raised and \
             its router's receive runtime not sized (set ZENOH_RUNTIME='(rx: (worker_threads: N))', \
             N = its links + 2, before Zenoh starts)"
        ),
    }
}

/// The host's router, listening on its endpoint and linking to the other hosts'.
fn open_router(team: &Team, host: &HostEntry) -> Result<HostRouter, MemberError> {
    let others: Vec<String> = team
        .file
        .hosts
        .iter()
        .filter(|h| h.name != host.name)
        .map(|h| h.endpoint.clone())
        .collect();
    HostRouter::open(&host.endpoint, &others).map_err(MemberError::failed)
}

/// Waits (until `startup_deadline`, at most [`DIRECT_LINKS_WITHIN`]) for the router's direct
/// link to every other host: each follows within Zenoh's reconnection period once the
/// other host is up; without one, messages go over other hosts.
fn link_routers(team: &Team, router: &HostRouter, startup_deadline: Instant) {
    let hosts = team.file.hosts.len().saturating_sub(1);
    let linked = router.await_routers(
        hosts,
        startup_deadline.min(Instant::now() + DIRECT_LINKS_WITHIN),
    );
    if linked < hosts {
        tracing::warn!(
            linked,
            hosts,
            "not every other host's router is linked directly: messages go over other hosts"
        );
    }
}

/// Says this host's goodbye (a liveliness token, declared and withdrawn) when dropped.
struct Goodbye<'s> {
    session: &'s zenoh::Session,
    key: String,
}

impl Drop for Goodbye<'_> {
    fn drop(&mut self) {
        if let Ok(token) = self.session.liveliness().declare_token(&self.key).wait() {
            let _ = token.undeclare().wait();
        }
    }
}
