//! `pca-variation`: surface variation `lambda0 / (lambda0 + lambda1 + lambda2)` of the
//! k-neighbourhood covariance (Pauly, Keiser & Gross 2003), the PCA baseline the thesis
//! compares with (seed 002 §5.1, §8.1.9).
//!
//! * `single` mode: one neighbourhood size k; a point is a feature when its surface
//!   variation exceeds `threshold`. `scores` = surface variation.
//! * `multi` mode (default, the thesis's comparison): surface variation at every size
//!   `n_min..=n_max`; the feature weight `omega` = number of sizes whose variation exceeds
//!   `threshold` (0..=31 with the thesis values); hysteresis: points with
//!   `omega >= omega_hi` seed a region grown through the symmetrised kNN graph
//!   (`n_min` nearest other points) to points with `omega >= omega_lo`. `scores` = omega.
//!
//! Only Pauly's classification part is implemented (the thesis did not use the minimum
//! spanning graph, pruning and snakes). The baseline does not separate corners from
//! edges: every detected point is labelled [`FeatureClass::Edge`].

use std::collections::VecDeque;

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostics, FeatureClass, FeatureDetector, FeatureLabels, MethodError, ParamDoc,
    RunCtx, Unit,
};
use serde::{Deserialize, Serialize};

use crate::common::{
    bad_param, check_range, count_labels, knn_excluding_self, num, par_map_chunked,
};
use crate::gauss_map::trivial_labels;

/// Single or multi-scale surface variation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PcaMode {
    /// One neighbourhood size `k`, plain threshold.
    Single,
    /// Sizes `n_min..=n_max`, feature weight and hysteresis (Pauly et al. 2003).
    Multi,
}

/// Parameters of `pca-variation`. Sizes count the point itself (ASSUMPTION W-15).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PcaVariationParams {
    /// `single` or `multi` (default; the thesis's comparison).
    pub mode: PcaMode,
    /// Neighbourhood size of `single` mode, the point itself included (ASSUMPTION W-17:
    /// 16, the Gauss-map k).
    pub k: usize,
    /// Surface-variation threshold `sigma_max`; thesis 0.08 (range `[0, 1/3]`).
    pub threshold: f64,
    /// Smallest neighbourhood size of `multi` mode; thesis 10.
    pub n_min: usize,
    /// Largest neighbourhood size of `multi` mode; thesis 40.
    pub n_max: usize,
    /// Lower hysteresis bound on the feature weight; thesis 25.
    pub omega_lo: usize,
    /// Upper hysteresis bound (seeds); thesis 30.
    pub omega_hi: usize,
    /// ASSUMPTION W-16: grow from the seeds (true, default); false labels only
    /// `omega >= omega_hi`.
    pub hysteresis: bool,
}

impl Default for PcaVariationParams {
    fn default() -> Self {
        Self {
            mode: PcaMode::Multi,
            k: 16,
            threshold: 0.08,
            n_min: 10,
            n_max: 40,
            omega_lo: 25,
            omega_hi: 30,
            hysteresis: true,
        }
    }
}

impl PcaVariationParams {
    /// Checks ranges.
    pub fn validate(&self) -> Result<(), MethodError> {
        check_range("threshold", self.threshold, 0.0, 1.0)?;
        match self.mode {
            PcaMode::Single => {
                if self.k < 3 {
                    return Err(bad_param(
                        "k",
                        format!("must be at least 3, got {}", self.k),
                    ));
                }
            }
            PcaMode::Multi => {
                if self.n_min < 3 || self.n_max < self.n_min {
                    return Err(bad_param(
                        "n_max",
                        format!(
                            "need 3 <= n_min <= n_max, got {} and {}",
                            self.n_min, self.n_max
                        ),
                    ));
                }
                if self.omega_lo > self.omega_hi {
                    return Err(bad_param(
                        "omega_lo",
                        format!(
                            "must not exceed omega_hi ({} > {})",
                            self.omega_lo, self.omega_hi
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Eigenvalues (ascending) of the symmetric matrix `[[xx, xy, xz], [xy, yy, yz],
/// [xz, yz, zz]]`, closed form (trigonometric method).
pub fn sym3_eigenvalues(xx: f64, xy: f64, xz: f64, yy: f64, yz: f64, zz: f64) -> [f64; 3] {
    let p1 = xy * xy + xz * xz + yz * yz;
    let mut e = if p1 == 0.0 {
        [xx, yy, zz]
    } else {
        let q = (xx + yy + zz) / 3.0;
        let (a, b, c) = (xx - q, yy - q, zz - q);
        let p2 = a * a + b * b + c * c + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let inv = 1.0 / p;
        let (a, b, c, d, f, g) = (a * inv, b * inv, c * inv, xy * inv, xz * inv, yz * inv);
        // det of [[a, d, f], [d, b, g], [f, g, c]] / 2
        let r = ((a * (b * c - g * g) - d * (d * c - g * f) + f * (d * g - b * f)) * 0.5)
            .clamp(-1.0, 1.0);
        let phi = r.acos() / 3.0;
        let hi = q + 2.0 * p * phi.cos();
        let lo = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
        [lo, 3.0 * q - hi - lo, hi]
    };
    e.sort_unstable_by(f64::total_cmp);
    e
}

/// Running first and second moments of offsets from the query point.
#[derive(Debug, Default, Clone, Copy)]
struct Moments {
    n: f64,
    s: DVec3,
    xx: f64,
    xy: f64,
    xz: f64,
    yy: f64,
    yz: f64,
    zz: f64,
}

impl Moments {
    fn add(&mut self, d: DVec3) {
        self.n += 1.0;
        self.s += d;
        self.xx += d.x * d.x;
        self.xy += d.x * d.y;
        self.xz += d.x * d.z;
        self.yy += d.y * d.y;
        self.yz += d.y * d.z;
        self.zz += d.z * d.z;
    }

    /// Surface variation of the points added so far (0 when they all coincide).
    fn variation(&self) -> f64 {
        let inv = 1.0 / self.n;
        let m = self.s * inv;
        let e = sym3_eigenvalues(
            self.xx * inv - m.x * m.x,
            self.xy * inv - m.x * m.y,
            self.xz * inv - m.x * m.z,
            self.yy * inv - m.y * m.y,
            self.yz * inv - m.y * m.z,
            self.zz * inv - m.z * m.z,
        );
        let l0 = e[0].max(0.0);
        let tr = l0 + e[1].max(0.0) + e[2].max(0.0);
        if tr > 0.0 { l0 / tr } else { 0.0 }
    }
}

/// The `pca-variation` detector.
#[derive(Debug, Clone, Default)]
pub struct PcaVariation {
    /// Parameters.
    pub params: PcaVariationParams,
}

impl PcaVariation {
    /// A detector with `params`.
    pub fn new(params: PcaVariationParams) -> Self {
        Self { params }
    }
}

impl Describe for PcaVariation {
    const NAME: &'static str = "pca-variation";
    const SOURCE: &'static str = "seed 002 §5.1";
    const SUMMARY: &'static str =
        "PCA surface variation, single or multi-scale (Pauly et al. 2003)";
    type Params = PcaVariationParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "mode",
            Unit::Choice,
            "single or multi (multi-scale with hysteresis, the thesis's comparison)",
        ),
        ParamDoc::new(
            "k",
            Unit::Count,
            "single-mode neighbourhood size incl. the point (ASSUMPTION W-17: 16)",
        ),
        ParamDoc::new(
            "threshold",
            Unit::None,
            "surface-variation threshold sigma_max (thesis 0.08)",
        ),
        ParamDoc::new(
            "n_min",
            Unit::Count,
            "smallest multi-mode neighbourhood (thesis 10)",
        ),
        ParamDoc::new(
            "n_max",
            Unit::Count,
            "largest multi-mode neighbourhood (thesis 40)",
        ),
        ParamDoc::new(
            "omega_lo",
            Unit::Count,
            "lower hysteresis bound on the feature weight (thesis 25)",
        ),
        ParamDoc::new(
            "omega_hi",
            Unit::Count,
            "upper hysteresis bound, seeds (thesis 30)",
        ),
        ParamDoc::new(
            "hysteresis",
            Unit::Flag,
            "ASSUMPTION W-16: grow from seeds (true) or label omega >= omega_hi only",
        ),
    ];

    fn from_params(params: PcaVariationParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl FeatureDetector for PcaVariation {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn detect(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<FeatureLabels, MethodError> {
        let p = &self.params;
        p.validate()?;
        // Scale robustness: detect on the exact power-of-two working-scale copy (labels,
        // scores and every parameter are scale-free).
        let scaled = cloud.at_working_scale();
        let cloud = scaled.as_ref().map_or(cloud, |(c, _)| c);
        let points = cloud.positions();
        let n = points.len();
        if n < 3 {
            return Ok(trivial_labels(n, self.name()));
        }
        let size = match p.mode {
            PcaMode::Single => p.k,
            PcaMode::Multi => p.n_max,
        };
        // ASSUMPTION W-15: the point itself is the first element of its neighbourhood,
        // followed by its size - 1 nearest other points (clamped to the cloud).
        let table = knn_excluding_self(points, size - 1, ctx)?;
        let size = table.k + 1;
        let mut diagnostics = Diagnostics::new();
        num(&mut diagnostics, "points", n as f64);
        let (labels, scores): (Vec<FeatureClass>, Vec<f64>) = match p.mode {
            PcaMode::Single => {
                let sv = par_map_chunked(
                    n,
                    "variation",
                    ctx,
                    || (),
                    |_, i| {
                        let q = points[i];
                        let mut m = Moments::default();
                        m.add(DVec3::ZERO);
                        for &j in table.indices(i) {
                            m.add(points[j as usize] - q);
                        }
                        m.variation()
                    },
                )?;
                num(&mut diagnostics, "k_effective", size as f64);
                let labels = sv
                    .iter()
                    .map(|&s| {
                        if s > p.threshold {
                            FeatureClass::Edge
                        } else {
                            FeatureClass::None
                        }
                    })
                    .collect();
                (labels, sv)
            }
            PcaMode::Multi => {
                let n_max = size;
                let n_min = p.n_min.min(n_max);
                let omega = par_map_chunked(
                    n,
                    "variation",
                    ctx,
                    || (),
                    |_, i| {
                        let q = points[i];
                        let mut m = Moments::default();
                        m.add(DVec3::ZERO);
                        let mut w = 0u32;
                        for (c, &j) in table.indices(i).iter().enumerate() {
                            m.add(points[j as usize] - q);
                            if c + 2 >= n_min && m.variation() > p.threshold {
                                w += 1;
                            }
                        }
                        w
                    },
                )?;
                num(&mut diagnostics, "n_max_effective", n_max as f64);
                num(&mut diagnostics, "scales", (n_max - n_min + 1) as f64);
                let lo = p.omega_lo as u32;
                let hi = p.omega_hi as u32;
                let seeds = omega.iter().filter(|&&w| w >= hi).count();
                num(&mut diagnostics, "seeds", seeds as f64);
                let feature = if p.hysteresis {
                    let g = n_min.min(table.k);
                    ctx.phase("hysteresis", || hysteresis(n, &table, g, &omega, lo, hi))
                } else {
                    omega.iter().map(|&w| w >= hi).collect()
                };
                let labels = feature
                    .iter()
                    .map(|&f| {
                        if f {
                            FeatureClass::Edge
                        } else {
                            FeatureClass::None
                        }
                    })
                    .collect();
                (labels, omega.iter().map(|&w| f64::from(w)).collect())
            }
        };
        count_labels(&labels, &mut diagnostics);
        Ok(FeatureLabels {
            labels,
            scores: Some(scores),
            diagnostics,
        })
    }
}

/// ASSUMPTION W-16: seeds `omega >= hi`, grown breadth-first through the symmetrised
/// graph of the `g` nearest other points to points with `omega >= lo`.
fn hysteresis(
    n: usize,
    table: &reconbench_geom::spatial::KnnTable,
    g: usize,
    omega: &[u32],
    lo: u32,
    hi: u32,
) -> Vec<bool> {
    // Symmetrised adjacency in CSR form.
    let mut deg = vec![0usize; n + 1];
    for i in 0..n {
        for &j in &table.indices(i)[..g] {
            deg[i] += 1;
            deg[j as usize] += 1;
        }
    }
    let mut offsets = vec![0usize; n + 1];
    for i in 0..n {
        offsets[i + 1] = offsets[i] + deg[i];
    }
    let mut fill = offsets.clone();
    let mut adj = vec![0u32; offsets[n]];
    for i in 0..n {
        for &j in &table.indices(i)[..g] {
            adj[fill[i]] = j;
            fill[i] += 1;
            adj[fill[j as usize]] = i as u32;
            fill[j as usize] += 1;
        }
    }
    let mut reached: Vec<bool> = omega.iter().map(|&w| w >= hi).collect();
    let mut queue: VecDeque<usize> = (0..n).filter(|&i| reached[i]).collect();
    while let Some(i) = queue.pop_front() {
        for &j in &adj[offsets[i]..offsets[i + 1]] {
            let j = j as usize;
            if !reached[j] && omega[j] >= lo {
                reached[j] = true;
                queue.push_back(j);
            }
        }
    }
    reached
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_eigenvalues_match_known() {
        let e = sym3_eigenvalues(2.0, 0.0, 0.0, 3.0, 0.0, 1.0);
        assert_eq!(e, [1.0, 2.0, 3.0]);
        // [[2,1,0],[1,2,0],[0,0,5]] -> 1, 3, 5
        let e = sym3_eigenvalues(2.0, 1.0, 0.0, 2.0, 0.0, 5.0);
        for (a, b) in e.iter().zip([1.0, 3.0, 5.0]) {
            assert!((a - b).abs() < 1e-12, "{e:?}");
        }
        // Compare with the geom solver on a generic matrix.
        let m = glam::DMat3::from_cols(
            DVec3::new(4.0, 1.0, -2.0),
            DVec3::new(1.0, 2.0, 0.5),
            DVec3::new(-2.0, 0.5, 3.0),
        );
        let r = reconbench_geom::linalg::sym_eigen3(m).unwrap();
        let e = sym3_eigenvalues(4.0, 1.0, -2.0, 2.0, 0.5, 3.0);
        for (a, b) in e.iter().zip(r.values) {
            assert!((a - b).abs() < 1e-12, "{e:?} vs {:?}", r.values);
        }
    }

    #[test]
    fn planar_points_have_zero_variation() {
        let mut m = Moments::default();
        for i in 0..5 {
            for j in 0..5 {
                m.add(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        assert!(m.variation() < 1e-12);
    }
}
