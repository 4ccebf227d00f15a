//! Process-shared futex waits on 32-bit words of shared memory.
//!
//! A waiter reads a word, checks its condition and, if it must wait, calls [`wait`] with the
//! value it read: the kernel puts it to sleep only if the word still holds that value, so a
//! wake-up between the check and the sleep is never lost. A waker changes the word, then
//! calls [`wake`]. The words live in memory mapped by several processes (the run's board),
//! so these calls never use `FUTEX_PRIVATE_FLAG`: the kernel keys the wait queue on the
//! physical page, not on one process's address space.
//!
//! One wait or wake is one system call, where an iceoryx2 event (a unix-datagram socket on
//! Linux) costs several.
//!
//! ```
//! use admm_ta_runtime::futex::{self, Wait};
//! use std::sync::atomic::{AtomicU32, Ordering};
//! use std::time::Duration;
//! let word = AtomicU32::new(0);
//! // Nobody changes the word: the wait ends at its timeout.
//! assert_eq!(futex::wait(&word, 0, Duration::from_millis(1)), Wait::TimedOut);
//! // The word no longer holds the value the waiter read: no sleep at all.
//! word.fetch_add(1, Ordering::Release);
//! assert_eq!(futex::wait(&word, 0, Duration::from_secs(60)), Wait::Changed);
//! assert_eq!(futex::wake(&word, u32::MAX), 0);
//! ```

use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// Longest sleep of a waiter on a run's board between two looks at its failure mark, stop
/// request and launcher (every process transport's wait slice).
pub const FAILURE_CHECK_SLICE: Duration = Duration::from_millis(20);

/// How a [`wait`] ended. Every outcome but [`Wait::TimedOut`] may be spurious: the caller
/// re-checks its condition in any case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// Woken by [`wake`] (or spuriously).
    Woken,
    /// The word did not hold the expected value: the condition may already hold.
    Changed,
    /// Interrupted by a signal handler (the caller checks for a stop request).
    Interrupted,
    /// The timeout passed.
    TimedOut,
}

/// Sleeps while `word` holds `expected`, for at most `timeout`.
#[cfg(target_os = "linux")]
pub fn wait(word: &AtomicU32, expected: u32, timeout: Duration) -> Wait {
    let timeout = libc::timespec {
        tv_sec: timeout.as_secs().min(i32::MAX as u64) as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: `word` is a valid, aligned 32-bit word for the duration of the call (the
    // kernel only reads it); FUTEX_WAIT takes a relative timeout; the unused arguments are 0.
    let r = unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT,
            expected,
            &timeout as *const libc::timespec,
            std::ptr::null::<u32>(),
            0u32,
        )
    };
    if r == 0 {
        return Wait::Woken;
    }
    match std::io::Error::last_os_error().raw_os_error() {
        Some(libc::EAGAIN) => Wait::Changed,
        Some(libc::ETIMEDOUT) => Wait::TimedOut,
        Some(libc::EINTR) => Wait::Interrupted,
        // EFAULT/EINVAL cannot happen for a valid reference; treat as spurious.
        _ => Wait::Woken,
    }
}

/// Wakes up to `waiters` processes or threads sleeping on `word`; returns how many woke.
#[cfg(target_os = "linux")]
pub fn wake(word: &AtomicU32, waiters: u32) -> usize {
    // SAFETY: as in `wait`; FUTEX_WAKE only uses the address as a key.
    let r = unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAKE,
            waiters.min(i32::MAX as u32),
            std::ptr::null::<libc::timespec>(),
            std::ptr::null::<u32>(),
            0u32,
        )
    };
    r.max(0) as usize
}

/// The waker's half of the read-check-wait protocol: bumps `word`, then wakes every
/// sleeper on it.
pub fn bump_and_wake(word: &AtomicU32) {
    word.fetch_add(1, Ordering::Release);
    wake(word, u32::MAX);
}

/// Sleeps while `word` holds `seen`, until `deadline` but at most [`FAILURE_CHECK_SLICE`];
/// `true` if the whole slice passed without a wake-up (or no time was left). Every outcome
/// leads the caller to a new check.
pub fn wait_slice(word: &AtomicU32, seen: u32, deadline: Instant) -> bool {
    let left = deadline
        .saturating_duration_since(Instant::now())
        .min(FAILURE_CHECK_SLICE);
    left.is_zero() || wait(word, seen, left) == Wait::TimedOut
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn a_waker_ends_a_long_wait_at_once() {
        let word = Arc::new(AtomicU32::new(0));
        let waiter = {
            let word = word.clone();
            std::thread::spawn(move || {
                let started = Instant::now();
                while word.load(Ordering::Acquire) == 0 {
                    let _ = wait(&word, 0, Duration::from_secs(20));
                }
                started.elapsed()
            })
        };
        std::thread::sleep(Duration::from_millis(50));
        word.store(1, Ordering::Release);
        wake(&word, u32::MAX);
        let waited = waiter.join().unwrap();
        assert!(waited < Duration::from_secs(10), "{waited:?}");
    }

    #[test]
    fn the_read_check_wait_protocol_misses_no_wake_up() {
        // Two threads hand a turn back and forth 20,000 times, each waiting the way the
        // transports do (read the word, check, wait on the value read) with a long timeout:
        // one lost wake-up would stall the exchange for that timeout.
        const TURNS: u32 = 20_000;
        let (turn, word) = (Arc::new(AtomicU32::new(0)), Arc::new(AtomicU32::new(0)));
        let player = |me: u32| {
            let (turn, word) = (turn.clone(), word.clone());
            std::thread::spawn(move || {
                let mut stalls = 0;
                for t in (me..TURNS).step_by(2) {
                    loop {
                        let seen = word.load(Ordering::Acquire);
                        if turn.load(Ordering::Acquire) == t {
                            break;
                        }
                        if wait(&word, seen, Duration::from_secs(5)) == Wait::TimedOut {
                            stalls += 1;
                        }
                    }
                    turn.store(t + 1, Ordering::Release);
                    word.fetch_add(1, Ordering::Release);
                    wake(&word, u32::MAX);
                }
                stalls
            })
        };
        let started = Instant::now();
        let (a, b) = (player(0), player(1));
        assert_eq!((a.join().unwrap(), b.join().unwrap()), (0, 0));
        assert_eq!(turn.load(Ordering::Acquire), TURNS);
        assert!(started.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn a_wait_on_a_changed_word_returns_at_once() {
        let word = AtomicU32::new(7);
        assert_eq!(wait(&word, 6, Duration::from_secs(60)), Wait::Changed);
    }
}
