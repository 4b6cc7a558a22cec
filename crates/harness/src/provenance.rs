//! Provenance of a run: code version, toolchain, machine, time (for the manifest).

use std::time::{SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

/// Where and with what a run happened.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The git commit the running binary was built from (`unknown` when it was built
    /// outside a git checkout), whatever directory it runs in.
    pub git_commit: String,
    /// Whether that build's source tree had uncommitted changes to tracked files.
    pub git_dirty: Option<bool>,
    /// rustc that built the harness.
    pub rustc: String,
    /// Harness crate version.
    pub harness_version: String,
    /// CPU model (`/proc/cpuinfo`), or `unknown`.
    pub cpu_model: String,
    /// Logical CPUs available to this process.
    pub cpus: usize,
    /// OS and architecture.
    pub os: String,
    /// Kernel release, when known.
    pub kernel: String,
    /// Host name, when known.
    pub hostname: String,
    /// Start time, UTC, RFC 3339.
    pub started: String,
    /// The command line.
    pub command: Vec<String>,
}

impl Provenance {
    /// Collects provenance now.
    pub fn collect() -> Self {
        let git_commit = env!("RECONBENCH_BUILD_COMMIT").to_string();
        let git_dirty = env!("RECONBENCH_BUILD_DIRTY").parse::<bool>().ok();
        let cpu_model = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|t| {
                t.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        let read = |p: &str| {
            std::fs::read_to_string(p)
                .map(|s| s.trim().to_string())
                .unwrap_or_else(|_| "unknown".into())
        };
        Self {
            git_commit,
            git_dirty,
            rustc: env!("RECONBENCH_RUSTC_VERSION").to_string(),
            harness_version: env!("CARGO_PKG_VERSION").to_string(),
            cpu_model,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
            os: format!("{}-{}", std::env::consts::OS, std::env::consts::ARCH),
            kernel: read("/proc/sys/kernel/osrelease"),
            hostname: read("/proc/sys/kernel/hostname"),
            started: now_rfc3339(),
            command: std::env::args().collect(),
        }
    }
}

/// The current UTC time as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn now_rfc3339() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    rfc3339(secs)
}

/// Formats Unix seconds as RFC 3339 UTC.
pub fn rfc3339(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    // Howard Hinnant's civil_from_days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = if m <= 2 { y + 1 } else { y };
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    )
}

/// Resident-memory figures of a process from `/proc/<pid>/status`, in MiB:
/// `(current VmRSS, peak VmHWM)`. `None` off Linux or when the process is gone.
pub fn rss_mib(pid: Option<u32>) -> Option<(f64, f64)> {
    let path = match pid {
        Some(p) => format!("/proc/{p}/status"),
        None => "/proc/self/status".to_string(),
    };
    let text = std::fs::read_to_string(path).ok()?;
    let field = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<f64>().ok())
            .map(|kb| kb / 1024.0)
    };
    Some((field("VmRSS:")?, field("VmHWM:").unwrap_or(0.0)))
}

/// CPU time (user + system) of this process in seconds, from `/proc/self/stat`
/// (assumes the usual 100 clock ticks per second).
pub fn cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which is in parentheses and may contain spaces).
    let rest = &text[text.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rfc3339_known_dates() {
        assert_eq!(rfc3339(0), "1970-01-01T00:00:00Z");
        assert_eq!(rfc3339(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(rfc3339(1_700_000_000), "2023-11-14T22:13:20Z");
    }

    #[test]
    fn proc_readers_work_here() {
        if cfg!(target_os = "linux") {
            let (rss, peak) = rss_mib(None).unwrap();
            assert!(rss > 0.0 && peak >= rss * 0.5);
            assert!(cpu_seconds().unwrap() >= 0.0);
        }
    }
}
