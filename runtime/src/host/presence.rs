//! What a host knows of its team's presence: who came, who is still there, who failed,
//! which host was lost — filled by Zenoh's callbacks ([`watch_team`]), read by the host's
//! loop.

use crate::process::member_error::MemberError;
use crate::team::errors::HostError;
use crate::team::team_file::{HostEntry, Team};
use admm_ta_transport::zenoh_net::error::ZenohError;
use admm_ta_transport::zenoh_net::links::ZenohLinks;
use admm_ta_transport::zenoh_net::session::{watch_failures, watch_stops};
use std::collections::HashSet;
use std::sync::{Arc, Condvar, Mutex};
use zenoh::sample::{Sample, SampleKind};
use zenoh::{Session, Wait};

/// The team as this host sees it.
#[derive(Default)]
pub(super) struct TeamView {
    pub(super) seen: Vec<bool>,
    pub(super) alive: Vec<bool>,
    pub(super) failed: Option<usize>,
    /// A stop request (termination signal) announced by an agent or another host.
    pub(super) stopped: Option<i32>,
    /// Hosts that said goodbye (they left after the run, or stopped on purpose).
    pub(super) goodbyes: HashSet<String>,
    /// The hosts whose token vanished without a goodbye (killed, crashed or cut off), or
    /// that another host announced so, in the order seen.
    pub(super) lost_hosts: Vec<String>,
    /// Agents of a host whose token vanished: gone for this host, whatever their tokens say
    /// later (after a partition, routers that have not noticed it yet advertise the lost
    /// host's tokens again for a while).
    pub(super) settled: Vec<bool>,
}

impl TeamView {
    /// Host `lost` (whose agents are `agents`) left the team: its token vanished, or another
    /// host announced it lost. Its agents are settled with it — out of reach whatever their
    /// own tokens still say here (a router that lost a host can keep the host's agents'
    /// tokens for many seconds, or answer queries with them); without a goodbye, it is the
    /// team's lost host.
    pub(super) fn lose_host(&mut self, lost: &str, agents: &[usize]) {
        let known = self.alive.len();
        for &a in agents.iter().filter(|&&a| a < known) {
            self.alive[a] = false;
            self.settled[a] = true;
        }
        if !self.goodbyes.contains(lost) && !self.lost_hosts.iter().any(|h| h == lost) {
            self.lost_hosts.push(lost.to_string());
        }
    }

    /// The team's lost host: the first one lost.
    pub(super) fn lost_host(&self) -> Option<&str> {
        self.lost_hosts.first().map(String::as_str)
    }

    /// Whether every one of the `others` other hosts (two or more) was lost: then this host
    /// is the one most likely cut off, and naming any of them would blame a healthy host.
    pub(super) fn cut_off(&self, others: usize) -> bool {
        others >= 2 && self.lost_hosts.len() >= others
    }
    /// The verdict of a run that lost a host, when the failure (if any) is one of the lost
    /// hosts' agents: cut off when every other host was lost, else the first lost host
    /// named.
    pub(super) fn lost_verdict(
        &self,
        team: &Team,
        me: &str,
        failed: Option<usize>,
    ) -> Option<HostError> {
        let lost = self.lost_host()?;
        let others = team.file.hosts.len().saturating_sub(1);
        if self.cut_off(others) {
            return failed
                .is_none_or(|f| self.lost_hosts.iter().any(|h| lost_owns(team, h, f)))
                .then(|| HostError::CutOff {
                    host: me.to_string(),
                    lost: self.lost_hosts.clone(),
                });
        }
        failed
            .is_none_or(|f| lost_owns(team, lost, f))
            .then(|| HostError::HostLost {
                host: me.to_string(),
                lost: lost.to_string(),
            })
    }
}

/// Whether agent `agent` runs on host `host` of `team`.
fn lost_owns(team: &Team, host: &str, agent: usize) -> bool {
    team.host(host).is_ok_and(|h| h.agents.contains(&agent))
}

pub(super) struct TeamWatch {
    pub(super) view: Mutex<TeamView>,
    pub(super) changed: Condvar,
}

impl TeamWatch {
    pub(super) fn update(&self, change: impl FnOnce(&mut TeamView)) {
        let mut p = self.view.lock().unwrap_or_else(|e| e.into_inner());
        change(&mut p);
        drop(p);
        self.changed.notify_all();
    }
}

/// What keeps a host's [`TeamWatch`] up to date (dropped, the watch stops).
pub(super) type Watches = Vec<zenoh::pubsub::Subscriber<()>>;

/// Host `host`'s watch of team `team` on `session`: the agents' tokens, stop requests, the
/// other hosts' tokens and goodbyes (a token that vanishes without a goodbye is a host
/// lost), and failure announcements.
pub(super) fn watch_team(
    team: &Team,
    host: &HostEntry,
    session: &Session,
    links: &ZenohLinks,
) -> Result<(Arc<TeamWatch>, Watches), MemberError> {
    let n = team.file.robots;
    let watch = Arc::new(TeamWatch {
        view: Mutex::new(TeamView {
            seen: vec![false; n],
            alive: vec![false; n],
            settled: vec![false; n],
            ..TeamView::default()
        }),
        changed: Condvar::new(),
    });
    let zenoh = |what: &'static str| move |e| MemberError::failed(ZenohError::new(what, e));
    let mut watches = Vec::new();
    {
        let watch = Arc::clone(&watch);
        let links = links.clone();
        watches.push(
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
                .map_err(zenoh("cannot watch the team's agents"))?,
        );
    }
    {
        let watch = Arc::clone(&watch);
        watches.push(
            watch_stops(session, links, move |signal| {
                watch.update(|p| {
                    p.stopped.get_or_insert(signal);
                });
            })
            .map_err(MemberError::failed)?,
        );
    }
    watches.extend(watch_hosts(team, host, session, links, &watch)?);
    Ok((watch, watches))
}

/// The other hosts' goodbyes and tokens (both are liveliness declarations of a router's
/// session, so they arrive in order: a token that vanishes without a goodbye is a host
/// lost), and the failures announced (a host lost by another host's account: this router
/// may notice it much later, or never — it can keep advertising the lost host's tokens).
fn watch_hosts(
    team: &Team,
    host: &HostEntry,
    session: &Session,
    links: &ZenohLinks,
    watch: &Arc<TeamWatch>,
) -> Result<Watches, MemberError> {
    let zenoh = |what: &'static str| move |e| MemberError::failed(ZenohError::new(what, e));
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
    let mut watches = Vec::new();
    {
        let watch = Arc::clone(watch);
        let links = links.clone();
        watches.push(
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
                .map_err(zenoh("cannot watch the other hosts' goodbyes"))?,
        );
    }
    {
        let watch = Arc::clone(watch);
        let links = links.clone();
        let me = host.name.clone();
        let theirs = theirs.clone();
        watches.push(
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
                .map_err(zenoh("cannot watch the other hosts"))?,
        );
    }
    let watch = Arc::clone(watch);
    let me = host.name.clone();
    watches.push(
        watch_failures(session, links, move |failed, lost| {
            tracing::debug!(failed, lost, "a failure was announced");
            let agents = lost.filter(|h| *h != me).map(&theirs);
            watch.update(|p| {
                p.failed.get_or_insert(failed);
                if let (Some(h), Some(agents)) = (lost, &agents) {
                    p.lose_host(h, agents);
                }
            });
        })
        .map_err(MemberError::failed)?,
    );
    Ok(watches)
}
