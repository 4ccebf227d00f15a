//! `admm-ta solve`: a problem from a CSV or random costs, solved as the flags say.

use crate::command_line::cli::SolveArgs;
use crate::command_line::commands::shared::agent_program;
use crate::command_line::exit::{Outcome, UsageError};
use crate::command_line::output;
use crate::request::{CostSource, GivenOptions, SolveRequest, TopologySource};
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
    let options = SolveOptions::builder()
        .method(args.method)
        .settings(args.settings.0.clone())
        .transport(args.transport)
        .check(args.check)
        .agent_program(agent_program()?)
        .fault_injection(true);
    let chosen = GivenOptions {
        rho: given("rho").then(|| args.rho.clone()),
        adaptive_rho: given("adaptive_rho").then_some(args.adaptive_rho),
        max_iters: given("max_iters").then_some(args.max_iters),
        stop: given("stop").then_some(args.stop),
        stop_rounds: given("stop_rounds").then_some(args.stop_rounds),
        perturb: given("perturb").then(|| args.perturb.clone()),
        trace: given("trace").then_some(args.trace),
        global_barrier: given("global_barrier").then_some(args.global_barrier),
        round_timeout: given("round_timeout").then_some(args.round_timeout),
        startup_timeout: given("startup_timeout").then_some(args.startup_timeout),
        on_failure: given("on_failure").then_some(args.on_failure),
        wait: given("wait").then_some(args.wait),
    };
    Ok(chosen.apply(options)?)
}
