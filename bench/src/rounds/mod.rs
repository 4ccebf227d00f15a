//! The consensus-round latency harness (`admm-ta bench rounds`): teams of agents exchange
//! payloads for a fixed number of rounds after a warm-up, on every transport in **one run**
//! (so the ratios are comparable on a shared machine), sweeping team size, topology,
//! payload size, wait strategy and barrier kind.
//!
//! Per case it reports percentiles (p50/p90/p99/p99.9/max) over every agent's recorded
//! rounds of the round time and of the exchange overhead (round time minus compute), the
//! CPU time and context switches per agent-round (`getrusage(RUSAGE_THREAD)`), and start-up.
//! Outputs: a Markdown table on stdout, `rounds.json`, `rounds.csv` and SVG plots of latency
//! versus team size and versus payload size per transport.
//!
//! The default sweep varies one axis at a time around a baseline (10 agents, complete
//! graph, 10×10 payload, default wait, neighbour barrier); giving any axis on the command
//! line sweeps the cross product of the given lists instead (the baseline for the others).
//!
//! [`case`]: what a case is and which cases a sweep has; [`report`]: the results and their
//! tables, CSV and plots; here: measuring a case and running a sweep.

pub mod case;
pub mod overhead;
pub mod report;

use crate::rounds::case::{Case, RoundsConfig, StepKind, cases};
use crate::rounds::report::{CaseFailure, CaseResult, RoundsReport};
use admm_ta_agents::methods::probe::ProbeStep;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::error::ConfigError;
use admm_ta_runtime::options::run::RunOptions;
use admm_ta_runtime::options::{SolveOptions, StopRule};
use admm_ta_runtime::probe_run::{ProbeRun, run_probe};
use admm_ta_runtime::runner::RunError;
use admm_ta_runtime::solve::error::SolveError;
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::{Graph, TopologySpec};
use admm_ta_transport::error_text::one_line;
use admm_ta_transport::latency::LatencySummary;
use admm_ta_transport::timeline::{RoundStamp, chrome_trace, critical_path};
use admm_ta_transport::usage::ThreadUsage;
use std::path::Path;

/// Why a case could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum MeasureError {
    #[error("{0}")]
    Case(String),
    #[error(transparent)]
    Options(#[from] ConfigError),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// Measures one case.
pub fn measure(case: &Case, config: &RoundsConfig) -> Result<CaseResult, MeasureError> {
    let bad = |e: &dyn std::fmt::Display| MeasureError::Case(e.to_string());
    let graph = case
        .topology
        .parse::<TopologySpec>()
        .map_err(|e| bad(&e))?
        .build(case.agents, 0)
        .map_err(|e| bad(&e))?;
    let total_rounds = config
        .rounds
        .checked_add(config.warmup)
        .ok_or_else(|| MeasureError::Case("recorded plus warm-up rounds overflow".into()))?;
    let measured = match case.step {
        StepKind::Touch | StepKind::Average => probe(case, config, &graph, total_rounds)?,
        StepKind::Primal => primal(case, config, &graph, total_rounds)?,
    };
    Ok(result_of(case, config, &graph, measured))
}

/// What a case's run measured: round latency, CPU use, start-up (ms), wall time and the
/// agents' round stamps.
type Measured = (
    LatencySummary,
    ThreadUsage,
    Option<f64>,
    std::time::Duration,
    Vec<Vec<RoundStamp>>,
);

/// A probe step's case (touch or average the payload): rounds of exchange only.
fn probe(
    case: &Case,
    config: &RoundsConfig,
    graph: &Graph,
    total_rounds: u64,
) -> Result<Measured, MeasureError> {
    let options = RunOptions::builder()
        .transport(case.transport)
        .wait(case.wait)
        .global_barrier(case.global_barrier)
        .warmup_rounds(config.warmup)
        .round_timeout(config.round_timeout)
        .agent_program(config.agent_program.clone())
        .timeline(config.timeline)
        .build()?;
    let step = if case.step == StepKind::Touch {
        ProbeStep::Touch
    } else {
        ProbeStep::Average
    };
    let run = ProbeRun {
        rounds: total_rounds,
        ..ProbeRun::new(case.payload.values(), step, options)
    };
    let r = run_probe(graph, &run)?;
    Ok((
        r.latency,
        r.usage,
        r.startup.map(|d| d.as_secs_f64() * 1e3),
        r.wall,
        r.timeline,
    ))
}

/// The primal step's case: the primal method run to its round limit on a uniform n × n problem.
fn primal(
    case: &Case,
    config: &RoundsConfig,
    graph: &Graph,
    total_rounds: u64,
) -> Result<Measured, MeasureError> {
    let bad = |e: &dyn std::fmt::Display| MeasureError::Case(e.to_string());
    let n = case.agents;
    let problem = TaskAssignmentProblem::new(
        CostMatrix::uniform(n, n, 1).map_err(|e| bad(&e))?,
        CaseChoice::Auto,
    )
    .map_err(|e| bad(&e))?;
    let started = std::time::Instant::now();
    let options = SolveOptions::builder()
        .transport(case.transport)
        .stop(StopRule::MaxIters)
        .max_iters(total_rounds as usize)
        .warmup_rounds(config.warmup)
        .wait(case.wait)
        .global_barrier(case.global_barrier)
        .round_timeout(config.round_timeout)
        .agent_program(config.agent_program.clone())
        .fault_injection(false)
        .timeline(config.timeline)
        .build()?;
    let report = solve(&problem, graph, &options)?;
    Ok((
        report.round_latency_us.unwrap_or_default(),
        report.agent_usage.unwrap_or_default(),
        report.startup_ms,
        started.elapsed(),
        report.timeline,
    ))
}

/// The case's row: per-round figures from what its run measured.
fn result_of(case: &Case, config: &RoundsConfig, graph: &Graph, measured: Measured) -> CaseResult {
    let (latency, usage, startup, wall, timeline) = measured;
    let recorded = latency.round.count.max(1);
    let per_round = |v: u64| v as f64 / recorded as f64;
    // Samples an agent receives per round, on average: its degree.
    let mean_degree = (0..graph.robots()).map(|i| graph.degree(i)).sum::<usize>() as f64
        / graph.robots().max(1) as f64;
    CaseResult {
        case: case.clone(),
        payload_bytes: case.payload.values() * 8,
        recorded: latency.round.count,
        round_us: latency.round.into(),
        overhead_us: latency.overhead.into(),
        compute_p50_us: latency.compute.p50,
        wait_p50_us: latency.wait.p50,
        publish_p50_us: latency.publish.p50,
        barrier_p50_us: latency.barrier.p50,
        cpu_us_per_round: per_round(usage.cpu_ns) / 1e3,
        cpu_us_per_sample: per_round(usage.cpu_ns) / 1e3 / mean_degree.max(1.0),
        voluntary_switches_per_round: per_round(usage.voluntary_switches),
        involuntary_switches_per_round: per_round(usage.involuntary_switches),
        startup_ms: startup,
        wall_ms: wall.as_secs_f64() * 1e3,
        repeats: 1,
        round_p50_range_us: (latency.round.p50, latency.round.p50),
        // Over the recorded rounds, as the latencies are (the trace shows the warm-up too).
        critical_path: (config.timeline && !timeline.is_empty()).then(|| {
            let recorded: Vec<Vec<RoundStamp>> = timeline
                .iter()
                .map(|t| t[(config.warmup as usize).min(t.len())..].to_vec())
                .collect();
            critical_path(graph, &recorded)
        }),
        trace: None,
        timeline: if config.traces.is_some() {
            timeline
        } else {
            Vec::new()
        },
    }
}

/// Writes `result`'s trace into `dir` (named by its case) and lets go of its stamps.
fn write_trace(result: &mut CaseResult, dir: &Path) -> Result<(), String> {
    let case = &result.case;
    let graph = case
        .topology
        .parse::<TopologySpec>()
        .map_err(|e| e.to_string())?
        .build(case.agents, 0)
        .map_err(|e| e.to_string())?;
    let path = dir.join(format!("{}.json", case.slug()));
    let trace = chrome_trace(&graph, &std::mem::take(&mut result.timeline));
    let bytes = serde_json::to_vec(&trace).map_err(|e| e.to_string())?;
    std::fs::write(&path, bytes)
        .map_err(|e| format!("cannot write the trace {}: {e}", path.display()))?;
    result.trace = Some(path);
    Ok(())
}

/// The repetition with the median round p50, carrying the spread of all of them.
fn median_of(mut repeats: Vec<CaseResult>) -> CaseResult {
    repeats.sort_by(|a, b| a.round_us.p50.total_cmp(&b.round_us.p50));
    let range = (
        repeats.first().map_or(0.0, |r| r.round_us.p50),
        repeats.last().map_or(0.0, |r| r.round_us.p50),
    );
    let count = repeats.len();
    let mut median = repeats.swap_remove(count / 2);
    median.repeats = count;
    median.round_p50_range_us = range;
    median
}

/// Runs every case of `config`; `progress` sees each result (or failure) as it comes. A
/// failing case is recorded and the sweep goes on.
pub fn run(
    config: &RoundsConfig,
    progress: &mut dyn FnMut(&Case, Result<&CaseResult, &str>),
) -> RoundsReport {
    let mut report = RoundsReport {
        cores: std::thread::available_parallelism().map_or(1, |c| c.get()),
        rounds: config.rounds,
        warmup: config.warmup,
        step: config.step,
        results: Vec::new(),
        failures: Vec::new(),
    };
    let cases = cases(config);
    // An unrecorded first run warms the binary, the page cache and the CPU clocks, so that
    // the first measured case is not an outlier.
    if let Some(first) = cases.first() {
        let warm = RoundsConfig {
            rounds: config.rounds.min(100),
            warmup: 0,
            ..config.clone()
        };
        let _ = measure(first, &warm);
    }
    // Configurations that differ only by transport are measured together, repetition by
    // repetition, so that every transport sees the same state of the machine.
    let mut start = 0;
    while start < cases.len() {
        let same = |c: &Case| {
            Case {
                transport: cases[start].transport,
                ..c.clone()
            } == cases[start]
        };
        let end = start + cases[start..].iter().take_while(|c| same(c)).count();
        let group = &cases[start..end];
        let mut measured: Vec<Result<Vec<CaseResult>, String>> =
            group.iter().map(|_| Ok(Vec::new())).collect();
        for _ in 0..config.repeat.max(1) {
            for (case, slot) in group.iter().zip(measured.iter_mut()) {
                if let Ok(results) = slot {
                    match measure(case, config) {
                        Ok(r) => results.push(r),
                        Err(e) => *slot = Err(one_line(&e)),
                    }
                }
            }
        }
        for (case, outcome) in group.iter().zip(measured) {
            match outcome {
                Ok(results) => {
                    let mut result = median_of(results);
                    let written = match &config.traces {
                        Some(dir) => write_trace(&mut result, dir),
                        None => Ok(()),
                    };
                    match written {
                        Ok(()) => {
                            progress(case, Ok(&result));
                            report.results.push(result);
                        }
                        Err(error) => {
                            progress(case, Err(&error));
                            report.failures.push(CaseFailure {
                                case: case.clone(),
                                error,
                            });
                        }
                    }
                }
                Err(error) => {
                    progress(case, Err(&error));
                    report.failures.push(CaseFailure {
                        case: case.clone(),
                        error,
                    });
                }
            }
        }
        start = end;
    }
    report
}
