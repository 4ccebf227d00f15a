//! One robot of a standing team with private costs: [`TeamMember`].

use crate::board::Board;
use crate::endpoint::AgentEndpoint;
use crate::exchange::ExchangeError;
use crate::process::agent::tell_the_team;
use crate::process::connect::connect;
use crate::process::member_error::MemberError;
use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::standing::agreement::Presence;
use crate::standing::answer::{Answer, RowError};
use crate::standing::episode::{EpisodeError, Episodes};
use crate::team::errors::{PrivateTeamError, TeamFileError};
use crate::team::member::{Membership, member_of};
use crate::team::team_file::Team;
use std::path::Path;
use std::time::{Duration, Instant};

/// One robot of a standing team whose robots keep their costs (`costs = "private"` in the
/// team file): it joins once, then solves episode after episode with its own row, and
/// never sends, receives or stores another robot's costs.
///
/// Around every episode the team floods, for the graph's diameter `D` rounds each, its
/// scale (lowest and highest allowed cost and their lattice, so that every robot normalises
/// its own row as a solve of the stacked rows would), the episode's tasks and who takes no
/// part before, and every robot's cost of its own task after (the total and the
/// feasibility) — [`crate::standing::agreement`]. The method then starts from the last
/// episode's iterates (`warm_start`, the default, when the same robots and tasks take part)
/// with a fresh certified stop.
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
    episodes: Episodes,
    scenario: Scenario,
    episode: u64,
    /// Robots that left: the team has ended.
    left: Vec<usize>,
    /// The run failed: nothing more goes out.
    failed: bool,
    endpoint: Option<Box<dyn AgentEndpoint>>,
    membership: Option<Membership>,
    namespace: RunNamespace,
}

impl TeamMember {
    /// Joins the team of `team_path` as robot `id`, waiting for its neighbours until the
    /// team file's start-up deadline.
    ///
    /// While it joins, and while an episode runs, termination signals are recorded (the
    /// team stops cleanly: the call returns the stop and every robot of the team stops);
    /// between calls the process's own handlers apply.
    pub fn join(team_path: &Path, id: usize) -> Result<Self, MemberError> {
        let _signals = crate::signals::install();
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
        let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
        let membership = if team.file.transport.host_board() {
            Some(
                Membership::join(&scenario, &namespace, &[id], deadline)
                    .map_err(MemberError::refused)?,
            )
        } else {
            None
        };
        let plan = scenario.plan(id).map_err(MemberError::refused)?;
        let endpoint = match connect(&scenario, &graph, id, &namespace.dir, false, deadline) {
            Ok(endpoint) => endpoint,
            Err(e) => {
                if let Some(membership) = membership {
                    membership.leave();
                }
                return Err(e);
            }
        };
        tracing::debug!(robot = id, "joined the standing team");
        Ok(Self {
            episodes: Episodes::new(&team, id, &scenario, options, graph, plan),
            scenario,
            episode: 0,
            left: Vec::new(),
            failed: false,
            endpoint: Some(endpoint),
            membership,
            namespace,
        })
    }

    /// This robot's number.
    pub fn id(&self) -> usize {
        self.episodes.id
    }

    /// The most costs a row may have (the team's declared number of tasks).
    pub fn tasks(&self) -> usize {
        self.episodes.tasks
    }

    /// The rows are profits (the team file's `maximize`).
    pub fn maximize(&self) -> bool {
        self.episodes.maximize
    }

    /// The team's robots.
    pub fn robots(&self) -> usize {
        self.episodes.robots
    }

    /// How long the team waits for a robot's row ([`TeamMember::abstain`] when it has none).
    pub fn episode_timeout(&self) -> Duration {
        self.episodes.episode_timeout
    }

    /// Checks `row` as [`TeamMember::assign`] would, without the team.
    pub fn check_row(&self, row: &[Option<f64>]) -> Result<(), RowError> {
        if !self.left.is_empty() {
            return Err(RowError::Ended(self.left.clone()));
        }
        crate::standing::answer::check_row(row, self.tasks())
    }

    /// One episode with this robot's `row`, one cost per task of the episode (every robot
    /// gives as many; at most the team's `tasks`; `None`: a task it may not take): its task
    /// once the team has agreed. A row that cannot be used is refused before the team sees
    /// it ([`RowError`], inside [`MemberError::Refused`]).
    pub fn assign(&mut self, row: &[Option<f64>]) -> Result<Answer, MemberError> {
        self.check_row(row).map_err(MemberError::refused)?;
        self.episode_with(Some(row), Presence::Row { len: row.len() })
    }

    /// One episode without a row (the robot's program had none in time): every robot's
    /// answer names this one in `missing`; the team solves nothing (`on_failure = "abort"`,
    /// the default) or solves without it while it relays (`"continue"`).
    pub fn abstain(&mut self) -> Result<Answer, MemberError> {
        self.episode_with(None, Presence::Missing)
    }

    /// One episode in which this robot takes no task: it relays for its neighbours, and the
    /// others share the tasks (every robot's answer names it in `unavailable`).
    pub fn unavailable(&mut self) -> Result<Answer, MemberError> {
        self.episode_with(None, Presence::Unavailable)
    }

    /// Leaves the team: the other robots learn it in the next episode's agreement (their
    /// answers name this robot in `left`) and the team ends. Returns once they have heard.
    pub fn leave(mut self) -> Result<(), MemberError> {
        if self.left.is_empty() && !self.failed {
            self.episode_with(None, Presence::Leaving)?;
        }
        Ok(())
    }

    /// While the robot waits for its program's row: an error when the team must stop — a
    /// termination signal to this process (the whole team stops), or, on the team's board, a
    /// stop request or a failed robot. (A Zenoh team has no board: its robots learn it in
    /// the next episode's first round.)
    pub fn check(&mut self) -> Result<(), MemberError> {
        if self.failed {
            return Ok(());
        }
        if let Some(signal) = crate::signals::received() {
            return Err(self.stop(signal));
        }
        let round = self.episodes.round();
        let verdict = match self.membership.as_ref().map(Membership::board) {
            Some(board) => board.check_team(self.id(), round),
            None => Ok(()),
        };
        verdict.map_err(|e| {
            self.failed = true;
            if let ExchangeError::Stopped { signal, .. } = e {
                // Another process got the signal: this one ends as if it had.
                crate::signals::record(signal);
            }
            MemberError::failed(e)
        })
    }

    /// Stops the whole team because this process got termination signal `signal`.
    pub fn stop(&mut self, signal: i32) -> MemberError {
        crate::signals::record(signal);
        let stopped = ExchangeError::Stopped {
            agent: self.id(),
            signal,
        };
        self.blame(&stopped);
        self.failed = true;
        MemberError::failed(stopped)
    }

    fn episode_with(
        &mut self,
        row: Option<&[Option<f64>]>,
        presence: Presence,
    ) -> Result<Answer, MemberError> {
        if self.failed {
            return Err(MemberError::refused(RowError::Failed));
        }
        if !self.left.is_empty() {
            return Err(MemberError::refused(RowError::Ended(self.left.clone())));
        }
        let began = Instant::now();
        // A termination signal while the episode runs stops the team cleanly.
        let _signals = crate::signals::install();
        let exchange = self
            .endpoint
            .as_mut()
            .expect("joined until dropped")
            .exchange();
        let outcome = match self.episodes.run(exchange, row, presence) {
            Ok(outcome) => outcome,
            Err(e) => {
                self.failed = true;
                if let EpisodeError::Exchange(error) = &e {
                    self.blame(error);
                }
                return Err(MemberError::failed(e));
            }
        };
        let episode = self.episode;
        self.episode += 1;
        self.left = outcome.opening.leaving();
        Ok(outcome.answer(episode, self.id(), row, began.elapsed()))
    }

    /// After a failed episode: who is to blame, on the board and to the other agents (no
    /// launcher reports this one: a failure of its own is marked on the board; the first
    /// mark wins).
    fn blame(&self, error: &ExchangeError) {
        let Some(endpoint) = &self.endpoint else {
            return;
        };
        let board = self.membership.as_ref().map(Membership::board);
        tell_the_team(&**endpoint, board, self.id(), error);
        if let (Some(board), false) = (board, matches!(error, ExchangeError::Stopped { .. })) {
            let _ = board.mark_failed(self.id());
        }
    }
}

impl Drop for TeamMember {
    /// Leaves the team's transport and board (the last member removes its shared memory);
    /// finished, not dead, for the others.
    fn drop(&mut self) {
        if let Ok(board) = Board::open(&self.scenario.board_shm, self.robots())
            && !self.failed
        {
            board.set_finished(self.id());
        }
        drop(self.endpoint.take());
        if let Some(membership) = self.membership.take() {
            membership.leave();
        } else {
            // A Zenoh team: nothing of the run is in its directory but other agents' files.
            let _ = std::fs::remove_dir(&self.namespace.dir);
        }
    }
}
