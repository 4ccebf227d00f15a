//! scipy's `linear_sum_assignment` on the library's exact solver, and the cost matrix as
//! scipy makes it from any Python object (also [`crate::solve`]'s given costs).

use admm_ta::agents::numerics::lsap::{LsapError, ScipyLsap};
use numpy::npyffi::{NPY_ARRAY_DEFAULT, NPY_TYPES, PY_ARRAY_API};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::ffi::c_int;

/// `obj` as scipy makes its cost matrix: `PyArray_ContiguousFromAny(obj, NPY_DOUBLE, 0, 0)`
/// (numpy's own conversion: an array is cast safely, a `TypeError` for object or complex
/// data; a list element by element, a `ValueError` for a string that is not a number), then
/// scipy's check that it is a matrix.
pub(crate) fn cost_matrix<'py>(
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
pub(crate) fn linear_sum_assignment<'py>(
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
