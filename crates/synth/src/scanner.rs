//! A virtual range scanner: pinhole range images from several viewpoints, with
//! occlusion (first hit), grazing-angle dropout, range-dependent noise along the ray and
//! per-scan misalignment; merged output with scan id and view direction per point.
//! Works on every [`Shape`] through [`Shape::ray_intersect`]: analytic shapes (closed
//! form or sphere tracing on the exact distance) and [`crate::shapes::MeshShape`] (BVH).

use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cloud::{GroundTruthCloud, NO_FEATURE};
use crate::error::{Result, SynthError};
use crate::perturb::{self, PerturbContext, PerturbSpec, Reference};
use crate::shape::Shape;
use crate::spec::{fmt_f64, format_kv, parse_f64, parse_kv, parse_usize};
use crate::util::{frame, rng_for, std_normal, unit_vector};

/// Scanner settings. String form (all keys optional):
/// `views=8,res=128,fov=40,dist=1.5,grazing=80,noise=0,misalign=0,shift=0`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ScanSpec {
    /// Number of viewpoints, spread uniformly on a sphere around the shape (Fibonacci
    /// lattice under a random rotation drawn from the seed).
    pub views: usize,
    /// Range-image resolution (pixels per side).
    pub resolution: usize,
    /// Full field of view in degrees.
    pub fov_deg: f64,
    /// Camera distance from the bounding-box centre, relative to the diagonal.
    pub distance: f64,
    /// Returns whose angle between ray and surface normal exceeds this (degrees) are
    /// dropped (grazing-angle dropout).
    pub grazing_deg: f64,
    /// Range noise: standard deviation along the ray at the camera distance, relative to
    /// the diagonal; it grows with the squared range, `sigma(t) = noise (t / distance)^2`.
    pub noise: f64,
    /// Per-scan misalignment: max rotation per Euler axis (degrees) about the scan's
    /// centroid.
    pub misalign_deg: f64,
    /// Per-scan misalignment: max translation per axis (relative to the diagonal).
    pub misalign_shift: f64,
    /// Explicit camera positions (overrides `views`/`distance`), each looking at the
    /// bounding-box centre.
    pub viewpoints: Option<Vec<[f64; 3]>>,
}

impl Default for ScanSpec {
    fn default() -> Self {
        Self {
            views: 8,
            resolution: 128,
            fov_deg: 40.0,
            distance: 1.5,
            grazing_deg: 80.0,
            noise: 0.0,
            misalign_deg: 0.0,
            misalign_shift: 0.0,
            viewpoints: None,
        }
    }
}

const SCAN_KEYS: &str = "views, res, fov, dist, grazing, noise, misalign, shift";

impl FromStr for ScanSpec {
    type Err = SynthError;
    fn from_str(s: &str) -> Result<Self> {
        let kv = parse_kv("scan", s, false)?;
        if !kv.name.is_empty() && kv.name != "scan" {
            return Err(SynthError::Parse {
                what: "scan",
                input: s.into(),
                message: format!(
                    "expected 'scan:key=value,...' or 'key=value,...' with keys {SCAN_KEYS}"
                ),
            });
        }
        let mut spec = ScanSpec::default();
        let owner = "scan";
        for (k, v) in &kv.params {
            match k.as_str() {
                "views" => spec.views = parse_usize(owner, k, v)?,
                "res" => spec.resolution = parse_usize(owner, k, v)?,
                "fov" => spec.fov_deg = parse_f64(owner, k, v)?,
                "dist" => spec.distance = parse_f64(owner, k, v)?,
                "grazing" => spec.grazing_deg = parse_f64(owner, k, v)?,
                "noise" => spec.noise = parse_f64(owner, k, v)?,
                "misalign" => spec.misalign_deg = parse_f64(owner, k, v)?,
                "shift" => spec.misalign_shift = parse_f64(owner, k, v)?,
                _ => {
                    return Err(SynthError::UnknownParameter {
                        owner: owner.into(),
                        name: k.clone(),
                        valid: SCAN_KEYS.into(),
                    });
                }
            }
        }
        spec.validate()?;
        Ok(spec)
    }
}

impl fmt::Display for ScanSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&format_kv(
            "",
            [
                ("views", self.views.to_string()),
                ("res", self.resolution.to_string()),
                ("fov", fmt_f64(self.fov_deg)),
                ("dist", fmt_f64(self.distance)),
                ("grazing", fmt_f64(self.grazing_deg)),
                ("noise", fmt_f64(self.noise)),
                ("misalign", fmt_f64(self.misalign_deg)),
                ("shift", fmt_f64(self.misalign_shift)),
            ],
        ))
    }
}

impl ScanSpec {
    /// Checks ranges.
    pub fn validate(&self) -> Result<()> {
        let bad = |k: &str, m: String| Err(SynthError::invalid("scan", k, m));
        if self.views == 0 && self.viewpoints.is_none() {
            return bad("views", "must be >= 1".into());
        }
        if self.resolution == 0 || self.resolution > 8192 {
            return bad("res", format!("{} must be in 1..=8192", self.resolution));
        }
        if !(self.fov_deg > 0.0 && self.fov_deg < 179.0) {
            return bad("fov", format!("{} must be in (0, 179)", self.fov_deg));
        }
        if (self.distance.is_nan() || self.distance <= 0.5) && self.viewpoints.is_none() {
            return bad(
                "dist",
                format!("{} must be > 0.5 (outside the bounding box)", self.distance),
            );
        }
        if !(0.0..=90.0).contains(&self.grazing_deg) {
            return bad(
                "grazing",
                format!("{} must be in [0, 90]", self.grazing_deg),
            );
        }
        for (k, v) in [
            ("noise", self.noise),
            ("misalign", self.misalign_deg),
            ("shift", self.misalign_shift),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return bad(k, format!("{v} must be >= 0"));
            }
        }
        Ok(())
    }

    /// Camera positions for `shape` and `seed`.
    pub fn camera_positions(&self, shape: &dyn Shape, seed: u64) -> Vec<DVec3> {
        if let Some(v) = &self.viewpoints {
            return v.iter().map(|p| DVec3::from_array(*p)).collect();
        }
        let b = shape.aabb();
        let r = self.distance * b.diagonal();
        // Fibonacci lattice, randomly rotated.
        let mut rng = rng_for(seed, "scan-views", 0);
        let axis = unit_vector(&mut rng);
        let angle = crate::util::uniform(&mut rng, 0.0, std::f64::consts::TAU);
        let rot = glam::DMat3::from_axis_angle(axis, angle);
        let n = self.views;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let s = (1.0 - z * z).sqrt();
                let phi = golden * i as f64;
                b.center() + rot * DVec3::new(s * phi.cos(), s * phi.sin(), z) * r
            })
            .collect()
    }
}

/// Scans `shape`: one range image per viewpoint, merged. Source ids number the hits in
/// output order; clean positions are the exact hits; `view_dirs` point from each hit to
/// its camera.
pub fn scan(shape: &dyn Shape, spec: &ScanSpec, seed: u64) -> Result<GroundTruthCloud> {
    spec.validate()?;
    let b = shape.aabb();
    let diag = b.diagonal();
    let centre = b.center();
    let cams = spec.camera_positions(shape, seed);
    let res = spec.resolution;
    let half = (0.5 * spec.fov_deg).to_radians().tan();
    let cos_graze = spec.grazing_deg.to_radians().cos();
    let mut out = GroundTruthCloud {
        scan_ids: Some(Vec::new()),
        view_dirs: Some(Vec::new()),
        ..Default::default()
    };
    for (si, &cam) in cams.iter().enumerate() {
        let fwd = (centre - cam).normalize();
        let (u, v) = frame(fwd);
        let max_t = (cam - centre).length() + diag;
        let hits: Vec<Option<(DVec3, DVec3, f64)>> = (0..res * res)
            .into_par_iter()
            .map(|px| {
                let (a, c) = ((px % res) as f64, (px / res) as f64);
                let x = (2.0 * (a + 0.5) / res as f64 - 1.0) * half;
                let y = (2.0 * (c + 0.5) / res as f64 - 1.0) * half;
                let dir = (fwd + u * x + v * y).normalize();
                let t = shape.ray_intersect(cam, dir, max_t)?;
                let p = cam + dir * t;
                let n = shape.closest_point(p).normal;
                if n.dot(dir).abs() < cos_graze {
                    return None;
                }
                Some((p, n, t))
            })
            .collect();
        let mut rng = rng_for(seed, "scan-noise", si as u64);
        let ref_range = (cam - centre).length();
        for (p, n, t) in hits.into_iter().flatten() {
            let dir = (p - cam).normalize();
            let sigma = spec.noise * diag * (t / ref_range).powi(2);
            let noisy = if sigma > 0.0 {
                p + dir * (std_normal(&mut rng) * sigma)
            } else {
                p
            };
            let fd = shape.feature_distance(p);
            out.positions.push(noisy);
            out.clean_positions.push(p);
            out.normals.push(n);
            out.source_ids.push(out.source_ids.len() as u32);
            out.feature_distance
                .push(if fd.is_finite() { fd } else { NO_FEATURE });
            out.is_outlier.push(false);
            out.scan_ids.as_mut().expect("set").push(si as u32);
            out.view_dirs.as_mut().expect("set").push(-dir);
        }
    }
    if out.is_empty() {
        return Err(SynthError::Unsatisfiable(format!(
            "the scan of '{}' hit nothing (check the viewpoints and field of view)",
            shape.name()
        )));
    }
    if spec.misalign_deg > 0.0 || spec.misalign_shift > 0.0 {
        let step = PerturbSpec::Misalign {
            groups: cams.len(),
            angle: spec.misalign_deg,
            shift: spec.misalign_shift,
            relative_to: Reference::Diagonal,
        };
        perturb::apply(
            &mut out,
            &step,
            &PerturbContext { aabb: b },
            &mut rng_for(seed, "scan-misalign", 0),
        )?;
    }
    Ok(out)
}
