//! `admm-ta solve`: a problem from a CSV or random costs, solved as the flags say.

use crate::command_line::cli::SolveArgs;
use crate::command_line::commands::shared::agent_program;
use crate::command_line::exit::{Outcome, UsageError};
use crate::command_line::output;
use crate::request::{CostSource, SolveRequest, TopologySource, parse_perturb, parse_rho};
use crate::{CostMatrix, Graph, SolveOptions, SolveOptionsBuilder, SolveReport};
use anyhow::Result;
use clap::ArgMatches;
use clap::parser::ValueSource;

/// Solves as `args` say; `matches` (the command line's) tells which options the user gave.
pub fn run(args: SolveArgs, matches: Option<&ArgMatches>) -> Result<Outcome> {
    let report = solve_report(&args, matches, GivenInput::default())?;
    output::print_report(&report, args.json)?;
    Ok(Outcome::of(&report))
}

/// What a front end hands [`solve_report`] besides the command line: the costs as values
/// (instead of `--costs FILE` or `--robots N --tasks M`; `+∞` marks a forbidden pair, `−∞`
/// with `--maximize`, as in a cost file) and the graph (instead of `--topology`).
#[derive(Debug, Clone, Default)]
pub struct GivenInput {
    pub costs: Option<CostMatrix>,
    pub graph: Option<Graph>,
}

/// `admm-ta solve` without the printing: the report of the solve `args` and `given` ask
/// for. The caller decides what the report means ([`Outcome::of`]).
pub fn solve_report(
    args: &SolveArgs,
    matches: Option<&ArgMatches>,
    given_input: GivenInput,
) -> Result<SolveReport> {
    request_of(args, matches, given_input)?.solve()
}

/// The request `args` make: only the options the user gave are set, so that one the run
/// never reads is refused by the options' own rule (`refuse_unread`), as for team files.
fn request_of(
    args: &SolveArgs,
    matches: Option<&ArgMatches>,
    given_input: GivenInput,
) -> Result<SolveRequest> {
    let given =
        |id: &str| matches.is_some_and(|m| m.value_source(id) == Some(ValueSource::CommandLine));
    if given_input.costs.is_some() && (args.costs.is_some() || given("robots") || given("tasks")) {
        return Err(UsageError(
            "the costs are given already: no --costs, --robots or --tasks with them".into(),
        )
        .into());
    }
    if given_input.graph.is_some() && given("topology") {
        return Err(UsageError("the graph is given already: no --topology with it".into()).into());
    }
    let costs = match (given_input.costs, &args.costs, args.robots, args.tasks) {
        (Some(costs), ..) => CostSource::Given(costs),
        (None, Some(path), ..) => CostSource::File {
            path: path.clone(),
            delimiter: args.delimiter.map(|d| d.byte()),
        },
        (None, None, Some(robots), Some(tasks)) => CostSource::Random {
            robots,
            tasks,
            model: args.cost_model,
        },
        _ => CostSource::Missing,
    };
    Ok(SolveRequest {
        costs,
        forbidden: args.forbidden.clone(),
        maximize: args.maximize,
        case: args.case,
        seed: args.seed,
        topology: match given_input.graph {
            Some(graph) => TopologySource::Given(graph),
            None => TopologySource::Named(args.topology.clone()),
        },
        options: options_of(args, &given)?,
        timeline: args.timeline.clone(),
    })
}

/// The solve options the user gave (`given`).
fn options_of(args: &SolveArgs, given: &dyn Fn(&str) -> bool) -> Result<SolveOptionsBuilder> {
    let mut options = SolveOptions::builder()
        .method(args.method)
        .settings(args.settings.0.clone())
        .transport(args.transport)
        .check(args.check)
        .agent_program(agent_program()?)
        .fault_injection(true);
    if given("rho") {
        options = options.rho(parse_rho(&args.rho)?);
    }
    if given("adaptive_rho") {
        options = options.adaptive_rho(args.adaptive_rho);
    }
    if given("max_iters") {
        options = options.max_iters(args.max_iters);
    }
    if given("stop") {
        options = options.stop(args.stop);
    }
    if given("stop_rounds") {
        options = options.stop_rounds(args.stop_rounds);
    }
    if given("perturb") {
        options = options.perturbation(parse_perturb(&args.perturb)?);
    }
    if given("trace") {
        options = options.trace(args.trace);
    }
    if given("global_barrier") {
        options = options.global_barrier(args.global_barrier);
    }
    if given("round_timeout") {
        options = options.round_timeout_secs(args.round_timeout);
    }
    if given("startup_timeout") {
        options = options.startup_timeout_secs(args.startup_timeout);
    }
    if given("on_failure") {
        options = options.on_failure(args.on_failure);
    }
    if given("wait") {
        options = options.wait(args.wait);
    }
    Ok(options)
}
