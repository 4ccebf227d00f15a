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
