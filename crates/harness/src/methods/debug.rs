//! Test-only methods (`debug-*`), hidden from `list` unless `--all`. They exercise the
//! runner's isolation: each misbehaves in one way, and only its own cell may fail.
//! Most are normal estimators so that cells stay cheap; `debug-splats` is a trivial
//! reconstructor that needs oriented normals (the pipeline tests' subject).

use std::time::Duration;

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Diagnostics, MethodError, NormalEstimator, Normals, Reconstruction, Reconstructor, RunCtx,
};
use serde::{Deserialize, Serialize};

use crate::entry::{Built, MethodEntry, MethodKind, Needs, ParamDoc, Unit, custom};

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
    custom::<NoParams>(
        MethodKind::Normals,
        "debug-panic",
        "debug",
        "panics (tests cell isolation)",
        &[],
        |_, _| {
            Ok(Built::Normals(Box::new(Misbehave {
                name: "debug-panic",
                behaviour: Behaviour::Panic,
            })))
        },
    )
    .hidden()
}

/// `debug-abort`: aborts the process (SIGABRT).
pub fn abort() -> MethodEntry {
    custom::<NoParams>(
        MethodKind::Normals,
        "debug-abort",
        "debug",
        "aborts the process (SIGABRT)",
        &[],
        |_, _| {
            Ok(Built::Normals(Box::new(Misbehave {
                name: "debug-abort",
                behaviour: Behaviour::Abort,
            })))
        },
    )
    .hidden()
}

/// `debug-hang`: never returns and ignores its time budget.
pub fn hang() -> MethodEntry {
    custom::<NoParams>(
        MethodKind::Normals,
        "debug-hang",
        "debug",
        "hangs, ignoring its time budget",
        &[],
        |_, _| {
            Ok(Built::Normals(Box::new(Misbehave {
                name: "debug-hang",
                behaviour: Behaviour::Hang,
            })))
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
    custom::<AllocParams>(
        MethodKind::Normals,
        "debug-alloc",
        "debug",
        "allocates and holds memory (tests the memory limit)",
        const {
            &[ParamDoc::new(
                "mib",
                Unit::MiB,
                "memory to allocate and hold",
            )]
        },
        |p, _| {
            Ok(Built::Normals(Box::new(Misbehave {
                name: "debug-alloc",
                behaviour: Behaviour::Alloc(p.mib),
            })))
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
    custom::<SleepParams>(
        MethodKind::Normals,
        "debug-sleep",
        "debug",
        "sleeps, then returns +Z normals (tests resume and timeouts)",
        const { &[ParamDoc::new("seconds", Unit::Seconds, "sleep time")] },
        |p, _| {
            if !(p.seconds.is_finite() && p.seconds >= 0.0) {
                return Err(MethodError::InvalidParameter {
                    name: "seconds".into(),
                    message: format!("must be >= 0, got {}", p.seconds),
                });
            }
            Ok(Built::Normals(Box::new(Misbehave {
                name: "debug-sleep",
                behaviour: Behaviour::Sleep(p.seconds),
            })))
        },
    )
    .hidden()
}

/// Parameters of `debug-splats`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SplatParams {
    /// Side of each splat triangle.
    pub size: f64,
}

impl Default for SplatParams {
    fn default() -> Self {
        Self { size: 0.002 }
    }
}

/// `debug-splats`: one small triangle per point in the plane of its normal, wound
/// counter-clockwise about it. A reconstructor that needs oriented normals, so pipelines
/// (`steps = ["gt-normals", "debug-splats"]`) and the load-time needs check have a
/// cheap test subject.
#[derive(Debug)]
pub struct Splats {
    size: f64,
}

impl Reconstructor for Splats {
    fn name(&self) -> &str {
        "debug-splats"
    }

    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        let normals = cloud
            .normals()
            .ok_or_else(|| MethodError::InvalidInput("debug-splats needs normals".into()))?;
        let _g = ctx.phase_guard("splat");
        let mut vertices = Vec::with_capacity(3 * cloud.len());
        let mut faces = Vec::with_capacity(cloud.len());
        for (i, (&p, &n)) in cloud.positions().iter().zip(normals).enumerate() {
            let n = n.try_normalize().unwrap_or(DVec3::Z);
            let u = n.any_orthonormal_vector();
            let v = n.cross(u);
            let h = self.size;
            vertices.extend([p, p + h * u, p + h * v]);
            let b = 3 * i as u32;
            faces.push([b, b + 1, b + 2]);
        }
        let mesh = reconbench_geom::TriMesh::new(vertices, faces)?;
        Ok(Reconstruction {
            mesh,
            refused: Vec::new(),
            diagnostics: Diagnostics::new(),
        })
    }
}

/// Registry entry of `debug-splats`.
pub fn splats() -> MethodEntry {
    custom::<SplatParams>(
        MethodKind::Reconstruct,
        "debug-splats",
        "debug",
        "one small triangle per point, in the plane of its (oriented) normal",
        const {
            &[ParamDoc::new(
                "size",
                Unit::Diag,
                "side of each splat triangle",
            )]
        },
        |p, _| {
            if !(p.size.is_finite() && p.size > 0.0) {
                return Err(MethodError::InvalidParameter {
                    name: "size".into(),
                    message: format!("must be > 0, got {}", p.size),
                });
            }
            Ok(Built::Reconstruct(Box::new(Splats { size: p.size })))
        },
    )
    .needing(Needs::OrientedNormals)
    .hidden()
}
