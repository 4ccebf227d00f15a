//! Process-shared futex waits on 32-bit words of shared memory, and the one wake-word
//! protocol every process transport uses on them.
//!
//! The words live in memory mapped by several processes (the run's board), so these calls
//! never use `FUTEX_PRIVATE_FLAG`: the kernel keys the wait queue on the physical page, not on
//! one process's address space. One wait or wake is one system call, where an iceoryx2 event
//! (a unix-datagram socket on Linux) costs several.
//!
//! # The wake-word protocol
//!
//! A *waker* makes its condition true (a release store), then calls [`bump_and_wake`]: one
//! read-modify-write that adds 2 to the word and clears its [`SLEEPING`] mark, followed by a
//! `FUTEX_WAKE` of every sleeper **only if the mark was set**. A *waiter* reads the word
//! (acquire) *before* it checks its condition; if the condition does not hold it calls
//! [`wait_slice`] with the value read, which sets the mark (a compare-and-swap from that
//! value; if it fails the word was bumped since, and the waiter checks again) and sleeps
//! while the word holds the marked value. Most wake-ups go to agents that are running
//! anyway (50–100 agents on 2 cores): they cost one atomic, no system call.
//!
//! Why no wake-up is lost. All read-modify-writes of the word are totally ordered. Take a
//! waiter that read `seen` and found its condition false, and a waker whose bump `B` makes it
//! true. (1) If `B` precedes the waiter's read in that order, the read synchronises with `B`
//! (acquire of a release read-modify-write) and the check sees the condition: no sleep.
//! (2) Otherwise `B` changes the word after the read (every bump adds 2). If the waiter's
//! mark CAS comes after `B`, it fails, and the waiter checks again, as in (1). If the mark
//! was set before `B` (by this CAS, or already in `seen`), then the only writes that clear
//! it are bumps, each followed by a wake-all; so either `B` itself finds the mark and wakes
//! every sleeper after its write, or an earlier bump cleared it, changed the word and woke
//! every sleeper after that. In both cases the waiter is asleep when the wake comes (and is
//! woken) or calls `FUTEX_WAIT` after the word changed (the kernel refuses to sleep on a
//! value the word no longer holds). This holds for any number of waiters on one word (the
//! global barrier's) because a waker that clears the mark wakes them all. Only a wrap of the
//! word between a waiter's read and its sleep (2³¹ bumps) could fool it.
//!
//! ```
//! use admm_ta_transport::futex::{self, Wait};
//! use std::sync::atomic::{AtomicU32, Ordering};
//! use std::time::{Duration, Instant};
//! let word = AtomicU32::new(0);
//! // Nobody changes the word: the wait ends at its timeout.
//! assert_eq!(futex::wait(&word, 0, Duration::from_millis(1)), Wait::TimedOut);
//! // The word no longer holds the value the waiter read: no sleep at all.
//! word.fetch_add(1, Ordering::Release);
//! assert_eq!(futex::wait(&word, 0, Duration::from_secs(60)), Wait::Changed);
//! // The protocol: nobody marked the word, so a bump makes no system call.
//! let seen = word.load(Ordering::Acquire);
//! futex::bump_and_wake(&word);
//! // The waiter's mark fails on the bumped word: it checks its condition again at once.
//! assert!(!futex::wait_slice(&word, seen, Instant::now() + Duration::from_secs(60)));
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

/// The mark of a wake word that says somebody sleeps on it (or is about to); bumps add 2,
/// so the counting part never touches it.
pub const SLEEPING: u32 = 1;

/// The waker's half of the protocol (see the module docs): bumps `word` by 2 and takes its
/// [`SLEEPING`] mark in one read-modify-write, then wakes every sleeper if it was marked.
/// Returns whether it made the system call.
pub fn bump_and_wake(word: &AtomicU32) -> bool {
    let mut old = word.load(Ordering::Relaxed);
    // One CAS in the normal case: a word has one waker at a time but for rare races.
    while let Err(now) = word.compare_exchange_weak(
        old,
        old.wrapping_add(2) & !SLEEPING,
        Ordering::AcqRel,
        Ordering::Relaxed,
    ) {
        old = now;
    }
    let marked = old & SLEEPING != 0;
    if marked {
        wake(word, u32::MAX);
    }
    marked
}

/// The waiter's half of the protocol (see the module docs): `seen` is the value of `word`
/// read before the waiter's last check. Marks the word as slept on, then sleeps while it
/// holds the marked value, for at most `timeout`. [`Wait::Changed`] if the word was bumped
/// since `seen` was read.
pub fn wait_marked(word: &AtomicU32, seen: u32, timeout: Duration) -> Wait {
    let marked = seen | SLEEPING;
    if seen != marked
        && word
            .compare_exchange(seen, marked, Ordering::AcqRel, Ordering::Acquire)
            .is_err()
    {
        return Wait::Changed;
    }
    wait(word, marked, timeout)
}

/// [`wait_marked`] until `deadline` but at most [`FAILURE_CHECK_SLICE`]; `true` if the whole
/// slice passed without a wake-up (or no time was left). Every outcome leads the caller to a
/// new check.
pub fn wait_slice(word: &AtomicU32, seen: u32, deadline: Instant) -> bool {
    let left = deadline
        .saturating_duration_since(Instant::now())
        .min(FAILURE_CHECK_SLICE);
    left.is_zero() || wait_marked(word, seen, left) == Wait::TimedOut
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

    /// `players` threads pass a turn around a ring `turns` times, all sleeping on ONE
    /// shared word the way the transports do (read the word, check, [`wait_marked`] on the
    /// value read, with a long timeout); returns the waits that timed out (a lost wake-up:
    /// the first ends the game) and the wake system calls made.
    fn pass_turns(players: u32, turns: u32) -> (u32, usize) {
        let (turn, word) = (Arc::new(AtomicU32::new(0)), Arc::new(AtomicU32::new(0)));
        let wakes = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let player = |me: u32| {
            let (turn, word, wakes) = (turn.clone(), word.clone(), wakes.clone());
            std::thread::spawn(move || {
                let mut stalls = 0;
                for t in (me..turns).step_by(players as usize) {
                    loop {
                        let seen = word.load(Ordering::Acquire);
                        if turn.load(Ordering::Acquire) == t {
                            break;
                        }
                        if wait_marked(&word, seen, Duration::from_secs(2)) == Wait::TimedOut {
                            // A lost wake-up: the game is over for everybody.
                            stalls += 1;
                            turn.store(u32::MAX, Ordering::Release);
                        }
                        if turn.load(Ordering::Acquire) == u32::MAX {
                            return stalls;
                        }
                    }
                    turn.store(t + 1, Ordering::Release);
                    if bump_and_wake(&word) {
                        wakes.fetch_add(1, Ordering::Relaxed);
                    }
                }
                stalls
            })
        };
        let threads: Vec<_> = (0..players).map(player).collect();
        let stalls = threads.into_iter().map(|t| t.join().unwrap()).sum();
        if stalls == 0 {
            assert_eq!(turn.load(Ordering::Acquire), turns);
        }
        (stalls, wakes.load(Ordering::Relaxed))
    }

    #[test]
    fn the_wake_word_protocol_misses_no_wake_up_between_two() {
        // One lost wake-up would stall the exchange for the 2 s timeout.
        let started = Instant::now();
        assert_eq!(pass_turns(2, 20_000).0, 0);
        assert!(started.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn the_wake_word_protocol_misses_no_wake_up_among_many_sleepers() {
        // Five threads on one word (like the global barrier's): every bump must wake the
        // sleeper whose turn it is, whoever set the mark.
        let started = Instant::now();
        assert_eq!(pass_turns(5, 10_000).0, 0);
        assert!(started.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn a_bump_nobody_sleeps_on_makes_no_system_call() {
        let word = AtomicU32::new(0);
        assert!(!bump_and_wake(&word));
        assert_eq!(word.load(Ordering::Relaxed), 2);
        // A waiter marks the word (its sleep ends at once: a zero timeout).
        assert_eq!(wait_marked(&word, 2, Duration::ZERO), Wait::TimedOut);
        assert_eq!(word.load(Ordering::Relaxed), 3);
        // The next bump takes the mark and wakes.
        assert!(bump_and_wake(&word));
        assert_eq!(word.load(Ordering::Relaxed), 4);
    }

    #[test]
    fn a_wait_on_a_changed_word_returns_at_once() {
        let word = AtomicU32::new(7);
        assert_eq!(wait(&word, 6, Duration::from_secs(60)), Wait::Changed);
    }
}
