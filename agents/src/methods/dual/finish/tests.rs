//! The finish's unit tests: robots on a path graph run it from frozen claims and are
//! checked against a brute-force optimum; robots on a complete graph observe snapshots
//! and freeze their claims.
//!
//! Size: one protocol's tests, sharing two harnesses (message rounds on a path graph, and
//! snapshots settling on a complete graph) and a brute-force oracle.

use super::*;
use admm_ta_topologies::rng::SeededRng;

/// A robot's claim after a step, and whether it still labels.
type Step = (Option<usize>, bool);

/// The robots of a path graph `0 − 1 − … − (n−1)` run the finish on `claims` frozen at
/// step 0 (each robot's task in `tasks`) with their `costs`, for at most `limit` steps.
/// Returns per step every robot's claim and whether it still labels, and the robots.
fn run(costs: &[Vec<f64>], tasks: &[usize], limit: u64) -> (Vec<Vec<Step>>, Vec<Finish>) {
    let run = run_refrozen(costs, tasks, None, limit);
    (run.trace, run.robots)
}

/// A run of the finish: per step every robot's claim and whether it still labels, the
/// robots, how many labels robot 0 kept at a second freeze (reached, at a task not
/// unclaimed), and per step the paths robot 0 had moved.
struct Run {
    trace: Vec<Vec<Step>>,
    robots: Vec<Finish>,
    kept: usize,
    paths: Vec<u64>,
    /// Labels robot 0 capped at the bound, over all its batches.
    capped: usize,
    /// Bounded batches that settled with two excess robots on one task.
    crowded: usize,
}

/// Per task its smallest claimer's code (0: none) when robot `i` claims `tasks[i]`.
fn claims_of(tasks: &[usize]) -> Vec<u64> {
    let mut claims = vec![0u64; tasks.len()];
    for (i, &t) in tasks.iter().enumerate().rev() {
        claims[t] = i as u64 + 1;
    }
    claims
}

/// As [`run`], and at step `at` every robot freezes the claims of `then` (its rounded
/// task from there on) in place of the first.
fn run_refrozen(
    costs: &[Vec<f64>],
    tasks: &[usize],
    refreeze: Option<(u64, &[usize])>,
    limit: u64,
) -> Run {
    let n = costs.len();
    let claims = claims_of(tasks);
    let mut robots: Vec<Finish> = (0..n)
        .map(|i| Finish::new(i, n, n, AssignmentCase::One, n - 1, 1e-12))
        .collect();
    // A robot's moves (the potentials' place) and its section.
    let mut sections = vec![vec![0.0; n + words(n, n)]; n];
    for (i, robot) in robots.iter_mut().enumerate() {
        assert!(robot.runs());
        robot.freeze(0, &claims, Some(tasks[i]));
        let (labels, section) = sections[i].split_at_mut(n);
        robot.write(labels, section);
    }
    let allowed = vec![true; n];
    let (mut trace, mut kept, mut paths, mut capped) = (Vec::new(), 0, Vec::new(), 0);
    let mut crowded = 0;
    let mut tasks = tasks;
    for step in 1..=limit {
        let gathered = sections.clone();
        let mut round = Vec::new();
        for (i, robot) in robots.iter_mut().enumerate() {
            robot.begin();
            for j in [i.wrapping_sub(1), i + 1] {
                if j < n {
                    let (labels, section) = gathered[j].split_at(n);
                    assert!(labels.iter().all(|v| v.is_finite()));
                    assert_eq!(robot.check(section), Ok(()));
                    robot.merge(labels, section);
                }
            }
            let claim = robot.claim(step, Some(tasks[i]), &costs[i], &allowed);
            if i == 0 && robot.phase_settled_at(step) {
                capped += (0..n).filter(|&t| robot.capped(t)).count();
            }
            potentials_hold(robot, step, &costs[i], i);
            if robot.moved {
                let prices = robot.prices().unwrap_or_else(|| {
                    panic!("a full assignment is priced: {:?} {tasks:?}", robot.labels)
                });
                let reduced = |t: usize| costs[i][t] + prices[t];
                let best = (0..n).map(reduced).fold(f64::INFINITY, f64::min);
                assert!(reduced(claim.unwrap()) <= best + 1e-9, "robot {i}");
            }
            if let Some((at, then)) = refreeze.filter(|&(at, _)| at == step) {
                robot.freeze(at, &claims_of(then), Some(then[i]));
                if i == 0 {
                    let reached = robot.labels.iter().zip(&robot.frozen);
                    kept = reached.filter(|&(&l, &c)| l != UNREACHED && c != 0).count();
                }
            }
            let (labels, section) = sections[i].split_at_mut(n);
            robot.write(labels, section);
            round.push((claim, robot.labelling()));
        }
        if let Some((_, then)) = refreeze.filter(|&(at, _)| at == step) {
            tasks = then;
        }
        // Every robot is in the same phase with the same frozen claims after every step.
        for robot in &robots[1..] {
            assert_eq!(robot.labelling(), robots[0].labelling(), "step {step}");
            assert_eq!(robot.frozen, robots[0].frozen, "step {step}");
        }
        trace.push(round);
        paths.push(robots[0].paths());
        crowded += usize::from(two_excess_on_one_task(&robots, step));
    }
    Run {
        trace,
        robots,
        kept,
        paths,
        capped,
        crowded,
    }
}

/// Whether the labels settled at `step` in a bounded batch with two excess robots
/// claiming one task.
fn two_excess_on_one_task(robots: &[Finish], step: u64) -> bool {
    if !robots[0].phase_settled_at(step) || robots[0].base.iter().any(|b| b.is_infinite()) {
        return false;
    }
    let mut excess = vec![0; robots.len()];
    for robot in robots.iter().filter(|r| !r.owner) {
        if let Phase::Labelling { task: Some(s), .. } = robot.phase {
            excess[s] += 1;
        }
    }
    excess.contains(&2)
}

impl Finish {
    /// Whether the labels settled at `step`.
    fn phase_settled_at(&self, step: u64) -> bool {
        matches!(self.phase, Phase::Labelling { settled: Some(at), .. } if at == step)
    }
}

/// Right after a move that left tasks unclaimed, the labels moved along (capped at the
/// bound) are potentials: an owner's task is its cheapest under them, and an excess robot
/// notes its cheapest value as its entry's base.
fn potentials_hold(robot: &Finish, step: u64, costs: &[f64], i: usize) {
    let Phase::Labelling { since, task, .. } = robot.phase else {
        return;
    };
    if since != step || robot.base.iter().any(|b| b.is_infinite()) {
        return;
    }
    let priced = |t: usize| costs[t] + robot.base[t];
    let cheapest = (0..costs.len()).map(priced).fold(f64::INFINITY, f64::min);
    let s = task.expect("every robot claims a task");
    if robot.owner {
        // Within ε (1e-12) however many batches capped labels.
        assert!(priced(s) <= cheapest + 2e-12, "robot {i}: {:?}", robot.base);
        assert_eq!(robot.entry_base, None);
    } else {
        assert_eq!(robot.entry_base, Some(cheapest), "robot {i}");
    }
}

/// The cheapest assignment of `robots` to distinct `tasks` (brute force).
fn cheapest(costs: &[Vec<f64>], robots: &[usize], tasks: &[usize]) -> (f64, Vec<usize>) {
    fn go(
        costs: &[Vec<f64>],
        robots: &[usize],
        free: &mut Vec<usize>,
        chosen: &mut Vec<usize>,
        best: &mut (f64, Vec<usize>),
    ) {
        if chosen.len() == robots.len() {
            let cost = robots
                .iter()
                .zip(chosen.iter())
                .map(|(&r, &t)| costs[r][t])
                .sum();
            if cost < best.0 {
                *best = (cost, chosen.clone());
            }
            return;
        }
        for k in 0..free.len() {
            let t = free.remove(k);
            chosen.push(t);
            go(costs, robots, free, chosen, best);
            chosen.pop();
            free.insert(k, t);
        }
    }
    let mut best = (f64::INFINITY, Vec::new());
    go(
        costs,
        robots,
        &mut tasks.to_vec(),
        &mut Vec::new(),
        &mut best,
    );
    best
}

/// Trial `trial`'s costs and claims: the cheapest for all robots but one or two (excess
/// robots, each claiming a task beside a smaller owner) and all tasks but as many.
/// `None` where an excess robot has no smaller owner.
fn instance(rng: &mut SeededRng, trial: usize) -> Option<(Vec<Vec<f64>>, Vec<usize>)> {
    let n = 2 + trial % 5;
    let costs: Vec<Vec<f64>> = (0..n)
        .map(|_| (0..n).map(|_| rng.uniform()).collect())
        .collect();
    // k excess robots (the last k of a rotation) and k unclaimed tasks.
    let k = if n >= 4 { 1 + trial % 2 } else { 1 };
    let excess: Vec<usize> = (0..k).map(|j| (trial + n - 1 - j) % n).collect();
    let unclaimed: Vec<usize> = (0..k).map(|j| (trial / 3 + j) % n).collect();
    let robots: Vec<usize> = (0..n).filter(|r| !excess.contains(r)).collect();
    let free: Vec<usize> = (0..n).filter(|t| !unclaimed.contains(t)).collect();
    let (_, matched) = cheapest(&costs, &robots, &free);
    let mut tasks = vec![0; n];
    for (&r, &t) in robots.iter().zip(&matched) {
        tasks[r] = t;
    }
    // Each excess robot claims a task beside a smaller owner: the owners are the
    // matched robots.
    for &e in &excess {
        let beside: Vec<usize> = robots
            .iter()
            .filter(|&&r| r < e)
            .map(|&r| tasks[r])
            .collect();
        tasks[e] = *beside.get(trial % beside.len().max(1))?;
    }
    Some((costs, tasks))
}

/// The robots all stop labelling at one step, at which they claim an optimal
/// assignment; returns that step.
fn moved_to_the_optimum(trace: &[Vec<Step>], costs: &[Vec<f64>], trial: usize) -> usize {
    let n = costs.len();
    let moved = trace
        .iter()
        .position(|round| round.iter().any(|&(_, labelling)| !labelling))
        .unwrap_or_else(|| panic!("trial {trial}: the labels never settle: {costs:?}"));
    assert!(
        trace[moved].iter().all(|&(_, l)| !l),
        "trial {trial}: one step"
    );
    let after: Vec<usize> = trace[moved].iter().map(|&(c, _)| c.unwrap()).collect();
    let mut sorted = after.clone();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        (0..n).collect::<Vec<_>>(),
        "trial {trial}: {after:?}"
    );
    let cost: f64 = after.iter().enumerate().map(|(i, &t)| costs[i][t]).sum();
    let all: Vec<usize> = (0..n).collect();
    let (optimum, _) = cheapest(costs, &all, &all);
    assert!(
        (cost - optimum).abs() < 1e-9,
        "trial {trial}: {cost} > {optimum}"
    );
    moved
}

/// Claims that are the cheapest for all robots but one or two (excess robots, each
/// claiming a task beside a smaller owner) and all tasks but as many: the settled
/// labels move every robot at one step to the optimal assignment (successive shortest
/// paths, one batch of paths or two), with prices that price every robot's new task as
/// its cheapest.
#[test]
fn settled_labels_move_to_the_optimum_at_one_step() {
    let mut rng = SeededRng::new(11);
    let mut tried = 0;
    for trial in 0..300 {
        let Some((costs, tasks)) = instance(&mut rng, trial) else {
            continue;
        };
        tried += 1;
        let (trace, _) = run(&costs, &tasks, 40 * costs.len() as u64);
        moved_to_the_optimum(&trace, &costs, trial);
    }
    assert!(tried > 150, "{tried} trials");
}

/// Batches after a move compute only the labels up to the bound: some labels are capped,
/// the capped labels are potentials still (checked at every move), and the robots still
/// move to the optimum.
#[test]
fn labels_above_the_bound_are_capped_and_the_optimum_is_reached() {
    let mut rng = SeededRng::new(13);
    let (mut tried, mut capped) = (0, 0);
    for trial in 0..600 {
        let Some((costs, tasks)) = instance(&mut rng, trial) else {
            continue;
        };
        let n = costs.len() as u64;
        let run = run_refrozen(&costs, &tasks, None, 40 * n);
        let Some(first_move) = run.paths.iter().position(|&p| p > 0) else {
            panic!("trial {trial}: no path moved");
        };
        // Only runs of two batches have a base.
        if !run.trace[first_move][0].1 {
            continue;
        }
        tried += 1;
        moved_to_the_optimum(&run.trace[first_move + 1..], &costs, trial);
        capped += usize::from(run.capped > 0);
    }
    assert!(
        tried > 100 && capped > 50,
        "{tried} two-batch trials, {capped} capped"
    );
}

/// Claims cheapest for all robots but three excess robots, all claiming the task of the
/// smallest owner, and all tasks but three: after a first batch moves one path two
/// excess robots may claim one task in a bounded batch. `None` where an excess robot is
/// smaller than every owner.
fn crowded(rng: &mut SeededRng, trial: usize) -> Option<(Vec<Vec<f64>>, Vec<usize>)> {
    let n = 5 + trial % 3;
    let costs: Vec<Vec<f64>> = (0..n)
        .map(|_| (0..n).map(|_| rng.uniform()).collect())
        .collect();
    let excess: Vec<usize> = (0..3).map(|j| (trial + n - 1 - j) % n).collect();
    let unclaimed: Vec<usize> = (0..3).map(|j| (trial / 3 + j) % n).collect();
    let robots: Vec<usize> = (0..n).filter(|r| !excess.contains(r)).collect();
    let free: Vec<usize> = (0..n).filter(|t| !unclaimed.contains(t)).collect();
    let (_, matched) = cheapest(&costs, &robots, &free);
    let mut tasks = vec![0; n];
    for (&r, &t) in robots.iter().zip(&matched) {
        tasks[r] = t;
    }
    if excess.iter().any(|&e| e < robots[0]) {
        return None;
    }
    for &e in &excess {
        tasks[e] = tasks[robots[0]];
    }
    Some((costs, tasks))
}

/// Two excess robots claiming one task in a bounded batch: the one whose entry rose more
/// than the bound names no entry at a capped label (its smaller code would hide the
/// other's path, and the finish would give up), and the robots reach the optimum.
#[test]
fn an_excess_robot_at_a_capped_label_hides_no_path() {
    let mut rng = SeededRng::new(14);
    let (mut tried, mut crowded_batches) = (0, 0);
    for trial in 0..400 {
        let Some((costs, tasks)) = crowded(&mut rng, trial) else {
            continue;
        };
        let n = costs.len() as u64;
        let run = run_refrozen(&costs, &tasks, None, 60 * n);
        tried += 1;
        crowded_batches += run.crowded;
        let last = run
            .trace
            .iter()
            .rposition(|round| round.iter().any(|&(_, l)| l));
        let done = last.expect("the robots label from step 1") + 1;
        assert!(done < run.trace.len(), "trial {trial}: still labelling");
        moved_to_the_optimum(&run.trace[done - 1..], &costs, trial);
    }
    assert!(
        tried > 100 && crowded_batches > 100,
        "{tried} trials, {crowded_batches} crowded"
    );
}

/// Every robot of `a` holds the labels of its robot in `b`.
fn same_labels(a: &[Finish], b: &[Finish], trial: usize) {
    for (a, b) in a.iter().zip(b) {
        let same = a.labels.iter().zip(&b.labels);
        assert!(
            same.clone().all(|(a, b)| (a - b).abs() < 1e-9),
            "trial {trial}: {:?} against {:?}",
            a.labels,
            b.labels
        );
    }
}

/// The claims of `tasks` with other owners: on even trials two robots of different tasks
/// swapped, on odd ones a task's only claimer claiming another robot's task instead (so
/// the claims frozen after these claim one task more). `None` where no robot can.
fn other_owners(tasks: &[usize], trial: usize) -> Option<Vec<usize>> {
    let n = tasks.len();
    let claimers = |t: usize| tasks.iter().filter(|&&u| u == t).count();
    let a = (0..n)
        .map(|k| (trial + k) % n)
        .find(|&a| trial.is_multiple_of(2) || claimers(tasks[a]) == 1)?;
    let b = (1..n)
        .map(|k| (a + k) % n)
        .find(|&b| tasks[b] != tasks[a])?;
    let mut first = tasks.to_vec();
    if trial.is_multiple_of(2) {
        first.swap(a, b);
    } else {
        first[a] = tasks[b];
    }
    Some(first)
}

/// Claims frozen in place of claims still labelling (two owners swapped, or one task more
/// claimed) keep the labels whose paths are still there, and the robots still move at one
/// step to the optimum, with the labels a fresh start settles on.
#[test]
fn claims_frozen_anew_keep_the_paths_still_there() {
    let mut rng = SeededRng::new(12);
    let (mut tried, mut kept, mut two_batches) = (0, [0, 0], 0);
    let mut steps = [0, 0];
    for trial in 0..300 {
        let Some((costs, tasks)) = instance(&mut rng, trial) else {
            continue;
        };
        let n = costs.len();
        let Some(first) = other_owners(&tasks, trial) else {
            continue;
        };
        assert_ne!(claims_of(&first), claims_of(&tasks));
        let at = 1 + (trial % (2 * n)) as u64;
        let limit = 60 * n as u64;
        let refrozen = run_refrozen(&costs, &first, Some((at, &tasks)), limit);
        let moved = moved_to_the_optimum(&refrozen.trace[at as usize..], &costs, trial);
        let fresh = run_refrozen(&costs, &tasks, None, limit);
        let fresh_moved = moved_to_the_optimum(&fresh.trace, &costs, trial);
        // Labels kept are upper bounds: they fall no later than unreached ones.
        steps[0] += moved;
        steps[1] += fresh_moved;
        same_labels(&refrozen.robots, &fresh.robots, trial);
        tried += 1;
        kept[trial % 2] += usize::from(refrozen.kept > 0);
        // Two batches: the first batch's claims frozen again after it moved a path,
        // where the moved owners are known only from the paths traced.
        let Some(first_move) = fresh.paths.iter().position(|&p| p > 0) else {
            continue;
        };
        if !fresh.trace[first_move][0].1 {
            continue;
        }
        let at = first_move as u64 + 2;
        let again = run_refrozen(&costs, &tasks, Some((at, &tasks)), limit);
        moved_to_the_optimum(&again.trace[at as usize..], &costs, trial);
        same_labels(&again.robots, &fresh.robots, trial);
        two_batches += 1;
    }
    assert!(two_batches > 20, "{two_batches} two-batch trials");
    // Labels kept are upper bounds: in all the runs they settle no later than unreached
    // ones (not in each: labels follow the moves the robots take up, and which moves a
    // robot holds when changes order the labels' fall differently: 1 trial of 195 took
    // 21 steps against 19).
    assert!(
        steps[0] <= steps[1],
        "kept {} > fresh {} steps",
        steps[0],
        steps[1]
    );
    // Labels kept after swaps and after a task more claimed.
    assert!(
        tried > 150 && kept[0] > 5 && kept[1] > 15,
        "{tried} trials, {kept:?} kept labels"
    );
}

/// Claims with a negative cycle (robots 0 and 1 each on the other's cheap task): a robot
/// finds the cycle in the tags, the alarm reaches every robot, the cycle floods, and all
/// move its owners round it at one step (their claims stay the rounded ones meanwhile);
/// then excess robot 2's path fills task 2, at the optimum, priced (the harness checks
/// the prices).
#[test]
fn a_negative_cycle_is_cancelled_and_the_optimum_reached() {
    let costs = vec![
        vec![0.0, 5.0, 9.0],
        vec![5.0, 0.0, 9.0],
        vec![9.0, 9.0, 9.0],
    ];
    let tasks = [1, 0, 0];
    let (trace, robots) = run(&costs, &tasks, 60);
    let moved = moved_to_the_optimum(&trace, &costs, 0);
    assert!(moved < 30, "after {moved} steps");
    assert_eq!(
        trace[moved],
        vec![(Some(0), false), (Some(1), false), (Some(2), false)]
    );
    assert!(trace[..moved].iter().flatten().all(|&s| s.1));
    for (i, round) in trace[..moved].iter().enumerate() {
        let claims: Vec<_> = round.iter().map(|&(c, _)| c).collect();
        assert_eq!(claims, [Some(1), Some(0), Some(0)], "step {}", i + 1);
    }
    assert!(robots.iter().all(|r| r.cycles() == 1 && r.paths() == 1));
}

/// Any frozen claims reach the optimum, every robot cancelling the same cycles: claims of
/// random tasks (tasks claimed twice, tasks claimed by nobody, owners on negative cycles)
/// have their cycles cancelled until the labels settle, and the paths then fill the
/// unclaimed tasks; a random full assignment (rooted labels) has its cycles cancelled
/// until the labels settle, and they price it.
#[test]
fn any_frozen_claims_reach_the_optimum() {
    let mut rng = SeededRng::new(11);
    let (mut trials, mut cancelled) = ([0; 2], [0; 2]);
    for trial in 0..400 {
        let n = 3 + trial % 5;
        let costs: Vec<Vec<f64>> = (0..n)
            .map(|_| (0..n).map(|_| rng.uniform()).collect())
            .collect();
        let full = trial % 2;
        let mut tasks: Vec<usize> = (0..n).map(|_| rng.below(n)).collect();
        if full == 1 {
            tasks = (0..n).collect();
            for k in (1..n).rev() {
                tasks.swap(k, rng.below(k + 1));
            }
        } else if claims_of(&tasks).iter().all(|&c| c != 0) {
            continue;
        }
        let (trace, robots) = run(&costs, &tasks, 800);
        moved_to_the_optimum(&trace, &costs, trial);
        // They claim what the finish moved them to (rooted: what its labels priced).
        assert!(
            robots
                .iter()
                .all(|r| matches!(r.phase, Phase::Claiming { .. })),
            "trial {trial}"
        );
        let cycles = robots[0].cycles();
        assert!(robots.iter().all(|r| r.cycles() == cycles), "trial {trial}");
        trials[full] += 1;
        cancelled[full] += usize::from(cycles > 0);
    }
    assert!(
        trials[0] > 150 && trials[1] == 200 && cancelled[0] > 100 && cancelled[1] > 150,
        "{trials:?} trials (partial, full), {cancelled:?} with cycles"
    );
}

/// Labels that fall with no robot noticing are given up at the budget; the robots claim
/// their rounded tasks again.
#[test]
fn a_freeze_is_given_up_at_its_budget() {
    let costs = [[0.0, 5.0, 9.0], [5.0, 0.0, 9.0], [9.0, 9.0, 9.0]];
    let snapshot = Snapshot::new(0, 3, 3, AssignmentCase::One, 2, 1e-12);
    let claims = [2, 1, 0];
    let budget = LABEL_PERIODS * 2;
    for (i, cost) in costs.iter().enumerate() {
        let mut robot = Finish::new(i, 3, 3, AssignmentCase::One, 2, 1e-12);
        robot.freeze(0, &claims, Some([1, 0, 0][i]));
        robot.observe(budget - 1, &snapshot);
        assert!(robot.labelling());
        robot.observe(budget, &snapshot);
        assert!(!robot.labelling());
        assert_eq!(robot.claim(budget + 1, Some(2), cost, &[true; 3]), Some(2));
    }
}

/// After a move that left tasks unclaimed, a label is kept exactly when its tags lead to
/// a task still unclaimed over tasks no path touched: not through a task a path used
/// (on the way or at its end, a task just filled), not into a task no tag leaves, not
/// around a cycle of tags; unclaimed tasks start at 0, and the packed tags follow.
#[test]
fn kept_labels_are_the_paths_still_there() {
    let m = 10;
    let mut robot = Finish::new(0, m, m, AssignmentCase::One, 2, 1e-12);
    assert!(robot.runs());
    // Task 0 stays unclaimed; task 1 was, and a path filled it; a path used task 7.
    robot.frozen = (0..m)
        .map(|t| if t == 0 { 0 } else { t as u64 + 1 })
        .collect();
    robot.used = (0..m).map(|t| t == 1 || t == 7).collect();
    // Tags (task + 1, 0: none): 2 → 0, 3 → 2 → 0, 4 → 1, 5 ⇄ 6, 8 → 7 → 0, 9 unreached.
    let tags = [0, 0, 1, 3, 2, 7, 6, 1, 8, 0];
    robot.tags.copy_from_slice(&tags);
    for (t, label) in robot.labels.iter_mut().enumerate() {
        *label = if tags[t] == 0 { 0.5 } else { t as f64 / 10.0 };
    }
    robot.labels[9] = UNREACHED;
    let per = robot.packing.per_word();
    for (word, chunk) in robot.packed.iter_mut().zip(robot.tags.chunks(per)) {
        *word = robot.packing.pack(chunk) as u64;
    }
    robot.entries[3] = 7;
    robot.window = 5;
    robot.keep_untouched_labels();
    let kept = [2, 3];
    let after = robot.labels.iter().zip(&robot.tags).zip(tags).enumerate();
    for (t, ((&label, &tag), before)) in after {
        match t {
            0 => assert_eq!((label, tag), (0.0, 0), "the unclaimed task"),
            _ if kept.contains(&t) => assert_eq!((label, tag), (t as f64 / 10.0, before)),
            _ => assert_eq!((label, tag), (UNREACHED, 0), "task {t}"),
        }
    }
    for (word, chunk) in robot.packed.iter().zip(robot.tags.chunks(per)) {
        assert_eq!(*word as f64, robot.packing.pack(chunk));
    }
    assert!(robot.entries.iter().all(|&e| e == 0) && robot.window == 0);
}

/// A section is accepted as written and refused, at the right value, when a packed
/// value holds more tags than tasks or is not an integer, or the window is too wide.
#[test]
fn bad_sections_are_refused_at_their_value() {
    let costs = vec![vec![0.0, 1.0, 2.0]; 3];
    let (_, robots) = run(&costs, &[0, 0, 1], 1);
    let mut section = vec![0.0; words(3, 3)];
    // 3 tags of 2 bits (26 to a value), the window, the alarm, the bound; the moves go
    // in the potentials' place.
    assert_eq!(section.len(), 1 + 1 + 1 + 1);
    robots[0].write(&mut [0.0; 3], &mut section);
    assert_eq!(robots[0].check(&section), Ok(()));
    let bad = |k: usize, v: f64| {
        let mut s = section.clone();
        s[k] = v;
        robots[0].check(&s)
    };
    assert_eq!(bad(0, 3.0), Ok(())); // a tag of task 2 at task 0
    assert_eq!(bad(0, 4.0 + 64.0), Err(0)); // a 4th code
    assert_eq!(bad(0, 0.5), Err(0));
    assert_eq!(bad(0, f64::NAN), Err(0));
    assert_eq!(bad(1, 2f64.powi(53)), Err(1));
    assert_eq!(bad(1, 2f64.powi(52)), Ok(()));
    assert_eq!(bad(2, -1.0), Err(2));
    assert_eq!(bad(3, f64::MAX), Ok(())); // no bound
    assert_eq!(bad(3, 0.0), Ok(()));
    assert_eq!(bad(3, 1e-3), Ok(()));
    assert_eq!(bad(3, -1e-3), Err(3)); // a rise is at least 0
    assert_eq!(bad(3, f64::INFINITY), Err(3));
    assert_eq!(bad(3, f64::NEG_INFINITY), Err(3));
    assert_eq!(bad(3, f64::NAN), Err(3));
    let idle = Finish::new(0, 3, 3, AssignmentCase::Two, 2, 1e-12);
    assert!(!idle.runs());
    assert_eq!(idle.check(&[0.0; 4]), Ok(()));
    assert_eq!(idle.check(&[0.5, 1.0, 0.0, 0.0]), Err(0));
    // More robots than tasks carry the section too (a Case 1 part of a standing team
    // may run in it); a team of fewer robots carries none.
    assert_eq!((words(4, 3), words(2, 3), words(3, 1)), (4, 0, 0));
}

/// Robots on a complete graph (diameter 1: a snapshot settles every step) whose rounded
/// tasks at step `s` are `tasks(s)`; after each step every robot's finish observes its
/// snapshot (no robot labels: the labels never settle), and every robot decides the same.
/// Per step, whether robot 0 labels and its frozen claims.
fn observed(n: usize, tasks: impl Fn(u64) -> Vec<usize>, steps: u64) -> Vec<(bool, Vec<u64>)> {
    let case = AssignmentCase::One;
    let mut snapshots: Vec<_> = (0..n)
        .map(|i| Snapshot::new(i, n, n, case, 1, 1e-12))
        .collect();
    let mut robots: Vec<_> = (0..n)
        .map(|i| Finish::new(i, n, n, case, 1, 1e-12))
        .collect();
    let (costs, allowed) = (vec![0.0; n], vec![true; n]);
    let mut seen = Vec::new();
    for step in 0..=steps {
        let sections: Vec<Vec<f64>> = snapshots
            .iter()
            .map(|snapshot| {
                let mut section = vec![0.0; crate::methods::dual::snapshot::words(n, n)];
                snapshot.write(&mut section);
                section
            })
            .collect();
        let now = tasks(step);
        for (i, (snapshot, robot)) in snapshots.iter_mut().zip(&mut robots).enumerate() {
            snapshot.begin(false);
            for section in sections.iter().take(i).chain(sections.iter().skip(i + 1)) {
                snapshot.merge(step, section);
            }
            snapshot.advance(step, Some(now[i]), &costs, &allowed);
            robot.observe(step, snapshot);
        }
        // Every robot decides the same at the same step.
        for robot in &robots[1..] {
            assert_eq!(robot.labelling(), robots[0].labelling(), "step {step}");
            assert_eq!(robot.frozen, robots[0].frozen, "step {step}");
        }
        seen.push((robots[0].labelling(), robots[0].frozen.clone()));
    }
    seen
}

/// The finish freezes the first settled claims whose unclaimed tasks did not fall since
/// the last snapshot, though the claims change every period (the ADMM's claims at 1000
/// robots change for hundreds of rounds with hundreds of tasks unclaimed), and while
/// labelling freezes at once claims that leave fewer tasks unclaimed, changing or not.
/// Claims whose unclaimed tasks fall every period are left to the ADMM, and claims of
/// every task are frozen only when the certificate did not prove them for
/// [`FULL_PERIODS`] snapshots in a row.
#[test]
fn claims_with_tasks_unclaimed_are_frozen_though_they_change() {
    // Two claim sets in turn, each leaving two tasks unclaimed; the snapshot that settles
    // at step s holds the claims of step s − 1 (none before step 1).
    let turns = |s: u64| {
        if s.is_multiple_of(2) {
            vec![0, 0, 1, 1]
        } else {
            vec![2, 2, 3, 3]
        }
    };
    let seen = observed(4, turns, 8);
    let first = seen.iter().position(|(labelling, _)| *labelling);
    assert_eq!(
        first,
        Some(2),
        "frozen when the unclaimed tasks stop falling"
    );
    // Later claims that leave as many tasks unclaimed do not replace them.
    let frozen = claims_of(&turns(1));
    assert!(seen[2..].iter().all(|(l, f)| *l && *f == frozen));
    // Fewer tasks unclaimed, in claims that change every period, replace the frozen ones
    // at the first snapshot that holds them, and only then.
    let fewer = |s: u64| match s {
        0..=3 => turns(s),
        _ if s.is_multiple_of(2) => vec![0, 1, 2, 2],
        _ => vec![1, 0, 3, 3],
    };
    let seen = observed(4, fewer, 10);
    assert!(seen[2..=4].iter().all(|(l, f)| *l && *f == frozen));
    let fewer_frozen = claims_of(&fewer(4));
    assert_eq!(fewer_frozen.iter().filter(|&&c| c == 0).count(), 1);
    assert!(seen[5..].iter().all(|(l, f)| *l && *f == fewer_frozen));
    // Three tasks unclaimed, then two, then one, then none: the ADMM fills them itself.
    let falling = |s: u64| match s {
        0 => vec![0, 0, 0, 0],
        1 => vec![0, 0, 1, 1],
        2 => vec![0, 1, 2, 2],
        _ => vec![3, 1, 0, 2],
    };
    let seen = observed(4, falling, 8);
    let first = seen.iter().position(|(labelling, _)| *labelling);
    // Claims of every task are the certificate's for two snapshots (those of steps 3 and
    // 4, settling at steps 4 and 5); the third is frozen: the certificate did not prove it.
    assert_eq!(first, Some(6));
    assert_eq!(seen[6].1, claims_of(&falling(5)));
    let full = |_| vec![3, 1, 0, 2];
    let seen = observed(4, full, 8);
    assert_eq!(seen.iter().position(|(labelling, _)| *labelling), Some(3));
}

/// A faulty neighbour's moves whose sums leave an `f64` reach nothing: every label stays
/// finite (an unreached one is `f64::MAX`), so no prices handed to the certificate are
/// infinite.
#[test]
fn moves_beyond_an_f64_reach_nothing() {
    let m = 4;
    let mut robot = Finish::new(0, m, m, AssignmentCase::One, 2, 1e-12);
    // Task 0 unclaimed, tasks 1–3 claimed by robots 1–3.
    robot.freeze(2, &[0, 2, 3, 4], None);
    // Tags 1 → 0, 2 → 1, 3 → 2, each move −f64::MAX.
    let moves = [0.0, -f64::MAX, -f64::MAX, -f64::MAX];
    let mut section = vec![0.0; words(m, m)];
    section[0] = robot.packing.pack(&[0, 1, 2, 3]);
    let last = section.len() - 1;
    section[last] = UNREACHED;
    robot.begin();
    robot.merge(&moves, &section);
    robot.claim(3, None, &[0.0; 4], &[true; 4]);
    assert!(
        robot.labels.iter().all(|l| l.is_finite()),
        "{:?}",
        robot.labels
    );
    assert_eq!(robot.labels[1], -f64::MAX);
    assert_eq!(robot.labels[2..], [UNREACHED, UNREACHED]);
}

/// A faulty neighbour that raises the alarm at every step and offers a made-up cycle each
/// time has owners moved round it at most `m` times a freeze; then the finish gives up
/// (the certificate's potentials are not lent for ever).
#[test]
fn a_faulty_neighbour_has_at_most_m_cycles_cancelled_a_freeze() {
    let m = 3;
    let mut robot = Finish::new(0, m, m, AssignmentCase::One, 2, 1e-12);
    let (costs, allowed) = ([0.0, 1.0, 2.0], [true; 3]);
    // Claims of every task: rooted labels, no negative cycle.
    robot.freeze(0, &[1, 2, 3], Some(0));
    let mut section = vec![0.0; words(m, m)];
    let last = section.len() - 1;
    (section[last - 1], section[last]) = (((1u64 << WINDOW_BITS) - 1) as f64, UNREACHED);
    // Tasks 1 and 2 swapped, offered by robot 0: codes 0·(m + 1) + tag.
    let offer = [0.0, 3.0, 2.0];
    let given_up = (1..200).find(|&step| {
        robot.begin();
        let cancelling = matches!(robot.phase, Phase::Cancelling { .. });
        robot.merge(if cancelling { &offer } else { &[0.0; 3] }, &section);
        robot.claim(step, Some(0), &costs, &allowed);
        !robot.labelling()
    });
    assert!(given_up.is_some(), "the finish never gave up");
    assert_eq!(robot.cycles(), m as u64);
    assert_eq!(robot.frozen, [1, 3, 2], "swapped three times");
}

/// Offered codes that name no finder's tag are skipped: fractions, multiples of `m + 1`
/// (tag 0), codes from `robots · (m + 1)` on, negative and non-finite values.
#[test]
fn codes_that_name_no_tag_are_not_offered_cycles() {
    let m = 3;
    let mut robot = Finish::new(0, m, m, AssignmentCase::One, 2, 1e-12);
    robot.phase = Phase::Cancelling { at: 0, task: None };
    for bad in [
        2.5,
        4.0,
        12.0,
        13.0,
        -1.0,
        f64::MAX,
        f64::NAN,
        f64::INFINITY,
    ] {
        robot.merge_cycles(&[bad, 0.0, 0.0]);
        assert_eq!(robot.entries[0], 0, "{bad}");
    }
    // The smallest valid code stays: finder 2's tag 3, then finder 0's tag 2.
    robot.merge_cycles(&[11.0, 0.0, 0.0]);
    robot.merge_cycles(&[2.0, 0.0, 0.0]);
    robot.merge_cycles(&[7.0, 0.0, 0.0]);
    assert_eq!(robot.entries[0], 2);
}

/// A cycle of tags whose moves cost about nothing in all raises no alarm (nothing to
/// cancel: its labels stay); one that costs less than `−ε` does.
#[test]
fn only_a_negative_cycle_of_tags_raises_the_alarm() {
    let m = 3;
    let mut robot = Finish::new(0, m, m, AssignmentCase::One, 2, 1e-12);
    robot.freeze(0, &[1, 2, 3], Some(0));
    for (moves, negative) in [([-1.0, 1.0, 0.0], false), ([-1.0, 0.5, 0.0], true)] {
        robot.tags = vec![2, 1, 0];
        robot.moves = moves.to_vec();
        (robot.cycle, robot.dirty) = (false, true);
        robot.derive();
        assert_eq!(robot.cycle, negative, "{moves:?}");
    }
}
