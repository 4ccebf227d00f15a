//! The `shm` transport's slot table: one POSIX shared-memory segment per run, in cache lines
//! of 64 bytes:
//!
//! * line 0: the table's shape (agents, payload length), written by its creator;
//! * the control region, three lines per agent `i` from line `1 + 3i`: its published-round
//!   word (the latest round + 1, 0 before round 0), then the head of each of its two slots
//!   (round parity): the round header and the payload length;
//! * the payload region: the payloads of agent `i`'s two slots, each padded to whole lines.
//!
//! What a gather reads of every neighbour (its published-round word and its slot's head)
//! sits in the dense control region: a few pages for a hundred agents, so that a process
//! that was just switched in takes few TLB misses to look at all its neighbours.
//!
//! A slot is written only by its owner, for a round no neighbour reads any more, and read
//! only after the owner's release store of its published-round word (see
//! [`crate::shm::exchange`]).

use crate::exchange::header::RoundHeader;
use iceoryx2::prelude::*;
use iceoryx2_bb_posix::shared_memory::{
    SharedMemory, SharedMemoryBuilder, SharedMemoryCreationError,
};
use std::ptr::NonNull;
use std::sync::atomic::{AtomicU64, Ordering};

const LINE: usize = 64;
const PAGE: usize = 4096;

/// The line heading a slot: the round header and the number of payload values written.
#[repr(C)]
struct SlotHead {
    header: RoundHeader,
    len: u64,
}

const _: () = assert!(std::mem::size_of::<SlotHead>() == LINE);

/// Name of the slot table of the run whose shared memory is prefixed `prefix`.
pub fn table_name(prefix: &str) -> String {
    format!("{prefix}slots")
}

/// A slot table that cannot be created or opened.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TableError {
    #[error("bad slot table name {name}")]
    Name {
        name: String,
        #[source]
        source: SemanticStringError,
    },
    #[error("cannot create the run's slot table {name}")]
    Create {
        name: String,
        #[source]
        source: SharedMemoryCreationError,
    },
    #[error("cannot open the run's slot table {name}")]
    Open {
        name: String,
        #[source]
        source: SharedMemoryCreationError,
    },
    #[error(
        "the run's slot table {name} is for {running_agents} agents with payload {running_payload_len}, not {agents} with payload {payload_len}"
    )]
    Shape {
        name: String,
        agents: usize,
        payload_len: usize,
        running_agents: u64,
        running_payload_len: u64,
    },
}

/// Byte offsets of the table of a run.
#[derive(Debug, Clone, Copy)]
struct Layout {
    agents: usize,
    payload_len: usize,
    /// Bytes of one payload, in whole lines.
    payload: usize,
}

impl Layout {
    fn new(agents: usize, payload_len: usize) -> Self {
        Self {
            agents,
            payload_len,
            payload: (payload_len * 8).next_multiple_of(LINE),
        }
    }

    fn size(self) -> usize {
        self.payloads() + 2 * self.agents * self.payload
    }

    fn published(self, agent: usize) -> usize {
        LINE + 3 * LINE * agent
    }

    fn head(self, agent: usize, parity: usize) -> usize {
        self.published(agent) + LINE + parity * LINE
    }

    /// Where the payload region starts.
    fn payloads(self) -> usize {
        LINE + 3 * LINE * self.agents
    }

    fn payload(self, agent: usize, parity: usize) -> usize {
        self.payloads() + (2 * agent + parity) * self.payload
    }
}

/// The run's slot table, mapped into this process.
pub struct SlotTable {
    memory: SharedMemory,
    base: NonNull<u8>,
    layout: Layout,
}

fn file_name(name: &str) -> Result<FileName, TableError> {
    FileName::new(name.as_bytes()).map_err(|source| TableError::Name {
        name: name.to_string(),
        source,
    })
}

impl SlotTable {
    /// Creates the table `name` of a run of `agents` with payloads of `payload_len` values
    /// (the launcher, which owns it: it is removed when dropped): owner-only, zeroed, every
    /// page touched so that no agent takes a page fault in a round.
    pub fn create(name: &str, agents: usize, payload_len: usize) -> Result<Self, TableError> {
        let layout = Layout::new(agents, payload_len);
        let memory = SharedMemoryBuilder::new(&file_name(name)?)
            .is_memory_locked(false)
            .creation_mode(iceoryx2_bb_posix::creation_mode::CreationMode::PurgeAndCreate)
            .size(layout.size())
            .permission(iceoryx2_bb_posix::permission::Permission::OWNER_READ_WRITE)
            .zero_memory(true)
            .has_ownership(true)
            .create()
            .map_err(|source| TableError::Create {
                name: name.to_string(),
                source,
            })?;
        let table = Self::over(memory, layout);
        table.touch_pages(true);
        table.shape_word(0).store(agents as u64, Ordering::Relaxed);
        table
            .shape_word(8)
            .store(payload_len as u64, Ordering::Release);
        Ok(table)
    }

    /// Opens the table `name` (created by the launcher) of a run of `agents` with payloads
    /// of `payload_len` values, and maps every page of it.
    pub fn open(name: &str, agents: usize, payload_len: usize) -> Result<Self, TableError> {
        let layout = Layout::new(agents, payload_len);
        let memory = SharedMemoryBuilder::new(&file_name(name)?)
            .is_memory_locked(false)
            .open_existing(iceoryx2_bb_posix::access_mode::AccessMode::ReadWrite)
            .map_err(|source| TableError::Open {
                name: name.to_string(),
                source,
            })?;
        let shape_error = |running: (u64, u64)| TableError::Shape {
            name: name.to_string(),
            agents,
            payload_len,
            running_agents: running.0,
            running_payload_len: running.1,
        };
        if memory.size() < layout.size() {
            return Err(shape_error((0, 0)));
        }
        let table = Self::over(memory, layout);
        // The payload length is written last (release): read it first.
        let running_payload_len = table.shape_word(8).load(Ordering::Acquire);
        let running = (
            table.shape_word(0).load(Ordering::Relaxed),
            running_payload_len,
        );
        if running != (agents as u64, payload_len as u64) {
            return Err(shape_error(running));
        }
        table.touch_pages(false);
        Ok(table)
    }

    fn over(memory: SharedMemory, layout: Layout) -> Self {
        let base = memory.base_address();
        Self {
            memory,
            base,
            layout,
        }
    }

    /// Faults every page of the mapping in (writing when `write`: the creator).
    fn touch_pages(&self, write: bool) {
        let size = self.layout.size().min(self.memory.size());
        for offset in (0..size).step_by(PAGE) {
            // SAFETY: inside the mapping; a volatile access of one byte, before any agent
            // uses the table (the creator writes the zero the page already holds).
            unsafe {
                let byte = self.base.as_ptr().add(offset);
                if write {
                    byte.write_volatile(0);
                } else {
                    let _ = byte.read_volatile();
                }
            }
        }
    }

    fn shape_word(&self, offset: usize) -> &AtomicU64 {
        // SAFETY: line 0 is inside the mapping, 8-aligned (the mapping is page-aligned);
        // every process only uses it through atomics.
        unsafe { &*(self.base.as_ptr().add(offset) as *const AtomicU64) }
    }

    /// Agents of the run.
    pub fn agents(&self) -> usize {
        self.layout.agents
    }

    /// Values of a payload.
    pub fn payload_len(&self) -> usize {
        self.layout.payload_len
    }

    /// Agent `agent`'s published-round word: its latest round + 1 (0: nothing yet).
    pub fn published(&self, agent: usize) -> &AtomicU64 {
        assert!(
            agent < self.layout.agents,
            "agent {agent} is not in the table"
        );
        // SAFETY: as in `shape_word`, for the agent's first line.
        unsafe { &*(self.base.as_ptr().add(self.layout.published(agent)) as *const AtomicU64) }
    }

    fn head(&self, agent: usize, parity: usize) -> *mut SlotHead {
        assert!(
            agent < self.layout.agents,
            "agent {agent} is not in the table"
        );
        // SAFETY: the head is inside the mapping (its size was checked), line-aligned.
        unsafe {
            self.base
                .as_ptr()
                .add(self.layout.head(agent, parity % 2))
                .cast()
        }
    }

    fn payload_ptr(&self, agent: usize, parity: usize) -> *mut f64 {
        assert!(
            agent < self.layout.agents,
            "agent {agent} is not in the table"
        );
        // SAFETY: the payload is inside the mapping, line-aligned.
        unsafe {
            self.base
                .as_ptr()
                .add(self.layout.payload(agent, parity % 2))
                .cast()
        }
    }

    /// The round header in agent `agent`'s slot of parity `parity`.
    ///
    /// # Safety
    /// The owner published this slot (the caller saw its published-round word, acquire)
    /// and does not rewrite it while the reference lives (the round protocol).
    pub unsafe fn header(&self, agent: usize, parity: usize) -> &RoundHeader {
        // SAFETY: as the caller promises.
        unsafe { &(*self.head(agent, parity)).header }
    }

    /// The number of payload values in agent `agent`'s slot of parity `parity`.
    ///
    /// # Safety
    /// As for [`SlotTable::header`].
    pub unsafe fn written_len(&self, agent: usize, parity: usize) -> u64 {
        // SAFETY: as the caller promises.
        unsafe { (*self.head(agent, parity)).len }
    }

    /// The payload in agent `agent`'s slot of parity `parity`.
    ///
    /// # Safety
    /// As for [`SlotTable::header`].
    pub unsafe fn payload(&self, agent: usize, parity: usize) -> &[f64] {
        // SAFETY: as the caller promises; the slot holds `payload_len` values.
        unsafe {
            std::slice::from_raw_parts(self.payload_ptr(agent, parity), self.layout.payload_len)
        }
    }

    /// The own payload of parity `parity`, to write in place.
    ///
    /// # Safety
    /// Only agent `agent` calls it, for a slot no neighbour reads any more (its round is
    /// two behind the one about to be written), and holds no other reference to it.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn own_payload(&self, agent: usize, parity: usize) -> &mut [f64] {
        // SAFETY: as the caller promises.
        unsafe {
            std::slice::from_raw_parts_mut(self.payload_ptr(agent, parity), self.layout.payload_len)
        }
    }

    /// Writes the head of the own slot of parity `parity`: `header` and `len` values.
    ///
    /// # Safety
    /// As for [`SlotTable::own_payload`].
    pub unsafe fn write_head(&self, agent: usize, parity: usize, header: RoundHeader, len: u64) {
        // SAFETY: as the caller promises.
        unsafe { self.head(agent, parity).write(SlotHead { header, len }) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_opens_with_its_shape_only() {
        let name = format!("adta-test-{}-slots", std::process::id());
        let table = SlotTable::create(&name, 3, 5).unwrap();
        table.published(2).store(7, Ordering::Release);
        let opened = SlotTable::open(&name, 3, 5).unwrap();
        assert_eq!(opened.published(2).load(Ordering::Acquire), 7);
        assert!(matches!(
            SlotTable::open(&name, 3, 4),
            Err(TableError::Shape { .. })
        ));
        assert!(matches!(
            SlotTable::open(&name, 9, 5),
            Err(TableError::Shape { .. })
        ));
        // SAFETY: one thread, nobody else maps the table.
        unsafe {
            table.own_payload(1, 1).fill(2.5);
            table.write_head(1, 1, RoundHeader::initial(1), 5);
            assert_eq!(opened.payload(1, 1), &[2.5; 5]);
            assert_eq!(opened.header(1, 1).sender, 1);
            assert_eq!(opened.written_len(1, 1), 5);
            // Slots do not overlap.
            assert_eq!(opened.payload(1, 0), &[0.0; 5]);
            assert_eq!(opened.payload(2, 1), &[0.0; 5]);
        }
        drop(opened);
        drop(table);
        assert!(
            SlotTable::open(&name, 3, 5).is_err(),
            "the owner removes it"
        );
    }
}
