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
//! It waits for the first agents until the team's start-up deadline (naming those that never
//! came) and for the run no longer than every round's deadline allows.

use crate::process::member_error::MemberError;
use crate::team::census::Census;
use crate::team::errors::HostError;
use crate::team::host_digest::check_team_digest;
use crate::team::presence::{Presence, TeamWatch};
use crate::team::priority::{Prepared, prepare_host_process};
use crate::team::team_file::Team;
use crate::zenoh_net::ZenohError;
use crate::zenoh_net::links::ZenohLinks;
use crate::zenoh_net::router::HostRouter;
use crate::zenoh_net::session::{
    alive_agents, announce_lost_host, announce_stop, watch_failures, watch_stops,
};
use serde::Serialize;
use std::collections::HashSet;
use std::path::Path;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::sample::{Sample, SampleKind};

/// What a host saw of its team's run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HostReport {
    pub host: String,
    /// Agents of the whole team seen on the network.
    pub agents_seen: usize,
    /// Round messages the bridge forwarded to and from the other hosts (mixed teams).
    pub forwarded_out: u64,
    pub forwarded_in: u64,
}

/// How long a host that lost another host keeps announcing it (every loop pass, 20 ms), so
/// that its agents still starting hear it.
const LOST_HOST_LINGER: Duration = Duration::from_secs(2);

/// How long a host waits, once every other host is up, for its router's direct link to
/// each of them (Zenoh retries a connection every 1–4 s).
const DIRECT_LINKS_WITHIN: Duration = Duration::from_secs(10);

/// How long a host stopped by a signal waits for the team's agents to leave.
const STOP_GRACE: Duration = Duration::from_secs(2);

/// After a failure, how long beyond one round's deadline a host waits for the agents still
/// listed alive (a Zenoh lease is 10 s: a vanished session's tokens are gone by then).
const AFTER_FAILURE: Duration = Duration::from_secs(10);

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
    // The router's links: this host's Zenoh agents (a mixed team's agents use iceoryx2 and
    // its bridge is in this process) and the other hosts' routers. Before any thread: the
    // threads started later (Zenoh's, the bridge's) inherit what it sets.
    let router_links = team.host(name).map_or(0, |me| {
        let clients = if team.file.transport.bridged() {
            0
        } else {
            me.agents.len()
        };
        clients + team.file.hosts.len().saturating_sub(1)
    });
    let prepared = prepare_host_process(router_links);
    let _signals = crate::signals::install();
    let _span = tracing::info_span!("host", run = %team.file.run, host = name).entered();
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
    tracing::debug!(team = %team_path.display(), "starting the host");
    if !team.file.transport.across_hosts() {
        return Err(MemberError::refused(HostError::NoHosts));
    }
    let n = team.file.robots;
    let host = team.host(name).map_err(MemberError::refused)?.clone();
    let others: Vec<String> = team
        .file
        .hosts
        .iter()
        .filter(|h| h.name != host.name)
        .map(|h| h.endpoint.clone())
        .collect();
    let router = HostRouter::open(&host.endpoint, &others).map_err(MemberError::failed)?;
    let links: ZenohLinks = team.zenoh_links(&host);
    let watch = Arc::new(TeamWatch {
        presence: Mutex::new(Presence {
            seen: vec![false; n],
            alive: vec![false; n],
            failed: None,
            stopped: None,
            goodbyes: HashSet::new(),
            lost_hosts: Vec::new(),
            settled: vec![false; n],
        }),
        changed: Condvar::new(),
    });
    let session = router.session();
    let _presence = {
        let watch = Arc::clone(&watch);
        let links = links.clone();
        session
            .liveliness()
            .declare_subscriber(links.alive_all())
            .history(true)
            .callback(move |sample: Sample| {
                let Some(a) = links
                    .agent_of_alive_key(sample.key_expr().as_str())
                    .filter(|&a| a < n)
                else {
                    return;
                };
                let put = sample.kind() == SampleKind::Put;
                tracing::debug!(agent = a, alive = put, "an agent's token");
                watch.update(|p| {
                    p.seen[a] |= put;
                    p.alive[a] = put && !p.settled[a];
                });
            })
            .wait()
            .map_err(|e| {
                MemberError::failed(ZenohError::new("cannot watch the team's agents", e))
            })?
    };
    let _stops = {
        let watch = Arc::clone(&watch);
        watch_stops(session, &links, move |signal| {
            watch.update(|p| {
                p.stopped.get_or_insert(signal);
            });
        })
        .map_err(MemberError::failed)?
    };
    // The other hosts: one whose token vanishes without a goodbye is lost. Both are
    // liveliness declarations of its router's session, so they arrive in order.
    let _goodbyes = {
        let watch = Arc::clone(&watch);
        let links = links.clone();
        session
            .liveliness()
            .declare_subscriber(links.goodbye_all())
            .history(true)
            .callback(move |sample: Sample| {
                if let Some(h) = links.host_of_goodbye(sample.key_expr().as_str()) {
                    let h = h.to_string();
                    watch.update(|p| {
                        p.goodbyes.insert(h);
                    });
                }
            })
            .wait()
            .map_err(|e| {
                MemberError::failed(ZenohError::new("cannot watch the other hosts' goodbyes", e))
            })?
    };
    let agents_of: Arc<Vec<(String, Vec<usize>)>> = Arc::new(
        team.file
            .hosts
            .iter()
            .map(|h| (h.name.clone(), h.agents.clone()))
            .collect(),
    );
    let theirs = move |h: &str| {
        agents_of
            .iter()
            .find(|(name, _)| name == h)
            .map(|(_, agents)| agents.clone())
            .unwrap_or_default()
    };
    let _hosts = {
        let watch = Arc::clone(&watch);
        let links = links.clone();
        let me = host.name.clone();
        let theirs = theirs.clone();
        session
            .liveliness()
            .declare_subscriber(links.host_all())
            .callback(move |sample: Sample| {
                let Some(h) = links.host_of_key(sample.key_expr().as_str()) else {
                    return;
                };
                if sample.kind() == SampleKind::Delete && h != me {
                    tracing::debug!(host = h, "a host's token vanished");
                    let agents = theirs(h);
                    watch.update(|p| p.lose_host(h, &agents));
                }
            })
            .wait()
            .map_err(|e| MemberError::failed(ZenohError::new("cannot watch the other hosts", e)))?
    };
    let _failures = {
        let watch = Arc::clone(&watch);
        let me = host.name.clone();
        watch_failures(session, &links, move |failed, lost| {
            tracing::debug!(failed, lost, "a failure was announced");
            // A host lost by another host's account: this router may notice it much later,
            // or never (it can keep advertising the lost host's tokens).
            let agents = lost.filter(|h| *h != me).map(&theirs);
            watch.update(|p| {
                p.failed.get_or_insert(failed);
                if let (Some(h), Some(agents)) = (lost, &agents) {
                    p.lose_host(h, agents);
                }
            });
        })
        .map_err(MemberError::failed)?
    };
    // A standing team's hosts bridge each roster on its own (`standing_host`).
    let bridge = if team.file.transport.bridged() && !team.is_private() {
        Some(crate::team::bridge::Bridge::start(&team, &host, &router)?)
    } else {
        None
    };
    // The team's identity: the later of two hosts whose team files differ is refused by
    // name before it declares its host token (so no agent of the team starts with it).
    let startup_deadline = started + Duration::from_secs_f64(team.file.startup_timeout);
    let _digest = check_team_digest(&team, &host.name, &links, session, startup_deadline)?;
    // Every other host is up: its direct link follows within Zenoh's reconnection period.
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
        let served = crate::team::standing_host::serve_standing_team(
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
    let run_deadline = startup_deadline
        + Duration::from_secs_f64(team.file.round_timeout) * (team.file.max_iters as u32 + 2);
    let mut presence = watch.presence.lock().unwrap_or_else(|e| e.into_inner());
    let mut stop: Option<(i32, Instant)> = None;
    // The agent announced failed for a lost host, and when.
    let mut lost_announced: Option<(usize, Instant)> = None;
    // When this host first saw the team's failure; the last census and whom it missed.
    let mut failed_at: Option<Instant> = None;
    let mut census = Census::new(n);
    let round_timeout = Duration::from_secs_f64(team.file.round_timeout);
    let others = team.file.hosts.len().saturating_sub(1);
    loop {
        let signal = crate::signals::received().or(presence.stopped);
        if let Some(signal) = signal
            && stop.is_none()
        {
            // A termination signal (to this host, or announced): every agent of the team
            // stops; this host waits for its agents to leave, briefly.
            if crate::signals::received().is_some() {
                drop(presence);
                announce_stop(session, &links, signal);
                presence = watch.presence.lock().unwrap_or_else(|e| e.into_inner());
            }
            crate::signals::record(signal);
            stop = Some((signal, Instant::now() + STOP_GRACE));
        }
        if let Some((signal, until)) = stop {
            let running = presence.alive.iter().filter(|&&a| a).count();
            if running == 0 || Instant::now() >= until {
                let seen = presence.seen.iter().filter(|&&s| s).count();
                return Err(MemberError::failed(HostError::Stopped {
                    host: host.name.clone(),
                    signal,
                    stopped: seen - running,
                    leaving: running,
                }));
            }
        }
        if let Some(bridge) = &bridge {
            bridge.check().map_err(MemberError::failed)?;
        }
        let all_seen = presence.seen.iter().all(|&s| s);
        if presence.failed.is_some() {
            failed_at.get_or_insert_with(Instant::now);
        }
        // The team is ending (everybody came and somebody left, or somebody failed) and
        // agents are still listed alive: the network is asked, and an agent missing from two
        // answers in a row is taken as gone (its token's removal never reached this router).
        let somebody_left = all_seen && presence.alive.iter().any(|&a| !a);
        if (somebody_left || presence.failed.is_some())
            && presence.alive.iter().any(|&a| a)
            && census.due()
        {
            drop(presence);
            let answer = alive_agents(session, &links);
            presence = watch.presence.lock().unwrap_or_else(|e| e.into_inner());
            if let Ok(alive_now) = answer {
                tracing::debug!(?alive_now, "census");
                for a in census.gone(&alive_now, &presence.alive) {
                    tracing::debug!(agent = a, "a token the network no longer has: gone");
                    presence.alive[a] = false;
                }
            }
        }
        if let (Some(failed), Some(at)) = (presence.failed, failed_at)
            && at.elapsed() >= round_timeout + AFTER_FAILURE
        {
            let listed: Vec<usize> = (0..n).filter(|&a| presence.alive[a]).collect();
            if !listed.is_empty()
                && let Some(lost) = presence.lost_verdict(&team, &host.name, Some(failed))
            {
                tracing::warn!(?listed, "agents still listed after the loss of a host");
                return Err(MemberError::failed(lost));
            }
            if !listed.is_empty() {
                return Err(MemberError::failed(HostError::FailedWithAgentsListed {
                    host: host.name.clone(),
                    failed,
                    listed,
                    waited: at.elapsed(),
                }));
            }
        }
        let none_alive = presence.alive.iter().all(|&a| !a);
        let lingered = lost_announced.is_none_or(|(_, at)| at.elapsed() >= LOST_HOST_LINGER);
        if none_alive && (all_seen || presence.failed.is_some()) && lingered {
            break;
        }
        if presence.failed.is_none()
            && let Some(lost) = presence.lost_host()
        {
            // Its agents are out of reach: the team stops now, as for a failed agent,
            // rather than after every waiting agent's round deadline.
            let first = team
                .host(lost)
                .ok()
                .and_then(|h| h.agents.iter().min().copied());
            if let Some(first) = first {
                presence.failed = Some(first);
                lost_announced = Some((first, Instant::now()));
            }
        }
        if let Some((first, _)) = lost_announced
            && !lingered
        {
            // Again and again for a while: an announcement reaches only the agents already
            // subscribed, and some may still be starting. Cut off from every other host,
            // this host names nobody to the others (should the network heal, they would
            // take a healthy host for lost).
            let lost = if presence.cut_off(others) {
                None
            } else {
                presence.lost_host().map(str::to_string)
            };
            drop(presence);
            announce_lost_host(session, &links, first, lost.as_deref());
            presence = watch.presence.lock().unwrap_or_else(|e| e.into_inner());
        }
        let now = Instant::now();
        if !all_seen && presence.failed.is_none() && now >= startup_deadline {
            let missing: Vec<usize> = (0..n).filter(|&a| !presence.seen[a]).collect();
            return Err(MemberError::failed(HostError::NeverJoined {
                host: host.name.clone(),
                missing,
                waited: started.elapsed(),
            }));
        }
        if now >= run_deadline {
            let running: Vec<usize> = (0..n).filter(|&a| presence.alive[a]).collect();
            return Err(MemberError::failed(HostError::Overran {
                host: host.name.clone(),
                running,
            }));
        }
        presence = watch
            .changed
            .wait_timeout(presence, Duration::from_millis(20))
            .unwrap_or_else(|e| e.into_inner())
            .0;
    }
    // A failure marked on this host's board (mixed) may not have been announced yet.
    let failed = presence
        .failed
        .or_else(|| bridge.as_ref().and_then(|b| b.failed()));
    let lost = presence.lost_verdict(&team, &host.name, failed);
    let agents_seen = presence.seen.iter().filter(|&&s| s).count();
    drop(presence);
    let (forwarded_out, forwarded_in) = bridge.map_or((0, 0), |b| b.finish());
    if let Some(lost) = lost {
        return Err(MemberError::failed(lost));
    }
    if let Some(failed) = failed {
        return Err(MemberError::failed(HostError::AgentFailed {
            host: host.name,
            failed,
        }));
    }
    Ok(HostReport {
        host: host.name,
        agents_seen,
        forwarded_out,
        forwarded_in,
    })
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
