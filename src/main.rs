//! `admm-ta`: consensus ADMM task assignment for multi-robot teams — the command line of
//! the `admm_ta` library ([`admm_ta::command_line`]).

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(admm_ta::command_line::run(std::env::args_os()))
}
