//! Paper Fig. 2 (`fig2-scaling`: iterations against team size per method and graph family)
//! and, beyond the paper, `ipc-scaling` (wall time and round latency with one process per
//! robot).

use crate::experiment::{Experiment, OutputFile};
use crate::figures::{FigureConfig, FigureError, RANDOM_GRAPH, as_in_paper, uniform};
use crate::plot::{Chart, Scale, Series};
use admm_ta_agents::method::info::{Fig2Graphs, Role};
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_runtime::options::{SolveOptions, StopRule};
use admm_ta_transport::Transport;
use serde::Serialize;

/// One method at one team size on one graph family, over the trials.
#[derive(Debug, Clone, Serialize)]
pub struct ScalingPoint {
    pub robots: usize,
    pub topology: String,
    /// `ADMM-TA (within 0.1%)`, `ADMM-TA (decentralized stop)`, another ADMM method or
    /// variant (`dual (fast)`), or a baseline's name.
    pub series: String,
    pub trials: usize,
    /// Mean iterations: to the method's own stop (the paper's 0.1% criterion for the
    /// `within 0.1%` series).
    pub mean_iterations: f64,
    pub optimal_runs: usize,
    pub mean_gap: f64,
}

/// What `fig2-scaling` produces.
#[derive(Debug, Clone, Serialize)]
pub struct ScalingFigure {
    pub points: Vec<ScalingPoint>,
}

/// Markdown table of scaling points.
pub fn render_scaling(points: &[ScalingPoint]) -> String {
    let mut out = String::from(
        "| graph | robots | series | trials | mean iterations | optimal | mean gap |\n|---|---|---|---|---|---|---|\n",
    );
    for p in points {
        out += &format!(
            "| {} | {} | {} | {} | {:.1} | {}/{} | {:.2}% |\n",
            p.topology,
            p.robots,
            p.series,
            p.trials,
            p.mean_iterations,
            p.optimal_runs,
            p.trials,
            100.0 * p.mean_gap
        );
    }
    out
}

fn scaling_point(
    n: usize,
    graph_spec: &str,
    series: &str,
    contender: Contender,
    stop: StopRule,
    config: &FigureConfig,
) -> Result<ScalingPoint, FigureError> {
    let mut point = ScalingPoint {
        robots: n,
        topology: graph_spec.to_string(),
        series: series.to_string(),
        trials: 0,
        mean_iterations: 0.0,
        optimal_runs: 0,
        mean_gap: 0.0,
    };
    for seed in 0..config.trials {
        let (report, check) = config.checked_solve(
            &uniform(n, n, seed)?,
            graph_spec,
            seed,
            contender,
            SolveOptions::builder().stop(stop),
        )?;
        point.trials += 1;
        point.mean_iterations += match stop {
            StopRule::Oracle => check.rounds_within_0_1pct.unwrap_or(report.iterations),
            _ => report.iterations,
        } as f64;
        point.optimal_runs += usize::from(check.optimal);
        point.mean_gap += check.gap;
    }
    let t = point.trials.max(1) as f64;
    point.mean_iterations /= t;
    point.mean_gap /= t;
    Ok(point)
}

/// The runs of `fig2-scaling`, in order: `(graph, series label, contender, stop, sizes)`:
/// on the complete graph and on random graphs, every method the paper ran there — its own
/// method as it ran it to the paper's criterion (every size) and to the decentralized stop
/// (up to `decentralized_up_to`), each baseline to its own stop — and every other ADMM
/// method and variant to the decentralized stop (up to `decentralized_up_to`), labelled.
fn scaling_plan(
    config: &FigureConfig,
) -> Vec<(&'static str, String, Contender, StopRule, Vec<usize>)> {
    let small: Vec<usize> = config
        .sizes
        .iter()
        .copied()
        .filter(|&n| n <= config.decentralized_up_to)
        .collect();
    let all = config.sizes.clone();
    let mut plan = Vec::new();
    for (graph, on) in [
        ("complete", (|g| g.complete) as fn(&Fig2Graphs) -> bool),
        (RANDOM_GRAPH, |g| g.random),
    ] {
        for method in Method::ALL {
            let Some(paper) = method.info().paper.filter(|p| on(&p.fig2)) else {
                continue;
            };
            let contender = as_in_paper(method);
            if paper.proposed {
                let within = format!("{} (within 0.1%)", paper.label);
                plan.push((graph, within, contender, StopRule::Oracle, all.clone()));
                let stop = format!("{} (decentralized stop)", paper.label);
                plan.push((graph, stop, contender, StopRule::Local, small.clone()));
            } else {
                plan.push((
                    graph,
                    paper.label.to_string(),
                    contender,
                    StopRule::Local,
                    all.clone(),
                ));
            }
        }
        // The other ADMM methods and variants, which the paper did not plot here.
        for contender in Contender::all() {
            let info = contender.method.info();
            let plotted = info.paper.is_some_and(|p| on(&p.fig2))
                && as_in_paper(contender.method) == contender;
            if info.role == Role::Admm && !plotted {
                let label = format!("{} (decentralized stop)", contender.label());
                plan.push((graph, label, contender, StopRule::Local, small.clone()));
            }
        }
    }
    plan
}

/// Number of points `fig2-scaling` computes (for progress bars).
pub fn fig2_points(config: &FigureConfig) -> usize {
    scaling_plan(config).iter().map(|p| p.4.len()).sum()
}

/// Paper Fig. 2: iterations versus team size.
pub fn fig2_scaling(
    config: &FigureConfig,
    progress: &dyn Fn(&ScalingPoint),
) -> Result<ScalingFigure, FigureError> {
    let mut points = Vec::new();
    for (graph, series, contender, stop, sizes) in scaling_plan(config) {
        for n in sizes {
            let point = scaling_point(n, graph, &series, contender, stop, config)?;
            progress(&point);
            points.push(point);
        }
    }
    Ok(ScalingFigure { points })
}

/// One method at one team size over ipc.
#[derive(Debug, Clone, Serialize)]
pub struct IpcPoint {
    pub robots: usize,
    pub method: Method,
    pub trials: usize,
    pub optimal_runs: usize,
    pub mean_rounds: f64,
    /// Wall time of the whole solve (spawning the processes included), ms.
    pub mean_wall_ms: f64,
    pub mean_startup_ms: f64,
    pub mean_round_p50_us: f64,
    pub mean_round_p99_us: f64,
}

/// What `ipc-scaling` produces.
#[derive(Debug, Clone, Serialize)]
pub struct IpcScalingFigure {
    pub points: Vec<IpcPoint>,
}

/// The methods `ipc-scaling` runs: every method with agents.
pub fn ipc_methods() -> impl Iterator<Item = Method> {
    Method::ALL.into_iter().filter(|m| m.team().is_some())
}

/// Markdown table of ipc points.
pub fn render_ipc(points: &[IpcPoint]) -> String {
    let mut out = String::from(
        "| robots | method | trials | optimal | rounds | wall ms | start-up ms | round p50 µs | round p99 µs |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for p in points {
        out += &format!(
            "| {} | {} | {} | {}/{} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} |\n",
            p.robots,
            p.method.name(),
            p.trials,
            p.optimal_runs,
            p.trials,
            p.mean_rounds,
            p.mean_wall_ms,
            p.mean_startup_ms,
            p.mean_round_p50_us,
            p.mean_round_p99_us
        );
    }
    out
}

/// Beyond the paper: wall time to the optimal assignment and round latency with one process
/// per robot (iceoryx2), per method and team size, on the complete graph.
pub fn ipc_scaling(
    config: &FigureConfig,
    progress: &dyn Fn(&IpcPoint),
) -> Result<IpcScalingFigure, FigureError> {
    let mut points = Vec::new();
    for &n in &config.sizes {
        for method in ipc_methods() {
            let mut p = IpcPoint {
                robots: n,
                method,
                trials: 0,
                optimal_runs: 0,
                mean_rounds: 0.0,
                mean_wall_ms: 0.0,
                mean_startup_ms: 0.0,
                mean_round_p50_us: 0.0,
                mean_round_p99_us: 0.0,
            };
            for seed in 0..config.trials {
                let (report, check) = config.checked_solve(
                    &uniform(n, n, seed)?,
                    "complete",
                    seed,
                    as_in_paper(method),
                    SolveOptions::builder().transport(Transport::Ipc),
                )?;
                let latency = report.round_latency_us.unwrap_or_default();
                p.trials += 1;
                p.optimal_runs += usize::from(check.optimal);
                p.mean_rounds += report.iterations as f64;
                p.mean_wall_ms += report.wall_time_ms;
                p.mean_startup_ms += report.startup_ms.unwrap_or(0.0);
                p.mean_round_p50_us += latency.round.p50;
                p.mean_round_p99_us += latency.round.p99;
            }
            let t = p.trials.max(1) as f64;
            p.mean_rounds /= t;
            p.mean_wall_ms /= t;
            p.mean_startup_ms /= t;
            p.mean_round_p50_us /= t;
            p.mean_round_p99_us /= t;
            progress(&p);
            points.push(p);
        }
    }
    Ok(IpcScalingFigure { points })
}

impl Experiment for ScalingFigure {
    fn json_file(&self) -> &'static str {
        "fig2-scaling.json"
    }

    fn render(&self) -> String {
        render_scaling(&self.points)
    }

    /// Iterations against team size, one chart per graph family.
    fn files(&self) -> Vec<(String, OutputFile)> {
        let mut charts = Vec::new();
        for (graph, file, title) in [
            (
                "complete",
                "fig2-scaling.svg",
                "Fig. 2 (left): iterations vs team size, complete graph",
            ),
            (
                RANDOM_GRAPH,
                "fig2-scaling-random.svg",
                "Fig. 2 (right): iterations vs team size, random graphs (p = 0.1)",
            ),
        ] {
            let mut chart = Chart::new(title, "robots (= tasks)", "iterations (mean over trials)")
                .y_scale(Scale::Log);
            let mut labels: Vec<&str> = Vec::new();
            for p in self.points.iter().filter(|p| p.topology == graph) {
                if !labels.contains(&p.series.as_str()) {
                    labels.push(&p.series);
                }
            }
            for label in labels {
                let pts = self
                    .points
                    .iter()
                    .filter(|p| p.topology == graph && p.series == label)
                    .map(|p| (p.robots as f64, p.mean_iterations))
                    .collect();
                chart = chart.series(Series::new(label, pts));
            }
            charts.push((file.to_string(), OutputFile::Chart(chart)));
        }
        charts
    }
}

impl Experiment for IpcScalingFigure {
    fn json_file(&self) -> &'static str {
        "ipc-scaling.json"
    }

    fn render(&self) -> String {
        render_ipc(&self.points)
    }

    /// Wall time and round latency against team size, per method.
    fn files(&self) -> Vec<(String, OutputFile)> {
        let by_method = |f: fn(&IpcPoint) -> f64| -> Vec<(Method, Vec<(f64, f64)>)> {
            ipc_methods()
                .map(|m| {
                    let pts = self
                        .points
                        .iter()
                        .filter(|p| p.method == m)
                        .map(|p| (p.robots as f64, f(p)))
                        .collect();
                    (m, pts)
                })
                .collect()
        };
        let mut wall = Chart::new(
            "wall time to the assignment, one process per robot (iceoryx2), complete graph",
            "robots (= tasks)",
            "wall time (ms), start-up included",
        )
        .y_scale(Scale::Log);
        for (m, pts) in by_method(|p| p.mean_wall_ms) {
            wall = wall.series(Series::new(m.name(), pts));
        }
        let wall = ("ipc-scaling-wall.svg".to_string(), OutputFile::Chart(wall));
        let mut latency = Chart::new(
            "round latency vs team size over iceoryx2, complete graph (p50 solid, p99 dashed)",
            "robots (= tasks)",
            "round time (µs)",
        )
        .y_scale(Scale::Log)
        .colour_by_prefix();
        for (m, pts) in by_method(|p| p.mean_round_p50_us) {
            latency = latency.series(Series::new(format!("{} p50", m.name()), pts));
        }
        for (m, pts) in by_method(|p| p.mean_round_p99_us) {
            latency = latency.series(Series::new(format!("{} p99", m.name()), pts).dashed());
        }
        let latency = (
            "ipc-scaling-latency.svg".to_string(),
            OutputFile::Chart(latency),
        );
        vec![wall, latency]
    }
}
