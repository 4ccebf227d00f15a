//! The command line: every subcommand's arguments (clap definitions only; each subcommand
//! runs in its file of `commands/`). Value lists (methods, transports, stop rules, wait
//! strategies, …) come from the library's own types.
//!
//! Size: the whole command line in one file, one definition per subcommand and option with
//! its help text; split by subcommand it would no longer read as one interface.
//!
//! Doc comments here are clap's help text, not rustdoc Markdown (`[[hosts]]` is a TOML table).
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

use crate::command_line::method_flags::MethodFlags;
use crate::topologies::RobotRef;
use crate::{CaseChoice, CostModel, Method, OnFailure, StopRule, Transport, WaitStrategy};
use admm_ta_bench::rounds::case::{Barrier, StepKind};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "admm-ta",
    version,
    about = "Consensus ADMM task assignment for multi-robot teams"
)]
pub struct Cli {
    /// Structured logs on standard error, one line per event with the run, agent and round
    /// (`RUST_LOG` syntax: `info`, `debug`, `trace` for every round, `admm_ta_runtime=debug`);
    /// agent processes log to the launcher's standard error. Default: `RUST_LOG`, else none.
    #[arg(long, global = true, value_name = "FILTER")]
    pub log: Option<String>,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Solve a task assignment problem with a consensus method.
    Solve(SolveArgs),
    /// Solve a built-in default problem (20 robots, 20 tasks, complete graph) end to end.
    Demo(DemoArgs),
    /// Run one agent: of a team started independently (`--team FILE --robot I`: any order, any
    /// supervisor; see docs/teams.md), or of a launcher's run (`--run --robot --scenario`, started
    /// by `solve --transport ipc`).
    Agent(AgentArgs),
    /// Assemble the assignment of an independently started team from its agents' results.
    Collect(CollectArgs),
    /// Run one machine of a team across several machines (`transport = "zenoh"` or `"mixed"`
    /// in the team file): its Zenoh router, linked to the other hosts' routers, and in a
    /// mixed team its bridge. Start it next to the host's agents; it returns once every agent
    /// of the team has come and gone. Needs a build with `--features zenoh`.
    Host(HostArgs),
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
    Topology(TopologyArgs),
    /// Run many teams of agent processes at once (a stress test): failures, wall time,
    /// per-run p50/p99 and anything left behind; non-zero exit on any failure or leftover.
    Stress(crate::command_line::commands::stress::StressArgs),
    /// This user's running teams of agent processes (launched or started independently), and
    /// per agent its round, state (computing, waiting for whom, finished, failed), round time
    /// and CPU, refreshed in place; `q` quits, ↑/↓ choose the team. `--once` prints one
    /// snapshot (`--json` for scripts). It only reads what the teams share.
    Top(crate::command_line::commands::top::TopArgs),
}

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Print one JSON object instead of the human summary.
    #[arg(long)]
    pub json: bool,
    /// sim | threads | ipc (20 agent processes).
    #[arg(long, value_enum, default_value = "ipc")]
    pub transport: Transport,
}

#[derive(Args, Debug)]
pub struct AgentArgs {
    /// The team file (TOML) naming the run, the robots, the topology and the costs.
    #[arg(long, conflicts_with_all = ["run", "scenario"], requires = "robot")]
    pub team: Option<PathBuf>,
    /// This agent's robot: its number in the team (0-based), or, with --team, its name when
    /// the cost file names the robots. (`--id` and `--index`, its former names, still work.)
    #[arg(long, aliases = ["id", "index"])]
    pub robot: Option<RobotRef>,
    /// The run's id (it must match the scenario's).
    #[arg(long, requires_all = ["robot", "scenario"])]
    pub run: Option<String>,
    /// Serve a robot program on standard input and output, one JSON object per line
    /// (a team file with costs = "private"): a row `{"costs": [...]}` in, the robot's task
    /// out, episode after episode; end of input leaves the team (see docs/standing-teams.md).
    #[arg(long, requires = "team", conflicts_with = "row")]
    pub serve: bool,
    /// As --serve, over ROS 2 topics (std_msgs/String, one JSON line each): rows from
    /// `/robotI/admm_ta/costs`, answers to `/robotI/admm_ta/assignment` (`/<name>/…` when
    /// the cost file names the robots); `{"leave": true}` leaves. Reads ROS_DOMAIN_ID and
    /// ROS_AUTOMATIC_DISCOVERY_RANGE (see docs/ros2.md). Needs a build with `--features ros2`.
    #[arg(long, requires = "team", conflicts_with_all = ["row", "serve"])]
    pub ros2: bool,
    /// The ROS 2 namespace of the member's node and topics (default: `/robotI`, or the
    /// robot's name).
    #[arg(long, requires = "ros2", value_name = "NAMESPACE")]
    pub ros2_namespace: Option<String>,
    /// One episode of a private team with this robot's row from FILE (`-`: standard input;
    /// one CSV line or a JSON list, null or inf for a forbidden task): prints the answer
    /// and leaves with the others.
    #[arg(long, requires = "team", value_name = "FILE")]
    pub row: Option<PathBuf>,
    /// The scenario file the launcher wrote.
    #[arg(long, requires = "scenario_digest")]
    pub scenario: Option<PathBuf>,
    /// SHA-256 of the scenario file (hex): an agent refuses a file that differs.
    #[arg(long)]
    pub scenario_digest: Option<String>,
}

#[derive(Args, Debug)]
pub struct CollectArgs {
    /// The team file the agents were started with.
    #[arg(long)]
    pub team: PathBuf,
    /// Compare with the centralized optimum.
    #[arg(long)]
    pub check: bool,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct HostArgs {
    /// The team file (the same on every machine).
    #[arg(long)]
    pub team: PathBuf,
    /// This machine's name in the team file's [[hosts]].
    #[arg(long)]
    pub name: String,
}

#[derive(Args, Debug)]
pub struct TopologyArgs {
    /// complete | chain | ring | star | grid | random:P | geometric:R
    #[arg(long, default_value = "complete")]
    pub kind: String,
    #[arg(long)]
    pub robots: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

#[derive(Subcommand, Debug)]
pub enum Bench {
    /// Round latency of teams exchanging payloads on threads, shm (processes sharing a slot
    /// table), ipc (iceoryx2 zero-copy) and uds (Unix-domain sockets, copying) in one run: p50/p90/p99/p99.9/max of the round
    /// time and of the exchange overhead (round − compute), CPU time and context switches
    /// per agent-round. Without axis options it sweeps one axis at a time around 10 agents,
    /// complete graph, 10×10 payload; with any axis option, the cross product of the lists
    /// given. Writes rounds.json, rounds.csv and SVG plots into --out.
    Rounds(RoundsArgs),
}

#[derive(Args, Debug)]
pub struct RoundsArgs {
    /// A small sweep that finishes within a minute on 2 cores.
    #[arg(long)]
    pub quick: bool,
    /// Team sizes, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub agents: Option<Vec<usize>>,
    /// Topologies, comma-separated (complete, chain, ring, star, grid, random:P, geometric:R).
    #[arg(long, value_delimiter = ',')]
    pub topologies: Option<Vec<String>>,
    /// Payload shapes ROWSxCOLS of f64, comma-separated (e.g. 1x1,10x10,200x200).
    #[arg(long, value_delimiter = ',')]
    pub payloads: Option<Vec<String>>,
    /// Transports, comma-separated: threads, shm, ipc, uds, zenoh (default: threads, shm,
    /// ipc, uds; zenoh needs a build with `--features zenoh`).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub transports: Option<Vec<Transport>>,
    /// Wait strategies, comma-separated: auto, block, spin-then-block, spin.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub waits: Option<Vec<WaitStrategy>>,
    /// Barrier kinds, comma-separated: neighbour, global (uds and zenoh have no global
    /// barrier).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub barriers: Option<Vec<Barrier>>,
    /// What agents compute per round: touch (one value per neighbour: the exchange
    /// alone), average (every value of every neighbour) or primal (the ADMM step on
    /// uniform n×n costs; the payload is then n×n).
    #[arg(long, value_enum, default_value = "touch")]
    pub step: StepKind,
    /// Recorded rounds per case (default 1000, --quick 400).
    #[arg(long)]
    pub rounds: Option<u64>,
    /// Rounds before recording starts (default 100, --quick 50).
    #[arg(long)]
    pub warmup: Option<u64>,
    /// Measure every case this many times (the transports of a configuration in turn)
    /// and report the repetition with the median p50, with the p50 range.
    #[arg(long, default_value_t = 1)]
    pub repeat: usize,
    /// Directory for rounds.json, rounds.csv and the plots (created if missing).
    #[arg(long, default_value = "bench-results")]
    pub out: PathBuf,
    /// Print the JSON report on stdout instead of the tables.
    #[arg(long)]
    pub json: bool,
    /// Record every agent's rounds and write one Chrome trace per case into DIR
    /// (`<agents>-<graph>-<payload>-<transport>-<wait>-<barrier>.json`, created if missing;
    /// open in Perfetto or chrome://tracing); the critical path of each case goes into the
    /// report, rounds.json and one plot per case (critical-<case>.svg in --out).
    #[arg(long, value_name = "DIR")]
    pub timeline: Option<PathBuf>,
    /// Measure what `--timeline` costs instead: every case with and without timelines in
    /// turn (`--repeat` times), round p50 and p99 of each and their ratios.
    #[arg(long, conflicts_with_all = ["json", "timeline"])]
    pub timeline_overhead: bool,
}

/// Options shared by the figure experiments.
#[derive(Args, Debug)]
pub struct FigureArgs {
    /// Seeds (cost matrices and random graphs) per point.
    #[arg(long, default_value_t = 3)]
    pub trials: u64,
    /// Directory for the JSON and SVG files (created if missing).
    #[arg(long, default_value = "experiment-results")]
    pub out: PathBuf,
    /// Run the ADMM methods with --adaptive-rho.
    #[arg(long)]
    pub adaptive_rho: bool,
    #[arg(long, default_value_t = 5000)]
    pub max_iters: usize,
    /// Print the JSON instead of the table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand, Debug)]
pub enum Experiment {
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
    Compare(CompareArgs),
    /// The persistent-surveillance case study (paper Section 4.4, Fig. 3): one team alive for
    /// every episode, each robot computing its own costs from its battery and position, each
    /// episode warm-started from the last; compared per episode with the Hungarian optimum
    /// and with a cold start. Writes surveillance.json and SVG plots into --out.
    Surveillance(SurveillanceArgs),
    /// Where the rounds go: per method (primal in both variants, dual, inexact dual, market,
    /// distributed Hungarian, CBAA), cost model (uniform, geometric) and graph (complete,
    /// random:0.1, chain, ring, geometric:0.3), the median rounds to the relaxed objective
    /// and the decisions within 0.1%, to optimal decisions and to the certified stop.
    /// Writes rounds_anatomy.json and one SVG per cost model into --out.
    #[command(name = "rounds-anatomy")]
    RoundsAnatomy(RoundsAnatomyArgs),
    /// Every size certified: the primal method with the defaults on n × n problems (20, 50,
    /// 80, 120 robots), uniform and distance costs, chain / ring / random:0.1 / complete
    /// graphs; per point the runs certified and optimal, median and largest rounds, median
    /// wall time (sim). Exits non-zero unless every run certified the optimum.
    #[command(name = "size-sweep")]
    SizeSweep(SizeSweepArgs),
    /// Table 1: iterations of primal / dual / inexact dual at 20×20 on the complete graph
    /// (paper: 28 / 159 / 387), for uniform costs in [0,1) and shifted to [1,2).
    Table1(Table1Args),
}

/// The options of `experiment compare`.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// Team sizes (robots = tasks), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [10usize, 20, 50])]
    pub robots: Vec<usize>,
    /// Seeds per size (problems and random graphs).
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// Methods, comma-separated (default: all).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub methods: Vec<Method>,
    /// Transports, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["sim", "ipc"])]
    pub transports: Vec<Transport>,
    /// complete | chain | ring | star | grid | random:P | geometric:R
    #[arg(long, default_value = "complete")]
    pub topology: String,
    /// Random costs: uniform [0,1) or geometric (distances in the unit square).
    #[arg(long, value_enum, default_value = "uniform")]
    pub cost_model: CostModel,
    /// The methods' own settings (each method reads its own).
    #[command(flatten)]
    pub settings: MethodFlags,
    /// Run the ADMM methods that have a schedule (dual methods, paper primal) with
    /// --adaptive-rho.
    #[arg(long)]
    pub adaptive_rho: bool,
    #[arg(long, default_value_t = 5000)]
    pub max_iters: usize,
    /// Directory for compare.json (created if missing).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The options of `experiment surveillance`.
#[derive(Args, Debug)]
pub struct SurveillanceArgs {
    #[arg(long, default_value_t = 1000)]
    pub episodes: usize,
    /// Mission TOML file: robots, stations, batteries, weights (default: the built-in one,
    /// `admm-ta-agents::problem::surveillance`; `--scenario`, its former name, still works).
    #[arg(long, alias = "scenario", value_name = "FILE")]
    pub mission: Option<PathBuf>,
    /// ipc (one process per robot for the whole run), threads or uds.
    #[arg(long, value_enum, default_value = "ipc")]
    pub transport: Transport,
    /// Start every episode from zero iterates instead of the previous episode's.
    #[arg(long)]
    pub cold_start: bool,
    /// Round limit of each episode.
    #[arg(long, default_value_t = 5000)]
    pub max_iters: u64,
    /// Directory for surveillance.json and the plots (created if missing).
    #[arg(long, default_value = "experiment-results")]
    pub out: PathBuf,
    /// Print one JSON object (episodes, optimal_episodes, battery_violations,
    /// mean_iterations_warm, mean_iterations_cold, …) instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Record every agent's rounds over all episodes and write them as Chrome trace JSON
    /// to FILE (rounds numbered across episodes; at most 200 000 rounds per agent); the
    /// critical path goes into the summary and surveillance.json.
    #[arg(long, value_name = "FILE")]
    pub timeline: Option<PathBuf>,
}

/// The options of `experiment rounds-anatomy`.
#[derive(Args, Debug)]
pub struct RoundsAnatomyArgs {
    /// 12 robots × 8 tasks, 2 seeds, 2000 rounds (default: 50 × 30, 5 seeds, 5000).
    #[arg(long)]
    pub quick: bool,
    /// Seeds per cell (overrides the default of the size).
    #[arg(long)]
    pub seeds: Option<u64>,
    #[arg(long, default_value = "experiment-results")]
    pub out: PathBuf,
    /// Print the JSON instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// The options of `experiment size-sweep`.
#[derive(Args, Debug)]
pub struct SizeSweepArgs {
    /// 10 and 20 robots, 2 seeds (default: 20, 50, 80, 120 robots, 3 seeds).
    #[arg(long)]
    pub quick: bool,
    /// Sizes n, comma-separated (overrides the default).
    #[arg(long, value_delimiter = ',')]
    pub sizes: Vec<usize>,
    /// Seeds per point (overrides the default).
    #[arg(long)]
    pub seeds: Option<u64>,
    /// Graphs, comma-separated (default chain,ring,random:0.1,complete).
    #[arg(long, value_delimiter = ',')]
    pub topologies: Vec<String>,
    #[arg(long, default_value = "experiment-results")]
    pub out: PathBuf,
}

/// The options of `experiment table1`.
#[derive(Args, Debug)]
pub struct Table1Args {
    #[arg(long, default_value_t = 50)]
    pub trials: u64,
    /// Directory for table1.json (created if missing).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run every method with the --adaptive-rho schedule.
    #[arg(long)]
    pub adaptive_rho: bool,
    /// Multiply every method's default ρ by this factor (for ρ studies).
    #[arg(long, default_value_t = 1.0)]
    pub rho_scale: f64,
    /// Round limit of every run.
    #[arg(long, default_value_t = 3000)]
    pub max_iters: usize,
    /// Print the JSON instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// A cost file's delimiter.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Delimiter {
    Comma,
    Tab,
    Semicolon,
}

impl Delimiter {
    pub fn byte(self) -> u8 {
        match self {
            Self::Comma => b',',
            Self::Tab => b'\t',
            Self::Semicolon => b';',
        }
    }
}

#[derive(Args, Debug)]
pub struct SolveArgs {
    /// Cost file, `-` for standard input: CSV (one row per robot, one column per task;
    /// comma, tab or semicolon; quoted or not; an optional header row of task names and
    /// first column of robot names, as pandas' to_csv writes) or JSON (a list of rows, or
    /// {"costs": [[…]], "robots": […], "tasks": […]} with null for a forbidden pair). `inf`
    /// marks a forbidden pair (`-inf` with --maximize).
    #[arg(long, conflicts_with_all = ["robots", "tasks"])]
    pub costs: Option<PathBuf>,
    /// The cost file's delimiter (default: detected from its first row).
    #[arg(long, value_enum, requires = "costs")]
    pub delimiter: Option<Delimiter>,
    /// File of forbidden robot–task pairs (`-` for standard input), one `robot,task` per
    /// line: 0-based indices, or names when the cost file has them.
    #[arg(long)]
    pub forbidden: Option<PathBuf>,
    /// The matrix holds profits to maximise (scipy's maximize=True): `-inf` is forbidden.
    #[arg(long)]
    pub maximize: bool,
    /// Number of robots for random costs (see --cost-model).
    #[arg(long, requires = "tasks")]
    pub robots: Option<usize>,
    /// Number of tasks for random costs (see --cost-model).
    #[arg(long, requires = "robots")]
    pub tasks: Option<usize>,
    /// Random costs: uniform (entries uniform in [0,1)) or geometric (robots and tasks at
    /// random points of the unit square, cost = Euclidean distance).
    #[arg(long, value_enum, default_value = "uniform", conflicts_with = "costs")]
    pub cost_model: CostModel,
    /// Seed of the random costs, random topologies and tie-breaking.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Coverage case: auto (1 for n = m, 2 for n > m, idle for n < m), 1 (n = m, one robot
    /// per task), 2 (n ≥ m, every robot works, every task at least one robot) or idle
    /// (scipy's rectangular meaning: min(n, m) pairs, surplus robots idle or tasks unserved).
    #[arg(long, value_enum, default_value = "auto")]
    pub case: CaseChoice,
    /// complete | chain | ring | star | grid | random:P | geometric:R | FILE.toml
    #[arg(long, default_value = "complete")]
    pub topology: String,
    // The help lists every method with its summary, from the method registry.
    #[arg(long, value_enum, default_value = "primal", help = Method::help())]
    pub method: Method,
    /// sim (one thread, lockstep), threads (a thread per agent), shm (a process per agent,
    /// one shared table of slots read in place, futex wake-ups: a reference for the cost of
    /// a round between processes), ipc (a process per agent, iceoryx2 zero-copy), uds (a process per agent, payloads copied through Unix-domain
    /// sockets: a baseline) or zenoh (a process per agent, Zenoh through a router on
    /// loopback: the multi-host transport; needs `--features zenoh`).
    #[arg(long, value_enum, default_value = "sim")]
    pub transport: Transport,
    /// The methods' own settings, declared by each method (`--primal-variant`,
    /// `--projection`, `--gamma-factor`): a setting another method has is refused.
    #[command(flatten)]
    pub settings: MethodFlags,
    /// ADMM penalty ρ: auto (scale-free rule from the cost spread and the graph's mean
    /// degree d̄: primal fast 100·spread/(2·d̄), primal paper
    /// 0.5·spread·√((n−1)/d̄)/(2·d̄·n), dual and inexact dual (fast variant) 0.5·s/(spread·d̄)
    /// with s from 3 (independent costs) to ½ (distance-like costs; less for teams of 150
    /// and more) by the costs' structure (1 where it is unclear),
    /// growing to 300× over the run; paper variant dual 5/(spread·d̄), inexact dual
    /// 10/(spread·d̄)) or a positive number.
    #[arg(long, default_value = "auto", allow_negative_numbers = true)]
    pub rho: String,
    /// Vary ρ by the method's schedule, computed by every agent from the round number
    /// (primal paper variant: 3ρ shrinking 2% per round to 0.6ρ; dual methods: ρ, then
    /// growing 1% per round to 10ρ). Cut the rounds to the certified stop by 10–69% wherever
    /// the runs certified. Refused with the fast primal variant (ρ drops out of its iteration)
    /// and with the methods without ρ.
    #[arg(long)]
    pub adaptive_rho: bool,
    #[arg(long, default_value_t = 5000)]
    pub max_iters: usize,
    /// local: every robot checks its own optimality certificate and agreement with its
    /// neighbours, and a header protocol stops all robots at the same round (any transport);
    /// certified: the same certificate checked centrally (sim, primal); agreement: all robots
    /// agree on one near-integral assignment for --stop-rounds rounds (sim, primal); oracle:
    /// the paper's criterion, the first round whose relaxed objective is within 0.1% of the
    /// centralized optimum (sim, experiments only); max-iters: always run --max-iters rounds.
    #[arg(long, value_enum, default_value = "local")]
    pub stop: StopRule,
    #[arg(long, default_value_t = 10)]
    pub stop_rounds: usize,
    /// Tie-breaking cost perturbation: auto (only for lattice costs such as integers), off,
    /// or a number ε.
    #[arg(long, default_value = "auto")]
    pub perturb: String,
    /// Compare with the centralized optimum (adds optimal_cost and gap).
    #[arg(long)]
    pub check: bool,
    /// With --check on the sim transport: every round's relaxed and rounded cost in the
    /// JSON report (`check.trace`), for convergence plots.
    #[arg(long, requires = "check")]
    pub trace: bool,
    /// Write every agent's rounds (wait, compute, publish, barrier; the message each agent
    /// waited for last as a flow) to FILE as Chrome trace-event JSON (Perfetto,
    /// chrome://tracing), and name the critical path in the report (threads and process
    /// transports).
    #[arg(long, value_name = "FILE")]
    pub timeline: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// Add a global barrier (all agents reach round k) to every round: lockstep, for
    /// latency benchmarks (threads and ipc).
    #[arg(long)]
    pub global_barrier: bool,
    /// Seconds an agent waits for a neighbour's message or the barrier before failing.
    #[arg(long, default_value_t = 30.0)]
    pub round_timeout: f64,
    /// Seconds all agent processes have to start and connect (ipc).
    #[arg(long, default_value_t = 60.0)]
    pub startup_timeout: f64,
    /// When an agent process dies or misbehaves (ipc): abort (stop every agent, exit ≠ 0 with
    /// one line naming it) or continue (the survivors drop that robot and re-solve without
    /// it, if the graph stays connected and robots still cover the tasks; the report then
    /// names the failed robot and maps the assignment to the survivors' original numbers).
    #[arg(long, value_enum, default_value = "abort")]
    pub on_failure: OnFailure,
    /// How agents wait for their neighbours (threads, shm, ipc, uds): auto (spin 20 µs then
    /// sleep when every agent has a core, else sleep at once), block, spin-then-block, or
    /// spin (poll and yield, never sleep).
    #[arg(long, value_enum, default_value = "auto")]
    pub wait: WaitStrategy,
}
