//! The clock the benchmarks read: the benchmark thread's CPU time by default, wall time on request.
//!
//! Why not wall time: the reference machine has 2 cores shared with other work (compilers, test
//! runs), and under a load average of 4 the same build measured 1.0 and 2.3 Mtris/s in two wall-time
//! runs minutes apart. Thread CPU time (`CLOCK_THREAD_CPUTIME_ID`) leaves out the time the
//! scheduler gave to other processes, which is most of that noise. What it cannot remove (shared
//! caches and memory bandwidth) remains, so a quiet machine is still better. Every library here
//! builds and traces on the calling thread only, so its CPU time is its whole cost; a threaded
//! build would need wall time (`RDBVH_BENCH_CLOCK=wall`).

use std::time::Instant;

use criterion::measurement::{Measurement, ValueFormatter, WallTime};

/// The clock, chosen once per run from `RDBVH_BENCH_CLOCK` (`cpu`, the default, or `wall`).
pub enum Clock {
    /// CPU time of the calling thread.
    ThreadCpu,
    /// Elapsed real time.
    Wall,
}

impl Clock {
    /// The clock `RDBVH_BENCH_CLOCK` names, announced on stderr so a results file says which.
    pub fn from_env() -> Self {
        let clock = match std::env::var("RDBVH_BENCH_CLOCK").as_deref() {
            Ok("wall") => Clock::Wall,
            _ => Clock::ThreadCpu,
        };
        eprintln!(
            "clock: {}",
            match clock {
                Clock::ThreadCpu => "thread CPU time (RDBVH_BENCH_CLOCK=wall for wall time)",
                Clock::Wall => "wall time",
            }
        );
        clock
    }
}

fn thread_cpu_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant Linux supports.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// Where a measurement started: CPU nanoseconds or an instant.
pub enum Start {
    Cpu(u64),
    Wall(Instant),
}

/// Both clocks report nanoseconds, so criterion's own duration formatting applies.
static NANOSECONDS: WallTime = WallTime;

impl Measurement for Clock {
    type Intermediate = Start;
    type Value = u64;

    fn start(&self) -> Start {
        match self {
            Clock::ThreadCpu => Start::Cpu(thread_cpu_ns()),
            Clock::Wall => Start::Wall(Instant::now()),
        }
    }
    fn end(&self, start: Start) -> u64 {
        match start {
            Start::Cpu(t0) => thread_cpu_ns().saturating_sub(t0),
            Start::Wall(t0) => t0.elapsed().as_nanos() as u64,
        }
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, v: &u64) -> f64 {
        *v as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        NANOSECONDS.formatter()
    }
}
