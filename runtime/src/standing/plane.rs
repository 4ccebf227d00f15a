//! Where the robots of a standing team see each other across its rosters: who is in the
//! team, who asks to join, who vanished, which rosters are forming, and a stop request to
//! everybody. Two places implement it: on one machine ([`BoardPlane`]) the team's board in
//! shared memory and its directory; across machines (`crate::standing::zenoh_plane`, feature
//! `zenoh`) Zenoh liveliness tokens.
//!
//! What the robots agree on never travels here: a roster changes only as the robots of the
//! old roster agreed in an episode's flood ([`crate::standing::roster`]), or, after a robot
//! vanished, as each of them sees it here — and they meet only on the same roster.

use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::standing::roster::{EpochId, Roster};
use crate::team::errors::JoinError;
use crate::team::membership::{Joining, Membership};
use admm_ta_transport::board::Board;
use std::path::Path;
use std::time::Instant;

/// Where the robots of a standing team see each other (see the module).
pub(crate) trait TeamPlane {
    /// This robot takes part in a roster: the others see it alive.
    fn set_member(&self);
    /// This robot asks to join (it is present, in no roster).
    fn set_joining(&self);
    /// The slots that ask to join.
    fn joiners(&self) -> Vec<usize>;
    /// Which of `slots` are gone: they left the team, or their process died or vanished.
    fn gone(&self, slots: &[usize]) -> Vec<usize>;
    /// Which of `slots` are neither in the team nor asking to join it.
    fn absent(&self, slots: &[usize]) -> Vec<usize>;
    /// A robot that vanished is certainly dead (one machine), not perhaps cut off.
    fn exact(&self) -> bool;
    /// Says that this robot is in (or forms) roster `epoch`, so that the other robots of it
    /// see it come, and a robot of it that comes late, or restarts, finds it.
    fn enter_epoch(&self, epoch: &EpochId);
    /// Says that this robot is no longer in roster `epoch`.
    fn leave_epoch(&self, epoch: &EpochId);
    /// Gives roster `epoch` up (it did not form): this robot is no longer in it, and what
    /// robots made of it goes when none is left in it.
    fn give_up_epoch(&self, epoch: &EpochId) {
        self.leave_epoch(epoch);
    }
    /// The robots of `epoch` that said they are in it (and are alive).
    fn in_epoch(&self, epoch: &EpochId) -> Vec<usize>;
    /// Says that roster `epoch` formed: every robot of it connected and synced (no robot
    /// comes into it any more: a restarted robot of it asks to join instead).
    fn set_formed(&self, epoch: &EpochId);
    /// Whether roster `epoch` formed ([`TeamPlane::set_formed`]).
    fn formed(&self, epoch: &EpochId) -> bool;
    /// The rosters robots are in or forming now.
    fn epochs(&self) -> Vec<EpochId>;
    /// Asks every robot of the team to stop: termination signal `signal` to robot `by`.
    fn request_stop(&self, signal: i32, by: usize);
    /// A stop request of another robot of the team.
    fn stop_requested(&self) -> Option<i32>;
    /// Leaves the team for good: the others see this robot gone at once (again: nothing).
    fn leave_team(&mut self);
}

/// A slot's state on a standing team's board ([`Board::set_slot_state`]).
const ASKS_TO_JOIN: u64 = 1;
const MEMBER: u64 = 2;

/// File of a roster's directory that lists its robots.
const ROSTER_FILE: &str = "roster";

/// Prefix of the files of a roster's directory that say a robot is in it (`in.<robot>`,
/// holding its process id).
const IN_FILE: &str = "in.";

/// File of a roster's directory that says it formed.
const FORMED_FILE: &str = "formed";

/// The plane of a standing team on one machine: its board (each slot's process and state,
/// the stop request) and, in its directory, one folder per roster that robots are in or
/// forming (the namespace of that roster's transport, with a file listing its robots).
pub(crate) struct BoardPlane {
    /// `None` once the robot left the team.
    membership: Option<Membership>,
    id: usize,
    namespace: RunNamespace,
    robots: usize,
}

impl BoardPlane {
    /// Robot `id` on the board of the standing team of `scenario` (its team-wide scenario)
    /// in `namespace`, present but in no roster yet.
    pub(crate) fn open(
        scenario: &Scenario,
        namespace: &RunNamespace,
        id: usize,
        deadline: Instant,
    ) -> Result<Self, JoinError> {
        let membership =
            Membership::join_as(scenario, namespace, &[id], deadline, Joining::Standing)?;
        membership.board().set_slot_state(id, ASKS_TO_JOIN);
        Ok(Self {
            membership: Some(membership),
            id,
            namespace: namespace.clone(),
            robots: scenario.robots,
        })
    }

    fn board(&self) -> Option<&Board> {
        self.membership.as_ref().map(Membership::board)
    }

    /// Whether robot `slot` takes part (a roster's robot, alive).
    fn member(&self, slot: usize) -> bool {
        self.board()
            .is_some_and(|b| b.slot_state(slot) == MEMBER && b.member_alive(slot))
    }

    /// Writes `text` as file `name` of roster `epoch`'s folder, whole.
    fn write(&self, epoch: &EpochId, name: &str, text: &str) {
        let Ok(part) = self.namespace.within(&epoch.name()) else {
            return;
        };
        // Written whole, then renamed: a reader never sees half a file.
        let temporary = part.dir.join(format!("{name}.{}.new", self.id));
        if crate::process::private_dir::write_private_file(&temporary, text.as_bytes()).is_ok() {
            let _ = std::fs::rename(&temporary, part.dir.join(name));
        }
    }
}

/// The roster in the folder `dir` of a team of `robots`, once its file is written.
fn read_roster(dir: &Path, robots: usize) -> Option<Roster> {
    let text = std::fs::read_to_string(dir.join(ROSTER_FILE)).ok()?;
    let slots: Option<Vec<usize>> = text
        .split_whitespace()
        .map(|w| w.parse().ok().filter(|&s| s < robots))
        .collect();
    slots.map(Roster::new)
}

impl TeamPlane for BoardPlane {
    fn set_member(&self) {
        if let Some(board) = self.board() {
            board.set_slot_state(self.id, MEMBER);
        }
    }

    fn set_joining(&self) {
        if let Some(board) = self.board() {
            board.set_slot_state(self.id, ASKS_TO_JOIN);
        }
    }

    fn joiners(&self) -> Vec<usize> {
        let Some(board) = self.board() else {
            return Vec::new();
        };
        (0..self.robots)
            .filter(|&s| s != self.id && board.slot_state(s) == ASKS_TO_JOIN)
            .filter(|&s| board.member_alive(s))
            .collect()
    }

    fn gone(&self, slots: &[usize]) -> Vec<usize> {
        slots
            .iter()
            .copied()
            .filter(|&s| s != self.id && !self.member(s))
            .collect()
    }

    fn absent(&self, slots: &[usize]) -> Vec<usize> {
        let Some(board) = self.board() else {
            return slots.to_vec();
        };
        slots
            .iter()
            .copied()
            .filter(|&s| s != self.id)
            .filter(|&s| board.slot_state(s) == 0 || !board.member_alive(s))
            .collect()
    }

    fn exact(&self) -> bool {
        true
    }

    fn enter_epoch(&self, epoch: &EpochId) {
        let dir = self.namespace.parts_dir().join(epoch.name());
        if !dir.join(ROSTER_FILE).exists() {
            let robots: Vec<String> = epoch.roster.robots().iter().map(usize::to_string).collect();
            self.write(epoch, ROSTER_FILE, &robots.join(" "));
        }
        self.write(
            epoch,
            &format!("{IN_FILE}{}", self.id),
            &std::process::id().to_string(),
        );
    }

    fn leave_epoch(&self, epoch: &EpochId) {
        let dir = self.namespace.parts_dir().join(epoch.name());
        let _ = std::fs::remove_file(dir.join(format!("{IN_FILE}{}", self.id)));
    }

    fn give_up_epoch(&self, epoch: &EpochId) {
        self.leave_epoch(epoch);
        if self.in_epoch(epoch).is_empty() {
            self.namespace.remove_part(&epoch.name());
        }
    }

    fn in_epoch(&self, epoch: &EpochId) -> Vec<usize> {
        let dir = self.namespace.parts_dir().join(epoch.name());
        epoch
            .roster
            .robots()
            .iter()
            .copied()
            .filter(|r| {
                std::fs::read_to_string(dir.join(format!("{IN_FILE}{r}")))
                    .ok()
                    .and_then(|pid| pid.trim().parse::<u32>().ok())
                    .is_some_and(admm_ta_transport::liveness::process_alive)
            })
            .collect()
    }

    fn set_formed(&self, epoch: &EpochId) {
        self.write(epoch, FORMED_FILE, "");
    }

    fn formed(&self, epoch: &EpochId) -> bool {
        self.namespace
            .parts_dir()
            .join(epoch.name())
            .join(FORMED_FILE)
            .exists()
    }

    fn epochs(&self) -> Vec<EpochId> {
        let Ok(entries) = std::fs::read_dir(self.namespace.parts_dir()) else {
            return Vec::new();
        };
        entries
            .flatten()
            .filter_map(|entry| {
                let name = entry.file_name().to_string_lossy().into_owned();
                let number = EpochId::number_of(&name)?;
                let roster = read_roster(&entry.path(), self.robots)?;
                let epoch = EpochId { number, roster };
                (epoch.name() == name).then_some(epoch)
            })
            .collect()
    }

    fn request_stop(&self, signal: i32, by: usize) {
        if let Some(board) = self.board() {
            let _ = board.request_stop(signal, Some(by));
        }
    }

    fn stop_requested(&self) -> Option<i32> {
        self.board()?.stop_requested().map(|(signal, _)| signal)
    }

    fn leave_team(&mut self) {
        if let Some(membership) = self.membership.take() {
            membership.leave();
        }
    }
}

impl Drop for BoardPlane {
    fn drop(&mut self) {
        self.leave_team();
    }
}
