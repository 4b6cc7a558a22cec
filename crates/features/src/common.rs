//! Shared plumbing: neighbour tables, parameter checks, the chunked parallel driver
//! (time-budget checkpoints and progress between chunks) and diagnostics helpers.

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::method::{Diagnostic, Diagnostics, FeatureClass, MethodError, RunCtx};
use reconbench_geom::spatial::{KnnTable, knn_self_table};

/// Points handled between two [`RunCtx::checkpoint`] calls of the parallel driver.
pub(crate) const CHUNK: usize = 16_384;

/// kNN table of every point with the point itself excluded (seed 002 §1.2: "N_p is the k
/// nearest *other* points"), `k` clamped to `n - 1`. Needs at least 2 points. Timed as the
/// phase `knn` (the all-points kNN tree builds no kiddo index).
pub(crate) fn knn_excluding_self(
    points: &[DVec3],
    k: usize,
    ctx: &mut RunCtx,
) -> Result<KnnTable, MethodError> {
    let table = ctx.phase("knn", || knn_self_table(points, k, true))?;
    ctx.checkpoint()?;
    Ok(table)
}

/// Runs `f(ws, i)` for every `i in 0..n` in parallel, `CHUNK` points at a time, with one
/// workspace per rayon job (`map_init`), polling the time budget and reporting progress
/// between chunks. Results are in index order whatever the thread count. The wall time is
/// recorded as phase `phase`.
pub(crate) fn par_map_chunked<W, T, I, F>(
    n: usize,
    phase: &str,
    ctx: &mut RunCtx,
    init: I,
    f: F,
) -> Result<Vec<T>, MethodError>
where
    T: Send,
    I: Fn() -> W + Sync + Send,
    F: Fn(&mut W, usize) -> T + Sync + Send,
{
    let t0 = Instant::now();
    let mut out = Vec::with_capacity(n);
    let mut start = 0;
    while start < n {
        ctx.checkpoint()?;
        let end = (start + CHUNK).min(n);
        let part: Vec<T> = (start..end).into_par_iter().map_init(&init, &f).collect();
        out.extend(part);
        ctx.progress(end as f64 / n as f64);
        start = end;
    }
    ctx.record_phase(phase, t0.elapsed().as_secs_f64());
    Ok(out)
}

/// Error for an out-of-range parameter.
pub(crate) fn bad_param(name: &str, message: impl Into<String>) -> MethodError {
    MethodError::InvalidParameter {
        name: name.to_string(),
        message: message.into(),
    }
}

/// Checks `lo <= x <= hi` and finiteness.
pub(crate) fn check_range(name: &str, x: f64, lo: f64, hi: f64) -> Result<(), MethodError> {
    if !(x.is_finite() && x >= lo && x <= hi) {
        return Err(bad_param(
            name,
            format!("{x} must be finite and in [{lo}, {hi}]"),
        ));
    }
    Ok(())
}

/// Adds `features`, `edges`, `corners` counts for `labels`.
pub(crate) fn count_labels(labels: &[FeatureClass], diagnostics: &mut Diagnostics) {
    let edges = labels.iter().filter(|&&c| c == FeatureClass::Edge).count();
    let corners = labels
        .iter()
        .filter(|&&c| c == FeatureClass::Corner)
        .count();
    num(diagnostics, "features", (edges + corners) as f64);
    num(diagnostics, "edges", edges as f64);
    num(diagnostics, "corners", corners as f64);
}

/// Inserts a number diagnostic.
pub(crate) fn num(diagnostics: &mut Diagnostics, name: &str, x: f64) {
    diagnostics.insert(name.to_string(), Diagnostic::Number(x));
}
