//! `admm-ta demo`: the built-in problem (20 robots, 20 tasks, complete graph), checked.

use crate::command_line::cli::DemoArgs;
use crate::command_line::commands::shared::agent_program;
use crate::command_line::output;
use crate::command_line::output::outln;
use crate::{CaseChoice, CostMatrix, SolveOptions, TaskAssignmentProblem, generate};
use anyhow::Result;

pub fn run(args: DemoArgs) -> Result<()> {
    let problem = TaskAssignmentProblem::new(CostMatrix::uniform(20, 20, 2019)?, CaseChoice::Auto)?;
    let graph = generate::complete(20)?;
    let options = SolveOptions::builder()
        .check(true)
        .transport(args.transport)
        .agent_program(agent_program()?)
        .build()?;
    if !args.json {
        outln!(
            "demo: 20 robots, 20 tasks, uniform [0,1) costs (seed 2019), complete graph, transport {}\n",
            options.transport().name()
        );
    }
    let report = crate::solve(&problem, &graph, &options)?;
    output::print_report(&report, args.json)
}
