//! Agents started independently, in any order, by any supervisor (systemd, a shell script, a
//! ROS launch file): `admm-ta agent --team FILE --robot I`. No launcher: every agent reads the
//! same team file ([`crate::team::team_file`]), derives the same problem, graph, settings
//! and namespace from it, finds its neighbours through iceoryx2 service discovery, waits for
//! them until the start-up deadline (naming the ones that never came), runs, and writes
//! `result-I.json` into the team's results directory; `admm-ta collect --team FILE`
//! assembles the assignment.
//!
//! The run's shared board and, for `ipc`, every iceoryx2 service of the team are created by
//! whichever agent comes first (under a file lock in the team's directory, so the others only
//! open them: no open/create races); the board is removed, with every other shared-memory file of the team, by the
//! last agent to leave. A board left by a dead team (no agent recorded on it is alive) is
//! taken over by the next team of that name. One team per name at a time.

use crate::process::agent::{AgentReport, result_path, run_scenario};
use crate::process::connect::{RunResources, cleanup_dead};
use crate::process::member_error::MemberError;
use crate::process::namespace::RunNamespace;
use crate::process::scenario::Scenario;
use crate::process::team_digest::TeamDigest;
use crate::standing::agreement::message_len;
use crate::team::errors::{JoinError, PrivateTeamError, TeamFileError};
use crate::team::team_file::{HostEntry, Team};
use crate::workload::Workload;
use crate::workload::plan::prepare;
use admm_ta_agents::certify::local_stop::LocalCertifiedStop;
use admm_ta_transport::board::Board;
use admm_ta_transport::exchange::round_loop::AgentStop;
use std::os::fd::AsRawFd;
use std::path::Path;
use std::time::{Duration, Instant};

/// An exclusive `flock` on a file, released when dropped.
struct FileLock(std::fs::File);

impl FileLock {
    fn acquire(path: &Path, deadline: Instant) -> Result<Self, JoinError> {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(path)
            .map_err(|source| JoinError::Lock {
                path: path.to_path_buf(),
                source,
            })?;
        loop {
            // SAFETY: flock on a descriptor this function owns.
            if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } == 0 {
                return Ok(Self(file));
            }
            if Instant::now() >= deadline {
                return Err(JoinError::LockTaken {
                    path: path.to_path_buf(),
                });
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

impl Drop for FileLock {
    fn drop(&mut self) {
        // SAFETY: unlocking the descriptor we locked.
        unsafe { libc::flock(self.0.as_raw_fd(), libc::LOCK_UN) };
    }
}

/// The scenario every agent of the team derives from the team file, before the names of
/// one machine's run (what the team's digest is over).
pub(crate) fn team_scenario(team: &Team) -> Result<Scenario, TeamFileError> {
    let (problem, graph) = team.problem_and_graph()?;
    let options = team.solve_options().map_err(TeamFileError::Options)?;
    // The options refused a centralized method on the team's process transport.
    let setup = options
        .method_setup()
        .ok_or_else(|| TeamFileError::Centralized {
            method: options.method().name(),
        })?;
    // The agents solve the normalised problem, as a solve's do.
    let plan = prepare(problem.internal(), &graph, &options, setup)?;
    let stop = LocalCertifiedStop::new(plan.diameter, problem.robots(), plan.tolerance)?
        .with_cadence(plan.stop_cadence);
    let mut scenario = Scenario::new(
        Workload::Solve {
            plan: &plan,
            stop: &AgentStop::Local(stop),
            max_rounds: options.max_iters() as u64,
        },
        &graph,
        options.run(),
    );
    if team.is_private() {
        let payload = scenario.payload_len();
        scenario.message_len = Some(message_len(payload, problem.robots(), problem.tasks()));
    }
    Ok(scenario)
}

/// The scenario every agent of the team derives from the team file, in the namespace of
/// its machine (`host`, in a mixed team: each host has its own); a refusal.
pub(crate) fn member_scenario(
    team: &Team,
    host: Option<&HostEntry>,
) -> Result<(Scenario, RunNamespace), MemberError> {
    let mut scenario = team_scenario(team).map_err(MemberError::refused)?;
    let namespace = match host {
        Some(host) => RunNamespace::for_team(&format!("{}-{}", team.file.run, host.name)),
        None => RunNamespace::for_team(&team.file.run),
    }
    .map_err(MemberError::refused)?;
    scenario.run_id = namespace.id.clone();
    scenario.prefix = namespace.prefix.clone();
    scenario.transport_root = namespace.transport_root();
    scenario.board_shm = namespace.board_shm();
    scenario.local_agents = host.map(|h| h.agents.clone());
    Ok((scenario, namespace))
}

/// A place on the team's board in shared memory: an agent's own slot, or (a mixed host's
/// bridge) the slots of the agents it stands in for. The board is created by whoever comes
/// first; the last member to leave removes every shared-memory file of the namespace.
pub(crate) struct Membership {
    /// The team's services, created by its first member and kept until it leaves (a
    /// service lives while a node holds it: the other members hold their own ports).
    _resources: Option<RunResources>,
    board: Board,
    namespace: RunNamespace,
    slots: Vec<usize>,
    joining: Joining,
}

/// What a [`Membership`] is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Joining {
    /// A run of the team's transport: its first member creates the transport's resources,
    /// and a slot whose process already took part in it is refused.
    Run,
    /// A standing team's presence ([`crate::standing`]): no transport of its own, and a
    /// slot may come back (a robot restarted after it left or crashed).
    Standing,
}

impl Membership {
    /// Joins the board of `scenario` for `slots`, under the team's lock (until `deadline`).
    pub(crate) fn join(
        scenario: &Scenario,
        namespace: &RunNamespace,
        slots: &[usize],
        deadline: Instant,
    ) -> Result<Self, JoinError> {
        Self::join_as(scenario, namespace, slots, deadline, Joining::Run)
    }

    /// [`Membership::join`] for what `joining` says.
    pub(crate) fn join_as(
        scenario: &Scenario,
        namespace: &RunNamespace,
        slots: &[usize],
        deadline: Instant,
        joining: Joining,
    ) -> Result<Self, JoinError> {
        let _lock = FileLock::acquire(&namespace.dir.join("lock"), deadline)?;
        let n = scenario.robots;
        let (board, fresh) = Board::open_or_create_for_team(
            &scenario.board_shm,
            n,
            scenario.tasks,
            scenario.payload_len(),
        )?;
        // The first member writes the team's digest; the others must match it.
        let digest = TeamDigest::of(scenario);
        if board.digest().is_none() {
            digest.publish(&board);
        }
        if let Some(&first) = slots.first() {
            digest.check(&board, first)?;
        }
        // One process per slot: a second copy of a running agent (a supervisor's restart, a
        // script started twice) is refused by name before it touches anything, and the team
        // runs on; so is a copy of one that already took part in this run.
        for &slot in slots {
            if let Some(pid) = board.member_pid(slot).filter(|_| board.member_alive(slot)) {
                return Err(JoinError::AlreadyRunning { slot, pid });
            }
            if !fresh && joining == Joining::Run && board.registered(slot) {
                return Err(JoinError::TookPart { slot });
            }
        }
        for &slot in slots {
            board.set_member_pid(slot, std::process::id());
        }
        let resources = if joining == Joining::Standing {
            if fresh {
                // A team of this name that died whole: the leftovers of its parts go.
                namespace.remove_parts();
            }
            None
        } else if fresh {
            // Mode 0700, ours, not a symlink (its name in /dev/shm is predictable).
            crate::process::private_dir::ensure_private_dir(&scenario.transport_root)?;
            // Nodes of a dead team of this name.
            let _ = cleanup_dead(scenario, &namespace.dir);
            // The first member creates every service of the team before anybody opens one
            // (the others wait for the lock we hold).
            Some(RunResources::create(scenario, &namespace.dir)?)
        } else {
            crate::process::private_dir::ensure_private_dir(&scenario.transport_root)?;
            None
        };
        Ok(Self {
            _resources: resources,
            board,
            namespace: namespace.clone(),
            slots: slots.to_vec(),
            joining,
        })
    }

    pub(crate) fn board(&self) -> &Board {
        &self.board
    }

    /// Counts the slots out; the last member of the team removes its namespace.
    ///
    /// The services a first member created are dropped while the team's lock is held: the
    /// last member removes every file of the namespace under that lock, so a creator that
    /// dropped them after releasing it could find their storage already gone (iceoryx2
    /// then warns on standard error that "the static storage was already removed").
    pub(crate) fn leave(self) {
        let Self {
            _resources: resources,
            board,
            namespace,
            slots,
            joining,
        } = self;
        let deadline = Instant::now() + Duration::from_secs(5);
        let last = match FileLock::acquire(&namespace.dir.join("lock"), deadline) {
            Ok(_lock) => {
                let mut last = false;
                for &slot in &slots {
                    last |= match joining {
                        Joining::Run => board.member_left(slot),
                        // Slots come and go: the last one alive is the last.
                        Joining::Standing => {
                            board.set_slot_state(slot, 0);
                            board.set_member_pid(slot, 0);
                            !(0..board.agents()).any(|a| board.member_alive(a))
                        }
                    };
                }
                drop(resources);
                last
            }
            Err(_) => {
                // Without the lock, still not a death: a neighbour that finds the process
                // gone with its id recorded would take this member for crashed.
                for &slot in &slots {
                    board.set_member_pid(slot, 0);
                }
                false
            }
        };
        if last {
            drop(board);
            let _ = namespace.cleanup();
        }
    }
}

/// Agent `id` of `team`, as every member of it derives it: its scenario (on its host's
/// namespace in a mixed team, with its host router's links on Zenoh) and namespace, its id
/// and the system's limits checked (a refusal).
pub(crate) fn member_of(team: &Team, id: usize) -> Result<(Scenario, RunNamespace), MemberError> {
    let n = team.file.robots;
    if id >= n {
        return Err(MemberError::refused(JoinError::NoSuchAgent {
            id,
            robots: n,
        }));
    }
    let host = team
        .file
        .transport
        .bridged()
        .then(|| team.host_of(id))
        .flatten();
    let (mut scenario, namespace) = member_scenario(team, host)?;
    let degree = scenario.graph().map_or(n, |g| g.degree(id));
    crate::process::limits::check(scenario.transport, 1, degree).map_err(MemberError::refused)?;
    if !team.file.transport.host_board() {
        let host = team.host_of(id).expect("checked: every robot is on a host");
        scenario.transport_config = serde_json::to_value(team.zenoh_links(host)).ok();
    }
    Ok((scenario, namespace))
}

/// Runs agent `id` of the team in `team_path` to the end; errors are one line.
/// Everything before the run itself (the team file, the id, the limits, joining the team)
/// is refused ([`MemberError::Refused`]); what fails while it runs is a failure.
pub fn run_member(team_path: &Path, id: usize) -> Result<AgentReport, MemberError> {
    let _signals = admm_ta_transport::signals::install();
    let started = Instant::now();
    let team = Team::read(team_path).map_err(MemberError::refused)?;
    if team.is_private() {
        return Err(MemberError::refused(TeamFileError::Private(
            PrivateTeamError::NeedsServe,
        )));
    }
    let _span = tracing::info_span!("agent", run = %team.file.run, agent = id).entered();
    tracing::debug!(team = %team_path.display(), "joining the team");
    let (mut scenario, namespace) = member_of(&team, id)?;
    let results = team.results_dir();
    std::fs::create_dir_all(&results).map_err(|source| {
        MemberError::refused(JoinError::Results {
            path: results.clone(),
            source,
        })
    })?;
    let result = result_path(&results, id);
    let digest = Some(TeamDigest::of(&scenario).to_hex());
    // A result of an earlier run must not pass for this one's.
    let _ = std::fs::remove_file(&result);
    if !team.file.transport.host_board() {
        // No shared memory: presence, failures and cleanup are Zenoh's.
        let startup =
            Duration::from_millis(scenario.startup_timeout_ms).saturating_sub(started.elapsed());
        scenario.startup_timeout_ms = startup.as_millis() as u64;
        let report = run_scenario(&scenario, id, &results, &result, false, digest);
        // Nothing of the run is in it (other agents of this host may still be starting:
        // only an empty directory goes).
        let _ = std::fs::remove_dir(&namespace.dir);
        return report;
    }
    let deadline = started + Duration::from_millis(scenario.startup_timeout_ms);
    let membership =
        Membership::join(&scenario, &namespace, &[id], deadline).map_err(MemberError::refused)?;
    let report = run_scenario(&scenario, id, &namespace.dir, &result, false, digest);
    if let Some(signal) = admm_ta_transport::signals::received() {
        // A termination signal (to us, or to another member: then it is on the board
        // already): the whole team stops, nobody failed.
        let _ = membership.board().request_stop(signal, Some(id));
    } else if report.is_err() {
        // No launcher reports us: tell the others (the first mark wins, so an agent that
        // stopped because of another's failure changes nothing).
        let _ = membership.board().mark_failed(id);
    }
    membership.leave();
    report
}
