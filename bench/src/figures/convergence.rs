//! Paper Fig. 1: the team's relaxed cost per iteration against the Hungarian optimum, per
//! method (`fig1-convergence`) and per topology (`fig1-topologies`).

use crate::experiment::{Experiment, OutputFile, mean_of};
use crate::figures::{FigureConfig, FigureError, RANDOM_GRAPH, as_in_paper, uniform};
use crate::plot::{Chart, Legend, Scale, Series};
use admm_ta_agents::method::info::Role;
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_runtime::options::SolveOptions;
use admm_ta_runtime::solve::report::TracePoint;
use serde::Serialize;

/// The graphs of `fig1-topologies`.
const GRAPHS: [&str; 3] = ["complete", RANDOM_GRAPH, "chain"];

/// One traced run.
#[derive(Debug, Clone, Serialize)]
pub struct TracedRun {
    /// The method and its variant.
    pub contender: Contender,
    /// `primal (paper)`, `dual (fast)`, …
    pub label: String,
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
    contender: Contender,
    seed: u64,
    config: &FigureConfig,
) -> Result<TracedRun, FigureError> {
    let (report, check) = config.checked_solve(
        problem,
        graph_spec,
        seed,
        contender,
        SolveOptions::builder().trace(true),
    )?;
    Ok(TracedRun {
        contender,
        label: contender.label(),
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

/// Which of the two convergence figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Convergence {
    /// `fig1-convergence`: the ADMM methods on one graph.
    Methods,
    /// `fig1-topologies`: the primal method on several graphs.
    Topologies,
}

/// What `fig1-convergence` and `fig1-topologies` produce.
#[derive(Debug, Clone, Serialize)]
pub struct ConvergenceFigure {
    #[serde(skip)]
    pub kind: Convergence,
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

/// Every consensus ADMM method in each of its variants.
fn admm_contenders() -> Vec<Contender> {
    Contender::all()
        .into_iter()
        .filter(|c| c.method.info().role == Role::Admm)
        .collect()
}

/// Paper Fig. 1 (left): 50×50 on the complete graph, every ADMM method and variant.
pub fn fig1_convergence(
    config: &FigureConfig,
    progress: &dyn Fn(&str),
) -> Result<ConvergenceFigure, FigureError> {
    let n = 50;
    let mut runs = Vec::new();
    for seed in 0..config.trials {
        let problem = uniform(n, n, seed)?;
        for contender in admm_contenders() {
            progress(&format!("seed {seed} {}", contender.label()));
            runs.push(traced_run(&problem, "complete", contender, seed, config)?);
        }
    }
    let summaries = admm_contenders()
        .into_iter()
        .map(|c| {
            let of: Vec<&TracedRun> = runs.iter().filter(|r| r.contender == c).collect();
            // The paper's number belongs to the variant it ran.
            let paper = (as_in_paper(c.method) == c)
                .then(|| c.method.info().paper.and_then(|p| p.fig1))
                .flatten();
            summarise(&c.label(), &of, paper)
        })
        .collect();
    Ok(ConvergenceFigure {
        kind: Convergence::Methods,
        robots: n,
        tasks: n,
        summaries,
        runs,
    })
}

/// Paper Fig. 1 (right): 50 robots × 30 tasks on complete, random and chain graphs.
pub fn fig1_topologies(
    config: &FigureConfig,
    progress: &dyn Fn(&str),
) -> Result<ConvergenceFigure, FigureError> {
    let (n, m) = (50, 30);
    let mut runs = Vec::new();
    for seed in 0..config.trials {
        let problem = uniform(n, m, seed)?;
        for g in GRAPHS {
            progress(&format!("seed {seed} {g}"));
            let primal = as_in_paper(Method::papers_own());
            runs.push(traced_run(&problem, g, primal, seed, config)?);
        }
    }
    let summaries = GRAPHS
        .iter()
        .map(|&g| {
            let of: Vec<&TracedRun> = runs.iter().filter(|r| r.topology == g).collect();
            let paper = if g == "chain" { "≈ 200" } else { "≈ 30" };
            summarise(g, &of, Some(paper))
        })
        .collect();
    Ok(ConvergenceFigure {
        kind: Convergence::Topologies,
        robots: n,
        tasks: m,
        summaries,
        runs,
    })
}

impl ConvergenceFigure {
    /// `fig1-convergence.svg` (the primal's relaxed cost against the optimum) and
    /// `fig1-convergence-methods.svg` (every method's relative gap), of seed 0.
    fn method_charts(&self) -> Vec<(String, OutputFile)> {
        let first = |c: Contender| self.runs.iter().find(|r| r.contender == c && r.seed == 0);
        let mut charts = Vec::new();
        if let Some(primal) = first(as_in_paper(Method::papers_own())) {
            let chart = Chart::new(
                "Fig. 1 (left): primal ADMM-TA, 50 robots × 50 tasks, complete graph (seed 0)",
                "iteration",
                "team cost Σ αᵢᵀxᵢ (relaxed)",
            )
            .legend(Legend::UpperRight)
            .series(relaxed_series("ADMM-TA (primal)", primal))
            .reference("Hungarian optimum", primal.optimal_cost);
            charts.push(("fig1-convergence.svg".into(), OutputFile::Chart(chart)));
        }
        let mut chart = Chart::new(
            "50×50 complete graph: relative gap of the relaxed cost (seed 0)",
            "iteration",
            "|cost − optimum| / optimum",
        )
        .x_scale(Scale::Log)
        .y_scale(Scale::Log)
        .legend(Legend::LowerLeft);
        for c in admm_contenders() {
            if let Some(run) = first(c) {
                chart = chart.series(gap_series(&c.label(), run));
            }
        }
        let chart = chart.reference("0.1%", 1e-3);
        charts.push((
            "fig1-convergence-methods.svg".into(),
            OutputFile::Chart(chart),
        ));
        charts
    }

    /// `fig1-topologies.svg`: the relaxed cost per topology, of seed 0.
    fn topology_chart(&self) -> (String, OutputFile) {
        let mut chart = Chart::new(
            "Fig. 1 (right): primal ADMM-TA, 50 robots × 30 tasks per topology (seed 0)",
            "iteration",
            "team cost Σ αᵢᵀxᵢ (relaxed)",
        )
        .x_scale(Scale::Log)
        .legend(Legend::UpperRight);
        let mut optimum = None;
        for g in GRAPHS {
            if let Some(run) = self.runs.iter().find(|r| r.topology == g && r.seed == 0) {
                chart = chart.series(relaxed_series(g, run));
                optimum = Some(run.optimal_cost);
            }
        }
        if let Some(o) = optimum {
            chart = chart.reference("Hungarian optimum", o);
        }
        ("fig1-topologies.svg".into(), OutputFile::Chart(chart))
    }
}

impl Experiment for ConvergenceFigure {
    fn json_file(&self) -> &'static str {
        match self.kind {
            Convergence::Methods => "fig1-convergence.json",
            Convergence::Topologies => "fig1-topologies.json",
        }
    }

    fn render(&self) -> String {
        render_summaries(&self.summaries)
    }

    fn files(&self) -> Vec<(String, OutputFile)> {
        match self.kind {
            Convergence::Methods => self.method_charts(),
            Convergence::Topologies => vec![self.topology_chart()],
        }
    }
}
