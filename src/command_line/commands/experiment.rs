//! `admm-ta experiment NAME`: the paper's experiments and the comparisons beyond it. Each
//! runs into a report ([`admm_ta_bench::experiment::Experiment`]) that the one write path
//! puts into `--out`, then prints its table or its JSON.

use crate::Method;
use crate::agents::problem::surveillance::SurveillanceMission;
use crate::command_line::cli::{
    CompareArgs, Experiment as Command, FigureArgs, RoundsAnatomyArgs, SizeSweepArgs,
    SurveillanceArgs, Table1Args,
};
use crate::command_line::commands::shared::{agent_program, progress_bar};
use crate::command_line::exit::{NotOptimal, UsageError, usage_bail};
use crate::command_line::output::{out, outln, progress_row};
use crate::runtime::options::run::RunOptions;
use crate::runtime::surveillance::EpisodeRunConfig;
use crate::transport::{Execution, Transport};
use admm_ta_bench::experiment::{Experiment, write};
use admm_ta_bench::figures::{FigureConfig, convergence, scaling};
use admm_ta_bench::{compare, rounds_anatomy, size_sweep, surveillance, table1};
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Duration;

pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Compare(args) => run_compare(args),
        Command::Fig1Convergence { figure } => run_figure(
            figure,
            |_| {},
            |_| 0,
            |config, bar| {
                convergence::fig1_convergence(config, &|m| bar.set_message(m.to_string()))
            },
        ),
        Command::Fig1Topologies { figure } => run_figure(
            figure,
            |_| {},
            |_| 0,
            |config, bar| convergence::fig1_topologies(config, &|m| bar.set_message(m.to_string())),
        ),
        Command::Fig2Scaling {
            figure,
            sizes,
            decentralized_up_to,
        } => {
            check_sizes(&sizes)?;
            run_figure(
                figure,
                |c| {
                    c.sizes = sizes;
                    c.decentralized_up_to = decentralized_up_to;
                },
                scaling::fig2_points,
                |config, bar| {
                    scaling::fig2_scaling(config, &|p| {
                        bar.inc(1);
                        bar.set_message(format!("{} {} robots {}", p.topology, p.robots, p.series));
                    })
                },
            )
        }
        Command::IpcScaling { figure, sizes } => {
            check_sizes(&sizes)?;
            run_figure(
                figure,
                |c| c.sizes = sizes,
                |c| c.sizes.len() * scaling::ipc_methods().count(),
                |config, bar| {
                    scaling::ipc_scaling(config, &|p| {
                        bar.inc(1);
                        bar.set_message(format!("{} robots {}", p.robots, p.method.name()));
                    })
                },
            )
        }
        Command::Surveillance(args) => run_surveillance(args),
        Command::RoundsAnatomy(args) => run_rounds_anatomy(args),
        Command::SizeSweep(args) => run_size_sweep(args),
        Command::Table1(args) => run_table1(args),
    }
}

fn run_compare(args: CompareArgs) -> Result<()> {
    let CompareArgs {
        robots,
        seeds,
        methods,
        transports,
        topology,
        cost_model,
        settings,
        adaptive_rho,
        max_iters,
        out,
    } = args;
    if seeds == 0 || max_iters == 0 || robots.contains(&0) {
        usage_bail!("--seeds, --max-iters and every --robots size must be at least 1");
    }
    let methods = if methods.is_empty() {
        Method::ALL.to_vec()
    } else {
        methods
    };
    let spec: crate::TopologySpec = topology.parse()?;
    // Every team's graph now: a bad generator or topology file exits 2 before a run.
    for &n in &robots {
        for seed in 0..seeds {
            spec.build(n, seed)
                .with_context(|| format!("--topology '{topology}' with {n} robots"))?;
        }
    }
    let runs = |m: &Method, t: &Transport| {
        m.team().is_some() || t.capabilities().execution == Execution::Lockstep
    };
    if !methods
        .iter()
        .any(|m| transports.iter().any(|t| runs(m, t)))
    {
        usage_bail!(
            "no method of --methods runs on --transports: a centralized method ({}) runs on {} only",
            Method::names_where(|i| i.team.is_none(), "or"),
            Transport::names_where(|c| c.execution == Execution::Lockstep, "or")
        );
    }
    let config = compare::CompareConfig {
        robots,
        seeds,
        methods,
        transports,
        topology: spec,
        cost_model,
        settings: settings.0,
        adaptive_rho,
        max_iters,
        agent_program: Some(agent_program()?),
    };
    // The rows are printed as they come; the whole table is the report's.
    outln!("{}", compare::TABLE_HEADER);
    let comparison = compare::run(&config, &|row| progress_row(&compare::render_row(row)))?;
    if let Some(dir) = out {
        report_written(&write(&comparison, &dir)?);
    }
    Ok(())
}

fn run_surveillance(args: SurveillanceArgs) -> Result<()> {
    let SurveillanceArgs {
        episodes,
        mission,
        transport,
        cold_start,
        max_iters,
        out,
        json,
        timeline,
    } = args;
    if episodes == 0 || max_iters == 0 {
        usage_bail!("--episodes and --max-iters must be at least 1");
    }
    let model = match &mission {
        Some(path) => {
            // A mission that cannot be read or is not one: bad input (exit 2).
            let text = std::fs::read_to_string(path)
                .map_err(|e| UsageError(format!("cannot read {}: {e}", path.display())))?;
            SurveillanceMission::from_toml(&text)
                .map_err(|e| UsageError(format!("{}: {e:#}", path.display())))?
        }
        None => SurveillanceMission::default(),
    };
    if transport.capabilities().execution == Execution::Lockstep {
        usage_bail!("--transport: the team runs on threads, shm, ipc or uds");
    }
    if let Some(path) = &timeline {
        // Refused now, not after the episodes ran.
        std::fs::write(path, b"")
            .map_err(|e| UsageError(format!("--timeline {}: {e}", path.display())))?;
    }
    let config = EpisodeRunConfig {
        max_rounds: max_iters,
        options: RunOptions::builder()
            .transport(transport)
            .agent_program(agent_program()?)
            .timeline(timeline.is_some())
            .build()?,
    };
    let bar = progress_bar(
        episodes as u64,
        "{bar:30} {pos}/{len} cold-start comparisons, {elapsed} elapsed, ~{eta} left",
    );
    bar.set_message("team running");
    let report = surveillance::run(model, episodes, !cold_start, &config, &|done| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let report = report?;
    if let Some(path) = &timeline {
        let trace = surveillance::trace(&report).context("the agents recorded no timeline")?;
        std::fs::write(path, serde_json::to_vec(&trace)?)
            .with_context(|| format!("--timeline {}", path.display()))?;
    }
    let written = write(&report, &out)?;
    if json {
        let mut value = serde_json::to_value(&report)?;
        // The per-episode detail is in surveillance.json; stdout stays one object.
        if let Some(map) = value.as_object_mut() {
            map.remove("per_episode");
        }
        outln!("{value}");
    } else {
        out!("{}", report.render());
    }
    report_written(&written);
    Ok(())
}

fn run_rounds_anatomy(args: RoundsAnatomyArgs) -> Result<()> {
    let RoundsAnatomyArgs {
        quick,
        seeds,
        out,
        json,
    } = args;
    let mut config = if quick {
        rounds_anatomy::AnatomyConfig::quick()
    } else {
        rounds_anatomy::AnatomyConfig::full()
    };
    if let Some(seeds) = seeds {
        if seeds == 0 {
            usage_bail!("--seeds must be at least 1");
        }
        config.seeds = seeds;
    }
    let progress = |done: usize, total: usize| {
        if !json {
            eprint!("\rrounds-anatomy: {done}/{total} runs");
            if done == total {
                eprintln!();
            }
        }
    };
    let anatomy = rounds_anatomy::run(&config, &progress)?;
    let written = write(&anatomy, &out)?;
    if json {
        outln!("{}", serde_json::to_string_pretty(&anatomy)?);
    } else {
        report_written(&written);
        out!("{}", anatomy.render());
    }
    Ok(())
}

fn run_size_sweep(args: SizeSweepArgs) -> Result<()> {
    let SizeSweepArgs {
        quick,
        sizes,
        seeds,
        topologies,
        out,
    } = args;
    let mut config = if quick {
        size_sweep::SweepConfig::quick()
    } else {
        size_sweep::SweepConfig::full()
    };
    if sizes.contains(&0) || seeds == Some(0) {
        usage_bail!("--sizes and --seeds must be at least 1");
    }
    if !sizes.is_empty() {
        config.sizes = sizes;
    }
    if !topologies.is_empty() {
        for t in &topologies {
            t.parse::<crate::TopologySpec>()
                .with_context(|| format!("--topologies: {t}"))?;
        }
        config.topologies = topologies;
    }
    config.seeds = seeds.unwrap_or(config.seeds);
    let progress = |size: usize, done: usize, total: usize| {
        eprint!("\rsize-sweep: {size}×{size}, {done}/{total} runs");
        if done == total {
            eprintln!();
        }
    };
    let sweep = size_sweep::run(&config, &progress)?;
    let written = write(&sweep, &out)?;
    report_written(&written);
    out!("{}", sweep.render());
    if !sweep.all_certified_optimal() {
        return Err(NotOptimal("some run did not certify the optimal assignment".into()).into());
    }
    Ok(())
}

fn run_table1(args: Table1Args) -> Result<()> {
    let Table1Args {
        trials,
        out,
        adaptive_rho,
        rho_scale,
        max_iters,
        json,
    } = args;
    if trials == 0 || max_iters == 0 {
        usage_bail!("--trials and --max-iters must be at least 1");
    }
    if !(rho_scale > 0.0 && rho_scale.is_finite()) {
        usage_bail!("--rho-scale must be a positive number, got {rho_scale}");
    }
    let config = table1::Table1Config {
        trials,
        adaptive_rho,
        rho_scale,
        max_iters,
        ..table1::Table1Config::default()
    };
    let progress = |done: usize, total: usize| {
        if !json {
            eprint!("\rtable1: {done}/{total} runs");
            if done == total {
                eprintln!();
            }
        }
    };
    let table = table1::run(&config, &progress)?;
    if let Some(dir) = out {
        let written = write(&table, &dir)?;
        if !json {
            report_written(&written);
        }
    }
    if json {
        outln!("{}", serde_json::to_string_pretty(&table)?);
    } else {
        out!("{}", table.render());
    }
    Ok(())
}

fn check_sizes(sizes: &[usize]) -> Result<()> {
    if sizes.is_empty() || sizes.iter().any(|n| !(2..=500).contains(n)) {
        usage_bail!("--sizes: every team size must be 2…500");
    }
    Ok(())
}

/// Runs a figure experiment: its settings from `args` adjusted by `adjust`, a progress bar of
/// `steps(settings)` steps (a spinner when 0); writes the report into `--out`, prints its
/// table or its JSON, and names the files written.
fn run_figure<R: Experiment, E: std::error::Error + Send + Sync + 'static>(
    args: FigureArgs,
    adjust: impl FnOnce(&mut FigureConfig),
    steps: impl FnOnce(&FigureConfig) -> usize,
    body: impl FnOnce(&FigureConfig, &indicatif::ProgressBar) -> Result<R, E>,
) -> Result<()> {
    if args.trials == 0 || args.max_iters == 0 {
        usage_bail!("--trials and --max-iters must be at least 1");
    }
    let mut config = FigureConfig {
        trials: args.trials,
        adaptive_rho: args.adaptive_rho,
        max_iters: args.max_iters,
        agent_program: Some(agent_program()?),
        ..FigureConfig::default()
    };
    adjust(&mut config);
    let steps = steps(&config);
    let bar = if steps > 0 {
        progress_bar(
            steps as u64,
            "{bar:30} {pos}/{len}, {elapsed} elapsed, ~{eta} left  {msg}",
        )
    } else {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(Duration::from_millis(200));
        bar
    };
    let result = body(&config, &bar);
    bar.finish_and_clear();
    let report = result?;
    let written = write(&report, &args.out)?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        out!("{}", report.render());
    }
    report_written(&written);
    Ok(())
}

/// Names the files an experiment wrote (on stderr: stdout holds its table or JSON).
pub fn report_written(paths: &[impl AsRef<Path>]) {
    for path in paths {
        eprintln!("wrote {}", path.as_ref().display());
    }
}
