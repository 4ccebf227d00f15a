//! CPU time (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`, nanoseconds) and context switches
//! (`getrusage(RUSAGE_THREAD)`) of the calling thread: what a round costs the machine besides
//! its wall time. (`getrusage`'s own CPU times are apportioned from scheduler ticks and read
//! 0 for a thread that ran a few milliseconds.) An agent thread (threads) or an agent
//! process's main thread (ipc, uds) reads it when its measured rounds start and end.
//!
//! ```
//! use admm_ta_transport::usage::ThreadUsage;
//! let before = ThreadUsage::now();
//! let spent = ThreadUsage::now().since(&before);
//! assert!(spent.cpu_ns < 1_000_000_000);
//! ```

use serde::{Deserialize, Serialize};

/// Counters of one thread since it started (or a difference of two readings).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct ThreadUsage {
    /// User plus system CPU time, in nanoseconds.
    pub cpu_ns: u64,
    /// Times the thread gave up the core itself (it blocked: a sleep, a futex, a poll).
    pub voluntary_switches: u64,
    /// Times the scheduler took the core away (time slice over, a higher-priority wake-up).
    pub involuntary_switches: u64,
}

impl ThreadUsage {
    /// The calling thread's counters; all zero where the platform cannot tell.
    pub fn now() -> Self {
        #[cfg(target_os = "linux")]
        {
            // SAFETY: getrusage only writes the struct it is given.
            let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
            if unsafe { libc::getrusage(libc::RUSAGE_THREAD, &mut usage) } != 0 {
                return Self::default();
            }
            let mut cpu: libc::timespec = unsafe { std::mem::zeroed() };
            // SAFETY: clock_gettime only writes the struct it is given.
            let cpu_ns =
                if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut cpu) } == 0 {
                    cpu.tv_sec as u64 * 1_000_000_000 + cpu.tv_nsec as u64
                } else {
                    0
                };
            Self {
                cpu_ns,
                voluntary_switches: usage.ru_nvcsw as u64,
                involuntary_switches: usage.ru_nivcsw as u64,
            }
        }
        #[cfg(not(target_os = "linux"))]
        {
            Self::default()
        }
    }

    /// What was used between `earlier` and `self`.
    pub fn since(&self, earlier: &Self) -> Self {
        Self {
            cpu_ns: self.cpu_ns.saturating_sub(earlier.cpu_ns),
            voluntary_switches: self
                .voluntary_switches
                .saturating_sub(earlier.voluntary_switches),
            involuntary_switches: self
                .involuntary_switches
                .saturating_sub(earlier.involuntary_switches),
        }
    }

    /// Sum of two usages (a team's total).
    pub fn plus(&self, other: &Self) -> Self {
        Self {
            cpu_ns: self.cpu_ns + other.cpu_ns,
            voluntary_switches: self.voluntary_switches + other.voluntary_switches,
            involuntary_switches: self.involuntary_switches + other.involuntary_switches,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn busy_work_shows_as_cpu_time_and_sleeping_as_a_voluntary_switch() {
        let before = ThreadUsage::now();
        let started = std::time::Instant::now();
        let mut x = 0u64;
        while started.elapsed() < std::time::Duration::from_millis(20) {
            x = std::hint::black_box(x.wrapping_add(1));
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
        let spent = ThreadUsage::now().since(&before);
        if cfg!(target_os = "linux") {
            assert!(spent.cpu_ns >= 1_000_000, "{spent:?}");
            assert!(spent.voluntary_switches >= 1, "{spent:?}");
        }
    }
}
