//! `admm-ta solve`: a problem from a CSV or random costs, solved as the flags say.

use crate::cli::SolveArgs;
use crate::commands::shared::agent_program;
use crate::exit::{Outcome, UsageError};
use crate::output;
use admm_ta::agents::forbidden;
use admm_ta::runtime::options::error::{MethodOptions, method_options};
use admm_ta::{CostMatrix, Perturbation, SolveOptions, TaskAssignmentProblem, TopologySpec};
use anyhow::{Context, Result};

pub fn run(args: SolveArgs) -> Result<Outcome> {
    let costs = match (&args.costs, args.robots, args.tasks) {
        (Some(path), _, _) => CostMatrix::read_csv(path)?,
        (None, Some(robots), Some(tasks)) => args.cost_model.costs(robots, tasks, args.seed)?,
        _ => {
            return Err(UsageError(
                "give the costs with --costs FILE.csv, or --robots N --tasks M for random costs"
                    .into(),
            )
            .into());
        }
    };
    let costs = match &args.forbidden {
        Some(path) => {
            let pairs = forbidden::read(path, costs.robots(), costs.tasks())?;
            forbidden::apply(&costs, &pairs, args.maximize)?
        }
        None => costs,
    };
    let problem = if args.maximize {
        TaskAssignmentProblem::maximizing(costs, args.case)?
    } else {
        TaskAssignmentProblem::new(costs, args.case)?
    };
    let spec: TopologySpec = args.topology.parse()?;
    let graph = spec
        .build(problem.robots(), args.seed)
        .with_context(|| format!("topology '{}'", args.topology))?;
    let perturbation = match args.perturb.as_str() {
        "auto" => Perturbation::Auto,
        "off" | "0" => Perturbation::Off,
        value => match value.parse::<f64>() {
            Ok(eps) if eps > 0.0 && eps.is_finite() => Perturbation::Fixed(eps),
            _ => {
                return Err(UsageError(format!(
                    "--perturb must be auto, off or a positive number, got '{value}'"
                ))
                .into());
            }
        },
    };
    // An option the method never reads is refused, not silently ignored.
    method_options(
        args.method,
        MethodOptions {
            adaptive_rho: args.adaptive_rho,
            gamma_factor: args.gamma_factor,
            projection: args.projection,
            primal_variant: args.primal_variant,
        },
    )?;
    let options = SolveOptions::builder()
        .method(args.method)
        .transport(args.transport)
        .rho(parse_rho(&args.rho)?)
        .adaptive_rho(args.adaptive_rho)
        .primal_variant(args.primal_variant)
        .gamma_factor(args.gamma_factor)
        .max_iters(args.max_iters)
        .stop(args.stop)
        .stop_rounds(args.stop_rounds)
        .seed(args.seed)
        .perturbation(perturbation)
        .projection(args.projection)
        .check(args.check)
        .trace(args.trace)
        .global_barrier(args.global_barrier)
        .round_timeout_secs(args.round_timeout)
        .startup_timeout_secs(args.startup_timeout)
        .agent_program(agent_program()?)
        .on_failure(args.on_failure)
        .fault_injection(true)
        .wait(args.wait)
        .build()?;
    let report = admm_ta::solve(&problem, &graph, &options)?;
    output::print_report(&report, args.json)?;
    Ok(Outcome::of(&report))
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
