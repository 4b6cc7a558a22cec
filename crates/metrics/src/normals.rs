//! Normal errors: estimated normals `n` against ground-truth normals `g`, per point.
//!
//! * Unoriented angle `acos(|n . g|)` in `[0, 90]` degrees; oriented angle `acos(n . g)`
//!   in `[0, 180]` (only with [`NormalOptions::oriented`], for methods that claim an
//!   orientation) together with the flip rate, the share of points with `n . g < 0`.
//! * Both vectors are normalised first; dot products are clamped to `[-1, 1]`.
//! * An estimated normal that is zero or not finite is *invalid*: it counts as a 90
//!   degree error (unoriented and oriented), is never a flip, and is counted in
//!   `invalid_normals`.
//! * A point whose ground-truth normal is zero or not finite is left out of every
//!   statistic and counted in `normal_gt_missing`.
//! * Statistics over the points: mean, RMS, median (nearest rank), max, population std,
//!   in degrees and radians; PGP5 / PGP10 = % of points with unoriented error strictly
//!   below 5 / 10 degrees.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::{PointCloud, TriMesh};
use serde::{Deserialize, Serialize};

use crate::error::{MetricsError, Result};
use crate::reference::Reference;
use crate::report::{Entries, Report, put, serialize_as_entries};
use crate::stats::Summary;

/// Options of [`eval_normals`].
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct NormalOptions {
    /// Also report oriented errors and the flip rate (false: the method does not claim
    /// an orientation).
    pub oriented: bool,
}

/// Angle statistics in degrees (see [`Summary`] for the definitions).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AngleStats {
    /// Mean angle.
    pub mean_deg: f64,
    /// Root mean square angle.
    pub rms_deg: f64,
    /// Median angle (nearest rank).
    pub median_deg: f64,
    /// Largest angle.
    pub max_deg: f64,
    /// Population standard deviation.
    pub std_deg: f64,
}

impl AngleStats {
    fn of(deg: &[f64]) -> Self {
        let s = Summary::of(deg);
        AngleStats {
            mean_deg: s.mean,
            rms_deg: s.rms,
            median_deg: s.median,
            max_deg: s.max,
            std_deg: s.std,
        }
    }

    fn put(&self, e: &mut Entries, prefix: &str) {
        for (name, v) in [
            ("mean", self.mean_deg),
            ("rms", self.rms_deg),
            ("median", self.median_deg),
            ("max", self.max_deg),
            ("std", self.std_deg),
        ] {
            put(e, format!("{prefix}_{name}_deg"), v);
        }
        for (name, v) in [
            ("mean", self.mean_deg),
            ("rms", self.rms_deg),
            ("median", self.median_deg),
            ("max", self.max_deg),
            ("std", self.std_deg),
        ] {
            put(e, format!("{prefix}_{name}_rad"), v.to_radians());
        }
    }
}

/// Result of [`eval_normals`].
#[derive(Debug, Clone, PartialEq)]
pub struct NormalEval {
    /// Points evaluated (ground truth available).
    pub points: usize,
    /// Points with a zero or non-finite estimated normal (counted as 90 degrees).
    pub invalid: usize,
    /// Points left out for lack of a ground-truth normal.
    pub gt_missing: usize,
    /// Unoriented error statistics.
    pub unoriented: AngleStats,
    /// % of points with unoriented error < 5 degrees.
    pub pgp5: f64,
    /// % of points with unoriented error < 10 degrees.
    pub pgp10: f64,
    /// Oriented error statistics (when requested).
    pub oriented: Option<AngleStats>,
    /// Share of points with `n . g < 0` (when oriented errors were requested).
    pub flip_rate: Option<f64>,
    /// Where the ground truth came from: `given`, `source` or `closest`.
    pub gt_kind: String,
    /// Unoriented error per input point in degrees (NaN where the ground truth is
    /// missing). Not serialised.
    pub per_point_deg: Vec<f64>,
}

impl Report for NormalEval {
    fn entries(&self) -> Entries {
        let mut e = Entries::new();
        self.unoriented.put(&mut e, "normal");
        put(&mut e, "normal_pgp5", self.pgp5);
        put(&mut e, "normal_pgp10", self.pgp10);
        match &self.oriented {
            Some(o) => o.put(&mut e, "normal_oriented"),
            None => {
                for s in ["mean", "rms", "median", "max", "std"] {
                    put(&mut e, format!("normal_oriented_{s}_deg"), None::<f64>);
                }
                for s in ["mean", "rms", "median", "max", "std"] {
                    put(&mut e, format!("normal_oriented_{s}_rad"), None::<f64>);
                }
            }
        }
        put(&mut e, "normal_flip_rate", self.flip_rate);
        put(&mut e, "normal_points", self.points);
        put(&mut e, "invalid_normals", self.invalid);
        put(&mut e, "normal_gt_missing", self.gt_missing);
        put(&mut e, "normal_gt", self.gt_kind.clone());
        e
    }
}
serialize_as_entries!(NormalEval);

/// Unit vector, or `None` for a zero or non-finite one.
fn unit(v: DVec3) -> Option<DVec3> {
    let l = v.length();
    (l.is_finite() && l > 0.0).then(|| v / l)
}

/// Unoriented angle in degrees between `n` and `g` (`None` if `g` is unusable; 90 if `n`
/// is invalid).
pub fn unoriented_angle_deg(n: DVec3, g: DVec3) -> Option<f64> {
    let g = unit(g)?;
    Some(match unit(n) {
        Some(n) => n.dot(g).abs().clamp(-1.0, 1.0).acos().to_degrees(),
        None => 90.0,
    })
}

/// Compares `estimated[i]` with `gt[i]` (see the module docs).
pub fn eval_normals(estimated: &[DVec3], gt: &[DVec3], opts: &NormalOptions) -> Result<NormalEval> {
    eval_normals_kind(estimated, gt, opts, "given")
}

fn eval_normals_kind(
    estimated: &[DVec3],
    gt: &[DVec3],
    opts: &NormalOptions,
    kind: &str,
) -> Result<NormalEval> {
    if estimated.len() != gt.len() {
        return Err(MetricsError::InvalidInput(format!(
            "{} estimated normals but {} ground-truth normals",
            estimated.len(),
            gt.len()
        )));
    }
    // (unoriented deg, oriented deg, flipped, invalid); NaN where the GT is missing.
    let per: Vec<(f64, f64, bool, bool)> = estimated
        .par_iter()
        .zip(gt.par_iter())
        .map(|(&n, &g)| match unit(g) {
            None => (f64::NAN, f64::NAN, false, false),
            Some(g) => match unit(n) {
                None => (90.0, 90.0, false, true),
                Some(n) => {
                    let d = n.dot(g).clamp(-1.0, 1.0);
                    (
                        d.abs().acos().to_degrees(),
                        d.acos().to_degrees(),
                        d < 0.0,
                        false,
                    )
                }
            },
        })
        .collect();
    let valid: Vec<&(f64, f64, bool, bool)> = per.iter().filter(|x| !x.0.is_nan()).collect();
    let points = valid.len();
    if points == 0 {
        return Err(MetricsError::InvalidInput(
            "no point has a usable ground-truth normal".to_string(),
        ));
    }
    let un: Vec<f64> = valid.iter().map(|x| x.0).collect();
    let pct = |lim: f64| 100.0 * un.iter().filter(|&&a| a < lim).count() as f64 / points as f64;
    let (oriented, flip_rate) = if opts.oriented {
        let or: Vec<f64> = valid.iter().map(|x| x.1).collect();
        let flips = valid.iter().filter(|x| x.2).count();
        (
            Some(AngleStats::of(&or)),
            Some(flips as f64 / points as f64),
        )
    } else {
        (None, None)
    };
    Ok(NormalEval {
        points,
        invalid: valid.iter().filter(|x| x.3).count(),
        gt_missing: per.len() - points,
        unoriented: AngleStats::of(&un),
        pgp5: pct(5.0),
        pgp10: pct(10.0),
        oriented,
        flip_rate,
        gt_kind: kind.to_string(),
        per_point_deg: per.iter().map(|x| x.0).collect(),
    })
}

/// Where the ground-truth normals of a cloud come from.
#[derive(Debug, Clone, Copy)]
pub enum NormalGroundTruth<'a> {
    /// One normal per point, given by the caller.
    Given(&'a [DVec3]),
    /// The ground-truth cloud written by `reconbench gen` (its normals are the exact
    /// normals at the clean sample positions): point `i` is compared with the ground-truth
    /// point of the same source sample (see [`ground_truth_index`]).
    SourceSamples(&'a PointCloud),
    /// The reference normal at the closest surface point of each (possibly perturbed)
    /// point.
    ClosestPoint(&'a Reference<'a>),
}

/// For each point of `cloud`, the index of the point of the ground-truth cloud `gt` that
/// comes from the same clean sample: matched by source id when both clouds have source
/// ids (the first ground-truth point with that id; `None` for an outlier's
/// `u32::MAX` or an id `gt` does not have), else by index when both have the same length.
pub fn ground_truth_index(cloud: &PointCloud, gt: &PointCloud) -> Result<Vec<Option<usize>>> {
    match (cloud.source_ids(), gt.source_ids()) {
        (Some(ids), Some(gt_ids)) => {
            let mut map = std::collections::HashMap::with_capacity(gt_ids.len());
            for (j, &s) in gt_ids.iter().enumerate() {
                if s != u32::MAX {
                    map.entry(s).or_insert(j);
                }
            }
            Ok(ids.iter().map(|s| map.get(s).copied()).collect())
        }
        _ if cloud.len() == gt.len() => Ok((0..cloud.len()).map(Some).collect()),
        _ => Err(MetricsError::InvalidInput(format!(
            "cannot match {} points to a ground-truth cloud of {} points without source ids",
            cloud.len(),
            gt.len()
        ))),
    }
}

/// Ground-truth normals of a cloud from the ground-truth cloud (see
/// [`NormalGroundTruth::SourceSamples`]); zero (= missing) where no point matches.
pub fn gt_normals_from_source(cloud: &PointCloud, gt: &PointCloud) -> Result<Vec<DVec3>> {
    let gn = gt.normals().ok_or_else(|| {
        MetricsError::MissingAttribute("normals (ground-truth cloud)".to_string())
    })?;
    Ok(ground_truth_index(cloud, gt)?
        .into_iter()
        .map(|j| j.map_or(DVec3::ZERO, |j| gn[j]))
        .collect())
}

/// Ground-truth normals at the closest reference points.
pub fn gt_normals_closest(points: &[DVec3], reference: &Reference) -> Result<Vec<DVec3>> {
    Ok(reference
        .closest_batch(points)?
        .into_iter()
        .map(|h| h.normal)
        .collect())
}

/// Evaluates the normals of a cloud (its `normals()` are the estimates).
pub fn eval_cloud_normals(
    cloud: &PointCloud,
    gt: NormalGroundTruth,
    opts: &NormalOptions,
) -> Result<NormalEval> {
    let est = cloud
        .normals()
        .ok_or_else(|| MetricsError::MissingAttribute("normals".to_string()))?;
    let (g, kind) = match gt {
        NormalGroundTruth::Given(g) => (g.to_vec(), "given"),
        NormalGroundTruth::SourceSamples(clean) => {
            (gt_normals_from_source(cloud, clean)?, "source")
        }
        NormalGroundTruth::ClosestPoint(r) => {
            (gt_normals_closest(cloud.positions(), r)?, "closest")
        }
    };
    eval_normals_kind(est, &g, opts, kind)
}

/// Evaluates a mesh's angle-weighted vertex normals ([`TriMesh::angle_weighted_normals`])
/// against one ground-truth normal per vertex (for an interpolating mesh, vertex `i` is
/// input point `i`, so pass the ground truth of the input cloud). Unreferenced vertices
/// get a zero normal and count as invalid.
pub fn eval_mesh_vertex_normals(
    mesh: &TriMesh,
    gt: &[DVec3],
    opts: &NormalOptions,
) -> Result<NormalEval> {
    eval_normals_kind(&mesh.angle_weighted_normals(), gt, opts, "given")
}
