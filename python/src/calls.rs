//! How a call that runs a team waits: without the interpreter, with the library's signal
//! handlers installed, Python's handlers back (and the signal raised again) when it returns.

use admm_ta::transport::signals;
use pyo3::prelude::*;
use std::time::Duration;

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
pub(crate) fn with_signals<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
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

/// Runs `f` on this thread without the interpreter, with the library's signal handlers
/// installed: a SIGINT, SIGTERM or SIGHUP stops the robot's team cleanly; when the call
/// returns, Python's handlers are back and the signal is raised again (Ctrl-C:
/// `KeyboardInterrupt`). Signals Python handles itself run their handlers after the call.
pub(crate) fn in_team<T>(py: Python<'_>, f: impl FnOnce() -> T) -> PyResult<T> {
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
