//! The run's *board*: a small shared-memory segment every agent process of a run maps (and
//! the launcher, the members of an independently started team, a mixed host's bridge). It
//! holds, in cache lines of 64 bytes:
//!
//! * the global barrier's counters and its 32-bit futex wake-up word (line 0, byte 16);
//! * per agent (line `1 + i`): its two arrival counters (rounds of each parity, see
//!   [`arrivals_target`]), the last round it published, its process id (members of an
//!   independently started team), whether it is connected (start-up rendezvous), its
//!   32-bit futex wake-up word (byte 40) and whether it finished its run (byte 48);
//! * the failure line: the agent marked as failed (the first mark wins), the team's shape
//!   (tasks and payload length, so an agent of another shape is refused), the count of
//!   members that left, the stop request (a termination signal, distinct from a
//!   failure: [`Board::request_stop`]) and whether the team's digest is written;
//! * the team's digest (two lines: [`DIGEST_WORDS`] words).
//!
//! Every process only touches it through atomics. The `ipc` and `uds` transports, the
//! launcher and the team members all use it, so it sits below all of them.
//!
//! Size: one shared-memory layout and every accessor of it (the byte offsets stay in one
//! file), plus the waits built on its words (rendezvous, global barrier, the team check).

use crate::exchange::ExchangeError;
use crate::liveness::process_alive;
use crate::wait::CountingBarrier;
use iceoryx2::prelude::*;
use iceoryx2_bb_posix::shared_memory::{
    SharedMemory, SharedMemoryBuilder, SharedMemoryCreationError,
};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// Bytes of the board: the global barrier's line, one line per agent (two arrival counters
/// and the last round it published), then the failure line (failed agent, team shape).
fn board_size(agents: usize) -> usize {
    LINE * (agents + 4)
}

/// Words of a team digest on the board (see `process::team_digest`): 256 bits over the
/// whole team and 64 bits per part.
pub const DIGEST_WORDS: usize = 8;

const LINE: usize = 64;

// The barrier's wake-up word sits right after its counters.
const _: () = assert!(std::mem::size_of::<CountingBarrier>() <= 16);

/// Cumulative arrival count, for the parity of `round`, once all round-`round` messages of
/// an agent with `degree` neighbours are counted.
pub fn arrivals_target(degree: usize, round: u64) -> u64 {
    degree as u64 * (round / 2 + 1)
}

/// A board that cannot be opened, created or joined.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BoardError {
    #[error("bad board name {name}")]
    Name {
        name: String,
        #[source]
        source: SemanticStringError,
    },
    #[error("cannot open the run's board {name}")]
    Open {
        name: String,
        #[source]
        source: SharedMemoryCreationError,
    },
    #[error("the run's board {name} is too small")]
    TooSmall { name: String },
    #[error("cannot create the run's board {name}")]
    Create {
        name: String,
        #[source]
        source: SharedMemoryCreationError,
    },
    /// An agent whose scenario does not match the running team's shape.
    #[error(
        "this agent's scenario is {agents} robots × {tasks} tasks (payload {payload_len}) but the running team is {agents} robots × {running_tasks} tasks (payload {running_payload_len})"
    )]
    Shape {
        agents: usize,
        tasks: usize,
        payload_len: usize,
        running_tasks: u64,
        running_payload_len: u64,
    },
}

fn decode_stop(word: u64) -> (i32, Option<usize>) {
    let by = word >> 8;
    ((word & 0xff) as i32, (by != 0).then(|| by as usize - 1))
}

/// Why a start-up rendezvous ended without the whole team connected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Rendezvous {
    /// A termination signal (to this process, or requested on the board).
    Stopped(i32),
    /// An agent was marked failed.
    Failed(usize),
    /// These agents never started (or, if all did, never connected) before the deadline.
    NeverConnected(Vec<usize>),
}

/// `shm` as the name of a shared-memory segment.
fn file_name(shm: &str) -> Result<FileName, BoardError> {
    FileName::new(shm.as_bytes()).map_err(|source| BoardError::Name {
        name: shm.to_string(),
        source,
    })
}

/// The run-wide shared memory of arrival counters, published rounds, the global barrier and
/// the failure mark.
pub struct Board {
    memory: SharedMemory,
    agents: usize,
}

impl Board {
    /// Agents of the run.
    pub fn agents(&self) -> usize {
        self.agents
    }

    /// Opens the board `shm` of a run of `agents` (created by the launcher).
    pub fn open(shm: &str, agents: usize) -> Result<Self, BoardError> {
        let memory = SharedMemoryBuilder::new(&file_name(shm)?)
            .is_memory_locked(false)
            .open_existing(iceoryx2_bb_posix::access_mode::AccessMode::ReadWrite)
            .map_err(|source| BoardError::Open {
                name: shm.to_string(),
                source,
            })?;
        if memory.size() < board_size(agents) {
            return Err(BoardError::TooSmall {
                name: shm.to_string(),
            });
        }
        Ok(Self { memory, agents })
    }

    /// Opens a board whose team size is not known (`admm-ta top`): the size of the segment
    /// tells it. `None` if it cannot be opened or is not a board's size.
    pub fn open_sized(shm: &str) -> Option<Self> {
        let memory = SharedMemoryBuilder::new(&file_name(shm).ok()?)
            .is_memory_locked(false)
            .open_existing(iceoryx2_bb_posix::access_mode::AccessMode::ReadWrite)
            .ok()?;
        let lines = memory.size() / LINE;
        (memory.size() % LINE == 0 && lines > 4).then(|| Self {
            agents: lines - 4,
            memory,
        })
    }

    /// Creates the board of a run (the launcher, which owns it: it is removed when dropped),
    /// zeroed, with the team's shape `(agents, tasks, payload length)` recorded so that an
    /// agent of another shape is refused.
    pub fn create(
        shm: &str,
        agents: usize,
        tasks: usize,
        payload_len: usize,
    ) -> Result<Self, BoardError> {
        Self::create_owned(shm, agents, tasks, payload_len, true)
    }

    /// A fresh zeroed board with the team's shape; `owned`: removed when dropped.
    fn create_owned(
        shm: &str,
        agents: usize,
        tasks: usize,
        payload_len: usize,
        owned: bool,
    ) -> Result<Self, BoardError> {
        let memory = SharedMemoryBuilder::new(&file_name(shm)?)
            .is_memory_locked(false)
            .creation_mode(iceoryx2_bb_posix::creation_mode::CreationMode::PurgeAndCreate)
            .size(board_size(agents))
            .permission(iceoryx2_bb_posix::permission::Permission::OWNER_READ_WRITE)
            .zero_memory(true)
            .has_ownership(owned)
            .create()
            .map_err(|source| BoardError::Create {
                name: shm.to_string(),
                source,
            })?;
        let board = Self { memory, agents };
        let line = LINE * (agents + 1);
        board.word(line + 8).store(tasks as u64, Ordering::Relaxed);
        board
            .word(line + 16)
            .store(payload_len as u64, Ordering::Release);
        Ok(board)
    }

    fn word(&self, offset: usize) -> &AtomicU64 {
        debug_assert!(offset.is_multiple_of(8) && offset + 8 <= board_size(self.agents));
        // SAFETY: the segment is zeroed, page-aligned and `board_size` large (checked on
        // open); the offset is 8-aligned and inside it; every process only uses atomics.
        unsafe { &*(self.memory.base_address().as_ptr().add(offset) as *const AtomicU64) }
    }

    /// Opens the board of an independently started team, creating it if nobody has yet (or
    /// if the one there is left from a dead team: none of the agents recorded on it is
    /// alive). Call it under a lock that the team's other agents take too. `true` with a
    /// board this call created (its caller creates the rest of the team's resources).
    pub fn open_or_create_for_team(
        shm: &str,
        agents: usize,
        tasks: usize,
        payload_len: usize,
    ) -> Result<(Self, bool), BoardError> {
        // A dead team's board (nobody recorded on it alive) is taken over.
        if let Ok(board) = Self::open(shm, agents)
            && (0..agents).any(|i| board.member_alive(i))
        {
            board.check_shape(tasks, payload_len)?;
            return Ok((board, false));
        }
        // The last agent out removes it (with the team's other files), not its creator.
        Ok((
            Self::create_owned(shm, agents, tasks, payload_len, false)?,
            true,
        ))
    }

    /// Agent `agent` finished its run (it is about to leave): a node of it found dead from
    /// now on is one going away, not a failure.
    pub fn set_finished(&self, agent: usize) {
        self.word(LINE * (agent + 1) + 48)
            .store(1, Ordering::Release);
    }

    /// Whether agent `agent` said it finished its run ([`Board::set_finished`]).
    pub fn finished(&self, agent: usize) -> bool {
        self.word(LINE * (agent + 1) + 48).load(Ordering::Acquire) != 0
    }

    /// Records agent `agent`'s process id (independently started teams).
    pub fn set_member_pid(&self, agent: usize, pid: u32) {
        self.word(LINE * (agent + 1) + 24)
            .store(u64::from(pid), Ordering::Release);
    }

    /// The process id recorded for agent `agent` of an independently started team (`None`:
    /// it has not joined, or it left).
    pub fn member_pid(&self, agent: usize) -> Option<u32> {
        match self.word(LINE * (agent + 1) + 24).load(Ordering::Acquire) as u32 {
            0 => None,
            pid => Some(pid),
        }
    }

    /// Counts agent `agent` of an independently started team out (call it under the team's
    /// lock); `true` when no other agent of the team is left alive — every one finished, or
    /// the others died or never came — so this one removes the team's shared memory.
    pub fn member_left(&self, agent: usize) -> bool {
        self.set_member_pid(agent, 0);
        let line = LINE * (self.agents + 1);
        let finished = self.word(line + 24).fetch_add(1, Ordering::AcqRel) + 1;
        finished >= self.agents as u64 || !(0..self.agents).any(|i| self.member_alive(i))
    }

    /// Agent `agent` of an independently started team has joined and its process lives (a
    /// zombie — exited, not yet reaped by whoever started it — does not).
    pub fn member_alive(&self, agent: usize) -> bool {
        self.member_pid(agent).is_some_and(process_alive)
    }

    /// Agent `agent` of an independently started team joined and its process is gone since
    /// (it did not leave: a member that leaves clears its process id before it exits).
    ///
    /// The id is read again after the process is found gone: a member that cleared it and
    /// exited between the two reads left (200 robots leaving at once on 2 cores took such a
    /// leaver for dead, and cut their team apart).
    pub fn member_died(&self, agent: usize) -> bool {
        self.member_died_by(agent, process_alive)
    }

    /// [`Board::member_died`], with `alive` telling whether a process lives.
    fn member_died_by(&self, agent: usize, alive: impl Fn(u32) -> bool) -> bool {
        self.member_pid(agent)
            .is_some_and(|pid| !alive(pid) && self.member_pid(agent) == Some(pid))
    }

    /// Marks agent `failed` as failed (the first mark wins); every agent stops at its next
    /// wait. Returns the agent already marked, if another was first.
    pub fn mark_failed(&self, failed: usize) -> Option<usize> {
        let line = LINE * (self.agents + 1);
        match self.word(line).compare_exchange(
            0,
            failed as u64 + 1,
            Ordering::AcqRel,
            Ordering::Acquire,
        ) {
            Ok(_) => None,
            Err(first) => Some(first as usize - 1),
        }
    }

    /// Asks every process of the team to stop because of termination signal `signal`, sent
    /// to agent `by` (`None`: to the launcher or a host). The first request wins; returns
    /// the one already there, if another was first.
    pub fn request_stop(&self, signal: i32, by: Option<usize>) -> Option<(i32, Option<usize>)> {
        let word = (signal as u64 & 0xff) | (by.map_or(0, |a| a as u64 + 1) << 8);
        match self.word(LINE * (self.agents + 1) + 32).compare_exchange(
            0,
            word,
            Ordering::AcqRel,
            Ordering::Acquire,
        ) {
            Ok(_) => None,
            Err(first) => Some(decode_stop(first)),
        }
    }

    /// The stop request on the board, if any: the signal and the agent it was sent to
    /// (`None`: the launcher or a host). Distinct from a failure: nobody is to blame.
    pub fn stop_requested(&self) -> Option<(i32, Option<usize>)> {
        let word = self
            .word(LINE * (self.agents + 1) + 32)
            .load(Ordering::Acquire);
        (word != 0).then(|| decode_stop(word))
    }

    /// Why agent `agent`, waiting in round `round`, must stop, if it must: a termination
    /// signal or a stop request ([`Board::stop_signal`]: nobody to blame), or an agent marked
    /// failed (itself, by a neighbour that found it misbehaving). The check every process
    /// transport that reads the board makes in its waits.
    pub fn check_team(&self, agent: usize, round: u64) -> Result<(), ExchangeError> {
        if let Some(signal) = self.stop_signal() {
            return Err(ExchangeError::Stopped { agent, signal });
        }
        if let Some(failed) = self.failed() {
            let how = if failed == agent {
                "was reported failed by a neighbour"
            } else {
                "failed"
            };
            return Err(ExchangeError::PeerFailed {
                agent,
                failed,
                round,
                how: how.into(),
            });
        }
        Ok(())
    }

    /// Why an agent must stop now, if it must: a termination signal to this process, or a
    /// stop request on the board (the signal went to the launcher, a host or another
    /// agent). Two atomic loads: cheap enough for every round.
    pub fn stop_signal(&self) -> Option<i32> {
        crate::signals::received().or_else(|| self.stop_requested().map(|(s, _)| s))
    }

    /// Waits until every agent of `team` announced it is connected ([`Board::set_connected`]),
    /// a stop request, a failure mark, or `deadline`; at the deadline, the first agent that
    /// never connected is marked failed (not a neighbour waiting for it).
    pub fn await_connected(
        &self,
        team: &[usize],
        deadline: std::time::Instant,
    ) -> Result<(), Rendezvous> {
        // Sleeps on the barrier's wake word, which every `set_connected` bumps (no polling:
        // a hundred agents polling while the last ones start took their cores), in slices
        // between which it looks for stop requests and failure marks.
        let word = self.barrier_wake_word();
        loop {
            let seen = word.load(Ordering::Acquire);
            if let Some(signal) = self.stop_signal() {
                return Err(Rendezvous::Stopped(signal));
            }
            if let Some(failed) = self.failed() {
                return Err(Rendezvous::Failed(failed));
            }
            if team.iter().all(|&a| self.connected(a)) {
                return Ok(());
            }
            // A member of an independently started team whose process died while it started.
            if let Some(&dead) = team.iter().find(|&&a| self.member_died(a)) {
                let _ = self.mark_failed(dead);
                return Err(Rendezvous::Failed(dead));
            }
            if std::time::Instant::now() >= deadline {
                return Err(Rendezvous::NeverConnected(self.never_connected(team)));
            }
            crate::futex::wait_slice(word, seen, deadline);
        }
    }

    /// Arrives at the run's global barrier and waits, under `policy`, for the last of its
    /// agents until `deadline`: `Ok(false)` at the deadline. Sleeps on the barrier's wake
    /// word in slices; `between(whole_slice_passed)` runs after each (a transport's failure
    /// checks) and ends the wait with its error.
    pub fn global_barrier<E>(
        &self,
        policy: crate::wait::WaitPolicy,
        deadline: std::time::Instant,
        mut between: impl FnMut(bool) -> Result<(), E>,
    ) -> Result<bool, E> {
        let (state, word) = (self.barrier(), self.barrier_wake_word());
        // Read before arriving: a release after this read changes the word.
        let mut seen = word.load(Ordering::Acquire);
        match state.arrive(self.agents) {
            crate::wait::Arrival::Released => {
                crate::futex::bump_and_wake(word);
                Ok(true)
            }
            crate::wait::Arrival::Wait(ticket) => policy.wait_until(
                &mut seen,
                deadline,
                |seen| {
                    *seen = word.load(Ordering::Acquire);
                    Ok(state.released(ticket))
                },
                |seen, deadline| between(crate::futex::wait_slice(word, *seen, deadline)),
            ),
        }
    }

    /// The agents of `team` to blame for a start-up that did not complete: those that never
    /// started (registered), else those that never connected; the first is marked failed.
    pub fn never_connected(&self, team: &[usize]) -> Vec<usize> {
        let mut missing: Vec<usize> = team
            .iter()
            .copied()
            .filter(|&a| !self.registered(a))
            .collect();
        if missing.is_empty() {
            missing = team
                .iter()
                .copied()
                .filter(|&a| !self.connected(a))
                .collect();
        }
        if let Some(&first) = missing.first() {
            let _ = self.mark_failed(first);
        }
        missing
    }

    /// The agent marked as failed, if any.
    pub fn failed(&self) -> Option<usize> {
        let marked = self.word(LINE * (self.agents + 1)).load(Ordering::Acquire);
        (marked != 0).then(|| marked as usize - 1)
    }

    /// Refuses an agent whose scenario does not match the running team's shape.
    pub fn check_shape(&self, tasks: usize, payload_len: usize) -> Result<(), BoardError> {
        let line = LINE * (self.agents + 1);
        let running = (
            self.word(line + 8).load(Ordering::Relaxed),
            self.word(line + 16).load(Ordering::Acquire),
        );
        if running != (tasks as u64, payload_len as u64) {
            return Err(BoardError::Shape {
                agents: self.agents,
                tasks,
                payload_len,
                running_tasks: running.0,
                running_payload_len: running.1,
            });
        }
        Ok(())
    }

    /// Writes the team's digest (its creator, before any agent reads it): the words, then
    /// the flag that says they are there.
    pub fn set_digest(&self, words: &[u64; DIGEST_WORDS]) {
        let base = LINE * (self.agents + 2);
        for (k, &w) in words.iter().enumerate() {
            self.word(base + 8 * k).store(w, Ordering::Relaxed);
        }
        self.word(LINE * (self.agents + 1) + 40)
            .store(1, Ordering::Release);
    }

    /// The team's digest, once its creator wrote it.
    pub fn digest(&self) -> Option<[u64; DIGEST_WORDS]> {
        if self
            .word(LINE * (self.agents + 1) + 40)
            .load(Ordering::Acquire)
            == 0
        {
            return None;
        }
        let base = LINE * (self.agents + 2);
        Some(std::array::from_fn(|k| {
            self.word(base + 8 * k).load(Ordering::Relaxed)
        }))
    }

    /// Sets slot `agent`'s state word (the start-up rendezvous's: 0 nothing, 1 registered,
    /// 2 connected). A standing team's board keeps there where its robot is: 0 free, 1 it
    /// asks to join (or is starting), 2 it takes part (the runtime's `standing` teams).
    pub fn set_slot_state(&self, agent: usize, state: u64) {
        self.word(LINE * (agent + 1) + 32)
            .store(state, Ordering::Release);
    }

    /// Slot `agent`'s state word ([`Board::set_slot_state`]).
    pub fn slot_state(&self, agent: usize) -> u64 {
        self.word(LINE * (agent + 1) + 32).load(Ordering::Acquire)
    }

    /// Agent `agent` has its publisher connected to every subscriber and its subscribers
    /// in place: the start-up rendezvous ([`Board::connected`]).
    pub fn set_connected(&self, agent: usize) {
        self.word(LINE * (agent + 1) + 32)
            .store(2, Ordering::Release);
        // Wakes the agents waiting for the team in `await_connected`.
        crate::futex::bump_and_wake(self.barrier_wake_word());
    }

    /// Agent `agent`'s process started and opened the board (start-up evidence: an agent
    /// that never registered is the one to blame, not the neighbours waiting for it).
    pub fn set_registered(&self, agent: usize) {
        let _ = self.word(LINE * (agent + 1) + 32).compare_exchange(
            0,
            1,
            Ordering::AcqRel,
            Ordering::Acquire,
        );
    }

    /// Whether agent `agent` registered ([`Board::set_registered`]) or connected.
    pub fn registered(&self, agent: usize) -> bool {
        self.word(LINE * (agent + 1) + 32).load(Ordering::Acquire) != 0
    }

    /// Whether agent `agent` announced it is connected. Nobody publishes round 0 before
    /// every agent of the team (on this board) did, so that no round deadline starts while
    /// a member of the team is still starting.
    pub fn connected(&self, agent: usize) -> bool {
        self.word(LINE * (agent + 1) + 32).load(Ordering::Acquire) == 2
    }

    /// The agent that published the fewest rounds (the lowest number among equals): after
    /// a timeout, the one everybody is waiting for, directly or through a chain of blocked
    /// neighbours (a stopped process).
    pub fn laggard(&self) -> Option<usize> {
        (0..self.agents).min_by_key(|&a| (self.published_round(a), a))
    }

    /// Last round agent `agent` published (0 before its first step).
    pub fn published_round(&self, agent: usize) -> u64 {
        self.word(LINE * (agent + 1) + 16).load(Ordering::Relaxed)
    }

    pub fn set_published_round(&self, agent: usize, round: u64) {
        self.word(LINE * (agent + 1) + 16)
            .store(round, Ordering::Relaxed);
    }

    pub fn barrier(&self) -> &CountingBarrier {
        // SAFETY: the launcher created the segment zeroed and `board_size` large (checked on
        // open); the mapping is page-aligned, and every process only touches it through
        // atomics.
        unsafe { &*(self.memory.base_address().as_ptr() as *const CountingBarrier) }
    }

    /// Agent `agent`'s wake-up word (a 32-bit word of its line, for [`crate::futex`]): a
    /// process that makes agent `agent`'s wait end bumps it, then wakes its sleepers.
    pub fn wake_word(&self, agent: usize) -> &AtomicU32 {
        debug_assert!(agent < self.agents);
        self.word32(LINE * (agent + 1) + 40)
    }

    /// The global barrier's wake-up word (for [`crate::futex`]), next to its counters.
    pub fn barrier_wake_word(&self) -> &AtomicU32 {
        self.word32(16)
    }

    fn word32(&self, offset: usize) -> &AtomicU32 {
        debug_assert!(offset.is_multiple_of(4) && offset + 4 <= board_size(self.agents));
        // SAFETY: as in `word`, for a 4-aligned offset.
        unsafe { &*(self.memory.base_address().as_ptr().add(offset) as *const AtomicU32) }
    }

    /// Agent `agent`'s arrival counter for rounds of parity `round % 2`.
    pub fn arrivals(&self, agent: usize, round: u64) -> &AtomicU64 {
        debug_assert!(agent < self.agents);
        self.word(LINE * (agent + 1) + 8 * (round % 2) as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A member that clears its process id and exits between a neighbour's two reads
    /// (its id, then whether the process lives) left: it did not die.
    #[test]
    fn a_member_that_left_between_the_two_reads_did_not_die() {
        let shm = format!("adtboard{}", std::process::id());
        let board = Board::create(&shm, 2, 2, 4).unwrap();
        board.set_member_pid(1, 4_000_000);
        // The process is gone, its id still recorded: it died.
        assert!(board.member_died_by(1, |_| false));
        // It cleared its id (it left), then exited, while the neighbour looked.
        let leaves = |_| {
            board.set_member_pid(1, 0);
            false
        };
        assert!(!board.member_died_by(1, leaves));
        assert!(!board.member_died_by(1, |_| false), "no id: not a member");
        board.set_member_pid(0, std::process::id());
        assert!(!board.member_died(0), "this process lives");
    }
}
