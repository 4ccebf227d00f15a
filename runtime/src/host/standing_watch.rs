//! A host of a standing team (`costs = "private"`, [`crate::standing`]) across machines:
//! its robots come and go, so the host's run is the team's life, not one solve.
//!
//! It runs until every robot of the team has left (none of the team's robots' tokens is on
//! the network any more, once one was), or a termination signal. A lost host, a robot that
//! crashed, a roster that failed: the team goes on, and so does the host (it says what it
//! lost in its log). In a mixed team it bridges every roster that has robots on it: each
//! roster is a run of its own ([`crate::standing::epoch`]), with its own namespace on this
//! host and its own Zenoh keys, so the host starts a bridge for a roster as soon as one of
//! its robots says it is in it, and finishes it once none is.

use crate::host::bridge::{Bridge, BridgeRun};
use crate::host::presence::TeamWatch;
use crate::host::run_watch::STOP_GRACE;
use crate::process::member_error::MemberError;
use crate::standing::roster::{EpochId, Roster};
use crate::team::errors::HostError;
use crate::team::membership::member_scenario;
use crate::team::team_file::{HostEntry, Team};
use admm_ta_transport::zenoh_net::links::ZenohLinks;
use admm_ta_transport::zenoh_net::session::{alive_keys, announce_stop};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};
use zenoh::Session;

/// How often a mixed host looks for rosters to bridge.
const ROSTERS_EVERY: Duration = Duration::from_millis(20);

/// A mixed host's bridges, one per roster with robots on this host.
struct RosterBridges<'t> {
    team: &'t Team,
    host: &'t HostEntry,
    session: Session,
    links: ZenohLinks,
    running: BTreeMap<String, Bridge>,
    /// Rosters whose bridge failed: not started again.
    failed: Vec<String>,
    forwarded: (u64, u64),
    looked: Option<Instant>,
}

impl<'t> RosterBridges<'t> {
    /// The rosters this host's robots are in now.
    fn local_rosters(&self) -> BTreeMap<String, EpochId> {
        let Ok(keys) = alive_keys(&self.session, self.links.epoch_all()) else {
            return BTreeMap::new();
        };
        let robots = self.team.file.robots;
        keys.iter()
            .filter_map(|k| self.links.of_epoch_key(k))
            .filter(|(formed, _, _, robot)| !formed && self.host.agents.contains(robot))
            .filter_map(|(_, name, bitmap, _)| {
                let number = EpochId::number_of(name)?;
                let roster = Roster::from_hex(bitmap, robots)?;
                let id = EpochId { number, roster };
                (id.name() == name).then(|| (id.name(), id))
            })
            .collect()
    }

    /// The run of roster `id` on this host.
    fn run_of(&self, id: &EpochId) -> Result<BridgeRun, MemberError> {
        let (mut scenario, namespace) = member_scenario(self.team, Some(self.host))?;
        let part = namespace.within(&id.name()).map_err(MemberError::failed)?;
        scenario.roster = Some(id.roster.robots().to_vec());
        scenario.run_id = part.id.clone();
        scenario.prefix = part.prefix.clone();
        scenario.transport_root = part.transport_root();
        scenario.board_shm = part.board_shm();
        let startup = Duration::from_millis(scenario.startup_timeout_ms);
        let hosts = self.team.hosts_of(&id.roster);
        Ok(BridgeRun {
            scenario,
            namespace: part,
            links: ZenohLinks {
                epoch: Some(id.name()),
                hosts: hosts.clone(),
                ..self.links.clone()
            },
            host: self.host.name.clone(),
            hosts,
            local: self
                .host
                .agents
                .iter()
                .copied()
                .filter(|&a| id.roster.contains(a))
                .collect(),
            deadline: Instant::now() + startup,
        })
    }

    /// Starts the bridges of the rosters this host's robots came into, finishes those of
    /// the rosters they all left (and those that failed).
    fn update(&mut self) {
        if self.looked.is_some_and(|t| t.elapsed() < ROSTERS_EVERY) {
            return;
        }
        self.looked = Some(Instant::now());
        let rosters = self.local_rosters();
        // A roster whose bridge failed is not bridged again while its robots are in it.
        self.failed.retain(|name| rosters.contains_key(name));
        for (name, id) in &rosters {
            if self.running.contains_key(name) || self.failed.contains(name) {
                continue;
            }
            let started = self
                .run_of(id)
                .and_then(|run| Bridge::start_run(run, self.session.clone()));
            match started {
                Ok(bridge) => {
                    tracing::debug!(roster = %name, "bridging a roster");
                    self.running.insert(name.clone(), bridge);
                }
                Err(e) => {
                    tracing::warn!(roster = %name, error = %e.text(), "cannot bridge a roster");
                    self.failed.push(name.clone());
                }
            }
        }
        let ended: Vec<String> = self
            .running
            .iter()
            .filter(|(name, bridge)| {
                let failed = bridge.check().inspect_err(|e| {
                    tracing::warn!(roster = %name, error = %e, "a roster's bridge stopped");
                });
                !rosters.contains_key(*name) || failed.is_err()
            })
            .map(|(name, _)| name.clone())
            .collect();
        for name in ended {
            if rosters.contains_key(&name) {
                // It failed: its robots find the roster failed and form another.
                self.failed.push(name.clone());
            }
            if let Some(bridge) = self.running.remove(&name) {
                let (out, inn) = bridge.finish();
                self.forwarded.0 += out;
                self.forwarded.1 += inn;
            }
        }
    }

    fn finish(mut self) -> (u64, u64) {
        for (_, bridge) in std::mem::take(&mut self.running) {
            let (out, inn) = bridge.finish();
            self.forwarded.0 += out;
            self.forwarded.1 += inn;
        }
        self.forwarded
    }
}

/// What a standing team's host saw: the robots of the team that came, the round messages
/// its bridges forwarded out and in.
pub(super) struct Served {
    pub(super) robots_seen: usize,
    pub(super) forwarded: (u64, u64),
}

/// Runs host `host` of the standing team `team` (see the module) once its router and its
/// watches are up: until every robot of the team has left, or a termination signal.
pub(super) fn serve_standing_team(
    team: &Team,
    host: &HostEntry,
    session: &Session,
    links: &ZenohLinks,
    watch: &Arc<TeamWatch>,
    startup_deadline: Instant,
) -> Result<Served, MemberError> {
    let started = Instant::now();
    let n = team.file.robots;
    let mut bridges = team.file.transport.bridged().then(|| RosterBridges {
        team,
        host,
        session: session.clone(),
        links: links.clone(),
        running: BTreeMap::new(),
        failed: Vec::new(),
        forwarded: (0, 0),
        looked: None,
    });
    let mut stop: Option<(i32, Instant)> = None;
    let mut lost_told = 0;
    loop {
        let (seen, alive, stopped, lost) = {
            let p = watch.view.lock().unwrap_or_else(|e| e.into_inner());
            (
                p.seen.iter().filter(|&&s| s).count(),
                p.alive.iter().filter(|&&a| a).count(),
                p.stopped,
                p.lost_hosts.clone(),
            )
        };
        for lost in &lost[lost_told..] {
            tracing::warn!(lost = %lost, "a host left the team without a goodbye: its robots are gone");
        }
        lost_told = lost.len();
        let signal = admm_ta_transport::signals::received().or(stopped);
        if let Some(signal) = signal
            && stop.is_none()
        {
            if admm_ta_transport::signals::received().is_some() {
                announce_stop(session, links, signal);
            }
            admm_ta_transport::signals::record(signal);
            stop = Some((signal, Instant::now() + STOP_GRACE));
        }
        if let Some((signal, until)) = stop
            && (alive == 0 || Instant::now() >= until)
        {
            return Err(MemberError::failed(HostError::Stopped {
                host: host.name.clone(),
                signal,
                stopped: seen - alive,
                leaving: alive,
            }));
        }
        if let Some(bridges) = &mut bridges {
            bridges.update();
        }
        let bridging = bridges.as_ref().is_some_and(|b| !b.running.is_empty());
        if seen > 0 && alive == 0 && !bridging {
            break;
        }
        if seen == 0 && Instant::now() >= startup_deadline {
            return Err(MemberError::failed(HostError::NeverJoined {
                host: host.name.clone(),
                missing: (0..n).collect(),
                waited: started.elapsed(),
            }));
        }
        let p = watch.view.lock().unwrap_or_else(|e| e.into_inner());
        drop(
            watch
                .changed
                .wait_timeout(p, ROSTERS_EVERY)
                .unwrap_or_else(|e| e.into_inner()),
        );
    }
    let robots_seen = {
        let p = watch.view.lock().unwrap_or_else(|e| e.into_inner());
        p.seen.iter().filter(|&&s| s).count()
    };
    Ok(Served {
        robots_seen,
        forwarded: bridges.map_or((0, 0), RosterBridges::finish),
    })
}
