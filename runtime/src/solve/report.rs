//! What a solve reports.

use crate::options::StopRule;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::{AssignmentCase, IDLE};
use admm_ta_transport::Transport;
use admm_ta_transport::latency::LatencySummary;
use admm_ta_transport::usage::ThreadUsage;
use serde::{Serialize, Serializer};

/// A failed robot and how the survivors went on (`--on-failure continue`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Degraded {
    /// The failure of the first run, as the launcher reported it.
    pub failure: String,
    pub failed_robot: usize,
    /// The robots that re-solved (the user's numbers, in order).
    pub survivors: Vec<usize>,
    /// Rounds of the first run lost to the failure (the failed robot's last published round).
    pub lost_rounds: u64,
}

/// Comparison with the centralized optimum, and how fast the run got there.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OracleCheck {
    /// The optimum's total: a profit with `maximize` (then also in `optimal_profit`).
    pub optimal_cost: f64,
    /// With `maximize`: the optimum's profit (the same number as `optimal_cost`, named for
    /// what it is; `optimal_cost` stays for readers of earlier reports).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimal_profit: Option<f64>,
    /// `(cost − optimal) / |optimal|` (absolute gap when the optimum is 0).
    pub gap: f64,
    pub optimal: bool,
    /// First round whose relaxed objective (robots' own columns) is within 0.1% of the
    /// optimum: the paper's criterion (not shift-invariant).
    pub rounds_within_0_1pct: Option<usize>,
    /// Round from which the relaxed objective stays within 0.1% until the end.
    pub rounds_settled_0_1pct: Option<usize>,
    /// Round from which every robot's decision is an optimal assignment until the end
    /// (shift-invariant). A decision is the robot's own argmax, or in the fast primal
    /// variant its task in its readout.
    pub rounds_to_optimal_assignment: Option<usize>,
    /// First round whose decisions form a feasible assignment within 0.1% of the optimum:
    /// the paper's criterion on what the robots would do rather than on their relaxed
    /// columns (the fast primal variant keeps those near the polytope's centre on purpose).
    pub rounds_decisions_within_0_1pct: Option<usize>,
    /// Every round's objectives, when [`crate::options::SolveOptions::trace`] asked for them (sim only).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub trace: Vec<TracePoint>,
}

/// The team's objectives after one round.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TracePoint {
    pub round: usize,
    /// `Σ_i α_iᵀ x_i` over the robots' own relaxed columns (the paper's Fig. 1 quantity).
    pub relaxed_cost: f64,
    /// Cost of the robots' own rounded choices, when they form a feasible assignment.
    pub assignment_cost: Option<f64>,
}

/// The outcome of a solve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolveReport {
    /// Task index per robot (always feasible; [`IDLE`] for an idle robot, `null` in JSON).
    #[serde(serialize_with = "tasks_or_null")]
    pub assignment: Vec<usize>,
    pub cost: f64,
    pub iterations: usize,
    /// The stop rule fired before the iteration limit.
    pub converged: bool,
    /// The robots' own choices conflicted and were repaired.
    pub repaired: bool,
    pub method: Method,
    pub transport: Transport,
    pub rho: f64,
    pub robots: usize,
    pub tasks: usize,
    /// `1`, `2` or `"idle"` in JSON.
    #[serde(serialize_with = "case_label")]
    pub case: AssignmentCase,
    /// The costs are profits and `cost` is their total (scipy's `maximize=True`).
    pub maximize: bool,
    /// The method proved this assignment optimal (the centralized solver; market and
    /// distributed Hungarian when their protocol finished; an ADMM method whose local or
    /// certified stop fired). `false`: the best assignment found, not proved optimal.
    pub certified: bool,
    /// Robots without a task (`--case idle` with more robots than tasks).
    pub idle_robots: Vec<usize>,
    /// Tasks without a robot (`--case idle` with more tasks than robots).
    pub unserved_tasks: Vec<usize>,
    pub topology: String,
    /// Tie-breaking perturbation added to the costs (`null`: none).
    pub perturbation: Option<f64>,
    /// Mean Newton steps of the projection per robot and round.
    pub mean_projection_steps: f64,
    /// Bytes of one message (payload and header); every agent publishes one per round.
    pub message_bytes: usize,
    /// Messages each agent published (one per round; 0 for the centralized method).
    pub messages_per_agent: usize,
    /// `messages_per_agent · message_bytes`.
    pub bytes_per_agent: usize,
    pub wall_time_ms: f64,
    pub stop: StopRule,
    /// Round whose assignment the local stop certified (`iterations − diameter`).
    pub certified_round: Option<usize>,
    pub global_barrier: bool,
    /// Per-round latency percentiles of the agents (threads and ipc), in microseconds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub round_latency_us: Option<LatencySummary>,
    /// CPU time and context switches of all agents together over the recorded rounds
    /// (threads, ipc, uds).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub agent_usage: Option<ThreadUsage>,
    /// Time for all agent processes to start and connect (ipc).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub startup_ms: Option<f64>,
    /// The ipc run's id: its iceoryx2 prefix is `adta<id>_`, its directory
    /// `<runs>/<id>` (the user's private runs directory); both are gone when the solve returns.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub run_id: Option<String>,
    /// Hash of each agent's last published payload (to compare transports).
    #[serde(skip)]
    pub iterate_digests: Vec<u64>,
    /// Every agent's round stamps (`timeline` on; `timeline::chrome_trace` renders them).
    #[serde(skip)]
    pub timeline: Vec<Vec<admm_ta_transport::timeline::RoundStamp>>,
    /// Whom the team waited for, round by round (`timeline` on).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_path: Option<admm_ta_transport::timeline::CriticalPath>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<OracleCheck>,
    /// Set when a robot failed and the survivors re-solved without it: `cost` and `check`
    /// are then the survivors'; `assignment` and `idle_robots` keep the user's robot
    /// numbers, the failed robot without a task (`null`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub degraded: Option<Degraded>,
    /// The robots' names, when the cost file has them (`assignment` stays by index).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robot_names: Option<Vec<String>>,
    /// The tasks' names, when the cost file has them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub task_names: Option<Vec<String>>,
}

fn tasks_or_null<S: Serializer>(assignment: &[usize], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(
        assignment
            .iter()
            .map(|&t| if t == IDLE { None } else { Some(t) }),
    )
}

fn case_label<S: Serializer>(case: &AssignmentCase, s: S) -> Result<S::Ok, S::Error> {
    match case {
        AssignmentCase::Idle => s.serialize_str("idle"),
        other => s.serialize_u8(other.number()),
    }
}
