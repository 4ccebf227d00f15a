//! The methods, one module each, and their registry: every method the user can choose
//! ([`Method`]: the consensus ADMM methods, the baselines, the centralized optimum).
//!
//! Each method's module declares everything about it — its [`MethodInfo`] (name, summary,
//! role, stop rules, memory, certification, numbers, report text, what the paper reports)
//! and, for a method a team of agents runs, its [`crate::method::team::TeamMethod`] (payload,
//! ρ rule and schedule, settings, stop cadence, how its robots decide, how its team is
//! built). Runners, option checks, reports, the command line and the experiments read these
//! and never name a method.
//!
//! **A new method is its module plus one line of the registry below** (`Name => module::INFO`):
//! the variant of [`Method`], its name on the command line and in JSON, and its place in the
//! help all follow from it.
//!
//! ```
//! use admm_ta_agents::methods::Method;
//! // 2 task prices + 2 potentials + 2 packed claims, and Case 1's finish: 2 packed tags,
//! // its window, its alarm and its bound.
//! assert_eq!(Method::Dual.payload_len(2, 2), 9);
//! assert!(Method::Hungarian.info().team.is_none()); // solved centrally, no agents
//! assert!(Method::Dual.info().summary.starts_with("Algorithm 2"));
//! assert_eq!("inexact-dual".parse::<Method>(), Ok(Method::InexactDual));
//! ```

pub mod cbaa;
pub mod dist_hungarian;
pub mod dual;
pub mod hungarian;
pub mod market;
pub mod primal;
pub mod probe;
pub mod rho;

use crate::certify::stopping::StopRule;
use crate::method::info::{MethodInfo, Role, join};
use crate::method::settings::{GivenSettings, SettingError, SettingSpec};
use crate::method::team::{AnyTeamMethod, MethodSetup};
use serde::{Deserialize, Serialize};

/// Declares [`Method`] from the registry's lines: one variant per method, its registration.
macro_rules! registry {
    ($( $(#[$attr:meta])* $variant:ident => $info:path, )*) => {
        /// What solves the problem: the user's choice (`--method`, a team file's `method`, the
        /// JSON's `method`).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
        #[serde(rename_all = "kebab-case")]
        pub enum Method {
            $( $(#[$attr])* $variant, )*
        }

        impl Method {
            /// Every method, in the order of the command line's help.
            pub const ALL: [Method; [$(stringify!($variant)),*].len()] = [$(Method::$variant,)*];

            /// What this method declares.
            pub fn info(self) -> &'static MethodInfo {
                match self {
                    $( Self::$variant => &$info, )*
                }
            }
        }
    };
}

registry! {
    /// Primal consensus ADMM (Algorithm 1): robots exchange `m × n` matrices.
    #[default]
    Primal => primal::INFO,
    /// Dual consensus ADMM (Algorithm 2): robots exchange `n + m` multipliers.
    Dual => dual::DUAL,
    /// Dual consensus ADMM with the proximal-gradient x-update (no inner solve).
    InexactDual => dual::INEXACT_DUAL,
    /// Consensus-based auction algorithm (Choi, Brunet & How 2009): a greedy baseline.
    Cbaa => cbaa::INFO,
    /// Market with strategic pricing (Liu & Shell 2013), replicated over the graph: optimal.
    Market => market::INFO,
    /// Distributed Hungarian as the paper runs it: flood the cost rows, solve locally.
    DistHungarian => dist_hungarian::INFO,
    /// The centralized optimum (one "round", no agents): the reference row.
    Hungarian => hungarian::INFO,
}

impl Method {
    /// The name used on the command line, in team files and in JSON.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// Its team of agents, or `None`: the centralized solver.
    pub fn team(self) -> Option<&'static dyn AnyTeamMethod> {
        self.info().team
    }

    /// The method with the `given` settings, checked (`None`: the centralized solver, which
    /// has no settings).
    pub fn setup(
        self,
        given: &GivenSettings,
    ) -> Result<Option<Box<dyn MethodSetup>>, SettingError> {
        self.team().map(|team| team.configure(given)).transpose()
    }

    /// It has a penalty ρ (`--rho`, `--adaptive-rho`).
    pub fn penalty(self) -> bool {
        self.info().penalty()
    }

    /// Whether a standing team whose robots keep their costs private may run it with its
    /// default settings, and how ([`crate::method::team::TeamMethod::parts`]).
    pub fn parts(self) -> Option<crate::method::team::PartLayout> {
        self.team().and_then(|t| t.parts())
    }

    /// Length of the payload exchanged every round (0: no messages).
    pub fn payload_len(self, robots: usize, tasks: usize) -> usize {
        self.team().map_or(0, |t| t.payload_len(robots, tasks))
    }

    /// Whether it honours `stop`.
    pub fn supports(self, stop: StopRule) -> bool {
        self.info().stops.contains(&stop)
    }

    /// Its own settings.
    pub fn settings(self) -> &'static [SettingSpec] {
        self.team().map_or(&[], |t| t.settings())
    }

    /// Every method's settings, each key once, in the registry's order (the command line's
    /// flags and the team file's keys).
    pub fn all_settings() -> Vec<&'static SettingSpec> {
        let mut all: Vec<&'static SettingSpec> = Vec::new();
        for method in Self::ALL {
            for spec in method.settings() {
                if !all.iter().any(|s| s.key == spec.key) {
                    all.push(spec);
                }
            }
        }
        all
    }

    /// The methods whose entry satisfies `test`, for messages: `primal`, `dual or
    /// inexact-dual` (`conjunction` joins the last two).
    pub fn names_where(test: impl Fn(&MethodInfo) -> bool, conjunction: &str) -> String {
        let names: Vec<&str> = Self::ALL
            .into_iter()
            .filter(|m| test(m.info()))
            .map(Self::name)
            .collect();
        join(&names, conjunction)
    }

    /// The command line's help of `--method`: every method with its summary.
    pub fn help() -> String {
        let entries: Vec<String> = Self::ALL
            .into_iter()
            .map(|m| format!("{} ({})", m.name(), m.info().summary))
            .collect();
        let entries: Vec<&str> = entries.iter().map(String::as_str).collect();
        join(&entries, "or")
    }

    /// The paper's own method (ADMM-TA: the one its registration marks as proposed).
    pub fn papers_own() -> Method {
        Self::ALL
            .into_iter()
            .find(|m| m.info().paper.is_some_and(|p| p.proposed))
            .unwrap_or_default()
    }

    /// The consensus ADMM methods, in the registry's order.
    pub fn admm() -> Vec<Method> {
        Self::ALL
            .into_iter()
            .filter(|m| m.info().role == Role::Admm)
            .collect()
    }

    /// The setting that picks the method's variant, if it has variants.
    pub fn variant_setting(self) -> Option<&'static SettingSpec> {
        self.info().variants
    }

    /// The variants of the method (the names of its variant setting), its default first;
    /// `[None]` for a method without variants.
    pub fn variants(self) -> Vec<Option<&'static str>> {
        let Some(spec) = self.variant_setting() else {
            return vec![None];
        };
        let default = self
            .setup(&GivenSettings::default())
            .ok()
            .flatten()
            .and_then(|s| s.settings_json().get(spec.key).cloned());
        let mut names = spec.choices();
        names.sort_by_key(|n| default.as_ref().and_then(|d| d.as_str()) != Some(*n));
        names.into_iter().map(Some).collect()
    }
}

#[cfg(feature = "clap")]
crate::clap_value_enum!(Method);

/// A name that is no method.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown method '{name}' (use {})", Method::names_where(|_| true, "or"))]
pub struct UnknownMethod {
    pub name: String,
}

impl std::str::FromStr for Method {
    type Err = UnknownMethod;

    fn from_str(name: &str) -> Result<Self, UnknownMethod> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| UnknownMethod {
                name: name.to_string(),
            })
    }
}

/// A method as an experiment runs it: one of its variants (the primal method once per
/// variant), with a label for tables and plots (`primal (fast)`, `dual`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Contender {
    pub method: Method,
    /// A value of the method's variant setting (`None`: its default, or no variants).
    pub variant: Option<&'static str>,
}

impl Serialize for Contender {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut out = s.serialize_struct("Contender", 2)?;
        out.serialize_field("method", &self.method)?;
        out.serialize_field("variant", &self.variant)?;
        out.end()
    }
}

impl Contender {
    /// The method with its default settings.
    pub fn of(method: Method) -> Self {
        Self {
            method,
            variant: None,
        }
    }

    /// Every method a team runs, each variant once (default first): the consensus ADMM
    /// methods, then the optimal baselines, then the heuristics.
    pub fn all() -> Vec<Contender> {
        let mut all: Vec<Contender> = Method::ALL
            .into_iter()
            .filter(|m| m.team().is_some())
            .flat_map(|method| {
                method
                    .variants()
                    .into_iter()
                    .map(move |variant| Self { method, variant })
            })
            .collect();
        all.sort_by_key(|c| {
            let info = c.method.info();
            (
                info.role != Role::Admm,
                matches!(
                    info.certification,
                    crate::method::info::Certification::Never { .. }
                ),
            )
        });
        all
    }

    /// The method as the paper ran it (its paper variant), if the paper ran it.
    pub fn as_in_paper(method: Method) -> Option<Self> {
        let paper = method.info().paper?;
        Some(Self {
            method,
            variant: paper.variant,
        })
    }

    /// The settings it runs with.
    pub fn settings(&self) -> GivenSettings {
        match (self.variant, self.method.variant_setting()) {
            (Some(variant), Some(spec)) => GivenSettings::default().set(
                spec,
                crate::method::settings::SettingValue::Name(variant.to_string()),
            ),
            _ => GivenSettings::default(),
        }
    }

    /// `primal (fast)` for a method with variants, else the method's name.
    pub fn label(&self) -> String {
        match (self.method.variant_setting(), self.variant) {
            (Some(_), Some(variant)) => format!("{} ({variant})", self.method.name()),
            (Some(_), None) => {
                let default = self.method.variants()[0].unwrap_or_default();
                format!("{} ({default})", self.method.name())
            }
            _ => self.method.name().to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_registry_is_consistent() {
        for method in Method::ALL {
            let json = serde_json::to_string(&method).unwrap();
            assert_eq!(json, format!("\"{}\"", method.name()));
            assert_eq!(method.name().parse::<Method>(), Ok(method));
            assert!(method.supports(StopRule::Local) && method.supports(StopRule::MaxIters));
            // A method's settings take their own defaults.
            assert!(method.setup(&GivenSettings::default()).is_ok());
        }
        assert_eq!(Method::ALL.iter().filter(|m| m.team().is_none()).count(), 1);
        assert_eq!(
            Method::ALL
                .into_iter()
                .filter(|m| m.penalty())
                .collect::<Vec<_>>(),
            [Method::Primal, Method::Dual, Method::InexactDual]
        );
        assert_eq!(
            Method::admm(),
            [Method::Primal, Method::Dual, Method::InexactDual]
        );
        assert_eq!(Method::papers_own(), Method::Primal);
        assert_eq!(
            Method::names_where(|i| i.stops.contains(&StopRule::Certified), "or"),
            "primal"
        );
        assert!(Method::help().starts_with("primal (Algorithm 1, exchanges m×n matrices), dual ("));
        assert!(
            Method::help()
                .ends_with(" or hungarian (the centralized optimum, one round, sim only)")
        );
        let keys: Vec<&str> = Method::all_settings().iter().map(|s| s.key).collect();
        assert_eq!(
            keys,
            [
                "primal_variant",
                "projection",
                "dual_variant",
                "gamma_factor"
            ]
        );
        assert!("pigeon".parse::<Method>().is_err());
    }

    #[test]
    fn contenders_are_every_team_method_and_variant() {
        let labels: Vec<String> = Contender::all().iter().map(Contender::label).collect();
        assert_eq!(
            labels,
            [
                "primal (fast)",
                "primal (paper)",
                "dual (fast)",
                "dual (paper)",
                "inexact-dual (fast)",
                "inexact-dual (paper)",
                "market",
                "dist-hungarian",
                "cbaa"
            ]
        );
        assert_eq!(
            Contender::as_in_paper(Method::Primal).unwrap().label(),
            "primal (paper)"
        );
        assert!(Contender::as_in_paper(Method::Hungarian).is_none());
        assert_eq!(
            Contender::as_in_paper(Method::Market).unwrap().label(),
            "market"
        );
    }

    #[test]
    fn memory_estimates_follow_what_each_method_holds() {
        let gib =
            |m: Method, n: usize, t: usize| (m.info().memory.bytes)(n, t) / (1u64 << 30) as f64;
        // The primal's m×n matrix per robot: 5000 × 5000 is far beyond 8 GiB …
        assert!(gib(Method::Primal, 5000, 5000) > 5000.0);
        // … the dual's n + m multipliers and the centralized solver are not.
        assert!(gib(Method::Dual, 5000, 5000) < 8.0);
        assert!(gib(Method::Hungarian, 5000, 5000) < 1.0);
        assert!(
            gib(Method::Hungarian, 100_000, 2) > 8.0,
            "Case 2's n×n expansion"
        );
    }
}
