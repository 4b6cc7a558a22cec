//! Cost helpers: a per-phase wall-clock timer, process CPU time and peak resident memory.
//!
//! CPU time and peak RSS are read from `/proc/self` (Linux); elsewhere they are `None`.
//! CPU time is `utime + stime` of `/proc/self/stat` (all threads of the process) in clock
//! ticks, converted with the Linux user-space tick rate `USER_HZ = 100`. Peak RSS is
//! `VmHWM` of `/proc/self/status`: the high-water mark of the whole process since it
//! started, so measure one job per process for per-job figures.

use serde::Serialize;

use crate::report::{Entries, Report, put, serialize_as_entries};

/// Linux `USER_HZ` (the unit of the times in `/proc/<pid>/stat`); fixed at 100 by the
/// kernel ABI on every architecture.
const USER_HZ: f64 = 100.0;

/// Peak resident set size of this process in bytes (`VmHWM`), if available.
pub fn peak_rss_bytes() -> Option<u64> {
    proc_status_kib("VmHWM:").map(|k| k * 1024)
}

/// Current resident set size of this process in bytes (`VmRSS`), if available.
pub fn current_rss_bytes() -> Option<u64> {
    proc_status_kib("VmRSS:").map(|k| k * 1024)
}

fn proc_status_kib(key: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// User + system CPU time of this process (all threads) in seconds, if available.
pub fn cpu_time_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may contain spaces: parse after
    // the last ')'. Fields after it start at field 3 (state); utime and stime are fields
    // 14 and 15.
    let rest = &s[s.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / USER_HZ)
}

/// One timed phase.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Phase {
    /// Phase name (stable, snake_case recommended).
    pub name: String,
    /// Wall time in seconds (monotonic clock).
    pub wall_s: f64,
    /// CPU time of the process during the phase (seconds), if available.
    pub cpu_s: Option<f64>,
}

/// Cost summary of a run: its phases (from geom's [`PhaseTimer`](reconbench_geom::method::PhaseTimer), the one timer of the
/// project), process CPU time, threads and peak memory.
#[derive(Debug, Clone, PartialEq)]
pub struct CostReport {
    /// Timed phases, in order.
    pub phases: Vec<Phase>,
    /// Wall time since the timer was created (seconds).
    pub total_wall_s: f64,
    /// Process CPU time since the timer was created (seconds).
    pub total_cpu_s: Option<f64>,
    /// Rayon threads.
    pub threads: usize,
    /// Peak RSS of the process (bytes).
    pub peak_rss_bytes: Option<u64>,
}

impl CostReport {
    /// A report from the `(name, seconds)` phases of geom's `RunCtx` timer
    /// ([`reconbench_geom::method::PhaseTimer`]), with the process's current CPU time
    /// (since it started) and peak RSS.
    pub fn from_run_timer(timer: &reconbench_geom::method::PhaseTimer) -> Self {
        CostReport {
            phases: timer
                .phases
                .iter()
                .map(|(name, s)| Phase {
                    name: name.clone(),
                    wall_s: *s,
                    cpu_s: None,
                })
                .collect(),
            total_wall_s: timer.total(),
            total_cpu_s: cpu_time_seconds(),
            threads: rayon::current_num_threads(),
            peak_rss_bytes: peak_rss_bytes(),
        }
    }

    /// Items per second of wall time over the phases named `name` (e.g. points/s,
    /// triangles/s); `None` if they took no measurable time.
    pub fn throughput(&self, name: &str, items: usize) -> Option<f64> {
        let s: f64 = self
            .phases
            .iter()
            .filter(|p| p.name == name)
            .map(|p| p.wall_s)
            .sum();
        (s > 0.0).then(|| items as f64 / s)
    }
}

impl Report for CostReport {
    fn entries(&self) -> Entries {
        let mut e = Entries::new();
        // A phase that ran several times is reported once, with its total.
        let mut seen: Vec<(&str, f64)> = Vec::new();
        for p in &self.phases {
            match seen.iter_mut().find(|(n, _)| *n == p.name) {
                Some((_, s)) => *s += p.wall_s,
                None => seen.push((&p.name, p.wall_s)),
            }
        }
        for (name, s) in seen {
            put(&mut e, format!("time_{name}_s"), s);
        }
        put(&mut e, "time_total_s", self.total_wall_s);
        put(&mut e, "cpu_total_s", self.total_cpu_s);
        put(&mut e, "threads", self.threads);
        put(&mut e, "peak_rss_bytes", self.peak_rss_bytes);
        e
    }
}
serialize_as_entries!(CostReport);
