//! The errors of independently started teams, one type per operation: reading a team file
//! ([`TeamFileError`], with [`HostsError`] for its hosts), joining the team's board
//! ([`JoinError`]) and collecting the agents' results ([`CollectError`]). Each keeps its
//! cause as its source; the text is rendered at the edge (the command line, an agent's log).

use crate::options::error::ConfigError;
use crate::options::given::FrontEnd;
use crate::process::namespace::{BadTeamName, TeamNamespaceError};
use crate::process::private_dir::PrivateDirError;
use crate::process::team_digest::OtherTeam;
use crate::workload::plan::BadRho;
use admm_ta_agents::certify::local_stop::LocalStopError;
use admm_ta_agents::numerics::lsap::LsapError;
use admm_ta_agents::problem::ProblemError;
use admm_ta_topologies::{RobotNameError, TopologyError};
use admm_ta_transport::endpoint::SupportError;
use admm_ta_transport::latency::BucketsMismatch;
use admm_ta_transport::zenoh_net::error::ZenohError;
use admm_ta_transport::zenoh_net::links::NotAnEndpoint;
use std::path::PathBuf;
use std::time::Duration;

/// Why a team file cannot be used: read, parsed, checked, or its problem built.
#[derive(Debug, thiserror::Error)]
pub enum TeamFileError {
    #[error("cannot read team file")]
    Read(#[source] ProblemError),
    #[error("team file {}: {message}", path.display())]
    Syntax { path: PathBuf, message: String },
    #[error("team file {}: {key} must be a number or a name, got {got}", path.display())]
    SettingKind {
        path: PathBuf,
        key: &'static str,
        got: String,
    },
    #[error(transparent)]
    RunName(#[from] BadTeamName),
    #[error(transparent)]
    Hosts(#[from] HostsError),
    /// A setting refused as the command line's would be, named by the file's keys.
    #[error("team file {}: {}", path.display(), error.in_terms_of(FrontEnd::TeamFile))]
    Settings { path: PathBuf, error: ConfigError },
    /// The same, once the file was read.
    #[error("{}", .0.in_terms_of(FrontEnd::TeamFile))]
    Options(ConfigError),
    #[error("the team file has no host '{name}' (hosts: {hosts:?})")]
    NoHost { name: String, hosts: Vec<String> },
    #[error("costs = \"random\" needs tasks = M in the team file")]
    RandomNeedsTasks,
    /// A team whose robots keep their costs (`costs = "private"`) that cannot run.
    #[error("{0}")]
    Private(PrivateTeamError),
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// A file the team file names (costs, forbidden pairs).
    #[error("{}", path.display())]
    File {
        path: PathBuf,
        #[source]
        source: ProblemError,
    },
    #[error("the team file says {file} robots but the costs have {costs} rows")]
    Robots { file: usize, costs: usize },
    #[error(
        "{robots} robots cannot cover {tasks} tasks: a team file's problem needs at least as many robots as tasks"
    )]
    TooFewRobots { robots: usize, tasks: usize },
    #[error(transparent)]
    TopologyFile(TopologyError),
    /// A host's `agents` names a robot the costs do not name.
    #[error("team file {}: host '{host}'", path.display())]
    HostRobot {
        path: PathBuf,
        host: String,
        #[source]
        source: Box<RobotNameError>,
    },
    /// `agent --robot NAME` names a robot the costs do not name.
    #[error("--robot")]
    Id(#[source] Box<RobotNameError>),
    #[error("topology {} has {found} robots, the team {robots}", path.display())]
    TopologyRobots {
        path: PathBuf,
        found: usize,
        robots: usize,
    },
    #[error("topology '{spec}'")]
    Topology {
        spec: String,
        #[source]
        source: TopologyError,
    },
    #[error("method {method} is solved centrally: it has no agents")]
    Centralized { method: &'static str },
    #[error(transparent)]
    Rho(#[from] BadRho),
    #[error(transparent)]
    LocalStop(#[from] LocalStopError),
}

/// Why a team file's private team (`costs = "private"`) cannot run.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PrivateTeamError {
    #[error(
        "costs = \"private\" needs tasks = M in the team file (the most costs a robot's row has)"
    )]
    NeedsTasks,
    #[error(
        "method {method} cannot keep costs private with these settings: its agents take no new costs or cannot relay (use method = \"primal\", or \"dual\" or \"inexact-dual\" with their fast variant)"
    )]
    Method { method: &'static str },
    #[error(
        "a private team's forbidden pairs are part of each robot's row (null for a forbidden task), not a file"
    )]
    ForbiddenFile,
    #[error("{key} is a private team's key (costs = \"private\")")]
    NotPrivateKey { key: &'static str },
    #[error(
        "a private team's agents take their costs from their robot program: start them with --serve"
    )]
    NeedsServe,
    #[error(
        "a private team's robots answer their own programs (agent --serve): there are no results to collect"
    )]
    NothingToCollect,
    #[error(
        "--serve needs a team file with costs = \"private\" (the robots' rows come from their programs)"
    )]
    NotPrivate,
}

/// Hosts of a team file that cannot run it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HostsError {
    #[error("[[hosts]] are for teams across machines: add transport = \"zenoh\" or \"mixed\"")]
    NotAcrossHosts,
    #[error("a zenoh or mixed team needs [[hosts]] entries (name, agents, endpoint)")]
    None,
    #[error("host name '{0}': use 1 to 40 letters, digits and dashes")]
    BadName(String),
    #[error("host '{host}'")]
    Endpoint {
        host: String,
        #[source]
        source: NotAnEndpoint,
    },
    #[error("two hosts are called '{0}'")]
    SameName(String),
    #[error("hosts '{first}' and '{second}' have the same endpoint {endpoint}")]
    SameEndpoint {
        first: String,
        second: String,
        endpoint: String,
    },
    #[error("host '{host}' lists robot {robot}, but the team has {robots} robots (0..{robots})")]
    NoSuchRobot {
        host: String,
        robot: usize,
        robots: usize,
    },
    #[error("robot {robot} is on two hosts: '{first}' and '{second}'")]
    TwoHosts {
        robot: usize,
        first: String,
        second: String,
    },
    #[error(
        "a mixed team's run name and host name together must fit 40 characters ('{run}-{host}' does not): each host's shared memory is named after both"
    )]
    NameTooLong { run: String, host: String },
    #[error("robot(s) {0:?} are on no host")]
    Homeless(Vec<usize>),
}

/// Why a member cannot take its place in the team (its id, its results directory, the
/// team's board).
#[derive(Debug, thiserror::Error)]
pub enum JoinError {
    /// A robot that asked to join a running standing team was not admitted in time.
    #[error(
        "robot {robot} was not admitted to the running team within {waited:?}: its neighbours in the team file ({neighbours:?}) take no part, or the team ran no episode"
    )]
    NotAdmitted {
        robot: usize,
        waited: Duration,
        neighbours: Vec<usize>,
    },
    #[error("--robot {id} is out of range for a team of {robots} robots")]
    NoSuchAgent { id: usize, robots: usize },
    #[error("cannot create {}", path.display())]
    Results {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot open the team lock {}", path.display())]
    Lock {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("the team lock {} stayed taken until the start-up deadline", path.display())]
    LockTaken { path: PathBuf },
    #[error(transparent)]
    Namespace(#[from] TeamNamespaceError),
    #[error(transparent)]
    Board(#[from] admm_ta_transport::board::BoardError),
    #[error(transparent)]
    OtherTeam(#[from] OtherTeam),
    #[error("agent {slot} of this team is already running (pid {pid}): one process per agent")]
    AlreadyRunning { slot: usize, pid: u32 },
    /// A standing team's robot whose slot another process holds on the team's network.
    #[error("robot {slot} of this team is already running on its network: one process per robot")]
    AlreadyOnTheNetwork { slot: usize },
    #[error("agent {slot} already took part in this team's run: it cannot join it twice")]
    TookPart { slot: usize },
    #[error(transparent)]
    Directory(#[from] PrivateDirError),
    #[error(transparent)]
    Resources(#[from] SupportError),
}

/// Why the agents' results do not make the team's assignment.
#[derive(Debug, thiserror::Error)]
pub enum CollectError {
    #[error(transparent)]
    TeamFile(#[from] TeamFileError),
    #[error("{} is not an agent result", path.display())]
    NotAResult {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error(
        "agent(s) {missing:?} left no result in {} (still running, failed, or never started; see their output)",
        dir.display()
    )]
    Missing { missing: Vec<usize>, dir: PathBuf },
    #[error("{} is agent {found}'s result, not agent {id}'s", path.display())]
    WrongAgent {
        path: PathBuf,
        found: usize,
        id: usize,
    },
    #[error(
        "{} is not a result of this team (another team file, or the team file changed since the run)",
        path.display()
    )]
    OtherTeam { path: PathBuf },
    #[error("the results in {} come from different runs (rounds {rounds:?})", dir.display())]
    DifferentRuns { dir: PathBuf, rounds: Vec<u64> },
    #[error("agent {agent}'s result")]
    Unreadable {
        agent: usize,
        #[source]
        source: BucketsMismatch,
    },
    #[error("the agents' tasks {0:?} are not a feasible assignment")]
    Infeasible(Vec<usize>),
    #[error(transparent)]
    Problem(#[from] ProblemError),
    #[error(transparent)]
    Oracle(#[from] LsapError),
    /// The team file's `timeline` could not be written.
    #[error("cannot write the timeline {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// Why a host of a team across machines ended without its report.
#[derive(Debug, thiserror::Error)]
pub enum HostError {
    #[error(
        "this team runs on one machine over iceoryx2 (transport = \"iceoryx2\"): it has no hosts"
    )]
    NoHosts,
    #[error(transparent)]
    Zenoh(#[from] ZenohError),
    #[error("a host announced a malformed team digest {0}")]
    MalformedDigest(String),
    #[error(
        "host {host}: stopped by {}: {stopped} agent(s) stopped, {leaving} still leaving",
        admm_ta_transport::signals::name(*signal)
    )]
    Stopped {
        host: String,
        signal: i32,
        stopped: usize,
        leaving: usize,
    },
    #[error(
        "host {host}: agent(s) {missing:?} never joined the team's Zenoh network within {waited:.1?} (not started, or their host unreachable)"
    )]
    NeverJoined {
        host: String,
        missing: Vec<usize>,
        waited: Duration,
    },
    #[error("host {host}: agent(s) {running:?} still ran after every round's deadline")]
    Overran { host: String, running: Vec<usize> },
    #[error(
        "host {host}: host {lost} left the team during the run without a goodbye (killed, crashed or cut off): its agents were out of reach, the team stopped"
    )]
    HostLost { host: String, lost: String },
    #[error(
        "host {host}: every other host of the team ({lost:?}) left during the run without a goodbye at once: this host was most likely cut off from them (network), the team stopped"
    )]
    CutOff { host: String, lost: Vec<String> },
    #[error("host {host}: the team's run failed: agent {failed} failed (see its output)")]
    AgentFailed { host: String, failed: usize },
    #[error(
        "host {host}: the team's run failed: agent {failed} failed (see its output); agent(s) {listed:?} still listed alive {waited:.1?} later were not waited for"
    )]
    FailedWithAgentsListed {
        host: String,
        failed: usize,
        listed: Vec<usize>,
        waited: Duration,
    },
}
