//! Topology files: hand in your own robot network.
//!
//! A topology file is TOML with the number of robots and the undirected edges, each listed
//! once, robots numbered from 0:
//!
//! ```toml
//! # four robots in a square with one diagonal
//! robots = 4
//! edges = [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]]
//! ```
//!
//! Self-loops, repeated edges, robots outside `0..robots` and unknown keys are errors; so is a
//! disconnected graph when it is used for a solve (Assumption 1).

use crate::{Graph, TopologyError};
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TopologyFile {
    robots: usize,
    #[serde(default)]
    edges: Vec<[usize; 2]>,
}

/// Parses topology TOML text; `origin` names the source in error messages.
pub fn parse(text: &str, origin: &Path) -> Result<Graph, TopologyError> {
    let file: TopologyFile = toml::from_str(text).map_err(|e| TopologyError::Parse {
        path: origin.to_path_buf(),
        reason: e.message().to_string(),
    })?;
    let edges: Vec<(usize, usize)> = file.edges.iter().map(|e| (e[0], e[1])).collect();
    let name = origin
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "file".into());
    Graph::from_edges(file.robots, &edges, name)
}

/// Reads and parses a topology file.
pub fn read(path: &Path) -> Result<Graph, TopologyError> {
    let text = std::fs::read_to_string(path).map_err(|e| TopologyError::Io {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    parse(&text, path)
}

/// Writes `graph` in the topology file format.
pub fn to_toml(graph: &Graph) -> String {
    let mut out = format!(
        "# {}\nrobots = {}\nedges = [\n",
        graph.name(),
        graph.robots()
    );
    for (a, b) in graph.edges() {
        out.push_str(&format!("  [{a}, {b}],\n"));
    }
    out.push_str("]\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let g = crate::generate::grid(7).unwrap();
        let text = to_toml(&g);
        let back = parse(&text, Path::new("g.toml")).unwrap();
        assert_eq!(
            back.edges().collect::<Vec<_>>(),
            g.edges().collect::<Vec<_>>()
        );
        let bad = parse("robots = 3\nedges = [[0, 1], [1, 1]]", Path::new("t.toml"));
        assert_eq!(bad.unwrap_err(), TopologyError::SelfLoop(1));
        let unknown = parse("robots = 3\nedgez = []", Path::new("t.toml")).unwrap_err();
        assert!(unknown.to_string().contains("edgez"), "{unknown}");
        let missing = read(Path::new("/nonexistent/topo.toml")).unwrap_err();
        assert!(missing.to_string().contains("cannot read"), "{missing}");
    }
}
