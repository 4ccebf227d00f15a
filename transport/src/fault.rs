//! Fault injection for tests (not in `--help`; compiled in only with the cargo feature
//! `fault-injection`, which the workspace's tests enable and release builds do not: without
//! it [`fault_for`] never reads the environment): the environment variable
//! `ADMM_TA_FAULT=AGENT:ROUND:KIND` makes agent process `AGENT` misbehave when it is about to
//! publish round `ROUND + 1` (after gathering round `ROUND`). Kinds:
//!
//! * `exit`: `process::exit(3)` without any cleanup (like a crash: no `Drop`, stale shm);
//! * `abort`: `process::abort()` (SIGABRT);
//! * `hang`: stops sending and sleeps until killed (neighbours time out);
//! * `nan`: publishes a payload with a NaN in it;
//! * `wrong-round`: publishes a header with a round number far ahead;
//! * `wrong-size`: publishes a payload one value short;
//! * `never-start`: never connects (any process transport; `ROUND` is ignored): its
//!   process lives, but it never joins the team.
//!
//! The launcher passes the environment to its agents, so a test sets it on `admm-ta solve`;
//! the agent's exchange applies it when it publishes (the transports whose capabilities say
//! so: [`crate::ipc::exchange::IpcExchange`], the Zenoh exchange).

use crate::exchange::header::RoundHeader;
use std::time::Duration;

/// The environment variable that injects a fault.
#[cfg(feature = "fault-injection")]
pub const FAULT_ENV: &str = "ADMM_TA_FAULT";

/// What an agent does wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    Exit,
    Abort,
    Hang,
    Nan,
    WrongRound,
    WrongSize,
    NeverStart,
}

/// A fault of one agent at one round.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fault {
    pub agent: usize,
    pub round: u64,
    pub kind: FaultKind,
}

/// A fault switch that is not `AGENT:ROUND:KIND`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("a fault must be AGENT:ROUND:KIND, got {text:?}")]
pub struct BadFault {
    pub text: String,
}

impl std::str::FromStr for Fault {
    type Err = BadFault;
    fn from_str(text: &str) -> Result<Self, BadFault> {
        let bad = || BadFault {
            text: text.to_string(),
        };
        let mut parts = text.split(':');
        let (Some(agent), Some(round), Some(kind), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(bad());
        };
        let kind = match kind {
            "exit" => FaultKind::Exit,
            "abort" => FaultKind::Abort,
            "hang" => FaultKind::Hang,
            "nan" => FaultKind::Nan,
            "wrong-round" => FaultKind::WrongRound,
            "wrong-size" => FaultKind::WrongSize,
            "never-start" => FaultKind::NeverStart,
            _ => return Err(bad()),
        };
        Ok(Self {
            agent: agent.parse().map_err(|_| bad())?,
            round: round.parse().map_err(|_| bad())?,
            kind,
        })
    }
}

/// The fault the environment injects into agent `index`, if any (never, in a build without
/// the `fault-injection` feature).
#[cfg(not(feature = "fault-injection"))]
pub fn fault_for(_index: usize) -> Result<Option<Fault>, BadFault> {
    Ok(None)
}

/// The fault the environment injects into agent `index`, if any.
#[cfg(feature = "fault-injection")]
pub fn fault_for(index: usize) -> Result<Option<Fault>, BadFault> {
    match std::env::var(FAULT_ENV) {
        Ok(text) if !text.is_empty() => {
            let fault: Fault = text.parse()?;
            Ok((fault.agent == index).then_some(fault))
        }
        _ => Ok(None),
    }
}

impl Fault {
    /// Strikes when agent `fault.agent` is about to publish after gathering `fault.round`:
    /// `exit`, `abort` and `hang` end here (no return); the others return, and the sender
    /// then applies [`Fault::corrupt`] and sends [`Fault::payload_len`] values.
    pub fn strike(&self) {
        eprintln!(
            "fault injection: agent {} does {:?} at round {}",
            self.agent, self.kind, self.round
        );
        match self.kind {
            FaultKind::Exit => std::process::exit(3),
            FaultKind::Abort => std::process::abort(),
            FaultKind::Hang => loop {
                std::thread::sleep(Duration::from_secs(3600));
            },
            FaultKind::Nan
            | FaultKind::WrongRound
            | FaultKind::WrongSize
            | FaultKind::NeverStart => {}
        }
    }

    /// Corrupts the outgoing payload or header as the fault says.
    pub fn corrupt(&self, payload: &mut [f64], header: &mut RoundHeader) {
        match self.kind {
            FaultKind::Nan => payload[payload.len() / 2] = f64::NAN,
            // Odd: a round of the other parity, which never completes the receivers' arrival
            // counts of the round they wait for (they must still receive and refuse it).
            FaultKind::WrongRound => header.round += 1001,
            _ => {}
        }
    }

    /// Values actually sent instead of `len`.
    pub fn payload_len(&self, len: usize) -> usize {
        if self.kind == FaultKind::WrongSize {
            len.saturating_sub(1)
        } else {
            len
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_parse_and_bad_ones_are_refused() {
        assert_eq!(
            "3:10:nan".parse::<Fault>(),
            Ok(Fault {
                agent: 3,
                round: 10,
                kind: FaultKind::Nan
            })
        );
        for bad in [
            "",
            "3:10",
            "3:10:nan:1",
            "x:1:exit",
            "1:-1:exit",
            "1:1:melt",
        ] {
            assert!(bad.parse::<Fault>().is_err(), "{bad}");
        }
    }
}
