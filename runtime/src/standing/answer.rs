//! What a robot of a standing team gets back from an episode ([`Answer`]), and the rows it
//! cannot give ([`RowError`]).

use serde::Serialize;

/// What one robot learns from one episode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Answer {
    /// The episode's number (from 0).
    pub episode: u64,
    /// This robot.
    pub robot: usize,
    /// Its task (`None`: the team solved nothing this episode, or the problem had no
    /// feasible assignment).
    pub task: Option<usize>,
    /// The team proved the assignment optimal (the decentralized certified stop); `false`
    /// at the round limit, where the robots' choices may conflict.
    pub certified: bool,
    /// Rounds the method ran this episode.
    pub rounds: u64,
    /// Rounds the team spent agreeing on its scale before, and on its total after.
    pub agreement_rounds: u64,
    /// Bytes of round messages this robot sent in the episode (the agreements' included;
    /// what a network carries from it, before Zenoh's own headers). On Zenoh the messages
    /// as they went (coded against the robot's last one, with their round and sender, and
    /// any sent again); elsewhere one payload of the team's size a round.
    pub sent_bytes: u64,
    /// This robot's cost of its task (its own number).
    pub cost: Option<f64>,
    /// The team's total cost (a profit with `maximize`), from every robot's own cost.
    pub total_cost: Option<f64>,
    /// Every robot's task (`None`: it took no part), once every robot is heard of.
    pub assignment: Option<Vec<Option<usize>>>,
    /// `false`: the stacked rows have no assignment that avoids every forbidden pair, or
    /// fewer robots took part than the episode has tasks.
    pub feasible: bool,
    /// Why the team solved nothing this episode (no task for anybody), if it did not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unsolved: Option<String>,
    /// Robots whose programs gave no row in time (they relayed, or the team solved nothing:
    /// the team file's `on_failure`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub missing: Vec<usize>,
    /// Robots that took no task this episode and relayed.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unavailable: Vec<usize>,
    /// Robots that leave the team with this episode (their programs closed their input):
    /// they relayed in it, and the team goes on without them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub left: Vec<usize>,
    /// Robots that asked to leave but stay: without them the rest of the team would fall
    /// apart (the team file's `leave`); they relayed in this episode.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub leave_refused: Vec<usize>,
    /// Robots cut off from the team when robots left (`leave = "force"`) or vanished: the
    /// team goes on without them from the next episode.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub lost: Vec<usize>,
    /// Robots that take part from this episode on (started for a free slot, or back after
    /// leaving or crashing).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub joined: Vec<usize>,
    /// Robots whose processes died (or vanished from the network) since the last episode:
    /// the team went on without them. An episode they cut short is solved again without
    /// them, or, if another robot had already answered it, left unsolved.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub crashed: Vec<usize>,
    /// Milliseconds from this robot's row to its answer.
    pub ms: f64,
}

impl Answer {
    /// This robot is out of the team after this episode: it left, or it was cut off.
    pub fn ended(&self) -> bool {
        self.left.contains(&self.robot) || self.lost.contains(&self.robot)
    }
}

/// A row a robot cannot give: the team never sees it (the robot may give another).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RowError {
    #[error("{got} costs: give one per task of the episode, 1 to {tasks}")]
    Length { got: usize, tasks: usize },
    #[error("cost {index} is {value}: give a finite number (null for a forbidden task)")]
    NotFinite { index: usize, value: f64 },
    #[error("this robot left the team")]
    Left,
    /// The team went on without this robot ([`crate::standing::roster::CutOff`]).
    #[error("this robot was cut off from the team: {0}")]
    Lost(String),
    #[error("the team failed in an earlier episode")]
    Failed,
}

/// A leave refused: without this robot the others would fall apart (the team file's
/// `leave = "refuse"`, the default). The robot stays in the team and relays.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "robot {robot} cannot leave (episode {episode}): without it the team would fall apart into {apart:?}; it stays and relays (leave = \"force\" in the team file lets it go)"
)]
pub struct LeaveRefused {
    pub robot: usize,
    /// The episode in which it asked (and relayed).
    pub episode: u64,
    /// The parts the rest of the team would fall into.
    pub apart: Vec<Vec<usize>>,
}

/// Refuses a row that no episode of a team of up to `tasks` tasks can use: no costs, more
/// costs than tasks, or a cost that is not a finite number.
pub fn check_row(row: &[Option<f64>], tasks: usize) -> Result<(), RowError> {
    if row.is_empty() || row.len() > tasks {
        return Err(RowError::Length {
            got: row.len(),
            tasks,
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
