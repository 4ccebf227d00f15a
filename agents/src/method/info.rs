//! What a method declares about itself ([`MethodInfo`]), once, in its own module: its name
//! and summary, how it runs (a team of agents, or centrally), the stop rules it honours,
//! the memory a solve needs, how its result is certified, whether it solves the user's
//! exact numbers, its text in reports and what the paper reports of it. Option checks,
//! solves, reports and experiments read these and never name a method.

use crate::certify::stopping::StopRule;
use crate::method::settings::SettingSpec;
use crate::method::team::AnyTeamMethod;

/// What a method needs and supports.
pub struct MethodInfo {
    /// The name used on the command line, in team files and in JSON.
    pub name: &'static str,
    /// One line for the command line's help.
    pub summary: &'static str,
    /// What kind of method it is (experiments pick their contenders by it).
    pub role: Role,
    /// Its team of agents, or `None`: solved centrally, in the caller's process (on a
    /// lockstep transport only).
    pub team: Option<&'static dyn AnyTeamMethod>,
    /// The setting that picks one of its variants (one of its team's settings), if it has
    /// variants.
    pub variants: Option<&'static SettingSpec>,
    /// The stop rules it honours.
    pub stops: &'static [StopRule],
    /// The memory a solve needs.
    pub memory: Memory,
    /// When its result is proven optimal.
    pub certification: Certification,
    /// Which numbers it solves.
    pub numbers: Numbers,
    /// Its text in reports.
    pub report: ReportText,
    /// What the paper reports of it, if the paper ran it.
    pub paper: Option<PaperFacts>,
}

impl std::fmt::Debug for MethodInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MethodInfo")
            .field("name", &self.name)
            .field("role", &self.role)
            .field("certification", &self.certification)
            .finish_non_exhaustive()
    }
}

impl MethodInfo {
    /// The stop rules it honours, for messages: `local, oracle or max-iters`.
    pub fn stop_names(&self, conjunction: &str) -> String {
        let names: Vec<&str> = self.stops.iter().map(|s| s.name()).collect();
        join(&names, conjunction)
    }

    /// It has a penalty ρ (`--rho`, `--adaptive-rho`).
    pub fn penalty(&self) -> bool {
        self.team.is_some_and(|t| t.penalty())
    }
}

/// What kind of method it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A consensus ADMM method of the paper.
    Admm,
    /// A baseline the paper compares with.
    Baseline,
    /// The centralized optimum (the reference row).
    Centralized,
}

/// When a method's result is proven optimal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Certification {
    /// Always: the exact optimum.
    Always,
    /// When its protocol finished (an optimal protocol).
    WhenFinished,
    /// When a stop rule that proves optimality fired (the local or the certified stop).
    WhenStopProves,
    /// Never: a heuristic (`because` says so in reports: `CBAA is a heuristic`).
    Never { because: &'static str },
}

impl Certification {
    /// Whether a run that `finished` (its stop rule fired) under `stop` is certified.
    pub fn certifies(self, finished: bool, stop: StopRule) -> bool {
        match self {
            Self::Always => true,
            Self::WhenFinished => finished,
            Self::WhenStopProves => {
                finished && matches!(stop, StopRule::Local | StopRule::Certified)
            }
            Self::Never { .. } => false,
        }
    }
}

/// Which numbers a method solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Numbers {
    /// The normalised problem (costs shifted and scaled to `[0, 1]`, forbidden pairs as a
    /// penalty, the idle task): refused where that loses the differences that decide the
    /// optimum.
    Normalised,
    /// The user's own numbers, unperturbed, on the user's shape (the exact methods).
    Exact,
}

/// A method's text in reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ReportText {
    /// What its inner iterations are, if it reports them (`Newton steps per projection`).
    pub inner_steps: Option<&'static str>,
}

/// What the paper reports of a method (the experiments reproduce it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperFacts {
    /// Its name in the paper's figures (`ADMM-TA`, `CBAA (not optimal)`).
    pub label: &'static str,
    /// The paper's own method (the others are its baselines).
    pub proposed: bool,
    /// Table 1: mean iterations at 20×20 on the complete graph.
    pub table1: Option<f64>,
    /// Fig. 1 (left): what the paper shows of it.
    pub fig1: Option<&'static str>,
    /// Fig. 2: the graphs the paper ran it on.
    pub fig2: Fig2Graphs,
    /// The variant the paper ran (a value of the method's variant setting), if it has
    /// variants.
    pub variant: Option<&'static str>,
}

/// The graphs of the paper's Fig. 2 a method ran on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Fig2Graphs {
    pub complete: bool,
    pub random: bool,
}

/// The memory a solve of a method needs, refused up front when too large.
#[derive(Debug)]
pub struct Memory {
    /// Bytes for `(robots, tasks)`: every agent's state and round buffers, or the
    /// centralized solver's working memory.
    pub bytes: fn(usize, usize) -> f64,
    /// What the bytes are, for messages: `agent state`.
    pub of: &'static str,
    /// Why, for messages: `each robot holds an m×n matrix`.
    pub because: &'static str,
}

/// What a team's memory is, for messages.
pub const TEAM_STATE: &str = "agent state";

/// `8 · values` bytes for each of `robots` agents.
pub fn per_agent(robots: usize, values: f64) -> f64 {
    8.0 * robots as f64 * values
}

/// Values of the `n × n` matrix the exact assignment solves in Case 2 (0 in Case 1).
pub fn case_two_expansion(robots: usize, tasks: usize) -> f64 {
    if robots > tasks {
        (robots * robots) as f64
    } else {
        0.0
    }
}

/// `a, b and c` (`conjunction` between the last two).
pub fn join(items: &[&str], conjunction: &str) -> String {
    match items.split_last() {
        None => String::new(),
        Some((last, [])) => (*last).to_string(),
        Some((last, rest)) => format!("{} {conjunction} {last}", rest.join(", ")),
    }
}

/// Every stop rule.
pub const ALL_STOPS: &[StopRule] = &[
    StopRule::Local,
    StopRule::Agreement,
    StopRule::Certified,
    StopRule::Oracle,
    StopRule::MaxIters,
];

/// The stop rules that do not read every robot's `m × n` matrix.
pub const OWN_STATE_STOPS: &[StopRule] = &[StopRule::Local, StopRule::Oracle, StopRule::MaxIters];
