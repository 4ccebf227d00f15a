//! How a robot of a standing team gets to a roster and changes it: joining (found the
//! team's first roster, take its place in one forming, or wait to be admitted), moving on
//! to the roster an episode agreed on, and forming one again without the robots gone after
//! a roster failed.

use super::{Broken, Standing, TeamMember};
use crate::process::member_error::MemberError;
use crate::standing::agreement::{RosterNews, Sync};
use crate::standing::epoch::{Epoch, Forming, latest_epoch};
use crate::standing::plane::TeamPlane;
use crate::standing::roster::{Change, CutOff, EpochId, Roster, after_loss};
use crate::team::errors::JoinError;
use admm_ta_transport::exchange::ExchangeError;
use std::time::{Duration, Instant};

/// How long a robot waits for a vanished robot to show as gone before it takes a failure
/// for the team's: on one machine a process's death shows at once; across machines a
/// vanished robot's token goes within Zenoh's lease (10 s).
fn settle(plane: &dyn TeamPlane) -> Duration {
    if plane.exact() {
        Duration::from_millis(300)
    } else {
        Duration::from_secs(11)
    }
}

impl TeamMember {
    /// Out of the team: its roster and the plane.
    pub(super) fn depart(&mut self, standing: Standing) {
        if let Some(epoch) = self.epoch.take() {
            epoch.close(&*self.ctx.plane, true);
        }
        self.ctx.plane.leave_team();
        self.standing = standing;
    }

    /// To the roster an episode agreed on (its number the next).
    pub(super) fn move_on(&mut self, change: Change) {
        let Some(epoch) = self.epoch.take() else {
            return;
        };
        let mut next = EpochId {
            number: epoch.id.number + 1,
            roster: change.next,
        };
        epoch.close(&*self.ctx.plane, true);
        // Robots that could not finish the episode (a crash in its last rounds) may form
        // another roster: the later of the two is taken (the order every robot applies).
        if let Some(later) = latest_epoch(&*self.ctx.plane, self.id(), Some(&next)) {
            next = later;
        }
        self.known = RosterNews {
            joined: change.joined,
            ..RosterNews::default()
        };
        match Epoch::form(&self.ctx, next, Instant::now() + self.startup()) {
            Ok(epoch) => self.install(epoch),
            Err(e) => {
                tracing::debug!(error = %e, "the next roster did not form");
                self.broken = Some(Broken::forming(self.forming_error(e)));
            }
        }
    }

    pub(super) fn startup(&self) -> Duration {
        Duration::from_millis(self.ctx.scenario.startup_timeout_ms)
    }

    pub(super) fn round_timeout(&self) -> Duration {
        Duration::from_millis(self.ctx.scenario.round_timeout_ms)
    }

    /// A roster that did not form, as the failure it leaves behind.
    fn forming_error(&self, e: Forming) -> ExchangeError {
        ExchangeError::Transport {
            agent: self.id(),
            what: format!("the next roster did not form: {e}"),
        }
    }

    /// Takes roster `epoch` as this robot's: the sync that starts it (the episode the team
    /// is at, what changed). A failed sync leaves it broken (recovered from it).
    pub(super) fn install(&mut self, mut epoch: Epoch) {
        self.ctx.plane.set_member();
        let me = self.id();
        let n = self.robots();
        let known = std::mem::take(&mut self.known);
        let own = Sync::own(n, self.episode, &known);
        let (exchange, episodes) = epoch.parts();
        let synced = episodes.sync(exchange, own);
        self.base = Some(epoch.id.clone());
        self.base_formed = true;
        match synced {
            Ok(sync) => {
                self.episode = self.episode.max(sync.episode);
                self.news.merge(&sync.news());
                self.ctx.plane.set_formed(&epoch.id);
            }
            Err(e) => {
                epoch.blame(me, &e);
                self.known = known;
                self.broken = Some(Broken::forming(e));
            }
        }
        self.epoch = Some(epoch);
    }

    /// A formed, synced roster to run the next episode on: recovers a broken one.
    pub(super) fn ready(&mut self) -> Result<(), MemberError> {
        if let Some(signal) = admm_ta_transport::signals::received() {
            return Err(self.stop(signal));
        }
        while self.broken.is_some() || self.epoch.is_none() {
            if let Some(signal) = self.ctx.plane.stop_requested() {
                return Err(self.stopped(signal));
            }
            let failure = self.broken.take();
            self.recover(failure)?;
        }
        Ok(())
    }

    /// Forms a roster without the robots gone since `broken` broke the last one (see the
    /// module of [`crate::standing::roster`]).
    fn recover(&mut self, broken: Option<Broken>) -> Result<(), MemberError> {
        let me = self.id();
        if let Some(epoch) = self.epoch.take() {
            epoch.close(&*self.ctx.plane, false);
        }
        let Some(base) = self.base.clone() else {
            // Never formed a roster: join as a new robot does.
            return self.enter(Instant::now());
        };
        let started = Instant::now();
        let deadline = started + self.startup() + self.episode_timeout() + self.round_timeout();
        let settle_until = started + settle(&*self.ctx.plane);
        let (failure, forming) = match broken {
            Some(Broken { error, forming }) => (error, forming),
            None => (
                ExchangeError::Transport {
                    agent: me,
                    what: "the roster failed".into(),
                },
                true,
            ),
        };
        let mut given_up: Vec<EpochId> = Vec::new();
        loop {
            self.still_running()?;
            if !self.base_formed && self.running_without_me() {
                // Its first roster never formed, and the team runs without it: it asks to
                // join as a robot that comes late does.
                self.base = None;
                return self.enter(Instant::now());
            }
            let id = match self.next_roster(&base, &given_up, forming)? {
                Some(id) if !given_up.contains(&id) => id,
                // Nobody vanished (yet), or only a roster given up is in sight.
                next => {
                    let settled = next.is_none() && Instant::now() >= settle_until;
                    if settled || Instant::now() >= deadline {
                        // Nobody vanished: the failure is the team's.
                        return Err(self.fail(failure));
                    }
                    std::thread::sleep(Duration::from_millis(20));
                    continue;
                }
            };
            tracing::debug!(robot = me, epoch = %id.name(), "forming the roster again");
            match Epoch::form(&self.ctx, id.clone(), deadline) {
                Ok(epoch) => {
                    self.install(epoch);
                    return Ok(());
                }
                Err(Forming::Stopped(signal)) => return Err(self.stopped(signal)),
                Err(e) => {
                    tracing::debug!(error = %e, "the roster did not form");
                    given_up.push(id);
                    if Instant::now() >= deadline {
                        return Err(self.fail(self.forming_error(e)));
                    }
                    // Before the next look: the others see what this robot saw.
                    std::thread::sleep(Duration::from_millis(20));
                }
            }
        }
    }

    /// An error when the team must stop: a termination signal to this process, or a stop
    /// request of another robot.
    fn still_running(&mut self) -> Result<(), MemberError> {
        if let Some(signal) = admm_ta_transport::signals::received() {
            return Err(self.stop(signal));
        }
        match self.ctx.plane.stop_requested() {
            Some(signal) => Err(self.stopped(signal)),
            None => Ok(()),
        }
    }

    /// The roster to form after `base` failed: without the robots gone from it (their
    /// largest part, this robot in it), or a later one the others are forming; numbered
    /// after the rosters `given_up`. `None` while nobody is gone and, the roster having
    /// failed while it ran (not `forming`), the failure may be the team's.
    fn next_roster(
        &mut self,
        base: &EpochId,
        given_up: &[EpochId],
        forming: bool,
    ) -> Result<Option<EpochId>, MemberError> {
        let me = self.id();
        let others: Vec<usize> = base
            .roster
            .robots()
            .iter()
            .copied()
            .filter(|&r| r != me)
            .collect();
        let gone = self.ctx.plane.gone(&others);
        let adopt = latest_epoch(&*self.ctx.plane, me, Some(base))
            .filter(|e| e.number > base.number && !given_up.contains(e));
        if gone.is_empty() && adopt.is_none() && !forming {
            return Ok(None);
        }
        // Where it may have been cut off rather than its neighbours dead, it goes on only
        // with most of the roster it formed.
        let majority = !self.ctx.plane.exact() && self.base_formed;
        let (next, lost) =
            match after_loss(&self.ctx.settings.graph, &base.roster, &gone, me, majority) {
                Ok(found) => found,
                Err(cut) => return Err(self.cut_off(cut)),
            };
        self.known = RosterNews {
            joined: Vec::new(),
            crashed: gone,
            lost,
        };
        // A roster given up is not formed again: the next attempt is numbered after it (a
        // robot still on an earlier one sees it and follows).
        let next = EpochId {
            number: base.number + 1 + given_up.len() as u64,
            roster: next,
        };
        Ok(Some(match adopt {
            Some(found) if found >= next => found,
            _ => next,
        }))
    }

    /// Whether robots run a roster (formed) without this one.
    fn running_without_me(&self) -> bool {
        let plane = &*self.ctx.plane;
        let me = self.id();
        plane
            .epochs()
            .iter()
            .any(|e| !e.roster.contains(me) && plane.formed(e) && !plane.in_epoch(e).is_empty())
    }

    /// The team went on without this robot.
    fn cut_off(&mut self, cut: CutOff) -> MemberError {
        if let Some(epoch) = self.epoch.take() {
            epoch.close(&*self.ctx.plane, false);
        }
        self.ctx.plane.leave_team();
        self.standing = Standing::Lost(cut.to_string());
        MemberError::failed(cut)
    }

    /// A robot coming to the team: forms its first roster with the others (none formed
    /// yet), takes its place in one forming with it, or asks to join and waits to be
    /// admitted (see [`TeamMember::join`]).
    pub(super) fn enter(&mut self, started: Instant) -> Result<(), MemberError> {
        let me = self.id();
        let startup = self.startup();
        let admission = startup + 2 * (self.episode_timeout() + self.round_timeout());
        let deadline = started + admission;
        let first = EpochId {
            number: 0,
            roster: Roster::all(self.robots()),
        };
        let mut given_up: Vec<EpochId> = Vec::new();
        let mut asked = false;
        loop {
            self.still_running()?;
            let plane = &*self.ctx.plane;
            let found = latest_epoch(plane, me, None).filter(|e| !given_up.contains(e));
            let running = plane.epochs().iter().any(|e| !plane.in_epoch(e).is_empty());
            let id = match found {
                Some(id) => id,
                None if given_up.contains(&first) => {
                    // The team's first roster did not form with every robot: those that
                    // came go on without the others.
                    self.base = Some(first);
                    self.base_formed = false;
                    self.broken = Some(Broken::forming(ExchangeError::Transport {
                        agent: me,
                        what: "the team's first roster did not form".into(),
                    }));
                    return self.ready();
                }
                None if !running => first.clone(),
                None => {
                    // The team runs without this robot: it asks to join.
                    if !asked {
                        asked = true;
                        tracing::info!(robot = me, "asking to join the running team");
                    }
                    self.ctx.plane.set_joining();
                    if Instant::now() >= deadline {
                        return Err(self.not_admitted(admission));
                    }
                    std::thread::sleep(Duration::from_millis(20));
                    continue;
                }
            };
            self.ctx.plane.set_member();
            let until = if id.number == 0 {
                started + startup
            } else {
                deadline
            };
            match Epoch::form(&self.ctx, id.clone(), until) {
                Ok(epoch) => {
                    self.install(epoch);
                    return self.ready();
                }
                Err(Forming::Stopped(signal)) => return Err(self.stopped(signal)),
                Err(e) => {
                    tracing::debug!(error = %e, epoch = %id.name(), "the roster did not form");
                    if Instant::now() >= deadline {
                        return Err(self.fail(self.forming_error(e)));
                    }
                    given_up.push(id);
                }
            }
        }
    }

    /// The team never admitted this robot.
    fn not_admitted(&mut self, waited: Duration) -> MemberError {
        let me = self.id();
        self.standing = Standing::Failed;
        MemberError::failed(JoinError::NotAdmitted {
            robot: me,
            waited,
            neighbours: self.ctx.settings.graph.neighbours(me).to_vec(),
        })
    }
}
