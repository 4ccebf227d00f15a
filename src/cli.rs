//! Command-line interface: argument parsing and dispatch to the crates.

use crate::output;
use admm_ta_agents::method::Method;
use admm_ta_agents::primal::ProjectionPath;
use admm_ta_agents::problem::{AssignmentCase, CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_agents::ties::Perturbation;
use admm_ta_runtime::options::{OnFailure, SolveOptions, StopRule};
use admm_ta_runtime::solve;
use admm_ta_runtime::transport::Transport;
use admm_ta_runtime::wait::WaitStrategy;
use admm_ta_topologies::{TopologySpec, file as topology_file};
use anyhow::{Context, Result, bail};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "admm-ta",
    version,
    about = "Consensus ADMM task assignment for multi-robot teams"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Solve a task assignment problem with a consensus method.
    Solve(SolveArgs),
    /// Solve a built-in default problem (20 robots, 20 tasks, complete graph) end to end.
    Demo {
        /// Print one JSON object instead of the human summary.
        #[arg(long)]
        json: bool,
        /// sim | threads | ipc (20 agent processes).
        #[arg(long, default_value = "ipc", value_parser = transport_parser())]
        transport: Transport,
    },
    /// Run one agent: of a team started independently (`--team FILE --id I`: any order, any
    /// supervisor; see the README), or of a launcher's run (`--run --index --scenario`, started
    /// by `solve --transport ipc`).
    Agent {
        /// The team file (TOML) naming the run, the robots, the topology and the costs.
        #[arg(long, conflicts_with_all = ["run", "index", "scenario"], requires = "id")]
        team: Option<PathBuf>,
        /// This agent's robot number in the team (0-based).
        #[arg(long)]
        id: Option<usize>,
        /// The run's id (it must match the scenario's).
        #[arg(long, requires_all = ["index", "scenario"])]
        run: Option<String>,
        /// This agent's robot index.
        #[arg(long)]
        index: Option<usize>,
        /// The scenario file the launcher wrote.
        #[arg(long)]
        scenario: Option<PathBuf>,
    },
    /// Assemble the assignment of an independently started team from its agents' results.
    Collect {
        /// The team file the agents were started with.
        #[arg(long)]
        team: PathBuf,
        /// Compare with the centralized optimum.
        #[arg(long)]
        check: bool,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Run one machine of a team across several machines (`transport = "zenoh"` or `"mixed"`
    /// in the team file): its Zenoh router, linked to the other hosts' routers, and in a
    /// mixed team its bridge. Start it next to the host's agents; it returns once every agent
    /// of the team has come and gone. Needs a build with `--features zenoh`.
    Host {
        /// The team file (the same on every machine).
        #[arg(long)]
        team: PathBuf,
        /// This machine's name in the team file's [[hosts]].
        #[arg(long)]
        name: String,
    },
    /// Benchmarks: consensus-round latency per transport.
    Bench {
        #[command(subcommand)]
        bench: Bench,
    },
    /// Reproduce an experiment of the paper.
    Experiment {
        #[command(subcommand)]
        experiment: Experiment,
    },
    /// Print a generated topology in the topology file format (TOML).
    Topology {
        /// complete | chain | ring | star | grid | random:P | geometric:R
        #[arg(long, default_value = "complete")]
        kind: String,
        #[arg(long)]
        robots: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
}

#[derive(Subcommand, Debug)]
pub(crate) enum Bench {
    /// Round latency of teams exchanging payloads on threads, ipc (iceoryx2 zero-copy) and
    /// uds (Unix-domain sockets, copying) in one run: p50/p90/p99/p99.9/max of the round
    /// time and of the exchange overhead (round − compute), CPU time and context switches
    /// per agent-round. Without axis options it sweeps one axis at a time around 10 agents,
    /// complete graph, 10×10 payload; with any axis option, the cross product of the lists
    /// given. Writes rounds.json, rounds.csv and SVG plots into --out.
    Rounds {
        /// A small sweep that finishes within a minute on 2 cores.
        #[arg(long)]
        quick: bool,
        /// Team sizes, comma-separated.
        #[arg(long, value_delimiter = ',')]
        agents: Option<Vec<usize>>,
        /// Topologies, comma-separated (complete, chain, ring, star, grid, random:P, geometric:R).
        #[arg(long, value_delimiter = ',')]
        topologies: Option<Vec<String>>,
        /// Payload shapes ROWSxCOLS of f64, comma-separated (e.g. 1x1,10x10,200x200).
        #[arg(long, value_delimiter = ',')]
        payloads: Option<Vec<String>>,
        /// Transports, comma-separated: threads, ipc, uds, zenoh (default: threads, ipc, uds;
        /// zenoh needs a build with `--features zenoh`).
        #[arg(long, value_delimiter = ',', value_parser = transport_parser())]
        transports: Option<Vec<Transport>>,
        /// Wait strategies, comma-separated: auto, block, spin-then-block, spin.
        #[arg(long, value_enum, value_delimiter = ',')]
        waits: Option<Vec<WaitArg>>,
        /// Barrier kinds, comma-separated: neighbour, global (uds and zenoh have no global
        /// barrier).
        #[arg(long, value_enum, value_delimiter = ',')]
        barriers: Option<Vec<BarrierArg>>,
        /// What agents compute per round: touch (one value per neighbour: the exchange
        /// alone), average (every value of every neighbour) or primal (the ADMM step on
        /// uniform n×n costs; the payload is then n×n).
        #[arg(long, value_enum, default_value = "touch")]
        step: StepArg,
        /// Recorded rounds per case (default 1000, --quick 400).
        #[arg(long)]
        rounds: Option<u64>,
        /// Rounds before recording starts (default 100, --quick 50).
        #[arg(long)]
        warmup: Option<u64>,
        /// Measure every case this many times (the transports of a configuration in turn)
        /// and report the repetition with the median p50, with the p50 range.
        #[arg(long, default_value_t = 1)]
        repeat: usize,
        /// Directory for rounds.json, rounds.csv and the plots (created if missing).
        #[arg(long, default_value = "bench-results")]
        out: PathBuf,
        /// Print the JSON report on stdout instead of the tables.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum BarrierArg {
    Neighbour,
    Global,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum StepArg {
    Touch,
    Average,
    Primal,
}

/// Options shared by the figure experiments.
#[derive(Args, Debug)]
pub(crate) struct FigureArgs {
    /// Seeds (cost matrices and random graphs) per point.
    #[arg(long, default_value_t = 3)]
    pub(crate) trials: u64,
    /// Directory for the JSON and SVG files (created if missing).
    #[arg(long, default_value = "experiment-results")]
    pub(crate) out: PathBuf,
    /// Run the ADMM methods with --adaptive-rho.
    #[arg(long)]
    pub(crate) adaptive_rho: bool,
    #[arg(long, default_value_t = 5000)]
    pub(crate) max_iters: usize,
    /// Print the JSON instead of the table.
    #[arg(long)]
    pub(crate) json: bool,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Experiment {
    /// Fig. 1 (left): the team's relaxed cost per iteration against the Hungarian optimum,
    /// 50×50 complete graph, primal / dual / inexact dual (paper: primal within ~50).
    #[command(name = "fig1-convergence")]
    Fig1Convergence {
        #[command(flatten)]
        figure: FigureArgs,
    },
    /// Fig. 1 (right): primal ADMM-TA on 50 robots × 30 tasks over complete, random (p = 0.1)
    /// and chain graphs (paper: chain slowest, ~200 iterations).
    #[command(name = "fig1-topologies")]
    Fig1Topologies {
        #[command(flatten)]
        figure: FigureArgs,
    },
    /// Fig. 2: iterations vs team size for ADMM-TA (paper's 0.1% criterion and the
    /// decentralized stop), CBAA, market and distributed Hungarian on the complete graph, and
    /// ADMM-TA vs distributed Hungarian on random graphs.
    #[command(name = "fig2-scaling")]
    Fig2Scaling {
        #[command(flatten)]
        figure: FigureArgs,
        /// Team sizes (robots = tasks), comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = [10usize, 20, 30, 40, 50, 60, 70, 80, 90, 100])]
        sizes: Vec<usize>,
        /// Largest team run to the decentralized stop with ADMM (slow beyond ~50 on 2 cores).
        #[arg(long, default_value_t = 50)]
        decentralized_up_to: usize,
    },
    /// Beyond the paper: wall time to the assignment and round latency with one process per
    /// robot (iceoryx2), per method and team size, complete graph.
    #[command(name = "ipc-scaling")]
    IpcScaling {
        #[command(flatten)]
        figure: FigureArgs,
        /// Team sizes (robots = tasks), comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = [10usize, 20, 50])]
        sizes: Vec<usize>,
    },
    /// Every method side by side (rounds to its own stop, optimality, bytes per agent, wall
    /// time) on uniform square problems, per team size and transport; prints a Markdown table.
    Compare {
        /// Team sizes (robots = tasks), comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = [10usize, 20, 50])]
        robots: Vec<usize>,
        /// Seeds per size (problems and random graphs).
        #[arg(long, default_value_t = 3)]
        seeds: u64,
        /// Methods, comma-separated (default: all).
        #[arg(long, value_enum, value_delimiter = ',')]
        methods: Vec<MethodArg>,
        /// Transports, comma-separated.
        #[arg(long, value_delimiter = ',', default_values = ["sim", "ipc"], value_parser = transport_parser())]
        transports: Vec<Transport>,
        /// complete | chain | ring | star | grid | random:P | geometric:R
        #[arg(long, default_value = "complete")]
        topology: String,
        /// Run the ADMM methods with --adaptive-rho.
        #[arg(long)]
        adaptive_rho: bool,
        #[arg(long, default_value_t = 5000)]
        max_iters: usize,
        /// Directory for compare.json (created if missing).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The persistent-surveillance case study (paper Section 4.4, Fig. 3): one team alive for
    /// every episode, each robot computing its own costs from its battery and position, each
    /// episode warm-started from the last; compared per episode with the Hungarian optimum
    /// and with a cold start. Writes surveillance.json and SVG plots into --out.
    Surveillance {
        #[arg(long, default_value_t = 1000)]
        episodes: usize,
        /// Scenario TOML file (default: the built-in one, `admm-ta-agents::surveillance`).
        #[arg(long)]
        scenario: Option<PathBuf>,
        /// ipc (one process per robot for the whole run), threads or uds.
        #[arg(long, default_value = "ipc", value_parser = transport_parser())]
        transport: Transport,
        /// Start every episode from zero iterates instead of the previous episode's.
        #[arg(long)]
        cold_start: bool,
        /// Round limit of each episode.
        #[arg(long, default_value_t = 5000)]
        max_iters: u64,
        /// Directory for surveillance.json and the plots (created if missing).
        #[arg(long, default_value = "experiment-results")]
        out: PathBuf,
        /// Print one JSON object (episodes, optimal_episodes, battery_violations,
        /// mean_iterations_warm, mean_iterations_cold, …) instead of the summary.
        #[arg(long)]
        json: bool,
    },
    /// Table 1: iterations of primal / dual / inexact dual at 20×20 on the complete graph
    /// (paper: 28 / 159 / 387), for uniform costs in [0,1) and shifted to [1,2).
    Table1 {
        #[arg(long, default_value_t = 50)]
        trials: u64,
        /// Directory for table1.json (created if missing).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Run every method with the --adaptive-rho schedule.
        #[arg(long)]
        adaptive_rho: bool,
        /// Multiply every method's default ρ by this factor (for ρ studies).
        #[arg(long, default_value_t = 1.0)]
        rho_scale: f64,
        /// Round limit of every run.
        #[arg(long, default_value_t = 3000)]
        max_iters: usize,
        /// Print the JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Args, Debug)]
struct SolveArgs {
    /// Cost CSV: one row per robot, one column per task, no header.
    #[arg(long, conflicts_with_all = ["robots", "tasks"])]
    costs: Option<PathBuf>,
    /// Number of robots for random uniform [0,1) costs.
    #[arg(long, requires = "tasks")]
    robots: Option<usize>,
    /// Number of tasks for random uniform [0,1) costs.
    #[arg(long, requires = "robots")]
    tasks: Option<usize>,
    /// Seed of the random costs, random topologies and tie-breaking.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Coverage case: auto (from the shape), 1 (n = m, one robot per task) or 2 (n ≥ m, at
    /// least one robot per task).
    #[arg(long, default_value = "auto")]
    case: CaseArg,
    /// complete | chain | ring | star | grid | random:P | geometric:R | FILE.toml
    #[arg(long, default_value = "complete")]
    topology: String,
    /// primal (Algorithm 1, exchanges m×n matrices), dual (Algorithm 2, exchanges n+m
    /// multipliers), inexact-dual (proximal-gradient x-update, no inner solve), cbaa (the
    /// consensus-based auction baseline: fast, conflict-free, not optimal), market (Liu &
    /// Shell's price-escalation market replicated over the graph: optimal, 2·diameter
    /// rounds per price raise, sends demand bits only), dist-hungarian
    /// (robots flood their cost rows and solve locally: optimal after a graph diameter) or
    /// hungarian (the centralized optimum, one round, sim only).
    #[arg(long, value_enum, default_value = "primal")]
    method: MethodArg,
    /// sim (one thread, lockstep), threads (a thread per agent), ipc (a process per agent,
    /// iceoryx2 zero-copy), uds (a process per agent, payloads copied through Unix-domain
    /// sockets: a baseline) or zenoh (a process per agent, Zenoh through a router on
    /// loopback: the multi-host transport; needs `--features zenoh`).
    #[arg(long, default_value = "sim", value_parser = transport_parser())]
    transport: Transport,
    /// ADMM penalty ρ: auto (scale-free rule from the cost spread and the graph's mean
    /// degree d̄: primal 0.5·spread·√((n−1)/d̄)/(2·d̄·n), dual 5/(spread·d̄), inexact dual
    /// 10/(spread·d̄)) or a positive number.
    #[arg(long, default_value = "auto", allow_negative_numbers = true)]
    rho: String,
    /// Vary ρ by the method's schedule, computed by every agent from the round number
    /// (primal: 3ρ shrinking 2% per round to 0.6ρ; dual methods: ρ, then growing 1% per
    /// round to 10ρ). Cut the rounds to the certified stop by 10–69% wherever the runs certified.
    #[arg(long)]
    adaptive_rho: bool,
    /// Inexact dual: g of the proximal weight γ = g·(m+1)/(2·|N(i)|·ρ) (default 0.5).
    #[arg(long, allow_negative_numbers = true)]
    gamma_factor: Option<f64>,
    #[arg(long, default_value_t = 5000)]
    max_iters: usize,
    /// local: every robot checks its own optimality certificate and agreement with its
    /// neighbours, and a header protocol stops all robots at the same round (any transport);
    /// certified: the same certificate checked centrally (sim, primal); agreement: all robots
    /// agree on one near-integral assignment for --stop-rounds rounds (sim, primal); oracle:
    /// the paper's criterion, the first round whose relaxed objective is within 0.1% of the
    /// centralized optimum (sim, experiments only); max-iters: always run --max-iters rounds.
    #[arg(long, value_enum, default_value = "local")]
    stop: StopArg,
    #[arg(long, default_value_t = 10)]
    stop_rounds: usize,
    /// x-update solver: fast (Newton projection) or qp (clarabel; slow cross-check).
    #[arg(long, value_enum, default_value = "fast")]
    projection: ProjectionArg,
    /// Tie-breaking cost perturbation: auto (only for lattice costs such as integers), off,
    /// or a number ε.
    #[arg(long, default_value = "auto")]
    perturb: String,
    /// Compare with the centralized optimum (adds optimal_cost and gap).
    #[arg(long)]
    check: bool,
    /// With --check on the sim transport: every round's relaxed and rounded cost in the
    /// JSON report (`check.trace`), for convergence plots.
    #[arg(long, requires = "check")]
    trace: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Add a global barrier (all agents reach round k) to every round: lockstep, for
    /// latency benchmarks (threads and ipc).
    #[arg(long)]
    global_barrier: bool,
    /// Seconds an agent waits for a neighbour's message or the barrier before failing.
    #[arg(long, default_value_t = 30.0)]
    round_timeout: f64,
    /// Seconds all agent processes have to start and connect (ipc).
    #[arg(long, default_value_t = 60.0)]
    startup_timeout: f64,
    /// When an agent process dies or misbehaves (ipc): abort (stop every agent, exit ≠ 0 with
    /// one line naming it) or continue (the survivors drop that robot and re-solve without
    /// it, if the graph stays connected and robots still cover the tasks; the report then
    /// names the failed robot and maps the assignment to the survivors' original numbers).
    #[arg(long, value_enum, default_value = "abort")]
    on_failure: OnFailureArg,
    /// How agents wait for their neighbours (threads, ipc, uds): auto (spin 20 µs then
    /// sleep when every agent has a core, else sleep at once), block, spin-then-block, or
    /// spin (poll and yield, never sleep).
    #[arg(long, value_enum, default_value = "auto")]
    wait: WaitArg,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum OnFailureArg {
    Abort,
    Continue,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum CaseArg {
    Auto,
    #[value(name = "1")]
    One,
    #[value(name = "2")]
    Two,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum MethodArg {
    Primal,
    Dual,
    InexactDual,
    Cbaa,
    Market,
    DistHungarian,
    Hungarian,
}

impl MethodArg {
    pub(crate) fn method(self) -> Method {
        match self {
            Self::Primal => Method::Primal,
            Self::Dual => Method::Dual,
            Self::InexactDual => Method::InexactDual,
            Self::Cbaa => Method::Cbaa,
            Self::Market => Method::Market,
            Self::DistHungarian => Method::DistHungarian,
            Self::Hungarian => Method::Hungarian,
        }
    }
}

/// Parses a transport by its name ([`Transport::ALL`]), listing the names in errors and help.
fn transport_parser() -> impl TypedValueParser<Value = Transport> {
    PossibleValuesParser::new(Transport::ALL.map(Transport::name))
        .map(|name| name.parse::<Transport>().expect("one of the listed names"))
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum WaitArg {
    Auto,
    Block,
    SpinThenBlock,
    Spin,
}

impl WaitArg {
    pub(crate) fn strategy(self) -> WaitStrategy {
        match self {
            Self::Auto => WaitStrategy::Auto,
            Self::Block => WaitStrategy::Block,
            Self::SpinThenBlock => WaitStrategy::SpinThenBlock,
            Self::Spin => WaitStrategy::Spin,
        }
    }
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum StopArg {
    Local,
    Agreement,
    Certified,
    MaxIters,
    Oracle,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum ProjectionArg {
    Fast,
    Qp,
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Solve(args) => run_solve(args),
        Command::Demo { json, transport } => run_demo(json, transport),
        Command::Agent {
            team,
            id,
            run,
            index,
            scenario,
        } => {
            let (index, result) = match (team, id, run, index, scenario) {
                (Some(team), Some(id), ..) => {
                    let report = admm_ta_runtime::process::member::run_member(&team, id);
                    if let Ok(r) = &report {
                        println!(
                            "{}",
                            serde_json::json!({
                                "id": id,
                                "task": r.outcome.task,
                                "rounds": r.outcome.rounds,
                                "converged": r.outcome.converged,
                            })
                        );
                    }
                    (id, report.map(|_| ()))
                }
                (None, None, Some(run), Some(index), Some(scenario)) => (
                    index,
                    admm_ta_runtime::process::agent::run(&run, index, &scenario),
                ),
                _ => bail!("agent needs --team FILE --id I (or --run, --index and --scenario)"),
            };
            result.map_err(|e| {
                // Exchange errors already start with "agent N:".
                if e.starts_with(&format!("agent {index}:")) {
                    anyhow::anyhow!(e)
                } else {
                    anyhow::anyhow!("agent {index}: {e}")
                }
            })
        }
        Command::Host { team, name } => run_host(&team, &name),
        Command::Collect { team, check, json } => {
            let result = admm_ta_runtime::process::member::collect(&team, check)
                .map_err(anyhow::Error::msg)?;
            if json {
                println!("{}", serde_json::to_string(&result)?);
            } else {
                println!(
                    "team {}: assignment {:?}, cost {:.6}, {} rounds, {}{}",
                    result.run,
                    result.assignment,
                    result.cost,
                    result.iterations,
                    if result.converged {
                        "certified"
                    } else {
                        "round limit reached (not certified)"
                    },
                    match (result.optimal, result.optimal_cost) {
                        (Some(true), _) => ", optimal".to_string(),
                        (Some(false), Some(o)) => format!(", NOT optimal (optimum {o:.6})"),
                        _ => String::new(),
                    }
                );
                let round = result.round_latency_us.round;
                println!(
                    "round latency (µs, all agents): p50 {:.1}, p90 {:.1}, p99 {:.1}, max {:.1}",
                    round.p50, round.p90, round.p99, round.max
                );
            }
            if result.optimal == Some(false) {
                bail!("the team's assignment is not optimal");
            }
            Ok(())
        }
        Command::Experiment { experiment } => crate::experiments::run_experiment(experiment),
        Command::Bench { bench } => crate::bench_cmd::run_bench(bench),
        Command::Topology { kind, robots, seed } => {
            let spec: TopologySpec = kind.parse()?;
            print!("{}", topology_file::to_toml(&spec.build(robots, seed)?));
            Ok(())
        }
    }
}

fn run_solve(args: SolveArgs) -> Result<()> {
    let costs = match (&args.costs, args.robots, args.tasks) {
        (Some(path), _, _) => CostMatrix::read_csv(path)?,
        (None, Some(robots), Some(tasks)) => CostMatrix::uniform(robots, tasks, args.seed)?,
        _ => {
            bail!("give the costs with --costs FILE.csv, or --robots N --tasks M for random costs")
        }
    };
    let case = match args.case {
        CaseArg::Auto => CaseChoice::Auto,
        CaseArg::One => CaseChoice::Forced(AssignmentCase::One),
        CaseArg::Two => CaseChoice::Forced(AssignmentCase::Two),
    };
    let problem = TaskAssignmentProblem::new(costs, case)?;
    let spec: TopologySpec = args.topology.parse()?;
    let graph = spec
        .build(problem.robots(), args.seed)
        .with_context(|| format!("topology '{}'", args.topology))?;
    let perturbation = match args.perturb.as_str() {
        "auto" => Perturbation::Auto,
        "off" | "0" => Perturbation::Off,
        value => match value.parse::<f64>() {
            Ok(eps) if eps > 0.0 && eps.is_finite() => Perturbation::Fixed(eps),
            _ => bail!("--perturb must be auto, off or a positive number, got '{value}'"),
        },
    };
    let options = SolveOptions::builder()
        .method(args.method.method())
        .transport(args.transport)
        .rho(parse_rho(&args.rho)?)
        .adaptive_rho(args.adaptive_rho)
        .gamma_factor(args.gamma_factor)
        .max_iters(args.max_iters)
        .stop(match args.stop {
            StopArg::Local => StopRule::Local,
            StopArg::Agreement => StopRule::Agreement,
            StopArg::Certified => StopRule::Certified,
            StopArg::MaxIters => StopRule::MaxIters,
            StopArg::Oracle => StopRule::Oracle,
        })
        .stop_rounds(args.stop_rounds)
        .seed(args.seed)
        .perturbation(perturbation)
        .projection(match args.projection {
            ProjectionArg::Fast => ProjectionPath::Fast,
            ProjectionArg::Qp => ProjectionPath::Qp,
        })
        .check(args.check)
        .trace(args.trace)
        .global_barrier(args.global_barrier)
        .round_timeout_secs(args.round_timeout)
        .startup_timeout_secs(args.startup_timeout)
        .agent_program(agent_program()?)
        .on_failure(match args.on_failure {
            OnFailureArg::Abort => OnFailure::Abort,
            OnFailureArg::Continue => OnFailure::Continue,
        })
        .fault_injection(true)
        .wait(args.wait.strategy())
        .build()?;
    let report = solve::solve(&problem, &graph, &options)?;
    output::print_report(&report, args.json)
}

/// `auto` (None) or a number (the options check that it is a positive one).
fn parse_rho(text: &str) -> Result<Option<f64>> {
    if text == "auto" {
        return Ok(None);
    }
    match text.parse::<f64>() {
        Ok(rho) => Ok(Some(rho)),
        Err(_) => bail!("--rho (ρ) must be auto or a positive number, got '{text}'"),
    }
}

/// This binary: agent processes are started from it.
pub(crate) fn agent_program() -> Result<PathBuf> {
    std::env::current_exe().context("cannot locate the admm-ta binary to start agents from")
}

#[cfg(feature = "zenoh")]
fn run_host(team: &std::path::Path, name: &str) -> Result<()> {
    let report =
        admm_ta_runtime::process::host::run_host(team, name).map_err(anyhow::Error::msg)?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

#[cfg(not(feature = "zenoh"))]
fn run_host(_team: &std::path::Path, _name: &str) -> Result<()> {
    bail!(admm_ta_runtime::transport::ZenohNotBuilt)
}

fn run_demo(json: bool, transport: Transport) -> Result<()> {
    let problem = TaskAssignmentProblem::new(CostMatrix::uniform(20, 20, 2019)?, CaseChoice::Auto)?;
    let graph = TopologySpec::Complete.build(20, 0)?;
    let options = SolveOptions::builder()
        .check(true)
        .transport(transport)
        .agent_program(agent_program()?)
        .build()?;
    if !json {
        println!(
            "demo: 20 robots, 20 tasks, uniform [0,1) costs (seed 2019), complete graph, transport {}\n",
            options.transport().name()
        );
    }
    let report = solve::solve(&problem, &graph, &options)?;
    output::print_report(&report, json)
}
