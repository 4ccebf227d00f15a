//! Round latency recording: one histogram per component of a round, per agent, merged by
//! the runner into percentiles.
//!
//! A round of a distributed agent is `wait` (neighbour barrier: until all neighbours'
//! round-`k` messages are held) + `compute` (the algorithm's step and the stop protocol) +
//! `publish` (handing the loaned message to the transport and waking the neighbours) +
//! `barrier` (the optional global barrier). `round` is the whole, end to end.
//!
//! ```
//! use admm_ta_transport::latency::{Component, RoundLatency};
//! use std::time::Duration;
//! let mut agent = RoundLatency::new();
//! agent.record(Component::Round, Duration::from_micros(40));
//! let mut team = RoundLatency::new();
//! team.merge(&agent.to_buckets()).unwrap();
//! assert_eq!(team.summary().round.count, 1);
//! ```

use hdrhistogram::Histogram;
use serde::{Deserialize, Serialize};
use std::time::Duration;

/// Parts of a round that are timed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    Wait,
    Compute,
    Publish,
    Barrier,
    Round,
    /// Round time minus compute time.
    Overhead,
}

const COMPONENTS: [Component; 6] = [
    Component::Wait,
    Component::Compute,
    Component::Publish,
    Component::Barrier,
    Component::Round,
    Component::Overhead,
];

/// Longest duration a histogram holds (longer ones are clamped to it).
const MAX_NANOS: u64 = 600_000_000_000;

/// Histograms (nanoseconds, 3 significant digits) of each round component.
#[derive(Debug, Clone)]
pub struct RoundLatency {
    histograms: [Histogram<u64>; COMPONENTS.len()],
}

/// A histogram as `(value in ns, count)` pairs: how agents ship theirs to the runner.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LatencyBuckets {
    pub components: Vec<Vec<(u64, u64)>>,
}

/// Percentiles of one component, in microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Percentiles {
    pub p50: f64,
    pub p90: f64,
    pub p99: f64,
    pub p999: f64,
    pub max: f64,
    pub mean: f64,
    pub count: u64,
}

/// Percentiles of every component.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct LatencySummary {
    pub round: Percentiles,
    pub wait: Percentiles,
    pub compute: Percentiles,
    pub publish: Percentiles,
    pub barrier: Percentiles,
    pub overhead: Percentiles,
}

/// A shipped histogram that does not fit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("latency histogram has {0} components, expected {expected}", expected = COMPONENTS.len())]
pub struct BucketsMismatch(usize);

impl Default for RoundLatency {
    fn default() -> Self {
        Self::new()
    }
}

impl RoundLatency {
    pub fn new() -> Self {
        let make = || Histogram::new_with_bounds(1, MAX_NANOS, 3).expect("valid histogram bounds");
        Self {
            histograms: COMPONENTS.map(|_| make()),
        }
    }

    fn index(component: Component) -> usize {
        COMPONENTS.iter().position(|&c| c == component).unwrap_or(0)
    }

    /// Records one duration (no allocation: the histogram's buckets are preallocated).
    pub fn record(&mut self, component: Component, duration: Duration) {
        let nanos = (duration.as_nanos() as u64).clamp(1, MAX_NANOS);
        self.histograms[Self::index(component)].saturating_record(nanos);
    }

    /// The recorded values, for shipping to the runner.
    pub fn to_buckets(&self) -> LatencyBuckets {
        LatencyBuckets {
            components: self
                .histograms
                .iter()
                .map(|h| {
                    h.iter_recorded()
                        .map(|v| (v.value_iterated_to(), v.count_at_value()))
                        .collect()
                })
                .collect(),
        }
    }

    /// Adds another agent's histograms.
    pub fn merge(&mut self, buckets: &LatencyBuckets) -> Result<(), BucketsMismatch> {
        if buckets.components.len() != COMPONENTS.len() {
            return Err(BucketsMismatch(buckets.components.len()));
        }
        for (h, values) in self.histograms.iter_mut().zip(&buckets.components) {
            for &(value, count) in values {
                h.saturating_record_n(value.clamp(1, MAX_NANOS), count);
            }
        }
        Ok(())
    }

    /// Adds another recorder's histograms.
    pub fn add(&mut self, other: &RoundLatency) {
        for (h, o) in self.histograms.iter_mut().zip(&other.histograms) {
            h.add(o).expect("histograms share their bounds");
        }
    }

    pub fn percentiles(&self, component: Component) -> Percentiles {
        let h = &self.histograms[Self::index(component)];
        let micros = |ns: u64| ns as f64 / 1e3;
        if h.is_empty() {
            return Percentiles::default();
        }
        Percentiles {
            p50: micros(h.value_at_quantile(0.5)),
            p90: micros(h.value_at_quantile(0.9)),
            p99: micros(h.value_at_quantile(0.99)),
            p999: micros(h.value_at_quantile(0.999)),
            max: micros(h.max()),
            mean: h.mean() / 1e3,
            count: h.len(),
        }
    }

    pub fn summary(&self) -> LatencySummary {
        LatencySummary {
            round: self.percentiles(Component::Round),
            wait: self.percentiles(Component::Wait),
            compute: self.percentiles(Component::Compute),
            publish: self.percentiles(Component::Publish),
            barrier: self.percentiles(Component::Barrier),
            overhead: self.percentiles(Component::Overhead),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipping_and_merging_keeps_the_percentiles() {
        let mut a = RoundLatency::new();
        for us in 1..=1000u64 {
            a.record(Component::Wait, Duration::from_micros(us));
        }
        let mut merged = RoundLatency::new();
        merged.merge(&a.to_buckets()).unwrap();
        let p = merged.percentiles(Component::Wait);
        assert_eq!(p.count, 1000);
        assert!((p.p50 - 500.0).abs() <= 1.0, "{p:?}");
        assert!((p.p99 - 990.0).abs() <= 1.0, "{p:?}");
        assert!((p.max - 1000.0).abs() <= 1.0, "{p:?}");
        assert_eq!(merged.percentiles(Component::Compute).count, 0);
        assert!(merged.merge(&LatencyBuckets::default()).is_err());
    }
}
