//! What a host knows of its team's presence: who came, who is still there, who failed,
//! which host was lost — filled by Zenoh's callbacks, read by the host's loop.

use crate::team::errors::HostError;
use crate::team::team_file::Team;
use std::collections::HashSet;
use std::sync::{Condvar, Mutex};

/// The team's presence as this host sees it.
#[derive(Default)]
pub(super) struct Presence {
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

impl Presence {
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
    pub(super) presence: Mutex<Presence>,
    pub(super) changed: Condvar,
}

impl TeamWatch {
    pub(super) fn update(&self, change: impl FnOnce(&mut Presence)) {
        let mut p = self.presence.lock().unwrap_or_else(|e| e.into_inner());
        change(&mut p);
        drop(p);
        self.changed.notify_all();
    }
}
