//! What `--timeline` costs a round (`bench rounds --timeline-overhead`): every case measured
//! with and without timelines in turn, `repeat` times (which goes first alternates), so both
//! see the same state of the machine; the median round p50 and p99 of each, and the ratios
//! as the median of the paired repetitions' ratios (drift between repetitions cancels).

use crate::rounds::case::{Case, RoundsConfig, cases};
use crate::rounds::measure;

/// One case with and without timelines (µs, medians over the repetitions).
#[derive(Debug, Clone, serde::Serialize)]
pub struct OverheadRow {
    pub case: Case,
    pub p50_off: f64,
    pub p50_on: f64,
    pub p99_off: f64,
    pub p99_on: f64,
    /// Median over the repetitions of p50 on / p50 off (and p99).
    pub p50_ratio: f64,
    pub p99_ratio: f64,
}

impl OverheadRow {
    /// A Markdown table row (see [`HEADER`]).
    pub fn render(&self) -> String {
        format!(
            "{} {:.1} | {:.1} | {:.3} | {:.1} | {:.1} | {:.3} |",
            self.case.columns(),
            self.p50_off,
            self.p50_on,
            self.p50_ratio,
            self.p99_off,
            self.p99_on,
            self.p99_ratio
        )
    }
}

/// The table's header.
pub const HEADER: &str = "| agents | graph | payload | transport | wait | barrier | p50 off | p50 on | p50 on/off (paired) | p99 off | p99 on | p99 on/off (paired) |\n|---|---|---|---|---|---|---|---|---|---|---|---|";

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Measures every case of `config` with and without timelines; `progress` sees each row
/// (or the case's failure) as it is done.
pub fn timeline_overhead(
    config: &RoundsConfig,
    progress: &mut dyn FnMut(&Case, Result<&OverheadRow, &str>),
) -> Vec<Result<OverheadRow, String>> {
    let mut rows = Vec::new();
    for case in cases(config) {
        let mut samples = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
        let mut failed = None;
        'repeats: for rep in 0..config.repeat.max(1) {
            // Alternate which goes first, so that order effects cancel.
            let order = if rep % 2 == 0 {
                [false, true]
            } else {
                [true, false]
            };
            for timeline in order {
                let k = usize::from(timeline);
                let config = RoundsConfig {
                    timeline,
                    ..config.clone()
                };
                match measure(&case, &config) {
                    Ok(r) => {
                        samples[k].push(r.round_us.p50);
                        samples[k + 2].push(r.round_us.p99);
                    }
                    Err(e) => {
                        failed = Some(e.to_string());
                        break 'repeats;
                    }
                }
            }
        }
        let row = match failed {
            Some(e) => Err(e),
            None => {
                let paired = |on: &[f64], off: &[f64]| {
                    median(on.iter().zip(off).map(|(a, b)| a / b).collect())
                };
                let p50_ratio = paired(&samples[1], &samples[0]);
                let p99_ratio = paired(&samples[3], &samples[2]);
                let [p50_off, p50_on, p99_off, p99_on] = samples.map(median);
                Ok(OverheadRow {
                    case: case.clone(),
                    p50_off,
                    p50_on,
                    p99_off,
                    p99_on,
                    p50_ratio,
                    p99_ratio,
                })
            }
        };
        progress(&case, row.as_ref().map_err(String::as_str));
        rows.push(row);
    }
    rows
}
