//! Cost data: the robot-by-task [`CostMatrix`] with its CSV reading and every check of its
//! data, the coverage cases, and the errors of both. `+∞` marks a forbidden pair (`−∞` when
//! maximising); a normalised matrix ([`crate::problem::normalise`]) stores finite values and a mask.

use admm_ta_topologies::rng::SeededRng;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Largest cost matrix accepted (entries), refused before anything is allocated for it.
pub const MAX_COST_ENTRIES: usize = 50_000_000;

/// Problems with the cost data or the problem shape.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ProblemError {
    #[error("cannot read {path}: {reason}")]
    Io { path: String, reason: String },
    #[error("the cost file is empty (expected one row per robot, one column per task)")]
    Empty,
    #[error("line {line}, column {column}: '{text}' is not a number")]
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
    #[error(
        "cost of robot {robot} for task {task} is {value} (costs must be numbers; +inf marks a forbidden pair, -inf with --maximize)"
    )]
    NonFinite {
        robot: usize,
        task: usize,
        value: f64,
    },
    #[error(
        "line {line}, column {column}: '{text}' is beyond the range of double precision (about ±1.8e308); write inf for a forbidden pair"
    )]
    OutOfRange {
        line: usize,
        column: usize,
        text: String,
    },
    #[error(
        "an assignment's total can exceed the range of double precision: the largest |cost| is {largest:e} over {pairs} pairs; scale the costs down"
    )]
    TotalOverflow { largest: f64, pairs: usize },
    #[error("infeasible: {0}")]
    Infeasible(String),
    #[error("robot {robot} is assigned task {task}, a forbidden pair")]
    Forbidden { robot: usize, task: usize },
    #[error("{0}")]
    Forbid(String),
    /// Robot or task names that cannot name them.
    #[error("{0}")]
    Names(String),
    /// A cost file's cell or shape, with where it is.
    #[error("{0}")]
    Format(String),
    #[error("the problem has zero {0}")]
    Zero(&'static str),
    #[error(
        "{robots} robots cannot cover {tasks} tasks: Case 2 needs at least as many robots as tasks (use --case idle to leave tasks unserved)"
    )]
    TooFewRobots { robots: usize, tasks: usize },
    #[error(
        "Case 1 needs as many robots as tasks, got {robots} robots and {tasks} tasks (use --case idle for scipy's rectangular meaning)"
    )]
    NotSquare { robots: usize, tasks: usize },
    #[error(
        "a problem of {robots} robot{} × {tasks} task{} is too large: {} costs, more than the limit of {limit}",
        if *robots == 1 { "" } else { "s" },
        if *tasks == 1 { "" } else { "s" },
        (*robots as u128) * (*tasks as u128)
    )]
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
    #[error("robot {robot} is assigned task {task}, but there are {tasks} tasks, numbered from 0")]
    TaskOutOfRange {
        robot: usize,
        task: usize,
        tasks: usize,
    },
}

/// Robot-by-task costs, row-major: row `i` is `α_i`, one column per task. Entries are numbers
/// or `±∞` (a forbidden pair: `+∞` when minimising, `−∞` when maximising); a normalised
/// matrix ([`crate::problem::normalise`]) instead stores finite values and a mask of allowed pairs.
#[derive(Debug, Clone, PartialEq)]
pub struct CostMatrix {
    robots: usize,
    tasks: usize,
    values: Vec<f64>,
    /// `Some` when some stored (finite) values stand for forbidden pairs.
    allowed: Option<Vec<bool>>,
    /// The robots' and tasks' names, when the cost file has them.
    names: Option<Box<Names>>,
}

/// Robot and task names, as a cost file's first column and header row give them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Names {
    /// One per robot, or none.
    pub robots: Option<Vec<String>>,
    /// One per task, or none.
    pub tasks: Option<Vec<String>>,
}

impl CostMatrix {
    /// Builds a matrix from row-major values, checking the shape; `NaN` is refused, `±∞`
    /// mark forbidden pairs (which sign is the problem's to check).
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
        if let Some(k) = values.iter().position(|v| v.is_nan()) {
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
            allowed: None,
            names: None,
        })
    }

    /// The same costs with `names` (each list as long as the robots or tasks, each name
    /// unique and not empty).
    pub fn with_names(mut self, names: Names) -> Result<Self, ProblemError> {
        check_names("robot", names.robots.as_deref(), self.robots)?;
        check_names("task", names.tasks.as_deref(), self.tasks)?;
        self.names = (names.robots.is_some() || names.tasks.is_some()).then(|| Box::new(names));
        Ok(self)
    }

    /// The robots' names, when the costs came with them.
    pub fn robot_names(&self) -> Option<&[String]> {
        self.names.as_ref()?.robots.as_deref()
    }

    /// The tasks' names, when the costs came with them.
    pub fn task_names(&self) -> Option<&[String]> {
        self.names.as_ref()?.tasks.as_deref()
    }

    /// The names, if any.
    pub fn names(&self) -> Option<&Names> {
        self.names.as_deref()
    }

    /// Finite values plus a mask of allowed pairs (`None`: all allowed), as the normalised
    /// problem stores them.
    pub fn with_mask(
        robots: usize,
        tasks: usize,
        values: Vec<f64>,
        allowed: Option<Vec<bool>>,
    ) -> Result<Self, ProblemError> {
        let mut matrix = Self::new(robots, tasks, values)?;
        if let Some(k) = matrix.values.iter().position(|v| !v.is_finite()) {
            return Err(ProblemError::NonFinite {
                robot: k / tasks,
                task: k % tasks,
                value: matrix.values[k],
            });
        }
        if let Some(mask) = &allowed
            && mask.len() != robots * tasks
        {
            return Err(ProblemError::Ragged {
                line: 1,
                found: mask.len(),
                expected: robots * tasks,
            });
        }
        matrix.allowed = allowed.filter(|m| m.iter().any(|a| !a));
        Ok(matrix)
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

    /// Whether robot `robot` may do task `task`.
    pub fn is_allowed(&self, robot: usize, task: usize) -> bool {
        let k = robot * self.tasks + task;
        self.values[k].is_finite() && self.allowed.as_ref().is_none_or(|m| m[k])
    }

    /// Whether some pair is forbidden.
    pub fn has_forbidden(&self) -> bool {
        self.allowed.is_some() || self.values.iter().any(|v| !v.is_finite())
    }

    /// The allowed pairs, row-major.
    pub fn allowed_mask(&self) -> Vec<bool> {
        (0..self.values.len())
            .map(|k| self.is_allowed(k / self.tasks, k % self.tasks))
            .collect()
    }

    /// The values of the allowed pairs.
    pub fn allowed_values(&self) -> impl Iterator<Item = f64> + Clone + '_ {
        self.allowed_values_indexed().map(|(_, v)| v)
    }

    /// The allowed pairs' row-major indices and values.
    pub fn allowed_values_indexed(&self) -> impl Iterator<Item = (usize, f64)> + Clone + '_ {
        self.values
            .iter()
            .enumerate()
            .filter(|&(k, v)| v.is_finite() && self.allowed.as_ref().is_none_or(|m| m[k]))
            .map(|(k, v)| (k, *v))
    }

    /// A spread of the allowed costs that ignores shifts and follows scaling: `√12 · std`,
    /// which equals `max − min` for uniform costs but is not driven by a single outlier.
    /// Falls back to 1 for constant costs.
    pub fn spread(&self) -> f64 {
        spread_of(self.allowed_values())
    }
}

/// [`CostMatrix::spread`] of any costs: `√12 · std`, 1 for constant (or no) costs.
pub fn spread_of(values: impl Iterator<Item = f64> + Clone) -> f64 {
    let (count, sum) = values
        .clone()
        .fold((0usize, 0.0), |(c, s), v| (c + 1, s + v));
    let count = count.max(1) as f64;
    let mean = sum / count;
    let var = values.map(|v| (v - mean) * (v - mean)).sum::<f64>() / count;
    let spread = (12.0 * var).sqrt();
    if spread > 0.0 && spread.is_finite() {
        spread
    } else {
        1.0
    }
}

/// The text of a cost file (`-`: standard input), bounded: a full-precision cost with its
/// separator fits in 32 bytes; twice that is allowed for padding.
pub fn read_cost_text(path: &Path) -> Result<String, ProblemError> {
    read_bounded(path, 64 * MAX_COST_ENTRIES as u64)
}

/// Reads a text file of at most `limit` bytes: a regular file, a pipe or a terminal
/// (`/dev/stdin`), or standard input for `-`. Directories are refused; nothing beyond the
/// limit is read, and a stream with NUL bytes (`/dev/zero`, a binary file) is refused at
/// its first block.
pub fn read_bounded(path: &Path, limit: u64) -> Result<String, ProblemError> {
    use std::io::Read;
    let io = |reason: String| ProblemError::Io {
        path: path.display().to_string(),
        reason,
    };
    let too_large = |bytes: u64| ProblemError::FileTooLarge {
        path: path.display().to_string(),
        bytes,
        limit: MAX_COST_ENTRIES,
    };
    let mut source: Box<dyn Read> = if path == Path::new("-") {
        Box::new(std::io::stdin().lock())
    } else {
        let meta = std::fs::metadata(path).map_err(|e| io(e.to_string()))?;
        if meta.is_dir() {
            return Err(io("it is a directory".into()));
        }
        if meta.is_file() && meta.len() > limit {
            return Err(too_large(meta.len()));
        }
        Box::new(std::fs::File::open(path).map_err(|e| io(e.to_string()))?)
    };
    let mut bytes = Vec::new();
    let mut block = vec![0u8; 1 << 16];
    loop {
        let n = match source.read(&mut block) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e.to_string())),
        };
        if block[..n].contains(&0) {
            return Err(io("not a text file (it holds NUL bytes)".into()));
        }
        bytes.extend_from_slice(&block[..n]);
        if bytes.len() as u64 > limit {
            return Err(too_large(bytes.len() as u64));
        }
    }
    String::from_utf8(bytes).map_err(|_| io("not UTF-8 text".into()))
}

/// Refuses a list of `what` names that is not one per item, unique and not empty.
fn check_names(what: &str, names: Option<&[String]>, count: usize) -> Result<(), ProblemError> {
    let Some(names) = names else {
        return Ok(());
    };
    if names.len() != count {
        return Err(ProblemError::Names(format!(
            "{} {what} names for {count} {what}s",
            names.len()
        )));
    }
    let mut seen = std::collections::HashSet::new();
    for (k, name) in names.iter().enumerate() {
        if name.trim().is_empty() {
            return Err(ProblemError::Names(format!("{what} {k} has an empty name")));
        }
        if !seen.insert(name.as_str()) {
            return Err(ProblemError::Names(format!(
                "two {what}s are called '{name}': names must be unique"
            )));
        }
    }
    Ok(())
}

pub(crate) fn check_size(robots: usize, tasks: usize) -> Result<(), ProblemError> {
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
    /// scipy's rectangular meaning: `min(n, m)` pairs, each robot at most one task and each
    /// task at most one robot (surplus robots idle, or surplus tasks unserved).
    Idle,
}

impl AssignmentCase {
    /// 1 or 2, as the paper numbers them; 0 for `idle`.
    pub fn number(self) -> u8 {
        match self {
            Self::One => 1,
            Self::Two => 2,
            Self::Idle => 0,
        }
    }

    /// `1`, `2` or `idle`.
    pub fn name(self) -> &'static str {
        match self {
            Self::One => "1",
            Self::Two => "2",
            Self::Idle => "idle",
        }
    }
}
