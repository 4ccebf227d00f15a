//! One robot of a standing team with private costs: [`TeamMember`].
//!
//! Its episodes, its leave and its checks between episodes are here; how it gets to a
//! roster (joining, moving on, forming one again after a crash) is in `rosters`.

use crate::process::member_error::MemberError;
use crate::standing::agreement::{Participation, RosterNews};
use crate::standing::answer::{Answer, LeaveRefused, RowError};
use crate::standing::episode::{EpisodeError, Settings};
use crate::standing::epoch::{Context, Epoch};
use crate::standing::outcome::Outcome;
use crate::standing::plane::{BoardPlane, TeamPlane};
use crate::standing::roster::EpochId;
use crate::team::errors::{PrivateTeamError, TeamFileError};
use crate::team::membership::member_of;
use crate::team::team_file::Team;
use admm_ta_transport::exchange::ExchangeError;
mod rosters;

use std::path::Path;
use std::time::{Duration, Instant};

/// Where a robot stands in its team.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Standing {
    /// It takes part.
    In,
    /// It left.
    Left,
    /// The team went on without it (a forced leave or a loss cut it off).
    Lost(String),
    /// The team failed (a signal, or a failure nobody could recover from).
    Failed,
}

/// One robot of a standing team whose robots keep their costs (`costs = "private"` in the
/// team file): it joins once, then solves episode after episode with its own row, and
/// never sends, receives or stores another robot's costs.
///
/// Around every episode the team floods, for its roster's diameter `D` rounds each, its
/// scale (lowest and highest allowed cost and their lattice, so that every robot normalises
/// its own row as a solve of the stacked rows would), the episode's tasks, who takes no
/// part, who leaves and who asks to join before, and every robot's cost of its own task
/// after (the total and the feasibility) — [`crate::standing::agreement`]. The method then
/// starts from the last episode's iterates (`warm_start`, the default, when the same robots
/// and tasks take part) with a fresh certified stop.
///
/// **Robots come and go.** The team file lists the robots' slots; the team's *roster* is
/// who takes part now ([`crate::standing::roster`]). A robot started for a free slot (one
/// nobody runs, or whose robot left or crashed) is admitted at the next episode boundary
/// and answers from the episode after; [`TeamMember::leave`] takes a robot out at the next
/// boundary (refused, and the robot stays, when the others would fall apart); a robot whose
/// process dies costs the team at most the episode in flight: the others drop it, solve that
/// episode again without it and go on. Every roster is a fresh run of the team's transport
/// on the graph it induces, with its own diameter: the certificate holds on every one.
///
/// ```no_run
/// use admm_ta_runtime::standing::TeamMember;
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// // team.toml: run = "fleet", robots = 4, tasks = 4, costs = "private", topology = "ring"
/// let mut me = TeamMember::join("team.toml".as_ref(), 2)?;
/// for step in 0..10 {
///     let row = [Some(3.0 + step as f64), Some(1.0), None, Some(7.5)]; // None: forbidden
///     let answer = me.assign(&row)?;
///     println!("episode {}: task {:?}, certified {}", answer.episode, answer.task, answer.certified);
/// }
/// me.unavailable()?; // an episode without this robot: it relays for its neighbours
/// me.leave()?;
/// # Ok(()) }
/// ```
pub struct TeamMember {
    ctx: Context,
    /// The roster this robot is in (formed, synced).
    epoch: Option<Epoch>,
    /// The last roster it formed (or, founding the team, tried to): what a recovery
    /// starts from.
    base: Option<EpochId>,
    /// The base formed: robots that vanish from it may have gone on without this one.
    base_formed: bool,
    /// Its roster failed: why, until it recovers.
    broken: Option<Broken>,
    /// The episode it answers next.
    episode: u64,
    /// What its next answer tells of the roster's changes.
    news: RosterNews,
    /// What it adds to the next sync: the changes it knows of.
    known: RosterNews,
    standing: Standing,
    /// When it last looked at its neighbours between episodes.
    looked: Instant,
}

/// A roster that failed.
#[derive(Debug)]
struct Broken {
    error: ExchangeError,
    /// It failed while forming (a robot that never came, a sync cut short): the same
    /// robots may form it again even when none of them is gone.
    forming: bool,
}

impl Broken {
    fn running(error: ExchangeError) -> Self {
        Self {
            error,
            forming: false,
        }
    }

    fn forming(error: ExchangeError) -> Self {
        Self {
            error,
            forming: true,
        }
    }
}

/// How often a robot waiting between episodes looks at its neighbours on the plane.
const LOOK_EVERY: Duration = Duration::from_millis(100);

/// Robot `id`'s plane of the team (its scenario and namespace are the team's, or its
/// host's): the team's board on one machine, Zenoh across machines.
fn open_plane(
    team: &Team,
    scenario: &crate::process::scenario::Scenario,
    namespace: &crate::process::namespace::RunNamespace,
    id: usize,
    deadline: Instant,
) -> Result<Box<dyn TeamPlane>, MemberError> {
    if team.file.transport.across_hosts() {
        return crate::standing::zenoh_plane::open(team, scenario, id, deadline);
    }
    let plane =
        BoardPlane::open(scenario, namespace, id, deadline).map_err(MemberError::refused)?;
    Ok(Box::new(plane))
}

impl TeamMember {
    /// Joins the team of `team_path` as robot `id`: it forms the team's first roster with
    /// the others (waiting for every robot of the team file until its start-up deadline),
    /// takes its place in a roster forming with it, or — the team running without it — asks
    /// to join and waits to be admitted at the next episode boundary.
    ///
    /// While it joins, and while an episode runs, termination signals are recorded (the
    /// team stops cleanly: the call returns the stop and every robot of the team stops);
    /// between calls the process's own handlers apply.
    pub fn join(team_path: &Path, id: usize) -> Result<Self, MemberError> {
        let _signals = admm_ta_transport::signals::install();
        let started = Instant::now();
        let team = Team::read(team_path).map_err(MemberError::refused)?;
        if !team.is_private() {
            return Err(MemberError::refused(TeamFileError::Private(
                PrivateTeamError::NotPrivate,
            )));
        }
        let options = team.solve_options().map_err(MemberError::refused)?;
        let (scenario, namespace) = member_of(&team, id)?;
        let graph = scenario.graph().map_err(MemberError::refused)?;
        let startup = Duration::from_millis(scenario.startup_timeout_ms);
        let plane = open_plane(&team, &scenario, &namespace, id, started + startup)?;
        let settings = Settings::new(&team, id, &scenario, options, graph);
        let mut member = Self {
            ctx: Context {
                team,
                settings,
                scenario,
                namespace,
                plane,
            },
            epoch: None,
            base: None,
            base_formed: false,
            broken: None,
            episode: 0,
            news: RosterNews::default(),
            known: RosterNews::default(),
            standing: Standing::In,
            looked: Instant::now(),
        };
        member.enter(started)?;
        tracing::debug!(robot = id, "joined the standing team");
        Ok(member)
    }

    /// This robot's number.
    pub fn id(&self) -> usize {
        self.ctx.me()
    }

    /// The most costs a row may have (the team's declared number of tasks).
    pub fn tasks(&self) -> usize {
        self.ctx.settings.tasks
    }

    /// The rows are profits (the team file's `maximize`).
    pub fn maximize(&self) -> bool {
        self.ctx.settings.maximize
    }

    /// The team's robots (its slots: who takes part changes).
    pub fn robots(&self) -> usize {
        self.ctx.settings.robots
    }

    /// The robots that take part now (the current roster).
    pub fn roster(&self) -> Vec<usize> {
        self.epoch
            .as_ref()
            .map_or_else(Vec::new, |e| e.id.roster.robots().to_vec())
    }

    /// How long the team waits for a robot's row ([`TeamMember::abstain`] when it has none).
    pub fn episode_timeout(&self) -> Duration {
        self.ctx.settings.episode_timeout
    }

    /// The episode this robot answers next.
    pub fn episode(&self) -> u64 {
        self.episode
    }

    /// Checks `row` as [`TeamMember::assign`] would, without the team.
    pub fn check_row(&self, row: &[Option<f64>]) -> Result<(), RowError> {
        self.usable()?;
        crate::standing::answer::check_row(row, self.tasks())
    }

    /// An error when this robot can take part in no further episode.
    fn usable(&self) -> Result<(), RowError> {
        match &self.standing {
            Standing::In => Ok(()),
            Standing::Left => Err(RowError::Left),
            Standing::Lost(why) => Err(RowError::Lost(why.clone())),
            Standing::Failed => Err(RowError::Failed),
        }
    }

    /// One episode with this robot's `row`, one cost per task of the episode (every robot
    /// gives as many; at most the team's `tasks`; `None`: a task it may not take): its task
    /// once the team has agreed. A row that cannot be used is refused before the team sees
    /// it ([`RowError`], inside [`MemberError::Refused`]).
    pub fn assign(&mut self, row: &[Option<f64>]) -> Result<Answer, MemberError> {
        self.check_row(row).map_err(MemberError::refused)?;
        self.episode_with(Some(row), Participation::Row { len: row.len() })
    }

    /// One episode without a row (the robot's program had none in time): every robot's
    /// answer names this one in `missing`; the team solves nothing (`on_failure = "abort"`,
    /// the default) or solves without it while it relays (`"continue"`).
    pub fn abstain(&mut self) -> Result<Answer, MemberError> {
        self.episode_with(None, Participation::Missing)
    }

    /// One episode in which this robot takes no task: it relays for its neighbours, and the
    /// others share the tasks (every robot's answer names it in `unavailable`).
    pub fn unavailable(&mut self) -> Result<Answer, MemberError> {
        self.episode_with(None, Participation::Unavailable)
    }

    /// Leaves the team: it relays in one more episode, in which the others learn it (their
    /// answers name it in `left`), then it is out and the team goes on without it. When the
    /// others would fall apart without it, the leave is refused ([`LeaveRefused`], inside
    /// [`MemberError::Refused`]) and it stays: ask again later (each call is an episode in
    /// which it relays), or set `leave = "force"` in the team file.
    /// A robot the team went on without meanwhile (crashes split its roster, and its part
    /// does not go on) is out, as it asked: that is a leave too.
    pub fn leave(&mut self) -> Result<(), MemberError> {
        let me = self.id();
        while self.standing == Standing::In {
            let roster = self.roster();
            let answer = match self.episode_with(None, Participation::Leaving) {
                Err(e) if matches!(self.standing, Standing::Lost(_)) => {
                    tracing::info!(robot = me, why = %e, "left: its roster broke apart in its leave");
                    return Ok(());
                }
                other => other?,
            };
            if answer.leave_refused.contains(&me) {
                let others: Vec<usize> = roster.into_iter().filter(|&r| r != me).collect();
                return Err(MemberError::refused(LeaveRefused {
                    robot: me,
                    episode: answer.episode,
                    apart: self.ctx.settings.graph.components_among(&others),
                }));
            }
            // Else it left, or a crash cut the episode short after another robot had
            // answered it: the leave goes into the next.
        }
        match self.usable() {
            Err(RowError::Left) => Ok(()),
            other => other.map_err(MemberError::refused),
        }
    }

    /// While the robot waits for its program's row: an error when the team must stop — a
    /// termination signal to this process (the whole team stops), or a stop request of
    /// another robot. A roster that failed meanwhile (a robot crashed) is formed again
    /// without the robots gone, as the others do.
    pub fn check(&mut self) -> Result<(), MemberError> {
        if self.standing != Standing::In {
            return Ok(());
        }
        if let Some(signal) = admm_ta_transport::signals::received() {
            return Err(self.stop(signal));
        }
        if let Some(signal) = self.ctx.plane.stop_requested() {
            return Err(self.stopped(signal));
        }
        if self.broken.is_none()
            && let Some(epoch) = &self.epoch
        {
            if let Err(e) = epoch.check(self.id()) {
                if let ExchangeError::Stopped { signal, .. } = e {
                    return Err(self.stopped(signal));
                }
                self.broken = Some(Broken::running(e));
            } else if self.looked.elapsed() >= LOOK_EVERY {
                self.looked = Instant::now();
                self.look_at_neighbours();
            }
        }
        if self.broken.is_some() {
            let _signals = admm_ta_transport::signals::install();
            self.ready()?;
        }
        Ok(())
    }

    /// A neighbour of the roster gone from the plane: the roster failed (every robot of it
    /// learns it from the mark).
    fn look_at_neighbours(&mut self) {
        let me = self.id();
        let Some(epoch) = &self.epoch else {
            return;
        };
        let neighbours: Vec<usize> = self
            .ctx
            .settings
            .graph
            .neighbours(me)
            .iter()
            .copied()
            .filter(|&n| epoch.id.roster.contains(n))
            .collect();
        if let Some(&gone) = self.ctx.plane.gone(&neighbours).first() {
            let error = ExchangeError::PeerFailed {
                agent: me,
                failed: gone,
                round: epoch.episodes.round(),
                how: "left the team without a word".into(),
            };
            epoch.report_gone(gone, &error);
            self.broken = Some(Broken::running(error));
        }
    }

    /// Stops the whole team because this process got termination signal `signal`.
    pub fn stop(&mut self, signal: i32) -> MemberError {
        admm_ta_transport::signals::record(signal);
        self.ctx.plane.request_stop(signal, self.id());
        let stopped = ExchangeError::Stopped {
            agent: self.id(),
            signal,
        };
        if let Some(epoch) = &self.epoch {
            epoch.blame(self.id(), &stopped);
        }
        self.standing = Standing::Failed;
        MemberError::failed(stopped)
    }

    /// Another robot got termination signal `signal`: this one ends as if it had.
    fn stopped(&mut self, signal: i32) -> MemberError {
        admm_ta_transport::signals::record(signal);
        self.standing = Standing::Failed;
        MemberError::failed(ExchangeError::Stopped {
            agent: self.id(),
            signal,
        })
    }

    /// The team failed for this robot: it leaves its roster and the team (the others see
    /// it gone rather than wait for it) and nothing more goes out.
    fn fail(&mut self, error: impl Into<crate::process::member_error::Cause>) -> MemberError {
        self.standing = Standing::Failed;
        if let Some(epoch) = self.epoch.take() {
            epoch.close(&*self.ctx.plane, false);
        }
        self.ctx.plane.leave_team();
        MemberError::failed(error)
    }

    fn episode_with(
        &mut self,
        row: Option<&[Option<f64>]>,
        part: Participation,
    ) -> Result<Answer, MemberError> {
        self.usable().map_err(MemberError::refused)?;
        let began = Instant::now();
        // A termination signal while the episode runs stops the team cleanly.
        let _signals = admm_ta_transport::signals::install();
        loop {
            self.ready()?;
            let pending = self.episode;
            let me = self.id();
            let joiners = self.ctx.plane.joiners();
            let epoch = self.epoch.as_mut().expect("ready");
            let (exchange, episodes) = epoch.parts();
            match episodes.run(exchange, row, part, &joiners) {
                Ok(outcome) => return Ok(self.finish(outcome, row, began)),
                Err(EpisodeError::Exchange(e)) => {
                    epoch.blame(me, &e);
                    if let ExchangeError::Stopped { signal, .. } = e {
                        return Err(self.stopped(signal));
                    }
                    tracing::debug!(error = %e, episode = pending, "the roster failed");
                    self.broken = Some(Broken::running(e));
                    self.ready()?;
                    if self.episode > pending {
                        // Another robot answered this episode already: it is lost.
                        return Ok(self.lost_episode(pending, began));
                    }
                    // Solved again, on the new roster.
                }
                Err(e) => return Err(self.fail(e)),
            }
        }
    }

    /// The answer of episode `episode`, which a crash cut short after another robot had
    /// answered it.
    fn lost_episode(&mut self, episode: u64, began: Instant) -> Answer {
        let news = std::mem::take(&mut self.news);
        Answer {
            episode,
            robot: self.id(),
            task: None,
            certified: false,
            rounds: 0,
            agreement_rounds: 0,
            sent_bytes: 0,
            cost: None,
            total_cost: None,
            assignment: None,
            feasible: true,
            unsolved: Some(format!(
                "robot(s) {:?} crashed during this episode, after another robot had its answer",
                news.crashed
            )),
            missing: Vec::new(),
            unavailable: Vec::new(),
            left: Vec::new(),
            leave_refused: Vec::new(),
            lost: news.lost,
            joined: news.joined,
            crashed: news.crashed,
            ms: began.elapsed().as_secs_f64() * 1e3,
        }
    }

    /// The answer of an episode the roster finished, and the change of roster it agreed.
    fn finish(&mut self, outcome: Outcome, row: Option<&[Option<f64>]>, began: Instant) -> Answer {
        let episode = self.episode;
        self.episode += 1;
        let change = outcome.change.clone();
        let news = std::mem::take(&mut self.news);
        let me = self.id();
        let answer = outcome.answer(episode, me, row, began.elapsed(), news);
        if change.left.contains(&me) {
            self.depart(Standing::Left);
        } else if change.lost.contains(&me) {
            let why = format!(
                "robot(s) {:?} left and the team went on with robot(s) {:?}",
                change.left,
                change.next.robots()
            );
            self.depart(Standing::Lost(why));
        } else if let Some(epoch) = &self.epoch
            && change.next != epoch.id.roster
        {
            self.move_on(change);
        }
        answer
    }
}

impl Drop for TeamMember {
    /// Leaves the roster's transport and board (the last robot out removes its shared
    /// memory) and the team: without [`TeamMember::leave`] first, the others take this
    /// robot for crashed.
    fn drop(&mut self) {
        let finished = self.standing == Standing::In;
        if let Some(epoch) = self.epoch.take() {
            epoch.close(&*self.ctx.plane, finished);
        }
        self.ctx.plane.leave_team();
    }
}
