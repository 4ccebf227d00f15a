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
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
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
    /// Every round's messages go through one relay that cannot carry them within half the
    /// round deadline.
    #[error(
        "the team's round is {:.2} GB of messages (each agent's {bytes} bytes to each of its neighbours), all relayed by the {transport} router at about {:.1} GB/s: {:.1} s a round, over half the round deadline ({:.0} s); use a method with small messages (--method dual), --transport ipc on one machine, fewer robots, or a longer --round-timeout",
        *round_bytes as f64 / 1e9,
        relay_rate / 1e9,
        *round_bytes as f64 / relay_rate,
        round_timeout.as_secs_f64()
    )]
    Relay {
        transport: &'static str,
        bytes: u64,
        round_bytes: u64,
        relay_rate: f64,
        round_timeout: std::time::Duration,
    },
}

/// A team's round: what its agents send each round, and within what.
#[derive(Debug, Clone, Copy)]
pub struct RoundLoad {
    /// Sum of the agents' degrees (messages a round).
    pub messages: u64,
    /// Bytes of one message.
    pub message_bytes: u64,
    pub round_timeout: std::time::Duration,
}

/// Refuses a round that the one relay of `transport` (if it has one) cannot carry within
/// half the round deadline.
pub fn check_relay(transport: Transport, load: RoundLoad) -> Result<(), LimitError> {
    let Some(rate) = transport
        .processes()
        .and_then(|p| p.relay_bytes_per_second())
    else {
        return Ok(());
    };
    let round_bytes = load.messages.saturating_mul(load.message_bytes);
    if round_bytes as f64 / rate <= load.round_timeout.as_secs_f64() / 2.0 {
        return Ok(());
    }
    Err(LimitError::Relay {
        transport: transport.name(),
        bytes: load.message_bytes,
        round_bytes,
        relay_rate: rate,
        round_timeout: load.round_timeout,
    })
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    fn load(agents: u64, degree: u64, payload: u64, timeout_s: u64) -> RoundLoad {
        RoundLoad {
            messages: agents * degree,
            message_bytes: (payload + 7) * 8,
            round_timeout: Duration::from_secs(timeout_s),
        }
    }

    /// 200 primal agents of 200 tasks on `random:0.1` (about 20 neighbours each) fit one
    /// Zenoh router within the default deadline; the same round within 2 s does not, and
    /// the refusal says how big the round is and what to change. Transports without one
    /// relay are never refused.
    #[test]
    fn a_round_one_router_cannot_carry_is_refused_with_its_size() {
        let primal = load(200, 20, 200 * 200, 30);
        assert_eq!(check_relay(Transport::Zenoh, primal), Ok(()));
        let tight = load(200, 20, 200 * 200, 2);
        let refused = check_relay(Transport::Zenoh, tight).unwrap_err();
        let text = refused.to_string();
        for part in [
            "1.28 GB",
            "320056 bytes",
            "--method dual",
            "--round-timeout",
        ] {
            assert!(text.contains(part), "{text}");
        }
        for transport in [Transport::Ipc, Transport::Uds, Transport::Shm] {
            assert_eq!(check_relay(transport, tight), Ok(()));
        }
        // The dual's messages (2m + ⌈m/7⌉ values) are 160 times lighter.
        let dual = load(200, 20, 2 * 200 + 29, 2);
        assert_eq!(check_relay(Transport::Zenoh, dual), Ok(()));
    }
}
