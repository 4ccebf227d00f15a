use crate::{Graph, TopologyError, file, generate};
use std::path::PathBuf;
use std::str::FromStr;

/// A topology as the user names it on the command line:
/// `complete | chain | ring | star | grid | random:P | geometric:R | FILE.toml`.
#[derive(Debug, Clone, PartialEq)]
pub enum TopologySpec {
    Complete,
    Chain,
    Ring,
    Star,
    Grid,
    /// Erdős–Rényi with edge probability `P`, redrawn until connected.
    Random(f64),
    /// Random geometric graph in the unit square with radius `R`, redrawn until connected.
    Geometric(f64),
    /// A topology file (see [`crate::file`]).
    File(PathBuf),
}

impl TopologySpec {
    /// Builds the graph for `robots` robots; random families draw from `seed`. The result
    /// is always connected (Assumption 1) and sized for `robots`, or an error says why not.
    pub fn build(&self, robots: usize, seed: u64) -> Result<Graph, TopologyError> {
        self.build_named(robots, seed, None)
    }

    /// As [`TopologySpec::build`], where a topology file may name robots by `robot_names`
    /// (the cost file's, in row order; see [`crate::file::parse_named`]).
    pub fn build_named(
        &self,
        robots: usize,
        seed: u64,
        robot_names: Option<&[String]>,
    ) -> Result<Graph, TopologyError> {
        let graph = match self {
            Self::Complete => generate::complete(robots)?,
            Self::Chain => generate::chain(robots)?,
            Self::Ring => generate::ring(robots)?,
            Self::Star => generate::star(robots)?,
            Self::Grid => generate::grid(robots)?,
            Self::Random(p) => generate::random_connected(robots, *p, seed)?,
            Self::Geometric(r) => generate::random_geometric(robots, *r, seed)?.0,
            Self::File(path) => {
                let g = file::read_named(path, robot_names)?;
                if g.robots() != robots {
                    return Err(TopologyError::SizeMismatch {
                        expected: robots,
                        found: g.robots(),
                    });
                }
                g
            }
        };
        graph.require_connected()?;
        Ok(graph)
    }
}

impl FromStr for TopologySpec {
    type Err = TopologyError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parameter = |value: &str| -> Result<f64, TopologyError> {
            value
                .parse::<f64>()
                .map_err(|_| TopologyError::BadParameter {
                    spec: s.to_string(),
                    reason: format!("'{value}' is not a number"),
                })
        };
        Ok(match s {
            "complete" | "full" => Self::Complete,
            "chain" | "line" => Self::Chain,
            "ring" | "cycle" => Self::Ring,
            "star" => Self::Star,
            "grid" => Self::Grid,
            _ => {
                if let Some(p) = s.strip_prefix("random:") {
                    Self::Random(parameter(p)?)
                } else if let Some(r) = s.strip_prefix("geometric:") {
                    Self::Geometric(parameter(r)?)
                } else if s.ends_with(".toml") || s.contains('/') {
                    Self::File(PathBuf::from(s))
                } else {
                    return Err(TopologyError::UnknownKind(s.to_string()));
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_kind() {
        assert_eq!(
            "chain".parse::<TopologySpec>().unwrap(),
            TopologySpec::Chain
        );
        assert_eq!(
            "random:0.3".parse::<TopologySpec>().unwrap(),
            TopologySpec::Random(0.3)
        );
        assert!(matches!(
            "geometric:x".parse::<TopologySpec>(),
            Err(TopologyError::BadParameter { .. })
        ));
        assert!(matches!(
            "hypercube".parse::<TopologySpec>(),
            Err(TopologyError::UnknownKind(_))
        ));
        assert!(matches!(
            "nets/a.toml".parse::<TopologySpec>().unwrap(),
            TopologySpec::File(_)
        ));
    }
}
