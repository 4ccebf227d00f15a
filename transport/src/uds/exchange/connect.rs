//! A `uds` agent's start-up: it dials its lower-numbered neighbours, accepts its
//! higher-numbered ones, then waits for the whole team on the board.

use super::{HEADER_WORDS, Link, UdsExchange, socket_path, transport};

use crate::board::{Board, Rendezvous};
use crate::endpoint::{ConnectError, ConnectRequest};
use crate::exchange::ExchangeError;
use crate::exchange::header::RoundHeader;
use std::io::{ErrorKind, Read, Write};
use std::os::fd::AsRawFd;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The agent's socket could not be bound.
#[derive(Debug, thiserror::Error)]
#[error("cannot listen on {}", path.display())]
struct CannotListen {
    path: PathBuf,
    #[source]
    source: std::io::Error,
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

/// The link to neighbour `neighbour` over `stream`, for messages of `payload_len` values.
fn new_link(neighbour: usize, stream: UnixStream, payload_len: usize) -> Link {
    let message_words = HEADER_WORDS + payload_len;
    Link {
        neighbour,
        stream,
        inbox: vec![0.0; message_words],
        received: 0,
        header: RoundHeader::default(),
        sent: message_words * 8,
    }
}

/// Connects to the lower-numbered neighbours (they listen for us), until `deadline`.
fn dial_lower(
    endpoint: &ConnectRequest,
    board: &Board,
    links: &mut [Option<Link>],
    deadline: Instant,
) -> Result<(), ConnectError> {
    let i = endpoint.index;
    let err = |what: String| ConnectError::from(transport(i, what));
    for (k, &j) in endpoint
        .neighbours
        .iter()
        .enumerate()
        .filter(|(_, j)| **j < i)
    {
        let path = socket_path(&endpoint.run.dir, j);
        let mut stream = loop {
            match UnixStream::connect(&path) {
                Ok(s) => break s,
                Err(_) if Instant::now() < deadline => {
                    stop_during_startup(i, board, &endpoint.neighbours)?;
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => {
                    let missing = board.never_connected(&endpoint.team());
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
        links[k] = Some(new_link(j, stream, endpoint.payload_len));
    }
    Ok(())
}

/// Accepts the higher-numbered neighbours on `listener` (they connect to us), until
/// `deadline`.
fn accept_higher(
    endpoint: &ConnectRequest,
    board: &Board,
    listener: &UnixListener,
    links: &mut [Option<Link>],
    deadline: Instant,
) -> Result<(), ConnectError> {
    let i = endpoint.index;
    let err = |what: String| ConnectError::from(transport(i, what));
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
                links[k] = Some(new_link(j, stream, endpoint.payload_len));
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock && Instant::now() < deadline => {
                stop_during_startup(i, board, &endpoint.neighbours)?;
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(e) => {
                let missing: Vec<usize> = endpoint
                    .neighbours
                    .iter()
                    .zip(links.iter())
                    .filter(|(_, l)| l.is_none())
                    .map(|(&j, _)| j)
                    .collect();
                let never = board.never_connected(&endpoint.team());
                return Err(err(format!(
                    "neighbour(s) {missing:?} did not connect before the start-up deadline ({e}); missing: agent(s) {never:?}"
                )));
            }
        }
    }
    Ok(())
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
        let mut links: Vec<Option<Link>> = endpoint.neighbours.iter().map(|_| None).collect();
        let linked = dial_lower(endpoint, &board, &mut links, deadline)
            .and_then(|()| accept_higher(endpoint, &board, &listener, &mut links, deadline));
        let _ = std::fs::remove_file(&own);
        linked?;
        // Nobody's round deadline starts before the whole team is connected.
        board.set_connected(i);
        board
            .await_connected(&endpoint.team(), deadline)
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
            outbox: vec![0.0; HEADER_WORDS + endpoint.payload_len],
            policy: endpoint.policy,
            board,
            poll_fds,
        })
    }
}
