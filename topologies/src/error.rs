use std::path::PathBuf;

/// Everything that can be wrong with a communication graph or a topology file.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum TopologyError {
    #[error("a team needs at least one robot")]
    NoRobots,
    /// `max`: the generators' limit on robot pairs.
    #[error(
        "a {what} graph of {robots} robots has {pairs} robot pairs to consider; the limit is {max} (about 6300 robots)"
    )]
    TooDense {
        what: &'static str,
        robots: usize,
        pairs: u128,
        max: u128,
    },
    #[error("too many robots: {robots} (the limit is {max})")]
    TooManyRobots { robots: usize, max: usize },
    #[error("edge ({0}, {1}) names robot {2}, but there are {3} robots, numbered from 0")]
    OutOfRange(usize, usize, usize, usize),
    #[error("edge ({0}, {0}) is a self-loop")]
    SelfLoop(usize),
    #[error("edge ({0}, {1}) is listed more than once")]
    DuplicateEdge(usize, usize),
    #[error(
        "the communication graph is disconnected (Assumption 1 needs a connected graph): {} components: {}",
        .0.len(), describe_components(.0)
    )]
    Disconnected(Vec<Vec<usize>>),
    #[error("the topology has {found} robots but the problem has {expected}")]
    SizeMismatch { expected: usize, found: usize },
    #[error(
        "unknown topology '{0}' (expected complete, chain, ring, star, grid, random:P, geometric:R or a .toml file)"
    )]
    UnknownKind(String),
    #[error("bad topology parameter in '{spec}': {reason}")]
    BadParameter { spec: String, reason: String },
    #[error("could not draw a connected {what} graph in {attempts} attempts; {hint}")]
    NeverConnected {
        what: &'static str,
        attempts: usize,
        hint: &'static str,
    },
    #[error("cannot read topology file {}: {reason}", .path.display())]
    Io { path: PathBuf, reason: String },
    #[error("topology file {}: {reason}", .path.display())]
    Parse { path: PathBuf, reason: String },
    #[error("topology file {}, edge {edge}", .path.display())]
    RobotName {
        path: PathBuf,
        edge: usize,
        source: Box<crate::RobotNameError>,
    },
}

fn describe_components(components: &[Vec<usize>]) -> String {
    components
        .iter()
        .map(|c| {
            if c.len() <= 8 {
                format!("{c:?}")
            } else {
                format!("[{}, {}, ... {} robots]", c[0], c[1], c.len())
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}
