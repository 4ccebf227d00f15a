//! `admm_ta.TeamMember`: one robot of a standing team whose robots keep their own costs.

use crate::calls::in_team;
use admm_ta::runtime::process::member_error::MemberError;
use admm_ta::runtime::standing::TeamMember as StandingMember;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;

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
pub(crate) struct TeamMember {
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
