//! A robot named in a file: by its 0-based number, or by the name the cost file gave it.
//!
//! ```
//! use admm_ta_topologies::RobotRef;
//! let names = ["uav1".to_string(), "uav2".to_string()];
//! assert_eq!(RobotRef::Name("uav2".into()).resolve(Some(&names)), Ok(1));
//! assert_eq!(RobotRef::Index(0).resolve(None), Ok(0));
//! assert!(RobotRef::Name("uav9".into()).resolve(Some(&names)).is_err());
//! ```

use serde::{Deserialize, Deserializer, Serialize, de};
use std::fmt;

/// A robot by number (a TOML integer) or by name (a TOML string).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(untagged)]
pub enum RobotRef {
    Index(usize),
    Name(String),
}

impl<'de> Deserialize<'de> for RobotRef {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl de::Visitor<'_> for Visitor {
            type Value = RobotRef;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a robot number from 0 or a robot name")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<RobotRef, E> {
                usize::try_from(v)
                    .map(RobotRef::Index)
                    .map_err(|_| E::custom(format!("robot {v} is too large")))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<RobotRef, E> {
                match u64::try_from(v) {
                    Ok(v) => self.visit_u64(v),
                    Err(_) => Err(E::custom(format!(
                        "robot {v} is negative: robots are numbered from 0"
                    ))),
                }
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RobotRef, E> {
                Ok(RobotRef::Name(v.to_string()))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// A name that does not match a robot.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RobotNameError {
    /// The cost file has no robot names, so only numbers can refer to robots.
    #[error("robot '{0}' is named, but the costs name no robots: number robots from 0")]
    Unnamed(String),
    /// No robot has this name.
    #[error("no robot is named '{name}' (the robots are {})", listed(.known))]
    Unknown { name: String, known: Vec<String> },
}

fn listed(names: &[String]) -> String {
    const SHOWN: usize = 8;
    let mut text = names
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        text.push_str(&format!(", … {} in all", names.len()));
    }
    text
}

impl RobotRef {
    /// The robot's number: an index as it is (range checks are the caller's), a name looked
    /// up in `names` (the cost file's robot names, in row order).
    pub fn resolve(&self, names: Option<&[String]>) -> Result<usize, RobotNameError> {
        match self {
            Self::Index(i) => Ok(*i),
            Self::Name(name) => {
                let names = names.ok_or_else(|| RobotNameError::Unnamed(name.clone()))?;
                names
                    .iter()
                    .position(|n| n == name)
                    .ok_or_else(|| RobotNameError::Unknown {
                        name: name.clone(),
                        known: names.to_vec(),
                    })
            }
        }
    }
}

/// From the command line: digits are a number, anything else a name.
impl std::str::FromStr for RobotRef {
    type Err = std::convert::Infallible;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(s.parse()
            .map(Self::Index)
            .unwrap_or_else(|_| Self::Name(s.to_string())))
    }
}

impl fmt::Display for RobotRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Index(i) => write!(f, "{i}"),
            Self::Name(name) => write!(f, "'{name}'"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_robot_and_the_known_names() {
        let names: Vec<String> = (0..12).map(|i| format!("r{i}")).collect();
        let unknown = RobotRef::Name("x".into())
            .resolve(Some(&names))
            .unwrap_err()
            .to_string();
        assert!(unknown.contains("'x'"), "{unknown}");
        assert!(unknown.contains("r0, r1"), "{unknown}");
        assert!(unknown.contains("12 in all"), "{unknown}");
        let unnamed = RobotRef::Name("x".into()).resolve(None).unwrap_err();
        assert_eq!(unnamed, RobotNameError::Unnamed("x".into()));
        // An index is taken as it is, names or not.
        assert_eq!(RobotRef::Index(40).resolve(Some(&names)), Ok(40));
        let parsed: Vec<RobotRef> = toml::from_str::<toml::Table>("a = [1, \"r2\"]").unwrap()["a"]
            .clone()
            .try_into()
            .unwrap();
        assert_eq!(parsed, [RobotRef::Index(1), RobotRef::Name("r2".into())]);
        let negative = toml::from_str::<toml::Table>("a = -1").unwrap()["a"]
            .clone()
            .try_into::<RobotRef>()
            .unwrap_err()
            .to_string();
        assert!(negative.contains("numbered from 0"), "{negative}");
        let fraction = toml::from_str::<toml::Table>("a = 1.5").unwrap()["a"]
            .clone()
            .try_into::<RobotRef>()
            .unwrap_err()
            .to_string();
        assert!(
            fraction.contains("a robot number from 0 or a robot name"),
            "{fraction}"
        );
    }
}
