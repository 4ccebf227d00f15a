//! Private, verified run directories on a computer shared with other accounts: a hostile
//! base directory (open to everybody, a symlink to elsewhere, owned by another uid) neither
//! blocks a run nor is used by it; a team refuses it with one line; an agent refuses a
//! scenario that is a symlink, readable by others, or replaced; and a real second account
//! (uid 65534, when the tests run as root) neither blocks nor sees the runs of another.

use crate::common;

use std::os::unix::fs::PermissionsExt;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// A short ipc run with `tmp` as its temporary directory, as uid `uid` if given.
fn solve_in(tmp: &Path, uid: Option<u32>) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_admm-ta"));
    command
        .args([
            "solve",
            "--transport",
            "ipc",
            "--robots",
            "5",
            "--tasks",
            "5",
        ])
        .args(["--topology", "ring", "--json"])
        .env("TMPDIR", tmp)
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("ADMM_TA_FAULT")
        .stdin(Stdio::null());
    if let Some(uid) = uid {
        as_user(&mut command, uid);
    }
    command.output().expect("the admm-ta binary runs")
}

/// Runs `command` as account `uid` (the tests run as root to use a second account).
fn as_user(command: &mut Command, uid: u32) {
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        command.pre_exec(move || {
            if libc::setgid(uid) != 0 || libc::setuid(uid) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

fn euid() -> u32 {
    // SAFETY: geteuid cannot fail.
    unsafe { libc::geteuid() }
}

/// A temporary directory everybody may write to (sticky), like `/tmp`.
fn shared_tmp() -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o1777)).unwrap();
    tmp
}

/// The run succeeded despite a hostile base, said why on stderr, and left nothing behind.
fn assert_not_blocked(out: &Output, tmp: &Path, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "blocked: {stderr}");
    assert!(stderr.contains(needle), "{stderr}");
    // Nothing of the run is left: not the private base it made for itself.
    let left: Vec<String> = std::fs::read_dir(tmp)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&format!("admm-ta-{}-", euid())))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn a_hostile_base_directory_neither_blocks_a_run_nor_is_used() {
    let me = euid();
    // Open to everybody.
    let tmp = shared_tmp();
    let base = tmp.path().join(format!("admm-ta-{me}"));
    std::fs::create_dir(&base).unwrap();
    std::fs::set_permissions(&base, std::fs::Permissions::from_mode(0o777)).unwrap();
    assert_not_blocked(&solve_in(tmp.path(), None), tmp.path(), "has mode 777");
    assert_eq!(
        std::fs::read_dir(&base).unwrap().count(),
        0,
        "the open base was used"
    );
    // A symlink to a directory of somebody else's choice.
    let tmp = shared_tmp();
    let elsewhere = tempfile::tempdir().unwrap();
    std::fs::set_permissions(elsewhere.path(), std::fs::Permissions::from_mode(0o700)).unwrap();
    std::os::unix::fs::symlink(elsewhere.path(), tmp.path().join(format!("admm-ta-{me}"))).unwrap();
    assert_not_blocked(&solve_in(tmp.path(), None), tmp.path(), "is a symlink");
    assert_eq!(std::fs::read_dir(elsewhere.path()).unwrap().count(), 0);
    // Owned by another account (simulated with chown when we are root).
    if me == 0 {
        let tmp = shared_tmp();
        let base = tmp.path().join("admm-ta-0");
        std::fs::create_dir(&base).unwrap();
        std::fs::set_permissions(&base, std::fs::Permissions::from_mode(0o700)).unwrap();
        std::os::unix::fs::chown(&base, Some(65534), Some(65534)).unwrap();
        assert_not_blocked(
            &solve_in(tmp.path(), None),
            tmp.path(),
            "owned by uid 65534",
        );
    }
}

#[test]
fn a_team_refuses_a_hostile_base_directory_with_one_line() {
    let tmp = shared_tmp();
    let base = tmp.path().join(format!("admm-ta-{}", euid()));
    std::fs::create_dir(&base).unwrap();
    std::fs::set_permissions(&base, std::fs::Permissions::from_mode(0o755)).unwrap();
    let team = tmp.path().join("team.toml");
    std::fs::write(
        &team,
        "run = \"hostile\"\nrobots = 3\ncosts = \"random\"\ntasks = 3\nstartup_timeout = 5.0\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["agent", "--team"])
        .arg(&team)
        .args(["--robot", "0"])
        .env("TMPDIR", tmp.path())
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("refusing the run directory") && stderr.contains("has mode 755"),
        "{stderr}"
    );
}

#[test]
fn an_agent_refuses_a_symlinked_open_or_replaced_scenario() {
    use admm_ta::runtime::process::private_dir::{sha256_hex, write_private_file};
    let dir = tempfile::tempdir().unwrap();
    let text = b"{\"run_id\": \"r\"}";
    let digest = sha256_hex(text);
    let real = dir.path().join("real.json");
    write_private_file(&real, text).unwrap();
    let planted = dir.path().join("planted.json");
    std::os::unix::fs::symlink(&real, &planted).unwrap();
    let open = dir.path().join("open.json");
    std::fs::write(&open, text).unwrap();
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o644)).unwrap();
    let replaced = dir.path().join("replaced.json");
    write_private_file(&replaced, b"{\"run_id\": \"someone else's\"}").unwrap();
    for (path, needle) in [
        (&planted, "is a symlink"),
        (&open, "mode 644, not 600"),
        (&replaced, "it was replaced"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
            .args(["agent", "--run", "r", "--robot", "0", "--scenario"])
            .arg(path)
            .args(["--scenario-digest", &digest])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{}", path.display());
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(needle), "{needle}: {stderr}");
    }
}

#[test]
fn a_second_account_neither_blocks_nor_sees_another_accounts_runs() {
    if euid() != 0 {
        eprintln!("skipped: needs root to act as a second account (uid 65534)");
        return;
    }
    let tmp = shared_tmp();
    // The other account plants the base name of root's runs first, then runs its own team
    // next to root's.
    let planted = tmp.path().join("admm-ta-0");
    std::fs::create_dir(&planted).unwrap();
    std::os::unix::fs::chown(&planted, Some(65534), Some(65534)).unwrap();
    std::thread::scope(|scope| {
        let theirs = scope.spawn(|| solve_in(tmp.path(), Some(65534)));
        let ours = solve_in(tmp.path(), None);
        let theirs = theirs.join().unwrap();
        assert!(
            theirs.status.success(),
            "uid 65534: {}",
            String::from_utf8_lossy(&theirs.stderr)
        );
        assert_not_blocked(&ours, tmp.path(), "owned by uid 65534");
    });
    // The other account's runs live in its own private base.
    let meta = std::fs::symlink_metadata(tmp.path().join("admm-ta-65534")).unwrap();
    use std::os::unix::fs::MetadataExt;
    assert_eq!((meta.uid(), meta.mode() & 0o777), (65534, 0o700));
}

#[test]
fn two_accounts_run_teams_of_the_same_name_side_by_side() {
    if euid() != 0 {
        eprintln!("skipped: needs root to act as a second account (uid 65534)");
        return;
    }
    let tmp = shared_tmp();
    // One team file both accounts can read, results where both can write.
    let run = format!("same{}", std::process::id());
    let team = tmp.path().join("team.toml");
    std::fs::write(
        &team,
        format!("run = \"{run}\"\nrobots = 2\ncosts = \"random\"\ntasks = 2\nresults = \"results\"\nstartup_timeout = 60.0\n"),
    )
    .unwrap();
    let results = tmp.path().join("results");
    std::fs::create_dir(&results).unwrap();
    std::fs::set_permissions(&results, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let agent = |id: &str, uid: Option<u32>| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_admm-ta"));
        command
            .args(["agent", "--team", team.to_str().unwrap(), "--robot", id])
            .env("TMPDIR", tmp.path())
            .env_remove("XDG_RUNTIME_DIR")
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        if let Some(uid) = uid {
            as_user(&mut command, uid);
        }
        command.spawn().unwrap()
    };
    // Root's agent 0 holds the name while uid 65534 starts its own whole team of that name.
    let mut ours = agent("0", None);
    std::thread::sleep(std::time::Duration::from_millis(300));
    let theirs: Vec<_> = ["0", "1"].iter().map(|id| agent(id, Some(65534))).collect();
    for (k, child) in theirs.into_iter().enumerate() {
        let out = child.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "uid 65534, agent {k}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // Root's team completes too.
    let last = agent("1", None).wait_with_output().unwrap();
    assert!(
        last.status.success(),
        "{}",
        String::from_utf8_lossy(&last.stderr)
    );
    let first = common::wait_with_deadline(&mut ours, std::time::Duration::from_secs(60));
    assert!(first.success());
}

#[test]
fn a_temporary_directory_that_does_not_exist_is_named_and_refused() {
    let missing = tempfile::tempdir().unwrap().path().join("gone");
    let out = solve_in(&missing, None);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    let last = stderr.trim_end().lines().last().unwrap_or_default();
    assert!(
        last.contains(&format!("in {}", missing.display())) && last.contains("set TMPDIR"),
        "{stderr}"
    );
}
