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
    /// This robot's cost of its task (its own number).
    pub cost: Option<f64>,
    /// The team's total cost (a profit with `maximize`), from every robot's own cost.
    pub total_cost: Option<f64>,
    /// Every robot's task (`None`: it took no part), when the round message has room for it.
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
    /// Robots that left (their programs closed their input): the team has ended.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub left: Vec<usize>,
    /// Milliseconds from this robot's row to its answer.
    pub ms: f64,
}

impl Answer {
    /// The team has ended (a robot left): no further episode.
    pub fn ended(&self) -> bool {
        !self.left.is_empty()
    }
}

/// A row a robot cannot give: the team never sees it (the robot may give another).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RowError {
    #[error("{got} costs: give one per task of the episode, 1 to {tasks}")]
    Length { got: usize, tasks: usize },
    #[error("cost {index} is {value}: give a finite number (null for a forbidden task)")]
    NotFinite { index: usize, value: f64 },
    #[error("the team has ended (robot(s) {0:?} left)")]
    Ended(Vec<usize>),
    #[error("the team failed in an earlier episode")]
    Failed,
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
