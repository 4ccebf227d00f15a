//! Robot communication graphs for admm-ta.
//!
//! A [`Graph`] is an undirected simple graph on robots `0..n` with sorted neighbour lists.
//! This crate builds graphs from generators ([`generate`]), from topology files
//! ([`mod@file`]), checks Assumption 1 of the paper (the graph is connected, see
//! [`Graph::require_connected`]) and gives the seeded random numbers used across the project
//! ([`rng`]). It knows nothing about agents or algorithms.
//!
//! ```
//! use admm_ta_topologies::{Graph, TopologySpec};
//! let g: Graph = "ring".parse::<TopologySpec>().unwrap().build(6, 0).unwrap();
//! assert_eq!(g.neighbours(0), &[1, 5]);
//! assert!(g.require_connected().is_ok());
//! ```

mod error;
pub mod file;
pub mod generate;
mod graph;
pub mod rng;
mod robot_ref;
mod spec;

pub use error::TopologyError;
pub use graph::Graph;
pub use robot_ref::{RobotNameError, RobotRef};
pub use spec::TopologySpec;
