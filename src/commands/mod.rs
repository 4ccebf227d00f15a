//! One file per subcommand, each a `run(args)`; [`run`] dispatches the parsed command line.

pub mod agent;
pub mod bench;
pub mod collect;
pub mod demo;
pub mod experiment;
pub mod host;
pub mod shared;
pub mod solve;
pub mod stress;
pub mod topology;

use crate::cli::Command;
use anyhow::Result;

/// Runs the subcommand.
pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Solve(args) => solve::run(args),
        Command::Demo(args) => demo::run(args),
        Command::Agent(args) => agent::run(args),
        Command::Collect(args) => collect::run(args),
        Command::Host(args) => host::run(args),
        Command::Bench { bench } => bench::run(bench),
        Command::Experiment { experiment } => experiment::run(experiment),
        Command::Topology(args) => topology::run(args),
        Command::Stress(args) => stress::run(args),
    }
}
