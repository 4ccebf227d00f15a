//! Graph generators: the deterministic shapes of the paper and seeded random families.

use crate::{Graph, TopologyError, rng::SeededRng};

/// How many times a random family is redrawn before giving up on connectivity.
pub const MAX_ATTEMPTS: usize = 10_000;

/// Largest number of robot pairs a dense family (complete, random, geometric) considers:
/// refused before any allocation, so a typo like `--robots 100000` fails at once instead of
/// exhausting memory.
pub const MAX_PAIRS: u128 = 20_000_000;

fn check_pairs(what: &'static str, robots: usize) -> Result<(), TopologyError> {
    let pairs = robots as u128 * (robots as u128).saturating_sub(1) / 2;
    if pairs > MAX_PAIRS {
        return Err(TopologyError::TooDense {
            what,
            robots,
            pairs,
            max: MAX_PAIRS,
        });
    }
    Ok(())
}

/// Every robot talks to every other robot.
pub fn complete(n: usize) -> Result<Graph, TopologyError> {
    check_pairs("complete", n)?;
    let edges: Vec<_> = (0..n)
        .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
        .collect();
    Graph::from_edges(n, &edges, "complete")
}

/// The paper's linear chain `0 - 1 - ... - (n-1)`, the worst case for consensus.
pub fn chain(n: usize) -> Result<Graph, TopologyError> {
    let edges: Vec<_> = (1..n).map(|b| (b - 1, b)).collect();
    Graph::from_edges(n, &edges, "chain")
}

/// A chain closed into a cycle (a chain for n ≤ 2).
pub fn ring(n: usize) -> Result<Graph, TopologyError> {
    let mut edges: Vec<_> = (1..n).map(|b| (b - 1, b)).collect();
    if n > 2 {
        edges.push((0, n - 1));
    }
    Graph::from_edges(n, &edges, "ring")
}

/// Robot 0 in the centre, linked to everyone else.
pub fn star(n: usize) -> Result<Graph, TopologyError> {
    let edges: Vec<_> = (1..n).map(|b| (0, b)).collect();
    Graph::from_edges(n, &edges, "star")
}

/// A 2-D grid with `floor(sqrt n)` rows filled row by row (the last row may be partial).
pub fn grid(n: usize) -> Result<Graph, TopologyError> {
    if n == 0 {
        return Err(TopologyError::NoRobots);
    }
    let rows = (n as f64).sqrt().floor().max(1.0) as usize;
    let cols = n.div_ceil(rows);
    let mut edges = Vec::new();
    for v in 0..n {
        let (r, c) = (v / cols, v % cols);
        if c + 1 < cols && v + 1 < n {
            edges.push((v, v + 1));
        }
        if r + 1 < rows && v + cols < n {
            edges.push((v, v + cols));
        }
    }
    Graph::from_edges(n, &edges, format!("grid {rows}x{cols}"))
}

/// Erdős–Rényi `G(n, p)`, redrawn from the same seeded stream until connected.
pub fn random_connected(n: usize, p: f64, seed: u64) -> Result<Graph, TopologyError> {
    if !(p > 0.0 && p <= 1.0) {
        return Err(TopologyError::BadParameter {
            spec: format!("random:{p}"),
            reason: "the edge probability P must be in (0, 1]".into(),
        });
    }
    check_pairs("random", n)?;
    let mut rng = SeededRng::for_stream(seed, 0x746f706f);
    for _ in 0..MAX_ATTEMPTS {
        let mut edges = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                if rng.uniform() < p {
                    edges.push((a, b));
                }
            }
        }
        let g = Graph::from_edges(n, &edges, format!("random:{p} (seed {seed})"))?;
        if g.is_connected() {
            return Ok(g);
        }
    }
    Err(TopologyError::NeverConnected {
        what: "random",
        attempts: MAX_ATTEMPTS,
        hint: "increase the edge probability P",
    })
}

/// Random geometric graph: robots uniform in the unit square, linked when closer than
/// `radius`; redrawn until connected. Also returns the positions it used.
pub fn random_geometric(
    n: usize,
    radius: f64,
    seed: u64,
) -> Result<(Graph, Vec<[f64; 2]>), TopologyError> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(TopologyError::BadParameter {
            spec: format!("geometric:{radius}"),
            reason: "the radius R must be a positive number".into(),
        });
    }
    check_pairs("geometric", n)?;
    let mut rng = SeededRng::for_stream(seed, 0x67656f6d);
    for _ in 0..MAX_ATTEMPTS {
        let points: Vec<[f64; 2]> = (0..n).map(|_| [rng.uniform(), rng.uniform()]).collect();
        let mut edges = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                let (dx, dy) = (points[a][0] - points[b][0], points[a][1] - points[b][1]);
                if dx * dx + dy * dy < radius * radius {
                    edges.push((a, b));
                }
            }
        }
        let g = Graph::from_edges(n, &edges, format!("geometric:{radius} (seed {seed})"))?;
        if g.is_connected() {
            return Ok((g, points));
        }
    }
    Err(TopologyError::NeverConnected {
        what: "geometric",
        attempts: MAX_ATTEMPTS,
        hint: "increase the radius R",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_shapes() {
        assert_eq!(complete(5).unwrap().edge_count(), 10);
        assert_eq!(chain(5).unwrap().diameter(), Some(4));
        assert_eq!(ring(5).unwrap().diameter(), Some(2));
        assert_eq!(ring(2).unwrap().edge_count(), 1);
        assert_eq!(star(5).unwrap().degree(0), 4);
        let g = grid(10).unwrap();
        assert_eq!(g.name(), "grid 3x4");
        assert!(g.is_connected());
        for n in 1..30 {
            for g in [complete(n), chain(n), ring(n), star(n), grid(n)] {
                assert!(g.unwrap().is_connected(), "n = {n}");
            }
        }
    }

    #[test]
    fn random_families_are_connected_and_seeded() {
        for seed in 0..20 {
            let a = random_connected(30, 0.1, seed).unwrap();
            assert!(a.is_connected());
            assert_eq!(a, random_connected(30, 0.1, seed).unwrap());
            let (g, points) = random_geometric(30, 0.35, seed).unwrap();
            assert!(g.is_connected());
            assert_eq!(points.len(), 30);
        }
        assert_ne!(
            random_connected(30, 0.2, 1).unwrap(),
            random_connected(30, 0.2, 2).unwrap()
        );
    }

    #[test]
    fn impossible_parameters_fail_clearly() {
        assert!(random_connected(5, 0.0, 0).is_err());
        assert!(random_connected(5, 1.5, 0).is_err());
        assert!(random_geometric(5, -1.0, 0).is_err());
        let err = random_geometric(40, 0.01, 0).unwrap_err().to_string();
        assert!(err.contains("increase the radius"), "{err}");
    }
}
