//! The task assignment problem (Problem 1 of the paper) and its cost data.
//!
//! `n` robots, `m` tasks, robot `i` pays `α_i[t]` for task `t`. Every robot does exactly one
//! task; in Case 1 (`n = m`) every task gets exactly one robot, in Case 2 (`n > m`) every task
//! gets at least one. The LP relaxation replaces `x ∈ {0,1}` by `0 ≤ x ≤ 1`; its constraint
//! matrix is a bipartite incidence matrix (totally unimodular), so its vertices are
//! assignments in both cases.
//!
//! ```
//! use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
//! let costs = CostMatrix::from_csv_str("0.1,0.9\n0.8,0.2\n").unwrap();
//! let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
//! assert_eq!(problem.cost_of(&[0, 1]).unwrap(), 0.30000000000000004);
//! ```
//!
//! Size: the cost matrix with its CSV reading and every check of its data, the cases and the
//! problem built from them; about 90 lines are unit tests.

use admm_ta_topologies::rng::SeededRng;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Largest cost matrix accepted (entries), refused before anything is allocated for it.
pub const MAX_COST_ENTRIES: usize = 50_000_000;

/// Problems with the cost data or the problem shape.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ProblemError {
    #[error("cannot read cost file {path}: {reason}")]
    Io { path: String, reason: String },
    #[error("the cost file is empty (expected one row per robot, one column per task)")]
    Empty,
    #[error(
        "line {line}, column {column}: '{text}' is not a number (cost files are plain comma-separated numbers, no header)"
    )]
    NotANumber {
        line: usize,
        column: usize,
        text: String,
    },
    #[error("line {line} has {found} values but the first row has {expected} (ragged rows)")]
    Ragged {
        line: usize,
        found: usize,
        expected: usize,
    },
    #[error("cost of robot {robot} for task {task} is {value} (costs must be finite numbers)")]
    NonFinite {
        robot: usize,
        task: usize,
        value: f64,
    },
    #[error("the problem has zero {0}")]
    Zero(&'static str),
    #[error(
        "{robots} robots cannot cover {tasks} tasks: every task needs a robot, so robots must be at least tasks (n ≥ m)"
    )]
    TooFewRobots { robots: usize, tasks: usize },
    #[error("Case 1 needs as many robots as tasks, got {robots} robots and {tasks} tasks")]
    NotSquare { robots: usize, tasks: usize },
    #[error("the problem is too large: {robots} × {tasks} costs (limit {limit} entries)")]
    TooLarge {
        robots: usize,
        tasks: usize,
        limit: usize,
    },
    #[error(
        "cost file {path} is {bytes} bytes, more than any cost matrix within the limit of {limit} entries can take"
    )]
    FileTooLarge {
        path: String,
        bytes: u64,
        limit: usize,
    },
    #[error("assignment has {found} entries for {expected} robots")]
    WrongLength { expected: usize, found: usize },
    #[error("robot {robot} is assigned task {task}, but tasks are numbered 0..{tasks}")]
    TaskOutOfRange {
        robot: usize,
        task: usize,
        tasks: usize,
    },
}

/// Robot-by-task costs, row-major: row `i` is `α_i`, one column per task.
#[derive(Debug, Clone, PartialEq)]
pub struct CostMatrix {
    robots: usize,
    tasks: usize,
    values: Vec<f64>,
}

impl CostMatrix {
    /// Builds a matrix from row-major values, checking shape and finiteness.
    pub fn new(robots: usize, tasks: usize, values: Vec<f64>) -> Result<Self, ProblemError> {
        if robots == 0 {
            return Err(ProblemError::Zero("robots"));
        }
        if tasks == 0 {
            return Err(ProblemError::Zero("tasks"));
        }
        check_size(robots, tasks)?;
        if values.len() != robots * tasks {
            return Err(ProblemError::Ragged {
                line: values.len() / tasks + 1,
                found: values.len() % tasks,
                expected: tasks,
            });
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(ProblemError::NonFinite {
                robot: k / tasks,
                task: k % tasks,
                value: values[k],
            });
        }
        Ok(Self {
            robots,
            tasks,
            values,
        })
    }

    /// Parses a cost CSV: one line per robot, comma-separated costs per task, no header.
    /// Blank lines and lines starting with `#` are skipped.
    pub fn from_csv_str(text: &str) -> Result<Self, ProblemError> {
        let mut values = Vec::new();
        let mut tasks = None;
        let mut robots = 0;
        for (index, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let mut count = 0;
            for (column, cell) in line.split(',').enumerate() {
                let cell = cell.trim();
                let value: f64 = cell.parse().map_err(|_| ProblemError::NotANumber {
                    line: index + 1,
                    column: column + 1,
                    text: cell.chars().take(40).collect(),
                })?;
                if !value.is_finite() {
                    return Err(ProblemError::NonFinite {
                        robot: robots,
                        task: column,
                        value,
                    });
                }
                values.push(value);
                count += 1;
            }
            match tasks {
                None => tasks = Some(count),
                Some(expected) if expected != count => {
                    return Err(ProblemError::Ragged {
                        line: index + 1,
                        found: count,
                        expected,
                    });
                }
                Some(_) => {}
            }
            robots += 1;
            check_size(robots, count)?;
        }
        let tasks = tasks.ok_or(ProblemError::Empty)?;
        Self::new(robots, tasks, values)
    }

    /// Reads a cost CSV file (see [`CostMatrix::from_csv_str`]).
    pub fn read_csv(path: &Path) -> Result<Self, ProblemError> {
        let io = |e: std::io::Error| ProblemError::Io {
            path: path.display().to_string(),
            reason: e.to_string(),
        };
        let meta = std::fs::metadata(path).map_err(io)?;
        // A full-precision cost with its separator fits in 32 bytes; allow twice that for
        // padding, and refuse bigger files before reading them into memory.
        if meta.len() > 64 * MAX_COST_ENTRIES as u64 {
            return Err(ProblemError::FileTooLarge {
                path: path.display().to_string(),
                bytes: meta.len(),
                limit: MAX_COST_ENTRIES,
            });
        }
        Self::from_csv_str(&std::fs::read_to_string(path).map_err(io)?)
    }

    /// Uniform `[0, 1)` costs drawn from `seed`.
    pub fn uniform(robots: usize, tasks: usize, seed: u64) -> Result<Self, ProblemError> {
        check_size(robots, tasks)?;
        let mut rng = SeededRng::for_stream(seed, 0x636f737473);
        let values = (0..robots * tasks).map(|_| rng.uniform()).collect();
        Self::new(robots, tasks, values)
    }

    /// The CSV text of the matrix (round-trips exactly).
    pub fn to_csv(&self) -> String {
        let mut out = String::new();
        for i in 0..self.robots {
            let row: Vec<String> = self.row(i).iter().map(|v| format!("{v:?}")).collect();
            out.push_str(&row.join(","));
            out.push('\n');
        }
        out
    }

    pub fn robots(&self) -> usize {
        self.robots
    }

    pub fn tasks(&self) -> usize {
        self.tasks
    }

    /// `α_i`: robot `i`'s cost for every task.
    pub fn row(&self, robot: usize) -> &[f64] {
        &self.values[robot * self.tasks..(robot + 1) * self.tasks]
    }

    pub fn get(&self, robot: usize, task: usize) -> f64 {
        self.values[robot * self.tasks + task]
    }

    /// All costs, row-major.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// A spread of the costs that ignores shifts and follows scaling: `√12 · std`, which
    /// equals `max − min` for uniform costs but is not driven by a single outlier.
    /// Falls back to 1 for constant costs.
    pub fn spread(&self) -> f64 {
        let count = self.values.len() as f64;
        let mean = self.values.iter().sum::<f64>() / count;
        let var = self
            .values
            .iter()
            .map(|v| (v - mean) * (v - mean))
            .sum::<f64>()
            / count;
        let spread = (12.0 * var).sqrt();
        if spread > 0.0 && spread.is_finite() {
            spread
        } else {
            1.0
        }
    }
}

fn check_size(robots: usize, tasks: usize) -> Result<(), ProblemError> {
    match robots.checked_mul(tasks) {
        Some(entries) if entries <= MAX_COST_ENTRIES => Ok(()),
        _ => Err(ProblemError::TooLarge {
            robots,
            tasks,
            limit: MAX_COST_ENTRIES,
        }),
    }
}

/// Which coverage constraint (1d) applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AssignmentCase {
    /// `n = m`: every task exactly one robot.
    One,
    /// `n > m`: every task at least one robot.
    Two,
}

impl AssignmentCase {
    /// 1 or 2, as the paper numbers them.
    pub fn number(self) -> u8 {
        match self {
            Self::One => 1,
            Self::Two => 2,
        }
    }
}

/// How to pick the case: from the shape, or forced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CaseChoice {
    #[default]
    Auto,
    Forced(AssignmentCase),
}

impl CaseChoice {
    /// Every choice, in the order of the command line's help.
    pub const ALL: [CaseChoice; 3] = [
        Self::Auto,
        Self::Forced(AssignmentCase::One),
        Self::Forced(AssignmentCase::Two),
    ];

    /// The name used on the command line: `auto`, `1` or `2`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Forced(AssignmentCase::One) => "1",
            Self::Forced(AssignmentCase::Two) => "2",
        }
    }
}

#[cfg(feature = "clap")]
impl clap::ValueEnum for CaseChoice {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

/// Problem 1: costs plus the coverage case. Always feasible once constructed.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskAssignmentProblem {
    costs: CostMatrix,
    case: AssignmentCase,
}

impl TaskAssignmentProblem {
    /// Checks `n ≥ m` and the case against the shape. `Auto` picks Case 1 for square
    /// problems and Case 2 otherwise; Case 2 may be forced on a square problem (it then
    /// coincides with Case 1), Case 1 cannot be forced on `n > m`.
    pub fn new(costs: CostMatrix, choice: CaseChoice) -> Result<Self, ProblemError> {
        let (robots, tasks) = (costs.robots(), costs.tasks());
        if robots < tasks {
            return Err(ProblemError::TooFewRobots { robots, tasks });
        }
        let case = match choice {
            CaseChoice::Auto if robots == tasks => AssignmentCase::One,
            CaseChoice::Auto => AssignmentCase::Two,
            CaseChoice::Forced(AssignmentCase::One) if robots != tasks => {
                return Err(ProblemError::NotSquare { robots, tasks });
            }
            CaseChoice::Forced(case) => case,
        };
        Ok(Self { costs, case })
    }

    pub fn costs(&self) -> &CostMatrix {
        &self.costs
    }

    pub fn case(&self) -> AssignmentCase {
        self.case
    }

    pub fn robots(&self) -> usize {
        self.costs.robots()
    }

    pub fn tasks(&self) -> usize {
        self.costs.tasks()
    }

    /// Whether `assignment` (task per robot) satisfies (1b)–(1d).
    pub fn is_feasible(&self, assignment: &[usize]) -> bool {
        if assignment.len() != self.robots() || assignment.iter().any(|&t| t >= self.tasks()) {
            return false;
        }
        let mut load = vec![0usize; self.tasks()];
        for &t in assignment {
            load[t] += 1;
        }
        match self.case {
            AssignmentCase::One => load.iter().all(|&l| l == 1),
            AssignmentCase::Two => load.iter().all(|&l| l >= 1),
        }
    }

    /// Objective (1a) of an assignment; checks lengths and task indices, not coverage.
    pub fn cost_of(&self, assignment: &[usize]) -> Result<f64, ProblemError> {
        if assignment.len() != self.robots() {
            return Err(ProblemError::WrongLength {
                expected: self.robots(),
                found: assignment.len(),
            });
        }
        let mut total = 0.0;
        for (robot, &task) in assignment.iter().enumerate() {
            if task >= self.tasks() {
                return Err(ProblemError::TaskOutOfRange {
                    robot,
                    task,
                    tasks: self.tasks(),
                });
            }
            total += self.costs.get(robot, task);
        }
        Ok(total)
    }

    /// LP objective `Σ_i α_iᵀ x_i` of a relaxed solution given as an `m × n` column-major
    /// matrix (column `i` is robot `i`'s vector).
    pub fn relaxed_cost(&self, x_column_major: &[f64]) -> f64 {
        let m = self.tasks();
        (0..self.robots())
            .map(|i| {
                let column = &x_column_major[i * m..(i + 1) * m];
                column
                    .iter()
                    .zip(self.costs.row(i))
                    .map(|(x, a)| x * a)
                    .sum::<f64>()
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_errors_name_the_problem() {
        assert_eq!(CostMatrix::from_csv_str(""), Err(ProblemError::Empty));
        assert_eq!(
            CostMatrix::from_csv_str("\n# c\n\n"),
            Err(ProblemError::Empty)
        );
        assert!(matches!(
            CostMatrix::from_csv_str("1,2\n3\n"),
            Err(ProblemError::Ragged {
                line: 2,
                found: 1,
                expected: 2
            })
        ));
        assert!(matches!(
            CostMatrix::from_csv_str("task0,task1\n1,2\n"),
            Err(ProblemError::NotANumber {
                line: 1,
                column: 1,
                ..
            })
        ));
        assert!(matches!(
            CostMatrix::from_csv_str("1,NaN\n"),
            Err(ProblemError::NonFinite {
                robot: 0,
                task: 1,
                ..
            })
        ));
        assert!(matches!(
            CostMatrix::from_csv_str("1,2\n3,inf\n"),
            Err(ProblemError::NonFinite {
                robot: 1,
                task: 1,
                ..
            })
        ));
        assert!(matches!(
            CostMatrix::from_csv_str("1,,2\n"),
            Err(ProblemError::NotANumber { column: 2, .. })
        ));
    }

    #[test]
    fn case_selection() {
        let square = CostMatrix::uniform(3, 3, 1).unwrap();
        let tall = CostMatrix::uniform(4, 2, 1).unwrap();
        let wide = CostMatrix::uniform(2, 4, 1).unwrap();
        let auto = |c: &CostMatrix| TaskAssignmentProblem::new(c.clone(), CaseChoice::Auto);
        assert_eq!(auto(&square).unwrap().case(), AssignmentCase::One);
        assert_eq!(auto(&tall).unwrap().case(), AssignmentCase::Two);
        assert!(matches!(
            auto(&wide),
            Err(ProblemError::TooFewRobots { .. })
        ));
        assert!(TaskAssignmentProblem::new(tall, CaseChoice::Forced(AssignmentCase::One)).is_err());
        let forced =
            TaskAssignmentProblem::new(square, CaseChoice::Forced(AssignmentCase::Two)).unwrap();
        assert_eq!(forced.case(), AssignmentCase::Two);
    }

    #[test]
    fn feasibility_and_cost() {
        let costs = CostMatrix::new(3, 2, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
        let p = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        assert!(p.is_feasible(&[0, 1, 0]));
        assert!(!p.is_feasible(&[0, 0, 0]));
        assert!(!p.is_feasible(&[0, 1]));
        assert_eq!(p.cost_of(&[0, 1, 0]).unwrap(), 1.0 + 4.0 + 5.0);
        assert!(p.cost_of(&[0, 2, 0]).is_err());
        assert_eq!(
            CostMatrix::from_csv_str(&p.costs().to_csv()).unwrap(),
            *p.costs()
        );
    }

    #[test]
    fn refuses_huge_before_allocating() {
        assert!(matches!(
            CostMatrix::uniform(1_000_000, 1_000_000, 0),
            Err(ProblemError::TooLarge { .. })
        ));
        assert!(CostMatrix::new(0, 3, vec![]).is_err());
        assert!(CostMatrix::new(3, 0, vec![]).is_err());
    }
}
