//! Every method side by side on the same problems, graphs and transports: rounds to its own
//! stop, optimality, messages and bytes per agent, wall time (`admm-ta experiment compare`).

use crate::experiment::Experiment;
use admm_ta_agents::method::settings::GivenSettings;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::cost_model::CostModel;
use admm_ta_agents::problem::{CaseChoice, TaskAssignmentProblem};
use admm_ta_runtime::options::SolveOptions;
use admm_ta_runtime::solve::error::SolveError;
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::TopologySpec;
use admm_ta_transport::{Execution, Transport};
use serde::Serialize;

/// Settings of the comparison.
#[derive(Debug, Clone)]
pub struct CompareConfig {
    pub robots: Vec<usize>,
    pub seeds: u64,
    pub methods: Vec<Method>,
    pub transports: Vec<Transport>,
    pub topology: TopologySpec,
    pub cost_model: CostModel,
    /// The methods' own settings (each method reads its own: `--primal-variant` the primal
    /// method's).
    pub settings: GivenSettings,
    /// `--adaptive-rho` for the methods whose settings follow a schedule (not the fast
    /// primal variant).
    pub adaptive_rho: bool,
    pub max_iters: usize,
    /// The `admm-ta` binary (ipc transport).
    pub agent_program: Option<admm_ta_runtime::options::run::AgentProgram>,
}

/// One method on one team size and transport, averaged over the seeds.
#[derive(Debug, Clone, Serialize)]
pub struct CompareRow {
    pub robots: usize,
    pub method: Method,
    pub transport: Transport,
    pub runs: usize,
    pub mean_rounds: f64,
    pub optimal_runs: usize,
    /// Mean of `(cost − optimum)/optimum`.
    pub mean_gap: f64,
    pub mean_bytes_per_agent: f64,
    pub mean_wall_time_ms: f64,
}

/// Every row of a comparison (written as a JSON array).
#[derive(Debug, Clone, Serialize)]
#[serde(transparent)]
pub struct Comparison {
    pub rows: Vec<CompareRow>,
}

impl Experiment for Comparison {
    fn json_file(&self) -> &'static str {
        "compare.json"
    }

    /// The Markdown table of every row.
    fn render(&self) -> String {
        let mut out = format!("{TABLE_HEADER}\n");
        for row in &self.rows {
            out += &render_row(row);
            out.push('\n');
        }
        out
    }
}

/// Whether `method` with its own of `settings` follows an `--adaptive-rho` schedule (the
/// experiments' `--adaptive-rho` applies to those only: the fast variants refuse it).
pub(crate) fn has_schedule(method: Method, settings: &GivenSettings) -> bool {
    method
        .setup(&settings.only(method.settings()))
        .ok()
        .flatten()
        .is_some_and(|setup| setup.schedule(1.0).is_some())
}

/// Runs every (size, method, transport) on `seeds` square problems of the cost model.
pub fn run(
    config: &CompareConfig,
    progress: &dyn Fn(&CompareRow),
) -> Result<Comparison, SolveError> {
    let mut rows = Vec::new();
    for &n in &config.robots {
        for &method in &config.methods {
            for &transport in &config.transports {
                // A centralized method runs on a lockstep transport only.
                if method.team().is_none()
                    && transport.capabilities().execution != Execution::Lockstep
                {
                    continue;
                }
                let mut row = CompareRow {
                    robots: n,
                    method,
                    transport,
                    runs: 0,
                    mean_rounds: 0.0,
                    optimal_runs: 0,
                    mean_gap: 0.0,
                    mean_bytes_per_agent: 0.0,
                    mean_wall_time_ms: 0.0,
                };
                for seed in 0..config.seeds {
                    let problem = TaskAssignmentProblem::new(
                        config.cost_model.costs(n, n, seed).expect("valid size"),
                        CaseChoice::Auto,
                    )
                    .expect("square problem");
                    let graph = config
                        .topology
                        .build(n, seed)
                        .map_err(|e| SolveError::Unsupported(format!("topology: {e}")))?;
                    let options = SolveOptions::builder()
                        .method(method)
                        .transport(transport)
                        .seed(seed)
                        .check(true)
                        .adaptive_rho(config.adaptive_rho && has_schedule(method, &config.settings))
                        .settings(config.settings.clone())
                        .max_iters(config.max_iters)
                        .agent_program(config.agent_program.clone())
                        .build()?;
                    let report = solve(&problem, &graph, &options)?;
                    let check = report.check.expect("checked run");
                    row.runs += 1;
                    row.mean_rounds += report.iterations as f64;
                    row.optimal_runs += usize::from(check.optimal);
                    row.mean_gap += check.gap;
                    row.mean_bytes_per_agent += report.bytes_per_agent as f64;
                    row.mean_wall_time_ms += report.wall_time_ms;
                }
                let runs = row.runs.max(1) as f64;
                row.mean_rounds /= runs;
                row.mean_gap /= runs;
                row.mean_bytes_per_agent /= runs;
                row.mean_wall_time_ms /= runs;
                progress(&row);
                rows.push(row);
            }
        }
    }
    Ok(Comparison { rows })
}

/// The header of the Markdown table [`render_row`] fills.
pub const TABLE_HEADER: &str = "| n | method | transport | rounds | optimal | gap | KiB / agent | wall ms |\n| --- | --- | --- | --- | --- | --- | --- | --- |";

/// One Markdown table line.
pub fn render_row(row: &CompareRow) -> String {
    format!(
        "| {} | {} | {} | {:.0} | {}/{} | {:.1}% | {:.1} | {:.0} |",
        row.robots,
        row.method.name(),
        row.transport.name(),
        row.mean_rounds,
        row.optimal_runs,
        row.runs,
        100.0 * row.mean_gap,
        row.mean_bytes_per_agent / 1024.0,
        row.mean_wall_time_ms
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_comparison_has_a_row_per_method() {
        let config = CompareConfig {
            robots: vec![5],
            seeds: 2,
            methods: vec![
                Method::Primal,
                Method::Cbaa,
                Method::Market,
                Method::DistHungarian,
                Method::Hungarian,
            ],
            transports: vec![Transport::Sim],
            topology: TopologySpec::Complete,
            cost_model: CostModel::Uniform,
            settings: GivenSettings::default(),
            adaptive_rho: false,
            max_iters: 2000,
            agent_program: None,
        };
        let comparison = run(&config, &|_| {}).unwrap();
        assert!(comparison.render().starts_with(TABLE_HEADER));
        let rows = comparison.rows;
        assert_eq!(rows.len(), 5);
        for row in &rows {
            assert_eq!(row.runs, 2);
            if row.method != Method::Cbaa {
                assert_eq!(row.optimal_runs, 2, "{:?}", row.method);
            }
            assert!(render_row(row).starts_with("| 5 |"));
        }
        let hungarian = rows.iter().find(|r| r.method == Method::Hungarian).unwrap();
        assert_eq!(hungarian.mean_rounds, 1.0);
        assert_eq!(hungarian.mean_bytes_per_agent, 0.0);
    }
}
