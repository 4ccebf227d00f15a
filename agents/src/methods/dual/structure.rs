//! The fast dual variant's factor on `ρ₀` from the costs' structure ([`structure_factor`]):
//! larger for independent costs, smaller for distance-like ones, the rule as it is where the
//! structure is unclear (bench/README.md, "The dual methods, third pass").

use crate::problem::CostMatrix;
use crate::problem::costs::spread_of;

/// The fast variant's `ρ₀` follows the costs' structure ([`structure_factor`]): at most
/// this many times its rule …
pub const FAST_STRUCTURE_MAX: f64 = 3.0;
/// … and this share of it for distance-like costs up to `h` = [`FAST_STRUCTURE_KNEE`] …
pub const FAST_STRUCTURE_MIN: f64 = 0.5;
/// … beyond which it falls as `1/h²` to a quarter of that at twice the knee (distance
/// costs of 150 to about 400 robots), rising back to it at four times the knee (costs
/// with one clear favourite per robot, whose `h` grows with the number of tasks).
pub const FAST_STRUCTURE_KNEE: f64 = 3.2;

/// The fast variant's factor on `ρ₀` for these costs, from `h`: the mean over robots (with
/// two allowed tasks or more) of the gap between their two cheapest allowed costs times
/// their number of allowed tasks, over the costs' spread. Tasks whose allowed costs are
/// the same for every robot (the idle columns of a normalised problem), and robots whose
/// allowed costs are all the same (its idle rows), tell nothing about the competition and
/// are left out (of the gaps, the counts and the spread).
///
/// Independent, uniform costs give `h` between 0.8 and 1.3 at any size (the two smallest
/// of `k` uniform draws are `1/(k+1)` apart); distance costs more (1.6 at 20 × 20 on
/// average, 2.3 at 50 × 50, 3.0 at 100 × 100, 3.1 at 120 × 120, 4.3 at 200 × 200: a
/// robot's nearest tasks are `1/√k` apart); costs whose spread says little about the
/// competition less (tasks in far-apart clusters 0.1–0.25, points on a line 0.5–0.9,
/// rows of different scales 0.35–0.75, few distinct values 0). The factor is
/// [`FAST_STRUCTURE_MAX`] in the band of independent costs (`0.8 ≤ h ≤ 1.25`), the rule
/// as it is (1) below 0.7 and at 1.4, falling to [`FAST_STRUCTURE_MIN`] at `h = 2`,
/// linear in between, and that times `(3.2/h)²` from [`FAST_STRUCTURE_KNEE`] to twice it,
/// back to [`FAST_STRUCTURE_MIN`] linearly at four times it and beyond (`factor_of`; basic
/// operations only, so every machine of a team computes the same ρ).
///
/// Measured (fast dual, seeds 1–10, rounds to the certified stop, the rule's ρ times a
/// constant): uniform costs certify faster with 3× (50 × 50 complete 183 → 124, 120 × 120
/// complete 434 → 390) and the 100 × 100 chain every run (9/10 → 10/10); distance costs
/// want less: at 1× the 120 × 120 complete graph certified 5 of 10 runs and at 2× the
/// 100 × 100 one 1 of 10, at ½ every run of every size from 50 to 120. Clustered costs
/// (three far-apart clusters, 40 × 40) are why the band is narrow: they certified at 1×
/// and never at 3×. Distance costs of larger teams want less still (`h` measured 3.2–4.3 at
/// 150, 4.1–4.5 at 200, 5.6–6.3 at 400): at ½ the 150 × 150 complete graph certified 7 of 8
/// runs in 5000 rounds, 200 × 200 (complete and `random:0.1`) 1 of 3 each and
/// `random:0.05` at 400 0 of 2; with the fall beyond the knee every one of them (bench/README.md,
/// "Light messages"). The fall stops at twice the knee because costs whose robots each
/// have one clear favourite (`h` from 20 to 190 at 50–200 robots) want ½: with `(3.2/h)²`
/// for every `h` favourites shared by two robots took 3 to 8 times the rounds or never
/// certified, and at ⅛ they were slower on every run (complete graph, 50 / 100 / 200
/// robots: 277 / 252 / 295 rounds at ½, 406 / 390 / 417 at ⅛).
pub fn structure_factor(costs: &CostMatrix) -> f64 {
    structure_h(costs).map_or(1.0, factor_of)
}

/// `h` of [`structure_factor`]: none when no robot has two allowed tasks whose costs tell
/// something about the competition.
fn structure_h(costs: &CostMatrix) -> Option<f64> {
    let (n, m) = (costs.robots(), costs.tasks());
    let allowed = |i: usize, t: usize| costs.is_allowed(i, t).then(|| costs.get(i, t));
    // Tasks and robots whose allowed costs differ somewhere (not an idle column or row).
    let column = |t: usize| varies((0..n).filter_map(|i| allowed(i, t)));
    let columns: Vec<bool> = (0..m).map(column).collect();
    let counted = |i: usize| {
        (0..m)
            .filter(|&t| columns[t])
            .filter_map(move |t| allowed(i, t))
    };
    let rows: Vec<bool> = (0..n).map(|i| varies(counted(i))).collect();
    let spread = spread_of((0..n).filter(|&i| rows[i]).flat_map(counted));
    let (mut sum, mut robots) = (0.0, 0usize);
    for i in (0..n).filter(|&i| rows[i]) {
        let (mut first, mut second, mut tasks) = (f64::INFINITY, f64::INFINITY, 0usize);
        for v in counted(i) {
            tasks += 1;
            if v < first {
                second = first;
                first = v;
            } else if v < second {
                second = v;
            }
        }
        // Each gap over the spread first: no overflow for costs near the largest double.
        sum += (second / spread - first / spread) * tasks as f64;
        robots += 1;
    }
    (robots > 0).then(|| sum / robots as f64)
}

/// The factor for `h` (see [`structure_factor`]): [`FAST_STRUCTURE_MAX`] in the band of
/// independent costs, 1 (the rule as it is) below it, falling to [`FAST_STRUCTURE_MIN`]
/// above it, and below that between one and four times [`FAST_STRUCTURE_KNEE`]; linear
/// between, basic operations only.
fn factor_of(h: f64) -> f64 {
    let (max, min, knee) = (FAST_STRUCTURE_MAX, FAST_STRUCTURE_MIN, FAST_STRUCTURE_KNEE);
    let ramp = |x: f64, from: f64, to: f64, a: f64, b: f64| a + (b - a) * (x - from) / (to - from);
    match h {
        h if !h.is_finite() || h < 0.7 => 1.0,
        h if h < 0.8 => ramp(h, 0.7, 0.8, 1.0, max),
        h if h <= 1.25 => max,
        h if h <= 1.4 => ramp(h, 1.25, 1.4, max, 1.0),
        h if h <= 2.0 => ramp(h, 1.4, 2.0, 1.0, min),
        h if h <= knee => min,
        h if h <= 2.0 * knee => min * (knee / h) * (knee / h),
        h if h <= 4.0 * knee => ramp(h, 2.0 * knee, 4.0 * knee, min / 4.0, min),
        _ => min,
    }
}

/// Whether not all of `values` are equal (false for none or one).
fn varies(mut values: impl Iterator<Item = f64>) -> bool {
    values
        .next()
        .is_some_and(|first| values.any(|v| v != first))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::cost_model::geometric;

    /// Uniform costs get the largest factor at every size, distance costs (nearly) the
    /// smallest from 50 robots on, and less for the larger teams, clustered costs the rule
    /// as it is; the factor ignores
    /// shifts and scales of the costs and the idle columns and rows of a normalised
    /// problem; costs that say nothing (constant, or one allowed task per robot) leave ρ₀
    /// as it is.
    #[test]
    fn structure_factor_follows_the_costs() {
        for n in [20, 50, 120] {
            let uniform = CostMatrix::uniform(n, n, 3).unwrap();
            assert!(structure_factor(&uniform) > 2.0, "{n}");
            if n >= 50 {
                for seed in 1..=5 {
                    let distance = geometric(n, n, seed).unwrap();
                    let factor = structure_factor(&distance);
                    assert!(factor <= 0.7, "{n} {seed}: {factor}");
                }
            }
            let moved = CostMatrix::new(
                n,
                n,
                uniform.values().iter().map(|c| 250.0 * c - 1e6).collect(),
            )
            .unwrap();
            let (a, b) = (structure_factor(&uniform), structure_factor(&moved));
            assert!((a - b).abs() <= 1e-6 * a, "{a} {b}");
            // Idle columns (cost 0 for everyone, real costs above): the same factor.
            let tasks = n / 2;
            let real = CostMatrix::uniform(n, tasks, 4).unwrap();
            let idle = CostMatrix::new(
                n,
                tasks + n - tasks,
                (0..n)
                    .flat_map(|i| {
                        let row: Vec<f64> = real.row(i).iter().map(|c| 1.0 + c).collect();
                        row.into_iter().chain(std::iter::repeat_n(0.0, n - tasks))
                    })
                    .collect(),
            )
            .unwrap();
            let (with, without) = (structure_factor(&idle), structure_factor(&real));
            assert!(
                (with - without).abs() <= 1e-9 * without,
                "{n}: {with} {without}"
            );
        }
        // Distance costs of 400 robots get much less than those of 120; one clear favourite
        // per robot (cost 0, the rest from ½ to 1): `h` near the number of tasks, and ρ₀
        // as for distance costs of small teams.
        let n = 120;
        let uniform = CostMatrix::uniform(n, n, 3).unwrap();
        let (small, large) = (geometric(n, n, 2), geometric(400, 400, 2));
        let (small, large) = (small.unwrap(), large.unwrap());
        let (a, b) = (structure_factor(&small), structure_factor(&large));
        assert!(b < 0.2 && b < a / 2.0, "{a} {b}");
        let favourite = CostMatrix::new(
            n,
            n,
            (0..n * n)
                .map(|k| {
                    if k % (n + 1) == 0 {
                        0.0
                    } else {
                        0.5 + uniform.values()[k] / 2.0
                    }
                })
                .collect(),
        )
        .unwrap();
        assert_eq!(structure_factor(&favourite), FAST_STRUCTURE_MIN);
        // Tasks and robots in three far-apart clusters: the spread is the clusters' distance,
        // not the competition's scale; the rule stays as it is.
        let mut rng = admm_ta_topologies::rng::SeededRng::new(3);
        let mut point = || {
            (
                10.0 * (rng.uniform() * 3.0).floor() + rng.uniform(),
                rng.uniform(),
            )
        };
        let (robots, tasks): (Vec<_>, Vec<_>) = (
            (0..40).map(|_| point()).collect(),
            (0..40).map(|_| point()).collect(),
        );
        let clustered = CostMatrix::new(
            40,
            40,
            robots
                .iter()
                .flat_map(|r| tasks.iter().map(move |t| f64::hypot(r.0 - t.0, r.1 - t.1)))
                .collect(),
        )
        .unwrap();
        assert_eq!(structure_factor(&clustered), 1.0);
        for (h, factor) in [
            (0.5, 1.0),
            (0.75, 2.0),
            (1.0, 3.0),
            (1.4, 1.0),
            (1.7, 0.75),
            (3.0, 0.5),
            (3.2, 0.5),
            (6.4, 0.125),
            (9.6, 0.3125),
            (12.8, 0.5),
            (100.0, 0.5),
        ] {
            assert!((factor_of(h) - factor).abs() < 1e-12, "{h}");
        }
        let constant = CostMatrix::new(3, 3, vec![2.0; 9]).unwrap();
        assert_eq!(structure_factor(&constant), 1.0);
        let inf = f64::INFINITY;
        let single = CostMatrix::new(2, 2, vec![1.0, inf, inf, 5.0]).unwrap();
        assert_eq!(structure_factor(&single), 1.0);
        let huge = CostMatrix::new(2, 2, vec![1e307, -1e307, -1e307, 1e307]).unwrap();
        assert!(structure_factor(&huge).is_finite() && structure_factor(&huge) > 0.0);
    }
}
