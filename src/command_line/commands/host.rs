//! `admm-ta host`: one machine of a team across machines (its Zenoh router and bridge).

use crate::command_line::cli::HostArgs;
#[cfg(feature = "zenoh")]
use crate::command_line::output::outln;
use anyhow::Result;

#[cfg(feature = "zenoh")]
pub fn run(args: HostArgs) -> Result<()> {
    let report = crate::runtime::host::run_host(&args.team, &args.name)?;
    outln!("{}", serde_json::to_string(&report)?);
    Ok(())
}

#[cfg(not(feature = "zenoh"))]
pub fn run(_args: HostArgs) -> Result<()> {
    anyhow::bail!(crate::transport::ZenohNotBuilt)
}
