//! One robot of a standing team with private costs: [`TeamMember`].

use crate::board::Board;
use crate::endpoint::AgentEndpoint;
use crate::exchange::round_loop::{AgentPlan, RoundLoop};
use crate::exchange::{Exchange, ExchangeError};
use crate::process::connect::connect;
use crate::process::member_error::MemberError;
use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::signals::SignalGuard;
use crate::standing::agreement::{Closing, Flooded, Opening};
use crate::standing::answer::{Answer, RowError};
use crate::team::errors::{JoinError, PrivateTeamError, TeamFileError};
use crate::team::member::{Membership, member_scenario};
use crate::team::team_file::Team;
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::problem::private::TeamScale;
use admm_ta_agents::problem::ties;
use admm_ta_topologies::Graph;
use std::path::Path;
use std::time::{Duration, Instant};

/// One robot of a standing team whose robots keep their costs (`costs = "private"` in the
/// team file): it joins once, then solves episode after episode with its own row, and
/// never sends, receives or stores another robot's costs.
///
/// Around every episode the team floods, for the graph's diameter `D` rounds each, its
/// scale (lowest and highest allowed cost and their lattice, so that every robot normalises
/// its own row as a solve of the stacked rows would) before, and every robot's cost of its
/// own task after (the total and the feasibility). The method then starts from the last
/// episode's iterates (`warm_start`, the default) with a fresh certified stop.
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
/// me.leave()?;
/// # Ok(()) }
/// ```
pub struct TeamMember {
    id: usize,
    robots: usize,
    tasks: usize,
    maximize: bool,
    warm: bool,
    seed: u64,
    episode_timeout: Duration,
    round_timeout: Duration,
    scenario: Scenario,
    graph: Graph,
    plan: AgentPlan,
    agent: MethodAgent,
    rounds: Option<RoundLoop>,
    /// Room for one round message (the agreement's).
    message: Vec<f64>,
    solved: u64,
    episode: u64,
    /// Robots that left: the team has ended.
    left: Vec<usize>,
    /// The run failed: nothing more goes out.
    failed: bool,
    endpoint: Option<Box<dyn AgentEndpoint>>,
    membership: Option<Membership>,
    namespace: RunNamespace,
    _signals: SignalGuard,
}

impl TeamMember {
    /// Joins the team of `team_path` as robot `id`, waiting for its neighbours until the
    /// team file's start-up deadline.
    pub fn join(team_path: &Path, id: usize) -> Result<Self, MemberError> {
        let signals = crate::signals::install();
        let started = Instant::now();
        let team = Team::read(team_path).map_err(MemberError::refused)?;
        if !team.is_private() {
            return Err(MemberError::refused(TeamFileError::Private(
                PrivateTeamError::NotPrivate,
            )));
        }
        let n = team.file.robots;
        if id >= n {
            return Err(MemberError::refused(JoinError::NoSuchAgent {
                id,
                robots: n,
            }));
        }
        let host = team
            .file
            .transport
            .bridged()
            .then(|| team.host_of(id))
            .flatten();
        let (mut scenario, namespace) = member_scenario(&team, host)?;
        let graph = scenario.graph().map_err(MemberError::refused)?;
        crate::process::limits::check(scenario.transport, 1, graph.degree(id))
            .map_err(MemberError::refused)?;
        let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
        let membership = if team.file.transport.host_board() {
            Some(
                Membership::join(&scenario, &namespace, &[id], deadline)
                    .map_err(MemberError::refused)?,
            )
        } else {
            let host = team.host_of(id).expect("checked: every robot is on a host");
            scenario.transport_config = serde_json::to_value(team.zenoh_links(host)).ok();
            None
        };
        let plan = scenario.plan(id).map_err(MemberError::refused)?;
        // Built from the team's shape (no costs); each episode gives it its own row.
        let agent = scenario.agent(id).map_err(MemberError::refused)?;
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
        let payload_len = scenario.payload_len();
        Ok(Self {
            id,
            robots: n,
            tasks: scenario.tasks,
            maximize: team.file.maximize,
            warm: team.file.warm_start,
            seed: team.file.seed,
            episode_timeout: Duration::from_secs_f64(team.file.episode_timeout),
            round_timeout: Duration::from_millis(scenario.round_timeout_ms),
            scenario,
            graph,
            plan,
            agent,
            rounds: None,
            message: vec![0.0; payload_len],
            solved: 0,
            episode: 0,
            left: Vec::new(),
            failed: false,
            endpoint: Some(endpoint),
            membership,
            namespace,
            _signals: signals,
        })
    }

    /// This robot's number.
    pub fn id(&self) -> usize {
        self.id
    }

    /// Costs per row.
    pub fn tasks(&self) -> usize {
        self.tasks
    }

    /// The team's robots.
    pub fn robots(&self) -> usize {
        self.robots
    }

    /// How long the team waits for a robot's row ([`TeamMember::abstain`] when it has none).
    pub fn episode_timeout(&self) -> Duration {
        self.episode_timeout
    }

    /// Checks `row` as [`TeamMember::assign`] would, without the team.
    pub fn check_row(&self, row: &[Option<f64>]) -> Result<(), RowError> {
        if !self.left.is_empty() {
            return Err(RowError::Ended(self.left.clone()));
        }
        if row.len() != self.tasks {
            return Err(RowError::Length {
                got: row.len(),
                tasks: self.tasks,
            });
        }
        match row
            .iter()
            .enumerate()
            .find(|(_, v)| v.is_some_and(|v| !v.is_finite()))
        {
            Some((index, value)) => Err(RowError::NotFinite {
                index,
                value: value.unwrap_or(f64::NAN),
            }),
            None => Ok(()),
        }
    }

    /// One episode with this robot's `row` (`None`: a task it may not take): its task once
    /// the team has agreed. A row that cannot be used is refused before the team sees it
    /// ([`RowError`], inside [`MemberError::Refused`]).
    pub fn assign(&mut self, row: &[Option<f64>]) -> Result<Answer, MemberError> {
        self.check_row(row).map_err(MemberError::refused)?;
        self.episode_with(Some(row), false)
    }

    /// One episode without a row (the robot's program had none in time): the team solves
    /// nothing and every robot's answer names this one in `missing`.
    pub fn abstain(&mut self) -> Result<Answer, MemberError> {
        if !self.left.is_empty() {
            return Err(MemberError::refused(RowError::Ended(self.left.clone())));
        }
        self.episode_with(None, false)
    }

    /// Leaves the team: the other robots learn it in the next episode's agreement (their
    /// answers name this robot in `left`) and the team ends. Returns once they have heard.
    pub fn leave(mut self) -> Result<(), MemberError> {
        if self.left.is_empty() && !self.failed {
            self.episode_with(None, true)?;
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
        let round = self.rounds.as_ref().map_or(0, RoundLoop::round);
        let verdict = match self.membership.as_ref().map(Membership::board) {
            Some(board) => board.check_team(self.id, round),
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
        if let Some(board) = self.membership.as_ref().map(Membership::board) {
            let _ = board.request_stop(signal, Some(self.id));
        }
        if let Some(endpoint) = &self.endpoint {
            endpoint.announce_stop(signal);
        }
        self.failed = true;
        MemberError::failed(ExchangeError::Stopped {
            agent: self.id,
            signal,
        })
    }

    fn episode_with(
        &mut self,
        row: Option<&[Option<f64>]>,
        leaving: bool,
    ) -> Result<Answer, MemberError> {
        if self.failed {
            return Err(MemberError::refused(RowError::Ended(self.left.clone())));
        }
        let began = Instant::now();
        let result = self.run_episode(row, leaving, began);
        if let Err(e) = &result {
            self.failed = true;
            self.blame(e);
        }
        let (task, certified, rounds, agreement_rounds, closing, opening) =
            result.map_err(MemberError::failed)?;
        let episode = self.episode;
        self.episode += 1;
        self.left = opening.leaving();
        let cost = task.map(|t| row.and_then(|r| r[t]).unwrap_or(f64::INFINITY));
        let total = closing.as_ref().and_then(Closing::total);
        let feasible = !opening.scale.is_empty() && total.is_none_or(|t| t.is_finite());
        Ok(Answer {
            episode,
            robot: self.id,
            task: task.filter(|_| feasible),
            certified: certified && feasible,
            rounds,
            agreement_rounds,
            cost: cost.filter(|c| c.is_finite()),
            total_cost: total.filter(|t| t.is_finite()),
            assignment: closing
                .as_ref()
                .and_then(Closing::assignment)
                .filter(|_| feasible),
            feasible,
            missing: opening.missing(),
            left: opening.leaving(),
            ms: began.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// The agreement, the method and the closing of one episode.
    #[allow(clippy::type_complexity)]
    fn run_episode(
        &mut self,
        row: Option<&[Option<f64>]>,
        leaving: bool,
        began: Instant,
    ) -> Result<(Option<usize>, bool, u64, u64, Option<Closing>, Opening), ExchangeError> {
        let (n, m, id) = (self.robots, self.tasks, self.id);
        // At least one round: a team of one robot has diameter 0.
        let spread_rounds = (self.graph.diameter().unwrap_or(0) as u64).max(1);
        let exchange = self.endpoint.as_mut().expect("joined").exchange();
        let mut opening = Opening::own(
            n,
            id,
            row.map(|r| TeamScale::of_row(r, self.maximize)),
            leaving,
        );
        // The slowest robot's program may take the episode deadline to give its row.
        let wait = self.episode_timeout + self.round_timeout;
        if self.rounds.is_none() {
            write_message(&opening, &mut self.message);
            let message = &self.message;
            let first = RoundLoop::start_with(exchange, &self.plan, 1, &mut |out| {
                out.copy_from_slice(message)
            })?;
            self.rounds = Some(first);
        }
        let rounds = self.rounds.as_mut().expect("started");
        let plan = &self.plan;
        let message = &mut self.message;
        flood(
            rounds,
            exchange,
            plan,
            &mut opening,
            spread_rounds,
            wait,
            message,
        )?;
        let (Some(row), true, true) = (
            row,
            opening.missing().is_empty() && opening.leaving().is_empty(),
            !opening.scale.is_empty(),
        ) else {
            // Somebody has no row, leaves, or no pair is allowed: nothing to solve.
            return Ok((None, false, 0, spread_rounds, None, opening));
        };
        // Its own row as a solve of the stacked rows would normalise and perturb it.
        let mut normalised = opening.scale.normalised_row(row, self.maximize, n, m);
        ties::perturb(&mut normalised, id, opening.scale.epsilon(n), self.seed);
        let warm = self.warm && self.solved > 0;
        self.agent
            .set_costs(&normalised, warm)
            .map_err(|e| ExchangeError::Transport {
                agent: id,
                what: e.to_string(),
            })?;
        // Its iterate again, so that the method's first step reads the neighbours' iterates.
        let agent = &self.agent;
        rounds.side_round(
            exchange,
            plan,
            Instant::now() + self.round_timeout,
            &mut |out| agent.write_initial_payload(out),
            &mut |_| {},
        )?;
        let before = rounds.round();
        let (task, certified) = rounds.run(&mut self.agent, exchange, plan, plan.stop.clone())?;
        let method_rounds = rounds.round() - before;
        self.solved += 1;
        let cost = row[task].unwrap_or(f64::INFINITY);
        let mut closing = Closing::own(n, message.len(), id, task, cost);
        flood(
            rounds,
            exchange,
            plan,
            &mut closing,
            spread_rounds,
            self.round_timeout,
            message,
        )?;
        tracing::debug!(
            episode = self.episode,
            task,
            rounds = method_rounds,
            ms = began.elapsed().as_secs_f64() * 1e3,
            "episode answered"
        );
        Ok((
            Some(task),
            certified.is_some(),
            method_rounds,
            spread_rounds * 2 + 1,
            Some(closing),
            opening,
        ))
    }

    /// After a failed episode: who is to blame, on the board and to the other agents.
    fn blame(&self, error: &ExchangeError) {
        let Some(endpoint) = &self.endpoint else {
            return;
        };
        if let ExchangeError::Stopped { signal, .. } = error {
            if crate::signals::received().is_some() {
                if let Some(board) = self.membership.as_ref().map(Membership::board) {
                    let _ = board.request_stop(*signal, Some(self.id));
                }
                endpoint.announce_stop(*signal);
            }
            crate::signals::record(*signal);
        } else {
            endpoint.blame_for(error);
            if let Some(board) = self.membership.as_ref().map(Membership::board) {
                let _ = board.mark_failed(self.id);
            }
        }
    }
}

/// `value` as a whole message (zeros after it).
fn write_message(value: &dyn Flooded, message: &mut [f64]) {
    message.fill(0.0);
    value.write(message);
}

/// `times` side rounds in which every robot sends `value` and merges its neighbours'
/// (`message`: room for one message, filled here).
fn flood(
    rounds: &mut RoundLoop,
    exchange: &mut dyn Exchange,
    plan: &AgentPlan,
    value: &mut dyn Flooded,
    times: u64,
    wait: Duration,
    message: &mut [f64],
) -> Result<(), ExchangeError> {
    for _ in 0..times {
        write_message(value, message);
        let message = &*message;
        rounds.side_round(
            exchange,
            plan,
            Instant::now() + wait,
            &mut |out| out.copy_from_slice(message),
            &mut |ex| {
                for k in 0..ex.degree() {
                    value.merge(ex.neighbour_payload(k));
                }
            },
        )?;
    }
    Ok(())
}

impl Drop for TeamMember {
    /// Leaves the team's transport and board (the last member removes its shared memory);
    /// finished, not dead, for the others.
    fn drop(&mut self) {
        if let Ok(board) = Board::open(&self.scenario.board_shm, self.robots)
            && !self.failed
        {
            board.set_finished(self.id);
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
