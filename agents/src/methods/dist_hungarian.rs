//! Distributed Hungarian baseline, in the form the paper compares against (its Section 4.3:
//! "each robot shares its local cost information to create the bipartite graph required by
//! the Hungarian method"): every robot floods the cost rows it knows and, once it knows the
//! whole bipartite graph, solves it with the Hungarian method (our exact LSAP, Case 2
//! included). Robots that hold the same data compute the same optimum, so the assignment is
//! optimal and conflict-free.
//!
//! The payload is the `n × m` matrix of the rows the robot knows (`NaN` where unknown): a
//! robot at distance `h` from robot `j` learns row `j` after `h` rounds, so every robot knows
//! everything after the graph diameter `D`. The certificate is exact: slack 0 once the robot
//! knows every row (its assignment is then the optimum), ∞ before; the header protocol stops
//! every robot at the same round.
//!
//! Not built (issue 6): Chopra et al.'s edge-pruned exchange, where robots send only the
//! edges of their current optimal matching and its tight edges instead of whole rows; it
//! needs far fewer bytes on large teams. This version sends `8nm` bytes per round, like the
//! primal ADMM.

use crate::agent::{AgentAlgorithm, ConsensusAgent, Inbox, PayloadError, PayloadPart, StepReport};
use crate::method::info::{
    Certification, Fig2Graphs, Memory, MethodInfo, Numbers, OWN_STATE_STOPS, PaperFacts,
    ReportText, Role, TEAM_STATE, case_two_expansion, per_agent,
};
use crate::method::settings::NoSettings;
use crate::method::team::{AgentInit, TeamBuilder, TeamContext, TeamMethod};
use crate::problem::{AssignmentCase, CostMatrix};

/// Robot `index`'s state.
pub struct DistHungarianAgent {
    index: usize,
    tasks: usize,
    robots: usize,
    case: AssignmentCase,
    /// Row-major `n × m` known costs, `NaN` where unknown: the payload.
    known: Vec<f64>,
    known_rows: usize,
    /// Own task: the optimum's once solved, the cheapest before.
    task: usize,
    solved: bool,
    column: Vec<f64>,
}

impl DistHungarianAgent {
    pub fn new(index: usize, costs: Vec<f64>, robots: usize, case: AssignmentCase) -> Self {
        let tasks = costs.len();
        assert!(index < robots && tasks >= 1);
        let mut known = vec![f64::NAN; robots * tasks];
        known[index * tasks..(index + 1) * tasks].copy_from_slice(&costs);
        let cheapest = crate::certify::oracle::argmin(&costs);
        let mut column = vec![0.0; tasks];
        column[cheapest] = 1.0;
        let mut agent = Self {
            index,
            tasks,
            robots,
            case,
            known,
            known_rows: 1,
            task: cheapest,
            solved: false,
            column,
        };
        agent.solve_if_complete();
        agent
    }

    fn solve_if_complete(&mut self) {
        if self.solved || self.known_rows < self.robots {
            return;
        }
        // Every row is known and was checked finite; a failure (which Hall's condition,
        // checked before the run, rules out) keeps the cheapest task and never panics.
        let Ok(assignment) = CostMatrix::new(self.robots, self.tasks, self.known.clone())
            .map_err(|_| ())
            .and_then(|costs| {
                crate::certify::oracle::solve_costs(&costs, self.case).map_err(|_| ())
            })
        else {
            self.solved = true;
            return;
        };
        self.task = assignment[self.index];
        self.column.fill(0.0);
        // An idle robot (`--case idle`) has no task: an all-zero column.
        if let Some(slot) = self.column.get_mut(self.task) {
            *slot = 1.0;
        }
        self.solved = true;
    }
}

impl ConsensusAgent for DistHungarianAgent {
    fn payload_len(&self) -> usize {
        self.robots * self.tasks
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        out.copy_from_slice(&self.known);
    }

    /// Each row all `NaN` (unknown) or all finite.
    fn check_payload(&self, payload: &[f64]) -> Result<(), PayloadError> {
        crate::agent::check_length(payload, self.known.len())?;
        for (r, row) in payload.chunks(self.tasks).enumerate() {
            let unknown = row[0].is_nan();
            if row
                .iter()
                .any(|v| if unknown { !v.is_nan() } else { !v.is_finite() })
            {
                return Err(PayloadError::BadBlock {
                    part: PayloadPart::at("cost row", r),
                });
            }
        }
        Ok(())
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        let m = self.tasks;
        let before = self.known_rows;
        for k in 0..inbox.len() {
            let theirs = inbox.payload(k);
            assert_eq!(
                theirs.len(),
                self.known.len(),
                "neighbour payload has the wrong length"
            );
            for r in 0..self.robots {
                let row = r * m..(r + 1) * m;
                if self.known[r * m].is_nan() && !theirs[r * m].is_nan() {
                    self.known[row.clone()].copy_from_slice(&theirs[row]);
                    self.known_rows += 1;
                }
            }
        }
        self.solve_if_complete();
        out.copy_from_slice(&self.known);
        StepReport {
            disagreement: if self.known_rows == self.robots {
                0.0
            } else {
                1.0
            },
            change: (self.known_rows - before) as f64,
            inner_iterations: 0,
            inner_converged: true,
            integrality_gap: 0.0,
            own_integrality_gap: 0.0,
            // Equal at every robot once all know everything (and not before).
            assignment_digest: self.known_rows as u64,
        }
    }

    fn decide(&self) -> usize {
        self.task
    }

    fn rounded_task(&self) -> usize {
        self.task
    }

    fn certificate_slack(&self) -> f64 {
        if self.solved { 0.0 } else { f64::INFINITY }
    }

    fn own_column(&self) -> &[f64] {
        &self.column
    }
}

/// No penalty, one problem: the defaults.
impl AgentAlgorithm for DistHungarianAgent {}

/// The distributed Hungarian baseline's registration.
pub const INFO: MethodInfo = MethodInfo {
    name: "dist-hungarian",
    summary: "robots flood their cost rows and solve locally: optimal after a graph diameter",
    role: Role::Baseline,
    team: Some(&DistHungarianMethod),
    variants: None,
    stops: OWN_STATE_STOPS,
    // The known rows, two round buffers and the copy solved; Case 2's n×n expansion.
    memory: Memory {
        bytes: |n, m| per_agent(n, 4.0 * (n * m) as f64 + case_two_expansion(n, m)),
        of: TEAM_STATE,
        because: "each robot holds the n×m cost rows",
    },
    certification: Certification::WhenFinished,
    // It floods and solves the user's own numbers: every robot solves the same matrix the
    // same way.
    numbers: Numbers::Exact,
    report: ReportText { inner_steps: None },
    paper: Some(PaperFacts {
        label: "distributed Hungarian",
        proposed: false,
        table1: None,
        fig1: None,
        fig2: Fig2Graphs {
            complete: true,
            random: true,
        },
        variant: None,
    }),
};

/// The distributed Hungarian method as a team method.
pub struct DistHungarianMethod;

impl TeamMethod for DistHungarianMethod {
    type Settings = NoSettings;
    const PENALTY: bool = false;

    fn payload_len(&self, _: &NoSettings, robots: usize, tasks: usize) -> usize {
        robots * tasks
    }

    fn team<'a>(&'static self, _: &NoSettings, _: TeamContext<'a>) -> Box<dyn TeamBuilder + 'a> {
        Box::new(DistHungarianTeam)
    }
}

struct DistHungarianTeam;

impl TeamBuilder for DistHungarianTeam {
    fn agent(&self, init: AgentInit) -> Box<dyn AgentAlgorithm> {
        Box::new(DistHungarianAgent::new(
            init.index,
            init.costs,
            init.robots,
            init.case,
        ))
    }
}
