//! `admm_ta.solve` on the library: its keyword arguments become the library's
//! [`SolveRequest`] (costs, graph, the options given), the report comes back as a
//! [`Report`] whose fields Python reads — no command line and no JSON text in between.
//! Options are named as the command line names them (`max_iters=` is `--max-iters`), and a
//! bad one is refused in the command line's words.

use admm_ta::agents::method::settings::{GivenSettings, SettingKind, SettingValue};
use admm_ta::command_line::Outcome;
use admm_ta::command_line::cli::Delimiter;
use admm_ta::command_line::commands::shared::agent_program;
use admm_ta::command_line::exit::code_of;
use admm_ta::request::{CostSource, GivenOptions, RequestError, SolveRequest, TopologySource};
use admm_ta::{CostMatrix, Graph, Method, SolveOptions, SolveOptionsBuilder, SolveReport};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The keyword arguments not taken yet, by name.
struct Kwargs<'py> {
    values: BTreeMap<String, Bound<'py, PyAny>>,
}

/// `name` as the command line spells it: `max_iters` is `--max-iters`.
fn flag(name: &str) -> String {
    format!("--{}", name.replace('_', "-"))
}

fn refused(text: String) -> anyhow::Error {
    RequestError(text).into()
}

impl<'py> Kwargs<'py> {
    fn new(options: &Bound<'py, PyDict>) -> PyResult<Self> {
        let mut values = BTreeMap::new();
        for (name, value) in options.iter() {
            values.insert(name.extract::<String>()?, value);
        }
        Ok(Self { values })
    }

    /// A switch: `True` sets it, `False` and `None` leave it out.
    fn switch(&mut self, name: &str) -> anyhow::Result<bool> {
        match self.values.remove(name) {
            None => Ok(false),
            Some(value) if value.is_none() => Ok(false),
            Some(value) => match value.extract::<bool>() {
                Ok(on) => Ok(on),
                Err(_) => Err(refused(format!(
                    "unexpected value '{}' for '{}': it takes True or False",
                    text_of(&value)?,
                    flag(name)
                ))),
            },
        }
    }

    /// An option's value as text (a path-like as its path); `None` and `False` leave it out.
    fn text(&mut self, name: &str) -> anyhow::Result<Option<String>> {
        let Some(value) = self.values.remove(name) else {
            return Ok(None);
        };
        if value.is_none() || value.extract::<bool>().is_ok_and(|on| !on) {
            return Ok(None);
        }
        if value.extract::<bool>().is_ok() {
            return Err(refused(format!(
                "a value is required for '{}' but none was supplied",
                flag(name)
            )));
        }
        Ok(Some(text_of(&value)?))
    }

    /// An option parsed as `T` (a number).
    fn number<T: std::str::FromStr>(&mut self, name: &str) -> anyhow::Result<Option<T>>
    where
        T::Err: std::fmt::Display,
    {
        self.text(name)?
            .map(|text| {
                text.parse::<T>().map_err(|e| {
                    refused(format!("invalid value '{text}' for '{}': {e}", flag(name)))
                })
            })
            .transpose()
    }

    /// An option that is one of the names of `T`.
    fn choice<T: clap::ValueEnum>(&mut self, name: &str) -> anyhow::Result<Option<T>> {
        self.text(name)?
            .map(|text| {
                T::from_str(&text, false).map_err(|_| {
                    let names: Vec<String> = T::value_variants()
                        .iter()
                        .filter_map(|v| v.to_possible_value())
                        .map(|v| v.get_name().to_string())
                        .collect();
                    refused(format!(
                        "invalid value '{text}' for '{}' [possible values: {}]",
                        flag(name),
                        names.join(", ")
                    ))
                })
            })
            .transpose()
    }

    /// Refuses what is left: no option of `admm-ta solve` has that name.
    fn finish(self) -> anyhow::Result<()> {
        match self.values.keys().next() {
            None => Ok(()),
            Some(name) => Err(refused(format!(
                "unexpected argument '{}' found ({name}=): not an option of `admm-ta solve`",
                flag(name)
            ))),
        }
    }
}

/// `str(value)`, or a path-like's path.
fn text_of(value: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(path) = value.extract::<PathBuf>() {
        return Ok(path.to_string_lossy().into_owned());
    }
    Ok(value.str()?.to_string())
}

/// The costs as the keyword arguments give them: the matrix, the cost file, or random costs
/// (`robots`, `tasks`, `cost_model`).
fn costs_of(
    kwargs: &mut Kwargs<'_>,
    matrix: Option<CostMatrix>,
    file: Option<PathBuf>,
) -> anyhow::Result<CostSource> {
    let robots = kwargs.number::<usize>("robots")?;
    let tasks = kwargs.number::<usize>("tasks")?;
    let model = kwargs.choice("cost_model")?;
    let delimiter: Option<Delimiter> = kwargs.choice("delimiter")?;
    let given = matrix.is_some() || file.is_some();
    if given && (robots.is_some() || tasks.is_some()) {
        return Err(refused(
            "the costs are given already: no --costs, --robots or --tasks with them".into(),
        ));
    }
    if given && model.is_some() {
        return Err(refused(
            "--cost-model draws random costs: not with the costs given".into(),
        ));
    }
    if delimiter.is_some() && file.is_none() {
        return Err(refused("--delimiter is for a cost file".into()));
    }
    Ok(match (matrix, file, robots, tasks) {
        (Some(costs), ..) => CostSource::Given(costs),
        (None, Some(path), ..) => CostSource::File {
            path,
            delimiter: delimiter.map(|d| d.byte()),
        },
        (None, None, Some(robots), Some(tasks)) => CostSource::Random {
            robots,
            tasks,
            model: model.unwrap_or_default(),
        },
        (None, None, Some(_), None) => {
            return Err(refused("--robots needs --tasks".into()));
        }
        (None, None, None, Some(_)) => {
            return Err(refused("--tasks needs --robots".into()));
        }
        _ => CostSource::Missing,
    })
}

/// The methods' own settings given (`dual_variant=` is `--dual-variant`).
fn settings_of(kwargs: &mut Kwargs<'_>) -> anyhow::Result<GivenSettings> {
    let mut given = GivenSettings::default();
    for spec in Method::all_settings() {
        let name = spec.flag.trim_start_matches("--").replace('-', "_");
        let value = match spec.kind {
            SettingKind::PositiveNumber { .. } => {
                kwargs.number::<f64>(&name)?.map(SettingValue::Number)
            }
            SettingKind::Choice(names) => match kwargs.text(&name)? {
                Some(text) if names().contains(&text.as_str()) => Some(SettingValue::Name(text)),
                Some(text) => {
                    return Err(refused(format!(
                        "invalid value '{text}' for '{}' [possible values: {}]",
                        spec.flag,
                        names().join(", ")
                    )));
                }
                None => None,
            },
        };
        if let Some(value) = value {
            given = given.set(spec, value);
        }
    }
    Ok(given)
}

/// The solve options the keyword arguments give, as the command line sets its flags (a
/// switch set to `False` is not given, as a flag left out).
fn options_of(kwargs: &mut Kwargs<'_>) -> anyhow::Result<SolveOptionsBuilder> {
    let options = SolveOptions::builder()
        .method(kwargs.choice("method")?.unwrap_or_default())
        .transport(kwargs.choice("transport")?.unwrap_or_default())
        .check(kwargs.switch("check")?)
        .settings(settings_of(kwargs)?)
        .agent_program(agent_program()?)
        .fault_injection(true);
    let given = GivenOptions {
        rho: kwargs.text("rho")?,
        adaptive_rho: kwargs.switch("adaptive_rho")?.then_some(true),
        max_iters: kwargs.number("max_iters")?,
        stop: kwargs.choice("stop")?,
        stop_rounds: kwargs.number("stop_rounds")?,
        perturb: kwargs.text("perturb")?,
        trace: kwargs.switch("trace")?.then_some(true),
        global_barrier: kwargs.switch("global_barrier")?.then_some(true),
        round_timeout: kwargs.number("round_timeout")?,
        startup_timeout: kwargs.number("startup_timeout")?,
        on_failure: kwargs.choice("on_failure")?,
        wait: kwargs.choice("wait")?,
    };
    Ok(given.apply(options)?)
}

/// The request of `admm_ta.solve`'s arguments: the cost matrix or cost file, the graph as
/// `(robots, edges)` or the topology's name, and the options by name.
fn request_of(
    matrix: Option<CostMatrix>,
    file: Option<PathBuf>,
    graph: Option<Graph>,
    options: &Bound<'_, PyDict>,
) -> anyhow::Result<SolveRequest> {
    let mut kwargs = Kwargs::new(options)?;
    let costs = costs_of(&mut kwargs, matrix, file)?;
    let topology = match (graph, kwargs.text("topology")?) {
        (Some(graph), None) => TopologySource::Given(graph),
        (Some(_), Some(_)) => {
            return Err(refused(
                "the graph is given already: no --topology with it".into(),
            ));
        }
        (None, name) => TopologySource::Named(name.unwrap_or_else(|| "complete".into())),
    };
    let trace = kwargs
        .values
        .get("trace")
        .is_some_and(|v| v.is_truthy().unwrap_or(false));
    let check = kwargs
        .values
        .get("check")
        .is_some_and(|v| v.is_truthy().unwrap_or(false));
    if trace && !check {
        return Err(refused("--trace needs --check".into()));
    }
    let request = SolveRequest {
        costs,
        forbidden: kwargs.text("forbidden")?.map(PathBuf::from),
        maximize: kwargs.switch("maximize")?,
        case: kwargs.choice("case")?.unwrap_or_default(),
        seed: kwargs.number("seed")?.unwrap_or(0),
        topology,
        options: options_of(&mut kwargs)?,
        timeline: kwargs.text("timeline")?.map(PathBuf::from),
    };
    kwargs.finish()?;
    Ok(request)
}

/// A solve's report, read field by field from Python (`admm_ta.SolveResult` wraps it).
#[pyclass(name = "Report", module = "admm_ta._core", frozen)]
pub struct Report(SolveReport);

#[pymethods]
impl Report {
    /// Robot `i`'s task, `None` for an idle robot.
    #[getter]
    fn assignment(&self) -> Vec<Option<usize>> {
        let idle = admm_ta::agents::problem::IDLE;
        self.0
            .assignment
            .iter()
            .map(|&task| (task != idle).then_some(task))
            .collect()
    }
    #[getter]
    fn cost(&self) -> f64 {
        self.0.cost
    }
    #[getter]
    fn certified(&self) -> bool {
        self.0.certified
    }
    #[getter]
    fn converged(&self) -> bool {
        self.0.converged
    }
    #[getter]
    fn iterations(&self) -> usize {
        self.0.iterations
    }
    #[getter]
    fn stop(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        python_of(py, &self.0.stop)
    }
    #[getter]
    fn method(&self) -> &'static str {
        self.0.method.name()
    }
    #[getter]
    fn transport(&self) -> &'static str {
        self.0.transport.name()
    }
    #[getter]
    fn bytes_per_agent(&self) -> usize {
        self.0.bytes_per_agent
    }
    #[getter]
    fn wall_time_ms(&self) -> f64 {
        self.0.wall_time_ms
    }
    #[getter]
    fn round_latency_us(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        python_of(py, &self.0.round_latency_us)
    }
    #[getter]
    fn critical_path(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        python_of(py, &self.0.critical_path)
    }
    /// `check=True`: whether the centralized optimum agrees; else `None`.
    #[getter]
    fn optimal(&self) -> Option<bool> {
        self.0.check.as_ref().map(|c| c.optimal)
    }
    /// The report as `admm-ta solve --json` prints it, as Python values (a new copy).
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        python_of(py, &self.0)
    }
}

/// `value` as Python values: its serde form (what `--json` prints) with objects as dicts,
/// arrays as lists, integers as ints.
fn python_of(py: Python<'_>, value: &impl serde::Serialize) -> PyResult<Py<PyAny>> {
    let value = serde_json::to_value(value)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    python_value(py, &value)
}

fn python_value(py: Python<'_>, value: &serde_json::Value) -> PyResult<Py<PyAny>> {
    use serde_json::Value;
    Ok(match value {
        Value::Null => py.None(),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any().unbind(),
        Value::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.into_pyobject(py)?.into_any().unbind(),
            (None, Some(i)) => i.into_pyobject(py)?.into_any().unbind(),
            _ => n
                .as_f64()
                .unwrap_or(f64::NAN)
                .into_pyobject(py)?
                .into_any()
                .unbind(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any().unbind(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(python_value(py, item)?)?;
            }
            list.into_any().unbind()
        }
        Value::Object(fields) => {
            let dict = PyDict::new(py);
            for (key, item) in fields {
                dict.set_item(key, python_value(py, item)?)?;
            }
            dict.into_any().unbind()
        }
    })
}

/// `admm_ta.solve`: the costs as an array-like (converted as `linear_sum_assignment`
/// converts it) or the path of a cost file, the graph as `(robots, edges)` or `None`, and
/// the other options by name. Returns `(exit code, report or None, message)` — the command
/// line's exit code and one-line message for what it would refuse or fail on: code 0 with
/// the report; 5 (not certified) and 6 (not optimal) with the report and the reason.
#[pyfunction]
#[pyo3(signature = (cost, costs_file, graph, options))]
pub fn solve<'py>(
    py: Python<'py>,
    cost: Option<&Bound<'py, PyAny>>,
    costs_file: Option<PathBuf>,
    graph: Option<(usize, Vec<(usize, usize)>)>,
    options: &Bound<'py, PyDict>,
) -> PyResult<(u8, Option<Report>, String)> {
    let failed = |error: anyhow::Error| (code_of(&error), None, format!("{error:#}"));
    let matrix = match cost {
        None => None,
        Some(cost) => {
            let matrix = crate::lsap::cost_matrix(py, cost)?.readonly();
            let (rows, cols) = (matrix.shape()[0], matrix.shape()[1]);
            match CostMatrix::new(rows, cols, matrix.as_slice()?.to_vec()) {
                Ok(costs) => Some(costs),
                Err(e) => return Ok(failed(e.into())),
            }
        }
    };
    let graph = match graph {
        None => None,
        Some((robots, edges)) => match Graph::from_edges(robots, &edges, "edges") {
            Ok(graph) => Some(graph),
            Err(e) => return Ok((2, None, format!("graph: {e}"))),
        },
    };
    let request = match request_of(matrix, costs_file, graph, options) {
        Ok(request) => request,
        Err(error) => return Ok(failed(error)),
    };
    let result = crate::calls::with_signals(py, move || request.solve())?;
    Ok(match result {
        Ok(report) => {
            let outcome = Outcome::of(&report);
            (outcome.code(), Some(Report(report)), outcome_text(outcome))
        }
        Err(error) => failed(error),
    })
}

/// The message of a solve's outcome: none for a success; why a report is not the
/// certified optimum otherwise.
fn outcome_text(outcome: Outcome) -> String {
    match outcome {
        Outcome::Success => String::new(),
        Outcome::Uncertified => "the round limit ended the run before the team certified an \
             assignment (the best assignment found when the run stopped)"
            .into(),
        Outcome::NotOptimal => "the centralized check found the assignment NOT optimal".into(),
    }
}
