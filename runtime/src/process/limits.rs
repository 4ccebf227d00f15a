//! Resource checks before anything is spawned: the open files an agent process needs for its
//! transport and degree, and the processes (threads) a team needs, against the soft limits
//! (`getrlimit`) the agents inherit. A team that cannot fit fails at once with one line and
//! the number to raise the limit to, instead of an opaque iceoryx2 error half-way through
//! start-up.
//!
//! Open files per agent process, counted in `/proc/PID/fd` on real runs and fitted (degree
//! `d`): iceoryx2 `19 + 11·d` (degree 1, 2, 9, 49: 30, 41, 118, 558 — each neighbour costs a
//! subscriber, a notifier and their shared-memory connections and segments); Unix sockets
//! `6 + d`; the shm slot table 6 (the board and the table, whatever the degree); Zenoh
//! (threads and sockets of its runtime) about 64. One thread per agent process (shm, ipc,
//! uds); a Zenoh agent runs its runtime's threads too.

use crate::transport::Transport;

/// Files no count covers (a margin for what the formulas do not see).
const MARGIN: u64 = 16;

/// Open files an agent process of `transport` with `degree` neighbours needs.
pub fn files_per_agent(transport: Transport, degree: usize) -> u64 {
    let d = degree as u64;
    match transport {
        Transport::Ipc => 19 + 11 * d,
        Transport::Shm => 6,
        Transport::Uds => 6 + d,
        Transport::Zenoh => 64 + d,
        Transport::Sim | Transport::Threads => 0,
    }
}

/// Threads an agent process of `transport` runs.
pub fn threads_per_agent(transport: Transport) -> u64 {
    match transport {
        Transport::Zenoh => 16,
        _ => 1,
    }
}

fn soft_limit(resource: libc::__rlimit_resource_t) -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes into our struct.
    if unsafe { libc::getrlimit(resource, &mut limit) } != 0
        || limit.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    Some(limit.rlim_cur)
}

/// Refuses a team of `agents` agent processes on `transport` whose largest degree is
/// `max_degree` if the open-file or process limits cannot hold it; one line saying what to
/// raise and to what.
pub fn check(transport: Transport, agents: usize, max_degree: usize) -> Result<(), String> {
    let files = files_per_agent(transport, max_degree) + MARGIN;
    if let Some(limit) = soft_limit(libc::RLIMIT_NOFILE)
        && files > limit
    {
        return Err(format!(
            "the team needs {files} open files per agent but the limit is {limit}: raise it with ulimit -n {}",
            files.next_power_of_two()
        ));
    }
    let threads = agents as u64 * threads_per_agent(transport) + 1;
    if let Some(limit) = soft_limit(libc::RLIMIT_NPROC)
        && threads > limit
    {
        return Err(format!(
            "the team needs {threads} processes (threads) but the limit is {limit}: raise it with ulimit -u {}",
            (2 * threads).next_power_of_two()
        ));
    }
    Ok(())
}
