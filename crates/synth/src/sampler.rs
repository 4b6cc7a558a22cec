//! Surface samplers: area-uniform random, blue noise (sample elimination), parametric
//! grids, and PCPNet-style density gradient and stripes; by count or by spacing.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::PointIndex;
use serde::{Deserialize, Serialize};

use crate::cloud::{GroundTruthCloud, NO_FEATURE};
use crate::error::{Result, SynthError};
use crate::shape::{Sample, Shape};
use crate::spec::{fmt_f64, format_kv, parse_f64, parse_kv, parse_usize};
use crate::util::{rng_for, unit};

/// How many points: an exact count, or a spacing `h` meaning one point per `h^2` of
/// surface area (`n = ceil(area / h^2)`; the mean nearest-neighbour distance of a
/// uniform random sample is then about `0.5 h`, of a blue-noise sample about `0.9 h`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Density {
    /// Exactly this many points (grids: as close as the grid allows).
    Count(usize),
    /// Spacing in the shape's units (unit bounding-box diagonal for built-in shapes).
    Spacing(f64),
}

/// Most points one sample may hold (and most nodes of a `grid` sampler's `nu x nv`):
/// a sampled cloud of that size already takes about 8 GB (positions, clean positions,
/// normals, feature distances and ids, 84 bytes a point), so a request beyond it is
/// refused before anything is allocated.
pub const MAX_SAMPLES: usize = 100_000_000;

/// Bytes per point of a sampled ground-truth cloud (for the estimates in messages).
const BYTES_PER_SAMPLE: f64 = 84.0;

/// "about 24 TB": the memory `n` sampled points would take.
pub(crate) fn memory_estimate(n: f64) -> String {
    let b = n * BYTES_PER_SAMPLE;
    let (v, unit) = [(1e15, "PB"), (1e12, "TB"), (1e9, "GB"), (1e6, "MB")]
        .into_iter()
        .find(|(u, _)| b >= *u)
        .map_or((b / 1e3, "kB"), |(u, name)| (b / u, name));
    format!("about {v:.0} {unit}")
}

/// Refuses a point count above [`MAX_SAMPLES`], naming the memory it would need.
pub(crate) fn check_count(owner: &str, name: &str, n: f64) -> Result<()> {
    if n <= MAX_SAMPLES as f64 {
        return Ok(());
    }
    Err(SynthError::invalid(
        owner,
        name,
        format!(
            "{n:.3e} points need {}: at most {MAX_SAMPLES} points",
            memory_estimate(n)
        ),
    ))
}

impl Density {
    /// The point count for `shape`; more than [`MAX_SAMPLES`] is refused.
    pub fn count(&self, shape: &dyn Shape) -> Result<usize> {
        match *self {
            Density::Count(n) => {
                check_count("density", "points", n as f64)?;
                Ok(n)
            }
            Density::Spacing(h) if h > 0.0 && h.is_finite() => {
                let n = (shape.area() / (h * h)).ceil();
                check_count("density", "spacing", n)?;
                Ok(n as usize)
            }
            Density::Spacing(h) => Err(SynthError::invalid(
                "density",
                "spacing",
                format!("{h} must be > 0"),
            )),
        }
    }
}

/// Axis of the density variants.
fn axis_vec(axis: usize) -> DVec3 {
    [DVec3::X, DVec3::Y, DVec3::Z][axis.min(2)]
}

/// A sampler. String forms: `uniform`, `blue-noise[:oversample=5]`,
/// `grid[:nu=60,nv=60]`, `gradient[:min=0.1,axis=0]`, `stripes[:count=5,min=0.1,axis=0]`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum SamplerSpec {
    /// Area-uniform i.i.d. samples.
    #[default]
    Uniform,
    /// Blue noise by weighted sample elimination (Yuksel 2015) from `oversample` times
    /// as many uniform samples.
    BlueNoise {
        /// Oversampling factor (>= 2; Yuksel uses 5).
        #[serde(default = "default_oversample")]
        oversample: f64,
    },
    /// The shape's parametric grid (`nu` x `nv`, meaning per shape; e.g. torus 60 x 60,
    /// box `nu` points per edge). Without dimensions, derived from the count.
    Grid {
        /// First grid dimension.
        #[serde(default)]
        nu: Option<usize>,
        /// Second grid dimension.
        #[serde(default)]
        nv: Option<usize>,
    },
    /// The shape's own vertices (a mesh: de-duplicated, with area-weighted vertex
    /// normals); the point count is not used.
    Vertices,
    /// PCPNet-like density gradient ("simulating distance from the sensor"): keep
    /// probability rises linearly from `min` to 1 along `axis` over the bounding box.
    Gradient {
        /// Relative density at the sparse end.
        #[serde(default = "default_min")]
        min: f64,
        /// 0 = x, 1 = y, 2 = z.
        #[serde(default)]
        axis: usize,
    },
    /// PCPNet-like stripes ("simulating occlusion"): `count` equal slabs along `axis`
    /// alternate between density 1 and `min`.
    Stripes {
        /// Number of slabs.
        #[serde(default = "default_stripes")]
        count: usize,
        /// Relative density of the sparse slabs.
        #[serde(default = "default_min")]
        min: f64,
        /// 0 = x, 1 = y, 2 = z.
        #[serde(default)]
        axis: usize,
    },
}

fn default_oversample() -> f64 {
    5.0
}
fn default_min() -> f64 {
    0.1
}
fn default_stripes() -> usize {
    5
}

const SAMPLER_NAMES: &str = "uniform, blue-noise, grid, vertices, gradient, stripes";

impl FromStr for SamplerSpec {
    type Err = SynthError;
    fn from_str(s: &str) -> Result<Self> {
        let kv = parse_kv("sampler", s, true)?;
        let owner = format!("sampler '{}'", kv.name);
        let allowed: &[&str] = match kv.name.as_str() {
            "uniform" => &[],
            "blue-noise" => &["oversample"],
            "grid" => &["nu", "nv"],
            "vertices" => &[],
            "gradient" => &["min", "axis"],
            "stripes" => &["count", "min", "axis"],
            _ => {
                return Err(SynthError::UnknownName {
                    what: "sampler",
                    name: kv.name,
                    valid: SAMPLER_NAMES.into(),
                });
            }
        };
        let mut spec = match kv.name.as_str() {
            "uniform" => SamplerSpec::Uniform,
            "blue-noise" => SamplerSpec::BlueNoise { oversample: 5.0 },
            "grid" => SamplerSpec::Grid { nu: None, nv: None },
            "vertices" => SamplerSpec::Vertices,
            "gradient" => SamplerSpec::Gradient { min: 0.1, axis: 0 },
            _ => SamplerSpec::Stripes {
                count: 5,
                min: 0.1,
                axis: 0,
            },
        };
        for (k, v) in &kv.params {
            if !allowed.contains(&k.as_str()) {
                return Err(SynthError::UnknownParameter {
                    owner,
                    name: k.clone(),
                    valid: if allowed.is_empty() {
                        "(none)".into()
                    } else {
                        allowed.join(", ")
                    },
                });
            }
            match (&mut spec, k.as_str()) {
                (SamplerSpec::BlueNoise { oversample }, _) => {
                    *oversample = parse_f64(&owner, k, v)?
                }
                (SamplerSpec::Grid { nu, .. }, "nu") => *nu = Some(parse_usize(&owner, k, v)?),
                (SamplerSpec::Grid { nv, .. }, _) => *nv = Some(parse_usize(&owner, k, v)?),
                (SamplerSpec::Gradient { min, .. } | SamplerSpec::Stripes { min, .. }, "min") => {
                    *min = parse_f64(&owner, k, v)?
                }
                (
                    SamplerSpec::Gradient { axis, .. } | SamplerSpec::Stripes { axis, .. },
                    "axis",
                ) => *axis = parse_usize(&owner, k, v)?,
                (SamplerSpec::Stripes { count, .. }, _) => *count = parse_usize(&owner, k, v)?,
                _ => unreachable!("checked against the allowed keys"),
            }
        }
        spec.validate()?;
        Ok(spec)
    }
}

impl fmt::Display for SamplerSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            SamplerSpec::Uniform => "uniform".to_string(),
            SamplerSpec::BlueNoise { oversample } => {
                format_kv("blue-noise", [("oversample", fmt_f64(*oversample))])
            }
            SamplerSpec::Grid { nu, nv } => format_kv(
                "grid",
                nu.map(|x| ("nu", x.to_string()))
                    .into_iter()
                    .chain(nv.map(|x| ("nv", x.to_string()))),
            ),
            SamplerSpec::Vertices => "vertices".to_string(),
            SamplerSpec::Gradient { min, axis } => format_kv(
                "gradient",
                [("min", fmt_f64(*min)), ("axis", axis.to_string())],
            ),
            SamplerSpec::Stripes { count, min, axis } => format_kv(
                "stripes",
                [
                    ("count", count.to_string()),
                    ("min", fmt_f64(*min)),
                    ("axis", axis.to_string()),
                ],
            ),
        };
        f.write_str(&s)
    }
}

impl SamplerSpec {
    /// Checks parameter ranges.
    pub fn validate(&self) -> Result<()> {
        let bad = |k: &str, m: String| Err(SynthError::invalid(format!("sampler '{self}'"), k, m));
        match *self {
            SamplerSpec::BlueNoise { oversample } if oversample.is_nan() || oversample < 1.5 => {
                bad("oversample", format!("{oversample} must be >= 1.5"))
            }
            SamplerSpec::Gradient { min, axis } | SamplerSpec::Stripes { min, axis, .. }
                if !(min > 0.0 && min <= 1.0) || axis > 2 =>
            {
                bad(
                    "min/axis",
                    format!("min {min} must be in (0, 1], axis {axis} in 0..=2"),
                )
            }
            SamplerSpec::Stripes { count: 0, .. } => bad("count", "must be >= 1".into()),
            SamplerSpec::Grid { nu, nv } if nu == Some(0) || nv == Some(0) => {
                bad("nu/nv", "must be >= 1".into())
            }
            SamplerSpec::Grid {
                nu: Some(nu),
                nv: Some(nv),
            } if nu as f64 * nv as f64 > MAX_SAMPLES as f64 => {
                let n = nu as f64 * nv as f64;
                bad(
                    "nu/nv",
                    format!(
                        "a {nu} x {nv} grid has {n:.3e} nodes and needs {}: at most \
                         {MAX_SAMPLES} nodes",
                        memory_estimate(n)
                    ),
                )
            }
            SamplerSpec::Grid {
                nu: Some(nu),
                nv: None,
            } if nu as f64 * nu as f64 > MAX_SAMPLES as f64 => {
                let n = nu as f64 * nu as f64;
                bad(
                    "nu",
                    format!(
                        "a {nu} x {nu} grid has {n:.3e} nodes and needs {}: at most \
                         {MAX_SAMPLES} nodes",
                        memory_estimate(n)
                    ),
                )
            }
            _ => Ok(()),
        }
    }
}

/// Samples `shape` into a [`GroundTruthCloud`] with source ids `0..n`, clean positions,
/// GT normals and feature distances. Deterministic for a given `seed`.
pub fn sample(
    shape: &dyn Shape,
    spec: &SamplerSpec,
    density: Density,
    seed: u64,
) -> Result<GroundTruthCloud> {
    spec.validate()?;
    if *spec == SamplerSpec::Vertices {
        let samples = shape.vertex_samples().ok_or_else(|| {
            SynthError::Unsatisfiable(format!(
                "shape '{}' has no vertices: the vertices sampler needs a mesh",
                shape.name()
            ))
        })?;
        return Ok(from_samples(shape, &samples));
    }
    let n = density.count(shape)?;
    let samples = match *spec {
        SamplerSpec::Uniform => shape.sample_uniform(n, &mut rng_for(seed, "uniform", 0)),
        SamplerSpec::BlueNoise { oversample } => blue_noise(shape, n, oversample, seed)?,
        SamplerSpec::Grid { nu, nv } => {
            let (du, dv) = shape.grid_dims_for_count(n);
            shape
                .parametric_grid(nu.unwrap_or(du), nv.or(nu).unwrap_or(dv))
                .ok_or_else(|| {
                    SynthError::Unsatisfiable(format!(
                        "shape '{}' has no parametric grid",
                        shape.name()
                    ))
                })?
        }
        SamplerSpec::Vertices => unreachable!("handled above"),
        SamplerSpec::Gradient { min, axis } => {
            let b = shape.aabb();
            let a = axis_vec(axis);
            let (lo, span) = (b.min.dot(a), b.size().dot(a).max(f64::MIN_POSITIVE));
            thinned(shape, n, seed, &|p| {
                min + (1.0 - min) * ((p.dot(a) - lo) / span).clamp(0.0, 1.0)
            })
        }
        SamplerSpec::Stripes { count, min, axis } => {
            let b = shape.aabb();
            let a = axis_vec(axis);
            let (lo, span) = (b.min.dot(a), b.size().dot(a).max(f64::MIN_POSITIVE));
            thinned(shape, n, seed, &|p| {
                let k = (((p.dot(a) - lo) / span * count as f64).floor() as i64)
                    .clamp(0, count as i64 - 1);
                if k % 2 == 0 { 1.0 } else { min }
            })
        }
    };
    Ok(from_samples(shape, &samples))
}

/// A clean cloud from surface samples.
pub fn from_samples(shape: &dyn Shape, samples: &[Sample]) -> GroundTruthCloud {
    let positions: Vec<DVec3> = samples.iter().map(|s| s.position).collect();
    let feature_distance = positions
        .par_iter()
        .map(|&p| {
            let d = shape.feature_distance(p);
            if d.is_finite() { d } else { NO_FEATURE }
        })
        .collect();
    GroundTruthCloud {
        clean_positions: positions.clone(),
        normals: samples.iter().map(|s| s.normal).collect(),
        source_ids: (0..samples.len() as u32).collect(),
        feature_distance,
        is_outlier: vec![false; samples.len()],
        positions,
        scan_ids: None,
        view_dirs: None,
    }
}

/// Uniform samples kept with probability `keep(p)` until `n` are accepted.
fn thinned(
    shape: &dyn Shape,
    n: usize,
    seed: u64,
    keep: &(dyn Fn(DVec3) -> f64 + Sync),
) -> Vec<Sample> {
    let mut rng = rng_for(seed, "thinned", 0);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let batch = shape.sample_uniform((n - out.len()).max(64) * 2, &mut rng);
        for s in batch {
            if out.len() < n && unit(&mut rng) < keep(s.position) {
                out.push(s);
            }
        }
    }
    out
}

/// Weighted sample elimination (Yuksel, "Sample Elimination for Generating Poisson Disk
/// Sample Sets", CGF 2015) with his surface defaults: `r_max = sqrt(A / (2 sqrt(3) n))`,
/// weights `(1 - d / (2 r_max))^8`, weight limiting with `r_min = r_max (1 - (n/M)^1.5)
/// 0.65`. Ties are broken by index, so the result is deterministic.
fn blue_noise(shape: &dyn Shape, n: usize, oversample: f64, seed: u64) -> Result<Vec<Sample>> {
    if n < 2 {
        return Ok(shape.sample_uniform(n, &mut rng_for(seed, "blue-noise", 0)));
    }
    let m = ((n as f64) * oversample).ceil() as usize;
    let cand = shape.sample_uniform(m, &mut rng_for(seed, "blue-noise", 0));
    let pts: Vec<DVec3> = cand.iter().map(|s| s.position).collect();
    let r_max = (shape.area() / (2.0 * 3f64.sqrt() * n as f64)).sqrt();
    let r_min = r_max * (1.0 - (n as f64 / m as f64).powf(1.5)) * 0.65;
    let index = PointIndex::new(&pts)?;
    let table = index.radius_batch(&pts, 2.0 * r_max)?;
    let w = |d2: f64| {
        let d = d2.sqrt().max(r_min);
        (1.0 - d / (2.0 * r_max)).max(0.0).powi(8)
    };
    let mut weight: Vec<f64> = (0..m)
        .map(|i| {
            table
                .indices(i)
                .iter()
                .zip(table.dist2(i))
                .filter(|(j, _)| **j as usize != i)
                .map(|(_, &d2)| w(d2))
                .sum()
        })
        .collect();
    let mut alive = vec![true; m];
    let mut heap: BinaryHeap<(u64, Reverse<usize>)> =
        (0..m).map(|i| (weight[i].to_bits(), Reverse(i))).collect();
    let mut remaining = m;
    while remaining > n {
        let (wb, Reverse(i)) = heap.pop().expect("heap holds every live point");
        if !alive[i] || wb != weight[i].to_bits() {
            continue;
        }
        alive[i] = false;
        remaining -= 1;
        for (j, &d2) in table.indices(i).iter().zip(table.dist2(i)) {
            let j = *j as usize;
            if j != i && alive[j] {
                weight[j] = (weight[j] - w(d2)).max(0.0);
                heap.push((weight[j].to_bits(), Reverse(j)));
            }
        }
    }
    Ok((0..m).filter(|&i| alive[i]).map(|i| cand[i]).collect())
}
