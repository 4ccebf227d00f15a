//! Where the `sim` transport's agents run: all of them in the calling thread (or a few
//! scoped workers for large teams), round by round, with the observer that watches each
//! round.

use crate::sim::exchange::SimInbox;
use admm_ta_agents::agent::{ConsensusAgent, StepReport};
use admm_ta_agents::certify::local_stop::{LocalCertifiedStop, NeighbourState, Verdict};
use admm_ta_agents::certify::stopping::TeamStopRule;
use admm_ta_topologies::Graph;

/// What an observer sees after each round.
pub struct RoundView<'a> {
    /// Rounds completed (1 after the first step).
    pub round: usize,
    pub reports: &'a [StepReport],
    /// Every agent's payload, concatenated (`payload_len` each).
    pub payloads: &'a [f64],
    pub payload_len: usize,
    /// The agents' own relaxed columns.
    pub columns: &'a dyn OwnColumns,
}

/// Each robot's own relaxed assignment vector `x_i` (whatever its method's payload is).
pub trait OwnColumns {
    fn own_column(&self, robot: usize) -> &[f64];
    /// The robot's own task in its rounded view of the team's assignment.
    fn rounded_task(&self, robot: usize) -> usize;
}

impl<A: ConsensusAgent> OwnColumns for Vec<A> {
    fn own_column(&self, robot: usize) -> &[f64] {
        self[robot].own_column()
    }
    fn rounded_task(&self, robot: usize) -> usize {
        self[robot].rounded_task()
    }
}

/// How a simulation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimOutcome {
    pub rounds: usize,
    /// The stop rule fired (as opposed to the round limit).
    pub stopped: bool,
}

/// How a run under the decentralized stop protocol ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LocalStopOutcome {
    pub rounds: usize,
    /// Round whose assignment all robots certified, and each robot's task in it.
    pub certified: Option<(usize, Vec<usize>)>,
}

/// All agents with double-buffered payloads, stepped in lockstep. Within a round the
/// agents are independent, so large teams are stepped by a few scoped worker threads; each
/// agent's arithmetic is the same whatever the split, so results are bit-identical.
pub struct LockstepSim<A> {
    agents: Vec<A>,
    neighbours: Vec<Vec<usize>>,
    len: usize,
    current: Vec<f64>,
    next: Vec<f64>,
    reports: Vec<StepReport>,
    round: usize,
    workers: usize,
}

/// Below this much neighbour data per round (f64 values read), one thread is faster than
/// spawning workers every round.
const PARALLEL_THRESHOLD: usize = 1 << 18;

impl<A: ConsensusAgent + Send> LockstepSim<A> {
    /// `agents[i]` is robot `i` of `graph`; all payloads must have the same length.
    pub fn new(agents: Vec<A>, graph: &Graph) -> Self {
        assert_eq!(agents.len(), graph.robots(), "one agent per robot");
        let len = agents.first().map_or(0, |a| a.payload_len());
        assert!(agents.iter().all(|a| a.payload_len() == len));
        let traffic = len * 2 * graph.edge_count();
        let workers = if traffic >= PARALLEL_THRESHOLD {
            std::thread::available_parallelism()
                .map_or(1, |p| p.get())
                .min(agents.len())
        } else {
            1
        };
        let mut current = vec![0.0; len * agents.len()];
        for (i, agent) in agents.iter().enumerate() {
            agent.write_initial_payload(&mut current[i * len..(i + 1) * len]);
        }
        Self {
            neighbours: (0..graph.robots())
                .map(|i| graph.neighbours(i).to_vec())
                .collect(),
            next: vec![0.0; current.len()],
            reports: vec![StepReport::default(); agents.len()],
            agents,
            len,
            current,
            round: 0,
            workers,
        }
    }

    /// Steps with exactly this many worker threads (1: all in the caller's thread).
    pub fn with_workers(mut self, workers: usize) -> Self {
        self.workers = workers.clamp(1, self.agents.len().max(1));
        self
    }

    /// Runs one round: every agent steps on its neighbours' current payloads.
    pub fn step_round(&mut self) -> &[StepReport] {
        let (len, current, neighbours) = (self.len, &self.current[..], &self.neighbours[..]);
        let step_range =
            |first: usize, agents: &mut [A], next: &mut [f64], reports: &mut [StepReport]| {
                for (k, agent) in agents.iter_mut().enumerate() {
                    let inbox = SimInbox {
                        payloads: current,
                        len,
                        neighbours: &neighbours[first + k],
                    };
                    reports[k] = agent.step(&inbox, &mut next[k * len..(k + 1) * len]);
                }
            };
        if self.workers <= 1 {
            step_range(0, &mut self.agents, &mut self.next, &mut self.reports);
        } else {
            let chunk = self.agents.len().div_ceil(self.workers);
            std::thread::scope(|scope| {
                let parts = self
                    .agents
                    .chunks_mut(chunk)
                    .zip(self.next.chunks_mut(chunk * len))
                    .zip(self.reports.chunks_mut(chunk))
                    .enumerate();
                for (part, ((agents, next), reports)) in parts {
                    let step_range = &step_range;
                    scope.spawn(move || step_range(part * chunk, agents, next, reports));
                }
            });
        }
        std::mem::swap(&mut self.current, &mut self.next);
        self.round += 1;
        &self.reports
    }

    /// Steps until `stop` fires or `max_rounds` rounds have run, showing each round to
    /// `observer`.
    pub fn run(
        &mut self,
        max_rounds: usize,
        stop: &mut dyn TeamStopRule,
        observer: &mut dyn FnMut(&RoundView<'_>),
    ) -> SimOutcome {
        self.run_until(max_rounds, observer, |sim| stop.should_stop(&sim.reports))
    }

    /// Steps until `done` (which sees the whole simulation after each round, after the
    /// observer) is true or `max_rounds` rounds have run: for stop rules that need more
    /// than the step reports (the agents' certificates, the centralized optimum).
    pub fn run_until(
        &mut self,
        max_rounds: usize,
        observer: &mut dyn FnMut(&RoundView<'_>),
        mut done: impl FnMut(&Self) -> bool,
    ) -> SimOutcome {
        while self.round < max_rounds && crate::signals::stop_requested().is_none() {
            self.step_round();
            observer(&self.view());
            if done(self) {
                return SimOutcome {
                    rounds: self.round,
                    stopped: true,
                };
            }
        }
        SimOutcome {
            rounds: self.round,
            stopped: false,
        }
    }

    /// Steps under the decentralized certified stop ([`LocalCertifiedStop`], one per agent,
    /// seeing only its neighbours' headers) until all agents certify or `max_rounds` rounds
    /// have run. The threads and ipc transports run the same protocol, so they stop at the
    /// same round with the same iterates.
    pub fn run_local_stop(
        &mut self,
        stops: &mut [LocalCertifiedStop],
        max_rounds: usize,
        observer: &mut dyn FnMut(&RoundView<'_>),
    ) -> LocalStopOutcome {
        assert_eq!(
            stops.len(),
            self.agents.len(),
            "one stop protocol per agent"
        );
        let mut states = vec![NeighbourState::default(); self.agents.len()];
        let mut verdicts = Vec::with_capacity(self.agents.len());
        loop {
            let round = self.round as u64;
            if crate::signals::stop_requested().is_some() {
                // The caller names the signal ([`crate::signals::stop_requested`]).
                return LocalStopOutcome {
                    rounds: self.round,
                    certified: None,
                };
            }
            verdicts.clear();
            for (i, (agent, stop)) in self.agents.iter().zip(stops.iter_mut()).enumerate() {
                let theirs = self.neighbours[i].iter().map(|&j| states[j]);
                verdicts.push(
                    stop.observe(round, states[i], theirs, agent.rounded_task(), || {
                        agent.certificate_slack()
                    }),
                );
            }
            if let Some(Verdict::Certified {
                certified_round, ..
            }) = verdicts.first().copied()
            {
                let tasks = verdicts
                    .iter()
                    .map(|v| match v {
                        Verdict::Certified {
                            task,
                            certified_round: r,
                        } if *r == certified_round => *task,
                        _ => unreachable!("the stop protocol gives every agent the same verdict"),
                    })
                    .collect();
                return LocalStopOutcome {
                    rounds: self.round,
                    certified: Some((certified_round as usize, tasks)),
                };
            }
            if self.round >= max_rounds {
                return LocalStopOutcome {
                    rounds: self.round,
                    certified: None,
                };
            }
            self.step_round();
            for (i, state) in states.iter_mut().enumerate() {
                *state = NeighbourState {
                    digest: self.reports[i].assignment_digest,
                    window: stops[i].next_window(),
                };
            }
            observer(&self.view());
        }
    }

    /// The latest round as observers see it.
    pub fn view(&self) -> RoundView<'_> {
        RoundView {
            round: self.round,
            reports: &self.reports,
            payloads: &self.current,
            payload_len: self.len,
            columns: &self.agents,
        }
    }

    pub fn agents(&self) -> &[A] {
        &self.agents
    }

    /// Mutable access to the agents between rounds (e.g. to change a parameter for all).
    pub fn agents_mut(&mut self) -> &mut [A] {
        &mut self.agents
    }

    /// The agents, in their current state (e.g. to time one of them on its own).
    pub fn into_agents(self) -> Vec<A> {
        self.agents
    }

    /// Agent `i`'s latest payload.
    pub fn payload(&self, i: usize) -> &[f64] {
        &self.current[i * self.len..(i + 1) * self.len]
    }

    pub fn round(&self) -> usize {
        self.round
    }
}
