//! How close the fast dual variant's certificate is to what any certificate could give on
//! its iterates (bench/README, "The dual methods, fourth pass"). Per seed it runs the team
//! in lockstep, records every round's rounded tasks, columns and multipliers, and replays
//! the recording under models of other certificates and decision rules (the certificate
//! never feeds back into the iteration, so a replay is exact):
//!
//! * `t0`: the first round from which the rounded assignment stays optimal; `floor` =
//!   `t0 + D`, the earliest any decentralized stop can certify it (the last change must
//!   cross the graph);
//! * `now`: the round every robot's certificate holds, plus the stop's `D` (= the solver's
//!   stop);
//! * `wave`: potentials restarted by a wave from every task change (a max-flooded round
//!   stamp) instead of at the snapshots' settles (Case 2; Case 1 never restarts), with the
//!   snapshots' claims as now; `wave*`: the same with the claims known at once;
//! * `free`: Case 2 priced as a square problem with one more column (the free slot, cost =
//!   a robot's cheapest task, holding the extra claimers), so potentials never restart;
//!   who is an extra claimer read from the settled snapshot, claims as now; `free°`: the
//!   same with the claims known at once; `free*`: roles and claims known at once;
//! * `aitken`, `prices`: `t0` of two decision rules (columns extrapolated by Aitken's Δ² over
//!   20 rounds; a fractional robot's top two tasks decided by its own multipliers).
//!
//! `RHO_SCALE=F` multiplies the default ρ, `HORIZON=R` records `R` rounds past the stop
//! (default `3D + 50`).
//! `cargo run --release -p admm-ta-runtime --example dual_certificate_floor -- ROBOTS TASKS TOPOLOGY uniform|distance FIRST-LAST`.
mod common;

use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::oracle;
use admm_ta_agents::method::settings::GivenSettings;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::{AssignmentCase, TaskAssignmentProblem};
use admm_ta_topologies::Graph;
use admm_ta_transport::sim::process::LockstepSim;
use common::Problems;

/// One run: per round (index 0 = before the first) every robot's task, column and
/// multipliers.
struct Recording {
    tasks: Vec<Vec<usize>>,
    columns: Vec<Vec<Vec<f64>>>,
    prices: Vec<Vec<Vec<f64>>>,
    /// First round every certificate held.
    now: Option<usize>,
}

/// The problem as the models see it.
struct Instance<'a> {
    problem: &'a TaskAssignmentProblem,
    graph: &'a Graph,
    optimum: f64,
    diameter: usize,
    /// Per-robot slack the stop allows, and the relaxation threshold.
    tol: f64,
    eps: f64,
}

impl Instance<'_> {
    fn robots(&self) -> usize {
        self.problem.costs().robots()
    }
    fn tasks(&self) -> usize {
        self.problem.costs().tasks()
    }
    fn case(&self) -> AssignmentCase {
        self.problem.case()
    }
    /// Robot `i`'s costs.
    fn row(&self, i: usize) -> &[f64] {
        self.problem.costs().row(i)
    }
    fn allowed(&self, i: usize, t: usize) -> bool {
        self.problem.costs().is_allowed(i, t)
    }
    fn optimal(&self, decisions: &[usize]) -> bool {
        self.problem.is_feasible(decisions)
            && self.problem.cost_of(decisions).unwrap() <= self.optimum + 1e-9
    }
    fn cheapest(&self, i: usize) -> f64 {
        let row = self.row(i);
        (0..row.len())
            .filter(|&t| self.allowed(i, t))
            .map(|t| row[t])
            .fold(f64::INFINITY, f64::min)
    }
    /// The smallest claimer of every task, if the claims cover it (once in Case 1).
    fn first_claimers(&self, pi: &[usize]) -> Option<Vec<usize>> {
        let mut first = vec![usize::MAX; self.tasks()];
        let mut count = vec![0; self.tasks()];
        for (i, &t) in pi.iter().enumerate() {
            first[t] = first[t].min(i);
            count[t] += 1;
        }
        let once = self.case() != AssignmentCase::Two;
        (count.iter().all(|&c| c > 0) && !(once && count.iter().any(|&c| c > 1))).then_some(first)
    }
}

/// The solver's default round limit.
const MAX_ROUNDS: usize = 5000;

/// Runs the team until every certificate held, and `horizon` rounds more (at most
/// [`MAX_ROUNDS`]).
fn run<A: ConsensusAgent + Send>(
    mut sim: LockstepSim<A>,
    inst: &Instance,
    horizon: usize,
) -> Recording {
    let (n, m) = (inst.robots(), inst.tasks());
    let mut rec = Recording {
        tasks: vec![vec![usize::MAX; n]],
        columns: vec![vec![vec![0.0; m]; n]],
        prices: vec![vec![vec![0.0; m]; n]],
        now: None,
    };
    for round in 1..=MAX_ROUNDS {
        sim.step_round();
        let agents = sim.agents();
        rec.tasks.push(agents.iter().map(|a| a.decide()).collect());
        rec.columns
            .push(agents.iter().map(|a| a.own_column().to_vec()).collect());
        rec.prices
            .push((0..n).map(|i| sim.payload(i)[..m].to_vec()).collect());
        if rec.now.is_none() && agents.iter().all(|a| a.certificate_slack() <= inst.tol) {
            rec.now = Some(round);
        }
        if rec.now.is_some_and(|r| round >= r + horizon) {
            break;
        }
    }
    rec
}

/// Whether the snapshot settled at round `r` (claims of the start `P = D` rounds before
/// the last start) holds the tasks of round `r`.
fn snapshot_holds(rec: &Recording, r: usize, diameter: usize) -> bool {
    let (period, step) = (diameter.max(1), r - 1);
    step / period >= 1 && {
        let claimed = period * (step / period - 1) + 1;
        (claimed..=r).all(|q| rec.tasks[q] == rec.tasks[r])
    }
}

/// The first round from which `decisions` stay optimal (NaN: never).
fn optimal_from(inst: &Instance, decisions: &[Vec<usize>]) -> f64 {
    let mut since = None;
    for (r, d) in decisions.iter().enumerate().skip(1) {
        if inst.optimal(d) {
            since.get_or_insert(r);
        } else {
            since = None;
        }
    }
    since.map_or(f64::NAN, |r| r as f64)
}

/// One round of the potentials' min-flood: robot `i`'s vector `own` merged with its
/// neighbours' of the round before (those in `same` only).
fn merged(
    inst: &Instance,
    own: Vec<f64>,
    prev: &[Vec<f64>],
    i: usize,
    same: impl Fn(usize) -> bool,
) -> (Vec<f64>, bool) {
    let mut p = own;
    let mut all = true;
    for &j in inst.graph.neighbours(i) {
        if same(j) {
            for (mine, theirs) in p.iter_mut().zip(&prev[j]) {
                *mine = mine.min(*theirs);
            }
        } else {
            all = false;
        }
    }
    (p, all)
}

/// Lowers `p[task]` to `bound` when it is more than ε below.
fn relax(p: &mut [f64], task: usize, bound: f64, eps: f64) {
    if bound < p[task] - eps {
        p[task] = bound;
    }
}

/// Per round: does every robot's certificate hold (claims known at once) with potentials
/// restarted by a wave from every task change (Case 2)?
fn wave_potentials(inst: &Instance, rec: &Recording) -> Vec<bool> {
    let (n, m) = (inst.robots(), inst.tasks());
    let restarts = inst.case() == AssignmentCase::Two;
    let mut pot = vec![vec![0.0; m]; n];
    let mut epoch = vec![0usize; n];
    let mut ok = vec![false];
    for r in 1..rec.tasks.len() {
        let (prev, prev_epoch) = (pot.clone(), epoch.clone());
        let mut stable = true;
        for i in 0..n {
            let task = rec.tasks[r][i];
            let mut e = prev_epoch[i];
            if restarts && r >= 2 && task != rec.tasks[r - 1][i] {
                e = r;
            }
            e = inst
                .graph
                .neighbours(i)
                .iter()
                .fold(e, |e, &j| e.max(prev_epoch[j]));
            let restarted = e != prev_epoch[i];
            let own = if restarted {
                vec![0.0; m]
            } else {
                prev[i].clone()
            };
            let (mut p, all) = merged(inst, own, &prev, i, |j| prev_epoch[j] == e);
            let row = inst.row(i);
            let best = (0..m)
                .filter(|&t| inst.allowed(i, t) && t != task)
                .map(|t| p[t] + row[t] - row[task])
                .fold(f64::INFINITY, f64::min);
            relax(&mut p, task, best, inst.eps);
            stable &= all && !restarted && p == prev[i];
            pot[i] = p;
            epoch[i] = e;
        }
        ok.push(stable && prices_claims(inst, &rec.tasks[r], &pot[0], None));
    }
    ok
}

/// Where the free-slot model learns who is an extra claimer.
#[derive(Clone, Copy, PartialEq)]
enum Roles {
    /// From the current tasks (an oracle).
    Known,
    /// From the last settled snapshot.
    Snapshot,
}

/// Per round: does every robot's certificate hold (claims known at once) with Case 2 priced
/// as a square problem plus a free slot (potential `m`), never restarted?
fn free_slot_potentials(inst: &Instance, rec: &Recording, roles: Roles) -> Vec<bool> {
    let (n, m, d) = (inst.robots(), inst.tasks(), inst.diameter.max(1));
    if inst.case() != AssignmentCase::Two {
        return wave_potentials(inst, rec);
    }
    let mut pot = vec![vec![0.0; m + 1]; n];
    let mut ok = vec![false];
    for r in 1..rec.tasks.len() {
        let prev = pot.clone();
        let mut stable = true;
        for i in 0..n {
            let (mut p, _) = merged(inst, prev[i].clone(), &prev, i, |_| true);
            let (row, task, cheapest) = (inst.row(i), rec.tasks[r][i], inst.cheapest(i));
            let other = (0..m)
                .filter(|&t| inst.allowed(i, t) && t != task)
                .map(|t| p[t] + row[t])
                .fold(f64::INFINITY, f64::min);
            let bound = other.min(p[m] + cheapest) - row[task];
            relax(&mut p, task, bound, inst.eps);
            let extra = match roles {
                Roles::Known => (0..i).any(|j| rec.tasks[r][j] == task),
                Roles::Snapshot => {
                    let step = r - 1;
                    step / d >= 1 && {
                        let claims = &rec.tasks[d * (step / d - 1) + 1];
                        claims[i] == task && (0..i).any(|j| claims[j] == task)
                    }
                }
            };
            if extra {
                let bound = other.min(p[task] + row[task]) - cheapest;
                relax(&mut p, m, bound, inst.eps);
            }
            stable &= p == prev[i];
            pot[i] = p;
        }
        ok.push(stable && prices_claims(inst, &rec.tasks[r], &pot[0], Some(m)));
    }
    ok
}

/// Whether common potentials `y` price the claims `pi` within every robot's tolerance
/// (`free`: the free slot's index, else Case 2's extra claimers pay `λ = −y`).
fn prices_claims(inst: &Instance, pi: &[usize], y: &[f64], free: Option<usize>) -> bool {
    let Some(first) = inst.first_claimers(pi) else {
        return false;
    };
    let fine = (0..inst.robots()).all(|i| {
        let (row, t) = (inst.row(i), pi[i]);
        let mut best = (0..inst.tasks())
            .filter(|&s| inst.allowed(i, s))
            .map(|s| row[s] + y[s])
            .fold(f64::INFINITY, f64::min);
        let extra = first[t] != i;
        let own = match free {
            Some(f) => {
                best = best.min(inst.cheapest(i) + y[f]);
                if extra {
                    row[t] + y[f] - best
                } else {
                    row[t] + y[t] - best
                }
            }
            // An extra claimer also pays its task's `λ = −y`.
            None if extra => row[t] - best,
            None => row[t] + y[t] - best,
        };
        own <= inst.tol
    });
    if fine {
        assert!(
            inst.optimal(pi),
            "a model certified a non-optimal assignment"
        );
    }
    fine
}

/// Decision rules tried instead of the rounded column.
#[derive(Clone, Copy)]
enum Rule {
    /// Each column entry extrapolated by Aitken's Δ² over rounds `r − 2W, r − W, r`.
    Aitken(usize),
    /// A robot whose largest entry is below the threshold takes the cheaper of its top two
    /// tasks at its own multipliers.
    Prices(f64),
}

fn decide(inst: &Instance, rec: &Recording, rule: Rule) -> Vec<Vec<usize>> {
    let (n, m) = (inst.robots(), inst.tasks());
    let argmax = |i: usize, x: &[f64]| {
        (0..m)
            .filter(|&t| inst.allowed(i, t))
            .max_by(|&a, &b| x[a].total_cmp(&x[b]))
            .unwrap()
    };
    (0..rec.tasks.len())
        .map(|r| {
            (0..n)
                .map(|i| {
                    let x = &rec.columns[r][i];
                    match rule {
                        Rule::Aitken(w) if r > 2 * w => {
                            let (a, b) = (&rec.columns[r - w][i], &rec.columns[r - 2 * w][i]);
                            let xe: Vec<f64> = (0..m)
                                .map(|t| {
                                    let (d1, d0) = (x[t] - a[t], a[t] - b[t]);
                                    let ratio = d1 / d0;
                                    if (d1 - d0).abs() > 1e-12 && ratio > 0.0 && ratio < 1.0 {
                                        x[t] - d1 * d1 / (d1 - d0)
                                    } else {
                                        x[t]
                                    }
                                })
                                .collect();
                            argmax(i, &xe)
                        }
                        Rule::Prices(threshold)
                            if x.iter().fold(0.0f64, |a, &b| a.max(b)) < threshold =>
                        {
                            let y = &rec.prices[r][i];
                            let sign = if inst.case() == AssignmentCase::Two {
                                -1.0
                            } else {
                                1.0
                            };
                            let reduced = |t: usize| inst.row(i)[t] + sign * y[t];
                            let mut top: Vec<usize> =
                                (0..m).filter(|&t| inst.allowed(i, t)).collect();
                            top.sort_by(|&a, &b| x[b].total_cmp(&x[a]));
                            top.truncate(2);
                            top.into_iter()
                                .min_by(|&a, &b| reduced(a).total_cmp(&reduced(b)))
                                .unwrap()
                        }
                        _ => argmax(i, x),
                    }
                })
                .collect()
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let problems = Problems::from_args(&args);
    let n = problems.robots;
    let (first, last) = args[5].split_once('-').unwrap_or((&args[5], &args[5]));
    let seeds = first.parse::<u64>().unwrap()..=last.parse::<u64>().unwrap();
    let rho_scale: f64 = std::env::var("RHO_SCALE").map_or(1.0, |v| v.parse().unwrap());
    let names = [
        "t0", "floor", "now", "wave", "wave*", "free", "free°", "free*", "aitken", "prices",
    ];
    let mut table: Vec<Vec<f64>> = Vec::new();
    println!("seed {}", names.join(" "));
    for seed in seeds {
        let (problem, graph) = problems.instance(seed);
        let diameter = graph.diameter().unwrap();
        let setup = Method::Dual
            .setup(&GivenSettings::default())
            .unwrap()
            .unwrap();
        let rho = setup
            .default_rho(problem.costs(), graph.mean_degree())
            .unwrap()
            * rho_scale;
        let params = common::params(&problem, &graph, rho);
        let inst = Instance {
            problem: &problem,
            graph: &graph,
            optimum: oracle::solve(&problem).unwrap().cost,
            diameter,
            tol: params.tolerance / n as f64,
            eps: params.tolerance / (10.0 * n as f64),
        };
        let agents = common::agents(setup.as_ref(), &problem, &graph, params);
        let horizon = std::env::var("HORIZON").map_or(3 * diameter + 50, |v| v.parse().unwrap());
        let rec = run(LockstepSim::new(agents, &graph), &inst, horizon);
        let stop = |ok: &[bool], from_snapshot: bool| {
            (1..ok.len())
                .find(|&r| ok[r] && (!from_snapshot || snapshot_holds(&rec, r, diameter)))
                .map_or(f64::NAN, |r| (r + diameter) as f64)
        };
        let wave = wave_potentials(&inst, &rec);
        let free = free_slot_potentials(&inst, &rec, Roles::Snapshot);
        let t0 = optimal_from(&inst, &rec.tasks);
        let row = vec![
            t0,
            t0 + diameter as f64,
            rec.now.map_or(f64::NAN, |r| (r + diameter) as f64),
            stop(&wave, true),
            stop(&wave, false),
            stop(&free, true),
            stop(&free, false),
            stop(&free_slot_potentials(&inst, &rec, Roles::Known), false),
            optimal_from(&inst, &decide(&inst, &rec, Rule::Aitken(20))),
            optimal_from(&inst, &decide(&inst, &rec, Rule::Prices(0.7))),
        ];
        println!("{seed} {}", cells(&row));
        table.push(row);
    }
    let medians: Vec<f64> = (0..names.len())
        .map(|k| {
            let mut v: Vec<f64> = table.iter().map(|r| r[k]).collect();
            v.sort_by(f64::total_cmp);
            let l = v.len();
            if l % 2 == 1 {
                v[l / 2]
            } else {
                (v[l / 2 - 1] + v[l / 2]) / 2.0
            }
        })
        .collect();
    println!("median {}", cells(&medians));
}

fn cells(row: &[f64]) -> String {
    row.iter()
        .map(|v| format!("{v}"))
        .collect::<Vec<_>>()
        .join(" ")
}
