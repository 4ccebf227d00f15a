//! `admm-ta solve`: a problem from a CSV or random costs, solved as the flags say.

use crate::agents::problem::{cost_file, forbidden, read_cost_text};
use crate::command_line::cli::SolveArgs;
use crate::command_line::commands::shared::agent_program;
use crate::command_line::exit::{Outcome, UsageError};
use crate::command_line::output;
use crate::{
    CostMatrix, Graph, Perturbation, SolveOptions, SolveReport, TaskAssignmentProblem, TopologySpec,
};
use anyhow::{Context, Result};
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
    // Only the options the user gave are set: an option given that the run never reads
    // is refused by the options' own rule (`refuse_unread`), as for team files.
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
    if args.costs.as_deref() == Some(std::path::Path::new("-"))
        && args.forbidden.as_deref() == Some(std::path::Path::new("-"))
    {
        return Err(UsageError(
            "--costs - and --forbidden - cannot both read standard input".into(),
        )
        .into());
    }
    // Pairs the cost file itself marks forbidden (JSON nulls).
    let mut marked = Vec::new();
    let costs = match (&args.costs, args.robots, args.tasks) {
        _ if given_input.costs.is_some() => given_input.costs.expect("checked above"),
        (Some(path), _, _) => {
            let file = cost_file::parse(&read_cost_text(path)?, args.delimiter.map(|d| d.byte()))?;
            marked = file.forbidden;
            file.costs
        }
        (None, Some(robots), Some(tasks)) => args.cost_model.costs(robots, tasks, args.seed)?,
        _ => {
            return Err(UsageError(
                "give the costs with --costs FILE.csv, or --robots N --tasks M for random costs"
                    .into(),
            )
            .into());
        }
    };
    if let Some(path) = &args.forbidden {
        marked.extend(forbidden::read(path, &costs)?);
    }
    let costs = if marked.is_empty() {
        costs
    } else {
        forbidden::apply(&costs, &marked, args.maximize)?
    };
    let problem = if args.maximize {
        TaskAssignmentProblem::maximizing(costs, args.case)?
    } else {
        TaskAssignmentProblem::new(costs, args.case)?
    };
    let graph = match given_input.graph {
        Some(graph) if graph.robots() != problem.robots() => {
            return Err(UsageError(format!(
                "the graph has {} robots but the costs have {}",
                graph.robots(),
                problem.robots()
            ))
            .into());
        }
        Some(graph) => {
            // Assumption 1 of the paper, as every generated or file topology is checked.
            graph.require_connected()?;
            graph
        }
        None => {
            let spec: TopologySpec = args.topology.parse()?;
            spec.build_named(problem.robots(), args.seed, problem.costs().robot_names())
                .with_context(|| format!("topology '{}'", args.topology))?
        }
    };
    let mut options = SolveOptions::builder()
        .refuse_unread(true)
        .method(args.method)
        .settings(args.settings.0.clone())
        .transport(args.transport)
        .seed(args.seed)
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
    if args.timeline.is_some() {
        options = options.timeline(true);
    }
    let options = options.build()?;
    if let Some(path) = &args.timeline {
        // Refused before the run if it cannot be written.
        std::fs::File::create(path)
            .map_err(|e| UsageError(format!("--timeline {}: {e}", path.display())))?;
    }
    let report = crate::solve(&problem, &graph, &options)?;
    if let Some(path) = &args.timeline {
        let trace = crate::runtime::timeline::chrome_trace(&graph, &report.timeline);
        std::fs::write(path, serde_json::to_vec(&trace)?)
            .with_context(|| format!("--timeline {}", path.display()))?;
    }
    Ok(report)
}

/// `auto`, `off` (or 0) or a positive number ε.
fn parse_perturb(text: &str) -> Result<Perturbation> {
    match text {
        "auto" => Ok(Perturbation::Auto),
        "off" | "0" => Ok(Perturbation::Off),
        value => match value.parse::<f64>() {
            Ok(eps) if eps > 0.0 && eps.is_finite() => Ok(Perturbation::Fixed(eps)),
            _ => Err(UsageError(format!(
                "--perturb must be auto, off or a positive number, got '{value}'"
            ))
            .into()),
        },
    }
}

/// `auto` (None) or a number (the options check that it is a positive one).
fn parse_rho(text: &str) -> Result<Option<f64>> {
    if text == "auto" {
        return Ok(None);
    }
    match text.parse::<f64>() {
        Ok(rho) => Ok(Some(rho)),
        Err(_) => Err(UsageError(format!(
            "--rho (ρ) must be auto or a positive number, got '{text}'"
        ))
        .into()),
    }
}
