//! Decentralized task assignment for robot teams by consensus ADMM, as a library: one
//! import for a robot program.
//!
//! A problem (costs, [`TaskAssignmentProblem`]) and a communication graph ([`Graph`], from
//! [`generate`] or a [`TopologySpec`]) go in; a [`SolveReport`] with the assignment comes
//! out. [`Solver`] is the short way, [`solve`] with [`SolveOptions`] the explicit one; the
//! member crates stay reachable as [`agents`], [`runtime`], [`transport`] and [`topologies`].
//!
//! **Costs from a CSV, assignment out** (one line per robot, one number per task; the team
//! runs in the lockstep simulation, the default):
//!
//! ```
//! use admm_ta::{CaseChoice, CostMatrix, Solver, TaskAssignmentProblem};
//! let costs = CostMatrix::from_csv_str("# 3 robots, 2 tasks\n0.9,0.1\n0.4,0.3\n0.2,0.8\n")?;
//! let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto)?;
//! let report = Solver::new(problem).check(true).solve()?;
//! assert_eq!(report.assignment, [1, 1, 0]); // robot → task
//! assert!(report.check.unwrap().optimal);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **A team of threads** (one OS thread per robot, each talking to its ring neighbours
//! only), here with the dual method:
//!
//! ```
//! use admm_ta::{CaseChoice, CostMatrix, Method, Solver, TaskAssignmentProblem, Transport, generate};
//! let problem = TaskAssignmentProblem::new(CostMatrix::uniform(6, 6, 3)?, CaseChoice::Auto)?;
//! let report = Solver::new(problem)
//!     .topology(generate::ring(6)?)
//!     .method(Method::Dual)
//!     .transport(Transport::Threads)
//!     .check(true)
//!     .solve()?;
//! assert!(report.check.unwrap().optimal);
//! assert!(report.round_latency_us.is_some()); // measured on every agent's rounds
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **A team of processes** (one OS process per robot over iceoryx2 shared memory). The
//! launcher starts each agent as `PROGRAM agent --run ID --robot I --scenario FILE`: point
//! [`Solver::agent_program`] at the `admm-ta` binary (or at a program of your own that
//! answers that command line with [`runtime::process::agent::run`]). Not run here: a
//! documentation test has no `admm-ta` binary at hand; `tests/answers/library.rs` runs this
//! example.
//!
//! ```no_run
//! use admm_ta::{CaseChoice, CostMatrix, Solver, TaskAssignmentProblem, Transport};
//! let problem = TaskAssignmentProblem::new(CostMatrix::uniform(8, 5, 1)?, CaseChoice::Auto)?;
//! let report = Solver::new(problem)
//!     .transport(Transport::Ipc)
//!     .agent_program("target/release/admm-ta")
//!     .solve()?;
//! println!("{:?} after {} rounds", report.assignment, report.iterations);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod command_line;
pub mod request;

pub use admm_ta_agents as agents;
pub use admm_ta_runtime as runtime;
pub use admm_ta_topologies as topologies;
pub use admm_ta_transport as transport;

pub use admm_ta_agents::certify::stopping::StopRule;
pub use admm_ta_agents::methods::Method;
pub use admm_ta_agents::methods::primal::agent::ProjectionPath;
pub use admm_ta_agents::methods::primal::settings::PrimalVariant;
pub use admm_ta_agents::problem::cost_model::CostModel;
pub use admm_ta_agents::problem::ties::Perturbation;
pub use admm_ta_agents::problem::{
    AssignmentCase, CaseChoice, CostMatrix, ProblemError, TaskAssignmentProblem,
};
pub use admm_ta_runtime::options::error::ConfigError;
pub use admm_ta_runtime::options::{OnFailure, SolveOptions, SolveOptionsBuilder};
pub use admm_ta_runtime::solve::error::SolveError;
pub use admm_ta_runtime::solve::report::{OracleCheck, SolveReport};
pub use admm_ta_runtime::solve::solve;
pub use admm_ta_topologies::{Graph, TopologyError, TopologySpec, generate};
pub use admm_ta_transport::Transport;
pub use admm_ta_transport::wait::WaitStrategy;

use std::path::PathBuf;

/// Why [`Solver::solve`] failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The default complete graph could not be built for this many robots.
    #[error(transparent)]
    Topology(#[from] TopologyError),
    /// Invalid options ([`SolveError::Config`]) or a failed solve.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// A solve of one problem: the graph and the options around it, then [`Solver::solve`].
///
/// Defaults: the complete graph, and [`SolveOptions::default`] (primal consensus ADMM, the
/// decentralized certified stop, the lockstep simulation). An option set that the run never
/// reads (ρ with the market method, a round timeout on the simulation) is refused by
/// [`Solver::solve`], as on the command line
/// ([`SolveOptionsBuilder::refuse_unread`]).
#[derive(Debug, Clone)]
pub struct Solver {
    problem: TaskAssignmentProblem,
    graph: Option<Graph>,
    options: SolveOptionsBuilder,
}

impl Solver {
    pub fn new(problem: TaskAssignmentProblem) -> Self {
        Self {
            problem,
            graph: None,
            options: SolveOptions::builder().refuse_unread(true),
        }
    }

    /// The robots' communication graph (one node per robot).
    pub fn topology(mut self, graph: Graph) -> Self {
        self.graph = Some(graph);
        self
    }

    pub fn method(self, method: Method) -> Self {
        self.configure(|o| o.method(method))
    }

    pub fn transport(self, transport: Transport) -> Self {
        self.configure(|o| o.transport(transport))
    }

    /// Compare with the centralized optimum ([`SolveReport::check`]).
    pub fn check(self, on: bool) -> Self {
        self.configure(|o| o.check(on))
    }

    /// The program agent processes are started from (process transports).
    pub fn agent_program(self, program: impl Into<PathBuf>) -> Self {
        let program = program.into();
        self.configure(|o| o.agent_program(program))
    }

    /// Any other option: `solver.configure(|o| o.max_iters(200).adaptive_rho(true))`.
    pub fn configure(mut self, f: impl FnOnce(SolveOptionsBuilder) -> SolveOptionsBuilder) -> Self {
        self.options = f(self.options);
        self
    }

    /// Checks the options and solves.
    pub fn solve(self) -> Result<SolveReport, Error> {
        let graph = match self.graph {
            Some(graph) => graph,
            None => generate::complete(self.problem.robots())?,
        };
        let options = self.options.build().map_err(SolveError::from)?;
        Ok(solve(&self.problem, &graph, &options)?)
    }
}
