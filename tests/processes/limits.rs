//! Resource checks up front: a team that needs more open files than `ulimit -n` allows is
//! refused before anything is spawned, with one line and the number to raise the limit to;
//! one that fits runs under the same limit.

use std::process::Command;

/// `admm-ta ARGS` under `ulimit -n files`.
fn with_file_limit(files: u32, args: &str) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -n {files} && exec \"$0\" {args}",))
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
        stderr.contains("the team needs 134 open files per agent but the limit is 64: raise it with ulimit -n 256"),
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
