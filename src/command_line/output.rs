//! Human and JSON renderings of a solve report.

use crate::agents::method::info::Certification;
use crate::agents::problem::{AssignmentCase, IDLE};
use crate::transport::Execution;
use crate::{SolveReport, StopRule};
use anyhow::Result;

/// Standard output could not be written (a full disk, a closed pipe): exit 1, or quietly
/// when the reader closed the pipe (`admm-ta topology | head -1`), as a Unix tool ends.
#[derive(Debug, thiserror::Error)]
#[error("cannot write the output")]
pub struct WriteError(#[from] pub std::io::Error);

/// `println!` that returns a [`WriteError`] from the enclosing function instead of panicking.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*).map_err($crate::command_line::output::WriteError)?
    }};
}
pub(crate) use outln;

/// `print!` that returns a [`WriteError`] from the enclosing function instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout(), $($arg)*).map_err($crate::command_line::output::WriteError)?
    }};
}
pub(crate) use out;

/// Whether `error` is standard output's reader having closed the pipe.
pub fn reader_closed(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<WriteError>()
            .is_some_and(|e| e.0.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// A row printed while a sweep runs: a write error is not fatal here (the sweep's report,
/// printed with `outln!` at its end, reports it).
pub fn progress_row(row: &str) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stdout(), "{row}");
}

pub fn print_report(report: &SolveReport, json: bool) -> Result<()> {
    if json {
        outln!("{}", serde_json::to_string(report)?);
        return Ok(());
    }
    print_problem(report)?;
    print_run(report)?;
    print_assignment(report)?;
    print_timing(report)?;
    print_check(report)
}

/// The degraded run's notice and the problem solved.
fn print_problem(report: &SolveReport) -> Result<()> {
    if let Some(d) = &report.degraded {
        outln!(
            "degraded: {}; the {} survivors re-solved without robot {} (robots below by their original numbers)",
            d.failure,
            d.survivors.len(),
            d.failed_robot
        );
    }
    outln!(
        "method {}, transport {}: {} robots × {} tasks ({}{}), topology {}",
        report.method.name(),
        report.transport.name(),
        report.robots,
        report.tasks,
        match report.case {
            AssignmentCase::Idle => "case idle".to_string(),
            case => format!("Case {}", case.number()),
        },
        if report.maximize { ", maximizing" } else { "" },
        report.topology
    );
    Ok(())
}

/// How the run ended: ρ, rounds, time, messages, the stop and the perturbation.
fn print_run(report: &SolveReport) -> Result<()> {
    let info = report.method.info();
    let inner = match info.report.inner_steps {
        Some(steps) => format!(", {:.2} {steps}", report.mean_projection_steps),
        None => String::new(),
    };
    let rho = if info.penalty() {
        format!("ρ = {:.4e}; ", report.rho)
    } else {
        String::new()
    };
    outln!(
        "{rho}{} after {} iterations ({:.1} ms{inner}); {} messages of {} bytes per agent",
        if report.converged {
            "converged"
        } else {
            "iteration limit reached"
        },
        report.iterations,
        report.wall_time_ms,
        report.messages_per_agent,
        report.message_bytes,
    );
    if let Some(r) = report.certified_round {
        outln!(
            "stop: {} — all robots certified the assignment of round {r}",
            match report.stop {
                StopRule::Local => "local (decentralized)",
                _ => "certified",
            }
        );
    }
    if let Some(eps) = report.perturbation {
        outln!("tie-breaking perturbation ε = {eps:.3e} per robot");
    }
    Ok(())
}

/// The assignment, by number and by name, and its cost.
fn print_assignment(report: &SolveReport) -> Result<()> {
    let info = report.method.info();
    let pairs: Vec<String> = report
        .assignment
        .iter()
        .enumerate()
        .map(|(robot, task)| {
            if *task == IDLE {
                format!("{robot}→-")
            } else {
                format!("{robot}→{task}")
            }
        })
        .collect();
    outln!("assignment (robot→task): {}", pairs.join(" "));
    if report.robot_names.is_some() || report.task_names.is_some() {
        let name = |names: &Option<Vec<String>>, k: usize| {
            names
                .as_ref()
                .and_then(|n| n.get(k))
                .cloned()
                .unwrap_or_else(|| k.to_string())
        };
        let named: Vec<String> = report
            .assignment
            .iter()
            .enumerate()
            .map(|(robot, &task)| {
                let task = if task == IDLE {
                    "-".to_string()
                } else {
                    name(&report.task_names, task)
                };
                format!("{} → {task}", name(&report.robot_names, robot))
            })
            .collect();
        outln!("by name: {}", named.join(", "));
    }
    if !report.idle_robots.is_empty() {
        outln!("idle robots: {:?}", report.idle_robots);
    }
    if !report.unserved_tasks.is_empty() {
        outln!("unserved tasks: {:?}", report.unserved_tasks);
    }
    outln!(
        "{} {:.6}{}{}",
        if report.maximize { "profit" } else { "cost" },
        report.cost,
        if report.repaired {
            " (robots' choices conflicted and were repaired)"
        } else {
            ""
        },
        match info.certification {
            _ if report.certified => String::new(),
            Certification::Never { because } => format!(" — NOT certified optimal ({because})"),
            _ => " — NOT certified optimal (the best assignment found when the run stopped)".into(),
        }
    );
    Ok(())
}

/// Start-up, round latency and the critical path, when measured.
fn print_timing(report: &SolveReport) -> Result<()> {
    if let Some(startup) = report.startup_ms {
        outln!(
            "{} agent processes connected in {startup:.1} ms",
            report.robots
        );
    }
    if let Some(l) = &report.round_latency_us {
        outln!(
            "round latency (µs): p50 {:.1}, p90 {:.1}, p99 {:.1}, max {:.1} — wait p50 {:.1}, compute p50 {:.1}, publish p50 {:.1}{}",
            l.round.p50,
            l.round.p90,
            l.round.p99,
            l.round.max,
            l.wait.p50,
            l.compute.p50,
            l.publish.p50,
            if report.global_barrier {
                format!(", global barrier p50 {:.1}", l.barrier.p50)
            } else {
                String::new()
            }
        );
    }
    if let Some(path) = &report.critical_path {
        let top: Vec<String> = path
            .top
            .iter()
            .map(|a| {
                format!(
                    "agent {} ({:.1}% of round time, waited for by {} agent-rounds, critical in {} rounds)",
                    a.agent,
                    100.0 * a.waiting_share,
                    a.waited_for,
                    a.rounds
                )
            })
            .collect();
        outln!(
            "critical path: {:.1}% of the agents' round time went to waiting for a late neighbour{}",
            100.0 * path.waiting_share,
            if top.is_empty() {
                String::new()
            } else {
                format!("; most waited for: {}", top.join(", "))
            }
        );
    }
    Ok(())
}

/// The centralized check against the optimum, when asked for.
fn print_check(report: &SolveReport) -> Result<()> {
    if let Some(check) = &report.check {
        let round = |r: Option<usize>| r.map_or("never".to_string(), |r| r.to_string());
        outln!(
            "optimal {} {:.6} (centralized), gap {:.4}%: {}",
            if report.maximize { "profit" } else { "cost" },
            check.optimal_cost,
            100.0 * check.gap,
            if check.optimal {
                "optimal"
            } else {
                "NOT optimal"
            }
        );
        if report.transport.capabilities().execution != Execution::Lockstep {
            return Ok(());
        }
        outln!(
            "rounds: within 0.1% first at {}, settled at {}; optimal assignment from {}",
            round(check.rounds_within_0_1pct),
            round(check.rounds_settled_0_1pct),
            round(check.rounds_to_optimal_assignment)
        );
    }
    Ok(())
}
