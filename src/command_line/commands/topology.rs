//! `admm-ta topology`: a generated topology in the topology file format.

use crate::TopologySpec;
use crate::command_line::cli::TopologyArgs;
use crate::command_line::output::out;
use crate::topologies::file as topology_file;
use anyhow::Result;

pub fn run(args: TopologyArgs) -> Result<()> {
    let spec: TopologySpec = args.kind.parse()?;
    out!(
        "{}",
        topology_file::to_toml(&spec.build(args.robots, args.seed)?)
    );
    Ok(())
}
