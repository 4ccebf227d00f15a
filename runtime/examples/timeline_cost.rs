//! What one round's timeline stamp costs the agent (`--timeline`): `TimelineRecorder::record`
//! called a million times with fresh instants, against the same loop without it.
//!
//! ```sh
//! cargo run --release -p admm-ta-runtime --example timeline_cost
//! ```

use admm_ta_transport::timeline::TimelineRecorder;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    const ROUNDS: u64 = 1_000_000;
    for trial in 0..3 {
        // The round loop takes these five instants anyway; only `record` is the timeline's.
        let started = Instant::now();
        let mut sink = 0u64;
        for r in 0..ROUNDS {
            let t = [Instant::now(); 5];
            sink = sink.wrapping_add(black_box(t)[4].elapsed().subsec_nanos() as u64 + r);
        }
        let without = started.elapsed();
        let mut recorder = TimelineRecorder::new(ROUNDS);
        let started = Instant::now();
        for r in 0..ROUNDS {
            let t = [Instant::now(); 5];
            sink = sink.wrapping_add(black_box(t)[4].elapsed().subsec_nanos() as u64 + r);
            recorder.record(r, black_box(t));
        }
        let with = started.elapsed();
        let stamps = recorder.into_stamps().len();
        println!(
            "trial {trial}: {:.1} ns per round with the stamp, {:.1} without: {:.1} ns per stamp ({stamps} stamps, sink {})",
            with.as_nanos() as f64 / ROUNDS as f64,
            without.as_nanos() as f64 / ROUNDS as f64,
            (with.as_nanos() as f64 - without.as_nanos() as f64) / ROUNDS as f64,
            sink % 10
        );
    }
}
