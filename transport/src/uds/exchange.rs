//! One `uds` agent's end: its links to its neighbours, moved without blocking, and its
//! round exchange. Its start-up is in `connect`.

use crate::board::Board;
use crate::exchange::header::{
    RoundHeader, words_as_bytes as as_bytes, words_as_bytes_mut as as_bytes_mut,
};
use crate::exchange::{Exchange, ExchangeError};
use crate::wait::WaitPolicy;
use admm_ta_agents::agent::Inbox;
use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

mod connect;

/// Words of the message header.
const HEADER_WORDS: usize = RoundHeader::WORDS;

/// Longest sleep between two looks at the run's failure mark.
const FAILURE_CHECK_SLICE: Duration = Duration::from_millis(20);

/// Path of agent `i`'s listening socket.
pub fn socket_path(dir: &Path, i: usize) -> PathBuf {
    dir.join(format!("uds-{i}.sock"))
}

/// One neighbour's stream and the message being received from / sent to it.
struct Link {
    neighbour: usize,
    stream: UnixStream,
    /// Header words and payload of the neighbour's current message.
    inbox: Vec<f64>,
    received: usize,
    header: RoundHeader,
    /// Bytes of the own current message written to this link.
    sent: usize,
}

/// One agent's end of the `uds` transport.
pub struct UdsExchange {
    index: usize,
    links: Vec<Link>,
    /// Header words and payload of the own current message.
    outbox: Vec<f64>,
    policy: WaitPolicy,
    board: Board,
    poll_fds: Vec<libc::pollfd>,
}

fn transport(agent: usize, what: impl Into<String>) -> ExchangeError {
    ExchangeError::Transport {
        agent,
        what: what.into(),
    }
}

impl UdsExchange {
    /// Moves bytes on every link without blocking; `true` once the current message of every
    /// neighbour is read and the own one is sent.
    fn progress(&mut self, round: u64) -> Result<bool, ExchangeError> {
        self.progress_sends()?;
        let i = self.index;
        let total = self.outbox.len() * 8;
        let mut done = true;
        for link in &mut self.links {
            let j = link.neighbour;
            while link.received < total {
                match link
                    .stream
                    .read(&mut as_bytes_mut(&mut link.inbox)[link.received..])
                {
                    Ok(0) => {
                        return Err(ExchangeError::PeerFailed {
                            agent: i,
                            failed: j,
                            round,
                            how: "closed its socket".into(),
                        });
                    }
                    Ok(n) => {
                        link.received += n;
                        if link.received == total {
                            link.header = RoundHeader::from_words(&link.inbox[..HEADER_WORDS]);
                            if link.header.sender as usize != j {
                                return Err(ExchangeError::WrongSender {
                                    agent: i,
                                    neighbour: j,
                                    got: link.header.sender,
                                });
                            }
                            if link.header.round != round {
                                return Err(ExchangeError::OutOfOrder {
                                    agent: i,
                                    neighbour: j,
                                    expected: round,
                                    got: link.header.round,
                                });
                            }
                        }
                    }
                    Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(e) if e.kind() == ErrorKind::ConnectionReset => {
                        // Evidence: the neighbour's process is gone (its kernel reset it).
                        return Err(ExchangeError::PeerFailed {
                            agent: i,
                            failed: j,
                            round,
                            how: "reset its connection (its process died)".into(),
                        });
                    }
                    Err(e) => {
                        return Err(transport(
                            i,
                            format!("receiving from neighbour {j} failed: {e}"),
                        ));
                    }
                }
            }
            done &= link.sent == total && link.received == total;
        }
        Ok(done)
    }

    /// Sleeps in `poll(2)` until a link can move bytes, `until`, or a signal.
    fn sleep(&mut self, until: Instant) {
        let total = self.outbox.len() * 8;
        for (fd, link) in self.poll_fds.iter_mut().zip(&self.links) {
            fd.events = 0;
            if link.received < total {
                fd.events |= libc::POLLIN;
            }
            if link.sent < total {
                fd.events |= libc::POLLOUT;
            }
            fd.revents = 0;
        }
        let timeout = until
            .saturating_duration_since(Instant::now())
            .as_micros()
            .div_ceil(1000)
            .min(i32::MAX as u128) as i32;
        // SAFETY: `poll_fds` is a live array of `len` pollfd structs.
        unsafe {
            libc::poll(
                self.poll_fds.as_mut_ptr(),
                self.poll_fds.len() as libc::nfds_t,
                timeout,
            );
        }
    }

    /// Marks agent `agent` as the one that failed (unless another was marked first).
    pub fn blame(&self, agent: usize) {
        let _ = self.board.mark_failed(agent);
    }

    /// The agent that published the fewest rounds: after a timeout, the one everybody is
    /// waiting for, directly or through a chain of blocked neighbours (a stopped process).
    pub fn laggard(&self) -> usize {
        self.board.laggard().unwrap_or(self.index)
    }

    fn send(&mut self, header: RoundHeader) -> Result<(), ExchangeError> {
        header.write_words(&mut self.outbox[..HEADER_WORDS]);
        for link in &mut self.links {
            link.sent = 0;
        }
        self.board.set_published_round(self.index, header.round);
        // Hand the kernel what it takes now; the rest goes out while gathering.
        self.progress_sends()
    }

    fn progress_sends(&mut self) -> Result<(), ExchangeError> {
        let total = self.outbox.len() * 8;
        for link in &mut self.links {
            while link.sent < total {
                match link.stream.write(&as_bytes(&self.outbox)[link.sent..]) {
                    Ok(n) => link.sent += n,
                    Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(e)
                        if matches!(
                            e.kind(),
                            ErrorKind::BrokenPipe | ErrorKind::ConnectionReset
                        ) =>
                    {
                        // Evidence: the neighbour's process is gone.
                        return Err(ExchangeError::PeerFailed {
                            agent: self.index,
                            failed: link.neighbour,
                            round: 0,
                            how: "closed its connection (its process died)".into(),
                        });
                    }
                    Err(e) => {
                        return Err(transport(
                            self.index,
                            format!("sending to neighbour {} failed: {e}", link.neighbour),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Neighbours' payloads of the gathered round, in the receive buffers.
struct LinkInbox<'a> {
    links: &'a [Link],
}

impl Inbox for LinkInbox<'_> {
    fn len(&self) -> usize {
        self.links.len()
    }
    fn payload(&self, k: usize) -> &[f64] {
        &self.links[k].inbox[HEADER_WORDS..]
    }
}

impl Exchange for UdsExchange {
    fn degree(&self) -> usize {
        self.links.len()
    }

    fn publish_initial(
        &mut self,
        header: RoundHeader,
        write: &mut dyn FnMut(&mut [f64]),
    ) -> Result<(), ExchangeError> {
        write(&mut self.outbox[HEADER_WORDS..]);
        self.send(header)
    }

    fn gather(&mut self, round: u64, deadline: Instant) -> Result<(), ExchangeError> {
        let started = Instant::now();
        self.board.check_team(self.index, round)?;
        for link in &mut self.links {
            link.received = 0;
        }
        let held = self.policy.wait_until(
            self,
            deadline,
            |s| s.progress(round),
            |s, deadline| {
                s.sleep(deadline.min(Instant::now() + FAILURE_CHECK_SLICE));
                s.board.check_team(s.index, round)
            },
        )?;
        if held {
            return Ok(());
        }
        let total = self.outbox.len() * 8;
        Err(ExchangeError::Timeout {
            agent: self.index,
            round,
            missing: self
                .links
                .iter()
                .filter(|l| l.received < total)
                .map(|l| l.neighbour)
                .collect(),
            waited: started.elapsed(),
        })
    }

    fn neighbour_header(&self, k: usize) -> &RoundHeader {
        &self.links[k].header
    }

    fn neighbour_payload(&self, k: usize) -> &[f64] {
        &self.links[k].inbox[HEADER_WORDS..]
    }

    fn compute_and_publish(
        &mut self,
        compute: &mut dyn FnMut(&dyn Inbox, &mut [f64]) -> RoundHeader,
    ) -> Result<(), ExchangeError> {
        let header = compute(
            &LinkInbox { links: &self.links },
            &mut self.outbox[HEADER_WORDS..],
        );
        self.send(header)
    }

    fn global_barrier(&mut self, _round: u64, _deadline: Instant) -> Result<(), ExchangeError> {
        Err(transport(
            self.index,
            "the uds baseline has no global barrier (use ipc or threads)",
        ))
    }
}
