//! The run context every method receives: seed, the one phase timer of the project, time
//! budget, cancellation and progress.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use super::MethodError;

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

/// Wall-clock time of named phases, in the order they ended (monotonic clock).
///
/// This is the project's only phase timer: methods record into it through
/// [`RunCtx::phase`] / [`RunCtx::phase_guard`], the metrics crate times its evaluation
/// with it and turns it into a cost report.
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

/// Records the wall time of one phase when dropped (see [`RunCtx::phase_guard`]). It does
/// not borrow the context, so the phase's code can keep using `ctx`.
#[derive(Debug)]
#[must_use = "a phase guard records its phase when dropped; bind it to a variable"]
pub struct PhaseGuard {
    timer: Arc<Mutex<PhaseTimer>>,
    name: String,
    start: Instant,
}

impl PhaseGuard {
    /// Ends the phase now (same as dropping the guard).
    pub fn finish(self) {}
}

impl Drop for PhaseGuard {
    fn drop(&mut self) {
        let s = self.start.elapsed().as_secs_f64();
        lock(&self.timer)
            .phases
            .push((std::mem::take(&mut self.name), s));
    }
}

fn lock(t: &Mutex<PhaseTimer>) -> MutexGuard<'_, PhaseTimer> {
    // A phase list stays valid even if a thread panicked while holding the lock.
    t.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a method receives besides its input: the seed for any randomness, the phase
/// timer, a time budget and cancellation flag to poll, and a progress sink.
pub struct RunCtx {
    /// Seed for all randomness of the method (use a ChaCha RNG seeded from it).
    pub seed: u64,
    timer: Arc<Mutex<PhaseTimer>>,
    deadline: Option<Instant>,
    cancel: Arc<AtomicBool>,
    progress: Option<ProgressSink>,
    prefix: String,
}

impl std::fmt::Debug for RunCtx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunCtx")
            .field("seed", &self.seed)
            .field("timer", &*lock(&self.timer))
            .field("deadline", &self.deadline)
            .finish_non_exhaustive()
    }
}

impl RunCtx {
    /// A context with the given seed, no time budget and no progress sink.
    pub fn new(seed: u64) -> Self {
        Self {
            seed,
            timer: Arc::default(),
            deadline: None,
            cancel: Arc::new(AtomicBool::new(false)),
            progress: None,
            prefix: String::new(),
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

    /// A context for one step of a pipeline: same budget, cancellation flag and timer,
    /// its own seed, phase names prefixed with `prefix` (e.g. `"jet/"`), and progress
    /// mapped into `[lo, hi]` of this context's progress.
    pub fn sub_step(&self, seed: u64, prefix: &str, lo: f64, hi: f64) -> Self {
        let progress = self.progress.clone().map(|p| -> ProgressSink {
            Arc::new(move |f: f64| p(lo + (hi - lo) * f.clamp(0.0, 1.0)))
        });
        Self {
            seed,
            timer: self.timer.clone(),
            deadline: self.deadline,
            cancel: self.cancel.clone(),
            progress,
            prefix: format!("{}{prefix}", self.prefix),
        }
    }

    /// Runs `f` as the named phase, recording its wall time. `f` may use the context
    /// (it is borrowed shared).
    pub fn phase<T>(&self, name: &str, f: impl FnOnce() -> T) -> T {
        let _g = self.phase_guard(name);
        f()
    }

    /// Starts the named phase; it is recorded when the guard drops (also on an early
    /// return through `?`).
    pub fn phase_guard(&self, name: &str) -> PhaseGuard {
        PhaseGuard {
            timer: self.timer.clone(),
            name: format!("{}{name}", self.prefix),
            start: Instant::now(),
        }
    }

    /// Records a phase measured elsewhere (e.g. inside a parallel section).
    pub fn record_phase(&self, name: &str, seconds: f64) {
        lock(&self.timer)
            .phases
            .push((format!("{}{name}", self.prefix), seconds));
    }

    /// The phases recorded so far, in the order they ended.
    pub fn phases(&self) -> Vec<(String, f64)> {
        lock(&self.timer).phases.clone()
    }

    /// A copy of the timer.
    pub fn timer(&self) -> PhaseTimer {
        lock(&self.timer).clone()
    }

    /// Total seconds of the phases named `name` recorded so far.
    pub fn phase_seconds(&self, name: &str) -> f64 {
        lock(&self.timer).seconds(&format!("{}{name}", self.prefix))
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

    #[test]
    fn guards_record_nested_phases_and_early_returns() {
        let ctx = RunCtx::new(3);
        let r: Result<(), MethodError> = (|| {
            let _outer = ctx.phase_guard("outer");
            ctx.phase("inner", || ctx.checkpoint())?;
            Err(MethodError::Failed("stop".into()))
        })();
        assert!(r.is_err());
        let names: Vec<String> = ctx.phases().into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, ["inner", "outer"]);
        assert!(ctx.phase_seconds("outer") >= ctx.phase_seconds("inner"));
    }

    #[test]
    fn sub_steps_share_the_timer_and_map_progress() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let s2 = seen.clone();
        let ctx = RunCtx::new(1).with_progress(Arc::new(move |f| s2.lock().unwrap().push(f)));
        let step = ctx.sub_step(9, "jet/", 0.5, 1.0);
        step.progress(0.5);
        step.progress(2.0);
        step.phase("x", || ());
        assert_eq!(step.seed, 9);
        assert_eq!(*seen.lock().unwrap(), [0.75, 1.0]);
        assert_eq!(ctx.phases()[0].0, "jet/x");
    }
}
