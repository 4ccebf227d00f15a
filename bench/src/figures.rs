//! The paper's figures and two beyond it, each one command (`admm-ta experiment NAME`)
//! writing a JSON file and SVG plots shaped like the paper's:
//!
//! * [`fig1_convergence`]: 50×50, complete graph — the team's relaxed cost per iteration
//!   against the Hungarian optimum (paper Fig. 1 left: primal ADMM-TA within 50 iterations),
//!   plus the three ADMM methods' relative gaps on log axes;
//! * [`fig1_topologies`]: 50 robots × 30 tasks on complete, random and chain graphs (paper
//!   Fig. 1 right: all converge, the chain slowest, "about 200 iterations");
//! * [`fig2_scaling`]: iterations versus team size for ADMM-TA, CBAA, the market and the
//!   distributed Hungarian method on the complete graph, and ADMM-TA versus distributed
//!   Hungarian on random graphs (paper Fig. 2);
//! * [`ipc_scaling`] (beyond the paper): wall time to the optimal assignment with one
//!   process per robot over iceoryx2, and the round latency, versus team size per method.
//!
//! Every run is a real solve ([`admm_ta_runtime::solve::solve`]) checked against the
//! centralized optimum; nothing is taken from the paper but the comparison numbers.

use crate::plot::{Chart, Legend, PlotError, Scale, Series};
use admm_ta_agents::method::Method;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::{SolveOptions, SolveOptionsBuilder, StopRule};
use admm_ta_runtime::runner::RunError;
use admm_ta_runtime::solve::error::SolveError;
use admm_ta_runtime::solve::report::{OracleCheck, SolveReport, TracePoint};
use admm_ta_runtime::solve::solve;
use admm_ta_runtime::transport::Transport;
use admm_ta_topologies::TopologySpec;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Settings shared by the figure experiments.
#[derive(Debug, Clone)]
pub struct FigureConfig {
    /// Seeds (cost matrices and random graphs) per point.
    pub trials: u64,
    /// Team sizes (robots = tasks) of the scaling experiments.
    pub sizes: Vec<usize>,
    pub adaptive_rho: bool,
    pub max_iters: usize,
    /// The `admm-ta` binary (ipc runs).
    pub agent_program: Option<PathBuf>,
    /// ADMM runs to the decentralized stop only up to this team size in `fig2-scaling`
    /// (beyond it, the paper's 0.1% criterion only: the decentralized stop of the primal
    /// method at 100 robots takes ~40 s per run on 2 cores).
    pub decentralized_up_to: usize,
}

impl Default for FigureConfig {
    fn default() -> Self {
        Self {
            trials: 3,
            sizes: vec![10, 20, 30, 40, 50, 60, 70, 80, 90, 100],
            adaptive_rho: false,
            max_iters: 5000,
            agent_program: None,
            decentralized_up_to: 50,
        }
    }
}

/// Failures of an experiment.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error("{0}")]
    Setup(String),
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

fn uniform(robots: usize, tasks: usize, seed: u64) -> Result<TaskAssignmentProblem, FigureError> {
    let costs =
        CostMatrix::uniform(robots, tasks, seed).map_err(|e| FigureError::Setup(e.to_string()))?;
    TaskAssignmentProblem::new(costs, CaseChoice::Auto)
        .map_err(|e| FigureError::Setup(e.to_string()))
}

fn topology(spec: &str, n: usize, seed: u64) -> Result<admm_ta_topologies::Graph, FigureError> {
    spec.parse::<TopologySpec>()
        .and_then(|t| t.build(n, seed))
        .map_err(|e| FigureError::Setup(format!("topology {spec}: {e}")))
}

impl FigureConfig {
    /// Solves `problem` on a `graph_spec` graph drawn from `seed`, checked against the
    /// optimum, with this experiment's ρ schedule, round limit and agent binary; `config`
    /// gives the rest (method, stop, transport, trace).
    fn checked_solve(
        &self,
        problem: &TaskAssignmentProblem,
        graph_spec: &str,
        seed: u64,
        options: SolveOptionsBuilder,
    ) -> Result<(SolveReport, OracleCheck), FigureError> {
        let graph = topology(graph_spec, problem.robots(), seed)?;
        let options = options
            .seed(seed)
            .check(true)
            .adaptive_rho(self.adaptive_rho)
            .max_iters(self.max_iters)
            .agent_program(self.agent_program.clone())
            .fault_injection(false)
            .build()
            .map_err(SolveError::from)?;
        let report = solve(problem, &graph, &options)?;
        let check = report.check.clone().expect("checked run");
        Ok((report, check))
    }
}

/// Writes `value` as pretty JSON into `dir/name`.
pub fn write_json(dir: &Path, name: &str, value: &impl Serialize) -> Result<PathBuf, FigureError> {
    let path = dir.join(name);
    std::fs::create_dir_all(dir)
        .and_then(|()| {
            std::fs::write(
                &path,
                serde_json::to_string_pretty(value).expect("serialisable"),
            )
        })
        .map_err(|source| FigureError::Write {
            path: path.clone(),
            source,
        })?;
    Ok(path)
}

/// One traced run.
#[derive(Debug, Clone, Serialize)]
pub struct TracedRun {
    pub method: Method,
    pub topology: String,
    pub seed: u64,
    pub optimal_cost: f64,
    /// Rounds to the decentralized stop.
    pub stop_round: usize,
    pub optimal: bool,
    pub rounds_within_0_1pct: Option<usize>,
    pub rounds_to_optimal_assignment: Option<usize>,
    pub trace: Vec<TracePoint>,
}

fn traced_run(
    problem: &TaskAssignmentProblem,
    graph_spec: &str,
    method: Method,
    seed: u64,
    config: &FigureConfig,
) -> Result<TracedRun, FigureError> {
    let (report, check) = config.checked_solve(
        problem,
        graph_spec,
        seed,
        SolveOptions::builder().method(method).trace(true),
    )?;
    Ok(TracedRun {
        method,
        topology: graph_spec.to_string(),
        seed,
        optimal_cost: check.optimal_cost,
        stop_round: report.iterations,
        optimal: check.optimal,
        rounds_within_0_1pct: check.rounds_within_0_1pct,
        rounds_to_optimal_assignment: check.rounds_to_optimal_assignment,
        trace: check.trace,
    })
}

/// Mean of the values (`None` when there are none).
pub(crate) fn mean_of(values: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (sum, count) = values
        .into_iter()
        .fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
    (count > 0).then(|| sum / count as f64)
}

/// Summary of one method (or topology) over the trials.
#[derive(Debug, Clone, Serialize)]
pub struct TraceSummary {
    pub label: String,
    pub trials: usize,
    pub optimal_runs: usize,
    pub mean_within_0_1pct: Option<f64>,
    pub mean_optimal_assignment_from: Option<f64>,
    pub mean_stop_round: f64,
    pub paper: Option<String>,
}

fn summarise(label: &str, runs: &[&TracedRun], paper: Option<&str>) -> TraceSummary {
    TraceSummary {
        label: label.to_string(),
        trials: runs.len(),
        optimal_runs: runs.iter().filter(|r| r.optimal).count(),
        mean_within_0_1pct: mean_of(
            runs.iter()
                .filter_map(|r| r.rounds_within_0_1pct.map(|v| v as f64)),
        ),
        mean_optimal_assignment_from: mean_of(
            runs.iter()
                .filter_map(|r| r.rounds_to_optimal_assignment.map(|v| v as f64)),
        ),
        mean_stop_round: mean_of(runs.iter().map(|r| r.stop_round as f64)).unwrap_or(0.0),
        paper: paper.map(str::to_string),
    }
}

/// What `fig1-convergence` and `fig1-topologies` produce.
#[derive(Debug, Clone, Serialize)]
pub struct ConvergenceFigure {
    pub robots: usize,
    pub tasks: usize,
    pub summaries: Vec<TraceSummary>,
    pub runs: Vec<TracedRun>,
}

/// Markdown table of the summaries.
pub fn render_summaries(summaries: &[TraceSummary]) -> String {
    let mut out = String::from(
        "| run | trials | optimal | within 0.1% (mean) | optimal assignment from (mean) | decentralized stop (mean) | paper |\n|---|---|---|---|---|---|---|\n",
    );
    let show = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.1}"));
    for s in summaries {
        out += &format!(
            "| {} | {} | {}/{} | {} | {} | {:.1} | {} |\n",
            s.label,
            s.trials,
            s.optimal_runs,
            s.trials,
            show(s.mean_within_0_1pct),
            show(s.mean_optimal_assignment_from),
            s.mean_stop_round,
            s.paper.as_deref().unwrap_or("-")
        );
    }
    out
}

fn relaxed_series(name: &str, run: &TracedRun) -> Series {
    Series::new(
        name,
        run.trace
            .iter()
            .map(|p| (p.round as f64, p.relaxed_cost))
            .collect(),
    )
}

fn gap_series(name: &str, run: &TracedRun) -> Series {
    Series::new(
        name,
        run.trace
            .iter()
            .map(|p| {
                let gap = ((p.relaxed_cost - run.optimal_cost) / run.optimal_cost).abs();
                (p.round as f64, gap.max(1e-12))
            })
            .collect(),
    )
}

/// Paper Fig. 1 (left): 50×50 on the complete graph.
pub fn fig1_convergence(
    config: &FigureConfig,
    out: &Path,
    progress: &dyn Fn(&str),
) -> Result<(ConvergenceFigure, Vec<PathBuf>), FigureError> {
    let n = 50;
    let methods = [Method::Primal, Method::Dual, Method::InexactDual];
    let mut runs = Vec::new();
    for seed in 0..config.trials {
        let problem = uniform(n, n, seed)?;
        for method in methods {
            progress(&format!("seed {seed} {}", method.name()));
            runs.push(traced_run(&problem, "complete", method, seed, config)?);
        }
    }
    let summaries = methods
        .iter()
        .map(|&m| {
            let of: Vec<&TracedRun> = runs.iter().filter(|r| r.method == m).collect();
            summarise(
                m.name(),
                &of,
                (m == Method::Primal).then_some("≈ 50 (within 0.1%)"),
            )
        })
        .collect();
    let figure = ConvergenceFigure {
        robots: n,
        tasks: n,
        summaries,
        runs,
    };
    let mut written = vec![write_json(out, "fig1-convergence.json", &figure)?];
    let first = |m: Method| figure.runs.iter().find(|r| r.method == m && r.seed == 0);
    if let Some(primal) = first(Method::Primal) {
        let path = out.join("fig1-convergence.svg");
        Chart::new(
            "Fig. 1 (left): primal ADMM-TA, 50 robots × 50 tasks, complete graph (seed 0)",
            "iteration",
            "team cost Σ αᵢᵀxᵢ (relaxed)",
        )
        .legend(Legend::UpperRight)
        .series(relaxed_series("ADMM-TA (primal)", primal))
        .reference("Hungarian optimum", primal.optimal_cost)
        .write(&path)?;
        written.push(path);
    }
    let mut chart = Chart::new(
        "50×50 complete graph: relative gap of the relaxed cost (seed 0)",
        "iteration",
        "|cost − optimum| / optimum",
    )
    .x_scale(Scale::Log)
    .y_scale(Scale::Log)
    .legend(Legend::LowerLeft);
    for m in methods {
        if let Some(run) = first(m) {
            chart = chart.series(gap_series(m.name(), run));
        }
    }
    let path = out.join("fig1-convergence-methods.svg");
    chart.reference("0.1%", 1e-3).write(&path)?;
    written.push(path);
    Ok((figure, written))
}

/// The random graph of the topology experiments (edge probability 0.1, connected).
pub const RANDOM_GRAPH: &str = "random:0.1";

/// Paper Fig. 1 (right): 50 robots × 30 tasks on complete, random and chain graphs.
pub fn fig1_topologies(
    config: &FigureConfig,
    out: &Path,
    progress: &dyn Fn(&str),
) -> Result<(ConvergenceFigure, Vec<PathBuf>), FigureError> {
    let (n, m) = (50, 30);
    let graphs = ["complete", RANDOM_GRAPH, "chain"];
    let mut runs = Vec::new();
    for seed in 0..config.trials {
        let problem = uniform(n, m, seed)?;
        for g in graphs {
            progress(&format!("seed {seed} {g}"));
            runs.push(traced_run(&problem, g, Method::Primal, seed, config)?);
        }
    }
    let summaries = graphs
        .iter()
        .map(|&g| {
            let of: Vec<&TracedRun> = runs.iter().filter(|r| r.topology == g).collect();
            let paper = if g == "chain" { "≈ 200" } else { "≈ 30" };
            summarise(g, &of, Some(paper))
        })
        .collect();
    let figure = ConvergenceFigure {
        robots: n,
        tasks: m,
        summaries,
        runs,
    };
    let mut written = vec![write_json(out, "fig1-topologies.json", &figure)?];
    let mut chart = Chart::new(
        "Fig. 1 (right): primal ADMM-TA, 50 robots × 30 tasks per topology (seed 0)",
        "iteration",
        "team cost Σ αᵢᵀxᵢ (relaxed)",
    )
    .x_scale(Scale::Log)
    .legend(Legend::UpperRight);
    let mut optimum = None;
    for g in graphs {
        if let Some(run) = figure.runs.iter().find(|r| r.topology == g && r.seed == 0) {
            chart = chart.series(relaxed_series(g, run));
            optimum = Some(run.optimal_cost);
        }
    }
    if let Some(o) = optimum {
        chart = chart.reference("Hungarian optimum", o);
    }
    let path = out.join("fig1-topologies.svg");
    chart.write(&path)?;
    written.push(path);
    Ok((figure, written))
}

/// One method at one team size on one graph family, over the trials.
#[derive(Debug, Clone, Serialize)]
pub struct ScalingPoint {
    pub robots: usize,
    pub topology: String,
    /// `primal (within 0.1%)`, `primal (decentralized stop)`, or a baseline's name.
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
    method: Method,
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
            SolveOptions::builder().method(method).stop(stop),
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

/// The runs of `fig2-scaling`, in order: `(graph, series label, method, stop, sizes)`.
fn scaling_plan(
    config: &FigureConfig,
) -> Vec<(&'static str, String, Method, StopRule, Vec<usize>)> {
    let small: Vec<usize> = config
        .sizes
        .iter()
        .copied()
        .filter(|&n| n <= config.decentralized_up_to)
        .collect();
    let all = config.sizes.clone();
    vec![
        (
            "complete",
            "ADMM-TA (within 0.1%)".into(),
            Method::Primal,
            StopRule::Oracle,
            all.clone(),
        ),
        (
            "complete",
            "ADMM-TA (decentralized stop)".into(),
            Method::Primal,
            StopRule::Local,
            small.clone(),
        ),
        (
            "complete",
            "CBAA (not optimal)".into(),
            Method::Cbaa,
            StopRule::Local,
            all.clone(),
        ),
        (
            "complete",
            "market".into(),
            Method::Market,
            StopRule::Local,
            all.clone(),
        ),
        (
            "complete",
            "distributed Hungarian".into(),
            Method::DistHungarian,
            StopRule::Local,
            all.clone(),
        ),
        (
            RANDOM_GRAPH,
            "ADMM-TA (within 0.1%)".into(),
            Method::Primal,
            StopRule::Oracle,
            all.clone(),
        ),
        (
            RANDOM_GRAPH,
            "ADMM-TA (decentralized stop)".into(),
            Method::Primal,
            StopRule::Local,
            small,
        ),
        (
            RANDOM_GRAPH,
            "distributed Hungarian".into(),
            Method::DistHungarian,
            StopRule::Local,
            all,
        ),
    ]
}

/// Number of points `fig2-scaling` computes (for progress bars).
pub fn fig2_points(config: &FigureConfig) -> usize {
    scaling_plan(config).iter().map(|p| p.4.len()).sum()
}

/// Paper Fig. 2: iterations versus team size.
pub fn fig2_scaling(
    config: &FigureConfig,
    out: &Path,
    progress: &dyn Fn(&ScalingPoint),
) -> Result<(ScalingFigure, Vec<PathBuf>), FigureError> {
    let mut points = Vec::new();
    for (graph, series, method, stop, sizes) in scaling_plan(config) {
        for n in sizes {
            let point = scaling_point(n, graph, &series, method, stop, config)?;
            progress(&point);
            points.push(point);
        }
    }
    let figure = ScalingFigure { points };
    let mut written = vec![write_json(out, "fig2-scaling.json", &figure)?];
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
        for p in figure.points.iter().filter(|p| p.topology == graph) {
            if !labels.contains(&p.series.as_str()) {
                labels.push(&p.series);
            }
        }
        for label in labels {
            let pts = figure
                .points
                .iter()
                .filter(|p| p.topology == graph && p.series == label)
                .map(|p| (p.robots as f64, p.mean_iterations))
                .collect();
            chart = chart.series(Series::new(label, pts));
        }
        let path = out.join(file);
        chart.write(&path)?;
        written.push(path);
    }
    Ok((figure, written))
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
    Method::ALL.into_iter().filter(|&m| m != Method::Hungarian)
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
    out: &Path,
    progress: &dyn Fn(&IpcPoint),
) -> Result<(IpcScalingFigure, Vec<PathBuf>), FigureError> {
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
                    SolveOptions::builder()
                        .method(method)
                        .transport(Transport::Ipc),
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
    let figure = IpcScalingFigure { points };
    let mut written = vec![write_json(out, "ipc-scaling.json", &figure)?];
    let by_method = |f: fn(&IpcPoint) -> f64| -> Vec<(Method, Vec<(f64, f64)>)> {
        ipc_methods()
            .map(|m| {
                let pts = figure
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
    let path = out.join("ipc-scaling-wall.svg");
    wall.write(&path)?;
    written.push(path);
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
    let path = out.join("ipc-scaling-latency.svg");
    latency.write(&path)?;
    written.push(path);
    Ok((figure, written))
}
