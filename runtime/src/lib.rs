//! The orchestration of admm-ta teams: options, workloads, the launcher and the agent
//! process, the team runner, solves, teams of independently started agents, standing teams
//! and the hosts of teams across machines — and the reports they produce. How the agents
//! exchange their messages (every transport, the round loop, the board, waiting, latency,
//! timelines, signals) is the crate below, `admm-ta-transport`; Cargo keeps the direction.
//!
//! Data flows one way: problem + graph + options → plan → team runner → transport → agents →
//! report. The modules, by layer, top to bottom; a module names modules of its own layer or
//! of lower ones only and no two files import each other (directly or around a circle)
//! (`tests/layout.rs` at the workspace root checks both on the sources).
//!
//! **Entry points**
//! * [`solve`]: one end-to-end solve (costs + graph + options → rounded, checked assignment
//!   with its report), the survivors' re-solve after a failure, the oracle tracer, the
//!   central stop rules of the simulation;
//! * [`surveillance`]: repeated surveillance assignments by one team alive for all of them;
//! * [`probe_run`]: a latency-benchmark team of probe agents;
//! * [`standing`]: standing teams whose robots keep their costs private, fed episode after
//!   episode by their robot programs (the Rust API and the `--serve` sidecar);
//! * [`team`]: teams of independently started agents (team files, members);
//! * `host` (feature `zenoh`): one machine of a multi-host team — its Zenoh router, its
//!   watch of the team, and the bridge of a mixed team.
//!
//! **Team runner**
//! * [`runner`]: `run_team` — the only dispatch on how a transport executes (lockstep,
//!   threads, processes) and the only merge of the agents' latency and CPU usage.
//!
//! **Process orchestration**
//! * [`process`]: the launcher, the agent process, how an agent connects any process
//!   transport (`connect`, through
//!   [`admm_ta_transport::endpoint::ProcessTransport`]), scenario files, run
//!   namespaces, the team digest.
//!
//! **Configuration**
//! * [`options`]: validated `SolveOptions` and `RunOptions` and their `ConfigError`;
//! * [`workload`]: what agents are built from and compute (a solve's plan, surveillance
//!   episodes, probes).
//!
//! ```
//! use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
//! use admm_ta_runtime::options::SolveOptions;
//! use admm_ta_runtime::solve::solve;
//! use admm_ta_transport::Transport;
//! use admm_ta_topologies::generate;
//! let problem = TaskAssignmentProblem::new(CostMatrix::uniform(6, 6, 1).unwrap(), CaseChoice::Auto).unwrap();
//! let graph = generate::complete(6).unwrap();
//! let options = SolveOptions::builder().transport(Transport::Threads).check(true).build().unwrap();
//! let report = solve(&problem, &graph, &options).unwrap();
//! assert!(report.check.unwrap().optimal);
//! assert!(problem.is_feasible(&report.assignment));
//! ```

// Entry points.
#[cfg(feature = "zenoh")]
pub mod host;
pub mod observe;
pub mod probe_run;
pub mod solve;
pub mod standing;
pub mod surveillance;
pub mod team;

// The team runner.
pub mod runner;

// Process orchestration.
pub mod process;

// Configuration.
pub mod options;
pub mod workload;
