//! A method's own settings: one type per method ([`MethodSettings`]), each setting one field
//! of it, described once by a [`SettingSpec`] next to the field (its team-file key, its
//! command-line flag, its help). Front ends (the command line, team files, the library)
//! collect the settings a caller gave ([`GivenSettings`]); the method's type takes them
//! (serde, by key) or refuses them ([`SettingError`]). A new setting is one field and one
//! spec: the command line's flag, the team file's key, option validation and the scenario
//! file of agent processes all follow from them.
//!
//! ```
//! use admm_ta_agents::method::settings::{GivenSettings, MethodSettings};
//! use admm_ta_agents::methods::dual::{GammaFactor, InexactDualSettings};
//! let given = GivenSettings::default().with(GammaFactor(0.7));
//! let settings = InexactDualSettings::from_given(&given).unwrap();
//! assert_eq!(settings.gamma_factor, Some(0.7));
//! assert!(InexactDualSettings::from_given(&GivenSettings::default().with(GammaFactor(0.0))).is_err());
//! ```

use serde::Serialize;
use serde::de::DeserializeOwned;

/// The values a setting takes.
#[derive(Debug, Clone, Copy)]
pub enum SettingKind {
    /// A positive finite number; `what` names it in errors (`the γ factor`).
    PositiveNumber { what: &'static str },
    /// One of these names (in the help's order).
    Choice(fn() -> Vec<&'static str>),
}

/// One setting of a method: a field of its settings type.
#[derive(Debug)]
pub struct SettingSpec {
    /// The field's name: the team file's key, and the settings type's serde name.
    pub key: &'static str,
    /// The command line's flag (`--gamma-factor`).
    pub flag: &'static str,
    /// The value's placeholder in the command line's help.
    pub value_name: &'static str,
    /// One paragraph for the command line's help.
    pub help: &'static str,
    pub kind: SettingKind,
}

impl PartialEq for SettingSpec {
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key
    }
}

impl SettingSpec {
    /// The names a [`SettingKind::Choice`] takes (empty for numbers).
    pub fn choices(&self) -> Vec<&'static str> {
        match self.kind {
            SettingKind::Choice(names) => names(),
            SettingKind::PositiveNumber { .. } => Vec::new(),
        }
    }

    /// Refuses a value outside what this setting takes (a number out of range, a name that
    /// is not a choice).
    pub fn check(&'static self, value: &SettingValue) -> Result<(), SettingError> {
        check_value(self, value)
    }

    /// `text` as a value of this setting: a name of its choices, or a positive finite
    /// number.
    pub fn parse(&'static self, text: &str) -> Result<SettingValue, SettingError> {
        match self.kind {
            SettingKind::Choice(names) => {
                let found = names().into_iter().find(|n| *n == text);
                found
                    .map(|n| SettingValue::Name(n.to_string()))
                    .ok_or_else(|| SettingError::NotAChoice {
                        spec: self,
                        got: text.to_string(),
                    })
            }
            SettingKind::PositiveNumber { .. } => text
                .trim()
                .parse::<f64>()
                .map_err(|_| SettingError::NotANumber {
                    spec: self,
                    got: text.to_string(),
                })
                .map(SettingValue::Number),
        }
    }
}

/// A value given for a setting.
#[derive(Debug, Clone, PartialEq)]
pub enum SettingValue {
    Number(f64),
    Name(String),
}

impl SettingValue {
    fn json(&self) -> serde_json::Value {
        match self {
            // A NaN or an infinity is refused before it gets here.
            Self::Number(v) => serde_json::Number::from_f64(*v)
                .map_or(serde_json::Value::Null, serde_json::Value::Number),
            Self::Name(n) => serde_json::Value::String(n.clone()),
        }
    }
}

impl std::fmt::Display for SettingValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Number(v) => write!(f, "{v}"),
            Self::Name(n) => f.write_str(n),
        }
    }
}

/// A setting's value type, for the library's typed setter
/// (`SolveOptionsBuilder::setting(PrimalVariant::Paper)`).
pub trait Setting {
    /// The setting it is the value of.
    const SPEC: &'static SettingSpec;
    fn value(self) -> SettingValue;
}

/// The settings a caller gave, in the order given (a key given twice keeps its last value).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GivenSettings(Vec<(&'static SettingSpec, SettingValue)>);

impl GivenSettings {
    /// These and `spec = value`.
    pub fn set(mut self, spec: &'static SettingSpec, value: SettingValue) -> Self {
        self.0.retain(|(s, _)| s.key != spec.key);
        self.0.push((spec, value));
        self
    }

    /// These and a typed setting.
    pub fn with<S: Setting>(self, setting: S) -> Self {
        self.set(S::SPEC, setting.value())
    }

    pub fn iter(&self) -> impl Iterator<Item = (&'static SettingSpec, &SettingValue)> {
        self.0.iter().map(|(s, v)| (*s, v))
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The given value of `key`, if any.
    pub fn get(&self, key: &str) -> Option<&SettingValue> {
        self.0.iter().find(|(s, _)| s.key == key).map(|(_, v)| v)
    }

    /// Only the settings among `specs` (what a method reads of settings given for a sweep
    /// over several methods).
    pub fn only(&self, specs: &[SettingSpec]) -> Self {
        Self(
            self.0
                .iter()
                .filter(|(s, _)| specs.iter().any(|t| t.key == s.key))
                .cloned()
                .collect(),
        )
    }
}

/// A setting no method can take as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingError {
    /// A value out of the setting's range.
    #[error(
        "{} ({}) must be a positive finite number, got {got}",
        spec.flag,
        match spec.kind { SettingKind::PositiveNumber { what } => what, SettingKind::Choice(_) => spec.key }
    )]
    OutOfRange {
        spec: &'static SettingSpec,
        got: f64,
    },
    #[error("{} must be a number, got '{got}'", spec.flag)]
    NotANumber {
        spec: &'static SettingSpec,
        got: String,
    },
    #[error("{} must be {}, got '{got}'", spec.flag, spec.choices().join(" or "))]
    NotAChoice {
        spec: &'static SettingSpec,
        got: String,
    },
    /// A setting of another method (the method's type has no such field).
    #[error("{} is not a setting of this method", spec.flag)]
    NotOfMethod { spec: &'static SettingSpec },
}

impl SettingError {
    /// The setting the error is about.
    pub fn spec(&self) -> &'static SettingSpec {
        match self {
            Self::OutOfRange { spec, .. }
            | Self::NotANumber { spec, .. }
            | Self::NotAChoice { spec, .. }
            | Self::NotOfMethod { spec } => spec,
        }
    }
}

/// A method's own settings: one field per [`SettingSpec`] of [`MethodSettings::SPECS`], named
/// by its key (serde), each with its default.
pub trait MethodSettings:
    Clone + std::fmt::Debug + Default + PartialEq + Serialize + DeserializeOwned + Send + Sync + 'static
{
    /// Every setting, one per field.
    const SPECS: &'static [SettingSpec];

    /// The defaults with the `given` settings (each must be one of [`MethodSettings::SPECS`]),
    /// checked.
    fn from_given(given: &GivenSettings) -> Result<Self, SettingError> {
        if given.is_empty() {
            return Ok(Self::default());
        }
        let mut fields = match serde_json::to_value(Self::default()) {
            Ok(serde_json::Value::Object(fields)) => fields,
            _ => serde_json::Map::new(),
        };
        for (spec, value) in given.iter() {
            if !Self::SPECS.iter().any(|s| s.key == spec.key) {
                return Err(SettingError::NotOfMethod { spec });
            }
            check_value(spec, value)?;
            fields.insert(spec.key.to_string(), value.json());
        }
        serde_json::from_value(serde_json::Value::Object(fields)).map_err(|_| {
            // The values were checked against their specs: only a spec that does not match
            // its field gets here.
            let (spec, _) = given.iter().last().expect("given is not empty");
            SettingError::NotOfMethod { spec }
        })
    }
}

/// Refuses a value outside what `spec` takes.
fn check_value(spec: &'static SettingSpec, value: &SettingValue) -> Result<(), SettingError> {
    match (spec.kind, value) {
        (SettingKind::PositiveNumber { .. }, SettingValue::Number(v)) => {
            if *v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(SettingError::OutOfRange { spec, got: *v })
            }
        }
        (SettingKind::PositiveNumber { .. }, SettingValue::Name(n)) => {
            Err(SettingError::NotANumber {
                spec,
                got: n.clone(),
            })
        }
        (SettingKind::Choice(names), SettingValue::Name(n)) if names().contains(&n.as_str()) => {
            Ok(())
        }
        (SettingKind::Choice(_), other) => Err(SettingError::NotAChoice {
            spec,
            got: other.to_string(),
        }),
    }
}

/// The settings of a method that has none.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoSettings {}

impl MethodSettings for NoSettings {
    const SPECS: &'static [SettingSpec] = &[];
}
