//! CPU clocks for benchmarks on a shared machine: wall time also counts the time a thread
//! waited for a core, CPU time does not (Linux `clock_gettime`; `None` elsewhere).

#[repr(C)]
struct Timespec {
    tv_sec: i64,
    tv_nsec: i64,
}

#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
unsafe extern "C" {
    fn clock_gettime(clock: i32, tp: *mut Timespec) -> i32;
}

const CLOCK_PROCESS_CPUTIME_ID: i32 = 2;
const CLOCK_THREAD_CPUTIME_ID: i32 = 3;

#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
fn read(clock: i32) -> Option<u64> {
    let mut t = Timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec (64-bit Linux layout).
    (unsafe { clock_gettime(clock, &mut t) } == 0)
        .then(|| t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64)
}

#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
fn read(_clock: i32) -> Option<u64> {
    let _ = Timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    None
}

/// CPU nanoseconds the calling thread has used.
pub fn thread_cpu_ns() -> Option<u64> {
    read(CLOCK_THREAD_CPUTIME_ID)
}

/// CPU nanoseconds all threads of this process have used (includes rayon workers spinning
/// while they wait for work).
pub fn process_cpu_ns() -> Option<u64> {
    read(CLOCK_PROCESS_CPUTIME_ID)
}

/// Milliseconds between two readings (NaN when the clock is unavailable).
pub fn ms_between(a: Option<u64>, b: Option<u64>) -> f64 {
    match (a, b) {
        (Some(a), Some(b)) => b.saturating_sub(a) as f64 * 1e-6,
        _ => f64::NAN,
    }
}
