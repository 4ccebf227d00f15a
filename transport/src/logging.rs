//! Structured logs (the `tracing` ecosystem): quiet unless asked for. `RUST_LOG` (or the
//! command line's `--log FILTER`, which wins) turns on one line per event on standard error,
//! each carrying what it belongs to as span fields — `launcher{run=…}`,
//! `agent{run=… agent=3}`, `host{…}` — and events' own fields (`round=…`, `neighbours=…`).
//! Start-up phases, connections, the stop protocol, faults and failure detection log at
//! `debug`/`info`/`warn`; the rounds themselves only at `trace` (one line per round and
//! agent), so the hot loop costs one atomic load when logging is off.
//!
//! **Agent processes log to the launcher's standard error.** An agent's own standard error
//! is its private log file (read for the one line that names a failure); a launcher with
//! logging on hands its children its filter (`RUST_LOG`) and its standard error as a spare
//! descriptor ([`LOG_FD_ENV`]), where their log lines go, so one terminal shows every
//! process of the team. An independently started agent logs to its own standard error.

use std::os::fd::RawFd;
use std::sync::OnceLock;

/// The environment variable naming the descriptor a launched agent writes its log lines to.
pub const LOG_FD_ENV: &str = "ADMM_TA_LOG_FD";

/// The descriptor the launcher gives its agents for log lines (a dup of its stderr).
pub const CHILD_LOG_FD: RawFd = 3;

/// The filter of this process's logs, once they are on.
static FILTER: OnceLock<String> = OnceLock::new();

/// Turns logs on if `filter` (the `--log` flag) or `RUST_LOG` asks for them; a filter that
/// does not parse is refused (returned) and logs stay off. Called once, first thing; later
/// calls change nothing.
pub fn init(filter: Option<&str>) -> Result<(), LogFilterError> {
    let Some(filter) = filter
        .map(str::to_string)
        .or_else(|| std::env::var("RUST_LOG").ok())
        .filter(|f| !f.trim().is_empty())
    else {
        return Ok(());
    };
    let parsed = tracing_subscriber::EnvFilter::try_new(&filter).map_err(|e| LogFilterError {
        filter: filter.clone(),
        reason: e.to_string(),
    })?;
    if FILTER.set(filter).is_err() {
        return Ok(());
    }
    let builder = tracing_subscriber::fmt()
        .with_env_filter(parsed)
        .with_target(false)
        .with_ansi(false);
    // An error: another subscriber (a host program's) is already set, and gets our events.
    let _ = match inherited_fd() {
        Some(fd) => builder.with_writer(move || FdWriter(fd)).try_init(),
        None => builder.with_writer(std::io::stderr).try_init(),
    };
    Ok(())
}

/// The filter in force, when logs are on: a launcher hands it to its agents.
pub fn filter() -> Option<&'static str> {
    FILTER.get().map(String::as_str)
}

/// A `--log` or `RUST_LOG` filter that does not parse.
#[derive(Debug, thiserror::Error)]
#[error("log filter '{filter}' is not valid: {reason}")]
pub struct LogFilterError {
    filter: String,
    reason: String,
}

/// The log descriptor a launcher gave this agent process, if it is open.
fn inherited_fd() -> Option<RawFd> {
    let fd: RawFd = std::env::var(LOG_FD_ENV).ok()?.parse().ok()?;
    // SAFETY: F_GETFD only asks whether the descriptor is open.
    (fd > 2 && unsafe { libc::fcntl(fd, libc::F_GETFD) } != -1).then_some(fd)
}

/// Writes to a raw descriptor this process does not own (never closes it); one `write` per
/// formatted event, so lines of several processes do not interleave within a line.
struct FdWriter(RawFd);

impl std::io::Write for FdWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        // SAFETY: writing `buf` to a descriptor that stays open for the process's life.
        let n = unsafe { libc::write(self.0, buf.as_ptr().cast(), buf.len()) };
        if n < 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok(n as usize)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}
