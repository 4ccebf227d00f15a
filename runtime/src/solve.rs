//! One end-to-end solve: build the agents, run them, round, repair, check.

use crate::sim::{LockstepSim, RoundView, SimOutcome};
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::oracle::{self, OptimalAssignment};
use admm_ta_agents::primal::{PrimalAgent, PrimalSettings, ProjectionPath};
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_agents::stopping::{AgreementStop, AgreementStreak, NeverStop};
use admm_ta_agents::{rho, rounding, ties};
use admm_ta_topologies::Graph;
use serde::Serialize;
use std::time::Instant;

/// Agent state plus round buffers above this many bytes is refused up front.
pub const MEMORY_LIMIT_BYTES: f64 = 8.0 * (1u64 << 30) as f64;

/// The consensus algorithm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Primal consensus ADMM (Algorithm 1).
    #[default]
    Primal,
}

impl Method {
    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Primal => "primal",
        }
    }
}

/// What carries the messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Transport {
    /// Lockstep simulation in one thread.
    #[default]
    Sim,
}

impl Transport {
    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sim => "sim",
        }
    }
}

/// When the run ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum StopRule {
    /// All robots agree on one near-integral assignment for some rounds (default 10).
    Agreement,
    /// All robots round to the same assignment and their optimality-certificate slacks
    /// ([`PrimalAgent::certificate_slack`]) sum to at most `1e-9 ·` its cost scale: the
    /// assignment is then provably optimal to that tolerance (default).
    #[default]
    Certified,
    /// Run to the iteration limit.
    MaxIters,
}

/// Everything a solve needs besides the problem and the graph.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveConfig {
    pub method: Method,
    pub transport: Transport,
    /// `None`: the scale-free default of [`rho::default_rho`].
    pub rho: Option<f64>,
    pub max_iters: usize,
    pub stop: StopRule,
    pub stop_rounds: usize,
    /// Seed of the tie-breaking perturbations.
    pub seed: u64,
    pub perturbation: ties::Perturbation,
    pub projection: ProjectionPath,
    /// Compare with the centralized optimum and trace convergence.
    pub check: bool,
}

impl Default for SolveConfig {
    fn default() -> Self {
        Self {
            method: Method::Primal,
            transport: Transport::Sim,
            rho: None,
            max_iters: 5000,
            stop: StopRule::Certified,
            stop_rounds: 10,
            seed: 0,
            perturbation: ties::Perturbation::Auto,
            projection: ProjectionPath::Fast,
            check: false,
        }
    }
}

/// Reasons a solve cannot start.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SolveError {
    #[error("the topology has {graph} robots but the costs have {problem}")]
    SizeMismatch { graph: usize, problem: usize },
    #[error("ρ must be a positive finite number, got {0}")]
    BadRho(f64),
    #[error("--max-iters must be at least 1")]
    NoIterations,
    #[error(
        "{robots} robots × {tasks} tasks need about {gib:.1} GiB of agent state (each robot holds an m×n matrix); the limit is 8 GiB"
    )]
    TooLarge {
        robots: usize,
        tasks: usize,
        gib: f64,
    },
}

/// Comparison with the centralized optimum, and how fast the run got there.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OracleCheck {
    pub optimal_cost: f64,
    /// `(cost − optimal) / |optimal|` (absolute gap when the optimum is 0).
    pub gap: f64,
    pub optimal: bool,
    /// First round whose relaxed objective (robots' own columns) is within 0.1% of the
    /// optimum: the paper's criterion (not shift-invariant).
    pub rounds_within_0_1pct: Option<usize>,
    /// Round from which the relaxed objective stays within 0.1% until the end.
    pub rounds_settled_0_1pct: Option<usize>,
    /// Round from which every robot's own argmax is an optimal assignment until the end
    /// (shift-invariant).
    pub rounds_to_optimal_assignment: Option<usize>,
}

/// The outcome of a solve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolveReport {
    /// Task index per robot (always feasible).
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
    pub case: u8,
    pub topology: String,
    /// Tie-breaking perturbation added to the costs (`null`: none).
    pub perturbation: Option<f64>,
    /// Mean Newton steps of the projection per robot and round.
    pub mean_projection_steps: f64,
    pub wall_time_ms: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<OracleCheck>,
}

/// Solves `problem` on `graph` as `config` says.
pub fn solve(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    config: &SolveConfig,
) -> Result<SolveReport, SolveError> {
    let (n, m) = (problem.robots(), problem.tasks());
    if graph.robots() != n {
        return Err(SolveError::SizeMismatch {
            graph: graph.robots(),
            problem: n,
        });
    }
    if config.max_iters == 0 {
        return Err(SolveError::NoIterations);
    }
    let bytes = 8.0 * 6.0 * (m * n) as f64 * n as f64;
    if bytes > MEMORY_LIMIT_BYTES {
        return Err(SolveError::TooLarge {
            robots: n,
            tasks: m,
            gib: bytes / (1u64 << 30) as f64,
        });
    }
    let rho = config
        .rho
        .unwrap_or_else(|| rho::default_rho(problem.costs(), graph.mean_degree()));
    if !(rho > 0.0 && rho.is_finite()) {
        return Err(SolveError::BadRho(rho));
    }
    let epsilon = ties::epsilon(problem.costs(), config.perturbation);
    let settings = PrimalSettings {
        projection: config.projection,
        ..PrimalSettings::new(rho)
    };
    let agents = primal_team(problem, graph, settings, epsilon, config.seed);
    let optimum = config
        .check
        .then(|| oracle::solve(problem).expect("validated costs have an optimum"));
    let mut tracer = optimum.as_ref().map(|o| Tracer::new(problem, o));
    let started = Instant::now();
    let mut sim = LockstepSim::new(agents, graph);
    let mut projection_steps = 0usize;
    let mut observer = |view: &RoundView<'_>| {
        projection_steps += view
            .reports
            .iter()
            .map(|r| r.inner_iterations)
            .sum::<usize>();
        if let Some(t) = tracer.as_mut() {
            t.observe(view);
        }
    };
    let mut agreement = AgreementStop::new(config.stop_rounds);
    let outcome = match config.stop {
        StopRule::Agreement => sim.run(config.max_iters, &mut agreement, &mut observer),
        StopRule::MaxIters => sim.run(config.max_iters, &mut NeverStop, &mut observer),
        StopRule::Certified => {
            let tolerance = 1e-9 * problem.costs().spread() * n as f64;
            run_until_certified(&mut sim, config.max_iters, tolerance, &mut observer)
        }
    };
    let decisions: Vec<usize> = sim.agents().iter().map(ConsensusAgent::decide).collect();
    let wall_time_ms = started.elapsed().as_secs_f64() * 1e3;
    let (assignment, repaired) = rounding::repair(problem, &decisions);
    let cost = problem
        .cost_of(&assignment)
        .expect("repaired assignment is in range");
    let check = tracer.map(|t| t.finish(cost));
    Ok(SolveReport {
        assignment,
        cost,
        iterations: outcome.rounds,
        converged: outcome.stopped,
        repaired,
        method: config.method,
        transport: config.transport,
        rho,
        robots: n,
        tasks: m,
        case: problem.case().number(),
        topology: graph.name().to_string(),
        perturbation: epsilon,
        mean_projection_steps: projection_steps as f64 / (n * outcome.rounds.max(1)) as f64,
        wall_time_ms,
        check,
    })
}

/// One primal agent per robot of `graph`, each with its own (optionally perturbed) costs.
pub fn primal_team(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    settings: PrimalSettings,
    epsilon: Option<f64>,
    seed: u64,
) -> Vec<PrimalAgent> {
    (0..problem.robots())
        .map(|i| {
            let costs = ties::perturbed_row(problem.costs(), i, epsilon, seed);
            PrimalAgent::new(
                i,
                costs,
                problem.robots(),
                problem.case(),
                graph.degree(i),
                settings,
            )
        })
        .collect()
}

/// Rounds after which an agreement is first certified, and the spacing of later checks
/// (each check is one `m × n` assignment problem per robot).
const CERTIFY_AFTER: usize = 3;
const CERTIFY_EVERY: usize = 5;

/// Steps until the robots agree on one assignment whose certificate slacks sum to at most
/// `tolerance` (see [`PrimalAgent::certificate_slack`]), or `max_rounds`.
fn run_until_certified(
    sim: &mut LockstepSim<PrimalAgent>,
    max_rounds: usize,
    tolerance: f64,
    observer: &mut dyn FnMut(&RoundView<'_>),
) -> SimOutcome {
    // Agreement on one feasible assignment; near-integrality is not needed here.
    let mut streak = AgreementStreak::default();
    while sim.round() < max_rounds {
        let agreed_for = streak.observe(sim.step_round(), f64::MAX);
        observer(&sim.view());
        if agreed_for >= CERTIFY_AFTER && (agreed_for - CERTIFY_AFTER).is_multiple_of(CERTIFY_EVERY)
        {
            let slack: f64 = sim
                .agents()
                .iter()
                .map(PrimalAgent::certificate_slack)
                .sum();
            if slack <= tolerance {
                return SimOutcome {
                    rounds: sim.round(),
                    stopped: true,
                };
            }
        }
    }
    SimOutcome {
        rounds: sim.round(),
        stopped: false,
    }
}

/// Follows the run against the optimum (only when checking).
struct Tracer<'p> {
    problem: &'p TaskAssignmentProblem,
    optimal_cost: f64,
    first_within: Option<usize>,
    settled_within: Option<usize>,
    optimal_since: Option<usize>,
    decisions: Vec<usize>,
}

impl<'p> Tracer<'p> {
    fn new(problem: &'p TaskAssignmentProblem, optimum: &OptimalAssignment) -> Self {
        Self {
            problem,
            optimal_cost: optimum.cost,
            first_within: None,
            settled_within: None,
            optimal_since: None,
            decisions: vec![0; problem.robots()],
        }
    }

    fn relative_gap(&self, cost: f64) -> f64 {
        let scale = self.optimal_cost.abs();
        let diff = cost - self.optimal_cost;
        if scale > 0.0 { diff / scale } else { diff }
    }

    fn observe(&mut self, view: &RoundView<'_>) {
        let m = self.problem.tasks();
        let mut relaxed = 0.0;
        for i in 0..self.problem.robots() {
            let own = &view.payloads[i * view.payload_len + i * m..][..m];
            relaxed += own
                .iter()
                .zip(self.problem.costs().row(i))
                .map(|(x, a)| x * a)
                .sum::<f64>();
            rounding::argmax_assignment(own, m, &mut self.decisions[i..i + 1]);
        }
        if self.relative_gap(relaxed).abs() <= 1e-3 {
            self.first_within.get_or_insert(view.round);
            self.settled_within.get_or_insert(view.round);
        } else {
            self.settled_within = None;
        }
        let optimal = self.problem.is_feasible(&self.decisions)
            && self.relative_gap(
                self.problem
                    .cost_of(&self.decisions)
                    .unwrap_or(f64::INFINITY),
            ) <= 1e-9;
        if optimal {
            self.optimal_since.get_or_insert(view.round);
        } else {
            self.optimal_since = None;
        }
    }

    fn finish(self, cost: f64) -> OracleCheck {
        let gap = self.relative_gap(cost);
        OracleCheck {
            optimal_cost: self.optimal_cost,
            gap,
            optimal: gap <= 1e-9,
            rounds_within_0_1pct: self.first_within,
            rounds_settled_0_1pct: self.settled_within,
            rounds_to_optimal_assignment: self.optimal_since,
        }
    }
}
