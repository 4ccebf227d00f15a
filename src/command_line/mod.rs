//! The `admm-ta` command line as a library: [`run`] is the whole program (`src/main.rs` only
//! calls it), so that other front ends — the Python package's `admm-ta` script and its agent
//! processes — run exactly the same program; [`solve_report`] is `admm-ta solve` returning
//! its report instead of printing it.
//!
//! [`cli`]: the arguments; [`commands`]: one file per subcommand; [`exit`]: exit codes;
//! [`output`]: the printed report.

pub mod cli;
pub mod commands;
pub mod exit;
pub mod method_flags;
pub mod output;

use clap::{CommandFactory, FromArgMatches};
use std::ffi::OsString;

pub use commands::solve::{GivenInput, solve_report};
pub use exit::Outcome;

/// Runs the command line `args` (the program name first) as the `admm-ta` binary does and
/// returns its exit code; messages go to standard error and reports to standard output.
pub fn run(args: impl IntoIterator<Item = impl Into<OsString> + Clone>) -> u8 {
    let parsed = parse(args);
    let (args, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(error) if !error.use_stderr() => {
            // --help and --version.
            let _ = error.print();
            return 0;
        }
        Err(error) => {
            eprintln!("{} (see admm-ta --help)", one_line(&error));
            return 2;
        }
    };
    if let Err(error) = crate::transport::logging::init(args.log.as_deref()) {
        eprintln!("error: {error}");
        return 2;
    }
    match commands::run(args.command, &matches) {
        Ok(code) => code,
        Err(error) if output::reader_closed(&error) => {
            // `admm-ta topology | head -1`: the reader has what it wanted; end quietly.
            0
        }
        Err(error) => {
            // One line naming the problem, with its causes; never a backtrace.
            eprintln!("error: {error:#}");
            // A team stopped by SIGINT, SIGTERM or SIGHUP: the conventional 128 + signal.
            match crate::transport::signals::received() {
                Some(signal) => crate::transport::signals::exit_code(signal),
                None => exit::code_of(&error),
            }
        }
    }
}

/// The parsed command line and clap's matches (which tell options given from defaults).
pub fn parse(
    args: impl IntoIterator<Item = impl Into<OsString> + Clone>,
) -> Result<(cli::Cli, clap::ArgMatches), clap::Error> {
    cli::Cli::command()
        .try_get_matches_from(args)
        .and_then(|matches| cli::Cli::from_arg_matches(&matches).map(|args| (args, matches)))
}

/// clap's first paragraph names the problem (with the missing arguments indented below it);
/// the usage block after it is noise here. One line.
pub fn one_line(error: &clap::Error) -> String {
    let rendered = error.to_string();
    let problem: Vec<&str> = rendered
        .lines()
        .take_while(|line| !line.trim().is_empty())
        .map(str::trim)
        .collect();
    match problem.split_first() {
        Some((first, [])) => first.to_string(),
        Some((first, rest)) => format!("{first} {}", rest.join(", ")),
        None => "invalid arguments".to_string(),
    }
}
