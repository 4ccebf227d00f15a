//! Every method's own settings as command-line flags, from the method registry: a method
//! declares each setting once ([`crate::agents::method::settings::SettingSpec`]: its key,
//! flag, help and values), and every command that takes method settings flattens
//! [`MethodFlags`].

use crate::Method;
use crate::agents::method::settings::{GivenSettings, SettingKind, SettingValue};
use clap::Args;

/// Every method's own settings as flags, from the method registry
/// ([`Method::all_settings`]): a method declares each of its settings once (its key, flag,
/// help and values) and every command that takes method settings has the flag. Holds the
/// settings the user gave.
#[derive(Debug, Clone, Default)]
pub struct MethodFlags(pub GivenSettings);

impl clap::FromArgMatches for MethodFlags {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut given = GivenSettings::default();
        for spec in Method::all_settings() {
            if matches.value_source(spec.key) != Some(clap::parser::ValueSource::CommandLine) {
                continue;
            }
            let value = match spec.kind {
                SettingKind::PositiveNumber { .. } => matches
                    .get_one::<f64>(spec.key)
                    .map(|v| SettingValue::Number(*v)),
                SettingKind::Choice(_) => matches
                    .get_one::<String>(spec.key)
                    .map(|v| SettingValue::Name(v.clone())),
            };
            if let Some(value) = value {
                given = given.set(spec, value);
            }
        }
        Ok(Self(given))
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl Args for MethodFlags {
    fn augment_args(command: clap::Command) -> clap::Command {
        Method::all_settings()
            .into_iter()
            .fold(command, |command, spec| {
                let arg = clap::Arg::new(spec.key)
                    .long(spec.flag.trim_start_matches("--"))
                    .value_name(spec.value_name)
                    .help(spec.help);
                let arg = match spec.kind {
                    SettingKind::PositiveNumber { .. } => arg
                        .value_parser(clap::value_parser!(f64))
                        .allow_negative_numbers(true),
                    SettingKind::Choice(names) => {
                        arg.value_parser(clap::builder::PossibleValuesParser::new(names()))
                    }
                };
                command.arg(arg)
            })
    }

    fn augment_args_for_update(command: clap::Command) -> clap::Command {
        Self::augment_args(command)
    }
}
