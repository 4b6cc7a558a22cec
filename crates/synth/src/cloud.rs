//! [`GroundTruthCloud`]: a generated point cloud with every ground-truth annotation.

use glam::DVec3;
use reconbench_geom::{Channel, PointCloud};

use crate::error::Result;

/// `feature_distance` of points with no sharp feature to measure to (smooth shapes,
/// outliers): `f64::MAX`, finite so that it can be stored in a channel and a PLY file;
/// test `>= NO_FEATURE` (or `> 1.0`: on a unit-diagonal shape no real distance exceeds 1).
pub const NO_FEATURE: f64 = f64::MAX;

/// Source id of points that come from no surface sample (outliers).
pub const NO_SOURCE: u32 = u32::MAX;

/// A synthetic point cloud with its ground truth, one entry per point in every vector.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GroundTruthCloud {
    /// Observed (possibly perturbed) positions.
    pub positions: Vec<DVec3>,
    /// The exact surface point each observation was generated from (for outliers: the
    /// outlier position itself).
    pub clean_positions: Vec<DVec3>,
    /// Exact unit outward normal at the clean position (zero for outliers).
    pub normals: Vec<DVec3>,
    /// Index of the clean sample (stable through decimation and duplication; duplicates
    /// share it); [`NO_SOURCE`] for outliers.
    pub source_ids: Vec<u32>,
    /// Distance of the clean position to the nearest sharp feature; [`NO_FEATURE`] when
    /// there is none.
    pub feature_distance: Vec<f64>,
    /// Whether the point is an outlier (added by an outlier perturbation).
    pub is_outlier: Vec<bool>,
    /// Scan index, for scanner output.
    pub scan_ids: Option<Vec<u32>>,
    /// Unit direction from the point towards the scanner that saw it, for scanner output.
    pub view_dirs: Option<Vec<DVec3>>,
}

impl GroundTruthCloud {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Keeps the points at `idx` (in order, repeats allowed).
    pub fn select(&self, idx: &[usize]) -> Self {
        fn pick<T: Copy>(v: &[T], idx: &[usize]) -> Vec<T> {
            idx.iter().map(|&i| v[i]).collect()
        }
        Self {
            positions: pick(&self.positions, idx),
            clean_positions: pick(&self.clean_positions, idx),
            normals: pick(&self.normals, idx),
            source_ids: pick(&self.source_ids, idx),
            feature_distance: pick(&self.feature_distance, idx),
            is_outlier: pick(&self.is_outlier, idx),
            scan_ids: self.scan_ids.as_ref().map(|v| pick(v, idx)),
            view_dirs: self.view_dirs.as_ref().map(|v| pick(v, idx)),
        }
    }

    /// Appends all points of `other` (both must have the same optional attributes; a
    /// missing one is filled with `u32::MAX` / zero).
    pub fn append(&mut self, other: &GroundTruthCloud) {
        let n0 = self.len();
        self.positions.extend_from_slice(&other.positions);
        self.clean_positions
            .extend_from_slice(&other.clean_positions);
        self.normals.extend_from_slice(&other.normals);
        self.source_ids.extend_from_slice(&other.source_ids);
        self.feature_distance
            .extend_from_slice(&other.feature_distance);
        self.is_outlier.extend_from_slice(&other.is_outlier);
        if self.scan_ids.is_some() || other.scan_ids.is_some() {
            let s = self.scan_ids.get_or_insert_with(|| vec![u32::MAX; n0]);
            match &other.scan_ids {
                Some(o) => s.extend_from_slice(o),
                None => s.extend(std::iter::repeat_n(u32::MAX, other.len())),
            }
        }
        if self.view_dirs.is_some() || other.view_dirs.is_some() {
            let s = self.view_dirs.get_or_insert_with(|| vec![DVec3::ZERO; n0]);
            match &other.view_dirs {
                Some(o) => s.extend_from_slice(o),
                None => s.extend(std::iter::repeat_n(DVec3::ZERO, other.len())),
            }
        }
    }

    /// The cloud as written by `reconbench gen`: positions, normals (GT), source ids and
    /// the channels `feature_distance` (Scalar), `is_outlier` (Label 0/1) and, for scans,
    /// `scan_id` (Label; -1 for outliers) and `view_x`, `view_y`, `view_z` (Scalar).
    pub fn to_point_cloud(&self) -> Result<PointCloud> {
        let mut c = PointCloud::new(self.positions.clone())?.with_normals(self.normals.clone())?;
        c.set_source_ids(Some(self.source_ids.clone()))?;
        c.set_channel(
            "feature_distance",
            Channel::Scalar(self.feature_distance.clone()),
        )?;
        c.set_channel(
            "is_outlier",
            Channel::Label(self.is_outlier.iter().map(|&o| i64::from(o)).collect()),
        )?;
        if let Some(s) = &self.scan_ids {
            c.set_channel(
                "scan_id",
                Channel::Label(
                    s.iter()
                        .map(|&x| if x == u32::MAX { -1 } else { i64::from(x) })
                        .collect(),
                ),
            )?;
        }
        if let Some(v) = &self.view_dirs {
            for (k, name) in ["view_x", "view_y", "view_z"].into_iter().enumerate() {
                c.set_channel(name, Channel::Scalar(v.iter().map(|d| d[k]).collect()))?;
            }
        }
        Ok(c)
    }

    /// [`Self::to_point_cloud`] plus the clean positions as channels `clean_x`,
    /// `clean_y`, `clean_z`.
    pub fn to_point_cloud_with_clean(&self) -> Result<PointCloud> {
        let mut c = self.to_point_cloud()?;
        for (k, name) in ["clean_x", "clean_y", "clean_z"].into_iter().enumerate() {
            c.set_channel(
                name,
                Channel::Scalar(self.clean_positions.iter().map(|d| d[k]).collect()),
            )?;
        }
        Ok(c)
    }
}
