//! CPU clocks for benchmarks on a shared machine: wall time also counts the time a thread
//! waited for a core, CPU time does not (`clock_gettime` through the `libc` crate on Linux;
//! `None` elsewhere). The one place benchmarks and examples read CPU time.

#[cfg(target_os = "linux")]
fn read(clock: libc::clockid_t) -> Option<u64> {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec.
    (unsafe { libc::clock_gettime(clock, &mut t) } == 0)
        .then(|| t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64)
}

/// CPU nanoseconds the calling thread has used.
pub fn thread_cpu_ns() -> Option<u64> {
    #[cfg(target_os = "linux")]
    return read(libc::CLOCK_THREAD_CPUTIME_ID);
    #[cfg(not(target_os = "linux"))]
    None
}

/// CPU nanoseconds all threads of this process have used (includes rayon workers spinning
/// while they wait for work).
pub fn process_cpu_ns() -> Option<u64> {
    #[cfg(target_os = "linux")]
    return read(libc::CLOCK_PROCESS_CPUTIME_ID);
    #[cfg(not(target_os = "linux"))]
    None
}

/// Milliseconds between two readings (NaN when the clock is unavailable).
pub fn ms_between(a: Option<u64>, b: Option<u64>) -> f64 {
    match (a, b) {
        (Some(a), Some(b)) => b.saturating_sub(a) as f64 * 1e-6,
        _ => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(target_os = "linux")]
    fn thread_clock_advances_with_work() {
        let a = thread_cpu_ns().unwrap();
        let mut x = 0u64;
        for i in 0..2_000_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        }
        std::hint::black_box(x);
        let b = thread_cpu_ns().unwrap();
        assert!(b > a && ms_between(Some(a), Some(b)) > 0.0);
        assert!(process_cpu_ns().unwrap() >= b - a);
        assert!(ms_between(None, Some(1)).is_nan());
    }
}
