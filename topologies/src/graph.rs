use crate::TopologyError;
use std::collections::VecDeque;

/// Upper bound on team size; it keeps `n × n × m` agent state from exhausting memory
/// before any work starts.
pub const MAX_ROBOTS: usize = 100_000;

/// An undirected simple graph on robots `0..n`, stored as sorted neighbour lists.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Graph {
    neighbours: Vec<Vec<usize>>,
    name: String,
}

impl Graph {
    /// Builds a graph from an edge list, rejecting self-loops, duplicates and out-of-range
    /// robots. Connectivity is *not* required here (see [`Graph::require_connected`]).
    pub fn from_edges(
        robots: usize,
        edges: &[(usize, usize)],
        name: impl Into<String>,
    ) -> Result<Self, TopologyError> {
        if robots == 0 {
            return Err(TopologyError::NoRobots);
        }
        if robots > MAX_ROBOTS {
            return Err(TopologyError::TooManyRobots {
                robots,
                max: MAX_ROBOTS,
            });
        }
        let mut neighbours = vec![Vec::new(); robots];
        for &(a, b) in edges {
            for v in [a, b] {
                if v >= robots {
                    return Err(TopologyError::OutOfRange(a, b, v, robots));
                }
            }
            if a == b {
                return Err(TopologyError::SelfLoop(a));
            }
            neighbours[a].push(b);
            neighbours[b].push(a);
        }
        for (a, list) in neighbours.iter_mut().enumerate() {
            list.sort_unstable();
            if let Some(w) = list.windows(2).find(|w| w[0] == w[1]) {
                return Err(TopologyError::DuplicateEdge(a.min(w[0]), a.max(w[0])));
            }
        }
        Ok(Self {
            neighbours,
            name: name.into(),
        })
    }

    /// Number of robots (vertices).
    pub fn robots(&self) -> usize {
        self.neighbours.len()
    }

    /// Sorted neighbours of robot `i` (the paper's `N(i)`).
    pub fn neighbours(&self, i: usize) -> &[usize] {
        &self.neighbours[i]
    }

    /// `|N(i)|`.
    pub fn degree(&self, i: usize) -> usize {
        self.neighbours[i].len()
    }

    /// Mean degree `2|E| / n`.
    pub fn mean_degree(&self) -> f64 {
        self.neighbours.iter().map(Vec::len).sum::<usize>() as f64 / self.robots() as f64
    }

    /// Number of undirected edges.
    pub fn edge_count(&self) -> usize {
        self.neighbours.iter().map(Vec::len).sum::<usize>() / 2
    }

    /// Edges `(a, b)` with `a < b`, in lexicographic order.
    pub fn edges(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.neighbours
            .iter()
            .enumerate()
            .flat_map(|(a, list)| list.iter().filter(move |&&b| b > a).map(move |&b| (a, b)))
    }

    /// A short description such as `ring` or `random:0.3 (seed 7)`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Connected components, each sorted, ordered by their smallest robot.
    pub fn components(&self) -> Vec<Vec<usize>> {
        let n = self.robots();
        let mut seen = vec![false; n];
        let mut components = Vec::new();
        for start in 0..n {
            if seen[start] {
                continue;
            }
            let mut component = self.bfs_distances(start, &mut seen).0;
            component.sort_unstable();
            components.push(component);
        }
        components
    }

    /// Whether every robot can reach every other one.
    pub fn is_connected(&self) -> bool {
        let mut seen = vec![false; self.robots()];
        self.bfs_distances(0, &mut seen).0.len() == self.robots()
    }

    /// Assumption 1 of the paper: fails with the list of components when disconnected.
    pub fn require_connected(&self) -> Result<(), TopologyError> {
        if self.is_connected() {
            Ok(())
        } else {
            Err(TopologyError::Disconnected(self.components()))
        }
    }

    /// Longest shortest path (hop count) between two robots; `None` when disconnected.
    pub fn diameter(&self) -> Option<usize> {
        let n = self.robots();
        let mut diameter = 0;
        let mut seen = vec![false; n];
        for start in 0..n {
            seen.iter_mut().for_each(|s| *s = false);
            let (reached, eccentricity) = self.bfs_distances(start, &mut seen);
            if reached.len() != n {
                return None;
            }
            diameter = diameter.max(eccentricity);
        }
        Some(diameter)
    }

    /// The graph induced on `members` (robots of this graph): the same robots `0..n`, with
    /// only the edges between two members (every other robot is isolated). A team whose
    /// robots come and go keeps its robots' numbers: this is the graph of those that take
    /// part.
    pub fn induced(&self, members: &[usize]) -> Self {
        let mut inside = vec![false; self.robots()];
        for &m in members {
            if let Some(slot) = inside.get_mut(m) {
                *slot = true;
            }
        }
        let neighbours = self
            .neighbours
            .iter()
            .enumerate()
            .map(|(a, list)| {
                if inside[a] {
                    list.iter().copied().filter(|&b| inside[b]).collect()
                } else {
                    Vec::new()
                }
            })
            .collect();
        Self {
            neighbours,
            name: self.name.clone(),
        }
    }

    /// The connected components of the graph induced on `members`, each sorted, ordered by
    /// their smallest robot (robots outside `members` belong to none).
    pub fn components_among(&self, members: &[usize]) -> Vec<Vec<usize>> {
        let induced = self.induced(members);
        let mut seen = vec![true; self.robots()];
        for &m in members.iter().filter(|&&m| m < self.robots()) {
            seen[m] = false;
        }
        let mut components = Vec::new();
        for start in 0..self.robots() {
            if seen[start] {
                continue;
            }
            let mut component = induced.bfs_distances(start, &mut seen).0;
            component.sort_unstable();
            components.push(component);
        }
        components
    }

    /// Longest shortest path between two of `members` in the graph they induce; `None` when
    /// they are not connected (or there are none). One member: 0.
    pub fn diameter_among(&self, members: &[usize]) -> Option<usize> {
        let induced = self.induced(members);
        let members: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&m| m < self.robots())
            .collect();
        let mut diameter = 0;
        let mut seen = vec![false; self.robots()];
        for &start in &members {
            seen.iter_mut().for_each(|s| *s = false);
            let (reached, eccentricity) = induced.bfs_distances(start, &mut seen);
            if reached.len() != members.len() {
                return None;
            }
            diameter = diameter.max(eccentricity);
        }
        (!members.is_empty()).then_some(diameter)
    }

    /// The graph induced on `members`, renumbered `0..members.len()` in their order (for
    /// what depends only on its shape: the mean degree, the diameter).
    pub fn compacted(&self, members: &[usize]) -> Self {
        let mut place = vec![usize::MAX; self.robots()];
        for (k, &m) in members.iter().enumerate() {
            if let Some(p) = place.get_mut(m) {
                *p = k;
            }
        }
        let neighbours = members
            .iter()
            .map(|&a| {
                let mut list: Vec<usize> = self
                    .neighbours(a)
                    .iter()
                    .filter_map(|&b| (place[b] != usize::MAX).then_some(place[b]))
                    .collect();
                list.sort_unstable();
                list
            })
            .collect();
        Self {
            neighbours,
            name: self.name.clone(),
        }
    }

    /// Breadth-first search from `start`: the reached robots and the largest hop distance.
    fn bfs_distances(&self, start: usize, seen: &mut [bool]) -> (Vec<usize>, usize) {
        let mut reached = vec![start];
        let mut queue = VecDeque::from([(start, 0usize)]);
        seen[start] = true;
        let mut farthest = 0;
        while let Some((v, d)) = queue.pop_front() {
            farthest = farthest.max(d);
            for &w in &self.neighbours[v] {
                if !seen[w] {
                    seen[w] = true;
                    reached.push(w);
                    queue.push_back((w, d + 1));
                }
            }
        }
        (reached, farthest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_self_loops_duplicates_and_out_of_range() {
        assert_eq!(
            Graph::from_edges(3, &[(1, 1)], "x"),
            Err(TopologyError::SelfLoop(1))
        );
        assert_eq!(
            Graph::from_edges(3, &[(0, 1), (1, 0)], "x"),
            Err(TopologyError::DuplicateEdge(0, 1))
        );
        assert_eq!(
            Graph::from_edges(3, &[(0, 3)], "x"),
            Err(TopologyError::OutOfRange(0, 3, 3, 3))
        );
        assert_eq!(Graph::from_edges(0, &[], "x"), Err(TopologyError::NoRobots));
    }

    #[test]
    fn disconnected_graph_names_its_components() {
        let g = Graph::from_edges(5, &[(0, 1), (2, 3)], "x").unwrap();
        assert_eq!(g.components(), vec![vec![0, 1], vec![2, 3], vec![4]]);
        let err = g.require_connected().unwrap_err().to_string();
        assert!(err.contains("3 components: [0, 1], [2, 3], [4]"), "{err}");
        assert_eq!(g.diameter(), None);
    }

    #[test]
    fn degree_diameter_and_edges() {
        let g = Graph::from_edges(4, &[(0, 1), (1, 2), (2, 3)], "chain").unwrap();
        assert_eq!(g.diameter(), Some(3));
        assert_eq!(g.mean_degree(), 1.5);
        assert_eq!(g.edges().collect::<Vec<_>>(), vec![(0, 1), (1, 2), (2, 3)]);
        let single = Graph::from_edges(1, &[], "single").unwrap();
        assert!(single.is_connected());
        assert_eq!(single.diameter(), Some(0));
    }

    #[test]
    fn induced_subgraphs_keep_the_robots_numbers() {
        let edges: Vec<(usize, usize)> = (0..8).map(|i| (i, (i + 1) % 8)).collect();
        let ring = Graph::from_edges(8, &edges, "ring").unwrap();
        let without_5: Vec<usize> = (0..8).filter(|&r| r != 5).collect();
        let chain = ring.induced(&without_5);
        assert_eq!(chain.robots(), 8);
        assert_eq!(chain.neighbours(4), &[3]);
        assert_eq!(chain.neighbours(6), &[7]);
        assert!(chain.neighbours(5).is_empty());
        assert_eq!(ring.diameter_among(&(0..8).collect::<Vec<_>>()), Some(4));
        assert_eq!(ring.diameter_among(&without_5), Some(6));
        assert_eq!(ring.components_among(&without_5), vec![without_5.clone()]);
        assert_eq!(ring.diameter_among(&[0, 1, 3]), None);
        assert_eq!(ring.components_among(&[0, 1, 3]), vec![vec![0, 1], vec![3]]);
        assert_eq!(ring.diameter_among(&[6]), Some(0));
        assert_eq!(ring.diameter_among(&[]), None);
        let compact = ring.compacted(&without_5);
        assert_eq!(compact.robots(), 7);
        assert_eq!(compact.diameter(), Some(6));
        assert_eq!(compact.neighbours(5), &[6]);
        let star = Graph::from_edges(5, &[(0, 1), (0, 2), (0, 3), (0, 4)], "star").unwrap();
        assert!(star.components_among(&[1, 2, 3, 4]).len() == 4);
    }
}
