//! The `uds` baseline transport: one process per agent, like `ipc`, but every payload is
//! **copied** through Unix-domain stream sockets — serialised into the sender's buffer,
//! copied into the kernel once per neighbour, and copied out by each receiver. It exists to
//! show what iceoryx2's zero-copy exchange saves, side by side in one benchmark run; runs
//! use it through `admm-ta bench rounds --transports uds`.
//!
//! One stream per graph edge: agent `i` listens on `uds-i.sock` in the run directory,
//! connects to its lower-numbered neighbours (sending its index as a handshake) and accepts
//! its higher-numbered ones; the socket files are removed once everybody is connected. All
//! sockets are non-blocking. A message is 7 header words (round, sender and flags, digest,
//! the stop window) followed by the payload, both as `f64` words. Sending never blocks: what
//! the kernel does not take at once is written while the agent gathers the next round, so
//! two neighbours sending large messages to each other cannot deadlock; a gather completes
//! once every neighbour's message is read *and* the agent's own message is fully sent.
//! Waiting follows the [`WaitPolicy`]: spin on non-blocking reads and/or sleep in `poll(2)`
//! in 20 ms slices, looking at the run's failure mark in between. A neighbour's end of file
//! is reported as its failure. There is no global barrier.

use crate::board::{Board, Rendezvous};
use crate::endpoint::{ConnectError, ConnectRequest};
use crate::exchange::header::{
    RoundHeader, words_as_bytes as as_bytes, words_as_bytes_mut as as_bytes_mut,
};
use crate::exchange::{Exchange, ExchangeError};
use crate::wait::WaitPolicy;
use admm_ta_agents::agent::Inbox;
use std::io::{ErrorKind, Read, Write};
use std::os::fd::AsRawFd;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub mod process;

/// Words of the message header.
const HEADER_WORDS: usize = RoundHeader::WORDS;

/// Longest sleep between two looks at the run's failure mark.
const FAILURE_CHECK_SLICE: Duration = Duration::from_millis(20);

/// The agent's socket could not be bound.
#[derive(Debug, thiserror::Error)]
#[error("cannot listen on {}", path.display())]
struct CannotListen {
    path: PathBuf,
    #[source]
    source: std::io::Error,
}

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

/// A stop request (termination signal) during start-up, as the agent's one-line error.
fn stop_during_startup(
    agent: usize,
    board: &Board,
    neighbours: &[usize],
) -> Result<(), ExchangeError> {
    if let Some(signal) = board.stop_signal() {
        return Err(ExchangeError::Stopped { agent, signal });
    }
    // A neighbour of an independently started team whose process died while it started.
    match neighbours.iter().find(|&&j| board.member_died(j)) {
        Some(&failed) => {
            let _ = board.mark_failed(failed);
            Err(ExchangeError::PeerFailed {
                agent,
                failed,
                round: 0,
                how: "died during start-up".into(),
            })
        }
        None => Ok(()),
    }
}

impl UdsExchange {
    /// Connects agent `endpoint.index` to all its neighbours, waiting for them until
    /// `deadline`.
    pub fn connect(endpoint: &ConnectRequest, deadline: Instant) -> Result<Self, ConnectError> {
        let i = endpoint.index;
        let agents = endpoint.agents();
        let socket_dir = &endpoint.run.dir;
        let err = |what: String| ConnectError::from(transport(i, what));
        let board = Board::open(&endpoint.run.board_shm, agents).map_err(ConnectError::setup)?;
        board.set_registered(i);
        let own = socket_path(socket_dir, i);
        let _ = std::fs::remove_file(&own);
        let listener = UnixListener::bind(&own).map_err(|source| {
            ConnectError::setup(CannotListen {
                path: own.clone(),
                source,
            })
        })?;
        let message_words = HEADER_WORDS + endpoint.payload_len;
        let link = |neighbour, stream| Link {
            neighbour,
            stream,
            inbox: vec![0.0; message_words],
            received: 0,
            header: RoundHeader::default(),
            sent: message_words * 8,
        };
        let mut links: Vec<Option<Link>> = endpoint.neighbours.iter().map(|_| None).collect();
        // Lower-numbered neighbours listen for us.
        for (k, &j) in endpoint
            .neighbours
            .iter()
            .enumerate()
            .filter(|(_, j)| **j < i)
        {
            let path = socket_path(socket_dir, j);
            let mut stream = loop {
                match UnixStream::connect(&path) {
                    Ok(s) => break s,
                    Err(_) if Instant::now() < deadline => {
                        stop_during_startup(i, &board, &endpoint.neighbours)?;
                        std::thread::sleep(Duration::from_millis(1));
                    }
                    Err(e) => {
                        let team = endpoint.team();
                        let missing = board.never_connected(&team);
                        return Err(err(format!(
                            "neighbour {j} did not listen on {} before the start-up deadline ({e}); missing: agent(s) {missing:?}",
                            path.display()
                        )));
                    }
                }
            };
            stream
                .write_all(&(i as u64).to_le_bytes())
                .map_err(|e| err(format!("handshake with neighbour {j} failed: {e}")))?;
            links[k] = Some(link(j, stream));
        }
        // Higher-numbered neighbours connect to us.
        listener
            .set_nonblocking(true)
            .map_err(|e| err(e.to_string()))?;
        while links.iter().any(Option::is_none) {
            match listener.accept() {
                Ok((mut stream, _)) => {
                    stream
                        .set_nonblocking(false)
                        .and_then(|()| {
                            stream.set_read_timeout(Some(
                                deadline
                                    .saturating_duration_since(Instant::now())
                                    .max(Duration::from_millis(1)),
                            ))
                        })
                        .map_err(|e| err(e.to_string()))?;
                    let mut word = [0u8; 8];
                    stream
                        .read_exact(&mut word)
                        .map_err(|e| err(format!("handshake failed: {e}")))?;
                    let j = u64::from_le_bytes(word) as usize;
                    let k = endpoint
                        .neighbours
                        .iter()
                        .position(|&n| n == j && n > i)
                        .filter(|&k| links[k].is_none())
                        .ok_or_else(|| err(format!("unexpected connection from agent {j}")))?;
                    links[k] = Some(link(j, stream));
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock && Instant::now() < deadline => {
                    if let Err(e) = stop_during_startup(i, &board, &endpoint.neighbours) {
                        let _ = std::fs::remove_file(&own);
                        return Err(e.into());
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => {
                    let missing: Vec<usize> = endpoint
                        .neighbours
                        .iter()
                        .zip(&links)
                        .filter(|(_, l)| l.is_none())
                        .map(|(&j, _)| j)
                        .collect();
                    let _ = std::fs::remove_file(&own);
                    let team = endpoint.team();
                    let never = board.never_connected(&team);
                    return Err(err(format!(
                        "neighbour(s) {missing:?} did not connect before the start-up deadline ({e}); missing: agent(s) {never:?}"
                    )));
                }
            }
        }
        let _ = std::fs::remove_file(&own);
        // Nobody's round deadline starts before the whole team is connected.
        board.set_connected(i);
        let team = endpoint.team();
        board
            .await_connected(&team, deadline)
            .map_err(|waited| match waited {
                Rendezvous::Stopped(signal) => ExchangeError::Stopped { agent: i, signal }.into(),
                Rendezvous::Failed(failed) => err(format!("stopped at start-up because agent {failed} failed")),
                Rendezvous::NeverConnected(missing) => err(format!(
                    "the team did not connect before the start-up deadline; missing: agent(s) {missing:?} (not started, started too late, or stuck)"
                )),
            })?;
        let links: Vec<Link> = links.into_iter().flatten().collect();
        for l in &links {
            l.stream
                .set_nonblocking(true)
                .map_err(|e| err(e.to_string()))?;
        }
        let poll_fds = links
            .iter()
            .map(|l| libc::pollfd {
                fd: l.stream.as_raw_fd(),
                events: 0,
                revents: 0,
            })
            .collect();
        Ok(Self {
            index: i,
            links,
            outbox: vec![0.0; message_words],
            policy: endpoint.policy,
            board,
            poll_fds,
        })
    }

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
