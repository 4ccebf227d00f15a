//! Every size certified (`admm-ta experiment size-sweep`): the primal method with the
//! defaults (fast variant, decentralized certified stop) on square problems of growing
//! size, per cost model and graph; per point the runs that certified, the runs whose
//! certified assignment is the Hungarian optimum, the median and largest rounds to the stop
//! and the median wall time of the lockstep simulation. The target is every run
//! certified and optimal within the default round limit at every size up to 120×120; the
//! slow points are the chains (a 120-robot chain has diameter 119 and needs about four
//! diameters of rounds).

use crate::experiment::Experiment;
use crate::rounds_anatomy::{self, AnatomyConfig, median};
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::cost_model::CostModel;
use admm_ta_runtime::solve::error::SolveError;
use serde::Serialize;

/// Settings of the sweep.
#[derive(Debug, Clone)]
pub struct SweepConfig {
    /// Problem sizes `n` (n robots × n tasks).
    pub sizes: Vec<usize>,
    pub seeds: u64,
    pub cost_models: Vec<CostModel>,
    pub topologies: Vec<String>,
    pub max_iters: usize,
    pub threads: usize,
}

impl SweepConfig {
    /// 20, 50, 80, 120 robots, 3 seeds, both cost models, chain / ring / random:0.1 /
    /// complete graphs, the default limit of 5000 rounds.
    pub fn full() -> Self {
        Self {
            sizes: vec![20, 50, 80, 120],
            seeds: 3,
            cost_models: CostModel::ALL.to_vec(),
            topologies: ["chain", "ring", "random:0.1", "complete"]
                .map(String::from)
                .to_vec(),
            max_iters: 5000,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }

    /// `--quick`: 10 and 20 robots, 2 seeds.
    pub fn quick() -> Self {
        Self {
            sizes: vec![10, 20],
            seeds: 2,
            ..Self::full()
        }
    }
}

/// One size, cost model and graph.
#[derive(Debug, Clone, Serialize)]
pub struct Point {
    pub size: usize,
    pub cost_model: CostModel,
    pub topology: String,
    pub runs: usize,
    pub certified: usize,
    /// Certified runs whose assignment is the Hungarian optimum.
    pub optimal: usize,
    pub median_rounds: Option<f64>,
    pub max_rounds: Option<usize>,
    pub median_wall_s: Option<f64>,
}

/// The whole sweep.
#[derive(Debug, Clone, Serialize)]
pub struct SizeSweep {
    pub seeds: u64,
    pub max_iters: usize,
    pub points: Vec<Point>,
}

impl SizeSweep {
    /// Every run certified an optimal assignment.
    pub fn all_certified_optimal(&self) -> bool {
        self.points
            .iter()
            .all(|p| p.certified == p.runs && p.optimal == p.runs)
    }
}

/// Runs the sweep, smallest size first; `progress(size, done, total)` after every run.
pub fn run(
    config: &SweepConfig,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<SizeSweep, SolveError> {
    let mut points = Vec::new();
    for &size in &config.sizes {
        let anatomy = AnatomyConfig {
            robots: size,
            tasks: size,
            seeds: config.seeds,
            // The method `solve` runs by default, with its default settings.
            contenders: vec![Contender::of(Method::default())],
            cost_models: config.cost_models.clone(),
            topologies: config.topologies.clone(),
            max_iters: config.max_iters,
            threads: config.threads,
        };
        let report = rounds_anatomy::run(&anatomy, &|done, total| progress(size, done, total))?;
        for cell in report.cells {
            let runs = &cell.runs;
            let mut walls: Vec<f64> = runs.iter().map(|r| r.wall_ms / 1e3).collect();
            walls.sort_by(f64::total_cmp);
            points.push(Point {
                size,
                cost_model: cell.cost_model,
                topology: cell.topology,
                runs: runs.len(),
                certified: runs.iter().filter(|r| r.certified_stop.is_some()).count(),
                optimal: runs
                    .iter()
                    .filter(|r| r.certified_stop.is_some() && r.optimal_at_stop)
                    .count(),
                median_rounds: median(runs.iter().map(|r| r.certified_stop)),
                max_rounds: runs.iter().filter_map(|r| r.certified_stop).max(),
                median_wall_s: walls.get(walls.len() / 2).copied(),
            });
        }
    }
    Ok(SizeSweep {
        seeds: config.seeds,
        max_iters: config.max_iters,
        points,
    })
}

impl Experiment for SizeSweep {
    fn json_file(&self) -> &'static str {
        "size_sweep.json"
    }

    /// A Markdown table, one line per size, cost model and graph, and the verdict.
    fn render(&self) -> String {
        let mut out = format!(
            "Size sweep: primal (fast), n × n, {} seeds per point, limit {} rounds\n\n",
            self.seeds, self.max_iters
        );
        out += "| n | costs | graph | certified | optimal | median rounds | max rounds | median wall (s) |\n";
        out += "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
        let or_never = |v: Option<String>| v.unwrap_or_else(|| "never".to_string());
        for p in &self.points {
            out += &format!(
                "| {} | {} | {} | {}/{} | {}/{} | {} | {} | {} |\n",
                p.size,
                p.cost_model.name(),
                p.topology,
                p.certified,
                p.runs,
                p.optimal,
                p.runs,
                or_never(p.median_rounds.map(|r| format!("{r:.1}"))),
                or_never(p.max_rounds.map(|r| r.to_string())),
                or_never(p.median_wall_s.map(|w| format!("{w:.2}"))),
            );
        }
        out += if self.all_certified_optimal() {
            "\nEvery run certified the optimal assignment.\n"
        } else {
            "\nNOT every run certified the optimal assignment.\n"
        };
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_sweep_certifies_the_optimum_everywhere() {
        let config = SweepConfig {
            sizes: vec![6],
            seeds: 1,
            topologies: vec!["chain".into(), "complete".into()],
            threads: 2,
            ..SweepConfig::quick()
        };
        let sweep = run(&config, &|_, _, _| {}).unwrap();
        assert_eq!(sweep.points.len(), 2 * 2);
        assert!(sweep.all_certified_optimal(), "{}", sweep.render());
        assert!(
            sweep
                .render()
                .contains("| 6 | geometric | chain | 1/1 | 1/1 |")
        );
    }
}
