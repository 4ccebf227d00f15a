//! Where the rounds go (`admm-ta experiment rounds-anatomy`): for each method (the primal
//! method in both variants), each cost model and each graph, the rounds to
//! (a) the relaxed objective of the robots' own columns within 0.1% of the optimum (the
//!     paper's criterion) and to the robots' decisions within 0.1%,
//! (b) every robot's decision optimal and staying so,
//! (c) the decentralized certified stop (and whether its assignment is optimal);
//! medians over seeds on the lockstep simulation. A median is "never" when more than half
//! the runs never reached the criterion within the round limit.

use crate::experiment::{Experiment, OutputFile};
use crate::plot::{Chart, Scale, Series};
use admm_ta_agents::methods::Contender;
use admm_ta_agents::problem::cost_model::CostModel;
use admm_ta_agents::problem::{CaseChoice, TaskAssignmentProblem};
use admm_ta_runtime::options::SolveOptions;
use admm_ta_runtime::solve::error::SolveError;
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::TopologySpec;
use serde::Serialize;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Settings of the experiment.
#[derive(Debug, Clone)]
pub struct AnatomyConfig {
    pub robots: usize,
    pub tasks: usize,
    pub seeds: u64,
    pub contenders: Vec<Contender>,
    pub cost_models: Vec<CostModel>,
    pub topologies: Vec<String>,
    pub max_iters: usize,
    pub threads: usize,
}

impl AnatomyConfig {
    /// 50 robots × 30 tasks, 5 seeds, every method, both cost models, complete /
    /// random:0.1 / chain / ring / geometric:0.3 graphs, 5000 rounds.
    pub fn full() -> Self {
        Self {
            robots: 50,
            tasks: 30,
            seeds: 5,
            contenders: Contender::all(),
            cost_models: CostModel::ALL.to_vec(),
            topologies: ["complete", "random:0.1", "chain", "ring", "geometric:0.3"]
                .map(String::from)
                .to_vec(),
            max_iters: 5000,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }

    /// `--quick`: 12 robots × 8 tasks, 2 seeds, 2000 rounds.
    pub fn quick() -> Self {
        Self {
            robots: 12,
            tasks: 8,
            seeds: 2,
            max_iters: 2000,
            ..Self::full()
        }
    }
}

/// One run's rounds to each criterion (`None`: never within the limit).
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    pub seed: u64,
    pub relaxed_within_0_1pct: Option<usize>,
    pub decisions_within_0_1pct: Option<usize>,
    pub optimal_decisions_from: Option<usize>,
    pub certified_stop: Option<usize>,
    pub optimal_at_stop: bool,
    /// Wall time of the solve (lockstep simulation), milliseconds.
    pub wall_ms: f64,
}

/// One method on one cost model and graph.
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    pub contender: Contender,
    pub name: String,
    pub cost_model: CostModel,
    pub topology: String,
    pub relaxed_within_0_1pct: Option<f64>,
    pub decisions_within_0_1pct: Option<f64>,
    pub optimal_decisions_from: Option<f64>,
    pub certified_stop: Option<f64>,
    /// Certified stops whose assignment was not optimal.
    pub wrong_stops: usize,
    pub runs: Vec<Run>,
}

/// The whole experiment.
#[derive(Debug, Clone, Serialize)]
pub struct Anatomy {
    pub robots: usize,
    pub tasks: usize,
    pub seeds: u64,
    pub max_iters: usize,
    pub cells: Vec<Cell>,
}

/// Median of the values, `None` ("never") when more than half are `None`.
pub fn median(values: impl Iterator<Item = Option<usize>>) -> Option<f64> {
    let mut v: Vec<f64> = values
        .map(|x| x.map_or(f64::INFINITY, |x| x as f64))
        .collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let k = v.len();
    let m = if k % 2 == 1 {
        v[k / 2]
    } else {
        0.5 * (v[k / 2 - 1] + v[k / 2])
    };
    m.is_finite().then_some(m)
}

type Job = (Contender, CostModel, usize, u64);

fn run_one(job: &Job, config: &AnatomyConfig) -> Result<Run, SolveError> {
    let (contender, model, topology, seed) = *job;
    let costs = model
        .costs(config.robots, config.tasks, seed)
        .expect("valid size");
    let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).expect("valid problem");
    let spec: TopologySpec = config.topologies[topology]
        .parse()
        .expect("checked topology");
    let graph = spec
        .build(config.robots, seed)
        .expect("generated topologies are connected");
    let options = SolveOptions::builder()
        .method(contender.method)
        .settings(contender.settings())
        .seed(seed)
        .check(true)
        .max_iters(config.max_iters)
        .build()?;
    let report = solve(&problem, &graph, &options)?;
    let check = report.check.expect("checked run");
    Ok(Run {
        seed,
        relaxed_within_0_1pct: check.rounds_within_0_1pct,
        decisions_within_0_1pct: check.rounds_decisions_within_0_1pct,
        optimal_decisions_from: check.rounds_to_optimal_assignment,
        certified_stop: report.converged.then_some(report.iterations),
        optimal_at_stop: check.optimal,
        wall_ms: report.wall_time_ms,
    })
}

/// Runs the experiment; `progress(done, total)` after every run.
pub fn run(
    config: &AnatomyConfig,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Anatomy, SolveError> {
    let mut jobs: Vec<Job> = Vec::new();
    for &contender in &config.contenders {
        for &model in &config.cost_models {
            for topology in 0..config.topologies.len() {
                for seed in 1..=config.seeds {
                    jobs.push((contender, model, topology, seed));
                }
            }
        }
    }
    let results: Mutex<Vec<Option<Result<Run, SolveError>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    let (next, done) = (AtomicUsize::new(0), AtomicUsize::new(0));
    std::thread::scope(|scope| {
        for _ in 0..config.threads.max(1) {
            scope.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(job) = jobs.get(k) else {
                        break;
                    };
                    let outcome = run_one(job, config);
                    results.lock().expect("no panics while holding it")[k] = Some(outcome);
                    progress(done.fetch_add(1, Ordering::Relaxed) + 1, jobs.len());
                }
            });
        }
    });
    let mut results = results.into_inner().expect("no panics while holding it");
    let mut cells = Vec::new();
    let per_cell = config.seeds as usize;
    for (chunk, first) in jobs.chunks(per_cell).zip((0..).step_by(per_cell)) {
        let (contender, model, topology, _) = chunk[0];
        let runs = (first..first + chunk.len())
            .map(|k| results[k].take().expect("every job ran"))
            .collect::<Result<Vec<Run>, _>>()?;
        cells.push(Cell {
            contender,
            name: contender.label(),
            cost_model: model,
            topology: config.topologies[topology].clone(),
            relaxed_within_0_1pct: median(runs.iter().map(|r| r.relaxed_within_0_1pct)),
            decisions_within_0_1pct: median(runs.iter().map(|r| r.decisions_within_0_1pct)),
            optimal_decisions_from: median(runs.iter().map(|r| r.optimal_decisions_from)),
            certified_stop: median(runs.iter().map(|r| r.certified_stop)),
            wrong_stops: runs
                .iter()
                .filter(|r| r.certified_stop.is_some() && !r.optimal_at_stop)
                .count(),
            runs,
        });
    }
    Ok(Anatomy {
        robots: config.robots,
        tasks: config.tasks,
        seeds: config.seeds,
        max_iters: config.max_iters,
        cells,
    })
}

fn cell(value: Option<f64>) -> String {
    value.map_or_else(|| "never".to_string(), |v| format!("{v:.1}"))
}

impl Experiment for Anatomy {
    fn json_file(&self) -> &'static str {
        "rounds_anatomy.json"
    }

    /// A Markdown table, one line per method, cost model and graph.
    fn render(&self) -> String {
        let mut out = format!(
            "Rounds anatomy: {} robots × {} tasks, medians over {} seeds, limit {} rounds\n\n",
            self.robots, self.tasks, self.seeds, self.max_iters
        );
        out += "| method | costs | graph | (a) relaxed ≤0.1% | (a') decisions ≤0.1% | (b) decisions optimal | (c) certified stop | wrong stops |\n";
        out += "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
        for c in &self.cells {
            out += &format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
                c.name,
                c.cost_model.name(),
                c.topology,
                cell(c.relaxed_within_0_1pct),
                cell(c.decisions_within_0_1pct),
                cell(c.optimal_decisions_from),
                cell(c.certified_stop),
                c.wrong_stops
            );
        }
        out
    }

    /// One chart per cost model: median rounds to the certified stop per graph.
    fn files(&self) -> Vec<(String, OutputFile)> {
        let mut topologies: Vec<&str> = Vec::new();
        for c in &self.cells {
            if !topologies.contains(&c.topology.as_str()) {
                topologies.push(&c.topology);
            }
        }
        let mut files = Vec::new();
        for model in CostModel::ALL {
            let x_label = topologies
                .iter()
                .enumerate()
                .map(|(k, t)| format!("{} {t}", k + 1))
                .collect::<Vec<_>>()
                .join(", ");
            let mut chart = Chart::new(
                format!("Rounds to the certified stop, {} costs", model.name()),
                format!("graph: {x_label}"),
                "median rounds",
            )
            .y_scale(Scale::Log);
            let mut names: Vec<String> = Vec::new();
            for c in self.cells.iter().filter(|c| c.cost_model == model) {
                if !names.contains(&c.name) {
                    names.push(c.name.clone());
                }
            }
            for name in names {
                let points = self
                    .cells
                    .iter()
                    .filter(|c| c.cost_model == model && c.name == name)
                    .filter_map(|c| {
                        let x = topologies.iter().position(|t| *t == c.topology)? + 1;
                        Some((x as f64, c.certified_stop?))
                    })
                    .collect();
                chart = chart.series(Series::new(name, points));
            }
            files.push((
                format!("rounds_anatomy_{}.svg", model.name()),
                OutputFile::Chart(chart),
            ));
        }
        files
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_say_never_when_most_runs_never_reach() {
        assert_eq!(median([Some(3), None, Some(5)].into_iter()), Some(5.0));
        assert_eq!(median([Some(3), None, None].into_iter()), None);
        assert_eq!(median([Some(2), Some(4)].into_iter()), Some(3.0));
    }

    #[test]
    fn a_tiny_anatomy_has_a_cell_per_method_model_and_graph() {
        let config = AnatomyConfig {
            robots: 5,
            tasks: 4,
            seeds: 1,
            contenders: Contender::all()[..2].to_vec(),
            topologies: vec!["complete".into(), "chain".into()],
            max_iters: 1000,
            threads: 2,
            ..AnatomyConfig::quick()
        };
        let anatomy = run(&config, &|_, _| {}).unwrap();
        assert_eq!(anatomy.cells.len(), 2 * 2 * 2);
        for c in &anatomy.cells {
            assert_eq!(c.wrong_stops, 0);
            assert!(c.certified_stop.is_some(), "{} {}", c.name, c.topology);
        }
        assert!(
            anatomy
                .render()
                .contains("| primal (fast) | geometric | chain |")
        );
        assert_eq!(anatomy.files().len(), 2);
    }
}
