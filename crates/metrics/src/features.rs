//! Sharp-feature metrics: point labelling against the ground-truth feature curves, curve
//! coverage, and feature recovery of a mesh.
//!
//! * A ground-truth curve *counts* when its normal deviation `180 - dihedral_deg` (the
//!   angle between the normals of the two patches; 90 for a cube edge, in synth's
//!   convention where a cube edge has `dihedral_deg = 90`) is `>= feature_angle`
//!   (default 20 degrees). Corners count under the same rule.
//! * Distances to the curves are exact point-to-polyline distances (per segment, through
//!   a bounding-box hierarchy of the segments).
//! * `r = radius_factor x s` with `s` the mean spacing of the cloud (distance to the
//!   nearest other point, averaged; `radius_factor` 1 by default), unless given.
//! * GT positive set at `r`: points whose *clean* position is within `r` of a counted
//!   curve (also at `2r`). Detected: a nonzero `feature` label.
//! * precision = TP / detected, recall = TP / positives, F1 = 2 TP / (2 TP + FP + FN).
//! * `feature_dist_mean` / `feature_dist_max` (seed 002's delta_avg / delta_inf, measured to
//!   the exact curve instead of the nearest original feature point): distance
//!   of the detected points' (observed) positions to the nearest counted curve.
//! * Coverage: the counted curves are sampled every `s / 2` (midpoints of equal pieces,
//!   each weighted by its length); a sample is covered when the clean position of a
//!   detected point is within `r`; coverage = covered length / total length.
//! * Mesh feature recovery: the curves sampled the same way; a sample is recovered when a
//!   sharp mesh edge (manifold edge whose face normals differ by `>= feature_angle / 2`)
//!   is within `r`; recovery = recovered length / total length. Face-normal error near
//!   the curves: faces whose centroid is within `r` of a counted curve, unoriented angle
//!   between the face normal and the reference normal at the centroid's closest point.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::spatial::closest_point_on_segment;
use reconbench_geom::topology::MeshTopology;
use reconbench_geom::{Aabb, Channel, PointCloud, PointIndex, TriMesh, mean_spacing};
use reconbench_synth::FeatureCurve;
use serde::{Deserialize, Serialize};

use crate::boxtree::BoxTree;
use crate::error::{MetricsError, Result, check_positive};
use crate::normals::unoriented_angle_deg;
use crate::reference::{Reference, mesh_sharp_edges};
use crate::report::{Entries, Report, put, serialize_as_entries};

/// Name of the label channel that marks detected feature points (0 none, 1 edge,
/// 2 corner; any nonzero value counts as detected).
pub const FEATURE_CHANNEL: &str = "feature";

/// Options of the feature metrics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FeatureOptions {
    /// A curve counts when `180 - dihedral_deg >= feature_angle_deg` (20). A mesh
    /// reference's edges count from 30 degrees at least (synth's
    /// `DEFAULT_MESH_FEATURE_ANGLE_DEG`, below which its facets of smooth parts would
    /// count as features).
    pub feature_angle_deg: f64,
    /// `r` as a multiple of the mean spacing (1).
    pub radius_factor: f64,
    /// Explicit absolute `r` (overrides `radius_factor`; the sampling step of the
    /// curves stays spacing / 2).
    pub radius: Option<f64>,
    /// Name of the detection label channel ([`FEATURE_CHANNEL`]).
    pub label_channel: String,
}

impl Default for FeatureOptions {
    fn default() -> Self {
        Self {
            feature_angle_deg: 20.0,
            radius_factor: 1.0,
            radius: None,
            label_channel: FEATURE_CHANNEL.to_string(),
        }
    }
}

/// Whether a ground-truth curve counts at `feature_angle_deg`.
pub fn curve_counts(c: &FeatureCurve, feature_angle_deg: f64) -> bool {
    180.0 - c.dihedral_deg >= feature_angle_deg
}

/// The counted curves' segments with a hierarchy for exact nearest-distance queries.
#[derive(Debug, Clone)]
pub struct CurveSet {
    segments: Vec<(DVec3, DVec3)>,
    tree: BoxTree,
    /// (segment index range) per non-corner curve, for length sampling.
    polylines: Vec<Vec<DVec3>>,
}

impl CurveSet {
    /// The curves that count at `feature_angle_deg`.
    pub fn new(curves: &[FeatureCurve], feature_angle_deg: f64) -> Self {
        let counted: Vec<&FeatureCurve> = curves
            .iter()
            .filter(|c| curve_counts(c, feature_angle_deg))
            .collect();
        let mut segments = Vec::new();
        let mut polylines = Vec::new();
        for c in counted {
            match c.points.len() {
                0 => {}
                1 => segments.push((c.points[0], c.points[0])),
                _ => {
                    segments.extend(c.points.windows(2).map(|w| (w[0], w[1])));
                    if !c.is_corner {
                        polylines.push(c.points.clone());
                    }
                }
            }
        }
        Self::from_parts(segments, polylines)
    }

    fn from_parts(segments: Vec<(DVec3, DVec3)>, polylines: Vec<Vec<DVec3>>) -> Self {
        let boxes: Vec<Aabb> = segments
            .iter()
            .map(|&(a, b)| Aabb::from_points(&[a, b]))
            .collect();
        CurveSet {
            tree: BoxTree::new(&boxes),
            segments,
            polylines,
        }
    }

    /// Number of segments (a corner is one zero-length segment).
    pub fn n_segments(&self) -> usize {
        self.segments.len()
    }

    /// Total length of the counted curves.
    pub fn length(&self) -> f64 {
        self.polylines
            .iter()
            .flat_map(|p| p.windows(2))
            .map(|w| (w[1] - w[0]).length())
            .sum()
    }

    /// Exact distance from `p` to the nearest segment, searching no farther than
    /// `max_dist` (infinity if none is that close).
    pub fn distance_within(&self, p: DVec3, max_dist: f64) -> f64 {
        let mut stack = Vec::new();
        self.tree
            .nearest(p, max_dist * max_dist, None, &mut stack, |s| {
                let (a, b) = self.segments[self.tree.item(s) as usize];
                (closest_point_on_segment(p, a, b).0 - p).length_squared()
            })
            .map_or(f64::INFINITY, |(_, d2)| d2.sqrt())
    }

    /// Exact distance from `p` to the nearest segment (infinity without segments).
    pub fn distance(&self, p: DVec3) -> f64 {
        self.distance_within(p, f64::INFINITY)
    }

    /// Length samples of the curves: midpoints of pieces of length `<= step`, each with
    /// its length as weight. Refused (before allocating) when that would take more than
    /// [`MAX_LENGTH_SAMPLES`] samples, or `step` is not a positive finite length: a step
    /// tiny against the curves means the cloud and the reference are not at one scale.
    pub fn length_samples(&self, step: f64) -> Result<Vec<(DVec3, f64)>> {
        let needed = self.length() / step + self.n_segments() as f64;
        if !(step > 0.0 && step.is_finite() && needed <= MAX_LENGTH_SAMPLES as f64) {
            return Err(MetricsError::InvalidInput(format!(
                "feature curves of total length {:e} sampled every {step:e} would need {needed:e} \
                 samples (at most {MAX_LENGTH_SAMPLES}); are the cloud and the reference at \
                 the same scale?",
                self.length()
            )));
        }
        let mut out = Vec::new();
        for p in &self.polylines {
            for w in p.windows(2) {
                let l = (w[1] - w[0]).length();
                if l == 0.0 {
                    continue;
                }
                let m = ((l / step).ceil() as usize).max(1);
                for k in 0..m {
                    let t = (k as f64 + 0.5) / m as f64;
                    out.push((w[0].lerp(w[1], t), l / m as f64));
                }
            }
        }
        Ok(out)
    }
}

/// Most length samples [`CurveSet::length_samples`] takes (32 bytes each: 128 MiB). A
/// cloud of a million points on a unit-diagonal shape needs about 10^4.
pub const MAX_LENGTH_SAMPLES: usize = 4_000_000;

/// Result of [`eval_features`].
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureEval {
    /// Ground-truth bounding-box diagonal (unit of the relative distances).
    pub diagonal: f64,
    /// Feature angle used.
    pub feature_angle_deg: f64,
    /// Mean spacing `s` of the cloud (absolute).
    pub spacing: f64,
    /// `r` (absolute).
    pub radius: f64,
    /// Points.
    pub points: usize,
    /// Detected points.
    pub detected: usize,
    /// Counted curves (including corners).
    pub curves: usize,
    /// Total length of the counted curves (absolute).
    pub curve_length: f64,
    /// GT positives at `r` and `2r`.
    pub positives: [usize; 2],
    /// True positives at `r` and `2r`.
    pub true_positives: [usize; 2],
    /// Distances of the detected points to the nearest counted curve (absolute): mean
    /// and max (NaN without detections or curves).
    pub dist_mean: f64,
    /// See `dist_mean`.
    pub dist_max: f64,
    /// Covered share of the curve length (NaN without curves).
    pub coverage: f64,
}

fn ratio(a: usize, b: usize) -> Option<f64> {
    (b > 0).then(|| a as f64 / b as f64)
}

impl FeatureEval {
    /// Precision at `r` (`k = 0`) or `2r` (`k = 1`); `None` without detections.
    pub fn precision(&self, k: usize) -> Option<f64> {
        ratio(self.true_positives[k], self.detected)
    }
    /// Recall at `r` or `2r`; `None` without positives.
    pub fn recall(&self, k: usize) -> Option<f64> {
        ratio(self.true_positives[k], self.positives[k])
    }
    /// F1 `= 2 TP / (2 TP + FP + FN)` at `r` or `2r`; `None` when nothing is detected and
    /// nothing is positive.
    pub fn f1(&self, k: usize) -> Option<f64> {
        let tp = self.true_positives[k];
        let fp = self.detected - tp;
        let fnn = self.positives[k] - tp;
        ratio(2 * tp, 2 * tp + fp + fnn)
    }
    /// Detected points farther than `r` (`k = 0`) or `2r` (`k = 1`) from every counted
    /// curve: the false positives, defined (0 or more) also where the ground truth has no
    /// feature and precision, recall and F1 are not.
    pub fn false_positives(&self, k: usize) -> usize {
        self.detected - self.true_positives[k]
    }
}

impl Report for FeatureEval {
    fn entries(&self) -> Entries {
        let d = self.diagonal;
        let nz = |x: f64| if x.is_finite() { Some(x) } else { None };
        let mut e = Entries::new();
        put(&mut e, "feature_precision", self.precision(0));
        put(&mut e, "feature_recall", self.recall(0));
        put(&mut e, "feature_f1", self.f1(0));
        put(&mut e, "feature_precision_2r", self.precision(1));
        put(&mut e, "feature_recall_2r", self.recall(1));
        put(&mut e, "feature_f1_2r", self.f1(1));
        put(&mut e, "feature_false_positives", self.false_positives(0));
        put(
            &mut e,
            "feature_false_positives_2r",
            self.false_positives(1),
        );
        put(&mut e, "feature_dist_mean", nz(self.dist_mean / d));
        put(&mut e, "feature_dist_max", nz(self.dist_max / d));
        put(&mut e, "feature_dist_mean_abs", nz(self.dist_mean));
        put(&mut e, "feature_dist_max_abs", nz(self.dist_max));
        put(&mut e, "feature_coverage", nz(self.coverage));
        put(&mut e, "feature_points", self.points);
        put(&mut e, "feature_detected", self.detected);
        put(&mut e, "feature_gt_positives", self.positives[0]);
        put(&mut e, "feature_gt_positives_2r", self.positives[1]);
        put(
            &mut e,
            "feature_gt_share",
            ratio(self.positives[0], self.points),
        );
        put(&mut e, "feature_curves", self.curves);
        put(&mut e, "feature_curve_length", self.curve_length / d);
        put(&mut e, "feature_angle_deg", self.feature_angle_deg);
        put(&mut e, "feature_radius", self.radius / d);
        put(&mut e, "feature_radius_abs", self.radius);
        put(&mut e, "feature_spacing_abs", self.spacing);
        e
    }
}
serialize_as_entries!(FeatureEval);

/// Point-labelling metrics (see the module docs).
///
/// `positions` are the observed points, `clean` their clean positions (pass `positions`
/// again for a noise-free cloud), `detected` the labels, `curves` the ground truth,
/// `diagonal` the ground-truth bounding-box diagonal.
pub fn eval_features(
    positions: &[DVec3],
    clean: &[DVec3],
    detected: &[bool],
    curves: &[FeatureCurve],
    diagonal: f64,
    opts: &FeatureOptions,
) -> Result<FeatureEval> {
    let n = positions.len();
    if clean.len() != n || detected.len() != n {
        return Err(MetricsError::InvalidInput(format!(
            "{n} points, {} clean positions, {} labels: lengths must agree",
            clean.len(),
            detected.len()
        )));
    }
    check_positive("diagonal", diagonal)?;
    check_positive("radius_factor", opts.radius_factor)?;
    let spacing = mean_spacing(positions, 1)?;
    let radius = match opts.radius {
        Some(r) => {
            check_positive("radius", r)?;
            r
        }
        None => opts.radius_factor * spacing,
    };
    let set = CurveSet::new(curves, opts.feature_angle_deg);

    // Distance of each clean position to the curves, searched up to 2r.
    let dclean: Vec<f64> = clean
        .par_iter()
        .map(|&p| set.distance_within(p, 2.0 * radius))
        .collect();
    let mut positives = [0usize; 2];
    let mut tps = [0usize; 2];
    for i in 0..n {
        for (k, lim) in [radius, 2.0 * radius].into_iter().enumerate() {
            if dclean[i] <= lim {
                positives[k] += 1;
                if detected[i] {
                    tps[k] += 1;
                }
            }
        }
    }
    let det_idx: Vec<usize> = (0..n).filter(|&i| detected[i]).collect();
    let ddet: Vec<f64> = det_idx
        .par_iter()
        .map(|&i| set.distance(positions[i]))
        .collect();
    let (dist_mean, dist_max) = if ddet.is_empty() || set.n_segments() == 0 {
        (f64::NAN, f64::NAN)
    } else {
        (
            ddet.iter().sum::<f64>() / ddet.len() as f64,
            ddet.iter().copied().fold(0.0, f64::max),
        )
    };

    let samples = set.length_samples(spacing / 2.0)?;
    let coverage = if samples.is_empty() {
        f64::NAN
    } else if det_idx.is_empty() {
        0.0
    } else {
        let det_clean: Vec<DVec3> = det_idx.iter().map(|&i| clean[i]).collect();
        let index = PointIndex::new(&det_clean)?;
        let hits = index.nearest_batch(&samples.iter().map(|s| s.0).collect::<Vec<_>>())?;
        let r2 = radius * radius;
        let total: f64 = samples.iter().map(|s| s.1).sum();
        let cov: f64 = samples
            .iter()
            .zip(&hits)
            .filter(|(_, h)| h.dist2 <= r2)
            .map(|(s, _)| s.1)
            .sum();
        cov / total
    };

    Ok(FeatureEval {
        diagonal,
        feature_angle_deg: opts.feature_angle_deg,
        spacing,
        radius,
        points: n,
        detected: det_idx.len(),
        curves: curves
            .iter()
            .filter(|c| curve_counts(c, opts.feature_angle_deg))
            .count(),
        curve_length: set.length(),
        positives,
        true_positives: tps,
        dist_mean,
        dist_max,
        coverage,
    })
}

/// Detection flags from a cloud's label channel (nonzero = detected; a scalar channel
/// works the same way).
pub fn detected_from_cloud(cloud: &PointCloud, channel: &str) -> Result<Vec<bool>> {
    match cloud.channel(channel) {
        Some(Channel::Label(v)) => Ok(v.iter().map(|&x| x != 0).collect()),
        Some(Channel::Scalar(v)) => Ok(v.iter().map(|&x| x != 0.0).collect()),
        None => Err(MetricsError::MissingAttribute(format!(
            "'{channel}' channel (feature labels)"
        ))),
    }
}

/// Detection flags from a detector's output (`Edge` and `Corner` count as detected).
pub fn detected_from_labels(labels: &reconbench_geom::method::FeatureLabels) -> Vec<bool> {
    labels
        .labels
        .iter()
        .map(|&c| c != reconbench_geom::method::FeatureClass::None)
        .collect()
}

/// Where the clean positions of a cloud's points come from.
#[derive(Debug, Clone, Copy)]
pub enum CleanPositions<'a> {
    /// The observed positions are clean (no positional noise).
    Observed,
    /// The cloud's own `clean_x`, `clean_y`, `clean_z` scalar channels (written by
    /// `reconbench gen` with clean positions).
    Channels,
    /// The ground-truth cloud written by `reconbench gen`, matched through source ids
    /// ([`crate::normals::ground_truth_index`]); its `clean_x/y/z` channels if it has
    /// them, else its positions. Unmatched points (outliers) keep their observed position.
    SourceSamples(&'a PointCloud),
    /// The closest points on the reference (an approximation for noisy clouds).
    ClosestPoint(&'a Reference<'a>),
}

/// The `clean_x`, `clean_y`, `clean_z` channels of a cloud, if all three are present.
fn clean_channels(cloud: &PointCloud) -> Option<Vec<DVec3>> {
    let ch = ["clean_x", "clean_y", "clean_z"].map(|n| cloud.channel(n));
    let [Some(x), Some(y), Some(z)] = ch else {
        return None;
    };
    Some(
        (0..cloud.len())
            .map(|i| DVec3::new(x.get_f64(i), y.get_f64(i), z.get_f64(i)))
            .collect(),
    )
}

/// Clean positions of `cloud` (see [`CleanPositions`]).
pub fn clean_positions(cloud: &PointCloud, how: CleanPositions) -> Result<Vec<DVec3>> {
    match how {
        CleanPositions::Observed => Ok(cloud.positions().to_vec()),
        CleanPositions::Channels => clean_channels(cloud).ok_or_else(|| {
            MetricsError::MissingAttribute("clean_x / clean_y / clean_z channels".to_string())
        }),
        CleanPositions::SourceSamples(gt) => {
            let idx = crate::normals::ground_truth_index(cloud, gt)?;
            let gp = clean_channels(gt).unwrap_or_else(|| gt.positions().to_vec());
            Ok(idx
                .iter()
                .zip(cloud.positions())
                .map(|(j, &p)| j.map_or(p, |j| gp[j]))
                .collect())
        }
        CleanPositions::ClosestPoint(r) => Ok(r
            .closest_batch(cloud.positions())?
            .into_iter()
            .map(|h| h.point)
            .collect()),
    }
}

/// Result of [`eval_mesh_features`].
#[derive(Debug, Clone, PartialEq)]
pub struct MeshFeatureEval {
    /// Ground-truth diagonal.
    pub diagonal: f64,
    /// `r` used (absolute).
    pub radius: f64,
    /// Share of the counted curve length within `r` of a sharp mesh edge (NaN without
    /// curves).
    pub recovery: f64,
    /// Sharp mesh edges (normal deviation `>= feature_angle / 2`).
    pub sharp_edges: usize,
    /// Faces whose centroid is within `r` of a counted curve.
    pub faces_near: usize,
    /// Mean / max unoriented face-normal error (degrees) of those faces (NaN when none,
    /// or without an analytic/mesh reference).
    pub face_normal_mean_deg: f64,
    /// See `face_normal_mean_deg`.
    pub face_normal_max_deg: f64,
}

impl Report for MeshFeatureEval {
    fn entries(&self) -> Entries {
        let nz = |x: f64| if x.is_finite() { Some(x) } else { None };
        let mut e = Entries::new();
        put(&mut e, "feature_recovery", nz(self.recovery));
        put(
            &mut e,
            "feature_face_normal_mean_deg",
            nz(self.face_normal_mean_deg),
        );
        put(
            &mut e,
            "feature_face_normal_max_deg",
            nz(self.face_normal_max_deg),
        );
        put(&mut e, "feature_faces_near", self.faces_near);
        put(&mut e, "feature_sharp_edges", self.sharp_edges);
        put(
            &mut e,
            "feature_recovery_radius",
            self.radius / self.diagonal,
        );
        put(&mut e, "feature_recovery_radius_abs", self.radius);
        e
    }
}
serialize_as_entries!(MeshFeatureEval);

/// Mean edge length of a mesh (over distinct edges), the default `r` of
/// [`eval_mesh_features`] when no cloud spacing is known.
pub fn mean_edge_length(mesh: &TriMesh, topo: &MeshTopology) -> f64 {
    let v = mesh.vertices();
    let e = topo.edges();
    if e.is_empty() {
        return f64::NAN;
    }
    e.iter()
        .map(|&[a, b]| (v[a as usize] - v[b as usize]).length())
        .sum::<f64>()
        / e.len() as f64
}

/// Mesh feature recovery and face-normal error near the curves (see the module docs).
/// `radius` is `r` (absolute); pass the cloud's mean spacing times `radius_factor`, or
/// `None` for the mesh's mean edge length. The curves are sampled every `r / 2`.
pub fn eval_mesh_features(
    mesh: &TriMesh,
    reference: &Reference,
    curves: &[FeatureCurve],
    radius: Option<f64>,
    opts: &FeatureOptions,
) -> Result<MeshFeatureEval> {
    let topo = MeshTopology::new(mesh);
    let radius = match radius.or(opts.radius) {
        Some(r) => r,
        None => opts.radius_factor * mean_edge_length(mesh, &topo),
    };
    check_positive("radius", radius)?;
    let diagonal = reference.diagonal();
    let set = CurveSet::new(curves, opts.feature_angle_deg);
    let sharp = mesh_sharp_edges(mesh, &topo, opts.feature_angle_deg / 2.0);
    let sharp_set =
        CurveSet::from_parts(sharp.iter().map(|&(a, b, _)| (a, b)).collect(), Vec::new());

    let samples = set.length_samples(radius / 2.0)?;
    let recovery = if samples.is_empty() {
        f64::NAN
    } else {
        let total: f64 = samples.iter().map(|s| s.1).sum();
        let rec: f64 = samples
            .par_iter()
            .map(|&(p, w)| {
                if sharp_set.distance_within(p, radius) <= radius {
                    w
                } else {
                    0.0
                }
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        rec / total
    };

    let near: Vec<usize> = (0..mesh.n_faces())
        .into_par_iter()
        .filter(|&f| {
            let [a, b, c] = mesh.triangle(f);
            set.distance_within((a + b + c) / 3.0, radius) <= radius
        })
        .collect();
    let centroids: Vec<DVec3> = near
        .iter()
        .map(|&f| {
            let [a, b, c] = mesh.triangle(f);
            (a + b + c) / 3.0
        })
        .collect();
    let hits = reference.closest_batch(&centroids)?;
    let errs: Vec<f64> = near
        .iter()
        .zip(&hits)
        .filter_map(|(&f, h)| unoriented_angle_deg(mesh.face_normal(f), h.normal))
        .collect();
    let (face_normal_mean_deg, face_normal_max_deg) = if errs.is_empty() {
        (f64::NAN, f64::NAN)
    } else {
        (
            errs.iter().sum::<f64>() / errs.len() as f64,
            errs.iter().copied().fold(0.0, f64::max),
        )
    };
    Ok(MeshFeatureEval {
        diagonal,
        radius,
        recovery,
        sharp_edges: sharp.len(),
        faces_near: near.len(),
        face_normal_mean_deg,
        face_normal_max_deg,
    })
}
