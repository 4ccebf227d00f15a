//! `admm-ta bench rounds`: the round-latency sweep's arguments checked, its progress shown,
//! its tables printed and its files written.

use crate::TopologySpec;
use crate::command_line::cli::{Bench, RoundsArgs};
use crate::command_line::commands::experiment::report_written;
use crate::command_line::commands::shared::{agent_program, progress_bar, writable_dir};
use crate::command_line::exit::{RunsFailed, UsageError, usage_bail};
use crate::command_line::output::{out, outln, progress_row};
use crate::transport::{Capabilities, Execution, Transport};
use admm_ta_bench::experiment::{Experiment, write};
use admm_ta_bench::rounds;
use admm_ta_bench::rounds::case::{RoundsConfig, SweepSpec, cases};
use admm_ta_bench::rounds::overhead;
use admm_ta_bench::rounds::report::{TABLE_HEADER, render_row};
use anyhow::{Context, Result};

/// The most rounds (recorded, or of warm-up) of a case: ten million rounds of a few
/// microseconds each already take minutes per case.
const MAX_ROUNDS: u64 = 10_000_000;

/// Whether a transport's agents run concurrently (round latency means nothing otherwise).
fn concurrent(c: Capabilities) -> bool {
    c.execution != Execution::Lockstep
}

pub fn run(bench: Bench) -> Result<()> {
    let Bench::Rounds(args) = bench;
    let (out, json, timeline_overhead) = (args.out.clone(), args.json, args.timeline_overhead);
    let config = config_of(args)?;
    let cases = cases(&config);
    if cases.is_empty() {
        usage_bail!(
            "no case to measure (a global barrier needs --transports {})",
            Transport::names_where(|c| c.global_barrier && concurrent(c), "or")
        );
    }
    let bar = progress_bar(
        cases.len() as u64,
        "{bar:30} {pos}/{len} cases, {elapsed} elapsed, ~{eta} left  {msg}",
    );
    if timeline_overhead {
        return measure_overhead(&config, &bar);
    }
    sweep(&config, &bar, &out, json)
}

/// The sweep's settings from its arguments, each checked: bad ones exit 2 before a case runs.
fn config_of(args: RoundsArgs) -> Result<RoundsConfig> {
    let RoundsArgs {
        quick,
        agents,
        topologies,
        payloads,
        transports,
        waits,
        barriers,
        step,
        rounds: recorded,
        warmup,
        repeat,
        out,
        json: _,
        timeline,
        timeline_overhead: _,
    } = args;
    if agents.as_ref().is_some_and(|a| a.contains(&0)) {
        usage_bail!("--agents: every team needs at least 1 agent");
    }
    if let Some(t) = &topologies {
        // Every team size of the sweep (or one of two agents): a generator's parameters are
        // checked when it builds a graph.
        let sizes = agents.as_deref().unwrap_or(&[2]);
        for topology in t {
            let spec = topology
                .parse::<TopologySpec>()
                .with_context(|| format!("--topologies '{topology}'"))?;
            for &n in sizes {
                spec.build(n, 0)
                    .with_context(|| format!("--topologies '{topology}' with {n} agents"))?;
            }
        }
    }
    let payloads = payloads
        .map(|list| {
            list.iter()
                .map(|p| {
                    p.parse()
                        .map_err(|e| UsageError(format!("--payloads: {e}")))
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .transpose()?;
    if transports
        .as_ref()
        .is_some_and(|t| t.iter().any(|t| !concurrent(t.capabilities())))
    {
        usage_bail!(
            "--transports: round latency needs agents that run concurrently: {}",
            Transport::names_where(concurrent, "or")
        );
    }
    let mut config = RoundsConfig::new(quick);
    config.sweep = SweepSpec {
        agents,
        topologies,
        payloads,
        transports,
        waits,
        barriers,
    };
    config.step = step;
    config.rounds = recorded.unwrap_or(config.rounds);
    config.warmup = warmup.unwrap_or(config.warmup);
    if !(1..=100).contains(&repeat) {
        usage_bail!("--repeat must be 1…100, got {repeat}");
    }
    config.repeat = repeat;
    if !(1..=MAX_ROUNDS).contains(&config.rounds) {
        usage_bail!("--rounds must be 1…{MAX_ROUNDS}, got {}", config.rounds);
    }
    if config.warmup > MAX_ROUNDS {
        usage_bail!("--warmup must be 0…{MAX_ROUNDS}, got {}", config.warmup);
    }
    // Refused now, not after the whole sweep ran.
    writable_dir("--out", &out)?;
    if let Some(dir) = &timeline {
        writable_dir("--timeline", dir)?;
        config.timeline = true;
        config.traces = Some(dir.clone());
    }
    config.agent_program = Some(agent_program()?);
    Ok(config)
}

/// `--timeline-overhead`: every case with the timeline on and off in turn.
fn measure_overhead(config: &RoundsConfig, bar: &indicatif::ProgressBar) -> Result<()> {
    outln!(
        "--timeline on and off in turn, {} repetition(s) of {} recorded rounds after {} of warm-up, step {}; round latency in µs (medians)
",
        config.repeat,
        config.rounds,
        config.warmup,
        config.step.name()
    );
    outln!("{}", overhead::HEADER);
    let rows = overhead::timeline_overhead(config, &mut |case, row| {
        bar.inc(1);
        bar.suspend(|| match row {
            Ok(r) => progress_row(&r.render()),
            Err(e) => progress_row(&format!("{} failed: {e} |", case.columns())),
        });
    });
    bar.finish_and_clear();
    let failed = rows.iter().filter(|r| r.is_err()).count();
    if failed > 0 {
        return Err(RunsFailed(format!("{failed} of {} cases failed", rows.len())).into());
    }
    Ok(())
}

/// The sweep: its rows as they come, then its table or JSON and its files.
fn sweep(
    config: &RoundsConfig,
    bar: &indicatif::ProgressBar,
    out: &std::path::Path,
    json: bool,
) -> Result<()> {
    if !json {
        outln!(
            "{} recorded rounds per case after {} of warm-up, step {}; latencies in µs over all agents' rounds
",
            config.rounds,
            config.warmup,
            config.step.name()
        );
        outln!("{}", TABLE_HEADER);
    }
    let report = rounds::run(config, &mut |case, result| {
        bar.inc(1);
        bar.set_message(format!(
            "{} agents {} {} {}",
            case.agents,
            case.topology,
            case.payload,
            case.transport.name()
        ));
        if json {
            return;
        }
        bar.suspend(|| match result {
            Ok(r) => progress_row(&render_row(r)),
            Err(e) => progress_row(&format!("{} failed: {e} |", case.columns())),
        });
    });
    bar.finish_and_clear();
    let written = write(&report, out)?;
    if json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        out!("{}", report.render());
    }
    report_written(&written);
    if !report.failures.is_empty() {
        return Err(RunsFailed(format!(
            "{} of {} cases failed (see above and rounds.json)",
            report.failures.len(),
            report.failures.len() + report.results.len()
        ))
        .into());
    }
    Ok(())
}
