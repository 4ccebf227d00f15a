//! A host's scheduling priority: it relays every message between hosts, so it runs ahead
//! of its agents where the system allows it.

/// Nice steps a host runs ahead of its agents, where the system allows it.
pub(super) const PRIORITY_BOOST: i32 = 10;

/// Raises the calling thread's scheduling priority by [`PRIORITY_BOOST`] nice steps (root,
/// `CAP_SYS_NICE` or `RLIMIT_NICE` allow it; threads started afterwards inherit it) and
/// returns the niceness it runs at.
///
/// Why: every message between hosts goes through the host's router (and, in a mixed team,
/// its bridge). With 50 busy agents per host on 2 cores the host's threads got the same share
/// of the processor as any one agent and fell behind: mixed teams of 200 agents on four hosts
/// had round p99s of 5.5–9.6 s against a 10 s round deadline, and one run in ten failed on
/// it; ten nice steps ahead, p99 1.8–2.8 s and wall time 15–17 s instead of 21–29 s.
pub(super) fn raise_priority() -> std::io::Result<i32> {
    // SAFETY: plain system calls on the calling thread; errno is cleared first because -1 is
    // also a valid niceness.
    unsafe {
        *libc::__errno_location() = 0;
        let now = libc::getpriority(libc::PRIO_PROCESS, 0);
        if now == -1 && *libc::__errno_location() != 0 {
            return Err(std::io::Error::last_os_error());
        }
        let wanted = (now - PRIORITY_BOOST).max(-20);
        if libc::setpriority(libc::PRIO_PROCESS, 0, wanted) != 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok(wanted)
    }
}
