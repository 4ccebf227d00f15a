//! What several subcommands need: the binary agent processes start from, progress bars.

use anyhow::{Context, Result};
use std::path::PathBuf;

/// This binary: agent processes are started from it.
pub fn agent_program() -> Result<PathBuf> {
    std::env::current_exe().context("cannot locate the admm-ta binary to start agents from")
}

/// A progress bar of `steps` steps drawn by `template` (indicatif's syntax).
pub fn progress_bar(steps: u64, template: &str) -> indicatif::ProgressBar {
    indicatif::ProgressBar::new(steps)
        .with_style(indicatif::ProgressStyle::with_template(template).expect("valid template"))
}

/// Creates `dir` if missing and checks a file can be written in it: an output directory is
/// refused (exit 2) before a long run, not after it.
pub fn writable_dir(dir: &std::path::Path) -> anyhow::Result<()> {
    let refused = |e: std::io::Error| {
        crate::exit::UsageError(format!("--out {}: cannot write there: {e}", dir.display()))
    };
    std::fs::create_dir_all(dir).map_err(refused)?;
    let probe = dir.join(format!(".admm-ta-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(refused)?;
    std::fs::remove_file(&probe).map_err(refused)?;
    Ok(())
}
