//! Whether a process lives: how the launcher, the team members and the namespace sweep tell
//! a live agent or launcher from a dead one.

/// Whether process `pid` runs (a zombie, exited but not yet reaped, does not).
pub fn process_alive(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|stat| {
        // The state is the first field after the parenthesised command name.
        let state = stat[stat.rfind(')').map_or(0, |i| i + 1)..]
            .split_whitespace()
            .next();
        state != Some("Z")
    })
}

/// The state letter of process `pid` in `/proc/PID/stat` (`R`, `S`, `T` stopped, `t`
/// traced, `Z` zombie, …), if it exists.
pub fn process_state(pid: u32) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat[stat.rfind(')').map_or(0, |i| i + 1)..]
        .split_whitespace()
        .next()
        .and_then(|s| s.chars().next())
}
