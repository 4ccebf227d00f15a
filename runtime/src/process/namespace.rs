//! A run's private namespace: a shared-memory prefix and a directory of its own, so that
//! concurrent runs and parallel tests never collide, and a cleanup that leaves nothing of
//! the run behind — not even when an agent was killed and could not clean up itself.

use crate::process::private_dir::{self, PrivateDirError, create_unique_dir, write_private_file};
use admm_ta_transport::liveness::process_alive;
use std::path::{Path, PathBuf};

/// Where POSIX shared memory lives on Linux.
const SHM_DIR: &str = "/dev/shm";

/// The subdirectory of a namespace's parts ([`RunNamespace::within`]).
const PARTS_DIR: &str = "parts";

/// A run's identity and the places it may write to.
#[derive(Debug, Clone)]
pub struct RunNamespace {
    pub id: String,
    /// Prefix of every transport file and shared-memory object of the run.
    pub prefix: String,
    /// The run directory: scenario, agent logs and results, and the transport root.
    pub dir: PathBuf,
    /// A private base made for this run alone (the user's was hostile): removed with it.
    pub own_base: Option<PathBuf>,
}

/// `e` naming the directory it happened in (`TMPDIR` pointing nowhere, a full disk).
fn in_dir(dir: &Path, e: std::io::Error) -> std::io::Error {
    let hint = if dir == std::env::temp_dir() {
        " (the temporary directory: set TMPDIR to a writable directory)"
    } else {
        ""
    };
    std::io::Error::new(e.kind(), format!("in {}{hint}: {e}", dir.display()))
}

impl RunNamespace {
    /// A fresh namespace in the user's private runs directory
    /// ([`crate::process::private_dir`]); its name has a random part and is created
    /// exclusively. If that directory is hostile (another account created it, or a symlink
    /// stands in its place), the run is not blocked: it gets a fresh private directory of its
    /// own instead (and says so on stderr).
    pub fn create() -> std::io::Result<Self> {
        let (runs, own_base) = match private_runs_dir() {
            Ok(runs) => {
                sweep_abandoned(&runs);
                (runs, None)
            }
            Err(why) => {
                eprintln!(
                    "warning: {}; this run uses a private directory of its own",
                    admm_ta_transport::error_text::one_line(&why)
                );
                let temp = std::env::temp_dir();
                let (base, _) =
                    create_unique_dir(&temp, &format!("admm-ta-{}-", private_dir::euid()))
                        .map_err(|e| in_dir(&temp, e))?;
                (base.clone(), Some(base))
            }
        };
        let (dir, id) = create_unique_dir(&runs, &run_id_prefix(std::process::id()))
            .map_err(|e| in_dir(&runs, e))?;
        write_private_file(
            &dir.join(LAUNCHER_PID),
            std::process::id().to_string().as_bytes(),
        )?;
        Ok(Self {
            prefix: format!("adta{id}_"),
            id,
            dir,
            own_base,
        })
    }

    /// Creates the run's transport root ([`RunNamespace::transport_root`]) exclusively, with
    /// mode 0700.
    pub fn create_transport_root(&self) -> std::io::Result<()> {
        std::os::unix::fs::DirBuilderExt::mode(&mut std::fs::DirBuilder::new(), 0o700)
            .create(self.transport_root())
    }

    /// The transport root directory of the run: on the shared-memory tmpfs when there is one,
    /// because a transport (iceoryx2) writes and fsyncs several small files per service and port, and on a
    /// disk-backed `/tmp` that made start-up of a 50-agent complete graph several times slower.
    pub fn transport_root(&self) -> PathBuf {
        if Path::new(SHM_DIR).is_dir() {
            Path::new(SHM_DIR).join(format!("{}root", self.prefix))
        } else {
            self.dir.join("iox2")
        }
    }

    /// Name of the run's board (arrival counters and global barrier) in shared memory.
    pub fn board_shm(&self) -> String {
        format!("{}board", self.prefix)
    }

    /// The namespace of an independently started team named `run` (letters, digits and
    /// dashes): every agent of the team derives the same one from the name.
    pub fn for_team(run: &str) -> Result<Self, TeamNamespaceError> {
        Self::check_team_name(run)?;
        let teams = private_dir::base_dir()?.join("teams");
        private_dir::ensure_private_dir(&teams)?;
        let dir = teams.join(run);
        private_dir::ensure_private_dir(&dir)?;
        // SAFETY: geteuid cannot fail.
        let uid = unsafe { libc::geteuid() };
        Ok(Self {
            // 't' is not a hex digit: no launcher run's prefix (`adta<hex>_`) starts so. The
            // user's id keeps teams of the same name of two users apart (the digits end at
            // the first dash, so no two users' prefixes coincide). [`team_parts_prefix`]
            // writes it too.
            prefix: format!("adtat{uid}-{run}_"),
            id: format!("team-{run}"),
            dir,
            own_base: None,
        })
    }

    /// The namespace of part `name` of this team's life (a standing team's roster: each
    /// has its own board, transport files and shared memory), inside the team's: removed
    /// with it. `name`: letters and digits.
    pub fn within(&self, name: &str) -> Result<Self, PrivateDirError> {
        let parts = self.dir.join(PARTS_DIR);
        private_dir::ensure_private_dir(&parts)?;
        let dir = parts.join(name);
        private_dir::ensure_private_dir(&dir)?;
        Ok(Self {
            id: format!("{}-{name}", self.id),
            prefix: self.part_prefix(name),
            dir,
            own_base: None,
        })
    }

    /// The shared-memory prefix of part `name`: short, as the Unix sockets of a transport's
    /// events must fit in 108 bytes — [`RunNamespace::parts_prefix`] and a hash of the name.
    fn part_prefix(&self, name: &str) -> String {
        format!("{}{:08x}_", self.parts_prefix(), short_hash(name))
    }

    /// What the shared memory of every part of this namespace starts with (`adtap` and a
    /// hash of its prefix).
    pub fn parts_prefix(&self) -> String {
        parts_prefix_of(&self.prefix)
    }

    /// The directory of the parts made by [`RunNamespace::within`].
    pub fn parts_dir(&self) -> PathBuf {
        self.dir.join(PARTS_DIR)
    }

    /// Removes part `name` ([`RunNamespace::within`]) with its shared memory. Only call
    /// once no process uses it.
    pub fn remove_part(&self, name: &str) {
        for path in shm_objects(&self.part_prefix(name)) {
            let _ = remove_if_exists(&path);
        }
        let _ = std::fs::remove_dir_all(self.parts_dir().join(name));
    }

    /// Removes every part ([`RunNamespace::within`]) with its shared memory. Only call
    /// once no process uses any.
    pub fn remove_parts(&self) {
        if let Ok(entries) = std::fs::read_dir(self.parts_dir()) {
            for entry in entries.flatten() {
                let name = entry.file_name().to_string_lossy().into_owned();
                for path in shm_objects(&self.part_prefix(&name)) {
                    let _ = remove_if_exists(&path);
                }
            }
        }
        let _ = std::fs::remove_dir_all(self.parts_dir());
    }

    /// Refuses team names that cannot name shared memory (or that would prefix another's).
    pub fn check_team_name(run: &str) -> Result<(), BadTeamName> {
        if run.is_empty()
            || run.len() > 40
            || !run.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')
        {
            return Err(BadTeamName {
                name: run.to_string(),
            });
        }
        Ok(())
    }

    /// Files of the run that still exist: shared memory with its prefix, and the run directory.
    pub fn leftovers(&self) -> Vec<PathBuf> {
        let mut found = shm_objects(&self.prefix);
        if self.dir.exists() {
            found.push(self.dir.clone());
        }
        found.extend(self.own_base.iter().filter(|b| b.exists()).cloned());
        found
    }

    /// Removes everything of the run. Only call once no agent of the run is alive.
    pub fn cleanup(&self) -> std::io::Result<()> {
        self.remove_parts();
        for path in shm_objects(&self.prefix) {
            remove_if_exists(&path)?;
        }
        let removed = match std::fs::remove_dir_all(&self.dir) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
            _ => Ok(()),
        };
        if let Some(base) = &self.own_base {
            let _ = std::fs::remove_dir(base);
        }
        removed
    }
}

/// 32 bits of FNV-1a over `text`.
fn short_hash(text: &str) -> u32 {
    let h = text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    (h ^ (h >> 32)) as u32
}

/// [`RunNamespace::parts_prefix`] of a namespace whose prefix is `prefix`.
fn parts_prefix_of(prefix: &str) -> String {
    format!("adtap{:08x}", short_hash(prefix))
}

/// What the shared memory of every part of the team named `run` on this machine starts
/// with (how a test finds what a standing team's rosters left behind), without touching
/// anything.
pub fn team_parts_prefix(run: &str) -> String {
    // SAFETY: geteuid cannot fail.
    let uid = unsafe { libc::geteuid() };
    parts_prefix_of(&format!("adtat{uid}-{run}_"))
}

/// A team name that cannot name shared memory.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("run name '{name}': use 1 to 40 letters, digits and dashes")]
pub struct BadTeamName {
    pub name: String,
}

/// Why a team's namespace cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TeamNamespaceError {
    #[error(transparent)]
    Name(#[from] BadTeamName),
    #[error(transparent)]
    Directory(#[from] PrivateDirError),
}

/// The user's directory of launcher runs (one subdirectory per run, named by its id),
/// created and checked.
pub fn private_runs_dir() -> Result<PathBuf, PrivateDirError> {
    let runs = private_dir::base_dir()?.join("runs");
    private_dir::ensure_private_dir(&runs)?;
    Ok(runs)
}

/// Where the user's launcher runs live (for reports of what runs left behind; not checked).
pub fn runs_dir() -> PathBuf {
    private_runs_dir().unwrap_or_else(|_| {
        std::env::temp_dir()
            .join(format!("admm-ta-{}", private_dir::euid()))
            .join("runs")
    })
}

/// The id prefix of every run a launcher in process `pid` starts (its shared memory is
/// named `adta<id>_…`, its run directory `<id>`): how a stress test finds what its runs
/// left behind.
pub fn run_id_prefix(pid: u32) -> String {
    format!("{pid:x}")
}

/// Names in `/dev/shm` starting with `prefix`.
pub fn shm_named(prefix: &str) -> Vec<PathBuf> {
    shm_objects(prefix)
}

/// File of a run directory holding the launcher's pid.
const LAUNCHER_PID: &str = "launcher.pid";

/// Removes the runs whose launcher died without cleaning up (killed with SIGKILL: nothing
/// can clean up after that but the next run). A run whose directory has no pid file yet is
/// being created and is left alone.
fn sweep_abandoned(runs: &Path) {
    let Ok(entries) = std::fs::read_dir(runs) else {
        return;
    };
    for entry in entries.flatten() {
        let dir = entry.path();
        let Some(pid) = std::fs::read_to_string(dir.join(LAUNCHER_PID))
            .ok()
            .and_then(|p| p.trim().parse::<u32>().ok())
        else {
            continue;
        };
        if process_alive(pid) {
            continue;
        }
        let abandoned = RunNamespace {
            prefix: format!("adta{}_", entry.file_name().to_string_lossy()),
            id: entry.file_name().to_string_lossy().into_owned(),
            dir,
            own_base: None,
        };
        let _ = abandoned.cleanup();
    }
}

fn shm_objects(prefix: &str) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(SHM_DIR) else {
        return Vec::new();
    };
    entries
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .map(|e| e.path())
        .collect()
}

fn remove_if_exists(path: &Path) -> std::io::Result<()> {
    let removed = if path.is_dir() {
        std::fs::remove_dir_all(path)
    } else {
        std::fs::remove_file(path)
    };
    match removed {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn namespaces_are_unique_and_clean_up_after_themselves() {
        let a = RunNamespace::create().unwrap();
        let b = RunNamespace::create().unwrap();
        assert_ne!(a.prefix, b.prefix);
        let shm = PathBuf::from(SHM_DIR).join(format!("{}test", a.prefix));
        if PathBuf::from(SHM_DIR).is_dir() {
            std::fs::write(&shm, b"x").unwrap();
            std::fs::create_dir_all(a.transport_root().join("services")).unwrap();
        }
        std::fs::write(a.dir.join("file"), b"x").unwrap();
        assert!(!a.leftovers().is_empty());
        a.cleanup().unwrap();
        b.cleanup().unwrap();
        assert!(a.leftovers().is_empty(), "{:?}", a.leftovers());
        assert!(b.leftovers().is_empty());
    }

    #[test]
    fn runs_of_dead_launchers_are_swept_by_the_next_run() {
        let dead = RunNamespace::create().unwrap();
        // Its shared memory first: once the pid file says its launcher is dead, another
        // test's `create` may sweep the run at any moment (an object written after that
        // sweep would stay).
        let shm = PathBuf::from(SHM_DIR).join(format!("{}board", dead.prefix));
        if PathBuf::from(SHM_DIR).is_dir() {
            std::fs::write(&shm, b"x").unwrap();
        }
        // No process has pid 0x7fff_fff0 (beyond Linux's pid_max).
        std::fs::write(dead.dir.join(LAUNCHER_PID), "2147483632").unwrap();
        let live = RunNamespace::create().unwrap();
        // Another test's `create` may be sweeping the dead run at the same moment: this
        // sweep then skips it (its pid file already gone) while the other finishes.
        let swept_by = std::time::Instant::now() + std::time::Duration::from_secs(2);
        while !dead.leftovers().is_empty() && std::time::Instant::now() < swept_by {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert!(dead.leftovers().is_empty(), "{:?}", dead.leftovers());
        assert!(live.dir.exists(), "a live run was swept");
        live.cleanup().unwrap();
    }
}
