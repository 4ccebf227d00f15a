//! What `admm-ta bench rounds` reports: each case's latency tails, CPU usage and start-up,
//! rendered as Markdown tables, `rounds.csv` and SVG plots.

use crate::experiment::{Experiment, OutputFile};
use crate::plot::{Chart, Scale, Series};
use crate::rounds::case::{Case, DEFAULT_TRANSPORTS, PayloadShape, StepKind};
use admm_ta_transport::Transport;
use admm_ta_transport::latency::Percentiles;
use admm_ta_transport::timeline::{CriticalPath, RoundStamp};
use admm_ta_transport::wait::WaitStrategy;
use serde::Serialize;

/// Percentiles of one quantity, in microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tail {
    pub p50: f64,
    pub p90: f64,
    pub p99: f64,
    pub p999: f64,
    pub max: f64,
}

impl From<Percentiles> for Tail {
    fn from(p: Percentiles) -> Self {
        Self {
            p50: p.p50,
            p90: p.p90,
            p99: p.p99,
            p999: p.p999,
            max: p.max,
        }
    }
}

/// What one case measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    #[serde(flatten)]
    pub case: Case,
    pub payload_bytes: usize,
    /// Agent-rounds recorded (agents × rounds after the warm-up).
    pub recorded: u64,
    /// Round time, µs.
    pub round_us: Tail,
    /// Round time minus compute time, µs: what the exchange and the barriers cost.
    pub overhead_us: Tail,
    pub compute_p50_us: f64,
    pub wait_p50_us: f64,
    pub publish_p50_us: f64,
    pub barrier_p50_us: f64,
    /// CPU time per agent-round, µs (user + system).
    pub cpu_us_per_round: f64,
    /// CPU time of all agents per received sample, µs: CPU / (agent-rounds × mean degree).
    pub cpu_us_per_sample: f64,
    pub voluntary_switches_per_round: f64,
    pub involuntary_switches_per_round: f64,
    pub startup_ms: Option<f64>,
    pub wall_ms: f64,
    /// Times the case was measured (`--repeat`); the numbers above are those of the
    /// repetition with the median round p50.
    pub repeats: usize,
    /// Lowest and highest round p50 over the repetitions, µs: the run-to-run spread.
    pub round_p50_range_us: (f64, f64),
    /// With timelines: whom the team waited for, round by round.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_path: Option<CriticalPath>,
    /// With `--timeline DIR`: the trace file of this case.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trace: Option<std::path::PathBuf>,
    /// Every agent's round stamps, until the trace is written.
    #[serde(skip)]
    pub timeline: Vec<Vec<RoundStamp>>,
}

/// A case that could not be measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseFailure {
    #[serde(flatten)]
    pub case: Case,
    pub error: String,
}

/// Everything a benchmark run produced.
#[derive(Debug, Clone, Serialize)]
pub struct RoundsReport {
    pub cores: usize,
    pub rounds: u64,
    pub warmup: u64,
    pub step: StepKind,
    pub results: Vec<CaseResult>,
    pub failures: Vec<CaseFailure>,
}

/// Header of [`render_row`]'s Markdown table.
pub const TABLE_HEADER: &str = "| agents | graph | payload | transport | wait | barrier | round p50 | p90 | p99 | p99.9 | max | overhead p50 | overhead p99 | compute p50 | CPU µs/round | CPU µs/sample | csw/round | start-up ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";

/// One Markdown table row (latencies in µs).
pub fn render_row(r: &CaseResult) -> String {
    let c = &r.case;
    format!(
        "{} {} | {:.1} | {:.1} | {:.1} | {:.0} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {} |",
        c.columns(),
        if r.repeats > 1 {
            format!(
                "{:.1} ({:.1}–{:.1})",
                r.round_us.p50, r.round_p50_range_us.0, r.round_p50_range_us.1
            )
        } else {
            format!("{:.1}", r.round_us.p50)
        },
        r.round_us.p90,
        r.round_us.p99,
        r.round_us.p999,
        r.round_us.max,
        r.overhead_us.p50,
        r.overhead_us.p99,
        r.compute_p50_us,
        r.cpu_us_per_round,
        r.cpu_us_per_sample,
        r.voluntary_switches_per_round + r.involuntary_switches_per_round,
        r.startup_ms.map_or("-".into(), |v| format!("{v:.0}")),
    )
}

/// Ratios of round p50 between transports on otherwise equal cases, as Markdown: every
/// transport measured against `threads` (`ipc / threads`, `uds / threads`, …, one column
/// each), then `uds / ipc` and `zenoh / ipc` (p50 and p99), and the start-up (ms) of every
/// process transport.
pub fn render_ratios(report: &RoundsReport) -> String {
    let find = |case: &Case, t: Transport| {
        report.results.iter().find(|r| {
            let mut other = case.clone();
            other.transport = t;
            r.case == other
        })
    };
    // The transports measured, in the order of `Transport::ALL`.
    let measured: Vec<Transport> = Transport::ALL
        .iter()
        .copied()
        .filter(|t| report.results.iter().any(|r| r.case.transport == *t))
        .collect();
    let against_threads: Vec<Transport> = measured
        .iter()
        .copied()
        .filter(|&t| t != Transport::Threads && t != Transport::Sim)
        .collect();
    let mut header = "| agents | graph | payload | wait | barrier |".to_string();
    for t in &against_threads {
        header.push_str(&format!(" {t} / threads p50 |"));
    }
    header.push_str(" uds / ipc p50 | uds / ipc p99 | zenoh / ipc p50 | zenoh / ipc p99 |");
    for t in &against_threads {
        header.push_str(&format!(" start-up ms {t} |"));
    }
    let columns = 5 + 2 * against_threads.len() + 4;
    let mut lines = vec![header, format!("|{}", "---|".repeat(columns))];
    let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.2}×", a / b),
        _ => "-".into(),
    };
    // One line per configuration: the cases of its first process transport.
    let Some(&first) = against_threads.first() else {
        return lines.join("\n");
    };
    for r in report.results.iter().filter(|r| r.case.transport == first) {
        let c = &r.case;
        let p50 = |t: Transport| find(c, t).map(|r| r.round_us.p50);
        let p99 = |t: Transport| find(c, t).map(|r| r.round_us.p99);
        let mut line = format!(
            "| {} | {} | {} | {} | {} |",
            c.agents,
            c.topology,
            c.payload,
            c.wait.name(),
            c.barrier_name()
        );
        for &t in &against_threads {
            line.push_str(&format!(" {} |", ratio(p50(t), p50(Transport::Threads))));
        }
        for (a, b) in [
            (p50(Transport::Uds), p50(Transport::Ipc)),
            (p99(Transport::Uds), p99(Transport::Ipc)),
            (p50(Transport::Zenoh), p50(Transport::Ipc)),
            (p99(Transport::Zenoh), p99(Transport::Ipc)),
        ] {
            line.push_str(&format!(" {} |", ratio(a, b)));
        }
        for &t in &against_threads {
            let startup = find(c, t).and_then(|r| r.startup_ms);
            line.push_str(&format!(
                " {} |",
                startup.map_or("-".into(), |v| format!("{v:.0}"))
            ));
        }
        lines.push(line);
    }
    lines.join("\n")
}

/// The critical path of every case with a timeline, as Markdown: the share of all agents'
/// round time spent waiting for a late neighbour, the agents most waited for (their share,
/// the rounds in which they were the one most agents waited for) and the trace file.
pub fn render_critical(report: &RoundsReport) -> String {
    let mut lines = vec![
        "| agents | graph | payload | transport | wait | barrier | waiting for a late neighbour | most waited for: agent (share of round time, rounds led) | trace |".to_string(),
        format!("|{}", "---|".repeat(9)),
    ];
    for r in &report.results {
        let Some(path) = &r.critical_path else {
            continue;
        };
        let top = path
            .top
            .iter()
            .take(3)
            .map(|a| {
                format!(
                    "{} ({:.1}%, {})",
                    a.agent,
                    100.0 * a.waiting_share,
                    a.rounds
                )
            })
            .collect::<Vec<_>>()
            .join(", ");
        lines.push(format!(
            "{} {:.1}% | {} | {} |",
            r.case.columns(),
            100.0 * path.waiting_share,
            if top.is_empty() { "-".into() } else { top },
            r.trace
                .as_ref()
                .map_or("-".into(), |p| p.display().to_string())
        ));
    }
    lines.join("\n")
}

/// `rounds.csv`: one line per measured case.
pub fn to_csv(report: &RoundsReport) -> String {
    let mut out = String::from(
        "agents,topology,payload,payload_bytes,transport,wait,barrier,step,recorded,round_p50_us,round_p90_us,round_p99_us,round_p999_us,round_max_us,overhead_p50_us,overhead_p90_us,overhead_p99_us,overhead_p999_us,overhead_max_us,compute_p50_us,wait_p50_us,publish_p50_us,barrier_p50_us,cpu_us_per_round,cpu_us_per_sample,voluntary_switches_per_round,involuntary_switches_per_round,startup_ms,wall_ms,repeats,round_p50_min_us,round_p50_max_us\n",
    );
    for r in &report.results {
        let c = &r.case;
        let t = |t: &Tail| format!("{},{},{},{},{}", t.p50, t.p90, t.p99, t.p999, t.max);
        out += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            c.agents,
            c.topology,
            c.payload,
            r.payload_bytes,
            c.transport.name(),
            c.wait.name(),
            c.barrier_name(),
            c.step.name(),
            r.recorded,
            t(&r.round_us),
            t(&r.overhead_us),
            r.compute_p50_us,
            r.wait_p50_us,
            r.publish_p50_us,
            r.barrier_p50_us,
            r.cpu_us_per_round,
            r.cpu_us_per_sample,
            r.voluntary_switches_per_round,
            r.involuntary_switches_per_round,
            r.startup_ms.map_or(String::new(), |v| v.to_string())
                + &format!(
                    ",{},{},{},{}",
                    r.wall_ms, r.repeats, r.round_p50_range_us.0, r.round_p50_range_us.1
                ),
        );
    }
    out
}

impl Experiment for RoundsReport {
    fn json_file(&self) -> &'static str {
        "rounds.json"
    }

    /// The ratios between transports (the rows are printed as they are measured), and the
    /// critical paths when the agents recorded timelines.
    fn render(&self) -> String {
        let mut text = format!(
            "\nRatios on equal cases (round time):\n\n{}\n",
            render_ratios(self)
        );
        if self.results.iter().any(|r| r.critical_path.is_some()) {
            text += &format!(
                "\nCritical path (whom the team waited for, from the timelines):\n\n{}\n",
                render_critical(self)
            );
        }
        text
    }

    /// `rounds.csv` and the plots.
    fn files(&self) -> Vec<(String, OutputFile)> {
        let mut files = vec![("rounds.csv".to_string(), OutputFile::Text(to_csv(self)))];
        files.extend(
            charts(self)
                .into_iter()
                .map(|(name, chart)| (name, OutputFile::Chart(chart))),
        );
        files
    }
}

/// The plots: round latency (p50 solid, p99 dashed) per transport against team size (one
/// chart per topology) and against payload size (one chart per team size).
pub fn charts(report: &RoundsReport) -> Vec<(String, Chart)> {
    let base_wait = WaitStrategy::Auto;
    let transports: Vec<Transport> = DEFAULT_TRANSPORTS
        .into_iter()
        .filter(|t| report.results.iter().any(|r| r.case.transport == *t))
        .collect();
    let mut charts = Vec::new();
    let mut topologies: Vec<String> = Vec::new();
    for r in &report.results {
        if !topologies.contains(&r.case.topology) {
            topologies.push(r.case.topology.clone());
        }
    }
    let base_payload = PayloadShape { rows: 10, cols: 10 };
    for topology in &topologies {
        let chart = Chart::new(
            format!(
                "round latency vs agents ({topology} graph, {} payload, {} step)",
                if report.step == StepKind::Primal {
                    "n×n".into()
                } else {
                    base_payload.to_string()
                },
                report.step.name()
            ),
            "agents",
            "round time (µs), p50 solid, p99 dashed",
        )
        .y_scale(Scale::Log)
        .colour_by_prefix();
        let (chart, points_any) = with_transport_series(chart, report, &transports, 2, |c| {
            (&c.topology == topology
                && c.wait == base_wait
                && !c.global_barrier
                && (report.step == StepKind::Primal || c.payload == base_payload))
                .then_some(c.agents as f64)
        });
        if points_any {
            let slug: String = topology
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
                .collect();
            charts.push((format!("rounds-agents-{slug}.svg"), chart));
        }
    }
    let mut sizes: Vec<usize> = report.results.iter().map(|r| r.case.agents).collect();
    sizes.sort_unstable();
    sizes.dedup();
    for n in sizes {
        let chart = Chart::new(
            format!(
                "round latency vs payload ({n} agents, complete graph, {} step)",
                report.step.name()
            ),
            "payload (bytes)",
            "round time (µs), p50 solid, p99 dashed",
        )
        .x_scale(Scale::Log)
        .y_scale(Scale::Log)
        .colour_by_prefix();
        let (chart, points_any) = with_transport_series(chart, report, &transports, 3, |c| {
            (c.agents == n && c.topology == "complete" && c.wait == base_wait && !c.global_barrier)
                .then_some((c.payload.values() * 8) as f64)
        });
        if points_any {
            charts.push((format!("rounds-payload-{n}-agents.svg"), chart));
        }
    }
    charts.extend(critical_charts(report));
    charts
}

/// With timelines, one chart per case: the share of the team's round time spent waiting for
/// each agent (`critical-<case>.svg`).
pub fn critical_charts(report: &RoundsReport) -> Vec<(String, Chart)> {
    report
        .results
        .iter()
        .filter_map(|r| {
            let path = r.critical_path.as_ref()?;
            let c = &r.case;
            let points = path
                .by_agent
                .iter()
                .enumerate()
                .map(|(i, share)| (i as f64, 100.0 * share))
                .collect();
            let chart = Chart::new(
                format!(
                    "critical path: waiting for each agent ({} agents, {} graph, {}, {} step; {:.1}% of round time in all)",
                    c.agents,
                    c.topology,
                    c.transport.name(),
                    c.step.name(),
                    100.0 * path.waiting_share
                ),
                "agent",
                "share of all agents' round time spent waiting for it (%)",
            )
            .series(Series::new("waited for", points));
            Some((format!("critical-{}.svg", c.slug()), chart))
        })
        .collect()
}

/// Adds a p50 and a dashed p99 line per transport to `chart`, over the cases that `x` places
/// (returns their x value, `None` to leave a case out); transports with fewer than
/// `min_points` cases are skipped. Also says whether any line was added.
fn with_transport_series(
    mut chart: Chart,
    report: &RoundsReport,
    transports: &[Transport],
    min_points: usize,
    x: impl Fn(&Case) -> Option<f64>,
) -> (Chart, bool) {
    let mut any = false;
    for &t in transports {
        let mut rows: Vec<(f64, &CaseResult)> = report
            .results
            .iter()
            .filter(|r| r.case.transport == t)
            .filter_map(|r| x(&r.case).map(|x| (x, r)))
            .collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        if rows.len() < min_points {
            continue;
        }
        any = true;
        let pts = |f: fn(&CaseResult) -> f64| rows.iter().map(|(x, r)| (*x, f(r))).collect();
        chart = chart
            .series(Series::new(
                format!("{} p50", t.name()),
                pts(|r| r.round_us.p50),
            ))
            .series(Series::new(format!("{} p99", t.name()), pts(|r| r.round_us.p99)).dashed());
    }
    (chart, any)
}
