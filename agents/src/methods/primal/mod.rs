//! Primal consensus ADMM (Algorithm 1) in its two variants — the agent ([`agent`]), its
//! settings and variants ([`settings`]), and the fast variant's consensus step
//! ([`fast_consensus`]), readout ([`readout`]) and extrapolated readout
//! ([`readout_filter`]) — and everything the method declares ([`INFO`], [`PrimalMethod`]):
//! its payload, its ρ rule and schedule per variant, its stop cadence, how its robots
//! decide, and the team's readout filter.

pub mod agent;
pub mod fast_consensus;
pub mod readout;
pub mod readout_filter;
pub mod settings;

pub use agent::PrimalAgent;
pub use settings::{PrimalParams, PrimalSettings, PrimalVariant, ProjectionPath};

use crate::agent::AgentAlgorithm;
use crate::certify::stopping::StopRule;
use crate::method::info::{
    ALL_STOPS, Certification, Fig2Graphs, Memory, MethodInfo, Numbers, PaperFacts, ReportText,
    Role, TEAM_STATE, per_agent,
};
use crate::method::team::PartLayout;
use crate::method::team::{
    AgentInit, Decisions, Refusal, RunOption, TeamBuilder, TeamContext, TeamMethod,
};
use crate::methods::rho::{RhoRule, RhoSchedule};
use crate::problem::{CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::Graph;
use readout_filter::ReadoutFilter;
use settings::{FastTuning, fast_rho};
use std::sync::{Arc, OnceLock};

/// The primal method's registration.
pub const INFO: MethodInfo = MethodInfo {
    name: "primal",
    summary: "Algorithm 1, exchanges m×n matrices",
    role: Role::Admm,
    team: Some(&PrimalMethod),
    variants: Some(&settings::VARIANT),
    stops: ALL_STOPS,
    // X, Q, Z, the projection's workspace and two round buffers: six m×n matrices; the fast
    // variant's integer multipliers, edge sums and tie-break matrix: three more; the
    // certificate's minimiser of `G_i`: one more; the readout filter's `Q̂` and exact sums
    // (three) and its history (at most `MAX_WINDOW − 1` matrices and `HISTORY_BUDGET`).
    memory: Memory {
        bytes: |n, m| {
            let values = (m * n) as f64;
            let history = (values * (readout_filter::MAX_WINDOW - 1) as f64)
                .min(readout_filter::HISTORY_BUDGET as f64);
            per_agent(n, 13.0 * values + history)
        },
        of: TEAM_STATE,
        because: "each robot holds an m×n matrix",
    },
    certification: Certification::WhenStopProves,
    numbers: Numbers::Normalised,
    report: ReportText {
        inner_steps: Some("Newton steps per projection"),
    },
    paper: Some(PaperFacts {
        label: "ADMM-TA",
        proposed: true,
        table1: Some(28.0),
        fig1: Some("≈ 50 (within 0.1%)"),
        fig2: Fig2Graphs {
            complete: true,
            random: true,
        },
        variant: Some("paper"),
    }),
};

/// Primal consensus ADMM as a team method.
pub struct PrimalMethod;

impl TeamMethod for PrimalMethod {
    type Settings = PrimalSettings;
    const PENALTY: bool = true;

    fn payload_len(&self, _: &PrimalSettings, robots: usize, tasks: usize) -> usize {
        robots * tasks
    }

    /// Both variants: their message is the team's assignment matrix.
    fn parts(&self, _: &PrimalSettings) -> Option<PartLayout> {
        Some(PartLayout::Block)
    }

    /// The paper's variant: [`crate::methods::rho::default_rho`]; the fast one:
    /// [`fast_rho`], where the iteration no longer depends on ρ.
    fn default_rho(&self, settings: &PrimalSettings, costs: &CostMatrix, degree: f64) -> f64 {
        match settings.primal_variant {
            PrimalVariant::Fast => fast_rho(costs.spread(), degree),
            PrimalVariant::Paper => RhoRule::Primal.rho(costs, degree),
        }
    }

    /// The paper's variant only: the fast variant runs in a regime where ρ drops out of the
    /// iteration (the schedule was measured for the paper's readout).
    fn schedule(&self, settings: &PrimalSettings, initial: f64) -> Option<RhoSchedule> {
        (settings.primal_variant == PrimalVariant::Paper).then(|| RhoRule::Primal.schedule(initial))
    }

    /// `--adaptive-rho` and `--stop agreement` (which waits for near-integral iterates, which
    /// the fast variant's never are: they stay inside the polytope) need the paper's variant.
    fn refuse(
        &self,
        settings: &PrimalSettings,
        adaptive_rho: bool,
        stop: StopRule,
    ) -> Result<(), Refusal> {
        if settings.primal_variant == PrimalVariant::Paper {
            return Ok(());
        }
        let paper_only = |option| Refusal {
            option,
            needs: &settings::VARIANT,
            value: PrimalVariant::Paper.name(),
            because: "the paper's primal variant, not the fast one",
        };
        if adaptive_rho {
            Err(paper_only(RunOption::AdaptiveRho))
        } else if stop == StopRule::Agreement {
            Err(paper_only(RunOption::Stop(StopRule::Agreement)))
        } else {
            Ok(())
        }
    }

    /// The fast variant's certificate is a by-product of its readout: checked every round as
    /// soon as a robot agrees with its neighbours (a 5-round cadence and a 3-round streak
    /// would add several rounds to a 6-round solve).
    fn stop_cadence(&self, settings: &PrimalSettings) -> (u64, u32) {
        match settings.primal_variant {
            PrimalVariant::Fast => (1, 0),
            PrimalVariant::Paper => (
                crate::certify::local_stop::CHECK_EVERY,
                crate::certify::local_stop::CHECK_AFTER,
            ),
        }
    }

    /// The fast variant's robots decide by their readout of `G_i`, not by the argmax of their
    /// own relaxed columns.
    fn decisions(&self, settings: &PrimalSettings) -> Decisions {
        match settings.primal_variant {
            PrimalVariant::Fast => Decisions::Readout,
            PrimalVariant::Paper => Decisions::OwnColumn,
        }
    }

    fn team<'a>(
        &'static self,
        settings: &PrimalSettings,
        team: TeamContext<'a>,
    ) -> Box<dyn TeamBuilder + 'a> {
        Box::new(PrimalTeam::new(*settings, team))
    }
}

/// Builds a primal team's agents; the fast variant's readout filter is designed on first
/// use and shared by every agent built here.
pub struct PrimalTeam<'a> {
    settings: PrimalSettings,
    team: TeamContext<'a>,
    filter: OnceLock<Option<Arc<ReadoutFilter>>>,
}

impl<'a> PrimalTeam<'a> {
    pub fn new(settings: PrimalSettings, team: TeamContext<'a>) -> Self {
        Self {
            settings,
            team,
            filter: OnceLock::new(),
        }
    }

    /// Robot `init.index`'s agent.
    pub fn primal_agent(&self, init: AgentInit) -> PrimalAgent {
        let p = self.team.params;
        let mut agent = PrimalAgent::new(
            init.index,
            init.costs,
            init.robots,
            init.case,
            init.degree,
            PrimalParams {
                projection: self.settings.projection,
                ..PrimalParams::for_variant(
                    self.settings.primal_variant,
                    p.rho,
                    p.diameter,
                    init.robots,
                    p.tolerance,
                )
            },
        );
        let filter = self.filter.get_or_init(|| {
            readout_filter(
                self.team.problem,
                self.team.graph,
                &self.settings,
                p.rho,
                p.diameter,
            )
        });
        if let Some(filter) = filter {
            agent.set_readout_filter(Arc::clone(filter));
        }
        agent
    }
}

impl TeamBuilder for PrimalTeam<'_> {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        Box::new(self.primal_agent(init))
    }
}

/// One agent per robot of `graph` with these numbers (the same at every robot), each with
/// its own (optionally perturbed) costs — for examples and tests that drive a simulation of
/// primal agents directly (solves build theirs through [`PrimalMethod`]).
pub fn team_agents(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    params: PrimalParams,
    epsilon: Option<f64>,
    seed: u64,
) -> Vec<PrimalAgent> {
    (0..problem.robots())
        .map(|i| {
            PrimalAgent::new(
                i,
                crate::problem::ties::perturbed_row(problem.costs(), i, epsilon, seed),
                problem.robots(),
                problem.case(),
                graph.degree(i),
                params,
            )
        })
        .collect()
}

/// The readout filter every robot of a fast primal team uses, designed from the graph
/// ([`readout_filter`]); `None` for the paper's variant, below a tenth of the fast variant's
/// ρ, on graphs without edges, and where no history window fits the robot's memory budget.
fn readout_filter(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    settings: &PrimalSettings,
    rho: f64,
    diameter: usize,
) -> Option<Arc<ReadoutFilter>> {
    if settings.primal_variant != PrimalVariant::Fast {
        return None;
    }
    // The weights fit the iteration's linear large-ρ regime (every factor from 10 up gives
    // the same rounds); a much smaller `--rho` clips the iterates and the fit would not hold.
    let linear = fast_rho(problem.costs().spread(), graph.mean_degree()) / 10.0;
    if rho.is_nan() || rho < linear {
        return None;
    }
    let window = ReadoutFilter::window_for(problem.tasks(), problem.robots(), diameter);
    ReadoutFilter::design(graph, FastTuning::for_diameter(diameter), window).map(Arc::new)
}
