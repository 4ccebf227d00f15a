//! Runners that drive admm-ta agents and the reports they produce.
//!
//! * [`sim`]: the lockstep simulation — every agent in one thread, round by round, each
//!   reading only its neighbours' previous-round payloads. It is the deterministic reference
//!   that the threaded and multi-process transports must reproduce.
//! * [`solve`]: one end-to-end solve (costs + graph + settings → rounded, checked
//!   assignment with its report).
//!
//! ```
//! use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
//! use admm_ta_runtime::options::SolveOptions;
//! use admm_ta_runtime::solve::solve;
//! use admm_ta_runtime::transport::Transport;
//! use admm_ta_topologies::generate;
//! let problem = TaskAssignmentProblem::new(CostMatrix::uniform(6, 6, 1).unwrap(), CaseChoice::Auto).unwrap();
//! let graph = generate::complete(6).unwrap();
//! let options = SolveOptions::builder().transport(Transport::Threads).check(true).build().unwrap();
//! let report = solve(&problem, &graph, &options).unwrap();
//! assert!(report.check.unwrap().optimal);
//! assert!(problem.is_feasible(&report.assignment));
//! ```

pub mod board;
pub mod episodes;
pub mod error_text;
pub mod exchange;
pub mod fault;
pub mod ipc;
pub mod latency;
pub mod liveness;
pub mod options;
pub mod probe_run;
pub mod process;
pub mod runner;
pub mod sim;
pub mod solve;
pub mod threads;
pub mod transport;
pub mod uds;
pub mod usage;
pub mod wait;
pub mod workload;
pub mod zenoh_net;
