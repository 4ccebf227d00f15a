//! What several subcommands need: the program agent processes start from, progress bars.

use crate::runtime::options::run::AgentProgram;
use anyhow::{Context, Result};
use std::sync::OnceLock;

/// The program agent processes start from when this process is not the `admm-ta` binary.
static AGENT_PROGRAM: OnceLock<AgentProgram> = OnceLock::new();

/// Agent processes of this process's teams start from `program` (the first call decides):
/// a front end that carries the command line in another program (the Python package:
/// `python -c "...admm_ta._core.main(...)"`) says so once, before any team starts.
pub fn set_agent_program(program: AgentProgram) {
    let _ = AGENT_PROGRAM.set(program);
}

/// The program agent processes start from: the one [`set_agent_program`] gave, else this
/// binary.
pub fn agent_program() -> Result<AgentProgram> {
    if let Some(program) = AGENT_PROGRAM.get() {
        return Ok(program.clone());
    }
    std::env::current_exe()
        .map(AgentProgram::from)
        .context("cannot locate the admm-ta binary to start agents from")
}

/// A progress bar of `steps` steps drawn by `template` (indicatif's syntax).
pub fn progress_bar(steps: u64, template: &str) -> indicatif::ProgressBar {
    indicatif::ProgressBar::new(steps)
        .with_style(indicatif::ProgressStyle::with_template(template).expect("valid template"))
}

/// Creates `dir` if missing and checks a file can be written in it: an output directory is
/// refused (exit 2) before a long run, not after it.
pub fn writable_dir(flag: &str, dir: &std::path::Path) -> anyhow::Result<()> {
    let refused = |e: std::io::Error| {
        crate::command_line::exit::UsageError(format!(
            "{flag} {}: cannot write there: {e}",
            dir.display()
        ))
    };
    std::fs::create_dir_all(dir).map_err(refused)?;
    let probe = dir.join(format!(".admm-ta-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(refused)?;
    std::fs::remove_file(&probe).map_err(refused)?;
    Ok(())
}
