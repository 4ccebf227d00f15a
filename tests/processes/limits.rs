//! Resource checks up front: a soft open-file limit below what the team needs is raised up
//! to the hard one; a team that needs more than the hard limit allows is refused before
//! anything is spawned, with one line and the number to raise it to; one that fits runs
//! under the same limit.

use std::process::Command;

/// `admm-ta ARGS` under `ulimit -n files` (soft and hard).
fn with_file_limit(files: u32, args: &str) -> std::process::Output {
    with_limits(&format!("ulimit -n {files}"), args)
}

/// `admm-ta ARGS` after the shell's `ulimits`.
fn with_limits(ulimits: &str, args: &str) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("{ulimits} && exec \"$0\" {args}",))
        .arg(env!("CARGO_BIN_EXE_admm-ta"))
        .env_remove("ADMM_TA_FAULT")
        .output()
        .expect("sh runs")
}

#[test]
fn a_low_open_file_limit_is_refused_up_front_with_the_number_to_raise_it_to() {
    let out = with_file_limit(64, "solve --transport ipc --robots 10 --tasks 10");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("the team needs 134 open files per agent but the hard limit is 64 (ulimit -Hn): raise it to 256 (as root: ulimit -Hn 256, or in /etc/security/limits.conf)"),
        "{stderr}"
    );
    // Degree 2 (a ring) fits in 64: the same limit runs it.
    let out = with_file_limit(
        64,
        "solve --transport ipc --robots 10 --tasks 10 --topology ring",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // So does a complete graph once the limit is raised as the line says.
    let out = with_file_limit(256, "solve --transport ipc --robots 10 --tasks 10");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_low_soft_open_file_limit_is_raised_up_to_the_hard_one() {
    // The usual desktop setting: a soft limit of 64 (1024 there) under a higher hard one.
    let out = with_limits(
        "ulimit -Sn 64 && ulimit -Hn 4096",
        "solve --transport ipc --robots 10 --tasks 10 --check",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A hard limit below the need is still refused, naming the hard limit.
    let out = with_limits(
        "ulimit -Sn 64 && ulimit -Hn 100",
        "solve --transport ipc --robots 10 --tasks 10",
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("hard limit is 100"), "{stderr}");
}
