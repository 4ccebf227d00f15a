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
pub mod top;
pub mod topology;

use crate::command_line::cli::Command;
use anyhow::Result;

/// Runs the subcommand; its exit code (see [`crate::command_line::exit`]).
/// `matches`: the whole command line's, which tell options given from defaults.
pub fn run(command: Command, matches: &clap::ArgMatches) -> Result<u8> {
    match command {
        Command::Solve(args) => {
            solve::run(args, matches.subcommand_matches("solve")).map(|outcome| outcome.code())
        }
        Command::Demo(args) => demo::run(args).map(|()| 0),
        Command::Agent(args) => agent::run(args).map(|outcome| outcome.code()),
        Command::Collect(args) => collect::run(args).map(|outcome| outcome.code()),
        Command::Host(args) => host::run(args).map(|()| 0),
        Command::Bench { bench } => bench::run(bench).map(|()| 0),
        Command::Experiment { experiment } => experiment::run(experiment).map(|()| 0),
        Command::Topology(args) => topology::run(args).map(|()| 0),
        Command::Stress(args) => stress::run(args).map(|()| 0),
        Command::Top(args) => top::run(args).map(|()| 0),
    }
}
