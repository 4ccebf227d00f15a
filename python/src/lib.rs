//! `admm_ta._core`: the Rust side of the Python package `admm_ta` (the package's
//! `__init__.py` is the public face; these functions take what it has already checked and
//! converted).
//!
//! * [`linear_sum_assignment`]: scipy's centralized call, on the library's exact solver,
//!   with the interpreter released while it runs.
//! * [`solve`]: `admm-ta solve` in this process, its costs and graph handed over as values;
//!   returns the exit code the command line would give, the JSON report and the message.
//! * [`main`]: the whole command line (`python -m admm_ta`, the `admm-ta` script, and the
//!   agent processes of a process transport, started as `python -c` with it).
//!
//! Termination signals: while a call runs a team, SIGINT, SIGTERM and SIGHUP are recorded by
//! the library's handlers (the team stops cleanly, agent processes are reaped and shared
//! memory is released); when the call returns, Python's handlers come back and the signal
//! is raised again, so Python sees it as it would have: Ctrl-C is a `KeyboardInterrupt`.

use admm_ta::agents::numerics::lsap::{LsapError, ScipyLsap};
use admm_ta::command_line::commands::shared::set_agent_program;
use admm_ta::command_line::{self as cli, GivenInput, Outcome};
use admm_ta::runtime::options::run::AgentProgram;
use admm_ta::runtime::process::member_error::MemberError;
use admm_ta::runtime::signals;
use admm_ta::runtime::standing::TeamMember as StandingMember;
use admm_ta::{CostMatrix, Graph};
use numpy::npyffi::{NPY_ARRAY_DEFAULT, NPY_TYPES, PY_ARRAY_API};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::ffi::c_int;
use std::path::PathBuf;
use std::time::Duration;

/// `obj` as scipy makes its cost matrix: `PyArray_ContiguousFromAny(obj, NPY_DOUBLE, 0, 0)`
/// (numpy's own conversion: an array is cast safely, a `TypeError` for object or complex
/// data; a list element by element, a `ValueError` for a string that is not a number), then
/// scipy's check that it is a matrix.
fn cost_matrix<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    // SAFETY: numpy's C API as scipy calls it; `PyArray_FromAny` steals the descriptor and
    // returns a new reference or NULL with the error set.
    let array = unsafe {
        let descr = PY_ARRAY_API.PyArray_DescrFromType(py, NPY_TYPES::NPY_DOUBLE as c_int);
        let ptr = PY_ARRAY_API.PyArray_FromAny(
            py,
            obj.as_ptr(),
            descr,
            0,
            0,
            NPY_ARRAY_DEFAULT,
            std::ptr::null_mut(),
        );
        Bound::from_owned_ptr_or_err(py, ptr)?
    };
    let array = array.cast_into::<PyArrayDyn<f64>>()?;
    if array.ndim() != 2 {
        return Err(PyValueError::new_err(format!(
            "expected a matrix (2-D array), got a {} array",
            array.ndim()
        )));
    }
    Ok(array)
}

/// `(row_ind, col_ind)`.
type Indices<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>);

thread_local! {
    /// Each thread's [`linear_sum_assignment`] memory.
    static SCRATCH: std::cell::RefCell<ScipyLsap> = std::cell::RefCell::default();
}

/// Matrices with more entries than this are solved with the interpreter released (a 64 × 64
/// matrix takes about 20 µs).
const RELEASE_ABOVE: usize = 4096;

/// Solve the linear sum assignment problem, as ``scipy.optimize.linear_sum_assignment``.
///
/// Parameters
/// ----------
/// cost_matrix : array_like
///     The cost matrix of the bipartite graph: any 2-D array-like of real numbers, square
///     or rectangular (``0 × k`` and ``k × 0`` too); ``inf`` marks a forbidden pair
///     (``-inf`` with ``maximize``).
/// maximize : bool (default: False)
///     Calculates a maximum weight matching if true.
///
/// Returns
/// -------
/// row_ind, col_ind : numpy.ndarray of int64
///     The optimal assignment, ``min(rows, cols)`` pairs with the rows sorted; its cost is
///     ``cost_matrix[row_ind, col_ind].sum()``.
///
/// Raises
/// ------
/// ValueError
///     Not a 2-D matrix; NaN or an infinity of the wrong sign ("matrix contains invalid
///     numeric entries"); no assignment avoids the forbidden pairs ("cost matrix is
///     infeasible"): scipy's exceptions and messages.
/// TypeError
///     Data numpy cannot cast safely to float64 (object or complex arrays).
///
/// The solver is the shortest augmenting path method scipy runs (Crouse 2016), step for
/// step, so ties resolve to scipy's assignment; the interpreter is released while it runs.
#[pyfunction]
#[pyo3(signature = (cost_matrix, maximize=None), text_signature = "(cost_matrix, maximize=False)")]
fn linear_sum_assignment<'py>(
    py: Python<'py>,
    cost_matrix: &Bound<'py, PyAny>,
    maximize: Option<&Bound<'py, PyAny>>,
) -> PyResult<Indices<'py>> {
    // Python's truth of any object, as scipy's `p` argument format takes it.
    let maximize = maximize
        .map(|m| m.is_truthy())
        .transpose()?
        .unwrap_or(false);
    let matrix = self::cost_matrix(py, cost_matrix)?;
    let (rows, cols) = (matrix.shape()[0], matrix.shape()[1]);
    // SAFETY: a C-contiguous float64 array (`NPY_ARRAY_DEFAULT`) that we hold; no Rust code
    // writes it. Like scipy, we read it with the interpreter released.
    let values = unsafe { matrix.as_slice()? };
    // This thread's solver memory, taken for the call (a call on another thread has its
    // own): no allocation once a matrix of this size was solved here.
    let mut scratch = SCRATCH.take();
    let solve = |scratch: &mut ScipyLsap| {
        scratch
            .solve(values, rows, cols, maximize)
            .map(|pairs| pairs.len())
    };
    // The interpreter is released for any matrix that takes more than microseconds;
    // releasing and taking it back would cost more than a tiny solve.
    let solved = if rows * cols > RELEASE_ABOVE {
        py.detach(|| solve(&mut scratch))
    } else {
        solve(&mut scratch)
    };
    let result = solved
        .map_err(|e| match e {
            LsapError::NonFinite(..) => {
                PyValueError::new_err("matrix contains invalid numeric entries")
            }
            LsapError::Infeasible => PyValueError::new_err("cost matrix is infeasible"),
            LsapError::Shape(..) => PyValueError::new_err(e.to_string()),
        })
        .map(|len| {
            // SAFETY: new arrays of `len` int64s, every entry written below.
            let (row_ind, col_ind) = unsafe {
                (
                    PyArray1::<i64>::new(py, [len], false),
                    PyArray1::<i64>::new(py, [len], false),
                )
            };
            // SAFETY: the new arrays are contiguous and nobody else holds them yet.
            let (rows_out, cols_out) = unsafe { (row_ind.as_slice_mut(), col_ind.as_slice_mut()) };
            let (rows_out, cols_out) =
                (rows_out.expect("contiguous"), cols_out.expect("contiguous"));
            let pairs = scratch.pairs();
            for (k, &(r, c)) in pairs.iter().enumerate() {
                rows_out[k] = r as i64;
                cols_out[k] = c as i64;
            }
            (row_ind, col_ind)
        });
    SCRATCH.set(scratch);
    result
}

/// How often the calling thread looks at Python's own pending signals while a team runs.
const PYTHON_SIGNAL_SLICE: Duration = Duration::from_millis(20);

/// Runs `f` (a team) on a worker thread with the library's signal handlers installed, while
/// the calling thread waits without the interpreter and looks at Python's pending signals
/// every [`PYTHON_SIGNAL_SLICE`]:
/// * SIGINT, SIGTERM, SIGHUP reach the library's handlers: the team stops cleanly; when the
///   last guard drops Python's handlers are back, the signal is raised again and Python's
///   handler takes over (Ctrl-C: `KeyboardInterrupt`);
/// * a signal Python handles itself (SIGALRM with a handler that raises, or
///   `_thread.interrupt_main()`) runs its handler here; if that raises, the team is stopped
///   as by SIGINT and the handler's exception is the call's.
fn with_signals<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    let guard = signals::install();
    let (value, raised) = std::thread::scope(|scope| {
        let (done, finished) = crossbeam::channel::bounded(1);
        let worker = scope.spawn(move || {
            let value = f();
            let _ = done.send(());
            value
        });
        let mut raised = None;
        // Until the worker is done (or gone: a panic, resumed below).
        while py.detach(|| finished.recv_timeout(PYTHON_SIGNAL_SLICE))
            == Err(crossbeam::channel::RecvTimeoutError::Timeout)
        {
            if raised.is_none()
                && let Err(error) = py.check_signals()
            {
                // Stop the team as a Ctrl-C would, then let the handler's exception out.
                signals::record(libc::SIGINT);
                raised = Some(error);
            }
        }
        let value = worker
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (value, raised)
    });
    // Python's handlers are back once the last guard drops.
    drop(guard);
    if let Some(error) = raised {
        return Err(error);
    }
    if let Some(signal) = signals::received() {
        // SAFETY: raising a signal in this process; Python's handler (or the default
        // action) is installed again.
        unsafe { libc::raise(signal) };
        py.check_signals()?;
    }
    Ok(value)
}

/// `admm-ta solve` with `argv` (the command line after `admm-ta solve`), the costs as an
/// array-like (converted as [`linear_sum_assignment`] converts it; `None`: `--costs` or
/// random costs in `argv`) and the
/// graph as `(robots, edges)` (or `None`: `--topology` in `argv`). Returns
/// `(exit code, JSON report or None, message)`: code 0 with the report; 5 (not
/// certified) and 6 (not optimal) with the report and the reason; any other code with
/// the command line's one-line error and no report.
#[pyfunction]
#[pyo3(signature = (argv, cost=None, graph=None))]
fn solve<'py>(
    py: Python<'py>,
    argv: Vec<String>,
    cost: Option<&Bound<'py, PyAny>>,
    graph: Option<(usize, Vec<(usize, usize)>)>,
) -> PyResult<(u8, Option<String>, String)> {
    let parsed = cli::parse(
        ["admm-ta".to_string(), "solve".to_string()]
            .into_iter()
            .chain(argv),
    );
    let (args, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(error) => return Ok((2, None, cli::one_line(&error))),
    };
    let cli::cli::Command::Solve(args) = args.command else {
        unreachable!("the command line starts with `solve`");
    };
    let costs = match cost {
        None => None,
        Some(cost) => {
            let matrix = cost_matrix(py, cost)?.readonly();
            let (rows, cols) = (matrix.shape()[0], matrix.shape()[1]);
            match CostMatrix::new(rows, cols, matrix.as_slice()?.to_vec()) {
                Ok(costs) => Some(costs),
                Err(e) => {
                    let error = anyhow::Error::from(e);
                    return Ok((cli::exit::code_of(&error), None, format!("{error:#}")));
                }
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
    let given = GivenInput { costs, graph };
    let matches = matches.subcommand_matches("solve").cloned();
    let result = with_signals(py, move || {
        cli::solve_report(&args, matches.as_ref(), given)
            .and_then(|report| Ok((Outcome::of(&report), serde_json::to_string(&report)?)))
    })?;
    Ok(match result {
        Ok((outcome, json)) => {
            let message = match outcome {
                Outcome::Success => String::new(),
                Outcome::Uncertified => {
                    "the round limit ended the run before the team certified an assignment \
                     (the best assignment found when the run stopped)"
                        .into()
                }
                Outcome::NotOptimal => {
                    "the centralized check found the assignment NOT optimal".into()
                }
            };
            (outcome.code(), Some(json), message)
        }
        Err(error) => (cli::exit::code_of(&error), None, format!("{error:#}")),
    })
}

/// The `admm-ta` command line in this process: `argv` with the program name first; returns
/// the exit code. A termination signal stops what runs (a team in this process too) and
/// gives the conventional 128 + signal, as the binary does; it is not raised again.
#[pyfunction]
fn main(py: Python<'_>, argv: Vec<String>) -> u8 {
    let _guard = signals::install();
    py.detach(move || cli::run(argv))
}

/// Agent processes of this process's teams start as `program ARGS… agent …` (the package
/// gives `sys.executable -c ...`, calling [`main`]).
#[pyfunction]
fn set_agent_command(program: PathBuf, args: Vec<String>) -> PyResult<()> {
    if program.as_os_str().is_empty() {
        return Err(PyTypeError::new_err("the agent program is empty"));
    }
    set_agent_program(AgentProgram::new(program, args));
    Ok(())
}

/// Runs `f` on this thread without the interpreter, with the library's signal handlers
/// installed: a SIGINT, SIGTERM or SIGHUP stops the robot's team cleanly; when the call
/// returns, Python's handlers are back and the signal is raised again (Ctrl-C:
/// `KeyboardInterrupt`). Signals Python handles itself run their handlers after the call.
fn in_team<T>(py: Python<'_>, f: impl FnOnce() -> T) -> PyResult<T> {
    /// `f` and its value stay on this thread: `detach` runs the closure here, without
    /// the interpreter (a standing team's member is not `Send`: its transport's ports are
    /// this thread's).
    struct OnThisThread<T>(T);
    // SAFETY: `Python::detach` runs its closure on the calling thread; nothing moves.
    unsafe impl<T> Send for OnThisThread<T> {}
    let guard = signals::install();
    let f = OnThisThread(f);
    let value = py.detach(move || {
        let f = f;
        OnThisThread((f.0)())
    });
    drop(guard);
    if let Some(signal) = signals::received() {
        // SAFETY: raising a signal in this process; Python's handler is installed again.
        unsafe { libc::raise(signal) };
        py.check_signals()?;
    }
    Ok(value.0)
}

pyo3::create_exception!(
    _core,
    LeaveRefused,
    PyRuntimeError,
    "A robot's leave refused: without it the rest of its team would fall apart. It stays in the team (it relayed in the episode of its leave) and may ask again."
);

/// A member's error as Python's: a refused leave is a `LeaveRefused`, another refusal (a
/// bad team file, a bad row) a `ValueError`, a failure of the team a `RuntimeError`.
fn member_error(error: MemberError) -> PyErr {
    if error
        .cause()
        .is::<admm_ta::runtime::standing::LeaveRefused>()
    {
        LeaveRefused::new_err(error.text())
    } else if error.is_refusal() {
        PyValueError::new_err(error.text())
    } else {
        PyRuntimeError::new_err(error.text())
    }
}

/// One robot of a standing team whose robots keep their own costs (a team file with
/// `costs = "private"`): see `admm_ta.TeamMember`.
#[pyclass(unsendable, module = "admm_ta._core")]
struct TeamMember {
    member: StandingMember,
}

impl TeamMember {
    fn member(&mut self) -> PyResult<&mut StandingMember> {
        Ok(&mut self.member)
    }
}

#[pymethods]
impl TeamMember {
    #[new]
    fn new(py: Python<'_>, team: PathBuf, robot: usize) -> PyResult<Self> {
        let member = in_team(py, || StandingMember::join(&team, robot))?.map_err(member_error)?;
        Ok(Self { member })
    }

    /// The episode's answer (JSON) for this robot's row (`None`: a forbidden task).
    fn assign(&mut self, py: Python<'_>, costs: Vec<Option<f64>>) -> PyResult<String> {
        let member = self.member()?;
        let answer = in_team(py, || member.assign(&costs))?.map_err(member_error)?;
        Ok(serde_json::to_string(&answer).expect("an answer serialises"))
    }

    /// An episode in which this robot takes no task and relays (JSON answer).
    fn unavailable(&mut self, py: Python<'_>) -> PyResult<String> {
        let member = self.member()?;
        let answer = in_team(py, || member.unavailable())?.map_err(member_error)?;
        Ok(serde_json::to_string(&answer).expect("an answer serialises"))
    }

    /// An episode without this robot's row (JSON answer).
    fn abstain(&mut self, py: Python<'_>) -> PyResult<String> {
        let member = self.member()?;
        let answer = in_team(py, || member.abstain())?.map_err(member_error)?;
        Ok(serde_json::to_string(&answer).expect("an answer serialises"))
    }

    /// Leaves the team at the next episode boundary (the team goes on without it); a
    /// refused leave raises `LeaveRefused` and the robot stays.
    fn leave(&mut self, py: Python<'_>) -> PyResult<()> {
        let member = self.member()?;
        in_team(py, || member.leave())?.map_err(member_error)
    }

    /// The episode this robot answers next.
    #[getter]
    fn episode(&mut self) -> PyResult<u64> {
        Ok(self.member()?.episode())
    }

    /// The robots that take part now.
    #[getter]
    fn roster(&mut self) -> PyResult<Vec<usize>> {
        Ok(self.member()?.roster())
    }

    #[getter]
    fn robot(&mut self) -> PyResult<usize> {
        Ok(self.member()?.id())
    }

    #[getter]
    fn robots(&mut self) -> PyResult<usize> {
        Ok(self.member()?.robots())
    }

    #[getter]
    fn tasks(&mut self) -> PyResult<usize> {
        Ok(self.member()?.tasks())
    }

    #[getter]
    fn maximize(&mut self) -> PyResult<bool> {
        Ok(self.member()?.maximize())
    }
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Structured logs when `RUST_LOG` asks for them (docs/command-line.md, "Logs"); a bad filter is
    // ignored here: importing the package must not fail over it.
    let _ = admm_ta::runtime::logging::init(None);
    m.add_function(wrap_pyfunction!(linear_sum_assignment, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(main, m)?)?;
    m.add_function(wrap_pyfunction!(set_agent_command, m)?)?;
    m.add_class::<TeamMember>()?;
    m.add("LeaveRefused", m.py().get_type::<LeaveRefused>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
