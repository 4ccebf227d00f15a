//! The runtime's integration tests: the runners, the fast primal, the baselines, the round header, stop rules.
//!
//! One test binary per area (as ripgrep does): each file here is a module.

mod common;

mod cbaa;
mod fast_primal;
mod fuzz_header;
mod optimal_baselines;
mod sim_runner;
mod wrong_stops;
