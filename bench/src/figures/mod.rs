//! The paper's figures and two beyond it, each one command (`admm-ta experiment NAME`)
//! writing a JSON file and SVG plots shaped like the paper's:
//!
//! * [`convergence::fig1_convergence`]: 50×50, complete graph — the team's relaxed cost per iteration
//!   against the Hungarian optimum (paper Fig. 1 left: primal ADMM-TA within 50 iterations),
//!   plus every ADMM method's and variant's relative gap on log axes, each labelled;
//! * [`convergence::fig1_topologies`]: 50 robots × 30 tasks on complete, random and chain graphs (paper
//!   Fig. 1 right: all converge, the chain slowest, "about 200 iterations");
//! * [`scaling::fig2_scaling`]: iterations versus team size for ADMM-TA, CBAA, the market and the
//!   distributed Hungarian method on the complete graph, and ADMM-TA versus distributed
//!   Hungarian on random graphs (paper Fig. 2), and beside them every other ADMM method and
//!   variant to the decentralized stop, labelled (`dual (fast)`, …);
//! * [`scaling::ipc_scaling`] (beyond the paper): wall time to the optimal assignment with one
//!   process per robot over iceoryx2, and the round latency, versus team size per method.
//!
//! [`convergence`] holds the first two, [`scaling`] the other two; each returns a report that
//! [`crate::experiment::write`] writes.
//!
//! Every run is a real solve ([`admm_ta_runtime::solve::solve`]) checked against the
//! centralized optimum; nothing is taken from the paper but the comparison numbers.

pub mod convergence;
pub mod scaling;

use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::SolveOptionsBuilder;
use admm_ta_runtime::runner::RunError;
use admm_ta_runtime::solve::error::SolveError;
use admm_ta_runtime::solve::report::{OracleCheck, SolveReport};
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::TopologySpec;

/// The random graph of the topology experiments (edge probability 0.1, connected).
pub const RANDOM_GRAPH: &str = "random:0.1";

/// Settings shared by the figure experiments.
#[derive(Debug, Clone)]
pub struct FigureConfig {
    /// Seeds (cost matrices and random graphs) per point.
    pub trials: u64,
    /// Team sizes (robots = tasks) of the scaling experiments.
    pub sizes: Vec<usize>,
    pub adaptive_rho: bool,
    pub max_iters: usize,
    /// The `admm-ta` binary (ipc runs).
    pub agent_program: Option<admm_ta_runtime::options::run::AgentProgram>,
    /// ADMM runs to the decentralized stop only up to this team size in `fig2-scaling`
    /// (beyond it, the paper's 0.1% criterion only: the decentralized stop of the primal
    /// method at 100 robots takes ~40 s per run on 2 cores).
    pub decentralized_up_to: usize,
}

impl Default for FigureConfig {
    fn default() -> Self {
        Self {
            trials: 3,
            sizes: vec![10, 20, 30, 40, 50, 60, 70, 80, 90, 100],
            adaptive_rho: false,
            max_iters: 5000,
            agent_program: None,
            decentralized_up_to: 50,
        }
    }
}

/// Failures of an experiment.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error("{0}")]
    Setup(String),
}

pub(crate) fn uniform(
    robots: usize,
    tasks: usize,
    seed: u64,
) -> Result<TaskAssignmentProblem, FigureError> {
    let costs =
        CostMatrix::uniform(robots, tasks, seed).map_err(|e| FigureError::Setup(e.to_string()))?;
    TaskAssignmentProblem::new(costs, CaseChoice::Auto)
        .map_err(|e| FigureError::Setup(e.to_string()))
}

pub(crate) fn topology(
    spec: &str,
    n: usize,
    seed: u64,
) -> Result<admm_ta_topologies::Graph, FigureError> {
    spec.parse::<TopologySpec>()
        .and_then(|t| t.build(n, seed))
        .map_err(|e| FigureError::Setup(format!("topology {spec}: {e}")))
}

/// A method as the paper ran it (the primal method's paper variant: the fast one's relaxed
/// columns stay near the polytope's centre on purpose), or with its defaults.
pub(crate) fn as_in_paper(method: Method) -> Contender {
    Contender::as_in_paper(method).unwrap_or(Contender::of(method))
}

impl FigureConfig {
    /// Solves `problem` by `contender` (a method in one of its variants) on a `graph_spec` graph drawn from `seed`, checked
    /// against the optimum, with this experiment's ρ schedule, round limit and agent binary;
    /// `options` gives the rest (stop, transport, trace).
    pub(crate) fn checked_solve(
        &self,
        problem: &TaskAssignmentProblem,
        graph_spec: &str,
        seed: u64,
        contender: Contender,
        options: SolveOptionsBuilder,
    ) -> Result<(SolveReport, OracleCheck), FigureError> {
        let graph = topology(graph_spec, problem.robots(), seed)?;
        let options = options
            .method(contender.method)
            .settings(contender.settings())
            .seed(seed)
            .check(true)
            .adaptive_rho(
                self.adaptive_rho
                    && crate::compare::has_schedule(contender.method, &contender.settings()),
            )
            .max_iters(self.max_iters)
            .agent_program(self.agent_program.clone())
            .fault_injection(false)
            .build()
            .map_err(SolveError::from)?;
        let report = solve(problem, &graph, &options)?;
        let check = report.check.clone().expect("checked run");
        Ok((report, check))
    }
}
