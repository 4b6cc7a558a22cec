//! The plug points: object-safe traits every method implements, and the run context
//! (seed, phase timer, time budget, cancellation, progress) they receive.
//!
//! They live in the geometry crate, below every algorithm crate, so that algorithms
//! never depend on the harness (see docs/ARCHITECTURE.md).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::cloud::PointCloud;
use crate::error::GeomError;
use crate::mesh::TriMesh;

/// Why a method did not produce a result.
#[derive(Debug, thiserror::Error)]
pub enum MethodError {
    /// The input cannot be processed by this method (too few points, missing normals...).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A parameter is out of range.
    #[error("parameter '{name}': {message}")]
    InvalidParameter {
        /// Parameter name as written in experiment files.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A geometry error from a shared routine.
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// The run was cancelled or ran out of its time budget.
    #[error("stopped: {0}")]
    Stopped(StopReason),
    /// The method failed for a reason of its own.
    #[error("{0}")]
    Failed(String),
}

/// Why [`RunCtx::checkpoint`] stopped a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StopReason {
    /// Someone set the cancellation flag.
    Cancelled,
    /// The time budget ran out.
    TimedOut,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StopReason::Cancelled => "cancelled",
            StopReason::TimedOut => "time budget exceeded",
        })
    }
}

/// Wall-clock time of named phases, in the order they ran (monotonic clock).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PhaseTimer {
    /// `(phase name, seconds)`; a phase run twice appears twice.
    pub phases: Vec<(String, f64)>,
}

impl PhaseTimer {
    /// Runs `f`, recording its duration under `name`.
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.phases
            .push((name.to_string(), t0.elapsed().as_secs_f64()));
        out
    }

    /// Total seconds of the phases named `name`.
    pub fn seconds(&self, name: &str) -> f64 {
        self.phases
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, s)| s)
            .sum()
    }

    /// Total seconds of all phases.
    pub fn total(&self) -> f64 {
        self.phases.iter().map(|(_, s)| s).sum()
    }
}

/// Receives progress fractions in `[0, 1]`.
pub type ProgressSink = Arc<dyn Fn(f64) + Send + Sync>;

/// What a method receives besides its input: the seed for any randomness, a phase timer,
/// a time budget and cancellation flag to poll, and a progress sink.
pub struct RunCtx {
    /// Seed for all randomness of the method (use a ChaCha RNG seeded from it).
    pub seed: u64,
    /// Per-phase wall times; methods time their phases through [`RunCtx::phase`].
    pub timer: PhaseTimer,
    deadline: Option<Instant>,
    cancel: Arc<AtomicBool>,
    progress: Option<ProgressSink>,
}

impl std::fmt::Debug for RunCtx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunCtx")
            .field("seed", &self.seed)
            .field("timer", &self.timer)
            .field("deadline", &self.deadline)
            .finish_non_exhaustive()
    }
}

impl RunCtx {
    /// A context with the given seed, no time budget and no progress sink.
    pub fn new(seed: u64) -> Self {
        Self {
            seed,
            timer: PhaseTimer::default(),
            deadline: None,
            cancel: Arc::new(AtomicBool::new(false)),
            progress: None,
        }
    }

    /// Sets a time budget counted from now.
    #[must_use]
    pub fn with_budget(mut self, budget: Duration) -> Self {
        self.deadline = Some(Instant::now() + budget);
        self
    }

    /// Shares a cancellation flag (set it to `true` to stop the method).
    #[must_use]
    pub fn with_cancel_flag(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = flag;
        self
    }

    /// Sets the progress sink.
    #[must_use]
    pub fn with_progress(mut self, sink: ProgressSink) -> Self {
        self.progress = Some(sink);
        self
    }

    /// Runs `f` as the named phase, recording its wall time.
    pub fn phase<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        self.timer.time(name, f)
    }

    /// Returns an error when the run should stop; long loops call it now and then.
    pub fn checkpoint(&self) -> Result<(), MethodError> {
        if self.cancel.load(Ordering::Relaxed) {
            return Err(MethodError::Stopped(StopReason::Cancelled));
        }
        match self.deadline {
            Some(d) if Instant::now() >= d => Err(MethodError::Stopped(StopReason::TimedOut)),
            _ => Ok(()),
        }
    }

    /// Reports progress (clamped to `[0, 1]`).
    pub fn progress(&self, fraction: f64) {
        if let Some(p) = &self.progress {
            p(fraction.clamp(0.0, 1.0));
        }
    }
}

/// A diagnostic value a method reports next to its result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Diagnostic {
    /// A single number (iterations, matching %, ...).
    Number(f64),
    /// A series (e.g. matching % after each iteration).
    Series(Vec<f64>),
    /// A free-form note.
    Text(String),
}

/// Named diagnostics, sorted by name for stable output.
pub type Diagnostics = BTreeMap<String, Diagnostic>;

/// Output of a normal estimator: one normal per input point.
#[derive(Debug, Clone, PartialEq)]
pub struct Normals {
    /// Unit normals (zero where the method could not decide; metrics count those).
    pub normals: Vec<DVec3>,
    /// Whether the method claims a consistent outward orientation.
    pub oriented: bool,
    /// Method diagnostics.
    pub diagnostics: Diagnostics,
}

/// Per-point class a feature detector assigns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[repr(u8)]
pub enum FeatureClass {
    /// Not on a sharp feature.
    None = 0,
    /// On a sharp edge.
    Edge = 1,
    /// On a corner (three or more patches meet).
    Corner = 2,
}

/// Output of a feature detector.
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureLabels {
    /// One class per input point.
    pub labels: Vec<FeatureClass>,
    /// Optional per-point score (e.g. surface variation or cluster count) for sweeps.
    pub scores: Option<Vec<f64>>,
    /// Method diagnostics.
    pub diagnostics: Diagnostics,
}

/// Output of a reconstructor.
#[derive(Debug, Clone, PartialEq)]
pub struct Reconstruction {
    /// The reconstructed mesh.
    pub mesh: TriMesh,
    /// Indices of input points the method refused (outliers, isolated points).
    pub refused: Vec<u32>,
    /// Method diagnostics (matching %, iterations, ...).
    pub diagnostics: Diagnostics,
}

/// Estimates a normal per point.
pub trait NormalEstimator: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case registry name.
    fn name(&self) -> &str;
    /// Estimates normals for every point of `cloud`.
    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError>;
}

/// Labels points on sharp features.
pub trait FeatureDetector: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case registry name.
    fn name(&self) -> &str;
    /// Labels every point of `cloud`.
    fn detect(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<FeatureLabels, MethodError>;
}

/// Builds a triangle mesh from a point cloud.
pub trait Reconstructor: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case registry name.
    fn name(&self) -> &str;
    /// Reconstructs a surface from `cloud`.
    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoint_reports_cancel_and_timeout() {
        let flag = Arc::new(AtomicBool::new(false));
        let ctx = RunCtx::new(1).with_cancel_flag(flag.clone());
        assert!(ctx.checkpoint().is_ok());
        flag.store(true, Ordering::Relaxed);
        assert!(matches!(
            ctx.checkpoint(),
            Err(MethodError::Stopped(StopReason::Cancelled))
        ));
        let ctx = RunCtx::new(1).with_budget(Duration::ZERO);
        assert!(matches!(
            ctx.checkpoint(),
            Err(MethodError::Stopped(StopReason::TimedOut))
        ));
    }

    #[test]
    fn phase_timer_sums_repeated_phases() {
        let mut t = PhaseTimer::default();
        t.phases.push(("a".into(), 1.0));
        t.phases.push(("b".into(), 2.0));
        t.phases.push(("a".into(), 0.5));
        assert_eq!(t.seconds("a"), 1.5);
        assert_eq!(t.total(), 3.5);
        assert_eq!(t.time("c", || 7), 7);
        assert_eq!(t.phases.len(), 4);
    }
}
