//! What `admm-ta bench rounds` measures: the steps, payloads and barriers of a case, the
//! cases of a sweep and the run's settings.

use admm_ta_transport::Transport;
use admm_ta_transport::wait::WaitStrategy;
use serde::Serialize;
use std::time::Duration;

/// What the agents compute each round.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StepKind {
    /// Read one value per neighbour: the round is the exchange alone.
    Touch,
    /// Average the whole payloads (every byte read).
    Average,
    /// The primal consensus ADMM step on uniform `n × n` costs (payload `n × n`).
    Primal,
}

impl StepKind {
    /// Every step, in the order of the command line's help.
    pub const ALL: [StepKind; 3] = [Self::Touch, Self::Average, Self::Primal];

    pub fn name(self) -> &'static str {
        match self {
            Self::Touch => "touch",
            Self::Average => "average",
            Self::Primal => "primal",
        }
    }
}

#[cfg(feature = "clap")]
admm_ta_agents::clap_value_enum!(StepKind);

/// Which barrier ends a round.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Barrier {
    /// Each agent waits for its neighbours' messages only.
    Neighbour,
    /// Every agent also waits for the whole team (threads and ipc).
    Global,
}

impl Barrier {
    /// Both kinds, in the order of the command line's help.
    pub const ALL: [Barrier; 2] = [Self::Neighbour, Self::Global];

    /// The kind of a run with or without a global barrier.
    pub fn of(global: bool) -> Self {
        if global {
            Self::Global
        } else {
            Self::Neighbour
        }
    }

    pub fn is_global(self) -> bool {
        self == Self::Global
    }

    /// `neighbour` or `global`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Neighbour => "neighbour",
            Self::Global => "global",
        }
    }
}

#[cfg(feature = "clap")]
admm_ta_agents::clap_value_enum!(Barrier);

/// Payload of `rows × cols` f64 values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct PayloadShape {
    pub rows: usize,
    pub cols: usize,
}

impl PayloadShape {
    pub fn values(self) -> usize {
        self.rows * self.cols
    }
}

impl std::fmt::Display for PayloadShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.rows, self.cols)
    }
}

impl std::str::FromStr for PayloadShape {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (r, c) = s
            .split_once(['x', 'X', '×'])
            .ok_or_else(|| format!("payload '{s}' is not ROWSxCOLS (e.g. 10x10)"))?;
        let parse = |t: &str| {
            t.trim()
                .parse::<usize>()
                .ok()
                .filter(|&v| (1..=2000).contains(&v))
                .ok_or_else(|| format!("payload '{s}': dimensions must be 1…2000"))
        };
        Ok(Self {
            rows: parse(r)?,
            cols: parse(c)?,
        })
    }
}

/// One measured configuration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Case {
    pub agents: usize,
    pub topology: String,
    pub payload: PayloadShape,
    pub transport: Transport,
    pub wait: WaitStrategy,
    pub global_barrier: bool,
    pub step: StepKind,
}

impl Case {
    /// A file name for the case: `10-complete-10x10-ipc-auto-neighbour` (anything but
    /// letters, digits, `.` and `-` becomes `-`).
    pub fn slug(&self) -> String {
        self.fields()
            .join("-")
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                    c
                } else {
                    '-'
                }
            })
            .collect()
    }

    /// Agents, graph, payload, transport, wait, barrier.
    fn fields(&self) -> [String; 6] {
        [
            self.agents.to_string(),
            self.topology.clone(),
            self.payload.to_string(),
            self.transport.name().to_string(),
            self.wait.name().to_string(),
            self.barrier_name().to_string(),
        ]
    }

    /// `global` or `neighbour`.
    pub fn barrier_name(&self) -> &'static str {
        Barrier::of(self.global_barrier).name()
    }

    /// The first six columns of the Markdown tables: agents, graph, payload, transport,
    /// wait, barrier.
    pub fn columns(&self) -> String {
        format!("| {} |", self.fields().join(" | "))
    }
}

/// Which configurations to measure. `None` axes take the preset's sweep.
#[derive(Debug, Clone, Default)]
pub struct SweepSpec {
    pub agents: Option<Vec<usize>>,
    pub topologies: Option<Vec<String>>,
    pub payloads: Option<Vec<PayloadShape>>,
    pub transports: Option<Vec<Transport>>,
    pub waits: Option<Vec<WaitStrategy>>,
    pub barriers: Option<Vec<Barrier>>,
}

/// Settings of a benchmark run.
#[derive(Debug, Clone)]
pub struct RoundsConfig {
    pub sweep: SweepSpec,
    pub quick: bool,
    pub step: StepKind,
    /// Recorded rounds per case (after the warm-up).
    pub rounds: u64,
    pub warmup: u64,
    /// Measurements of every case; transports of one configuration are interleaved.
    pub repeat: usize,
    pub agent_program: Option<admm_ta_runtime::options::run::AgentProgram>,
    pub round_timeout: Duration,
    /// Every agent stamps its rounds (`--timeline`, or to measure what that costs).
    pub timeline: bool,
    /// `--timeline DIR`: each case's trace is written there (`<case slug>.json`).
    pub traces: Option<std::path::PathBuf>,
}

impl RoundsConfig {
    /// The preset's rounds: 1000 after 100 (`--quick`: 400 after 50).
    pub fn new(quick: bool) -> Self {
        Self {
            sweep: SweepSpec::default(),
            quick,
            step: StepKind::Touch,
            rounds: if quick { 400 } else { 1000 },
            warmup: if quick { 50 } else { 100 },
            repeat: 1,
            agent_program: None,
            round_timeout: Duration::from_secs(30),
            timeline: false,
            traces: None,
        }
    }
}

/// The transports a sweep measures unless told otherwise.
pub const DEFAULT_TRANSPORTS: [Transport; 4] = [
    Transport::Threads,
    Transport::Shm,
    Transport::Ipc,
    Transport::Uds,
];

/// The cases of `config`, in run order, without duplicates. Invalid combinations (a global
/// barrier on uds or zenoh) are left out.
pub fn cases(config: &RoundsConfig) -> Vec<Case> {
    let s = &config.sweep;
    let given = s.agents.is_some()
        || s.topologies.is_some()
        || s.payloads.is_some()
        || s.waits.is_some()
        || s.barriers.is_some();
    let blocks = if given {
        vec![given_block(s)]
    } else if config.quick {
        quick_blocks()
    } else {
        full_blocks()
    };
    let transports = s.transports.clone().unwrap_or(DEFAULT_TRANSPORTS.to_vec());
    let mut out: Vec<Case> = Vec::new();
    for block in blocks {
        for case in block.cases(&transports, config.step) {
            if !out.contains(&case) {
                out.push(case);
            }
        }
    }
    out
}

/// The payload of a case the sweep does not vary it in (10 × 10).
const BASE_PAYLOAD: PayloadShape = PayloadShape { rows: 10, cols: 10 };

/// A block of the sweep: every combination of its values is a case (on every transport).
/// Each block: (agents, topologies, payloads, waits, barriers).
struct Block(
    Vec<usize>,
    Vec<String>,
    Vec<PayloadShape>,
    Vec<WaitStrategy>,
    Vec<bool>,
);

impl Block {
    /// The block's cases on `transports` (a global barrier only where one exists; the
    /// primal step's payload is its team's n × n).
    fn cases(&self, transports: &[Transport], step: StepKind) -> Vec<Case> {
        let Block(agents, topologies, payloads, waits, barriers) = self;
        let mut out = Vec::new();
        for &n in agents {
            for topology in topologies {
                for &payload in payloads {
                    for &wait in waits {
                        for &global_barrier in barriers {
                            for &transport in transports {
                                if global_barrier && !transport.capabilities().global_barrier {
                                    continue;
                                }
                                let payload = if step == StepKind::Primal {
                                    p(n, n)
                                } else {
                                    payload
                                };
                                out.push(Case {
                                    agents: n,
                                    topology: topology.clone(),
                                    payload,
                                    transport,
                                    wait,
                                    global_barrier,
                                    step,
                                });
                            }
                        }
                    }
                }
            }
        }
        out
    }
}

fn p(rows: usize, cols: usize) -> PayloadShape {
    PayloadShape { rows, cols }
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|t| t.to_string()).collect()
}

/// The one block of the values the user gave (10 agents, complete graph, 10 × 10, auto wait,
/// no global barrier for the rest).
fn given_block(s: &SweepSpec) -> Block {
    Block(
        s.agents.clone().unwrap_or(vec![10]),
        s.topologies.clone().unwrap_or(vec!["complete".into()]),
        s.payloads.clone().unwrap_or(vec![BASE_PAYLOAD]),
        s.waits.clone().unwrap_or(vec![WaitStrategy::Auto]),
        s.barriers
            .as_ref()
            .map_or(vec![false], |b| b.iter().map(|b| b.is_global()).collect()),
    )
}

/// `--quick`: team sizes, payloads, waits and the global barrier, a few points each.
fn quick_blocks() -> Vec<Block> {
    vec![
        Block(
            vec![2, 10, 50],
            strings(&["complete", "ring"]),
            vec![BASE_PAYLOAD],
            vec![WaitStrategy::Auto],
            vec![false],
        ),
        Block(
            vec![10],
            strings(&["complete"]),
            vec![p(1, 1), p(50, 50), p(200, 200)],
            vec![WaitStrategy::Auto],
            vec![false],
        ),
        Block(
            vec![4],
            strings(&["complete"]),
            vec![BASE_PAYLOAD],
            vec![
                WaitStrategy::Block,
                WaitStrategy::SpinThenBlock,
                WaitStrategy::Spin,
            ],
            vec![false],
        ),
        Block(
            vec![10],
            strings(&["complete"]),
            vec![BASE_PAYLOAD],
            vec![WaitStrategy::Auto],
            vec![true],
        ),
    ]
}

/// The full sweep.
fn full_blocks() -> Vec<Block> {
    vec![
        Block(
            vec![2, 4, 10, 20, 50, 100],
            strings(&["complete", "chain", "ring", "random:0.2"]),
            vec![BASE_PAYLOAD],
            vec![WaitStrategy::Auto],
            vec![false],
        ),
        Block(
            vec![4, 10],
            strings(&["complete"]),
            vec![p(1, 1), p(10, 10), p(50, 50), p(100, 100), p(200, 200)],
            vec![WaitStrategy::Auto],
            vec![false],
        ),
        Block(
            vec![2, 10],
            strings(&["complete"]),
            vec![BASE_PAYLOAD],
            vec![
                WaitStrategy::Block,
                WaitStrategy::SpinThenBlock,
                WaitStrategy::Spin,
            ],
            vec![false],
        ),
        Block(
            vec![10, 50],
            strings(&["complete"]),
            vec![BASE_PAYLOAD],
            vec![WaitStrategy::Auto],
            vec![false, true],
        ),
    ]
}
