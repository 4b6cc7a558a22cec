//! Surface distances between a reconstructed mesh R and the ground truth S.
//!
//! * Samples: `n_R` area-uniform samples of R plus every vertex of R used by a face;
//!   `n_S` area-uniform samples of S. Defaults `n = max(100_000, 10 x faces)` with the
//!   faces of R for `n_R` and of S for `n_S` (of R when S is analytic). Fixed seed.
//! * `d(R->S)` (accuracy): exact distance of each R sample to S (analytic closest point,
//!   or exact point-to-triangle through a BVH of S).
//! * `d(S->R)` (completeness): exact point-to-triangle distance of each S sample to R
//!   through a BVH of R.
//! * Per side: mean, RMS, p95 (nearest rank), max. Chamfer-L1 = `0.5 (mean d(R->S) +
//!   mean d(S->R))` (unsquared); Hausdorff = max of the two maxima; `hausdorff_p95` = max
//!   of the two p95.
//! * F-score at `tau = t x diag(S)`, `t` in {0.005, 0.01}: precision = % of R samples with
//!   `d(R->S) <= tau`, recall = % of S samples with `d(S->R) <= tau`, F = harmonic mean
//!   (all three in percent).
//! * Distances are reported divided by the bounding-box diagonal of S (keys without
//!   suffix) and absolute (`_abs`).

use glam::DVec3;
use reconbench_geom::{MeshBvh, TriMesh};
use serde::{Deserialize, Serialize};

use crate::error::{MetricsError, Result};
use crate::reference::{Reference, bvh_closest_coherent, require_faces};
use crate::report::{Entries, Report, put, serialize_as_entries};
use crate::sampling::sample_mesh;
use crate::stats::{Summary, harmonic};

/// F-score thresholds as fractions of the ground-truth bounding-box diagonal.
pub const FSCORE_THRESHOLDS: [f64; 2] = [0.005, 0.01];

/// Seed offset of the reference-side samples (so R and S never share a random stream).
const REFERENCE_SEED_SALT: u64 = 0x9e37_79b9_7f4a_7c15;

/// Which sides to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Sides {
    /// Both: accuracy, completeness, Chamfer, Hausdorff, F-score.
    #[default]
    Both,
    /// Only accuracy `d(R->S)`.
    Accuracy,
    /// Only completeness `d(S->R)`.
    Completeness,
}

impl Sides {
    fn accuracy(self) -> bool {
        self != Sides::Completeness
    }
    fn completeness(self) -> bool {
        self != Sides::Accuracy
    }
}

/// Options of [`eval_distance`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DistanceOptions {
    /// Lower bound of the default sample counts (100,000).
    pub min_samples: usize,
    /// Samples per face of the default sample counts (10).
    pub samples_per_face: usize,
    /// Explicit number of area samples of R (overrides the default).
    pub recon_samples: Option<usize>,
    /// Explicit number of area samples of S (overrides the default).
    pub reference_samples: Option<usize>,
    /// Add the vertices of R (those used by a face) to the R samples (true).
    pub include_vertices: bool,
    /// Sampling seed (0).
    pub seed: u64,
    /// Sides to compute (both).
    pub sides: Sides,
    /// Keep the per-vertex error of R for renders (true).
    pub vertex_error: bool,
}

impl Default for DistanceOptions {
    fn default() -> Self {
        Self {
            min_samples: 100_000,
            samples_per_face: 10,
            recon_samples: None,
            reference_samples: None,
            include_vertices: true,
            seed: 0,
            sides: Sides::Both,
            vertex_error: true,
        }
    }
}

/// Most area samples per side: about 5 GB of samples and nearest-point records at the
/// limit; an option or a mesh asking for more is refused before anything is allocated.
pub const MAX_SAMPLES: usize = 100_000_000;

/// Bytes per area sample of one side (position, closest point, distance, face).
const BYTES_PER_SAMPLE: f64 = 56.0;

fn check_samples(name: &'static str, n: usize) -> Result<()> {
    if n <= MAX_SAMPLES {
        return Ok(());
    }
    let gb = n as f64 * BYTES_PER_SAMPLE / 1e9;
    Err(MetricsError::InvalidParameter {
        name,
        message: format!(
            "{n} samples need about {}: at most {MAX_SAMPLES}",
            if gb >= 1000.0 {
                format!("{:.0} TB", gb / 1000.0)
            } else {
                format!("{gb:.0} GB")
            }
        ),
    })
}

impl DistanceOptions {
    /// Refuses sample counts above [`MAX_SAMPLES`] and a `samples_per_face` above
    /// 10,000 (experiment files are checked with this when they load).
    pub fn validate(&self) -> Result<()> {
        check_samples("distance.min_samples", self.min_samples)?;
        if let Some(n) = self.recon_samples {
            check_samples("distance.recon_samples", n)?;
        }
        if let Some(n) = self.reference_samples {
            check_samples("distance.reference_samples", n)?;
        }
        if self.samples_per_face > 10_000 {
            return Err(MetricsError::InvalidParameter {
                name: "distance.samples_per_face",
                message: format!("{} must be at most 10000", self.samples_per_face),
            });
        }
        Ok(())
    }

    /// Both sample counts set to `n`.
    pub fn with_samples(mut self, n: usize) -> Self {
        self.recon_samples = Some(n);
        self.reference_samples = Some(n);
        self
    }
}

/// F-score at one threshold (percentages).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FScore {
    /// Threshold as a fraction of the ground-truth diagonal.
    pub tau: f64,
    /// Absolute threshold.
    pub tau_abs: f64,
    /// % of R samples within `tau_abs` of S.
    pub precision: f64,
    /// % of S samples within `tau_abs` of R.
    pub recall: f64,
    /// Harmonic mean of precision and recall (percent).
    pub fscore: f64,
}

/// Result of [`eval_distance`]. Summaries are absolute; the report keys give both
/// relative and absolute values.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceEval {
    /// Bounding-box diagonal of S: the unit of the relative values.
    pub diagonal: f64,
    /// `d(R->S)` over the R samples (absolute), if computed.
    pub accuracy: Option<Summary>,
    /// `d(S->R)` over the S samples (absolute), if computed.
    pub completeness: Option<Summary>,
    /// F-scores at [`FSCORE_THRESHOLDS`] (both sides only).
    pub fscores: Vec<FScore>,
    /// Area samples of R.
    pub recon_area_samples: usize,
    /// Vertices of R added to its samples.
    pub recon_vertex_samples: usize,
    /// Area samples of S.
    pub reference_samples: usize,
    /// Sampling seed.
    pub seed: u64,
    /// Absolute distance of every vertex of R to S (index = vertex id), when requested
    /// and accuracy was computed. Not serialised.
    pub vertex_error: Option<Vec<f64>>,
    /// Absolute distance to S of every area sample of R (the mesh error over its
    /// surface, vertices not included), kept with `vertex_error` for the error
    /// distribution of box plots. Not serialised.
    pub sample_error: Option<Vec<f64>>,
}

impl DistanceEval {
    /// Absolute Chamfer-L1 `0.5 (mean d(R->S) + mean d(S->R))`.
    pub fn chamfer_l1_abs(&self) -> Option<f64> {
        Some(0.5 * (self.accuracy?.mean + self.completeness?.mean))
    }

    /// Absolute Hausdorff distance `max(max d(R->S), max d(S->R))`.
    pub fn hausdorff_abs(&self) -> Option<f64> {
        Some(self.accuracy?.max.max(self.completeness?.max))
    }

    /// Absolute `max(p95 d(R->S), p95 d(S->R))`.
    pub fn hausdorff_p95_abs(&self) -> Option<f64> {
        Some(self.accuracy?.p95.max(self.completeness?.p95))
    }

    /// The F-score at `tau` (a fraction of the diagonal), if computed.
    pub fn fscore(&self, tau: f64) -> Option<&FScore> {
        self.fscores.iter().find(|f| f.tau == tau)
    }
}

/// Formats a threshold for a key: `0.005`, `0.01`.
pub(crate) fn tau_key(t: f64) -> String {
    format!("{t}")
}

impl Report for DistanceEval {
    fn entries(&self) -> Entries {
        let d = self.diagonal;
        let mut e = Entries::new();
        let rel = |x: Option<f64>| x.map(|x| x / d);
        put(&mut e, "chamfer_l1", rel(self.chamfer_l1_abs()));
        put(&mut e, "chamfer_l1_abs", self.chamfer_l1_abs());
        put(&mut e, "hausdorff", rel(self.hausdorff_abs()));
        put(&mut e, "hausdorff_abs", self.hausdorff_abs());
        put(&mut e, "hausdorff_p95", rel(self.hausdorff_p95_abs()));
        put(&mut e, "hausdorff_p95_abs", self.hausdorff_p95_abs());
        for (name, s) in [
            ("accuracy", self.accuracy),
            ("completeness", self.completeness),
        ] {
            for (stat, f) in [
                ("mean", (|s: Summary| s.mean) as fn(Summary) -> f64),
                ("rms", |s| s.rms),
                ("p95", |s| s.p95),
                ("max", |s| s.max),
            ] {
                put(&mut e, format!("{name}_{stat}"), s.map(|s| f(s) / d));
                put(&mut e, format!("{name}_{stat}_abs"), s.map(f));
            }
        }
        for &t in &FSCORE_THRESHOLDS {
            let f = self.fscore(t);
            let k = tau_key(t);
            put(&mut e, format!("fscore_{k}"), f.map(|f| f.fscore));
            put(&mut e, format!("precision_{k}"), f.map(|f| f.precision));
            put(&mut e, format!("recall_{k}"), f.map(|f| f.recall));
        }
        put(&mut e, "gt_diagonal", d);
        put(&mut e, "samples_recon", self.recon_area_samples);
        put(&mut e, "samples_recon_vertices", self.recon_vertex_samples);
        put(&mut e, "samples_reference", self.reference_samples);
        put(&mut e, "sample_seed", self.seed);
        e
    }
}
serialize_as_entries!(DistanceEval);

/// Default number of area samples: `max(min_samples, samples_per_face x faces)`.
pub fn default_sample_count(opts: &DistanceOptions, faces: usize) -> usize {
    opts.min_samples
        .max(opts.samples_per_face.saturating_mul(faces))
}

/// The vertices of `mesh` used by at least one face, in index order.
pub(crate) fn referenced_vertices(mesh: &TriMesh) -> Vec<u32> {
    let mut used = vec![false; mesh.n_vertices()];
    for f in mesh.faces() {
        for &v in f {
            used[v as usize] = true;
        }
    }
    (0..mesh.n_vertices() as u32)
        .filter(|&v| used[v as usize])
        .collect()
}

/// Geometric comparison of a reconstructed mesh with the ground truth (see the module
/// docs for the exact definitions). Parallel; deterministic for a given seed whatever
/// the thread count.
///
/// Errors: R without faces or of zero area, a ground truth of zero diagonal, zero
/// sample counts.
pub fn eval_distance(
    recon: &TriMesh,
    reference: &Reference,
    opts: &DistanceOptions,
) -> Result<DistanceEval> {
    require_faces(recon, "reconstructed")?;
    let diagonal = reference.diagonal();
    if !(diagonal > 0.0 && diagonal.is_finite()) {
        return Err(MetricsError::InvalidInput(format!(
            "the ground truth has bounding-box diagonal {diagonal}"
        )));
    }
    let n_r = opts
        .recon_samples
        .unwrap_or_else(|| default_sample_count(opts, recon.n_faces()));
    let n_s = opts.reference_samples.unwrap_or_else(|| {
        default_sample_count(opts, reference.n_faces().unwrap_or(recon.n_faces()))
    });
    opts.validate()?;
    check_samples("samples", n_r)?;
    check_samples("samples", n_s)?;
    if n_r == 0 || n_s == 0 {
        return Err(MetricsError::InvalidParameter {
            name: "samples",
            message: "sample counts must be at least 1".to_string(),
        });
    }

    // The two sides are independent: run them concurrently, so that the (sequential)
    // BVH construction of R overlaps with the sampling and queries of the other side.
    let accuracy_side = || -> Result<Option<AccuracySide>> {
        if !opts.sides.accuracy() {
            return Ok(None);
        }
        let samples = sample_mesh(recon, n_r, opts.seed)?;
        let mut d = reference.distances(&samples.positions)?;
        let sample_error = opts.vertex_error.then(|| d.clone());
        let mut vertex_samples = 0;
        let mut vertex_error = None;
        if opts.include_vertices || opts.vertex_error {
            let dv = reference.distances(recon.vertices())?;
            if opts.include_vertices {
                let used = referenced_vertices(recon);
                vertex_samples = used.len();
                d.extend(used.iter().map(|&v| dv[v as usize]));
            }
            if opts.vertex_error {
                vertex_error = Some(dv);
            }
        }
        Ok(Some(AccuracySide {
            distances: d,
            vertex_samples,
            vertex_error,
            sample_error,
        }))
    };
    let completeness_side = || -> Result<Option<Vec<f64>>> {
        if !opts.sides.completeness() {
            return Ok(None);
        }
        let (bvh, samples) = rayon::join(
            || MeshBvh::new(recon),
            || reference.sample(n_s, opts.seed ^ REFERENCE_SEED_SALT),
        );
        let hits = bvh_closest_coherent(&bvh?, &samples.positions)?;
        Ok(Some(hits.into_iter().map(|h| h.distance).collect()))
    };
    let (acc, comp) = rayon::join(accuracy_side, completeness_side);
    let (accuracy_values, recon_vertex_samples, vertex_error, sample_error) = match acc? {
        Some(a) => (
            Some(a.distances),
            a.vertex_samples,
            a.vertex_error,
            a.sample_error,
        ),
        None => (None, 0, None, None),
    };
    let recon_area_samples = if accuracy_values.is_some() { n_r } else { 0 };
    let completeness_values = comp?;
    let reference_samples = if completeness_values.is_some() {
        n_s
    } else {
        0
    };

    let mut fscores = Vec::new();
    if let (Some(a), Some(c)) = (&accuracy_values, &completeness_values) {
        for &t in &FSCORE_THRESHOLDS {
            let tau_abs = t * diagonal;
            let precision = 100.0 * within(a, tau_abs);
            let recall = 100.0 * within(c, tau_abs);
            fscores.push(FScore {
                tau: t,
                tau_abs,
                precision,
                recall,
                fscore: harmonic(precision, recall),
            });
        }
    }

    Ok(DistanceEval {
        diagonal,
        accuracy: accuracy_values.as_deref().map(Summary::of),
        completeness: completeness_values.as_deref().map(Summary::of),
        fscores,
        recon_area_samples,
        recon_vertex_samples,
        reference_samples,
        seed: opts.seed,
        vertex_error,
        sample_error,
    })
}

/// What the accuracy side computes.
struct AccuracySide {
    distances: Vec<f64>,
    vertex_samples: usize,
    vertex_error: Option<Vec<f64>>,
    sample_error: Option<Vec<f64>>,
}

/// Share of `d` that is `<= tau`.
fn within(d: &[f64], tau: f64) -> f64 {
    d.iter().filter(|&&x| x <= tau).count() as f64 / d.len() as f64
}

/// Absolute distance of each point to the reference (exact; parallel; input order).
/// A convenience for per-point error channels.
pub fn point_errors(points: &[DVec3], reference: &Reference) -> Result<Vec<f64>> {
    reference.distances(points)
}
