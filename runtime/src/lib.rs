//! Runners that drive admm-ta agents and the reports they produce.
//!
//! Data flows one way: problem + graph + options → plan → team runner → transport → agents →
//! report. The modules, by layer, top to bottom; a module names modules of its own layer or
//! of lower ones only, no two files import each other (directly or around a circle), and no
//! transport names another (`tests/layout.rs` at the workspace root checks all three on the
//! sources, and the absence of cycles in every crate).
//!
//! **Entry points**
//! * [`solve`]: one end-to-end solve (costs + graph + options → rounded, checked assignment
//!   with its report), the survivors' re-solve after a failure, the oracle tracer, the
//!   central stop rules of the simulation;
//! * [`episodes`]: repeated surveillance assignments by one team alive for all of them;
//! * [`probe_run`]: a latency-benchmark team of probe agents;
//! * [`standing`]: standing teams whose robots keep their costs private, fed episode after
//!   episode by their robot programs (the Rust API and the `--serve` sidecar);
//! * [`team`]: teams of independently started agents (team files, members) and the hosts
//!   and bridges of teams across machines.
//!
//! **Team runner**
//! * [`runner`]: `run_team` — the only dispatch on how a transport executes (lockstep,
//!   threads, processes) and the only merge of the agents' latency and CPU usage.
//!
//! **Process orchestration**
//! * [`process`]: the launcher, the agent process, how an agent connects any process
//!   transport (`connect`, through [`endpoint::ProcessTransport`]), scenario files, run
//!   namespaces, the team digest.
//!
//! **Configuration**
//! * [`transport`]: the registry of transports (one line each) and their capabilities;
//! * [`options`]: validated `SolveOptions` and `RunOptions` and their `ConfigError`;
//! * [`workload`]: what agents are built from and compute (a solve's plan, surveillance
//!   episodes, probes).
//!
//! **Transports** (each independent of the others; each declares its
//! [`endpoint::TransportInfo`])
//! * [`sim`]: the lockstep simulation — every agent in one thread, round by round, each
//!   reading only its neighbours' previous-round payloads; the deterministic reference the
//!   others must reproduce bit for bit;
//! * [`threads`]: one OS thread per agent, lock-free double-buffered slots;
//! * [`shm`]: agent processes sharing one table of double-buffered slots, futex wake-ups (the
//!   `threads` protocol across processes: a reference for what a process round costs);
//! * [`ipc`]: the iceoryx2 exchange of agent processes (services, nodes, zero-copy samples);
//! * [`uds`]: agent processes copying payloads through Unix-domain sockets (a baseline);
//! * [`zenoh_net`]: agent processes over Zenoh (feature `zenoh`), the multi-host transport.
//!
//! **Shared mechanisms**
//! * [`exchange`]: the `Exchange` trait every distributed transport implements, its errors,
//!   the per-agent round loop and the round header;
//! * [`board`]: a run's shared-memory board (arrival counters, published rounds, failure
//!   mark, member pids, global barrier);
//! * [`liveness`]: whether a process lives;
//! * [`signals`]: SIGINT, SIGTERM and SIGHUP recorded (not fatal) while a team runs;
//! * [`fault`]: fault injection for tests;
//! * [`futex`]: process-shared futex waits and wake-ups on words of shared memory;
//! * [`wait`]: how agents wait (spin, then sleep), and the counting barrier;
//! * [`latency`]: round-latency histograms per component;
//! * [`usage`]: CPU time and context switches of an agent;
//! * [`endpoint`]: what a transport declares, and the trait of process transports (how an
//!   agent connects, what a run needs, whom to blame);
//! * [`error_text`]: errors as one line of text.
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

// Entry points.
pub mod episodes;
pub mod observe;
pub mod probe_run;
pub mod solve;
pub mod standing;
pub mod team;

// The team runner.
pub mod runner;

// Process orchestration.
pub mod process;

// Configuration.
pub mod options;
pub mod transport;
pub mod workload;

// Transports.
pub mod ipc;
pub mod shm;
pub mod sim;
pub mod threads;
pub mod uds;
pub mod zenoh_net;

// Shared mechanisms.
pub mod board;
pub mod endpoint;
pub mod error_text;
pub mod exchange;
pub mod fault;
pub mod futex;
pub mod latency;
pub mod liveness;
pub mod logging;
pub mod signals;
pub mod timeline;
pub mod usage;
pub mod wait;
