//! One episode of a standing team, as one robot runs it on its roster: the opening
//! agreement (with who leaves and who asks to join), the method on the part of the roster
//! that takes part, the closing agreement; and the sync that starts every roster.

use crate::options::OnFailure;
use crate::options::SolveOptions;
use crate::process::scenario::Scenario;
use crate::standing::agreement::{Closing, Flooded, Opening, Participation, Sync};
use crate::standing::outcome::{Outcome, nothing_to_solve};
use crate::standing::roster::{LeaveRule, Roster, change};
use crate::team::team_file::Team;
use crate::workload::plan::{BadRho, prepare_for_stop};
use admm_ta_agents::agent::{ConsensusAgent, NewCostsError};
use admm_ta_agents::certify::local_stop::{LocalCertifiedStop, LocalStopError};
use admm_ta_agents::method::masked::{MaskedAgent, Part};
use admm_ta_agents::problem::private::TeamScale;
use admm_ta_agents::problem::ties;
use admm_ta_agents::problem::{AssignmentCase, CostMatrix, ProblemError, TaskAssignmentProblem};
use admm_ta_topologies::Graph;
use admm_ta_transport::exchange::round_loop::{AgentPlan, AgentStop, RoundLoop};
use admm_ta_transport::exchange::{Exchange, ExchangeError};
use std::time::{Duration, Instant};

/// Why an episode failed: the exchange, or (a bug: the part's shape is checked before)
/// its agent could not be built.
#[derive(Debug, thiserror::Error)]
pub(super) enum EpisodeError {
    #[error(transparent)]
    Exchange(#[from] ExchangeError),
    #[error("the episode's problem")]
    Problem(#[from] ProblemError),
    #[error(transparent)]
    Rho(#[from] BadRho),
    #[error(transparent)]
    Stop(#[from] LocalStopError),
    #[error("the episode's agent")]
    Costs(#[from] NewCostsError),
    #[error("the team's method has no agents")]
    NoAgents,
    #[error("the team's method does not run on part of a team")]
    NoParts,
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
        message.fill(0.0);
        value.write(message);
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

/// What every roster of a robot's standing team shares: the team file's settings and
/// graph, and the robot's number.
#[derive(Clone)]
pub(super) struct Settings {
    pub(super) id: usize,
    pub(super) robots: usize,
    pub(super) tasks: usize,
    pub(super) maximize: bool,
    pub(super) warm: bool,
    pub(super) seed: u64,
    pub(super) on_failure: OnFailure,
    pub(super) leave: LeaveRule,
    pub(super) episode_timeout: Duration,
    pub(super) options: SolveOptions,
    /// The team file's graph (every slot).
    pub(super) graph: Graph,
}

impl Settings {
    /// Robot `id`'s settings of the private team in `team` (whose `scenario` every robot
    /// derives alike), on the team file's `graph`.
    pub(super) fn new(
        team: &Team,
        id: usize,
        scenario: &Scenario,
        options: SolveOptions,
        graph: Graph,
    ) -> Self {
        Self {
            id,
            robots: scenario.robots,
            tasks: scenario.tasks,
            maximize: team.file.maximize,
            warm: team.file.warm_start.unwrap_or(true),
            seed: team.file.seed,
            on_failure: team.file.on_failure.unwrap_or_default(),
            leave: team.file.leave.unwrap_or_default(),
            episode_timeout: Duration::from_secs_f64(team.episode_timeout()),
            options,
            graph,
        }
    }
}

/// A robot's side of its standing team's episodes on one roster: what every episode needs
/// and what goes on from one to the next (the round loop, the agent of the last part).
pub(super) struct Episodes {
    pub(super) settings: Settings,
    /// The robots of this roster.
    roster: Roster,
    /// The graph the roster induces (the robots keep their numbers), its diameter, and the
    /// same graph renumbered (what the method's ρ and stop read of it).
    graph: Graph,
    compact: Graph,
    diameter: usize,
    pub(super) plan: AgentPlan,
    /// The agent of the last episode's part of the team (built on the first episode), with
    /// its stop rule.
    agent: Option<(MaskedAgent, LocalCertifiedStop)>,
    rounds: Option<RoundLoop>,
    /// Room for one round message (the agreement's).
    message: Vec<f64>,
    /// This robot's last row and the team's scale of that episode (how far its costs moved).
    last: Option<(Vec<Option<f64>>, TeamScale)>,
}

/// A warm start pays off when the costs moved less than this share of the team's range
/// since the last episode (every robot's row); farther, the team starts from zero
/// (`bench/README.md`: on redrawn costs a warm start took 15–16 rounds, a cold one 10–11).
const WARM_WITHIN: f64 = 0.1;

/// Whether `row` moved far from `last` (normalised by the last episode's `scale`): another
/// length, another forbidden pair, or a cost by more than [`WARM_WITHIN`] of the range.
fn moved_far(row: &[Option<f64>], last: &[Option<f64>], scale: &TeamScale) -> bool {
    if row.len() != last.len() {
        return true;
    }
    let range = scale.hi - scale.lo;
    row.iter().zip(last).any(|(new, old)| match (new, old) {
        (Some(new), Some(old)) => {
            // NaN (an infinite range) counts as far.
            let within = (new - old).abs() <= WARM_WITHIN * range;
            !within
        }
        (None, None) => false,
        _ => true,
    })
}

impl Episodes {
    /// The episodes of `settings`'s robot on `roster` (connected in the team file's graph,
    /// with the robot in it), with its round `plan`, in messages of `payload_len` values.
    pub(super) fn new(
        settings: Settings,
        roster: Roster,
        plan: AgentPlan,
        payload_len: usize,
    ) -> Self {
        let graph = settings.graph.induced(roster.robots());
        let compact = settings.graph.compacted(roster.robots());
        let diameter = compact.diameter().unwrap_or(0);
        Self {
            settings,
            roster,
            graph,
            compact,
            diameter,
            plan,
            agent: None,
            rounds: None,
            message: vec![0.0; payload_len],
            last: None,
        }
    }

    /// The round last gathered.
    pub(super) fn round(&self) -> u64 {
        self.rounds.as_ref().map_or(0, RoundLoop::round)
    }

    /// Rounds of every flood: the roster's diameter, at least one (a robot alone has 0).
    fn spread_rounds(&self) -> u64 {
        (self.diameter as u64).max(1)
    }

    /// How long the first round of a flood waits: the slowest robot's program may take the
    /// episode deadline to give its row.
    fn first_wait(&self) -> Duration {
        self.settings.episode_timeout + self.plan.round_timeout
    }

    /// Floods `value` for the roster's diameter (the first message of this roster, if it is:
    /// its round 0).
    fn spread(
        &mut self,
        exchange: &mut dyn Exchange,
        value: &mut dyn Flooded,
        wait: Duration,
    ) -> Result<(), ExchangeError> {
        if self.rounds.is_none() {
            self.message.fill(0.0);
            value.write(&mut self.message);
            let message = &self.message;
            let first = RoundLoop::start_with(exchange, &self.plan, 1, &mut |out| {
                out.copy_from_slice(message)
            })?;
            self.rounds = Some(first);
        }
        let times = self.spread_rounds();
        let rounds = self.rounds.as_mut().expect("started");
        flood(
            rounds,
            exchange,
            &self.plan,
            value,
            times,
            wait,
            &mut self.message,
        )
    }

    /// The sync that starts a roster: every robot's `own` (the episode it is at, what it
    /// finds changed), merged over the roster.
    pub(super) fn sync(
        &mut self,
        exchange: &mut dyn Exchange,
        mut own: Sync,
    ) -> Result<Sync, ExchangeError> {
        let wait = self.first_wait();
        self.spread(exchange, &mut own, wait)?;
        Ok(own)
    }

    /// The agent of `part` (this robot at `place` among its robots, or a relay) and the
    /// episode's stop rule.
    fn part_agent(
        &self,
        part: &Part,
        place: Option<usize>,
    ) -> Result<(MaskedAgent, LocalCertifiedStop), EpisodeError> {
        let (r, k) = (part.robots.len(), part.tasks.len());
        let case = if r == k {
            AssignmentCase::One
        } else {
            AssignmentCase::Two
        };
        // The part's shape (no costs: each robot gives its agent its own row).
        let shape = CostMatrix::new(r, k, vec![0.0; r * k])?;
        let problem = TaskAssignmentProblem::internal_from(shape, case)?;
        let setup = self
            .settings
            .options
            .method_setup()
            .ok_or(EpisodeError::NoAgents)?;
        // Every robot of the roster takes part in the stop, relays too: the tolerance is
        // shared among them all (a part's method sized for its robots alone gave each agent
        // more slack than its share of the team's, and a part of fewer than half of the
        // team's slots never certified).
        let stoppers = self.roster.len();
        let options = &self.settings.options;
        let plan = prepare_for_stop(&problem, &self.compact, options, setup, stoppers)?;
        // Its own neighbours, whatever its place among the robots that take part.
        let (n, id) = (self.settings.robots, self.settings.id);
        let degree = self.graph.degree(id);
        let layout = plan.agents.setup.parts().ok_or(EpisodeError::NoParts)?;
        let inner = plan.agents.agent_with_degree(place, degree);
        let stop = LocalCertifiedStop::new(plan.diameter, stoppers, plan.tolerance)?
            .with_cadence(plan.stop_cadence);
        let team = (n, self.settings.tasks);
        let (len, part) = (self.message.len(), part.clone());
        let agent = MaskedAgent::new(inner, team, len, layout, part, (place, degree));
        Ok((agent, stop))
    }

    /// The opening agreement: this robot's own (how it takes part, its row's scale, the
    /// joiners it sees), merged over the roster.
    fn open(
        &mut self,
        exchange: &mut dyn Exchange,
        row: Option<&[Option<f64>]>,
        part: Participation,
        joiners: &[usize],
    ) -> Result<Opening, ExchangeError> {
        let s = &self.settings;
        let scale = row.map_or(TeamScale::EMPTY, |r| TeamScale::of_row(r, s.maximize));
        let mut opening = Opening::own(s.robots, s.tasks, s.id, part, scale);
        if let (Some(row), Some((last, last_scale))) = (row, &self.last)
            && moved_far(row, last, last_scale)
        {
            opening.set_moved();
        }
        for &j in joiners.iter().filter(|&&j| !self.roster.contains(j)) {
            opening.set_joining(j);
        }
        let wait = self.first_wait();
        self.spread(exchange, &mut opening, wait)?;
        Ok(opening)
    }

    /// The part of the roster that solves the episode the `opening` describes, or why
    /// nothing is solved (and whether that is for want of a feasible assignment).
    fn part_of(&self, opening: &Opening) -> Result<Part, (String, bool)> {
        if let Some(why) = nothing_to_solve(opening, self.settings.on_failure) {
            return Err((why, false));
        }
        let (_, k) = opening.lengths().expect("checked: some robot gave costs");
        // Leavers relay in the episode of their leave.
        let absent: Vec<usize> = opening
            .missing()
            .into_iter()
            .chain(opening.unavailable())
            .chain(opening.leaving())
            .collect();
        let robots: Vec<usize> = self
            .roster
            .robots()
            .iter()
            .copied()
            .filter(|i| !absent.contains(i))
            .collect();
        if robots.len() < k {
            let why = format!(
                "infeasible: {} robot(s) took part for {k} tasks, and every task needs one",
                robots.len()
            );
            return Err((why, true));
        }
        if opening.scale.is_empty() {
            let why = "infeasible: every task is forbidden to every robot".to_string();
            return Err((why, true));
        }
        Ok(Part {
            robots,
            tasks: (0..k).collect(),
        })
    }

    /// The agreement, the method and the closing of one episode (`joiners`: the robots this
    /// one sees ask to join).
    pub(super) fn run(
        &mut self,
        exchange: &mut dyn Exchange,
        row: Option<&[Option<f64>]>,
        part: Participation,
        joiners: &[usize],
    ) -> Result<Outcome, EpisodeError> {
        let first = self.rounds.as_ref().map(RoundLoop::round);
        let coded_before = exchange.sent_bytes();
        let mut outcome = self.agree_and_solve(exchange, row, part, joiners)?;
        // One message a round (the roster's first round, if it was this episode's, too), as
        // the transport coded them, or as they are.
        let rounds = self.round() + 1 - first.map_or(0, |r| r + 1);
        outcome.sent_bytes = match (coded_before, exchange.sent_bytes()) {
            (Some(before), Some(after)) => after - before,
            _ => rounds * (self.message.len() * size_of::<f64>()) as u64,
        };
        Ok(outcome)
    }

    fn agree_and_solve(
        &mut self,
        exchange: &mut dyn Exchange,
        row: Option<&[Option<f64>]>,
        part: Participation,
        joiners: &[usize],
    ) -> Result<Outcome, EpisodeError> {
        let opening = self.open(exchange, row, part, joiners)?;
        let change = change(
            &self.settings.graph,
            &self.roster,
            &opening.leaving(),
            &opening.joining(),
            self.settings.leave,
        );
        let agreement_rounds = self.spread_rounds();
        let part = match self.part_of(&opening) {
            Ok(part) => part,
            Err((why, infeasible)) => {
                return Ok(Outcome {
                    opening,
                    change,
                    task: None,
                    certified: false,
                    rounds: 0,
                    agreement_rounds,
                    sent_bytes: 0,
                    closing: None,
                    unsolved: Some(why),
                    infeasible,
                });
            }
        };
        let (task, certified, rounds, closing) = self.solve(exchange, row, &opening, part)?;
        Ok(Outcome {
            opening,
            change,
            task,
            certified,
            rounds,
            agreement_rounds: agreement_rounds * 2 + 1,
            sent_bytes: 0,
            closing: Some(closing),
            unsolved: None,
            infeasible: false,
        })
    }

    /// The method on `part`, then the closing agreement: this robot's task (`None`: it
    /// relayed), whether the stop certified it, the method's rounds and the closing.
    fn solve(
        &mut self,
        exchange: &mut dyn Exchange,
        row: Option<&[Option<f64>]>,
        opening: &Opening,
        part: Part,
    ) -> Result<(Option<usize>, bool, u64, Closing), EpisodeError> {
        let (n, id) = (self.settings.robots, self.settings.id);
        let k = part.tasks.len();
        let place = part.robots.iter().position(|&r| r == id);
        // The same part warm-starts from the last episode's iterates; another part starts
        // from zero.
        let same_part = self.agent.as_ref().is_some_and(|(a, _)| a.part() == &part);
        if !same_part {
            self.agent = Some(self.part_agent(&part, place)?);
        }
        let warm = self.settings.warm && same_part && !opening.moved();
        if let Some(row) = row {
            self.last = Some((row.to_vec(), opening.scale));
        }
        let costs = match (place, row) {
            (Some(_), Some(row)) => {
                // Its own row as a solve of the stacked rows would normalise and perturb it.
                let robots = part.robots.len();
                let s = &self.settings;
                let mut costs = opening.scale.normalised_row(row, s.maximize, robots, k);
                ties::perturb(&mut costs, id, opening.scale.epsilon(robots), s.seed);
                costs
            }
            // A relay adds nothing to the team's costs.
            _ => vec![0.0; k],
        };
        let (agent, stop) = self.agent.as_mut().expect("built above");
        agent.set_costs(&costs, warm)?;
        let rounds = self.rounds.as_mut().expect("started");
        let plan = &self.plan;
        // Its iterate again, so that the method's first step reads the neighbours' iterates.
        let current = &*agent;
        rounds.side_round(
            exchange,
            plan,
            Instant::now() + plan.round_timeout,
            &mut |out| current.write_initial_payload(out),
            &mut |_| {},
        )?;
        let before = rounds.round();
        let (task, certified) =
            rounds.run(agent, exchange, plan, AgentStop::Local(stop.clone()))?;
        let method_rounds = rounds.round() - before;
        let (task, cost) = match (place, row) {
            (Some(_), Some(row)) => (Some(task), row[task].unwrap_or(f64::INFINITY)),
            _ => (None, 0.0),
        };
        let message = &mut self.message;
        let mut closing = Closing::own(n, self.roster.robots(), id, task, cost);
        let times = (self.diameter as u64).max(1);
        flood(
            rounds,
            exchange,
            plan,
            &mut closing,
            times,
            plan.round_timeout,
            message,
        )?;
        Ok((task, certified.is_some(), method_rounds, closing))
    }
}
