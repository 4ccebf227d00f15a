//! Fault injection for tests (not in `--help`): the environment variable
//! `ADMM_TA_FAULT=AGENT:ROUND:KIND` makes agent process `AGENT` misbehave when it is about to
//! publish round `ROUND + 1` (after gathering round `ROUND`). Kinds:
//!
//! * `exit`: `process::exit(3)` without any cleanup (like a crash: no `Drop`, stale shm);
//! * `abort`: `process::abort()` (SIGABRT);
//! * `hang`: stops sending and sleeps until killed (neighbours time out);
//! * `nan`: publishes a payload with a NaN in it;
//! * `wrong-round`: publishes a header with a round number far ahead;
//! * `wrong-size`: publishes a payload one value short.
//!
//! The launcher passes the environment to its agents, so a test sets it on `admm-ta solve`.

use crate::exchange::{Exchange, ExchangeError};
use crate::header::RoundHeader;
use crate::ipc::transport::IpcExchange;
use admm_ta_agents::agent::Inbox;
use std::time::{Duration, Instant};

/// The environment variable that injects a fault.
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
}

/// A fault of one agent at one round.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fault {
    pub agent: usize,
    pub round: u64,
    pub kind: FaultKind,
}

impl std::str::FromStr for Fault {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, String> {
        let bad = || format!("{FAULT_ENV} must be AGENT:ROUND:KIND, got {text:?}");
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
            _ => return Err(bad()),
        };
        Ok(Self {
            agent: agent.parse().map_err(|_| bad())?,
            round: round.parse().map_err(|_| bad())?,
            kind,
        })
    }
}

/// The fault the environment injects into agent `index`, if any.
pub fn fault_for(index: usize) -> Result<Option<Fault>, String> {
    match std::env::var(FAULT_ENV) {
        Ok(text) if !text.is_empty() => {
            let fault: Fault = text.parse()?;
            Ok((fault.agent == index).then_some(fault))
        }
        _ => Ok(None),
    }
}

/// An [`IpcExchange`] that misbehaves as told at one round.
pub struct FaultyExchange {
    pub inner: IpcExchange,
    pub fault: Option<Fault>,
    gathered: u64,
}

impl FaultyExchange {
    pub fn new(inner: IpcExchange, fault: Option<Fault>) -> Self {
        Self {
            inner,
            fault,
            gathered: 0,
        }
    }
}

impl Exchange for FaultyExchange {
    fn degree(&self) -> usize {
        self.inner.degree()
    }
    fn publish_initial(
        &mut self,
        header: RoundHeader,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<(), ExchangeError> {
        self.inner.publish_initial(header, write)
    }
    fn gather(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        self.gathered = round;
        self.inner.gather(round, deadline)
    }
    fn neighbour_header(&self, k: usize) -> &RoundHeader {
        self.inner.neighbour_header(k)
    }
    fn neighbour_payload(&self, k: usize) -> &[f64] {
        self.inner.neighbour_payload(k)
    }
    fn compute_and_publish(
        &mut self,
        compute: &mut dyn FnMut(&dyn Inbox, &mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError> {
        let Some(fault) = self.fault.filter(|f| f.round == self.gathered) else {
            return self.inner.compute_and_publish(compute);
        };
        eprintln!(
            "fault injection: agent {} does {:?} at round {}",
            fault.agent, fault.kind, fault.round
        );
        match fault.kind {
            FaultKind::Exit => std::process::exit(3),
            FaultKind::Abort => std::process::abort(),
            FaultKind::Hang => loop {
                std::thread::sleep(Duration::from_secs(3600));
            },
            FaultKind::Nan => self.inner.compute_and_publish(&mut |inbox, out| {
                let header = compute(inbox, out);
                let middle = out.len() / 2;
                out[middle] = f64::NAN;
                header
            }),
            FaultKind::WrongRound => self.inner.compute_and_publish(&mut |inbox, out| {
                let mut header = compute(inbox, out);
                header.round += 1000;
                header
            }),
            FaultKind::WrongSize => {
                self.inner.truncate_next_payload();
                self.inner.compute_and_publish(compute)
            }
        }
    }
    fn global_barrier(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        self.inner.global_barrier(round, deadline)
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
