//! Where random costs come from (`--cost-model`): uniform in `[0, 1)`, or distance costs
//! — robots and tasks at random points of the unit square, cost = Euclidean distance, the
//! case of real robot teams. Distance costs are far harder for consensus ADMM than uniform
//! ones: the paper's primal variant needs 1026 rounds to its certified stop on 50×30
//! complete graphs where uniform costs need 76 (medians of 5 seeds, `experiment
//! rounds-anatomy`); the fast variant 6 and 5.

use crate::problem::{CostMatrix, ProblemError};
use admm_ta_topologies::rng::SeededRng;
use serde::{Deserialize, Serialize};

/// How random costs are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CostModel {
    /// Independent uniform `[0, 1)` entries ([`CostMatrix::uniform`]).
    #[default]
    Uniform,
    /// Travel distances between random points of the unit square ([`geometric`]).
    Geometric,
}

impl CostModel {
    /// Both models, in the order of the command line's help.
    pub const ALL: [CostModel; 2] = [Self::Uniform, Self::Geometric];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Uniform => "uniform",
            Self::Geometric => "geometric",
        }
    }

    /// A `robots × tasks` matrix drawn from `seed`.
    pub fn costs(self, robots: usize, tasks: usize, seed: u64) -> Result<CostMatrix, ProblemError> {
        match self {
            Self::Uniform => CostMatrix::uniform(robots, tasks, seed),
            Self::Geometric => geometric(robots, tasks, seed),
        }
    }
}

#[cfg(feature = "clap")]
crate::clap_value_enum!(CostModel);

/// Distance costs: robots, then tasks, uniform in the unit square (drawn from `seed`);
/// cost = Euclidean distance from a robot to a task.
pub fn geometric(robots: usize, tasks: usize, seed: u64) -> Result<CostMatrix, ProblemError> {
    // Refuse bad sizes before drawing.
    CostMatrix::uniform(robots, tasks, seed)?;
    let mut rng = SeededRng::for_stream(seed, 0x6765_6f63_6f73_7473);
    let mut point = || [rng.uniform(), rng.uniform()];
    let robot_at: Vec<[f64; 2]> = (0..robots).map(|_| point()).collect();
    let task_at: Vec<[f64; 2]> = (0..tasks).map(|_| point()).collect();
    let values = robot_at
        .iter()
        .flat_map(|r| {
            task_at
                .iter()
                .map(move |t| (r[0] - t[0]).hypot(r[1] - t[1]))
        })
        .collect();
    CostMatrix::new(robots, tasks, values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_costs_are_seeded_distances() {
        let a = CostModel::Geometric.costs(5, 4, 7).unwrap();
        assert_eq!(a, geometric(5, 4, 7).unwrap());
        assert_ne!(a, geometric(5, 4, 8).unwrap());
        assert!(a.values().iter().all(|&c| (0.0..=2f64.sqrt()).contains(&c)));
        assert_eq!(
            CostModel::Uniform.costs(3, 3, 1).unwrap(),
            CostMatrix::uniform(3, 3, 1).unwrap()
        );
    }
}
