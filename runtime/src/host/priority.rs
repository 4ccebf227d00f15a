//! A host process's set-up before its first thread: its scheduling priority (it relays every
//! message between hosts, so it runs ahead of its agents where the system allows it) and the
//! size of its router's receive runtime.

use admm_ta_transport::zenoh_net::session::{single_threaded, size_router_runtime};

/// Nice steps a host runs ahead of its agents, where the system allows it.
const PRIORITY_BOOST: i32 = 10;

/// What [`prepare_host_process`] did.
#[derive(Debug)]
pub(super) enum Prepared {
    /// Running at this niceness (ahead of its agents, as far as allowed), router sized.
    Ahead(i32),
    /// The priority could not be raised (router sized).
    NotRaised(std::io::Error),
    /// Another thread runs in this process (an embedding program): neither the environment
    /// nor the priority was touched.
    Shared,
}

/// Sets a host process up before it starts any thread: its router's receive runtime sized
/// for `router_links` links ([`size_router_runtime`]) and its priority raised
/// ([`raise_priority`]), both inherited by the threads started afterwards. Does neither in
/// a process that already runs other threads (a program embedding the command line, such
/// as the Python package): changing the environment there is unsound, and the priority
/// would outlive the host.
pub(super) fn prepare_host_process(router_links: usize) -> Prepared {
    if !single_threaded() {
        return Prepared::Shared;
    }
    // SAFETY: this process runs one thread (checked above), so nothing else reads or writes
    // the environment meanwhile.
    unsafe { size_router_runtime(router_links) };
    match raise_priority() {
        Ok(nice) => Prepared::Ahead(nice),
        Err(e) => Prepared::NotRaised(e),
    }
}

/// Raises the calling thread's scheduling priority by up to [`PRIORITY_BOOST`] nice steps
/// (root or `CAP_SYS_NICE` allow all of them, `RLIMIT_NICE` as many as it allows; threads
/// started afterwards inherit it) and returns the niceness it runs at. (With the kernel's
/// autogroup scheduling, nice weighs only against processes of the same session: a host
/// started from another session than its agents gains nothing from it.)
///
/// Why: every message between hosts goes through the host's router (and, in a mixed team,
/// its bridge). With 50 busy agents per host on 2 cores the host's threads got the same share
/// of the processor as any one agent and fell behind: mixed teams of 200 agents on four hosts
/// had round p99s of 5.5–9.6 s against a 10 s round deadline, and one run in ten failed on
/// it; ten nice steps ahead, p99 2.0–3.1 s and wall time 15–18 s instead of 21–29 s.
fn raise_priority() -> std::io::Result<i32> {
    // SAFETY: plain system calls on the calling thread; errno is cleared first because -1 is
    // also a valid niceness.
    unsafe {
        *libc::__errno_location() = 0;
        let now = libc::getpriority(libc::PRIO_PROCESS, 0);
        if now == -1 && *libc::__errno_location() != 0 {
            return Err(std::io::Error::last_os_error());
        }
        let wanted = (now - PRIORITY_BOOST).max(-20);
        if libc::setpriority(libc::PRIO_PROCESS, 0, wanted) == 0 {
            return Ok(wanted);
        }
        let refused = std::io::Error::last_os_error();
        // Without the privilege, RLIMIT_NICE allows a niceness down to 20 − its soft limit.
        let mut limit = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        if libc::getrlimit(libc::RLIMIT_NICE, &mut limit) != 0 {
            return Err(refused);
        }
        let floor = 20 - limit.rlim_cur.min(40) as i32;
        let allowed = wanted.max(floor);
        if allowed < now && libc::setpriority(libc::PRIO_PROCESS, 0, allowed) == 0 {
            return Ok(allowed);
        }
        Err(refused)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_test_process_runs_several_threads() {
        // The test harness runs every test on a thread of its own: never "single".
        assert!(!super::single_threaded());
    }
}
