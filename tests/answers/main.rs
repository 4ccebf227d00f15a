//! Answers users can trust: the command line and its exit codes, the corpus of inputs, any cost matrix, the oracle instances, scipy as the oracle of the LSAP solver, the library API.
//!
//! One test binary per area (as ripgrep does): each file here is a module.

#[path = "../common/mod.rs"]
mod common;

mod any_cost_matrix;
mod cli;
mod corpus;
mod cost_files;
mod dual_variants;
mod library;
mod oracle_instances;
mod scipy_lsap;
