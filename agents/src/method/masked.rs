//! A method's agent on part of its team's problem: the robots that take part in an episode
//! and the tasks that exist in it, inside the team's fixed-size messages.
//!
//! A standing team declares `n` robots and at most `m` tasks when it starts; its round
//! messages keep that size. In an episode where only the robots `R` take tasks (the others
//! relay: they keep exchanging so that the graph stays connected, with no costs of their
//! own) and only the tasks `T` exist, every robot runs the method on the `|T| × |R|`
//! problem: [`MaskedAgent`] reads that block of each neighbour's `m × n` message, steps its
//! inner agent on it and writes its block back (zeros elsewhere). This needs a method whose
//! message is the team's assignment matrix, column-major tasks × robots
//! ([`crate::method::team::TeamMethod::MASKABLE`]).
//!
//! A relay runs the same inner agent with zero costs (it stands at the first robot's place,
//! adding nothing to that robot's cost column): the certificate's `Σ_i G_i = C` still holds
//! over the robots that take part, and the stop protocol counts the relay like any robot.

use crate::agent::{ConsensusAgent, Inbox, NewCostsError, StepReport};
use crate::method::agent::MethodAgent;

/// Which robots take part and which tasks exist (both sorted, both non-empty).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Part {
    pub robots: Vec<usize>,
    pub tasks: Vec<usize>,
}

impl Part {
    /// Every robot and every task of an `n`-robot, `m`-task team.
    pub fn whole(robots: usize, tasks: usize) -> Self {
        Self {
            robots: (0..robots).collect(),
            tasks: (0..tasks).collect(),
        }
    }
}

/// The neighbours' blocks, for the inner agent.
struct Blocks<'a>(&'a [Vec<f64>]);

impl Inbox for Blocks<'_> {
    fn len(&self) -> usize {
        self.0.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        &self.0[k]
    }
}

/// A robot of an `n`-robot, `m`-task team running its method on a [`Part`].
pub struct MaskedAgent {
    inner: MethodAgent,
    tasks: usize,
    robots: usize,
    part: Part,
    /// The whole team: messages pass straight through.
    whole: bool,
    /// The robot's place among `part.robots`, `None` for a relay.
    place: Option<usize>,
    /// The neighbours' blocks and the robot's own (allocated once per part).
    blocks: Vec<Vec<f64>>,
    out: Vec<f64>,
}

impl MaskedAgent {
    /// `inner` (an agent of the `|part.tasks| × |part.robots|` problem, at `place`, or a relay
    /// at place 0 with zero costs) inside messages of an `n`-robot, `m`-task team; `degree`
    /// neighbours.
    pub fn new(
        inner: MethodAgent,
        tasks: usize,
        robots: usize,
        part: Part,
        place: Option<usize>,
        degree: usize,
    ) -> Self {
        let block = part.tasks.len() * part.robots.len();
        let whole = part == Part::whole(robots, tasks);
        let (blocks, out) = if whole {
            (Vec::new(), Vec::new())
        } else {
            (vec![vec![0.0; block]; degree], vec![0.0; block])
        };
        Self {
            inner,
            tasks,
            robots,
            part,
            whole,
            place,
            blocks,
            out,
        }
    }

    /// The part it runs on.
    pub fn part(&self) -> &Part {
        &self.part
    }

    /// Whether this robot relays (takes no task).
    pub fn relays(&self) -> bool {
        self.place.is_none()
    }

    /// New own costs (one per task of the part; zeros for a relay), warm or cold.
    pub fn set_costs(&mut self, costs: &[f64], warm: bool) -> Result<(), NewCostsError> {
        self.inner.set_costs(costs, warm)
    }

    fn read_block(part: &Part, tasks: usize, message: &[f64], block: &mut [f64]) {
        let t = part.tasks.len();
        for (c, &r) in part.robots.iter().enumerate() {
            for (k, &task) in part.tasks.iter().enumerate() {
                block[c * t + k] = message[r * tasks + task];
            }
        }
    }

    fn write_block(part: &Part, tasks: usize, block: &[f64], message: &mut [f64]) {
        message.fill(0.0);
        let t = part.tasks.len();
        for (c, &r) in part.robots.iter().enumerate() {
            for (k, &task) in part.tasks.iter().enumerate() {
                message[r * tasks + task] = block[c * t + k];
            }
        }
    }

    /// The team's task of the inner agent's task `k`.
    fn task(&self, k: usize) -> usize {
        self.part.tasks.get(k).copied().unwrap_or(k)
    }
}

impl ConsensusAgent for MaskedAgent {
    fn payload_len(&self) -> usize {
        self.tasks * self.robots
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        if self.whole {
            return self.inner.write_initial_payload(out);
        }
        let mut block = vec![0.0; self.part.tasks.len() * self.part.robots.len()];
        self.inner.write_initial_payload(&mut block);
        Self::write_block(&self.part, self.tasks, &block, out);
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        if self.whole {
            return self.inner.step(inbox, out);
        }
        for (k, block) in self.blocks.iter_mut().enumerate() {
            Self::read_block(&self.part, self.tasks, inbox.payload(k), block);
        }
        let report = self.inner.step(&Blocks(&self.blocks), &mut self.out);
        Self::write_block(&self.part, self.tasks, &self.out, out);
        report
    }

    fn decide(&self) -> usize {
        self.task(self.inner.decide())
    }

    fn rounded_task(&self) -> usize {
        self.task(self.inner.rounded_task())
    }

    fn certificate_slack(&self) -> f64 {
        self.inner.certificate_slack()
    }

    fn own_column(&self) -> &[f64] {
        self.inner.own_column()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::settings::GivenSettings;
    use crate::method::team::{AgentInit, TeamContext, TeamParams};
    use crate::methods::Method;
    use crate::problem::{AssignmentCase, CostMatrix, TaskAssignmentProblem};

    /// On the whole team the part is the method itself, bit for bit; on a part, its block
    /// of the message is the inner agent's message and the rest is zero.
    #[test]
    fn a_part_carries_the_inner_agents_messages() {
        let (n, m) = (4, 3);
        let graph = admm_ta_topologies::generate::complete(n).unwrap();
        let setup = Method::Primal
            .setup(&GivenSettings::default())
            .unwrap()
            .unwrap();
        let agent = |robots: usize, tasks: usize, index: usize, costs: Vec<f64>| {
            let shape = CostMatrix::new(robots, tasks, vec![0.0; robots * tasks]).unwrap();
            let case = if robots == tasks {
                AssignmentCase::One
            } else {
                AssignmentCase::Two
            };
            let problem = TaskAssignmentProblem::internal_from(shape, case).unwrap();
            let params = TeamParams {
                rho: 1.0,
                diameter: 1,
                tolerance: 1e-9,
            };
            let team = setup.team(TeamContext {
                problem: &problem,
                graph: &graph,
                params,
            });
            MethodAgent::new(team.agent(AgentInit {
                index,
                costs,
                robots,
                case,
                degree: n - 1,
            }))
        };
        let part = Part {
            robots: vec![0, 2, 3],
            tasks: vec![0, 2],
        };
        let mut masked = MaskedAgent::new(
            agent(3, 2, 1, vec![0.3, 0.7]),
            m,
            n,
            part.clone(),
            Some(1),
            n - 1,
        );
        let mut plain = agent(3, 2, 1, vec![0.3, 0.7]);
        let neighbour = |seed: f64| -> Vec<f64> {
            (0..n * m)
                .map(|k| (k as f64 * 0.37 + seed).fract())
                .collect()
        };
        let messages: Vec<Vec<f64>> = (0..n - 1).map(|j| neighbour(j as f64 * 0.11)).collect();
        let inbox: Vec<&[f64]> = messages.iter().map(Vec::as_slice).collect();
        let blocks: Vec<Vec<f64>> = messages
            .iter()
            .map(|msg| {
                let mut b = vec![0.0; 6];
                MaskedAgent::read_block(&part, m, msg, &mut b);
                b
            })
            .collect();
        let block_inbox: Vec<&[f64]> = blocks.iter().map(Vec::as_slice).collect();
        let mut out = vec![9.0; n * m];
        let mut expected = vec![0.0; 6];
        masked.step(&inbox, &mut out);
        plain.step(&block_inbox, &mut expected);
        for (c, &r) in part.robots.iter().enumerate() {
            for (k, &t) in part.tasks.iter().enumerate() {
                assert_eq!(out[r * m + t], expected[c * 2 + k]);
            }
        }
        assert_eq!(out[m + 1], 0.0, "robot 1 takes no part");
        assert_eq!(out[1], 0.0, "task 1 does not exist");
        assert_eq!(masked.decide(), part.tasks[plain.decide()]);
        // The whole team passes straight through.
        let mut whole = MaskedAgent::new(
            agent(n, m, 2, vec![0.1, 0.5, 0.9]),
            m,
            n,
            Part::whole(n, m),
            Some(2),
            n - 1,
        );
        let mut direct = agent(n, m, 2, vec![0.1, 0.5, 0.9]);
        let (mut a, mut b) = (vec![0.0; n * m], vec![0.0; n * m]);
        whole.step(&inbox, &mut a);
        direct.step(&inbox, &mut b);
        assert_eq!(a, b);
    }
}
