//! Which option a check or an error is about ([`OptionName`]: an option of every solve,
//! [`OptionId`], or a method's own setting, [`SettingSpec`]), which options a caller gave
//! ([`Given`]), and how each front end spells them ([`FrontEnd`]): the command line's flag
//! (`--max-iters`) or the team file's key (`max_iters`). Errors name options; each front
//! end renders them in its own terms.

use admm_ta_agents::method::settings::{SettingSpec, SettingValue};

/// An option of every solve, whatever front end set it (a method's own settings are
/// [`SettingSpec`]s of the method).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OptionId {
    Method,
    Transport,
    Rho,
    AdaptiveRho,
    MaxIters,
    Stop,
    StopRounds,
    Perturb,
    Trace,
    GlobalBarrier,
    RoundTimeout,
    StartupTimeout,
    OnFailure,
    Wait,
    Timeline,
}

impl OptionId {
    /// The command line's flag.
    pub fn flag(self) -> &'static str {
        match self {
            Self::Method => "--method",
            Self::Transport => "--transport",
            Self::Rho => "--rho",
            Self::AdaptiveRho => "--adaptive-rho",
            Self::MaxIters => "--max-iters",
            Self::Stop => "--stop",
            Self::StopRounds => "--stop-rounds",
            Self::Perturb => "--perturb",
            Self::Trace => "--trace",
            Self::GlobalBarrier => "--global-barrier",
            Self::RoundTimeout => "--round-timeout",
            Self::StartupTimeout => "--startup-timeout",
            Self::OnFailure => "--on-failure",
            Self::Wait => "--wait",
            Self::Timeline => "--timeline",
        }
    }

    /// The team file's key, for the options a team file sets.
    pub fn key(self) -> Option<&'static str> {
        Some(match self {
            Self::Method => "method",
            Self::Transport => "transport",
            Self::AdaptiveRho => "adaptive_rho",
            Self::MaxIters => "max_iters",
            Self::RoundTimeout => "round_timeout",
            Self::StartupTimeout => "startup_timeout",
            Self::Timeline => "timeline",
            _ => return None,
        })
    }

    fn bit(self) -> u32 {
        1 << self as u32
    }
}

/// The options a caller gave (set explicitly, whatever the value).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Given(u32);

impl Given {
    /// These and `id`.
    pub fn with(self, id: OptionId) -> Self {
        Self(self.0 | id.bit())
    }

    pub fn contains(self, id: OptionId) -> bool {
        self.0 & id.bit() != 0
    }
}

/// A value as an error shows it.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A switch that is on (`--adaptive-rho`, `adaptive_rho = true`).
    On,
    /// A name (`--method market`, `method = "market"`).
    Name(std::borrow::Cow<'static, str>),
    /// A number (`--rho 3`, `rho = 3`).
    Number(f64),
}

/// An option: of every solve, or a method's own setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionName {
    Run(OptionId),
    Method(&'static SettingSpec),
}

impl OptionName {
    /// The command line's flag.
    pub fn flag(self) -> &'static str {
        match self {
            Self::Run(id) => id.flag(),
            Self::Method(spec) => spec.flag,
        }
    }

    /// The team file's key, for the options a team file sets.
    pub fn key(self) -> Option<&'static str> {
        match self {
            Self::Run(id) => id.key(),
            Self::Method(spec) => Some(spec.key),
        }
    }
}

impl From<OptionId> for OptionName {
    fn from(id: OptionId) -> Self {
        Self::Run(id)
    }
}

/// An option with the value it was given.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    pub option: OptionName,
    pub value: Value,
}

impl Value {
    /// A method setting's given value as an error shows it.
    pub fn of(value: &SettingValue) -> Self {
        match value {
            SettingValue::Number(v) => Self::Number(*v),
            SettingValue::Name(n) => Self::Name(n.clone().into()),
        }
    }
}

impl Setting {
    pub fn new(option: impl Into<OptionName>, value: Value) -> Self {
        Self {
            option: option.into(),
            value,
        }
    }
}

/// Who set the options, and so how an error names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrontEnd {
    /// `admm-ta solve` and the library: flags (`--max-iters`).
    #[default]
    CommandLine,
    /// A team file (`admm-ta agent`, `collect`, `host`): keys (`max_iters`).
    TeamFile,
}

impl FrontEnd {
    /// The option's name: its flag, or its key in a team file (the flag when a team file
    /// has no such key: then no team file set it).
    pub fn name(self, option: impl Into<OptionName>) -> &'static str {
        let option = option.into();
        match (self, option.key()) {
            (Self::TeamFile, Some(key)) => key,
            _ => option.flag(),
        }
    }

    /// The option with any of `values`: `--method primal or dual`, or
    /// `method = "primal" or "dual"`.
    pub fn choices(self, option: impl Into<OptionName>, values: &[&str]) -> String {
        let option = option.into();
        let name = self.name(option);
        if self == Self::TeamFile && option.key().is_some() {
            let quoted: Vec<String> = values.iter().map(|v| format!("\"{v}\"")).collect();
            format!("{name} = {}", join(&quoted))
        } else {
            let plain: Vec<String> = values.iter().map(|v| v.to_string()).collect();
            format!("{name} {}", join(&plain))
        }
    }

    /// The option with its value: `--method market` or `method = "market"`.
    pub fn setting(self, setting: &Setting) -> String {
        let name = self.name(setting.option);
        let file = self == Self::TeamFile && setting.option.key().is_some();
        match (&setting.value, file) {
            (Value::On, false) => name.to_string(),
            (Value::On, true) => format!("{name} = true"),
            (Value::Name(value), false) => format!("{name} {value}"),
            (Value::Name(value), true) => format!("{name} = \"{value}\""),
            (Value::Number(value), false) => format!("{name} {}", Compact(*value)),
            (Value::Number(value), true) => format!("{name} = {}", Compact(*value)),
        }
    }
}

/// `first, second or last`.
fn join(names: &[String]) -> String {
    match names.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

/// A number as typed, or in scientific notation when that is far shorter (1e300, 1e-9).
pub(crate) struct Compact(pub f64);

impl std::fmt::Display for Compact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let plain = self.0.to_string();
        let scientific = format!("{:e}", self.0);
        f.write_str(if scientific.len() < plain.len() {
            &scientific
        } else {
            &plain
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_front_end_spells_an_option_its_own_way() {
        let variant = &admm_ta_agents::methods::primal::settings::VARIANT;
        let paper = Setting::new(OptionName::Method(variant), Value::Name("paper".into()));
        assert_eq!(
            FrontEnd::CommandLine.setting(&paper),
            "--primal-variant paper"
        );
        assert_eq!(
            FrontEnd::TeamFile.setting(&paper),
            "primal_variant = \"paper\""
        );
        let adaptive = Setting::new(OptionId::AdaptiveRho, Value::On);
        assert_eq!(FrontEnd::CommandLine.setting(&adaptive), "--adaptive-rho");
        assert_eq!(FrontEnd::TeamFile.setting(&adaptive), "adaptive_rho = true");
        let rho = Setting::new(OptionId::Rho, Value::Number(3.0));
        assert_eq!(FrontEnd::CommandLine.setting(&rho), "--rho 3");
        assert_eq!(FrontEnd::TeamFile.name(OptionId::MaxIters), "max_iters");
        assert_eq!(
            FrontEnd::TeamFile.choices(OptionId::Method, &["primal", "dual"]),
            "method = \"primal\" or \"dual\""
        );
        assert_eq!(
            FrontEnd::CommandLine.choices(OptionId::Method, &["a", "b", "c"]),
            "--method a, b or c"
        );
        let given = Given::default().with(OptionId::Rho);
        assert!(given.contains(OptionId::Rho) && !given.contains(OptionId::Wait));
    }
}
