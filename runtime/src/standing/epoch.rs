//! One roster of a standing team as one robot holds it (an *epoch*): its own namespace, its
//! own run of the team's transport on the graph the roster induces, and the robot's
//! episodes on it.
//!
//! Every roster is a fresh run: its name ([`EpochId::name`]) names its namespace (a board,
//! transport files and shared memory of its own, inside the team's), so robots meet only on
//! the same roster, and nothing of an earlier roster (a dead robot's ports, a failure mark,
//! arrival counts) reaches a later one. Forming a roster is a rendezvous in two steps:
//! every robot of it says it is in ([`TeamPlane::enter_epoch`]) and waits for the others —
//! giving up at once when one of them is gone, or gave the roster up, or a later roster
//! with this robot in it appears — and only then connects the transport, whose own start-up
//! rendezvous then completes at once.

use crate::process::agent::tell_the_team;
use crate::process::connect::connect;
use crate::process::member_error::MemberError;
use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::standing::episode::{Episodes, Settings};
use crate::standing::plane::TeamPlane;
use crate::standing::roster::{EpochId, Roster};
use crate::team::membership::Membership;
use crate::team::team_file::Team;
use admm_ta_transport::board::Board;
use admm_ta_transport::endpoint::AgentEndpoint;
use admm_ta_transport::exchange::{Exchange, ExchangeError};
use std::time::{Duration, Instant};

/// What a robot of a standing team keeps for its whole life in the team.
pub(super) struct Context {
    pub(super) team: Team,
    pub(super) settings: Settings,
    /// The team's scenario, in the team's namespace: every roster's is derived from it.
    pub(super) scenario: Scenario,
    pub(super) namespace: RunNamespace,
    pub(super) plane: Box<dyn TeamPlane>,
}

impl Context {
    /// This robot.
    pub(super) fn me(&self) -> usize {
        self.settings.id
    }

    /// The scenario of roster `id` in its namespace `part`.
    fn scenario_of(&self, id: &EpochId, part: &RunNamespace) -> Scenario {
        let mut scenario = self.scenario.clone();
        scenario.roster = Some(id.roster.robots().to_vec());
        scenario.run_id = part.id.clone();
        scenario.prefix = part.prefix.clone();
        scenario.transport_root = part.transport_root();
        scenario.board_shm = part.board_shm();
        if let Some(config) = scenario.transport_config.as_mut()
            && let Some(object) = config.as_object_mut()
        {
            // A Zenoh team's keys of this roster, and the hosts it waits for: those with
            // robots in it (a host lost with its robots is none of its business).
            object.insert("epoch".into(), id.name().into());
            object.insert("hosts".into(), self.team.hosts_of(&id.roster).into());
        }
        scenario
    }
}

/// Why a roster did not form.
#[derive(Debug)]
pub(super) enum Forming {
    /// Robots of the roster are gone from the team.
    Gone(Vec<usize>),
    /// A robot that was in it gave it up.
    Abandoned(usize),
    /// A later roster with this robot in it is forming.
    Superseded(EpochId),
    /// These robots did not come before the deadline.
    NeverCame(Vec<usize>),
    /// A termination signal (to this process, or requested by another robot).
    Stopped(i32),
    /// The transport did not connect.
    Failed(MemberError),
}

impl std::fmt::Display for Forming {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Gone(gone) => write!(f, "robot(s) {gone:?} are gone"),
            Self::Abandoned(robot) => write!(f, "robot {robot} gave the roster up"),
            Self::Superseded(id) => write!(f, "roster {} supersedes it", id.name()),
            Self::NeverCame(missing) => {
                write!(f, "robot(s) {missing:?} did not come before the deadline")
            }
            Self::Stopped(signal) => write!(
                f,
                "stopped by {}",
                admm_ta_transport::signals::name(*signal)
            ),
            Self::Failed(e) => write!(f, "{}", e.text()),
        }
    }
}

/// How often a robot that waits for its roster looks for a later one.
const SUPERSEDED_EVERY: Duration = Duration::from_millis(50);

/// The latest roster ([`EpochId`]'s order) with robot `me` in it that robots are forming
/// (not formed yet: a restarted robot does not take its former self's place in a running
/// roster), after `after`, none of whose robots is gone from the team.
pub(super) fn latest_epoch(
    plane: &dyn TeamPlane,
    me: usize,
    after: Option<&EpochId>,
) -> Option<EpochId> {
    plane
        .epochs()
        .into_iter()
        .filter(|e| e.roster.contains(me) && after.is_none_or(|a| e > a))
        .filter(|e| !plane.in_epoch(e).is_empty() && !plane.formed(e))
        .filter(|e| {
            // The team's first roster waits for robots that have not started yet.
            let others: Vec<usize> = e
                .roster
                .robots()
                .iter()
                .copied()
                .filter(|&r| r != me)
                .collect();
            e.number == 0 || plane.absent(&others).is_empty()
        })
        .max()
}

/// Waits until every robot of roster `id` is in it (see the module).
fn await_roster(ctx: &Context, id: &EpochId, deadline: Instant) -> Result<(), Forming> {
    let plane = &*ctx.plane;
    let mut seen: Vec<usize> = Vec::new();
    let mut poll = Duration::from_millis(1);
    let mut next_look = Instant::now() + SUPERSEDED_EVERY;
    loop {
        if let Some(signal) =
            admm_ta_transport::signals::received().or_else(|| plane.stop_requested())
        {
            return Err(Forming::Stopped(signal));
        }
        let present = plane.in_epoch(id);
        if present.len() == id.roster.len() {
            return Ok(());
        }
        if let Some(&left) = seen.iter().find(|s| !present.contains(s)) {
            return Err(Forming::Abandoned(left));
        }
        seen = present;
        let missing = id.roster.without(&Roster::new(seen.iter().copied()));
        // The team's first roster waits for robots that have not started yet; a later one
        // gives up on a robot gone from the team (a joiner asks to join until it comes).
        let gone = plane.absent(&missing);
        if id.number > 0 && !gone.is_empty() {
            return Err(Forming::Gone(gone));
        }
        let now = Instant::now();
        if now >= next_look {
            next_look = now + SUPERSEDED_EVERY;
            if let Some(later) = latest_epoch(plane, ctx.me(), Some(id)) {
                return Err(Forming::Superseded(later));
            }
        }
        if now >= deadline {
            return Err(Forming::NeverCame(missing));
        }
        std::thread::sleep(poll);
        poll = (poll * 2).min(Duration::from_millis(10));
    }
}

/// One roster as this robot holds it (see the module).
pub(super) struct Epoch {
    pub(super) id: EpochId,
    pub(super) episodes: Episodes,
    endpoint: Option<Box<dyn AgentEndpoint>>,
    /// The roster's board (a team on one machine).
    membership: Option<Membership>,
    namespace: RunNamespace,
}

impl Epoch {
    /// Forms roster `id` with the other robots of it, until `deadline`.
    pub(super) fn form(ctx: &Context, id: EpochId, deadline: Instant) -> Result<Self, Forming> {
        let me = ctx.me();
        let part = ctx
            .namespace
            .within(&id.name())
            .map_err(|e| Forming::Failed(MemberError::failed(e)))?;
        ctx.plane.enter_epoch(&id);
        let formed = await_roster(ctx, &id, deadline).and_then(|()| {
            Self::connect(ctx, &id, &part, deadline).map_err(|e| match e.cause().downcast_ref() {
                Some(ExchangeError::Stopped { signal, .. }) => Forming::Stopped(*signal),
                _ => Forming::Failed(e),
            })
        });
        match formed {
            Ok((endpoint, membership, episodes)) => {
                tracing::debug!(robot = me, roster = ?id.roster.robots(), epoch = %id.name(), "formed a roster");
                Ok(Self {
                    id,
                    episodes,
                    endpoint: Some(endpoint),
                    membership,
                    namespace: part,
                })
            }
            Err(e) => {
                ctx.plane.give_up_epoch(&id);
                if !ctx.team.file.transport.host_board() {
                    let _ = std::fs::remove_dir_all(&part.dir);
                }
                Err(e)
            }
        }
    }

    /// The roster's board (on one machine), its run of the transport and the robot's
    /// episodes on it.
    #[allow(clippy::type_complexity)]
    fn connect(
        ctx: &Context,
        id: &EpochId,
        part: &RunNamespace,
        deadline: Instant,
    ) -> Result<(Box<dyn AgentEndpoint>, Option<Membership>, Episodes), MemberError> {
        let me = ctx.me();
        let scenario = ctx.scenario_of(id, part);
        let graph = scenario.graph().map_err(MemberError::failed)?;
        let plan = scenario.plan(me).map_err(MemberError::failed)?;
        let membership = if ctx.team.file.transport.host_board() {
            Some(Membership::join(&scenario, part, &[me], deadline).map_err(MemberError::failed)?)
        } else {
            None
        };
        let endpoint = match connect(&scenario, &graph, me, &part.dir, false, deadline) {
            Ok(endpoint) => endpoint,
            Err(e) => {
                if let Some(membership) = membership {
                    membership.leave();
                }
                return Err(e);
            }
        };
        let episodes = Episodes::new(
            ctx.settings.clone(),
            id.roster.clone(),
            plan,
            scenario.payload_len(),
        );
        Ok((endpoint, membership, episodes))
    }

    /// The robot's end of the roster's exchange, and its episodes on it.
    pub(super) fn parts(&mut self) -> (&mut dyn Exchange, &mut Episodes) {
        let exchange = self
            .endpoint
            .as_mut()
            .expect("open until closed")
            .exchange();
        (exchange, &mut self.episodes)
    }

    /// The roster's board (on one machine).
    pub(super) fn board(&self) -> Option<&Board> {
        self.membership.as_ref().map(Membership::board)
    }

    /// While the robot waits between episodes: a failure or a stop request of this roster.
    pub(super) fn check(&self, me: usize) -> Result<(), ExchangeError> {
        let round = self.episodes.round();
        match self.board() {
            Some(board) => board.check_team(me, round),
            None => self.endpoint.as_ref().map_or(Ok(()), |e| e.check()),
        }
    }

    /// After the roster failed with `error` (this robot's exchange saw it first, or a
    /// neighbour vanished): whom to blame, on the board and to the other robots, so that
    /// every robot of the roster stops waiting.
    pub(super) fn blame(&self, me: usize, error: &ExchangeError) {
        let Some(endpoint) = &self.endpoint else {
            return;
        };
        tell_the_team(&**endpoint, self.board(), me, error);
        if let (Some(board), false) = (self.board(), matches!(error, ExchangeError::Stopped { .. }))
        {
            let _ = board.mark_failed(me);
        }
    }

    /// Robot `gone` of the roster vanished from the team (seen on the plane between
    /// episodes): the roster failed, for every robot of it (`error`: this robot's view).
    pub(super) fn report_gone(&self, gone: usize, error: &ExchangeError) {
        match (self.board(), &self.endpoint) {
            (Some(board), _) => {
                let _ = board.mark_failed(gone);
            }
            (None, Some(endpoint)) => endpoint.blame_for(error),
            (None, None) => {}
        }
    }

    /// Leaves the roster: its transport, its board (the last robot out removes its
    /// namespace) and the plane's note.
    pub(super) fn close(mut self, plane: &dyn TeamPlane, finished: bool) {
        if let (Some(board), true) = (self.board(), finished) {
            board.set_finished(self.episodes.settings.id);
        }
        drop(self.endpoint.take());
        plane.leave_epoch(&self.id);
        match self.membership.take() {
            Some(membership) => membership.leave(),
            // Zenoh: nothing of the roster is in its directory but what this robot wrote.
            None => {
                let _ = std::fs::remove_dir_all(&self.namespace.dir);
            }
        }
    }
}
