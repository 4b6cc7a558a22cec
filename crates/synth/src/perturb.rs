//! Seeded, composable perturbations of a [`GroundTruthCloud`]. Each step is a serde
//! [`PerturbSpec`] (tagged by `kind`) with a short string form for the CLI; a list is
//! applied in order, step `i` drawing from its own stream derived from `(seed, i)`.

use std::fmt;
use std::str::FromStr;

use glam::{DMat3, DVec3};
use reconbench_geom::spatial::knn_self_table;
use reconbench_geom::{Aabb, mean_spacing};
use serde::{Deserialize, Serialize};

use crate::cloud::{GroundTruthCloud, NO_FEATURE, NO_SOURCE};
use crate::error::{Result, SynthError};
use crate::spec::{fmt_f64, format_kv, parse_f64, parse_kv, parse_usize};
use crate::util::{SynthRng, in_unit_ball, index, rng_for, std_normal, uniform, unit_vector};

/// The length a relative magnitude is measured in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reference {
    /// Bounding-box diagonal of the shape (1 for the built-in shapes): PCPNet's
    /// "% of the bounding box", seed 002 ch. 4.
    #[default]
    Diagonal,
    /// Enclosing radius, taken as half the bounding-box diagonal (seed 002 ch. 3's `R`:
    /// for its cube-with-hole R = 8.5 is the circumradius = half diagonal).
    Radius,
    /// Mean nearest-neighbour spacing of the clean points (`mean_spacing`, k = 1).
    Spacing,
    /// Absolute units.
    Absolute,
}

impl Reference {
    fn name(self) -> &'static str {
        match self {
            Reference::Diagonal => "diagonal",
            Reference::Radius => "radius",
            Reference::Spacing => "spacing",
            Reference::Absolute => "absolute",
        }
    }

    fn parse(owner: &str, v: &str) -> Result<Self> {
        Ok(match v {
            "diagonal" | "diag" => Reference::Diagonal,
            "radius" => Reference::Radius,
            "spacing" => Reference::Spacing,
            "absolute" | "abs" => Reference::Absolute,
            _ => {
                return Err(SynthError::invalid(
                    owner,
                    "rel",
                    format!("'{v}'; valid: diagonal, radius, spacing, absolute"),
                ));
            }
        })
    }
}

/// One perturbation step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum PerturbSpec {
    /// Isotropic Gaussian: every coordinate gets `N(0, sigma^2)` (so `sigma` is the
    /// per-axis standard deviation, PCPNet's convention). `gaussian:sigma=0.005,rel=diagonal`.
    Gaussian {
        /// Per-axis standard deviation (relative).
        sigma: f64,
        /// Reference length.
        #[serde(default)]
        relative_to: Reference,
    },
    /// Gaussian displacement along the GT normal. `normal-gaussian:sigma=0.005`.
    NormalGaussian {
        /// Standard deviation along the normal (relative).
        sigma: f64,
        /// Reference length.
        #[serde(default)]
        relative_to: Reference,
    },
    /// Uniform in a ball (seed 002's noise model: "x % noise" = ball radius x/100 of the
    /// reference; ch. 3 uses `rel=radius`, ch. 4 `rel=diagonal`). `ball:radius=0.01`.
    Ball {
        /// Ball radius (relative).
        radius: f64,
        /// Reference length.
        #[serde(default)]
        relative_to: Reference,
    },
    /// Seed 000's noise (ch. 4.4.3): each coordinate gets `U[-level s_p, level s_p]`, where
    /// `s_p` is the mean distance from the clean point to its `k` (10) nearest other clean
    /// points; levels 0 to 0.2. `ma-uniform:level=0.1`.
    MaUniform {
        /// Noise level (factor of the local scale).
        level: f64,
        /// Neighbours of the local scale.
        #[serde(default = "default_k")]
        k: usize,
    },
    /// Uniform outliers in the bounding box of the shape inflated by `inflate` (relative to
    /// the diagonal) on every side; `round(fraction n)` points appended, marked
    /// `is_outlier`, source id [`NO_SOURCE`]. `outliers:fraction=0.1,inflate=0.1`.
    Outliers {
        /// Outliers per input point.
        fraction: f64,
        /// Box inflation (relative to the diagonal).
        #[serde(default = "default_inflate")]
        inflate: f64,
    },
    /// SCUTSurface's outliers: extra copies of `round(fraction n)` random points, each
    /// coordinate displaced by `+-U(min, max)` (relative to the diagonal); marked as
    /// outliers. `copies:fraction=0.003,min=0.01,max=0.1`.
    DisplacedCopies {
        /// Copies per input point.
        fraction: f64,
        /// Smallest per-axis displacement (relative).
        #[serde(default = "default_copy_min")]
        min: f64,
        /// Largest per-axis displacement (relative).
        #[serde(default = "default_copy_max")]
        max: f64,
    },
    /// Random decimation keeping `round(keep n)` points (order preserved).
    /// `decimate:keep=0.5`.
    Decimate {
        /// Fraction kept.
        keep: f64,
    },
    /// Patch-wise missing data: `count` holes centred on random points; every point whose
    /// clean position is within `radius` (relative) of a centre is removed.
    /// `holes:count=5,radius=0.05`.
    Holes {
        /// Number of holes.
        count: usize,
        /// Hole radius (relative).
        radius: f64,
        /// Reference length.
        #[serde(default)]
        relative_to: Reference,
    },
    /// Exact duplicates of `round(fraction n)` random points, appended (same source id).
    /// `duplicate:fraction=0.02`.
    Duplicate {
        /// Duplicates per input point.
        fraction: f64,
    },
    /// Scan-group misalignment (SCUTSurface): points are grouped by scan id (or, without
    /// scans, into `groups` slabs along a random direction); each group is rotated about
    /// its centroid by `U(-angle, angle)` degrees about each axis and translated by
    /// `U(-shift, shift)` (relative) per axis. `misalign:groups=4,angle=1,shift=0.01`.
    Misalign {
        /// Groups without scan ids.
        #[serde(default = "default_groups")]
        groups: usize,
        /// Max rotation per Euler axis, degrees.
        angle: f64,
        /// Max translation per axis (relative).
        shift: f64,
        /// Reference length of `shift`.
        #[serde(default)]
        relative_to: Reference,
    },
}

fn default_k() -> usize {
    10
}
fn default_inflate() -> f64 {
    0.1
}
fn default_copy_min() -> f64 {
    0.01
}
fn default_copy_max() -> f64 {
    0.1
}
fn default_groups() -> usize {
    4
}

const KINDS: &str = "gaussian, normal-gaussian, ball, ma-uniform, outliers, copies, decimate, holes, duplicate, misalign";

impl FromStr for PerturbSpec {
    type Err = SynthError;
    fn from_str(s: &str) -> Result<Self> {
        let kv = parse_kv("noise", s, true)?;
        let owner = format!("perturbation '{}'", kv.name);
        let keys: &[&str] = match kv.name.as_str() {
            "gaussian" | "normal-gaussian" => &["sigma", "rel"],
            "ball" => &["radius", "rel"],
            "ma-uniform" => &["level", "k"],
            "outliers" => &["fraction", "inflate"],
            "copies" => &["fraction", "min", "max"],
            "decimate" => &["keep"],
            "holes" => &["count", "radius", "rel"],
            "duplicate" => &["fraction"],
            "misalign" => &["groups", "angle", "shift", "rel"],
            _ => {
                return Err(SynthError::UnknownName {
                    what: "perturbation",
                    name: kv.name,
                    valid: KINDS.into(),
                });
            }
        };
        for (k, _) in &kv.params {
            if !keys.contains(&k.as_str()) {
                return Err(SynthError::UnknownParameter {
                    owner: owner.clone(),
                    name: k.clone(),
                    valid: keys.join(", "),
                });
            }
        }
        let get = |k: &str| {
            kv.params
                .iter()
                .find(|(pk, _)| pk == k)
                .map(|(_, v)| v.as_str())
        };
        let num = |k: &str, default: Option<f64>| -> Result<f64> {
            match (get(k), default) {
                (Some(v), _) => parse_f64(&owner, k, v),
                (None, Some(d)) => Ok(d),
                (None, None) => Err(SynthError::invalid(&owner, k, "is required")),
            }
        };
        let int = |k: &str, default: usize| -> Result<usize> {
            get(k).map_or(Ok(default), |v| parse_usize(&owner, k, v))
        };
        let rel = get("rel").map_or(Ok(Reference::Diagonal), |v| Reference::parse(&owner, v))?;
        let spec = match kv.name.as_str() {
            "gaussian" => PerturbSpec::Gaussian {
                sigma: num("sigma", None)?,
                relative_to: rel,
            },
            "normal-gaussian" => PerturbSpec::NormalGaussian {
                sigma: num("sigma", None)?,
                relative_to: rel,
            },
            "ball" => PerturbSpec::Ball {
                radius: num("radius", None)?,
                relative_to: rel,
            },
            "ma-uniform" => PerturbSpec::MaUniform {
                level: num("level", None)?,
                k: int("k", 10)?,
            },
            "outliers" => PerturbSpec::Outliers {
                fraction: num("fraction", None)?,
                inflate: num("inflate", Some(0.1))?,
            },
            "copies" => PerturbSpec::DisplacedCopies {
                fraction: num("fraction", None)?,
                min: num("min", Some(0.01))?,
                max: num("max", Some(0.1))?,
            },
            "decimate" => PerturbSpec::Decimate {
                keep: num("keep", None)?,
            },
            "holes" => PerturbSpec::Holes {
                count: int("count", 5)?,
                radius: num("radius", None)?,
                relative_to: rel,
            },
            "duplicate" => PerturbSpec::Duplicate {
                fraction: num("fraction", None)?,
            },
            _ => PerturbSpec::Misalign {
                groups: int("groups", 4)?,
                angle: num("angle", None)?,
                shift: num("shift", Some(0.0))?,
                relative_to: rel,
            },
        };
        spec.validate()?;
        Ok(spec)
    }
}

impl fmt::Display for PerturbSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = |x: &Reference| ("rel", x.name().to_string());
        let s = match self {
            PerturbSpec::Gaussian { sigma, relative_to } => {
                format_kv("gaussian", [("sigma", fmt_f64(*sigma)), r(relative_to)])
            }
            PerturbSpec::NormalGaussian { sigma, relative_to } => format_kv(
                "normal-gaussian",
                [("sigma", fmt_f64(*sigma)), r(relative_to)],
            ),
            PerturbSpec::Ball {
                radius,
                relative_to,
            } => format_kv("ball", [("radius", fmt_f64(*radius)), r(relative_to)]),
            PerturbSpec::MaUniform { level, k } => format_kv(
                "ma-uniform",
                [("level", fmt_f64(*level)), ("k", k.to_string())],
            ),
            PerturbSpec::Outliers { fraction, inflate } => format_kv(
                "outliers",
                [
                    ("fraction", fmt_f64(*fraction)),
                    ("inflate", fmt_f64(*inflate)),
                ],
            ),
            PerturbSpec::DisplacedCopies { fraction, min, max } => format_kv(
                "copies",
                [
                    ("fraction", fmt_f64(*fraction)),
                    ("min", fmt_f64(*min)),
                    ("max", fmt_f64(*max)),
                ],
            ),
            PerturbSpec::Decimate { keep } => format_kv("decimate", [("keep", fmt_f64(*keep))]),
            PerturbSpec::Holes {
                count,
                radius,
                relative_to,
            } => format_kv(
                "holes",
                [
                    ("count", count.to_string()),
                    ("radius", fmt_f64(*radius)),
                    r(relative_to),
                ],
            ),
            PerturbSpec::Duplicate { fraction } => {
                format_kv("duplicate", [("fraction", fmt_f64(*fraction))])
            }
            PerturbSpec::Misalign {
                groups,
                angle,
                shift,
                relative_to,
            } => format_kv(
                "misalign",
                [
                    ("groups", groups.to_string()),
                    ("angle", fmt_f64(*angle)),
                    ("shift", fmt_f64(*shift)),
                    r(relative_to),
                ],
            ),
        };
        f.write_str(&s)
    }
}

/// Most points a perturbation may add per input point (`outliers`, `copies`,
/// `duplicate` fractions).
pub const MAX_ADDED_PER_POINT: f64 = 100.0;

impl PerturbSpec {
    /// Checks parameter ranges.
    pub fn validate(&self) -> Result<()> {
        let owner = format!("perturbation '{self}'");
        let nonneg = |k: &str, v: f64| {
            if v >= 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(SynthError::invalid(&owner, k, format!("{v} must be >= 0")))
            }
        };
        // Points added per input point: bounded, so a typo cannot ask for 1e9 copies.
        let added = |k: &str, v: f64| {
            nonneg(k, v)?;
            if v <= MAX_ADDED_PER_POINT {
                Ok(())
            } else {
                Err(SynthError::invalid(
                    &owner,
                    k,
                    format!(
                        "{v} points added per input point: at most {MAX_ADDED_PER_POINT} \
                         (1,000 input points would become {:.3e} and need {})",
                        1000.0 * (1.0 + v),
                        crate::sampler::memory_estimate(1000.0 * (1.0 + v))
                    ),
                ))
            }
        };
        match *self {
            PerturbSpec::Gaussian { sigma, .. } | PerturbSpec::NormalGaussian { sigma, .. } => {
                nonneg("sigma", sigma)
            }
            PerturbSpec::Ball { radius, .. } | PerturbSpec::Holes { radius, .. } => {
                nonneg("radius", radius)
            }
            PerturbSpec::MaUniform { level, k } => {
                nonneg("level", level)?;
                if k == 0 {
                    return Err(SynthError::invalid(&owner, "k", "must be >= 1"));
                }
                Ok(())
            }
            PerturbSpec::Outliers { fraction, inflate } => {
                added("fraction", fraction)?;
                nonneg("inflate", inflate)
            }
            PerturbSpec::DisplacedCopies { fraction, min, max } => {
                added("fraction", fraction)?;
                nonneg("min", min)?;
                if max < min {
                    return Err(SynthError::invalid(
                        &owner,
                        "max",
                        format!("{max} must be >= min {min}"),
                    ));
                }
                Ok(())
            }
            PerturbSpec::Decimate { keep } => {
                if (0.0..=1.0).contains(&keep) {
                    Ok(())
                } else {
                    Err(SynthError::invalid(
                        &owner,
                        "keep",
                        format!("{keep} must be in [0, 1]"),
                    ))
                }
            }
            PerturbSpec::Duplicate { fraction } => added("fraction", fraction),
            PerturbSpec::Misalign {
                groups,
                angle,
                shift,
                ..
            } => {
                nonneg("angle", angle)?;
                nonneg("shift", shift)?;
                if groups == 0 {
                    return Err(SynthError::invalid(&owner, "groups", "must be >= 1"));
                }
                Ok(())
            }
        }
    }
}

/// Parses a `;`-separated list of perturbation strings (also accepts `+`).
pub fn parse_list(s: &str) -> Result<Vec<PerturbSpec>> {
    s.split([';', '+'])
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(str::parse)
        .collect()
}

/// Reference lengths for one cloud.
#[derive(Debug, Clone, Copy)]
pub struct PerturbContext {
    /// Bounding box of the shape (not of the noisy cloud).
    pub aabb: Aabb,
}

impl PerturbContext {
    fn length(&self, r: Reference, cloud: &GroundTruthCloud) -> Result<f64> {
        Ok(match r {
            Reference::Diagonal => self.aabb.diagonal(),
            Reference::Radius => 0.5 * self.aabb.diagonal(),
            Reference::Spacing => mean_spacing(&clean_inliers(cloud), 1)?,
            Reference::Absolute => 1.0,
        })
    }
}

fn clean_inliers(c: &GroundTruthCloud) -> Vec<DVec3> {
    c.clean_positions
        .iter()
        .zip(&c.is_outlier)
        .filter(|(_, o)| !**o)
        .map(|(p, _)| *p)
        .collect()
}

/// Applies `steps` in order; step `i` uses the stream `(seed, "perturb", i)`.
pub fn apply_all(
    cloud: &mut GroundTruthCloud,
    steps: &[PerturbSpec],
    ctx: &PerturbContext,
    seed: u64,
) -> Result<()> {
    for (i, s) in steps.iter().enumerate() {
        apply(cloud, s, ctx, &mut rng_for(seed, "perturb", i as u64))?;
    }
    Ok(())
}

/// Applies one step.
pub fn apply(
    cloud: &mut GroundTruthCloud,
    spec: &PerturbSpec,
    ctx: &PerturbContext,
    rng: &mut SynthRng,
) -> Result<()> {
    spec.validate()?;
    let n = cloud.len();
    match *spec {
        PerturbSpec::Gaussian { sigma, relative_to } => {
            let s = sigma * ctx.length(relative_to, cloud)?;
            for p in &mut cloud.positions {
                *p += DVec3::new(std_normal(rng), std_normal(rng), std_normal(rng)) * s;
            }
        }
        PerturbSpec::NormalGaussian { sigma, relative_to } => {
            let s = sigma * ctx.length(relative_to, cloud)?;
            for (p, nrm) in cloud.positions.iter_mut().zip(&cloud.normals) {
                *p += *nrm * (std_normal(rng) * s);
            }
        }
        PerturbSpec::Ball {
            radius,
            relative_to,
        } => {
            let r = radius * ctx.length(relative_to, cloud)?;
            for p in &mut cloud.positions {
                *p += in_unit_ball(rng) * r;
            }
        }
        PerturbSpec::MaUniform { level, k } => {
            if n < 2 {
                return Ok(());
            }
            let table = knn_self_table(&cloud.clean_positions, k, true)?;
            for (i, p) in cloud.positions.iter_mut().enumerate() {
                let sp = table.dist2(i).iter().map(|d| d.sqrt()).sum::<f64>() / table.k as f64;
                let a = level * sp;
                *p += DVec3::new(
                    uniform(rng, -a, a),
                    uniform(rng, -a, a),
                    uniform(rng, -a, a),
                );
            }
        }
        PerturbSpec::Outliers { fraction, inflate } => {
            let m = (fraction * n as f64).round();
            crate::sampler::check_count("perturbation 'outliers'", "fraction", n as f64 + m)?;
            let m = m as usize;
            let pad = DVec3::splat(inflate * ctx.aabb.diagonal());
            let (lo, hi) = (ctx.aabb.min - pad, ctx.aabb.max + pad);
            let pts: Vec<DVec3> = (0..m)
                .map(|_| {
                    DVec3::new(
                        uniform(rng, lo.x, hi.x),
                        uniform(rng, lo.y, hi.y),
                        uniform(rng, lo.z, hi.z),
                    )
                })
                .collect();
            cloud.append(&outliers(pts));
        }
        PerturbSpec::DisplacedCopies { fraction, min, max } => {
            let m = (fraction * n as f64).round();
            crate::sampler::check_count("perturbation 'copies'", "fraction", n as f64 + m)?;
            let m = m as usize;
            let d = ctx.aabb.diagonal();
            if n == 0 {
                return Ok(());
            }
            let pts: Vec<DVec3> = (0..m)
                .map(|_| {
                    let p = cloud.positions[index(rng, n)];
                    let mut off = DVec3::ZERO;
                    for k in 0..3 {
                        let sgn = if uniform(rng, 0.0, 1.0) < 0.5 {
                            -1.0
                        } else {
                            1.0
                        };
                        off[k] = sgn * uniform(rng, min, max) * d;
                    }
                    p + off
                })
                .collect();
            cloud.append(&outliers(pts));
        }
        PerturbSpec::Decimate { keep } => {
            let m = (keep * n as f64).round() as usize;
            let mut idx: Vec<usize> = (0..n).collect();
            for i in 0..m.min(n) {
                let j = i + index(rng, n - i);
                idx.swap(i, j);
            }
            idx.truncate(m);
            idx.sort_unstable();
            *cloud = cloud.select(&idx);
        }
        PerturbSpec::Holes {
            count,
            radius,
            relative_to,
        } => {
            let r = radius * ctx.length(relative_to, cloud)?;
            let inl: Vec<usize> = (0..n).filter(|&i| !cloud.is_outlier[i]).collect();
            if inl.is_empty() {
                return Ok(());
            }
            let centres: Vec<DVec3> = (0..count)
                .map(|_| cloud.clean_positions[inl[index(rng, inl.len())]])
                .collect();
            let keep: Vec<usize> = (0..n)
                .filter(|&i| {
                    cloud.is_outlier[i]
                        || centres
                            .iter()
                            .all(|c| (cloud.clean_positions[i] - *c).length() > r)
                })
                .collect();
            *cloud = cloud.select(&keep);
        }
        PerturbSpec::Duplicate { fraction } => {
            let m = (fraction * n as f64).round();
            if n == 0 {
                return Ok(());
            }
            crate::sampler::check_count("perturbation 'duplicate'", "fraction", n as f64 + m)?;
            let m = m as usize;
            let mut idx: Vec<usize> = (0..n).collect();
            idx.extend((0..m).map(|_| index(rng, n)));
            *cloud = cloud.select(&idx);
        }
        PerturbSpec::Misalign {
            groups,
            angle,
            shift,
            relative_to,
        } => {
            let t = shift * ctx.length(relative_to, cloud)?;
            let group: Vec<usize> = match &cloud.scan_ids {
                Some(s) => s
                    .iter()
                    .map(|&x| {
                        if x == u32::MAX {
                            usize::MAX
                        } else {
                            x as usize
                        }
                    })
                    .collect(),
                None => {
                    let dir = unit_vector(rng);
                    let mut order: Vec<usize> = (0..n).collect();
                    order.sort_by(|&a, &b| {
                        cloud.positions[a]
                            .dot(dir)
                            .total_cmp(&cloud.positions[b].dot(dir))
                            .then(a.cmp(&b))
                    });
                    let mut g = vec![0; n];
                    for (rank, &i) in order.iter().enumerate() {
                        g[i] = rank * groups / n.max(1);
                    }
                    g
                }
            };
            let ng = group
                .iter()
                .filter(|&&g| g != usize::MAX)
                .max()
                .map_or(0, |m| m + 1);
            for g in 0..ng {
                let members: Vec<usize> = (0..n).filter(|&i| group[i] == g).collect();
                let a = angle.to_radians();
                let rot = DMat3::from_rotation_z(uniform(rng, -a, a))
                    * DMat3::from_rotation_y(uniform(rng, -a, a))
                    * DMat3::from_rotation_x(uniform(rng, -a, a));
                let tr = DVec3::new(
                    uniform(rng, -t, t),
                    uniform(rng, -t, t),
                    uniform(rng, -t, t),
                );
                if members.is_empty() {
                    continue;
                }
                let c = members.iter().map(|&i| cloud.positions[i]).sum::<DVec3>()
                    / members.len() as f64;
                for &i in &members {
                    cloud.positions[i] = c + rot * (cloud.positions[i] - c) + tr;
                }
            }
        }
    }
    Ok(())
}

fn outliers(pts: Vec<DVec3>) -> GroundTruthCloud {
    let m = pts.len();
    GroundTruthCloud {
        clean_positions: pts.clone(),
        positions: pts,
        normals: vec![DVec3::ZERO; m],
        source_ids: vec![NO_SOURCE; m],
        feature_distance: vec![NO_FEATURE; m],
        is_outlier: vec![true; m],
        scan_ids: None,
        view_dirs: None,
    }
}
