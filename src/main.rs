//! `admm-ta`: consensus ADMM task assignment for multi-robot teams — the command line over
//! the `admm_ta` library ([`cli`]: the arguments; [`commands`]: one file per subcommand).

mod cli;
mod commands;
mod exit;
mod method_flags;
mod output;

use clap::{CommandFactory, FromArgMatches};
use std::process::ExitCode;

fn main() -> ExitCode {
    let parsed = cli::Cli::command()
        .try_get_matches()
        .and_then(|matches| cli::Cli::from_arg_matches(&matches).map(|args| (args, matches)));
    let (args, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(error) if !error.use_stderr() => {
            // --help and --version.
            let _ = error.print();
            return ExitCode::SUCCESS;
        }
        Err(error) => {
            // clap's first paragraph names the problem (with the missing arguments indented
            // below it); the usage block after it is noise here. One line.
            let rendered = error.to_string();
            let problem: Vec<&str> = rendered
                .lines()
                .take_while(|line| !line.trim().is_empty())
                .map(str::trim)
                .collect();
            let problem = match problem.split_first() {
                Some((first, [])) => first.to_string(),
                Some((first, rest)) => format!("{first} {}", rest.join(", ")),
                None => "invalid arguments".to_string(),
            };
            eprintln!("{problem} (see admm-ta --help)");
            return ExitCode::from(2);
        }
    };
    match commands::run(args.command, &matches) {
        Ok(code) => ExitCode::from(code),
        Err(error) if output::reader_closed(&error) => {
            // `admm-ta topology | head -1`: the reader has what it wanted; end quietly.
            ExitCode::SUCCESS
        }
        Err(error) => {
            // One line naming the problem, with its causes; never a backtrace.
            eprintln!("error: {error:#}");
            // A team stopped by SIGINT, SIGTERM or SIGHUP: the conventional 128 + signal.
            match admm_ta::runtime::signals::received() {
                Some(signal) => ExitCode::from(admm_ta::runtime::signals::exit_code(signal)),
                None => ExitCode::from(exit::code_of(&error)),
            }
        }
    }
}
