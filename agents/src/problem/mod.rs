//! The task assignment problem (Problem 1 of the paper) and its cost data.
//!
//! `n` robots, `m` tasks, robot `i` pays `α_i[t]` for task `t`. Every robot does exactly one
//! task; in Case 1 (`n = m`) every task gets exactly one robot, in Case 2 (`n > m`) every task
//! gets at least one. `idle` is scipy's rectangular meaning: `min(n, m)` robot–task pairs,
//! each robot at most one task and each task at most one robot. The LP relaxation replaces
//! `x ∈ {0,1}` by `0 ≤ x ≤ 1`; its constraint matrix is a bipartite incidence matrix (totally
//! unimodular), so its vertices are assignments in every case.
//!
//! A cost of `+∞` marks a *forbidden* pair (`−∞` with `--maximize`), as in scipy's
//! `linear_sum_assignment`. The problem checks Hall's condition when it is built
//! ([`crate::problem::feasibility`]) and carries the [`crate::problem::normalise`]d problem the agents solve.
//!
//! ```
//! use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
//! let costs = CostMatrix::from_csv_str("0.1,0.9\n0.8,0.2\n").unwrap();
//! let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
//! assert_eq!(problem.cost_of(&[0, 1]).unwrap(), 0.30000000000000004);
//! ```
//!
//! The cost data and its errors live in [`crate::problem::costs`] (re-exported here).

pub mod cost_file;
pub mod cost_model;
pub mod costs;
pub mod csv_text;
pub mod feasibility;
pub mod forbidden;
pub mod general;
pub mod normalise;
pub mod private;
pub mod surveillance;
pub mod ties;

pub use crate::problem::costs::{
    AssignmentCase, CostMatrix, MAX_COST_ENTRIES, Names, ProblemError, read_bounded, read_cost_text,
};

/// How to pick the case: from the shape, or forced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CaseChoice {
    #[default]
    Auto,
    Forced(AssignmentCase),
}

impl CaseChoice {
    /// Every choice, in the order of the command line's help.
    pub const ALL: [CaseChoice; 4] = [
        Self::Auto,
        Self::Forced(AssignmentCase::One),
        Self::Forced(AssignmentCase::Two),
        Self::Forced(AssignmentCase::Idle),
    ];

    /// The name used on the command line: `auto`, `1`, `2` or `idle`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Forced(case) => case.name(),
        }
    }
}

#[cfg(feature = "clap")]
crate::clap_value_enum!(CaseChoice);

/// The task index of an idle robot in an assignment (case `idle` with `n > m`).
pub const IDLE: usize = usize::MAX;

/// Problem 1: costs plus the coverage case, checked feasible (Hall's condition) when built.
/// `costs` are the user's numbers (profits when `maximize`); the agents solve
/// [`TaskAssignmentProblem::internal`], the [`crate::problem::normalise`]d problem.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskAssignmentProblem {
    costs: CostMatrix,
    case: AssignmentCase,
    maximize: bool,
    normalised: Option<Box<Normalised>>,
}

/// The problem the agents solve, and how its costs relate to the user's.
#[derive(Debug, Clone, PartialEq)]
pub struct Normalised {
    /// Allowed costs shifted and scaled to `[0, 1]`, forbidden pairs at a penalty above any
    /// allowed assignment, idle robots as extra zero-cost tasks (see [`crate::problem::normalise`]).
    pub problem: TaskAssignmentProblem,
    /// User cost (minimisation sign) `= shift + scale · (normalised cost − raise)` for every
    /// real pair.
    pub shift: f64,
    pub scale: f64,
    /// Added to every real task's normalised cost (1 with an idle task, else 0).
    pub raise: f64,
    /// Why the floating-point methods cannot resolve these costs, if they cannot.
    pub unresolved: Option<String>,
}

impl TaskAssignmentProblem {
    /// Checks the case against the shape and Hall's condition. `Auto` picks Case 1 for square
    /// problems, Case 2 for `n > m` and `idle` for `n < m`; Case 2 may be forced on a square
    /// problem (it then coincides with Case 1), Case 1 cannot be forced on `n ≠ m`.
    pub fn new(costs: CostMatrix, choice: CaseChoice) -> Result<Self, ProblemError> {
        Self::build(costs, choice, false)
    }

    /// As [`TaskAssignmentProblem::new`] with profits to maximise (scipy's `maximize=True`):
    /// `−∞` marks a forbidden pair.
    pub fn maximizing(costs: CostMatrix, choice: CaseChoice) -> Result<Self, ProblemError> {
        Self::build(costs, choice, true)
    }

    fn build(costs: CostMatrix, choice: CaseChoice, maximize: bool) -> Result<Self, ProblemError> {
        let case = resolve_case(costs.robots(), costs.tasks(), choice)?;
        let wrong = if maximize {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        };
        if let Some(k) = costs.values().iter().position(|&v| v == wrong) {
            return Err(ProblemError::NonFinite {
                robot: k / costs.tasks(),
                task: k % costs.tasks(),
                value: wrong,
            });
        }
        // Totals (and the allowed costs' range) must stay finite for every method and report.
        let largest = costs
            .values()
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0_f64, |a, v| a.max(v.abs()));
        let pairs = costs.robots().max(costs.tasks());
        if !(largest * pairs as f64 * 2.0).is_finite() {
            return Err(ProblemError::TotalOverflow { largest, pairs });
        }
        let mut problem = Self {
            costs,
            case,
            maximize,
            normalised: None,
        };
        if problem.costs.has_forbidden() {
            normalise::check_hall(&problem.costs, case)?;
        }
        let parts = normalise::normalise(&problem.costs, case, maximize)?;
        problem.normalised = Some(Box::new(Normalised {
            problem: TaskAssignmentProblem::internal_from(parts.matrix, parts.case)?,
            shift: parts.shift,
            scale: parts.scale,
            raise: parts.raise,
            unresolved: parts.unresolved,
        }));
        Ok(problem)
    }

    /// A problem exactly as given (finite costs, no normalisation): the normalised problem
    /// itself, as agents started from a scenario file rebuild it.
    pub fn internal_from(costs: CostMatrix, case: AssignmentCase) -> Result<Self, ProblemError> {
        let case = resolve_case(costs.robots(), costs.tasks(), CaseChoice::Forced(case))?;
        if let Some(k) = costs.values().iter().position(|v| !v.is_finite()) {
            return Err(ProblemError::NonFinite {
                robot: k / costs.tasks(),
                task: k % costs.tasks(),
                value: costs.values()[k],
            });
        }
        Ok(Self {
            costs,
            case,
            maximize: false,
            normalised: None,
        })
    }

    /// The problem the agents solve (this one when it is already normalised).
    pub fn internal(&self) -> &TaskAssignmentProblem {
        self.normalised.as_ref().map_or(self, |n| &n.problem)
    }

    /// The user's exact numbers in the minimisation sign, on the user's shape and case,
    /// forbidden pairs at the largest double (and masked): what a method that solves exactly
    /// (the distributed Hungarian) floods and solves, with no loss of precision.
    pub fn exact(&self) -> Result<TaskAssignmentProblem, ProblemError> {
        let (n, m) = (self.robots(), self.tasks());
        let mut allowed = vec![true; n * m];
        let values = (0..n * m)
            .map(|k| {
                let (i, t) = (k / m, k % m);
                if self.costs.is_allowed(i, t) {
                    normalise::signed(self.maximize, self.costs.get(i, t))
                } else {
                    allowed[k] = false;
                    f64::MAX
                }
            })
            .collect();
        let matrix = CostMatrix::with_mask(n, m, values, Some(allowed))?;
        Self::internal_from(matrix, self.case)
    }

    /// The normalisation, for a problem built from user costs.
    pub fn normalised(&self) -> Option<&Normalised> {
        self.normalised.as_deref()
    }

    /// The user's costs (profits when maximising).
    pub fn costs(&self) -> &CostMatrix {
        &self.costs
    }

    pub fn case(&self) -> AssignmentCase {
        self.case
    }

    pub fn maximize(&self) -> bool {
        self.maximize
    }

    pub fn robots(&self) -> usize {
        self.costs.robots()
    }

    pub fn tasks(&self) -> usize {
        self.costs.tasks()
    }

    /// An assignment of [`TaskAssignmentProblem::internal`] as this problem's: extra
    /// (idle) tasks become [`IDLE`]. The transposed problem's (`idle` with `n < m`, one entry
    /// per task: its robot, or the idle column) is turned back: each robot takes the first
    /// task that chose it (an optimum has exactly one), the other tasks are unserved.
    pub fn from_internal(&self, assignment: &[usize]) -> Vec<usize> {
        let (n, m) = (self.robots(), self.tasks());
        if normalise::transposed(n, m, self.case) && assignment.len() == m {
            let mut robots = vec![IDLE; n];
            for (task, &robot) in assignment.iter().enumerate() {
                if robot < n && robots[robot] == IDLE {
                    robots[robot] = task;
                }
            }
            return robots;
        }
        let mut user: Vec<usize> = assignment
            .iter()
            .map(|&t| if t >= m { IDLE } else { t })
            .collect();
        if self.case == AssignmentCase::Idle {
            // The reduction (Case 2 with an idle task) lets a non-optimal answer — a run that
            // ended at its round limit — put two robots on one task; each task keeps its
            // cheapest robot and the others go idle, which only lowers the cost.
            let mut keeper = vec![IDLE; m];
            for (i, &t) in user.iter().enumerate() {
                if t == IDLE {
                    continue;
                }
                let cost = |r: usize| normalise::signed(self.maximize, self.costs.get(r, t));
                if keeper[t] == IDLE || cost(i).total_cmp(&cost(keeper[t])).is_lt() {
                    keeper[t] = i;
                }
            }
            for (i, t) in user.iter_mut().enumerate() {
                if *t != IDLE && keeper[*t] != i {
                    *t = IDLE;
                }
            }
        }
        user
    }

    /// Whether `assignment` (task per robot, [`IDLE`] for an idle robot) uses allowed pairs
    /// only and covers the tasks as the case requires.
    pub fn is_feasible(&self, assignment: &[usize]) -> bool {
        let (n, m) = (self.robots(), self.tasks());
        if assignment.len() != n {
            return false;
        }
        let mut load = vec![0usize; m];
        for (i, &t) in assignment.iter().enumerate() {
            if t == IDLE && self.case == AssignmentCase::Idle {
                continue;
            }
            if t >= m || !self.costs.is_allowed(i, t) {
                return false;
            }
            load[t] += 1;
        }
        match self.case {
            AssignmentCase::One => load.iter().all(|&l| l == 1),
            AssignmentCase::Two => load.iter().all(|&l| l >= 1),
            AssignmentCase::Idle => {
                load.iter().all(|&l| l <= 1) && load.iter().sum::<usize>() == n.min(m)
            }
        }
    }

    /// Objective (1a) of an assignment in the user's numbers (a profit total when
    /// maximising); checks lengths, task indices and forbidden pairs, not coverage.
    pub fn cost_of(&self, assignment: &[usize]) -> Result<f64, ProblemError> {
        if assignment.len() != self.robots() {
            return Err(ProblemError::WrongLength {
                expected: self.robots(),
                found: assignment.len(),
            });
        }
        let mut total = 0.0;
        for (robot, &task) in assignment.iter().enumerate() {
            if task == IDLE && self.case == AssignmentCase::Idle {
                continue;
            }
            if task >= self.tasks() {
                return Err(ProblemError::TaskOutOfRange {
                    robot,
                    task,
                    tasks: self.tasks(),
                });
            }
            if !self.costs.is_allowed(robot, task) {
                return Err(ProblemError::Forbidden { robot, task });
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

fn resolve_case(
    robots: usize,
    tasks: usize,
    choice: CaseChoice,
) -> Result<AssignmentCase, ProblemError> {
    Ok(match choice {
        CaseChoice::Auto if robots == tasks => AssignmentCase::One,
        CaseChoice::Auto if robots > tasks => AssignmentCase::Two,
        CaseChoice::Auto => AssignmentCase::Idle,
        CaseChoice::Forced(AssignmentCase::One) if robots != tasks => {
            return Err(ProblemError::NotSquare { robots, tasks });
        }
        CaseChoice::Forced(AssignmentCase::Two) if robots < tasks => {
            return Err(ProblemError::TooFewRobots { robots, tasks });
        }
        CaseChoice::Forced(case) => case,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fewer_robots_than_tasks_is_solved_transposed() {
        // 2 robots, 3 tasks, robot 1 may not do task 0.
        let costs = CostMatrix::from_csv_str("1,5,3\ninf,2,4\n").unwrap();
        let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        let internal = problem.internal();
        // The tasks are the agents; the robots and the idle column their "tasks".
        assert_eq!((internal.robots(), internal.tasks()), (3, 3));
        assert_eq!(internal.case(), AssignmentCase::Two);
        assert!(!internal.costs().is_allowed(0, 1) && internal.costs().is_allowed(0, 0));
        assert_eq!(internal.costs().get(1, 2), 0.0);
        // Task 0 → robot 0, task 1 → robot 1, task 2 idle.
        assert_eq!(problem.from_internal(&[0, 1, 2]), vec![0, 1]);
        // Two tasks on robot 0 (a repaired, non-optimal run): robot 1 left without a task
        // is infeasible; the first task that chose a robot is its task.
        assert_eq!(problem.from_internal(&[2, 0, 0]), vec![1, IDLE]);
        assert_eq!(problem.from_internal(&[1, 0, 0]), vec![1, 0]);
    }

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
        // A header row of task names.
        let named = CostMatrix::from_csv_str("task0,task1\n1,2\n").unwrap();
        assert_eq!(named.task_names().unwrap(), ["task0", "task1"]);
        // A first row of costs with a bad cell is no header.
        assert!(matches!(
            CostMatrix::from_csv_str("1,2x\n1,2\n"),
            Err(ProblemError::NotANumber {
                line: 1,
                column: 2,
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
        let forbidden = CostMatrix::from_csv_str("1,2\n3,inf\n").unwrap();
        assert!(!forbidden.is_allowed(1, 1) && forbidden.is_allowed(1, 0));
        assert!(matches!(
            TaskAssignmentProblem::new(
                CostMatrix::from_csv_str("1,2\n3,-inf\n").unwrap(),
                CaseChoice::Auto
            ),
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
        assert_eq!(auto(&wide).unwrap().case(), AssignmentCase::Idle);
        assert!(matches!(
            TaskAssignmentProblem::new(wide.clone(), CaseChoice::Forced(AssignmentCase::Two)),
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
