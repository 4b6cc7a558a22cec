//! Test-only methods (`debug-*`), hidden from `list` unless `--all`. They exercise the
//! runner's isolation: each misbehaves in one way, and only its own cell may fail.
//! They are normal estimators so that cells stay cheap.

use std::time::Duration;

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostics, MethodError, NormalEstimator, Normals, RunCtx};
use serde::{Deserialize, Serialize};

use crate::registry::{MethodEntry, ParamDoc, normals};

/// No parameters.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NoParams {}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Behaviour {
    Panic,
    Abort,
    Hang,
    Alloc(u64),
    Sleep(f64),
}

/// A misbehaving normal estimator.
#[derive(Debug)]
pub struct Misbehave {
    name: &'static str,
    behaviour: Behaviour,
}

impl NormalEstimator for Misbehave {
    fn name(&self) -> &str {
        self.name
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        match self.behaviour {
            Behaviour::Panic => panic!("debug-panic: deliberate panic"),
            Behaviour::Abort => std::process::abort(),
            Behaviour::Hang => loop {
                // Deliberately ignores ctx.checkpoint(): the runner must kill it.
                std::thread::sleep(Duration::from_millis(50));
            },
            Behaviour::Alloc(mib) => {
                let mut hold: Vec<Vec<u8>> = Vec::new();
                for _ in 0..mib.div_ceil(16) {
                    // Touch every page so the memory is resident.
                    hold.push(vec![1u8; 16 << 20]);
                    std::thread::sleep(Duration::from_millis(5));
                }
                // Hold it until killed (or a minute).
                std::thread::sleep(Duration::from_secs(60));
                drop(hold);
                Err(MethodError::Failed("debug-alloc was not stopped".into()))
            }
            Behaviour::Sleep(s) => {
                ctx.phase("sleep", || std::thread::sleep(Duration::from_secs_f64(s)));
                Ok(Normals {
                    normals: vec![DVec3::Z; cloud.len()],
                    oriented: false,
                    diagnostics: Diagnostics::new(),
                })
            }
        }
    }
}

/// `debug-panic`: panics.
pub fn panic() -> MethodEntry {
    normals::<NoParams>(
        "debug-panic",
        "debug",
        "panics (tests cell isolation)",
        &[],
        |_, _| {
            Ok(Box::new(Misbehave {
                name: "debug-panic",
                behaviour: Behaviour::Panic,
            }))
        },
    )
    .hidden()
}

/// `debug-abort`: aborts the process (SIGABRT).
pub fn abort() -> MethodEntry {
    normals::<NoParams>(
        "debug-abort",
        "debug",
        "aborts the process (SIGABRT)",
        &[],
        |_, _| {
            Ok(Box::new(Misbehave {
                name: "debug-abort",
                behaviour: Behaviour::Abort,
            }))
        },
    )
    .hidden()
}

/// `debug-hang`: never returns and ignores its time budget.
pub fn hang() -> MethodEntry {
    normals::<NoParams>(
        "debug-hang",
        "debug",
        "hangs, ignoring its time budget",
        &[],
        |_, _| {
            Ok(Box::new(Misbehave {
                name: "debug-hang",
                behaviour: Behaviour::Hang,
            }))
        },
    )
    .hidden()
}

/// Parameters of `debug-alloc`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AllocParams {
    /// Memory to allocate and hold.
    pub mib: u64,
}

impl Default for AllocParams {
    fn default() -> Self {
        Self { mib: 512 }
    }
}

/// `debug-alloc`: allocates `mib` MiB and holds it (tests the memory limit).
pub fn alloc() -> MethodEntry {
    normals::<AllocParams>(
        "debug-alloc",
        "debug",
        "allocates and holds memory (tests the memory limit)",
        &[ParamDoc {
            name: "mib",
            unit: "MiB",
            doc: "memory to allocate and hold",
        }],
        |p, _| {
            Ok(Box::new(Misbehave {
                name: "debug-alloc",
                behaviour: Behaviour::Alloc(p.mib),
            }))
        },
    )
    .hidden()
}

/// Parameters of `debug-sleep`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SleepParams {
    /// Sleep time.
    pub seconds: f64,
}

impl Default for SleepParams {
    fn default() -> Self {
        Self { seconds: 0.1 }
    }
}

/// `debug-sleep`: sleeps, then returns +Z normals (a slow, well-behaved method).
pub fn sleep() -> MethodEntry {
    normals::<SleepParams>(
        "debug-sleep",
        "debug",
        "sleeps, then returns +Z normals (tests resume and timeouts)",
        &[ParamDoc {
            name: "seconds",
            unit: "s",
            doc: "sleep time",
        }],
        |p, _| {
            if !(p.seconds.is_finite() && p.seconds >= 0.0) {
                return Err(MethodError::InvalidParameter {
                    name: "seconds".into(),
                    message: format!("must be >= 0, got {}", p.seconds),
                });
            }
            Ok(Box::new(Misbehave {
                name: "debug-sleep",
                behaviour: Behaviour::Sleep(p.seconds),
            }))
        },
    )
    .hidden()
}
