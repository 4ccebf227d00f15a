//! Resource checks before anything is spawned: the open files an agent process needs for its
//! transport and degree, and the processes (threads) a team needs, against the limits
//! (`getrlimit`) the agents inherit. A soft limit below the need is raised up to the hard
//! limit first (as Go's runtime and many servers do: the usual soft `ulimit -n` of 1024
//! would refuse 100 agents over iceoryx2 on a complete graph where the hard limit allows
//! them); a team that still cannot fit fails at once with one line and the number to raise
//! the hard limit to, instead of an opaque iceoryx2 error half-way through start-up.
//!
//! The open files and threads an agent process needs are declared by its transport
//! ([`admm_ta_transport::endpoint::ProcessTransport`]; each transport's module says how it counted them).

use admm_ta_transport::Transport;

/// Files no count covers (a margin for what the formulas do not see).
const MARGIN: u64 = 16;

/// Open files an agent process of `transport` with `degree` neighbours needs (none for a
/// transport whose agents are not processes).
pub fn files_per_agent(transport: Transport, degree: usize) -> u64 {
    transport
        .processes()
        .map_or(0, |p| p.files_per_agent(degree))
}

/// Threads an agent process of `transport` runs.
pub fn threads_per_agent(transport: Transport) -> u64 {
    transport.processes().map_or(1, |p| p.threads_per_agent())
}

/// A team the open-file or process limits cannot hold: what to raise, and to what.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LimitError {
    /// `limit`: the hard limit (the soft one is raised up to it first).
    #[error(
        "the team needs {needed} open files per agent but the hard limit is {limit} (ulimit -Hn): raise it to {} (as root: ulimit -Hn {}, or in /etc/security/limits.conf)",
        needed.next_power_of_two(),
        needed.next_power_of_two()
    )]
    OpenFiles { needed: u64, limit: u64 },
    #[error(
        "the team needs {needed} processes (threads) but the hard limit is {limit} (ulimit -Hu): raise it to {} (as root: ulimit -Hu {}, or in /etc/security/limits.conf)",
        (2 * needed).next_power_of_two(),
        (2 * needed).next_power_of_two()
    )]
    Processes { needed: u64, limit: u64 },
}

/// Makes the soft limit of `resource` at least `needed` if the hard limit allows it (it is
/// raised to the hard limit, so the agents, which inherit it, have room too); returns the
/// limit that stays too low (the hard one), `None` when `needed` fits (or nothing limits).
fn fit_limit(resource: libc::__rlimit_resource_t, needed: u64) -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes into our struct.
    if unsafe { libc::getrlimit(resource, &mut limit) } != 0
        || limit.rlim_cur == libc::RLIM_INFINITY
        || needed <= limit.rlim_cur
    {
        return None;
    }
    if limit.rlim_max != libc::RLIM_INFINITY && limit.rlim_max < needed {
        return Some(limit.rlim_max);
    }
    let raised = libc::rlimit {
        rlim_cur: limit.rlim_max,
        rlim_max: limit.rlim_max,
    };
    // SAFETY: setrlimit reads our struct; raising a soft limit up to the hard one is allowed.
    if unsafe { libc::setrlimit(resource, &raised) } != 0 {
        return Some(limit.rlim_cur);
    }
    None
}

/// Refuses a team of `agents` agent processes on `transport` whose largest degree is
/// `max_degree` if the open-file or process limits cannot hold it; one line saying what to
/// raise and to what.
pub fn check(transport: Transport, agents: usize, max_degree: usize) -> Result<(), LimitError> {
    let files = files_per_agent(transport, max_degree) + MARGIN;
    if let Some(limit) = fit_limit(libc::RLIMIT_NOFILE, files) {
        return Err(LimitError::OpenFiles {
            needed: files,
            limit,
        });
    }
    let threads = agents as u64 * threads_per_agent(transport) + 1;
    if let Some(limit) = fit_limit(libc::RLIMIT_NPROC, threads) {
        return Err(LimitError::Processes {
            needed: threads,
            limit,
        });
    }
    Ok(())
}
