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
//! When the cost file names its robots (a first column of names, see docs/file-formats.md, "File
//! formats"), an edge may name them instead, or mix names and numbers:
//!
//! ```toml
//! robots = 3
//! edges = [["uav1", "uav2"], ["uav2", 2]]
//! ```
//!
//! Self-loops, repeated edges, robots outside `0..robots`, names the costs do not have and
//! unknown keys are errors; so is a disconnected graph when it is used for a solve
//! (Assumption 1).
//!
//! ```
//! use admm_ta_topologies::file;
//! use std::path::Path;
//! let names = ["uav1".to_string(), "uav2".to_string(), "uav3".to_string()];
//! let text = "robots = 3\nedges = [[\"uav1\", \"uav2\"], [\"uav2\", 2]]";
//! let g = file::parse_named(text, Path::new("net.toml"), Some(&names)).unwrap();
//! assert_eq!(g.edges().collect::<Vec<_>>(), [(0, 1), (1, 2)]);
//! ```

use crate::{Graph, RobotRef, TopologyError};
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TopologyFile {
    robots: usize,
    /// Read as lists so that an edge with other than two robots is an error, not truncated.
    #[serde(default)]
    edges: Vec<Vec<RobotRef>>,
}

/// Largest topology file read (bytes).
pub const MAX_TOPOLOGY_BYTES: u64 = 256 << 20;

/// Parses topology TOML text of numbered robots; `origin` names the source in error messages.
pub fn parse(text: &str, origin: &Path) -> Result<Graph, TopologyError> {
    parse_named(text, origin, None)
}

/// Parses topology TOML text whose edges may name robots by `robot_names` (the cost file's,
/// in row order; `None`: numbers only).
pub fn parse_named(
    text: &str,
    origin: &Path,
    robot_names: Option<&[String]>,
) -> Result<Graph, TopologyError> {
    let file: TopologyFile = toml::from_str(text).map_err(|e| TopologyError::Parse {
        path: origin.to_path_buf(),
        reason: e.message().to_string(),
    })?;
    let mut edges = Vec::with_capacity(file.edges.len());
    for (k, edge) in file.edges.iter().enumerate() {
        let resolve = |robot: &RobotRef| {
            robot
                .resolve(robot_names)
                .map_err(|source| TopologyError::RobotName {
                    path: origin.to_path_buf(),
                    edge: k,
                    source: Box::new(source),
                })
        };
        match edge.as_slice() {
            [a, b] => edges.push((resolve(a)?, resolve(b)?)),
            other => {
                let shown: Vec<String> = other.iter().map(RobotRef::to_string).collect();
                return Err(TopologyError::Parse {
                    path: origin.to_path_buf(),
                    reason: format!(
                        "edge {k} ([{}]) has {} robots; an edge joins exactly two robots",
                        shown.join(", "),
                        other.len()
                    ),
                });
            }
        }
    }
    let name = origin
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "file".into());
    Graph::from_edges(file.robots, &edges, name)
}

/// Reads and parses a topology file of numbered robots (a regular file of at most
/// [`MAX_TOPOLOGY_BYTES`]).
pub fn read(path: &Path) -> Result<Graph, TopologyError> {
    read_named(path, None)
}

/// Reads a topology file whose edges may name robots by `robot_names` (see [`parse_named`]).
pub fn read_named(path: &Path, robot_names: Option<&[String]>) -> Result<Graph, TopologyError> {
    use std::io::Read;
    let io = |reason: String| TopologyError::Io {
        path: path.to_path_buf(),
        reason,
    };
    let meta = std::fs::metadata(path).map_err(|e| io(e.to_string()))?;
    if !meta.is_file() {
        return Err(io("not a regular file".into()));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_TOPOLOGY_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| io(e.to_string()))?;
    if bytes.len() as u64 > MAX_TOPOLOGY_BYTES {
        return Err(io(format!("larger than {MAX_TOPOLOGY_BYTES} bytes")));
    }
    let text = String::from_utf8(bytes).map_err(|_| io("not UTF-8 text".into()))?;
    parse_named(&text, path, robot_names)
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
        let three = parse("robots = 3\nedges = [[0, 1, 2]]", Path::new("t.toml"));
        assert!(
            three
                .unwrap_err()
                .to_string()
                .contains("edge 0 ([0, 1, 2]) has 3 robots; an edge joins exactly two robots")
        );
        assert!(parse("robots = 3\nedges = [[0]]", Path::new("t.toml")).is_err());
        let bad = parse("robots = 3\nedges = [[0, 1], [1, 1]]", Path::new("t.toml"));
        assert_eq!(bad.unwrap_err(), TopologyError::SelfLoop(1));
        let unknown = parse("robots = 3\nedgez = []", Path::new("t.toml")).unwrap_err();
        assert!(unknown.to_string().contains("edgez"), "{unknown}");
        let missing = read(Path::new("/nonexistent/topo.toml")).unwrap_err();
        assert!(missing.to_string().contains("cannot read"), "{missing}");
    }

    #[test]
    fn named_robots() {
        let names: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let at = Path::new("n.toml");
        let text = "robots = 3\nedges = [[\"a\", \"b\"], [\"b\", 2]]";
        let g = parse_named(text, at, Some(&names)).unwrap();
        assert_eq!(g.edges().collect::<Vec<_>>(), [(0, 1), (1, 2)]);
        // Names need the costs' names; the error says which edge and which name.
        let unnamed = parse(text, at).unwrap_err();
        assert!(
            matches!(unnamed, TopologyError::RobotName { edge: 0, .. }),
            "{unnamed}"
        );
        let unknown =
            parse_named("robots = 3\nedges = [[0, \"z\"]]", at, Some(&names)).unwrap_err();
        assert!(matches!(unknown, TopologyError::RobotName { edge: 0, .. }));
        let source = std::error::Error::source(&unknown).unwrap().to_string();
        assert!(
            source.contains("'z'") && source.contains("a, b, c"),
            "{source}"
        );
        // A named self-loop is still a self-loop.
        let looped = parse_named("robots = 3\nedges = [[\"a\", 0]]", at, Some(&names));
        assert_eq!(looped.unwrap_err(), TopologyError::SelfLoop(0));
        // A negative or fractional robot is neither a number nor a name.
        assert!(parse("robots = 3\nedges = [[0, -1]]", at).is_err());
        assert!(parse("robots = 3\nedges = [[0, 1.5]]", at).is_err());
    }
}
