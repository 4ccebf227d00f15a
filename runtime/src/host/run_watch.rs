//! A host's watch of its team's one run (a team that solves once), once the host is up: it
//! returns when every agent of the team has shown up and left again (or a failure ended the
//! run and the agents left), naming a failure announced by any agent or a host lost; it
//! waits for the first agents until the team's start-up deadline (naming those that never
//! came) and for the run no longer than every round's deadline allows.
//!
//! Each pass of its loop, in order: a termination signal (this host's, or announced) stops
//! the team; the network is asked which agents are alive when the team is ending; after a
//! failure, agents still listed alive past a round's deadline and a lease are a verdict; a
//! host lost is announced, again and again for a while; the start-up and run deadlines.

use crate::host::bridge::Bridge;
use crate::host::census::Census;
use crate::host::presence::{TeamView, TeamWatch};
use crate::process::member_error::MemberError;
use crate::team::errors::HostError;
use crate::team::team_file::{HostEntry, Team};
use admm_ta_transport::zenoh_net::links::ZenohLinks;
use admm_ta_transport::zenoh_net::session::{alive_agents, announce_lost_host, announce_stop};
use serde::Serialize;
use std::sync::{Arc, MutexGuard};
use std::time::{Duration, Instant};
use zenoh::Session;

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

/// How long a host stopped by a signal waits for the team's agents to leave.
pub(super) const STOP_GRACE: Duration = Duration::from_secs(2);

/// After a failure, how long beyond one round's deadline a host waits for the agents still
/// listed alive (a Zenoh lease is 10 s: a vanished session's tokens are gone by then).
const AFTER_FAILURE: Duration = Duration::from_secs(10);

/// Host `host` of `team`, up: what its loop reads.
pub(super) struct HostRun<'a> {
    pub(super) team: &'a Team,
    pub(super) host: &'a HostEntry,
    pub(super) session: &'a Session,
    pub(super) links: &'a ZenohLinks,
    pub(super) watch: &'a Arc<TeamWatch>,
    pub(super) started: Instant,
    pub(super) startup_deadline: Instant,
}

/// What the loop carries from one pass to the next.
struct Progress {
    /// A stop request, and until when the host waits for its agents to leave.
    stop: Option<(i32, Instant)>,
    /// The agent announced failed for a lost host, and when.
    lost_announced: Option<(usize, Instant)>,
    /// When this host first saw the team's failure.
    failed_at: Option<Instant>,
    census: Census,
}

type Guard<'w> = MutexGuard<'w, TeamView>;

impl HostRun<'_> {
    fn lock(&self) -> Guard<'_> {
        self.watch.view.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn agents(&self) -> usize {
        self.team.file.robots
    }

    /// Watches the run to its end (see the module); `bridge`: a mixed team's.
    pub(super) fn serve(&self, bridge: Option<Bridge>) -> Result<HostReport, MemberError> {
        let run_deadline = self.startup_deadline
            + Duration::from_secs_f64(self.team.file.round_timeout)
                * (self.team.file.max_iters as u32 + 2);
        let mut progress = Progress {
            stop: None,
            lost_announced: None,
            failed_at: None,
            census: Census::new(self.agents()),
        };
        let mut view = self.lock();
        loop {
            view = self.stop_pass(view, &mut progress)?;
            if let Some(bridge) = &bridge {
                bridge.check().map_err(MemberError::failed)?;
            }
            let all_seen = view.seen.iter().all(|&s| s);
            if view.failed.is_some() {
                progress.failed_at.get_or_insert_with(Instant::now);
            }
            view = self.census_pass(view, &mut progress, all_seen);
            self.failure_verdict(&view, &progress)?;
            let lingered = progress
                .lost_announced
                .is_none_or(|(_, at)| at.elapsed() >= LOST_HOST_LINGER);
            let none_alive = view.alive.iter().all(|&a| !a);
            if none_alive && (all_seen || view.failed.is_some()) && lingered {
                break;
            }
            view = self.lost_host_pass(view, &mut progress, lingered);
            self.deadlines(&view, all_seen, run_deadline)?;
            view = self
                .watch
                .changed
                .wait_timeout(view, Duration::from_millis(20))
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
        self.report(view, bridge)
    }

    /// A termination signal (to this host, or announced): every agent of the team stops;
    /// this host waits for its agents to leave, briefly, then ends.
    fn stop_pass<'w>(
        &'w self,
        mut view: Guard<'w>,
        progress: &mut Progress,
    ) -> Result<Guard<'w>, MemberError> {
        let signal = admm_ta_transport::signals::received().or(view.stopped);
        if let Some(signal) = signal
            && progress.stop.is_none()
        {
            if admm_ta_transport::signals::received().is_some() {
                drop(view);
                announce_stop(self.session, self.links, signal);
                view = self.lock();
            }
            admm_ta_transport::signals::record(signal);
            progress.stop = Some((signal, Instant::now() + STOP_GRACE));
        }
        if let Some((signal, until)) = progress.stop {
            let running = view.alive.iter().filter(|&&a| a).count();
            if running == 0 || Instant::now() >= until {
                let seen = view.seen.iter().filter(|&&s| s).count();
                return Err(MemberError::failed(HostError::Stopped {
                    host: self.host.name.clone(),
                    signal,
                    stopped: seen - running,
                    leaving: running,
                }));
            }
        }
        Ok(view)
    }

    /// The team is ending (everybody came and somebody left, or somebody failed) and agents
    /// are still listed alive: the network is asked, and an agent missing from two answers
    /// in a row is taken as gone (its token's removal never reached this router).
    fn census_pass<'w>(
        &'w self,
        mut view: Guard<'w>,
        progress: &mut Progress,
        all_seen: bool,
    ) -> Guard<'w> {
        let somebody_left = all_seen && view.alive.iter().any(|&a| !a);
        if (somebody_left || view.failed.is_some())
            && view.alive.iter().any(|&a| a)
            && progress.census.due()
        {
            drop(view);
            let answer = alive_agents(self.session, self.links);
            view = self.lock();
            if let Ok(alive_now) = answer {
                tracing::debug!(?alive_now, "census");
                for a in progress.census.gone(&alive_now, &view.alive) {
                    tracing::debug!(agent = a, "a token the network no longer has: gone");
                    view.alive[a] = false;
                }
            }
        }
        view
    }

    /// After a failure, agents still listed alive a round's deadline and a lease later: the
    /// verdict (a host lost, when the failure is one of its agents).
    fn failure_verdict(&self, view: &TeamView, progress: &Progress) -> Result<(), MemberError> {
        let round_timeout = Duration::from_secs_f64(self.team.file.round_timeout);
        let (Some(failed), Some(at)) = (view.failed, progress.failed_at) else {
            return Ok(());
        };
        if at.elapsed() < round_timeout + AFTER_FAILURE {
            return Ok(());
        }
        let listed: Vec<usize> = (0..self.agents()).filter(|&a| view.alive[a]).collect();
        if listed.is_empty() {
            return Ok(());
        }
        if let Some(lost) = view.lost_verdict(self.team, &self.host.name, Some(failed)) {
            tracing::warn!(?listed, "agents still listed after the loss of a host");
            return Err(MemberError::failed(lost));
        }
        Err(MemberError::failed(HostError::FailedWithAgentsListed {
            host: self.host.name.clone(),
            failed,
            listed,
            waited: at.elapsed(),
        }))
    }

    /// A host lost: its agents are out of reach, so the team stops now, as for a failed
    /// agent, rather than after every waiting agent's round deadline; the announcement goes
    /// out again and again for a while (it reaches only the agents already subscribed, and
    /// some may still be starting). Cut off from every other host, this host names nobody
    /// to the others (should the network heal, they would take a healthy host for lost).
    fn lost_host_pass<'w>(
        &'w self,
        mut view: Guard<'w>,
        progress: &mut Progress,
        lingered: bool,
    ) -> Guard<'w> {
        if view.failed.is_none()
            && let Some(lost) = view.lost_host()
        {
            let first = self
                .team
                .host(lost)
                .ok()
                .and_then(|h| h.agents.iter().min().copied());
            if let Some(first) = first {
                view.failed = Some(first);
                progress.lost_announced = Some((first, Instant::now()));
            }
        }
        if let Some((first, _)) = progress.lost_announced
            && !lingered
        {
            let others = self.team.file.hosts.len().saturating_sub(1);
            let lost = if view.cut_off(others) {
                None
            } else {
                view.lost_host().map(str::to_string)
            };
            drop(view);
            announce_lost_host(self.session, self.links, first, lost.as_deref());
            view = self.lock();
        }
        view
    }

    /// The start-up deadline (agents that never came) and the run's.
    fn deadlines(
        &self,
        view: &TeamView,
        all_seen: bool,
        run_deadline: Instant,
    ) -> Result<(), MemberError> {
        let now = Instant::now();
        if !all_seen && view.failed.is_none() && now >= self.startup_deadline {
            let missing: Vec<usize> = (0..self.agents()).filter(|&a| !view.seen[a]).collect();
            return Err(MemberError::failed(HostError::NeverJoined {
                host: self.host.name.clone(),
                missing,
                waited: self.started.elapsed(),
            }));
        }
        if now >= run_deadline {
            let running: Vec<usize> = (0..self.agents()).filter(|&a| view.alive[a]).collect();
            return Err(MemberError::failed(HostError::Overran {
                host: self.host.name.clone(),
                running,
            }));
        }
        Ok(())
    }

    /// The run's verdict once every agent left: a host lost, an agent failed, or the report.
    fn report(&self, view: Guard<'_>, bridge: Option<Bridge>) -> Result<HostReport, MemberError> {
        // A failure marked on this host's board (mixed) may not have been announced yet.
        let failed = view
            .failed
            .or_else(|| bridge.as_ref().and_then(|b| b.failed()));
        let lost = view.lost_verdict(self.team, &self.host.name, failed);
        let agents_seen = view.seen.iter().filter(|&&s| s).count();
        drop(view);
        let (forwarded_out, forwarded_in) = bridge.map_or((0, 0), |b| b.finish());
        if let Some(lost) = lost {
            return Err(MemberError::failed(lost));
        }
        if let Some(failed) = failed {
            return Err(MemberError::failed(HostError::AgentFailed {
                host: self.host.name.clone(),
                failed,
            }));
        }
        Ok(HostReport {
            host: self.host.name.clone(),
            agents_seen,
            forwarded_out,
            forwarded_in,
        })
    }
}
