//! `admm_ta._core`: the Rust side of the Python package `admm_ta` (the package's
//! `__init__.py` is the public face; these functions take what it has already checked and
//! converted).
//!
//! * `lsap::linear_sum_assignment`: scipy's centralized call, on the library's exact solver,
//!   with the interpreter released while it runs.
//! * `solve::solve`: `admm_ta.solve` on the library — its keyword arguments as the library's
//!   solve request, its report as a `solve::Report` read field by field; returns the exit
//!   code the command line would give, the report and the message.
//! * `member::TeamMember`: one robot of a standing team that keeps its own costs.
//! * `main`: the whole command line (`python -m admm_ta`, the `admm-ta` script, and the
//!   agent processes of a process transport, started as `python -c` with it).
//!
//! Termination signals: while a call runs a team, SIGINT, SIGTERM and SIGHUP are recorded by
//! the library's handlers (the team stops cleanly, agent processes are reaped and shared
//! memory is released); when the call returns, Python's handlers come back and the signal
//! is raised again, so Python sees it as it would have: Ctrl-C is a `KeyboardInterrupt`.

use admm_ta::command_line as cli;
use admm_ta::command_line::commands::shared::set_agent_program;
use admm_ta::runtime::options::run::AgentProgram;
use admm_ta::transport::signals;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use std::path::PathBuf;

mod calls;
mod lsap;
mod member;
mod solve;

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

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Structured logs when `RUST_LOG` asks for them (docs/command-line.md, "Logs"); a bad filter is
    // ignored here: importing the package must not fail over it.
    let _ = admm_ta::transport::logging::init(None);
    m.add_function(wrap_pyfunction!(lsap::linear_sum_assignment, m)?)?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_class::<solve::Report>()?;
    m.add_function(wrap_pyfunction!(main, m)?)?;
    m.add_function(wrap_pyfunction!(set_agent_command, m)?)?;
    m.add_class::<member::TeamMember>()?;
    m.add("LeaveRefused", m.py().get_type::<member::LeaveRefused>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
