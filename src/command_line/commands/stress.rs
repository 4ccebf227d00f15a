//! `admm-ta stress`: many teams of agent processes at once, as a CI-stressing user runs them.
//! It starts `--runs` random problems (seeds `--seed`, `--seed + 1`, …), `--concurrency` at a
//! time, each solved by a team of `--robots` agent processes on `--transport`, and reports
//! the failures with their messages, the wall time, p50/p99 of a run's wall time, and what
//! the runs left behind: shared memory and run directories of its runs, and agent processes
//! still alive or unreaped. It exits non-zero on any failure or leftover.

use crate::command_line::commands::shared::{agent_program, progress_bar};
use crate::command_line::exit::{RunsFailed, usage_bail};
use crate::command_line::output::outln;
use crate::runtime::process::namespace::{run_id_prefix, runs_dir, shm_named};
use crate::{CaseChoice, CostMatrix, Method, SolveOptions, TaskAssignmentProblem, Transport};
use anyhow::{Context, Result, bail};
use clap::Args;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

#[derive(Args, Debug)]
pub struct StressArgs {
    /// Teams to run in all.
    #[arg(long, default_value_t = 100)]
    pub runs: usize,
    /// Teams running at the same time.
    #[arg(long, default_value_t = 4)]
    pub concurrency: usize,
    /// Agents (robots) per team.
    #[arg(long, default_value_t = 10)]
    pub robots: usize,
    /// Tasks per team (default: as many as robots).
    #[arg(long)]
    pub tasks: Option<usize>,
    /// ipc | uds | zenoh (a process transport).
    #[arg(long, value_enum, default_value = "ipc")]
    pub transport: Transport,
    #[arg(long, value_enum, default_value = "primal", help = Method::help())]
    pub method: Method,
    /// Communication topology of every team (as `solve --topology`).
    #[arg(long, default_value = "complete")]
    pub topology: String,
    /// Seed of the first run's costs and graph; run k uses seed + k.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Start-up deadline of every run (seconds).
    #[arg(long, default_value_t = 60.0)]
    pub startup_timeout: f64,
    /// Round deadline of every run (seconds).
    #[arg(long, default_value_t = 30.0)]
    pub round_timeout: f64,
    /// No progress bar (for logs).
    #[arg(long)]
    pub quiet: bool,
}

/// One run's outcome: its wall time, and its error if it failed.
type Outcome = (Duration, Option<String>);

pub fn run(args: StressArgs) -> Result<()> {
    if args.transport.capabilities().execution != crate::transport::Execution::Processes {
        usage_bail!(
            "stress runs teams of agent processes: use --transport shm, ipc, uds or zenoh (not {})",
            args.transport
        );
    }
    if args.runs == 0 || args.concurrency == 0 {
        usage_bail!("--runs and --concurrency must be at least 1");
    }
    // For the whole test, not only while a run's launcher lives: a signal between two runs
    // stops it too.
    let _signals = crate::transport::signals::install();
    if args.seed.checked_add(args.runs as u64 - 1).is_none() {
        usage_bail!(
            "--seed {} + --runs {} passes the largest seed, {}",
            args.seed,
            args.runs,
            u64::MAX
        );
    }
    let tasks = args.tasks.unwrap_or(args.robots);
    let spec: crate::TopologySpec = args.topology.parse()?;
    let program = agent_program()?;
    // Bad options exit 2 here, before any team starts, not as every run's failure.
    inputs(&args, tasks, &spec, &program, args.seed)?;
    let bar = progress_bar(
        args.runs as u64,
        "{elapsed_precise} [{bar:40}] {pos}/{len} runs {msg}",
    );
    if args.quiet {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let (outcomes, wall) = run_all(&args, tasks, &spec, &program, &bar);
    bar.finish_and_clear();
    summarize(&args, outcomes, wall)
}

/// The runs, `--concurrency` at a time until all ran or a signal came: each run's outcome by
/// its number, and the wall time.
fn run_all(
    args: &StressArgs,
    tasks: usize,
    spec: &crate::TopologySpec,
    program: &crate::runtime::options::run::AgentProgram,
    bar: &indicatif::ProgressBar,
) -> (Vec<(usize, Outcome)>, Duration) {
    let next = AtomicUsize::new(0);
    let failed = AtomicUsize::new(0);
    let outcomes: Mutex<Vec<(usize, Outcome)>> = Mutex::new(Vec::with_capacity(args.runs));
    let started = Instant::now();
    std::thread::scope(|scope| {
        for _ in 0..args.concurrency.min(args.runs) {
            scope.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    // A termination signal stops the stress test between runs too.
                    if k >= args.runs || crate::transport::signals::received().is_some() {
                        return;
                    }
                    let t0 = Instant::now();
                    let error = one_run(args, tasks, spec, program, k).err();
                    if error.is_some() {
                        failed.fetch_add(1, Ordering::Relaxed);
                    }
                    outcomes
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .push((k, (t0.elapsed(), error.map(|e| format!("{e:#}")))));
                    bar.set_message(format!("{} failed", failed.load(Ordering::Relaxed)));
                    bar.inc(1);
                }
            });
        }
    });
    let wall = started.elapsed();
    (
        outcomes.into_inner().unwrap_or_else(|e| e.into_inner()),
        wall,
    )
}

/// Prints the failures, what was left behind and the summary line; fails unless every run
/// succeeded and left nothing.
fn summarize(args: &StressArgs, mut outcomes: Vec<(usize, Outcome)>, wall: Duration) -> Result<()> {
    outcomes.sort_by_key(|(k, _)| *k);
    let mut times: Vec<Duration> = outcomes.iter().map(|(_, (t, _))| *t).collect();
    times.sort();
    // No run at all when a signal came first.
    let quantile = |q: f64| {
        let last = times.len().saturating_sub(1);
        times
            .get((last as f64 * q).round() as usize)
            .copied()
            .unwrap_or_default()
    };
    let failures: Vec<(usize, &String)> = outcomes
        .iter()
        .filter_map(|(k, (_, e))| e.as_ref().map(|e| (*k, e)))
        .collect();
    for (k, error) in &failures {
        outln!("run {k} (seed {}): {error}", args.seed + *k as u64);
    }
    let leftovers = leftovers();
    for left in &leftovers {
        outln!("left behind: {left}");
    }
    outln!(
        "{} runs of {} agents ({} transport, {} topology) at concurrency {}: {} failed, {} left behind; wall time {:.1?}, per run p50 {:.2?}, p99 {:.2?}, max {:.2?}",
        outcomes.len(),
        args.robots,
        args.transport,
        args.topology,
        args.concurrency,
        failures.len(),
        leftovers.len(),
        wall,
        quantile(0.5),
        quantile(0.99),
        times.last().copied().unwrap_or_default(),
    );
    if let Some(signal) = crate::transport::signals::received() {
        bail!(
            "stopped by {} after {} of {} runs",
            crate::transport::signals::name(signal),
            outcomes.len(),
            args.runs
        );
    }
    if !failures.is_empty() || !leftovers.is_empty() {
        return Err(RunsFailed(format!(
            "{} of {} runs failed, {} thing(s) left behind",
            failures.len(),
            outcomes.len(),
            leftovers.len()
        ))
        .into());
    }
    Ok(())
}

/// Run `k`: its own random problem and graph, solved by a team of agent processes.
fn one_run(
    args: &StressArgs,
    tasks: usize,
    spec: &crate::TopologySpec,
    program: &crate::runtime::options::run::AgentProgram,
    k: usize,
) -> Result<()> {
    let (problem, graph, options) = inputs(args, tasks, spec, program, args.seed + k as u64)?;
    crate::solve(&problem, &graph, &options)?;
    Ok(())
}

/// The problem, graph and options of the run with `seed`.
fn inputs(
    args: &StressArgs,
    tasks: usize,
    spec: &crate::TopologySpec,
    program: &crate::runtime::options::run::AgentProgram,
    seed: u64,
) -> Result<(TaskAssignmentProblem, crate::Graph, SolveOptions)> {
    let costs = CostMatrix::uniform(args.robots, tasks, seed)?;
    let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto)?;
    let graph = spec
        .build(args.robots, seed)
        .with_context(|| format!("topology '{}'", args.topology))?;
    let options = SolveOptions::builder()
        .method(args.method)
        .transport(args.transport)
        .seed(seed)
        .round_timeout_secs(args.round_timeout)
        .startup_timeout_secs(args.startup_timeout)
        .agent_program(program.clone())
        .build()?;
    Ok((problem, graph, options))
}

/// What this process's runs left behind: shared memory and run directories named after
/// it, and agent processes (its children, alive or unreaped; or orphans of its runs).
fn leftovers() -> Vec<String> {
    let me = std::process::id();
    let prefix = run_id_prefix(me);
    let mut found: Vec<String> = shm_named(&format!("adta{prefix}"))
        .into_iter()
        .map(|p| p.display().to_string())
        .collect();
    if let Ok(entries) = std::fs::read_dir(runs_dir()) {
        found.extend(
            entries
                .flatten()
                .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
                .map(|e| e.path().display().to_string()),
        );
    }
    let Ok(procs) = std::fs::read_dir("/proc") else {
        return found;
    };
    for entry in procs.flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        let after = &stat[stat.rfind(')').map_or(0, |i| i + 1)..];
        let mut fields = after.split_whitespace();
        let state = fields.next().unwrap_or("");
        let ppid: u32 = fields.next().and_then(|p| p.parse().ok()).unwrap_or(0);
        let cmdline = std::fs::read(format!("/proc/{pid}/cmdline"))
            .map(|c| String::from_utf8_lossy(&c).replace('\0', " "))
            .unwrap_or_default();
        let ours = cmdline.contains(&format!("--run {prefix}"));
        if ppid == me || ours {
            let what = if state == "Z" { "zombie" } else { "process" };
            found.push(format!("{what} {pid} ({})", cmdline.trim()));
        }
    }
    found
}
