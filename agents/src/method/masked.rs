//! A method's agent on part of its team's problem: the robots that take part in an episode
//! and the tasks that exist in it, inside the team's fixed-size messages.
//!
//! A standing team declares `n` robots and at most `m` tasks when it starts; its round
//! messages keep that size. In an episode where only the robots `R` take tasks (the others
//! relay: they keep exchanging so that the graph stays connected, with no costs of their
//! own) and only the tasks `T` exist, every robot runs the method on the `|T| × |R|`
//! problem inside the team's messages, as its method lays them out ([`PartLayout`],
//! [`crate::method::team::TeamMethod::parts`]):
//!
//! * [`PartLayout::Block`] (the primal method, whose message is the team's assignment
//!   matrix, column-major tasks × robots): [`MaskedAgent`] reads the part's block of each
//!   neighbour's `m × n` message, steps its inner agent on it and writes its block back
//!   (zeros elsewhere). A relay runs the same inner agent with zero costs (it stands at the
//!   first robot's place, adding nothing to that robot's cost column): the certificate's
//!   `Σ_i G_i = C` still holds over the robots that take part, and the stop protocol counts
//!   the relay like any robot.
//! * [`PartLayout::Prefix`] (the fast dual methods, whose message is prices and a
//!   certificate, of a length that grows with the robots and the tasks): the inner agent's
//!   message of the part is the first values of the team's message (zeros after it), read
//!   in place. A relay is the method's own ([`crate::method::team::TeamBuilder::relay`]):
//!   it takes part in the consensus on prices with no column of its own.

use crate::agent::{
    ConsensusAgent, Inbox, NewCostsError, PayloadError, StepReport, check_length, first_not_finite,
};
use crate::method::agent::MethodAgent;
pub use crate::method::team::PartLayout;

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

/// The first `len` values of the neighbours' messages, for the inner agent (no copy).
struct Prefixes<'a> {
    inbox: &'a dyn Inbox,
    len: usize,
}

impl Inbox for Prefixes<'_> {
    fn len(&self) -> usize {
        self.inbox.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        &self.inbox.payload(k)[..self.len]
    }
}

/// A robot of an `n`-robot, `m`-task team running its method on a [`Part`].
pub struct MaskedAgent {
    inner: MethodAgent,
    tasks: usize,
    layout: PartLayout,
    /// Values of the team's round message.
    message_len: usize,
    part: Part,
    /// The inner agent's message is the team's: messages pass straight through.
    whole: bool,
    /// The robot's place among `part.robots`, `None` for a relay.
    place: Option<usize>,
    /// The neighbours' blocks and the robot's own (allocated once per part).
    blocks: Vec<Vec<f64>>,
    out: Vec<f64>,
}

impl MaskedAgent {
    /// `inner` (an agent of the `|part.tasks| × |part.robots|` problem at `place`, or a
    /// relay) inside `message_len`-value messages of an `n`-robot, `m`-task team laid out
    /// as `layout` says; `degree` neighbours.
    pub fn new(
        inner: MethodAgent,
        team: (usize, usize),
        message_len: usize,
        layout: PartLayout,
        part: Part,
        (place, degree): (Option<usize>, usize),
    ) -> Self {
        let (robots, tasks) = team;
        let inner_len = inner.payload_len();
        assert!(inner_len <= message_len, "a part's message fits the team's");
        let whole = inner_len == message_len
            && (layout == PartLayout::Prefix || part == Part::whole(robots, tasks));
        let block = part.tasks.len() * part.robots.len();
        let (blocks, out) = if whole || layout == PartLayout::Prefix {
            (Vec::new(), Vec::new())
        } else {
            (vec![vec![0.0; block]; degree], vec![0.0; block])
        };
        Self {
            inner,
            tasks,
            layout,
            message_len,
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
        self.message_len
    }

    /// The inner agent's checks on its part of the message; finite numbers elsewhere.
    fn check_payload(&self, payload: &[f64]) -> Result<(), PayloadError> {
        if self.whole {
            return self.inner.check_payload(payload);
        }
        check_length(payload, self.message_len)?;
        let inner = match self.layout {
            PartLayout::Prefix => self.inner.payload_len(),
            PartLayout::Block => 0,
        };
        if inner > 0 {
            self.inner.check_payload(&payload[..inner])?;
        }
        match first_not_finite(&payload[inner..]) {
            Some(k) => Err(PayloadError::NotFinite {
                index: inner + k,
                value: payload[inner + k],
            }),
            None => Ok(()),
        }
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        if self.whole {
            return self.inner.write_initial_payload(out);
        }
        if self.layout == PartLayout::Prefix {
            let (mine, rest) = out.split_at_mut(self.inner.payload_len());
            rest.fill(0.0);
            return self.inner.write_initial_payload(mine);
        }
        let mut block = vec![0.0; self.part.tasks.len() * self.part.robots.len()];
        self.inner.write_initial_payload(&mut block);
        Self::write_block(&self.part, self.tasks, &block, out);
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        if self.whole {
            return self.inner.step(inbox, out);
        }
        if self.layout == PartLayout::Prefix {
            let len = self.inner.payload_len();
            let (mine, rest) = out.split_at_mut(len);
            rest.fill(0.0);
            return self.inner.step(&Prefixes { inbox, len }, mine);
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
            (n, m),
            n * m,
            PartLayout::Block,
            part.clone(),
            (Some(1), n - 1),
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
            (n, m),
            n * m,
            PartLayout::Block,
            Part::whole(n, m),
            (Some(2), n - 1),
        );
        let mut direct = agent(n, m, 2, vec![0.1, 0.5, 0.9]);
        let (mut a, mut b) = (vec![0.0; n * m], vec![0.0; n * m]);
        whole.step(&inbox, &mut a);
        direct.step(&inbox, &mut b);
        assert_eq!(a, b);
    }

    /// A prefix part: the inner agent reads the first values of its neighbours' messages and
    /// writes its own there, zeros after them; a longer value that is not finite is refused.
    #[test]
    fn a_prefix_part_carries_the_inner_message_first() {
        use crate::agent::AgentAlgorithm;
        use crate::methods::dual::{DualParams, DualUpdate, FastDualAgent};
        let params = DualParams {
            rho: 0.5,
            update: DualUpdate::Exact,
            diameter: 1,
            tolerance: 1e-9,
        };
        let make = || {
            let agent = FastDualAgent::new(
                0,
                &[0.2, 0.9],
                vec![true; 2],
                2,
                AssignmentCase::One,
                1,
                params,
            );
            Box::new(agent) as Box<dyn AgentAlgorithm>
        };
        let inner_len = make().payload_len();
        let len = inner_len + 4;
        let part = Part::whole(2, 2);
        let mut masked = MaskedAgent::new(
            MethodAgent::new(make()),
            (2, 2),
            len,
            PartLayout::Prefix,
            part,
            (Some(0), 1),
        );
        let mut plain = MethodAgent::new(make());
        let mut neighbour = vec![0.0; len];
        neighbour[0] = 0.3;
        let (mut out, mut expected) = (vec![7.0; len], vec![0.0; inner_len]);
        masked.step(&vec![neighbour.as_slice()], &mut out);
        plain.step(&vec![&neighbour[..inner_len]], &mut expected);
        assert_eq!(&out[..inner_len], &expected[..]);
        assert!(out[inner_len..].iter().all(|&v| v == 0.0));
        assert_eq!(masked.check_payload(&out), Ok(()));
        out[len - 1] = f64::NAN;
        assert!(masked.check_payload(&out).is_err());
        assert!(masked.check_payload(&out[..inner_len]).is_err());
    }
}
