//! The persistent-surveillance case study (paper Section 4.4, Fig. 3):
//! `admm-ta experiment surveillance --episodes 1000`.
//!
//! One team of agents (one process per robot over iceoryx2 by default) stays alive for all
//! episodes; each episode every robot computes its own costs from its battery and position
//! ([`admm_ta_agents::problem::surveillance`]), the team solves the assignment warm-started from the
//! previous episode, and every robot moves. Each episode's assignment is compared with the
//! Hungarian optimum of the same costs, batteries are checked (a violation is a battery
//! below 0), and the same cost matrix is solved again from a **cold** start (fresh agents,
//! lockstep simulation, same ρ and stop rule) to measure what the warm start saves.

use crate::experiment::{Experiment, OutputFile, mean_of};
use crate::figures::FigureError;
use crate::plot::{Chart, Legend, Series};
use admm_ta_agents::certify::local_stop::LocalCertifiedStop;
use admm_ta_agents::certify::oracle;
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::surveillance::SurveillanceMission;
use admm_ta_agents::problem::{AssignmentCase, CostMatrix};
use admm_ta_runtime::surveillance::{EpisodeRunConfig, run_episodes};
use admm_ta_runtime::workload::surveillance::{EpisodeRecord, EpisodeSettings};
use admm_ta_topologies::{Graph, TopologySpec};
use admm_ta_transport::sim::process::LockstepSim;
use admm_ta_transport::timeline::{CriticalPath, RoundStamp, chrome_trace, critical_path};
use serde::Serialize;

/// One episode as the experiment saw it.
#[derive(Debug, Clone, Serialize)]
pub struct Episode {
    pub episode: usize,
    /// Station of each robot.
    pub assignment: Vec<usize>,
    pub team_cost: f64,
    pub optimal_cost: f64,
    pub optimal: bool,
    /// The team's stop certified the assignment (not the round limit).
    pub certified: bool,
    pub rounds_warm: u64,
    /// Rounds of a cold-started solve of the same costs (`None`: not certified within the
    /// round limit).
    pub rounds_cold: Option<u64>,
    /// Battery of each robot after the episode.
    pub batteries: Vec<f64>,
}

/// What `experiment surveillance` reports.
#[derive(Debug, Clone, Serialize)]
pub struct SurveillanceReport {
    pub episodes: usize,
    pub optimal_episodes: usize,
    pub battery_violations: usize,
    pub mean_iterations_warm: f64,
    pub mean_iterations_cold: f64,
    pub robots: usize,
    pub surveillance_stations: usize,
    pub charging_stations: usize,
    pub transport: String,
    pub warm_start: bool,
    pub rho: f64,
    /// Wall time of the team's run (start-up included), ms.
    pub wall_ms: f64,
    pub round_p50_us: f64,
    pub round_p99_us: f64,
    /// Episodes that were not optimal, with the reason.
    pub misses: Vec<String>,
    /// Length of the cycle the total cost settles into over the last episodes, exactly (to
    /// 1e-9; `None`: no cycle of at most 50 episodes found) …
    pub limit_cycle: Option<usize>,
    /// … and up to the tie-breaking preferences (to `n·ε`): robots in the same roles
    /// rotate, so the exact cycle can be a multiple of this one.
    pub limit_cycle_roles: Option<usize>,
    pub mission: SurveillanceMission,
    pub per_episode: Vec<Episode>,
    /// With timelines (`--timeline`): whom the team waited for, round by round, over all
    /// episodes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_path: Option<CriticalPath>,
    /// Every agent's round stamps over all episodes (timelines on; see [`trace`]).
    #[serde(skip)]
    pub timeline: Vec<Vec<RoundStamp>>,
    #[serde(skip)]
    graph: Option<Graph>,
}

/// The team's timeline as Chrome trace JSON (rounds numbered across episodes), if its
/// agents recorded one.
pub fn trace(report: &SurveillanceReport) -> Option<serde_json::Value> {
    let graph = report.graph.as_ref()?;
    (!report.timeline.is_empty()).then(|| chrome_trace(graph, &report.timeline))
}

/// Rounds of a cold-started decentralized solve of `costs` (lockstep simulation).
fn cold_rounds(
    settings: &EpisodeSettings,
    graph: &Graph,
    costs: &[Vec<f64>],
    max_rounds: usize,
) -> Option<u64> {
    let n = costs.len();
    let agents = (0..n)
        .map(|i| {
            let mut agent = settings.agent(i, graph);
            agent
                .set_costs(&costs[i], false)
                .expect("a primal agent of the model's shape");
            agent
        })
        .collect();
    let mut sim = LockstepSim::new(agents, graph);
    let mut stops: Vec<LocalCertifiedStop> = (0..n)
        .map(|_| {
            LocalCertifiedStop::new(settings.diameter, n, settings.tolerance)
                .expect("checked diameter")
        })
        .collect();
    let outcome = sim.run_local_stop(&mut stops, max_rounds, &mut |_| {});
    outcome.certified.map(|_| outcome.rounds as u64)
}

/// The shortest period `p ≤ 50` with which the last `max(3p, 30)` total costs repeat to
/// `tolerance`: the cycle the team settled into.
fn limit_cycle(costs: &[f64], tolerance: f64) -> Option<usize> {
    (1..=50).find(|&p| {
        let span = (3 * p).max(30);
        span <= costs.len()
            && costs[costs.len() - span..]
                .windows(p + 1)
                .all(|w| (w[0] - w[p]).abs() <= tolerance)
    })
}

/// Runs the experiment.
pub fn run(
    model: SurveillanceMission,
    episodes: usize,
    warm_start: bool,
    config: &EpisodeRunConfig,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<SurveillanceReport, FigureError> {
    model
        .validate()
        .map_err(|e| FigureError::Setup(e.to_string()))?;
    let n = model.robots;
    let graph = model
        .topology
        .parse::<TopologySpec>()
        .and_then(|t| t.build(n, 0))
        .map_err(|e| FigureError::Setup(format!("topology {}: {e}", model.topology)))?;
    let diameter = graph.diameter().unwrap_or(0);
    // The paper's case study: its own method, as it ran it.
    let method = Method::papers_own();
    let contender = Contender::as_in_paper(method).unwrap_or(Contender::of(method));
    let settings = EpisodeSettings::new(
        model.clone(),
        episodes,
        warm_start,
        graph.mean_degree(),
        diameter,
        contender,
    )
    .map_err(|e| FigureError::Setup(e.to_string()))?;
    let run = run_episodes(&settings, &graph, config)?;
    let rows_of =
        |e: usize| -> Vec<Vec<f64>> { run.records.iter().map(|r| r[e].costs.clone()).collect() };
    let cold = cold_starts(
        &settings,
        &graph,
        &rows_of,
        config.max_rounds as usize,
        progress,
    );
    let mut per_episode = Vec::with_capacity(episodes);
    let mut misses = Vec::new();
    for (e, rounds_cold) in cold.into_iter().enumerate() {
        let (episode, miss) = judge(e, &rows_of(e), &run.records, rounds_cold)?;
        misses.extend(miss);
        per_episode.push(episode);
    }
    let violations = per_episode
        .iter()
        .map(|e| e.batteries.iter().filter(|&&b| b < 0.0).count())
        .sum();
    let costs: Vec<f64> = per_episode.iter().map(|e| e.team_cost).collect();
    Ok(SurveillanceReport {
        episodes,
        optimal_episodes: per_episode.iter().filter(|e| e.optimal).count(),
        battery_violations: violations,
        mean_iterations_warm: mean_of(per_episode.iter().map(|e| e.rounds_warm as f64))
            .unwrap_or(f64::NAN),
        mean_iterations_cold: mean_of(
            per_episode
                .iter()
                .filter_map(|e| e.rounds_cold.map(|r| r as f64)),
        )
        .unwrap_or(f64::NAN),
        robots: n,
        surveillance_stations: model.surveillance_stations.len(),
        charging_stations: model.charging_stations.len(),
        transport: config.options.transport().name().to_string(),
        warm_start,
        rho: settings.rho,
        wall_ms: run.wall.as_secs_f64() * 1e3,
        round_p50_us: run.latency.round.p50,
        round_p99_us: run.latency.round.p99,
        misses,
        limit_cycle: limit_cycle(&costs, 1e-9),
        limit_cycle_roles: limit_cycle(&costs, model.tie_break * n as f64),
        mission: model,
        per_episode,
        critical_path: (config.options.timeline() && run.timeline.iter().any(|t| !t.is_empty()))
            .then(|| critical_path(&graph, &run.timeline)),
        timeline: run.timeline,
        graph: Some(graph),
    })
}

/// The rounds of a cold-started solve of every episode's costs (`rows_of(e)`): the expensive
/// part, split over the cores.
fn cold_starts(
    settings: &EpisodeSettings,
    graph: &Graph,
    rows_of: &(dyn Fn(usize) -> Vec<Vec<f64>> + Sync),
    max_rounds: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<Option<u64>> {
    let episodes = settings.episodes;
    let workers = std::thread::available_parallelism()
        .map_or(1, |c| c.get())
        .min(8);
    let done = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|scope| {
        let chunks: Vec<_> = (0..workers)
            .map(|w| {
                let done = &done;
                scope.spawn(move || {
                    (w..episodes)
                        .step_by(workers)
                        .map(|e| {
                            let r = cold_rounds(settings, graph, &rows_of(e), max_rounds);
                            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                            (e, r)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        let mut all = vec![None; episodes];
        for c in chunks {
            for (e, r) in c.join().expect("cold-start worker") {
                all[e] = r;
            }
        }
        all
    })
}

/// Episode `e` judged against the Hungarian optimum of its costs (`rows`), with what went
/// wrong when it was not optimal.
fn judge(
    e: usize,
    rows: &[Vec<f64>],
    records: &[Vec<EpisodeRecord>],
    rounds_cold: Option<u64>,
) -> Result<(Episode, Option<String>), FigureError> {
    let tasks = rows.first().map_or(0, |r| r.len());
    let matrix = CostMatrix::new(rows.len(), tasks, rows.concat())
        .map_err(|e| FigureError::Setup(e.to_string()))?;
    let best = oracle::solve_costs(&matrix, AssignmentCase::Two)
        .map_err(|e| FigureError::Setup(e.to_string()))?;
    let cost_of = |a: &[usize]| a.iter().enumerate().map(|(i, &t)| rows[i][t]).sum::<f64>();
    let assignment: Vec<usize> = records.iter().map(|r| r[e].task).collect();
    let covered = (0..tasks).all(|t| assignment.contains(&t));
    let (team_cost, optimal_cost) = (cost_of(&assignment), cost_of(&best));
    let optimal = covered && team_cost - optimal_cost <= 1e-9 * optimal_cost.abs().max(1.0);
    let certified = records.iter().all(|r| r[e].certified);
    let miss = (!optimal).then(|| {
        format!(
            "episode {e}: cost {team_cost:.6} vs optimum {optimal_cost:.6}{}{}",
            if covered { "" } else { ", a station uncovered" },
            if certified {
                ""
            } else {
                ", round limit reached before the certified stop"
            }
        )
    });
    let episode = Episode {
        episode: e,
        assignment,
        team_cost,
        optimal_cost,
        optimal,
        certified,
        rounds_warm: records[0][e].rounds,
        rounds_cold,
        batteries: records.iter().map(|r| r[e].battery).collect(),
    };
    Ok((episode, miss))
}

/// A short human summary.
fn render(report: &SurveillanceReport) -> String {
    let mut out = format!(
        "{} robots, {} surveillance + {} charging stations, {} episodes over {} ({} start), ρ = {:.3e}\n\
         optimal episodes: {}/{}\n\
         battery violations: {}\n\
         iterations per episode: {:.1} warm-started, {:.1} cold (same costs, fresh agents)\n\
         limit cycle of the total cost: {} ({} up to the tie-breaking preferences)\n\
         team wall time {:.0} ms, round p50 {:.0} µs, p99 {:.0} µs\n",
        report.robots,
        report.surveillance_stations,
        report.charging_stations,
        report.episodes,
        report.transport,
        if report.warm_start { "warm" } else { "cold" },
        report.rho,
        report.optimal_episodes,
        report.episodes,
        report.battery_violations,
        report.mean_iterations_warm,
        report.mean_iterations_cold,
        report
            .limit_cycle
            .map_or("none found".into(), |p| format!("period {p} episodes")),
        report
            .limit_cycle_roles
            .map_or("none".into(), |p| format!("period {p}")),
        report.wall_ms,
        report.round_p50_us,
        report.round_p99_us,
    );
    if let Some(path) = &report.critical_path {
        out += &format!(
            "critical path: {:.1}% of the agents' round time went to waiting for a late neighbour{}\n",
            100.0 * path.waiting_share,
            path.top.first().map_or(String::new(), |a| format!(
                ", most for agent {} ({:.1}%, the one most waited for in {} rounds)",
                a.agent,
                100.0 * a.waiting_share,
                a.rounds
            ))
        );
    }
    for miss in report.misses.iter().take(20) {
        out += &format!("  {miss}\n");
    }
    out
}

/// The plots: total cost over episodes as the paper's Fig. 3, its last 60 episodes, battery
/// levels.
fn charts(report: &SurveillanceReport) -> Vec<(String, OutputFile)> {
    let mut charts = Vec::new();
    let series = |from: usize| {
        let pts = |f: fn(&Episode) -> f64| {
            report.per_episode[from..]
                .iter()
                .map(|e| (e.episode as f64, f(e)))
                .collect()
        };
        (
            Series::new("ADMM-TA (team)", pts(|e| e.team_cost)),
            Series::new("Hungarian optimum", pts(|e| e.optimal_cost)).dashed(),
        )
    };
    let (team, optimum) = series(0);
    let chart = Chart::new(
        format!(
            "Fig. 3: total assignment cost per episode, {} robots, {} surveillance stations",
            report.robots, report.surveillance_stations
        ),
        "episode",
        "total cost",
    )
    .legend(Legend::UpperRight)
    .series(team)
    .series(optimum);
    charts.push(("surveillance-cost.svg".into(), OutputFile::Chart(chart)));
    let (team, optimum) = series(report.episodes.saturating_sub(60));
    let chart = Chart::new(
        "total cost over the last 60 episodes (the limit cycle)",
        "episode",
        "total cost",
    )
    .legend(Legend::UpperRight)
    .series(team)
    .series(optimum);
    charts.push((
        "surveillance-cost-last60.svg".into(),
        OutputFile::Chart(chart),
    ));
    let shown = report.episodes.min(100);
    let mut chart = Chart::new(
        format!("battery level per robot after each episode (first {shown})"),
        "episode",
        "battery",
    )
    .legend(Legend::LowerRight)
    .reference("reserve", report.mission.reserve);
    for i in 0..report.robots {
        let pts = report.per_episode[..shown]
            .iter()
            .map(|e| (e.episode as f64, e.batteries[i]))
            .collect();
        chart = chart.series(Series::new(format!("robot {i}"), pts));
    }
    charts.push(("surveillance-battery.svg".into(), OutputFile::Chart(chart)));
    charts
}

impl Experiment for SurveillanceReport {
    fn json_file(&self) -> &'static str {
        "surveillance.json"
    }

    fn render(&self) -> String {
        render(self)
    }

    fn files(&self) -> Vec<(String, OutputFile)> {
        charts(self)
    }
}
