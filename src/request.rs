//! A solve as a front end asks for it: where the costs and the graph come from, the options
//! the user gave (only those: one the run never reads is refused), and where the timeline
//! goes. The command line builds one from its flags (`admm-ta solve`), the Python package
//! from `admm_ta.solve`'s keyword arguments; both get the same refusals, in the command
//! line's words, and the same [`SolveReport`].
//!
//! ```
//! use admm_ta::request::{CostSource, SolveRequest, TopologySource};
//! use admm_ta::{CostMatrix, SolveOptions};
//! let request = SolveRequest {
//!     costs: CostSource::Given(CostMatrix::uniform(4, 4, 1)?),
//!     topology: TopologySource::Named("ring".into()),
//!     options: SolveOptions::builder().check(true),
//!     ..SolveRequest::default()
//! };
//! let report = request.solve()?;
//! assert!(report.check.unwrap().optimal);
//! # Ok::<(), anyhow::Error>(())
//! ```

use crate::agents::problem::cost_model::CostModel;
use crate::agents::problem::{cost_file, forbidden, read_cost_text};
use crate::{
    CaseChoice, CostMatrix, Graph, Perturbation, SolveOptionsBuilder, SolveReport,
    TaskAssignmentProblem, TopologySpec,
};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// A request the user's input itself rules out (exit 2 on the command line, `ValueError`
/// in Python), in the command line's words.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct RequestError(pub String);

/// Where the costs come from.
#[derive(Debug, Clone, Default)]
pub enum CostSource {
    /// Values handed over (`+∞` marks a forbidden pair, `−∞` when maximizing).
    Given(CostMatrix),
    /// A cost file (`-`: standard input), with its delimiter when not detected.
    File {
        path: PathBuf,
        delimiter: Option<u8>,
    },
    /// Random costs of `model`, drawn from the request's seed.
    Random {
        robots: usize,
        tasks: usize,
        model: CostModel,
    },
    /// None was given: refused with the ways to give them.
    #[default]
    Missing,
}

/// Where the graph comes from.
#[derive(Debug, Clone)]
pub enum TopologySource {
    /// A graph handed over (checked connected and of the problem's size).
    Given(Graph),
    /// A generator or a topology file, as `--topology` names it.
    Named(String),
}

impl Default for TopologySource {
    fn default() -> Self {
        Self::Named("complete".into())
    }
}

/// A solve as a front end asks for it.
#[derive(Debug, Clone)]
pub struct SolveRequest {
    pub costs: CostSource,
    /// A file of forbidden robot–task pairs (`-`: standard input).
    pub forbidden: Option<PathBuf>,
    /// The costs are profits to maximize.
    pub maximize: bool,
    pub case: CaseChoice,
    /// Seed of random costs and random topologies (the options' seed is the solve's).
    pub seed: u64,
    pub topology: TopologySource,
    /// The options the user gave; [`SolveRequest::solve`] adds the seed, `timeline` and
    /// refuses any option the run never reads.
    pub options: SolveOptionsBuilder,
    /// Where the agents' rounds go as Chrome trace JSON.
    pub timeline: Option<PathBuf>,
}

impl Default for SolveRequest {
    /// No costs yet, the complete graph, the default options.
    fn default() -> Self {
        Self {
            costs: CostSource::Missing,
            forbidden: None,
            maximize: false,
            case: CaseChoice::Auto,
            seed: 0,
            topology: TopologySource::default(),
            options: crate::SolveOptions::builder(),
            timeline: None,
        }
    }
}

impl SolveRequest {
    /// The report of the solve this request asks for (the caller decides what it means:
    /// [`crate::command_line::Outcome::of`]).
    pub fn solve(self) -> Result<SolveReport> {
        let stdin = Path::new("-");
        if matches!(&self.costs, CostSource::File { path, .. } if path == stdin)
            && self.forbidden.as_deref() == Some(stdin)
        {
            return Err(RequestError(
                "--costs - and --forbidden - cannot both read standard input".into(),
            )
            .into());
        }
        let problem = self.problem()?;
        let graph = self.graph(&problem)?;
        let mut options = self.options.clone().refuse_unread(true).seed(self.seed);
        if self.timeline.is_some() {
            options = options.timeline(true);
        }
        let options = options.build()?;
        if let Some(path) = &self.timeline {
            // Refused before the run if it cannot be written.
            std::fs::File::create(path)
                .map_err(|e| RequestError(format!("--timeline {}: {e}", path.display())))?;
        }
        let report = crate::solve(&problem, &graph, &options)?;
        if let Some(path) = &self.timeline {
            let trace = crate::transport::timeline::chrome_trace(&graph, &report.timeline);
            std::fs::write(path, serde_json::to_vec(&trace)?)
                .with_context(|| format!("--timeline {}", path.display()))?;
        }
        Ok(report)
    }

    /// The problem: the given costs, the cost file (with its forbidden pairs and
    /// `--forbidden`'s) or random costs, minimized or maximized.
    fn problem(&self) -> Result<TaskAssignmentProblem> {
        // Pairs the cost file itself marks forbidden (JSON nulls).
        let mut marked = Vec::new();
        let costs = match &self.costs {
            CostSource::Given(costs) => costs.clone(),
            CostSource::File { path, delimiter } => {
                let file = cost_file::parse(&read_cost_text(path)?, *delimiter)?;
                marked = file.forbidden;
                file.costs
            }
            CostSource::Random {
                robots,
                tasks,
                model,
            } => model.costs(*robots, *tasks, self.seed)?,
            CostSource::Missing => {
                return Err(RequestError(
                    "give the costs with --costs FILE.csv, or --robots N --tasks M for random costs"
                        .into(),
                )
                .into());
            }
        };
        if let Some(path) = &self.forbidden {
            marked.extend(forbidden::read(path, &costs)?);
        }
        let costs = if marked.is_empty() {
            costs
        } else {
            forbidden::apply(&costs, &marked, self.maximize)?
        };
        Ok(if self.maximize {
            TaskAssignmentProblem::maximizing(costs, self.case)?
        } else {
            TaskAssignmentProblem::new(costs, self.case)?
        })
    }

    /// The graph: the given one (checked connected and of the problem's size) or the named
    /// topology.
    fn graph(&self, problem: &TaskAssignmentProblem) -> Result<Graph> {
        Ok(match &self.topology {
            TopologySource::Given(graph) if graph.robots() != problem.robots() => {
                return Err(RequestError(format!(
                    "the graph has {} robots but the costs have {}",
                    graph.robots(),
                    problem.robots()
                ))
                .into());
            }
            TopologySource::Given(graph) => {
                // Assumption 1 of the paper, as every generated or file topology is checked.
                graph.require_connected()?;
                graph.clone()
            }
            TopologySource::Named(name) => {
                let spec: TopologySpec = name.parse()?;
                spec.build_named(problem.robots(), self.seed, problem.costs().robot_names())
                    .with_context(|| format!("topology '{name}'"))?
            }
        })
    }
}

/// `--perturb`: `auto`, `off` (or 0) or a positive number ε.
pub fn parse_perturb(text: &str) -> Result<Perturbation, RequestError> {
    match text {
        "auto" => Ok(Perturbation::Auto),
        "off" | "0" => Ok(Perturbation::Off),
        value => match value.parse::<f64>() {
            Ok(eps) if eps > 0.0 && eps.is_finite() => Ok(Perturbation::Fixed(eps)),
            _ => Err(RequestError(format!(
                "--perturb must be auto, off or a positive number, got '{value}'"
            ))),
        },
    }
}

/// `--rho`: `auto` (None) or a number (the options check that it is a positive one).
pub fn parse_rho(text: &str) -> Result<Option<f64>, RequestError> {
    if text == "auto" {
        return Ok(None);
    }
    match text.parse::<f64>() {
        Ok(rho) => Ok(Some(rho)),
        Err(_) => Err(RequestError(format!(
            "--rho (ρ) must be auto or a positive number, got '{text}'"
        ))),
    }
}

/// The run options a front end was given, each `None` when not given (the options' default
/// then holds, and an option the run never reads is not refused): the command line fills it
/// from its flags, the Python package from `admm_ta.solve`'s keyword arguments, and both
/// apply it with [`GivenOptions::apply`].
#[derive(Debug, Clone, Default)]
pub struct GivenOptions {
    /// `--rho`: `auto` or a number.
    pub rho: Option<String>,
    pub adaptive_rho: Option<bool>,
    pub max_iters: Option<usize>,
    pub stop: Option<crate::StopRule>,
    pub stop_rounds: Option<usize>,
    /// `--perturb`: `auto`, `off` or a positive number.
    pub perturb: Option<String>,
    pub trace: Option<bool>,
    pub global_barrier: Option<bool>,
    pub round_timeout: Option<f64>,
    pub startup_timeout: Option<f64>,
    pub on_failure: Option<crate::OnFailure>,
    pub wait: Option<crate::WaitStrategy>,
}

impl GivenOptions {
    /// `options` with every given option set (the text ones parsed, refused in the command
    /// line's words).
    pub fn apply(
        self,
        mut options: SolveOptionsBuilder,
    ) -> Result<SolveOptionsBuilder, RequestError> {
        if let Some(rho) = self.rho {
            options = options.rho(parse_rho(&rho)?);
        }
        if let Some(perturb) = self.perturb {
            options = options.perturbation(parse_perturb(&perturb)?);
        }
        type Set<T> = fn(SolveOptionsBuilder, T) -> SolveOptionsBuilder;
        fn set<T>(
            options: SolveOptionsBuilder,
            value: Option<T>,
            set: Set<T>,
        ) -> SolveOptionsBuilder {
            match value {
                Some(value) => set(options, value),
                None => options,
            }
        }
        use SolveOptionsBuilder as B;
        options = set(options, self.adaptive_rho, B::adaptive_rho);
        options = set(options, self.max_iters, B::max_iters);
        options = set(options, self.stop, B::stop);
        options = set(options, self.stop_rounds, B::stop_rounds);
        options = set(options, self.trace, B::trace);
        options = set(options, self.global_barrier, B::global_barrier);
        options = set(options, self.round_timeout, B::round_timeout_secs);
        options = set(options, self.startup_timeout, B::startup_timeout_secs);
        options = set(options, self.on_failure, B::on_failure);
        options = set(options, self.wait, B::wait);
        Ok(options)
    }
}
