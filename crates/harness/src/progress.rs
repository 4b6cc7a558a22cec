//! Progress of a method running in a worker, as the runner sees it: the worker's sink
//! prints rate-limited lines on stderr, the runner parses them and shows them next to
//! the running cell.

/// Prefix of a progress line on stderr (`RECONBENCH-PROGRESS 0.42`), which the runner
/// shows next to the running cell.
pub const PROGRESS_PREFIX: &str = "RECONBENCH-PROGRESS ";

/// The progress sink of a worker: prints a [`PROGRESS_PREFIX`] line on stderr when the
/// fraction moved by at least 1 % and 0.2 s passed since the last line (or at 100 %),
/// so a method may report as often as it likes.
pub fn progress_sink() -> reconbench_geom::method::ProgressSink {
    let last = std::sync::Mutex::new((-1.0f64, None::<std::time::Instant>));
    std::sync::Arc::new(move |f: f64| {
        let Ok(mut l) = last.lock() else { return };
        let now = std::time::Instant::now();
        let due =
            l.1.is_none_or(|t| now.duration_since(t).as_secs_f64() >= 0.2);
        if (f - l.0 >= 0.01 && due) || (f >= 1.0 && l.0 < 1.0) {
            *l = (f, Some(now));
            eprintln!("{PROGRESS_PREFIX}{f:.3}");
        }
    })
}
