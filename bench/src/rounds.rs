//! The consensus-round latency harness (`admm-ta bench rounds`): teams of agents exchange
//! payloads for a fixed number of rounds after a warm-up, on every transport in **one run**
//! (so the ratios are comparable on a shared machine), sweeping team size, topology,
//! payload size, wait strategy and barrier kind.
//!
//! Per case it reports percentiles (p50/p90/p99/p99.9/max) over every agent's recorded
//! rounds of the round time and of the exchange overhead (round time minus compute), the
//! CPU time and context switches per agent-round (`getrusage(RUSAGE_THREAD)`), and start-up.
//! Outputs: a Markdown table on stdout, `rounds.json`, `rounds.csv` and SVG plots of latency
//! versus team size and versus payload size per transport.
//!
//! The default sweep varies one axis at a time around a baseline (10 agents, complete
//! graph, 10×10 payload, default wait, neighbour barrier); giving any axis on the command
//! line sweeps the cross product of the given lists instead (the baseline for the others).

use crate::plot::{Chart, PlotError, Scale, Series};
use admm_ta_agents::probe::ProbeStep;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::error_text::one_line;
use admm_ta_runtime::latency::Percentiles;
use admm_ta_runtime::options::error::ConfigError;
use admm_ta_runtime::options::run::RunOptions;
use admm_ta_runtime::options::{SolveOptions, StopRule};
use admm_ta_runtime::probe_run::{ProbeRun, run_probe};
use admm_ta_runtime::runner::RunError;
use admm_ta_runtime::solve::error::SolveError;
use admm_ta_runtime::solve::solve;
use admm_ta_runtime::transport::Transport;
use admm_ta_runtime::wait::WaitStrategy;
use admm_ta_topologies::TopologySpec;
use serde::Serialize;
use std::path::{Path, PathBuf};
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
impl clap::ValueEnum for StepKind {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

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
impl clap::ValueEnum for Barrier {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

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
    /// `global` or `neighbour`.
    pub fn barrier_name(&self) -> &'static str {
        Barrier::of(self.global_barrier).name()
    }

    /// The first six columns of the Markdown tables: agents, graph, payload, transport,
    /// wait, barrier.
    pub fn columns(&self) -> String {
        format!(
            "| {} | {} | {} | {} | {} | {} |",
            self.agents,
            self.topology,
            self.payload,
            self.transport.name(),
            self.wait.name(),
            self.barrier_name()
        )
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
    pub agent_program: Option<PathBuf>,
    pub round_timeout: Duration,
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
        }
    }
}

const ALL_TRANSPORTS: [Transport; 3] = [Transport::Threads, Transport::Ipc, Transport::Uds];

/// The cases of `config`, in run order, without duplicates. Invalid combinations (a global
/// barrier on uds or zenoh) are left out.
pub fn cases(config: &RoundsConfig) -> Vec<Case> {
    let s = &config.sweep;
    let base = Case {
        agents: 10,
        topology: "complete".into(),
        payload: PayloadShape { rows: 10, cols: 10 },
        transport: Transport::Ipc,
        wait: WaitStrategy::Auto,
        global_barrier: false,
        step: config.step,
    };
    let transports = s.transports.clone().unwrap_or(ALL_TRANSPORTS.to_vec());
    let given = s.agents.is_some()
        || s.topologies.is_some()
        || s.payloads.is_some()
        || s.waits.is_some()
        || s.barriers.is_some();
    // Each block: (agents, topologies, payloads, waits, barriers).
    type Block = (
        Vec<usize>,
        Vec<String>,
        Vec<PayloadShape>,
        Vec<WaitStrategy>,
        Vec<bool>,
    );
    let p = |r, c| PayloadShape { rows: r, cols: c };
    let strings = |v: &[&str]| v.iter().map(|t| t.to_string()).collect::<Vec<_>>();
    let blocks: Vec<Block> = if given {
        vec![(
            s.agents.clone().unwrap_or(vec![base.agents]),
            s.topologies.clone().unwrap_or(vec![base.topology.clone()]),
            s.payloads.clone().unwrap_or(vec![base.payload]),
            s.waits.clone().unwrap_or(vec![base.wait]),
            s.barriers
                .as_ref()
                .map_or(vec![false], |b| b.iter().map(|b| b.is_global()).collect()),
        )]
    } else if config.quick {
        vec![
            (
                vec![2, 10, 50],
                strings(&["complete", "ring"]),
                vec![base.payload],
                vec![base.wait],
                vec![false],
            ),
            (
                vec![10],
                strings(&["complete"]),
                vec![p(1, 1), p(50, 50), p(200, 200)],
                vec![base.wait],
                vec![false],
            ),
            (
                vec![4],
                strings(&["complete"]),
                vec![base.payload],
                vec![
                    WaitStrategy::Block,
                    WaitStrategy::SpinThenBlock,
                    WaitStrategy::Spin,
                ],
                vec![false],
            ),
            (
                vec![10],
                strings(&["complete"]),
                vec![base.payload],
                vec![base.wait],
                vec![true],
            ),
        ]
    } else {
        vec![
            (
                vec![2, 4, 10, 20, 50, 100],
                strings(&["complete", "chain", "ring", "random:0.2"]),
                vec![base.payload],
                vec![base.wait],
                vec![false],
            ),
            (
                vec![4, 10],
                strings(&["complete"]),
                vec![p(1, 1), p(10, 10), p(50, 50), p(100, 100), p(200, 200)],
                vec![base.wait],
                vec![false],
            ),
            (
                vec![2, 10],
                strings(&["complete"]),
                vec![base.payload],
                vec![
                    WaitStrategy::Block,
                    WaitStrategy::SpinThenBlock,
                    WaitStrategy::Spin,
                ],
                vec![false],
            ),
            (
                vec![10, 50],
                strings(&["complete"]),
                vec![base.payload],
                vec![base.wait],
                vec![false, true],
            ),
        ]
    };
    let mut out: Vec<Case> = Vec::new();
    for (agents, topologies, payloads, waits, barriers) in blocks {
        for &n in &agents {
            for topology in &topologies {
                for &payload in &payloads {
                    for &wait in &waits {
                        for &global_barrier in &barriers {
                            for &transport in &transports {
                                if global_barrier && !transport.capabilities().global_barrier {
                                    continue;
                                }
                                let payload = if config.step == StepKind::Primal {
                                    p(n, n)
                                } else {
                                    payload
                                };
                                let case = Case {
                                    agents: n,
                                    topology: topology.clone(),
                                    payload,
                                    transport,
                                    wait,
                                    global_barrier,
                                    step: config.step,
                                };
                                if !out.contains(&case) {
                                    out.push(case);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

/// Percentiles of one quantity, in microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tail {
    pub p50: f64,
    pub p90: f64,
    pub p99: f64,
    pub p999: f64,
    pub max: f64,
}

impl From<Percentiles> for Tail {
    fn from(p: Percentiles) -> Self {
        Self {
            p50: p.p50,
            p90: p.p90,
            p99: p.p99,
            p999: p.p999,
            max: p.max,
        }
    }
}

/// What one case measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    #[serde(flatten)]
    pub case: Case,
    pub payload_bytes: usize,
    /// Agent-rounds recorded (agents × rounds after the warm-up).
    pub recorded: u64,
    /// Round time, µs.
    pub round_us: Tail,
    /// Round time minus compute time, µs: what the exchange and the barriers cost.
    pub overhead_us: Tail,
    pub compute_p50_us: f64,
    pub wait_p50_us: f64,
    pub publish_p50_us: f64,
    pub barrier_p50_us: f64,
    /// CPU time per agent-round, µs (user + system).
    pub cpu_us_per_round: f64,
    pub voluntary_switches_per_round: f64,
    pub involuntary_switches_per_round: f64,
    pub startup_ms: Option<f64>,
    pub wall_ms: f64,
    /// Times the case was measured (`--repeat`); the numbers above are those of the
    /// repetition with the median round p50.
    pub repeats: usize,
    /// Lowest and highest round p50 over the repetitions, µs: the run-to-run spread.
    pub round_p50_range_us: (f64, f64),
}

/// A case that could not be measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseFailure {
    #[serde(flatten)]
    pub case: Case,
    pub error: String,
}

/// Everything a benchmark run produced.
#[derive(Debug, Clone, Serialize)]
pub struct RoundsReport {
    pub cores: usize,
    pub rounds: u64,
    pub warmup: u64,
    pub step: StepKind,
    pub results: Vec<CaseResult>,
    pub failures: Vec<CaseFailure>,
}

/// Why a case could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum MeasureError {
    #[error("{0}")]
    Case(String),
    #[error(transparent)]
    Options(#[from] ConfigError),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// Measures one case.
pub fn measure(case: &Case, config: &RoundsConfig) -> Result<CaseResult, MeasureError> {
    let bad = |e: &dyn std::fmt::Display| MeasureError::Case(e.to_string());
    let graph = case
        .topology
        .parse::<TopologySpec>()
        .map_err(|e| bad(&e))?
        .build(case.agents, 0)
        .map_err(|e| bad(&e))?;
    let total_rounds = config.rounds + config.warmup;
    let options = RunOptions::builder()
        .transport(case.transport)
        .wait(case.wait)
        .global_barrier(case.global_barrier)
        .warmup_rounds(config.warmup)
        .round_timeout(config.round_timeout)
        .agent_program(config.agent_program.clone())
        .build()?;
    let (latency, usage, startup, wall) = match case.step {
        StepKind::Touch | StepKind::Average => {
            let step = if case.step == StepKind::Touch {
                ProbeStep::Touch
            } else {
                ProbeStep::Average
            };
            let run = ProbeRun {
                rounds: total_rounds,
                ..ProbeRun::new(case.payload.values(), step, options)
            };
            let r = run_probe(&graph, &run)?;
            (
                r.latency,
                r.usage,
                r.startup.map(|d| d.as_secs_f64() * 1e3),
                r.wall,
            )
        }
        StepKind::Primal => {
            let n = case.agents;
            let problem = TaskAssignmentProblem::new(
                CostMatrix::uniform(n, n, 1).map_err(|e| bad(&e))?,
                CaseChoice::Auto,
            )
            .map_err(|e| bad(&e))?;
            let started = std::time::Instant::now();
            let options = SolveOptions::builder()
                .transport(case.transport)
                .stop(StopRule::MaxIters)
                .max_iters(total_rounds as usize)
                .warmup_rounds(config.warmup)
                .wait(case.wait)
                .global_barrier(case.global_barrier)
                .round_timeout(config.round_timeout)
                .agent_program(config.agent_program.clone())
                .fault_injection(false)
                .build()?;
            let report = solve(&problem, &graph, &options)?;
            (
                report.round_latency_us.unwrap_or_default(),
                report.agent_usage.unwrap_or_default(),
                report.startup_ms,
                started.elapsed(),
            )
        }
    };
    let recorded = latency.round.count.max(1);
    let per_round = |v: u64| v as f64 / recorded as f64;
    Ok(CaseResult {
        case: case.clone(),
        payload_bytes: case.payload.values() * 8,
        recorded: latency.round.count,
        round_us: latency.round.into(),
        overhead_us: latency.overhead.into(),
        compute_p50_us: latency.compute.p50,
        wait_p50_us: latency.wait.p50,
        publish_p50_us: latency.publish.p50,
        barrier_p50_us: latency.barrier.p50,
        cpu_us_per_round: per_round(usage.cpu_ns) / 1e3,
        voluntary_switches_per_round: per_round(usage.voluntary_switches),
        involuntary_switches_per_round: per_round(usage.involuntary_switches),
        startup_ms: startup,
        wall_ms: wall.as_secs_f64() * 1e3,
        repeats: 1,
        round_p50_range_us: (latency.round.p50, latency.round.p50),
    })
}

/// The repetition with the median round p50, carrying the spread of all of them.
fn median_of(mut repeats: Vec<CaseResult>) -> CaseResult {
    repeats.sort_by(|a, b| a.round_us.p50.total_cmp(&b.round_us.p50));
    let range = (
        repeats.first().map_or(0.0, |r| r.round_us.p50),
        repeats.last().map_or(0.0, |r| r.round_us.p50),
    );
    let count = repeats.len();
    let mut median = repeats.swap_remove(count / 2);
    median.repeats = count;
    median.round_p50_range_us = range;
    median
}

/// Runs every case of `config`; `progress` sees each result (or failure) as it comes. A
/// failing case is recorded and the sweep goes on.
pub fn run(
    config: &RoundsConfig,
    progress: &mut dyn FnMut(&Case, Result<&CaseResult, &str>),
) -> RoundsReport {
    let mut report = RoundsReport {
        cores: std::thread::available_parallelism().map_or(1, |c| c.get()),
        rounds: config.rounds,
        warmup: config.warmup,
        step: config.step,
        results: Vec::new(),
        failures: Vec::new(),
    };
    let cases = cases(config);
    // An unrecorded first run warms the binary, the page cache and the CPU clocks, so that
    // the first measured case is not an outlier.
    if let Some(first) = cases.first() {
        let warm = RoundsConfig {
            rounds: config.rounds.min(100),
            warmup: 0,
            ..config.clone()
        };
        let _ = measure(first, &warm);
    }
    // Configurations that differ only by transport are measured together, repetition by
    // repetition, so that every transport sees the same state of the machine.
    let mut start = 0;
    while start < cases.len() {
        let same = |c: &Case| {
            Case {
                transport: cases[start].transport,
                ..c.clone()
            } == cases[start]
        };
        let end = start + cases[start..].iter().take_while(|c| same(c)).count();
        let group = &cases[start..end];
        let mut measured: Vec<Result<Vec<CaseResult>, String>> =
            group.iter().map(|_| Ok(Vec::new())).collect();
        for _ in 0..config.repeat.max(1) {
            for (case, slot) in group.iter().zip(measured.iter_mut()) {
                if let Ok(results) = slot {
                    match measure(case, config) {
                        Ok(r) => results.push(r),
                        Err(e) => *slot = Err(one_line(&e)),
                    }
                }
            }
        }
        for (case, outcome) in group.iter().zip(measured) {
            match outcome {
                Ok(results) => {
                    let result = median_of(results);
                    progress(case, Ok(&result));
                    report.results.push(result);
                }
                Err(error) => {
                    progress(case, Err(&error));
                    report.failures.push(CaseFailure {
                        case: case.clone(),
                        error,
                    });
                }
            }
        }
        start = end;
    }
    report
}

/// Header of [`render_row`]'s Markdown table.
pub const TABLE_HEADER: &str = "| agents | graph | payload | transport | wait | barrier | round p50 | p90 | p99 | p99.9 | max | overhead p50 | overhead p99 | compute p50 | CPU µs/round | csw/round | start-up ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";

/// One Markdown table row (latencies in µs).
pub fn render_row(r: &CaseResult) -> String {
    let c = &r.case;
    format!(
        "{} {} | {:.1} | {:.1} | {:.1} | {:.0} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {} |",
        c.columns(),
        if r.repeats > 1 {
            format!(
                "{:.1} ({:.1}–{:.1})",
                r.round_us.p50, r.round_p50_range_us.0, r.round_p50_range_us.1
            )
        } else {
            format!("{:.1}", r.round_us.p50)
        },
        r.round_us.p90,
        r.round_us.p99,
        r.round_us.p999,
        r.round_us.max,
        r.overhead_us.p50,
        r.overhead_us.p99,
        r.compute_p50_us,
        r.cpu_us_per_round,
        r.voluntary_switches_per_round + r.involuntary_switches_per_round,
        r.startup_ms.map_or("-".into(), |v| format!("{v:.0}")),
    )
}

/// Ratios of round p50 between transports on otherwise equal cases (`ipc/threads`,
/// `uds/ipc`, `zenoh/ipc`), as Markdown.
pub fn render_ratios(report: &RoundsReport) -> String {
    let mut lines = vec![
        "| agents | graph | payload | wait | barrier | ipc / threads p50 | uds / ipc p50 | uds / ipc p99 | zenoh / ipc p50 | zenoh / ipc p99 |".to_string(),
        "|---|---|---|---|---|---|---|---|---|---|".to_string(),
    ];
    let find = |case: &Case, t: Transport| {
        report.results.iter().find(|r| {
            let mut other = case.clone();
            other.transport = t;
            r.case == other
        })
    };
    for r in report
        .results
        .iter()
        .filter(|r| r.case.transport == Transport::Ipc)
    {
        let c = &r.case;
        let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) if b > 0.0 => format!("{:.2}×", a / b),
            _ => "-".into(),
        };
        let threads = find(c, Transport::Threads);
        let uds = find(c, Transport::Uds);
        let zenoh = find(c, Transport::Zenoh);
        lines.push(format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.agents,
            c.topology,
            c.payload,
            c.wait.name(),
            c.barrier_name(),
            ratio(Some(r.round_us.p50), threads.map(|t| t.round_us.p50)),
            ratio(uds.map(|u| u.round_us.p50), Some(r.round_us.p50)),
            ratio(uds.map(|u| u.round_us.p99), Some(r.round_us.p99)),
            ratio(zenoh.map(|z| z.round_us.p50), Some(r.round_us.p50)),
            ratio(zenoh.map(|z| z.round_us.p99), Some(r.round_us.p99)),
        ));
    }
    lines.join("\n")
}

/// `rounds.csv`: one line per measured case.
pub fn to_csv(report: &RoundsReport) -> String {
    let mut out = String::from(
        "agents,topology,payload,payload_bytes,transport,wait,barrier,step,recorded,round_p50_us,round_p90_us,round_p99_us,round_p999_us,round_max_us,overhead_p50_us,overhead_p90_us,overhead_p99_us,overhead_p999_us,overhead_max_us,compute_p50_us,wait_p50_us,publish_p50_us,barrier_p50_us,cpu_us_per_round,voluntary_switches_per_round,involuntary_switches_per_round,startup_ms,wall_ms,repeats,round_p50_min_us,round_p50_max_us\n",
    );
    for r in &report.results {
        let c = &r.case;
        let t = |t: &Tail| format!("{},{},{},{},{}", t.p50, t.p90, t.p99, t.p999, t.max);
        out += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            c.agents,
            c.topology,
            c.payload,
            r.payload_bytes,
            c.transport.name(),
            c.wait.name(),
            c.barrier_name(),
            c.step.name(),
            r.recorded,
            t(&r.round_us),
            t(&r.overhead_us),
            r.compute_p50_us,
            r.wait_p50_us,
            r.publish_p50_us,
            r.barrier_p50_us,
            r.cpu_us_per_round,
            r.voluntary_switches_per_round,
            r.involuntary_switches_per_round,
            r.startup_ms.map_or(String::new(), |v| v.to_string())
                + &format!(
                    ",{},{},{},{}",
                    r.wall_ms, r.repeats, r.round_p50_range_us.0, r.round_p50_range_us.1
                ),
        );
    }
    out
}

/// Writes `rounds.json`, `rounds.csv` and the plots into `dir`; returns the files written.
pub fn write_outputs(report: &RoundsReport, dir: &Path) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut written = Vec::new();
    let mut write = |name: &str, text: String| -> Result<(), String> {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        written.push(path);
        Ok(())
    };
    write(
        "rounds.json",
        serde_json::to_string_pretty(report).map_err(|e| e.to_string())?,
    )?;
    write("rounds.csv", to_csv(report))?;
    for (name, chart) in charts(report) {
        let path = dir.join(name);
        match chart.write(&path) {
            Ok(()) => written.push(path),
            Err(PlotError::Empty(_)) => {}
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(written)
}

/// The plots: round latency (p50 solid, p99 dashed) per transport against team size (one
/// chart per topology) and against payload size (one chart per team size).
pub fn charts(report: &RoundsReport) -> Vec<(String, Chart)> {
    let base_wait = WaitStrategy::Auto;
    let transports: Vec<Transport> = ALL_TRANSPORTS
        .into_iter()
        .filter(|t| report.results.iter().any(|r| r.case.transport == *t))
        .collect();
    let mut charts = Vec::new();
    let mut topologies: Vec<String> = Vec::new();
    for r in &report.results {
        if !topologies.contains(&r.case.topology) {
            topologies.push(r.case.topology.clone());
        }
    }
    let base_payload = PayloadShape { rows: 10, cols: 10 };
    for topology in &topologies {
        let chart = Chart::new(
            format!(
                "round latency vs agents ({topology} graph, {} payload, {} step)",
                if report.step == StepKind::Primal {
                    "n×n".into()
                } else {
                    base_payload.to_string()
                },
                report.step.name()
            ),
            "agents",
            "round time (µs), p50 solid, p99 dashed",
        )
        .y_scale(Scale::Log)
        .colour_by_prefix();
        let (chart, points_any) = with_transport_series(chart, report, &transports, 2, |c| {
            (&c.topology == topology
                && c.wait == base_wait
                && !c.global_barrier
                && (report.step == StepKind::Primal || c.payload == base_payload))
                .then_some(c.agents as f64)
        });
        if points_any {
            let slug: String = topology
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
                .collect();
            charts.push((format!("rounds-agents-{slug}.svg"), chart));
        }
    }
    let mut sizes: Vec<usize> = report.results.iter().map(|r| r.case.agents).collect();
    sizes.sort_unstable();
    sizes.dedup();
    for n in sizes {
        let chart = Chart::new(
            format!(
                "round latency vs payload ({n} agents, complete graph, {} step)",
                report.step.name()
            ),
            "payload (bytes)",
            "round time (µs), p50 solid, p99 dashed",
        )
        .x_scale(Scale::Log)
        .y_scale(Scale::Log)
        .colour_by_prefix();
        let (chart, points_any) = with_transport_series(chart, report, &transports, 3, |c| {
            (c.agents == n && c.topology == "complete" && c.wait == base_wait && !c.global_barrier)
                .then_some((c.payload.values() * 8) as f64)
        });
        if points_any {
            charts.push((format!("rounds-payload-{n}-agents.svg"), chart));
        }
    }
    charts
}

/// Adds a p50 and a dashed p99 line per transport to `chart`, over the cases that `x` places
/// (returns their x value, `None` to leave a case out); transports with fewer than
/// `min_points` cases are skipped. Also says whether any line was added.
fn with_transport_series(
    mut chart: Chart,
    report: &RoundsReport,
    transports: &[Transport],
    min_points: usize,
    x: impl Fn(&Case) -> Option<f64>,
) -> (Chart, bool) {
    let mut any = false;
    for &t in transports {
        let mut rows: Vec<(f64, &CaseResult)> = report
            .results
            .iter()
            .filter(|r| r.case.transport == t)
            .filter_map(|r| x(&r.case).map(|x| (x, r)))
            .collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        if rows.len() < min_points {
            continue;
        }
        any = true;
        let pts = |f: fn(&CaseResult) -> f64| rows.iter().map(|(x, r)| (*x, f(r))).collect();
        chart = chart
            .series(Series::new(
                format!("{} p50", t.name()),
                pts(|r| r.round_us.p50),
            ))
            .series(Series::new(format!("{} p99", t.name()), pts(|r| r.round_us.p99)).dashed());
    }
    (chart, any)
}
