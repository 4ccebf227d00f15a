//! The timeline of a team of independently started agents (the team file's `timeline`),
//! written by `collect`: the agents' stamps merged into one Chrome trace and the critical
//! path; a team across hosts first has every host's stamps shifted onto the first host's
//! clock ([`admm_ta_transport::timeline::clocks`]), and the trace and the result say by how much.

use crate::team::errors::CollectError;
use crate::team::team_file::Team;
use admm_ta_topologies::Graph;
use admm_ta_transport::timeline::clocks::{self, HostClock};
use admm_ta_transport::timeline::{self, CriticalPath, RoundStamp};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// One host's clock in a team's timeline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NamedHostClock {
    pub host: String,
    #[serde(flatten)]
    pub clock: HostClock,
}

/// What [`write_timeline`] wrote: the trace's path, the critical path, the hosts' clocks.
pub type WrittenTimeline = (
    Option<PathBuf>,
    Option<CriticalPath>,
    Option<Vec<NamedHostClock>>,
);

/// Writes the team's trace if its file asks for one (`timelines[i]`: agent `i`'s stamps).
pub fn write_timeline(
    team: &Team,
    graph: &Graph,
    mut timelines: Vec<Vec<RoundStamp>>,
) -> Result<WrittenTimeline, CollectError> {
    let Some(path) = team.timeline_path() else {
        return Ok((None, None, None));
    };
    let hosts = &team.file.hosts;
    let host_of: Vec<usize> = (0..timelines.len())
        .map(|i| {
            hosts
                .iter()
                .position(|h| h.agents.contains(&i))
                .unwrap_or(usize::MAX)
        })
        .collect();
    let named = (!hosts.is_empty()).then(|| {
        let estimated = clocks::estimate(graph, &timelines, &host_of, hosts.len());
        clocks::align(&mut timelines, &host_of, &estimated);
        hosts
            .iter()
            .zip(estimated)
            .map(|(h, clock)| NamedHostClock {
                host: h.name.clone(),
                clock,
            })
            .collect::<Vec<_>>()
    });
    let mut trace =
        timeline::chrome_trace_named(graph, &timelines, &|i| match hosts.get(host_of[i]) {
            Some(h) => format!("agent {i} on {}", h.name),
            None => format!("agent {i}"),
        });
    if let Some(named) = &named {
        trace["otherData"]["clock"] = serde_json::Value::from(clock_note(named));
        trace["otherData"]["host_clocks"] = serde_json::to_value(named).expect("JSON serialises");
    }
    std::fs::write(&path, serde_json::to_vec(&trace).expect("JSON serialises")).map_err(
        |source| CollectError::Write {
            path: path.clone(),
            source,
        },
    )?;
    let critical = timeline::critical_path(graph, &timelines);
    Ok((Some(path), Some(critical), named))
}

/// How the trace's clock was made, in a sentence: the first host's clock, the others'
/// offsets and their uncertainty.
pub fn clock_note(clocks: &[NamedHostClock]) -> String {
    let Some(first) = clocks.first() else {
        return "CLOCK_MONOTONIC".into();
    };
    let mut note = format!(
        "CLOCK_MONOTONIC of host {}, µs from the first stamp; other hosts shifted by offsets \
         estimated from the round messages (a message arrives after it was sent, over every \
         edge between two hosts, both ways):",
        first.host
    );
    for c in &clocks[1..] {
        let clock = &c.clock;
        if clock.estimated {
            note += &format!(
                " {} {:+.1} µs ± {:.1} µs{};",
                c.host,
                clock.offset_ns as f64 / 1e3,
                clock.uncertainty_ns as f64 / 1e3,
                if clock.consistent {
                    ""
                } else {
                    " (bounds crossed: the clocks drifted?)"
                }
            );
        } else {
            note += &format!(" {} not aligned (no recorded rounds reach it);", c.host);
        }
    }
    note.trim_end_matches(';').to_string()
}
