//! `blend`: blending a designed NURBS surface into a scanned point set (seed 002 §7,
//! Weber 2011 ch. 5).
//!
//! Input: the scanned cloud P (with the `feature` labels of a detector when the result
//! is reconstructed sharply). The NURBS patch is described by the parameters (a tube:
//! [`Patch::Tube`], placed relative to the cloud's bounding box) and evaluated with
//! `truck-geometry`. The five steps of §5.4.2:
//!
//! 1. sample the patch from its start boundary (`u = 0`, the tube's outer rim) along
//!    parameter lines `v_j` (3-D spacing d_avg along the boundary), stepping `d_avg` in 3-D
//!    until a sample comes closer than the collar height `t` to P; bisection puts the
//!    line's border point α exactly at distance `t` (the rest of the line is cut off);
//! 2. densify the border A in the parameter domain to spacing `d_avg / border_density`;
//! 3. remove X: the scan points within the collar width `w` of a border point, and those
//!    swept by spheres of radius `w` moved from α_0 to every other α_j (the footprint);
//! 4. the scan-side border B: the nearest remaining scan point of each α, densified by
//!    straight-line interpolation;
//! 5. the collar C: segments from each α to its `collar_k` nearest points of B, each
//!    oversampled `collar_oversample` times per spacing, then thinned in a seeded
//!    random order to the radius `thin_radius · d_avg`.
//!
//! Output: G = (P ∖ X) ∪ S ∪ C with an [`ORIGIN_CHANNEL`] tag per point, reconstructed by
//! `mls-sharp` (collar points never features and always projected smoothly, §5.4.3),
//! `mls`, or left unprojected. Five scalar channels ([`CHART_CHANNELS`]) give every
//! output point's place around the tube, for the collar metrics.

use glam::DVec3;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use reconbench_geom::method::{
    BLEND_CHART_CHANNELS, Describe, Diagnostic, Diagnostics, FEATURE_CHANNEL, Filter, Filtered,
    MethodError, ORIGIN_CHANNEL, ORIGIN_COLLAR, ORIGIN_NURBS, ORIGIN_SCAN, ParamDoc, RunCtx, Unit,
};
use reconbench_geom::spatial::{PointIndex, mean_spacing};
use reconbench_geom::{Channel, PointCloud};
use reconbench_synth::shapes::blend_shapes::TubePlacement;
use serde::{Deserialize, Serialize};
use truck_geometry::prelude::{BSplineSurface, KnotVec, NurbsSurface, Vector4};

use crate::mls::{MlsParams, PolyDegree, Scratch, project_or_keep, setup};
use crate::mls_sharp::{MlsSharp, MlsSharpParams};
use crate::{Mls, mls};

/// The chart channels the output carries (see [`BLEND_CHART_CHANNELS`]).
pub const CHART_CHANNELS: [&str; 5] = BLEND_CHART_CHANNELS;

/// The designed surface the filter blends in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Patch {
    /// A circular tube (the thesis's test patch, seed 002 §2.6): degree 1 along the axis
    /// (`u`, 0 at the outer rim), the 7-point degree-2 rational circle around it (`v`).
    #[default]
    Tube,
    /// A NURBS patch read from `patch_file` ([`read_patch`]; absolute coordinates). The
    /// tube placement parameters still give the axis the chart channels are measured
    /// around.
    File,
}

/// How the blended set is reconstructed (step 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reconstruct {
    /// `mls-sharp` with the input's feature labels (collar and NURBS points are no
    /// features; collar points are projected smoothly). Needs a detector before it.
    #[default]
    Sharp,
    /// `mls` on the whole set.
    Smooth,
    /// The blended set as built, unprojected, without normals.
    None,
}

/// Parameters of `blend`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BlendParams {
    /// The patch type.
    pub patch: Patch,
    /// The patch file of `patch = "file"` ([`read_patch`]).
    pub patch_file: String,
    /// Where the tube axis meets the part, as fractions of the cloud's bounding box
    /// (`[0.5, 0.5, 1.0]` = centre of the top face).
    pub center_rel: [f64; 3],
    /// Tube axis, pointing away from the part towards the start boundary.
    pub axis: [f64; 3],
    /// Tube radius as a fraction of the bounding-box diagonal.
    pub radius_rel: f64,
    /// Tube length outside the part (from `center_rel` to the start rim), fraction of the
    /// diagonal.
    pub length_rel: f64,
    /// Tube length inside the part (never sampled; it only has to reach P), fraction of
    /// the diagonal.
    pub depth_rel: f64,
    /// The box `[min, max]` the placement is relative to; `None` (default): the scan's
    /// bounding box. Give the part's box (a blend shape's scanned part's box) to place the tube
    /// exactly where the ground truth has it even when noise grows the scan's box.
    pub frame: Option<[[f64; 3]; 2]>,
    /// Collar height t in mean spacings (ASSUMPTION W-41: 3).
    pub t_rel: f64,
    /// Collar width w (sphere radius) in mean spacings (ASSUMPTION W-41: 5; must exceed
    /// `t_rel`; ASSUMPTION W-42: a radius, not a diameter).
    pub w_rel: f64,
    /// Border densification: border spacing d_avg / this (thesis: 2).
    pub border_density: f64,
    /// Scan-side border points each collar segment fan starts from (thesis: 3).
    pub collar_k: usize,
    /// Collar oversampling per spacing before thinning (ASSUMPTION W-43: 4).
    pub collar_oversample: f64,
    /// Thinning radius in mean spacings (thesis: 1).
    pub thin_radius_rel: f64,
    /// Step 8: `sharp`, `smooth` or `none`.
    pub reconstruct: Reconstruct,
    /// MLS neighbourhood size of the reconstruction (thesis: 20).
    pub k: usize,
    /// MLS width h in mean spacings of the blended set (ASSUMPTION W-33: 0.8).
    pub h_rel: f64,
}

impl Default for BlendParams {
    fn default() -> Self {
        let m = MlsParams::default();
        Self {
            patch: Patch::Tube,
            patch_file: String::new(),
            center_rel: [0.5, 0.5, 1.0],
            axis: [0.0, 0.0, 1.0],
            radius_rel: 0.12,
            length_rel: 0.3,
            depth_rel: 0.1,
            frame: None,
            t_rel: 3.0,
            w_rel: 5.0,
            border_density: 2.0,
            collar_k: 3,
            collar_oversample: 4.0,
            thin_radius_rel: 1.0,
            reconstruct: Reconstruct::Sharp,
            k: m.k,
            h_rel: m.h_rel,
        }
    }
}

impl BlendParams {
    fn mls(&self) -> MlsParams {
        MlsParams {
            k: self.k,
            h_rel: self.h_rel,
            plane_iters: MlsParams::default().plane_iters,
            degree: PolyDegree::Quadratic,
        }
    }
}

/// The `blend` filter.
#[derive(Debug, Clone, Default)]
pub struct Blend {
    /// Parameters.
    pub params: BlendParams,
}

fn bad<T>(name: &str, message: String) -> Result<T, MethodError> {
    Err(MethodError::InvalidParameter {
        name: name.into(),
        message,
    })
}

fn positive(name: &str, v: f64) -> Result<(), MethodError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        bad(name, format!("must be a finite number > 0, got {v}"))
    }
}

impl Describe for Blend {
    const NAME: &'static str = "blend";
    const SOURCE: &'static str = "seed 002 §7 (Weber 2011 ch. 5)";
    const SUMMARY: &'static str = "blends a NURBS tube into the scan: cut back by collar height t and width w, oversampled-then-thinned collar, sharp MLS of the union";
    type Params = BlendParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "patch",
            Unit::Choice,
            "designed surface: tube, or file (a NURBS patch read from patch_file)",
        ),
        ParamDoc::new(
            "patch_file",
            Unit::Choice,
            "path of the NURBS patch of patch = \"file\" (text format: docs/methods/blend.md)",
        ),
        ParamDoc::new(
            "center_rel",
            Unit::Fraction,
            "where the tube axis meets the part, fractions of the bounding box per axis",
        ),
        ParamDoc::new(
            "axis",
            Unit::Choice,
            "tube axis direction, away from the part (any nonzero length)",
        ),
        ParamDoc::new(
            "radius_rel",
            Unit::Fraction,
            "tube radius, fraction of the bounding-box diagonal",
        ),
        ParamDoc::new(
            "length_rel",
            Unit::Fraction,
            "tube length outside the part, fraction of the diagonal",
        ),
        ParamDoc::new(
            "depth_rel",
            Unit::Fraction,
            "tube length inside the part (never sampled), fraction of the diagonal",
        ),
        ParamDoc::new(
            "frame",
            Unit::None,
            "box [[min x, y, z], [max x, y, z]] (cloud units) the placement is relative to; default: the scan's bounding box",
        ),
        ParamDoc::new(
            "t_rel",
            Unit::Spacing,
            "collar height t (ASSUMPTION W-41: 3 spacings)",
        ),
        ParamDoc::new(
            "w_rel",
            Unit::Spacing,
            "collar width w, sphere radius, > t (ASSUMPTION W-41/W-42: 5 spacings)",
        ),
        ParamDoc::new(
            "border_density",
            Unit::Count,
            "border spacing is d_avg / this (thesis: 2)",
        ),
        ParamDoc::new(
            "collar_k",
            Unit::Count,
            "scan-side border points joined to each NURBS border point (thesis: 3)",
        ),
        ParamDoc::new(
            "collar_oversample",
            Unit::Count,
            "collar points per spacing before thinning (ASSUMPTION W-43: 4)",
        ),
        ParamDoc::new(
            "thin_radius_rel",
            Unit::Spacing,
            "collar thinning radius (thesis: 1 spacing)",
        ),
        ParamDoc::new(
            "reconstruct",
            Unit::Choice,
            "sharp (mls-sharp, needs feature labels), smooth (mls) or none",
        ),
        ParamDoc::new("k", Unit::Count, "MLS neighbourhood size (thesis: 20)"),
        ParamDoc::new(
            "h_rel",
            Unit::Spacing,
            "MLS width h in mean spacings (ASSUMPTION W-33: 0.8)",
        ),
    ];

    fn from_params(params: BlendParams) -> Result<Self, MethodError> {
        let p = &params;
        for (i, c) in p.center_rel.iter().enumerate() {
            if !c.is_finite() {
                return bad("center_rel", format!("component {i} is not finite ({c})"));
            }
        }
        let a = DVec3::from_array(p.axis);
        if !(a.is_finite() && a.length() > 0.0) {
            return bad(
                "axis",
                format!("must be a finite nonzero vector, got {:?}", p.axis),
            );
        }
        positive("radius_rel", p.radius_rel)?;
        positive("length_rel", p.length_rel)?;
        if !(p.depth_rel.is_finite() && p.depth_rel >= 0.0) {
            return bad(
                "depth_rel",
                format!("must be finite and >= 0, got {}", p.depth_rel),
            );
        }
        if let Some([lo, hi]) = p.frame {
            let ok = lo.iter().chain(&hi).all(|x| x.is_finite())
                && (0..3).all(|i| hi[i] >= lo[i])
                && (0..3).any(|i| hi[i] > lo[i]);
            if !ok {
                return bad(
                    "frame",
                    format!(
                        "must be [[min x, y, z], [max x, y, z]] with finite max >= min and a positive diagonal, got {:?}",
                        [lo, hi]
                    ),
                );
            }
        }
        positive("t_rel", p.t_rel)?;
        positive("w_rel", p.w_rel)?;
        if p.w_rel <= p.t_rel {
            // The border points sit at distance t from P: spheres of radius w <= t
            // remove nothing (seed 002 §7.1).
            return bad(
                "w_rel",
                format!(
                    "collar width w = {} must exceed the height t = {} (spheres of radius w <= t around the border reach no scan point)",
                    p.w_rel, p.t_rel
                ),
            );
        }
        if !(p.border_density.is_finite() && p.border_density >= 1.0) {
            return bad(
                "border_density",
                format!("must be finite and >= 1, got {}", p.border_density),
            );
        }
        if p.collar_k == 0 {
            return bad("collar_k", "must be at least 1".into());
        }
        if !(p.collar_oversample.is_finite() && p.collar_oversample >= 1.0) {
            return bad(
                "collar_oversample",
                format!("must be finite and >= 1, got {}", p.collar_oversample),
            );
        }
        positive("thin_radius_rel", p.thin_radius_rel)?;
        p.mls().validate()?;
        match p.patch {
            Patch::File => {
                read_patch(&p.patch_file)?;
            }
            Patch::Tube if !p.patch_file.is_empty() => {
                return bad("patch_file", "is only read with patch = \"file\"".into());
            }
            Patch::Tube => {}
        }
        Ok(Self { params })
    }
}

/// The tube placed in the cloud's frame, as a NURBS surface and its analytic frame.
#[derive(Debug, Clone)]
pub struct Tube {
    /// The NURBS surface: `u` from the outer rim (0) to the inner end (1), `v` around.
    pub surface: NurbsSurface<Vector4>,
    /// Where the axis meets the part.
    pub foot: DVec3,
    /// Unit axis, away from the part.
    pub axis: DVec3,
    /// Radius.
    pub radius: f64,
    /// The placement (shared with the ground-truth blend shapes of `reconbench-synth`).
    pub placement: TubePlacement,
    /// Whether the patch is closed in `v` (the start boundary is a loop: the tube).
    pub closed_v: bool,
}

impl Tube {
    /// The tube of `p` for a cloud with bounding box `[min, max]` (or `p.frame` when
    /// given): [`TubePlacement::new`], the rule the blend shapes use.
    pub fn new(p: &BlendParams, min: DVec3, max: DVec3) -> Result<Self, MethodError> {
        let (min, max) = match p.frame {
            Some([lo, hi]) => (DVec3::from_array(lo), DVec3::from_array(hi)),
            None => (min, max),
        };
        let pl = TubePlacement::new(
            p.center_rel,
            p.axis,
            p.radius_rel,
            p.length_rel,
            p.depth_rel,
            min,
            max,
        )
        .map_err(|(name, message)| MethodError::InvalidParameter {
            name: name.into(),
            message,
        })?;
        let (foot, axis, radius) = (pl.foot, pl.axis, pl.radius);
        let (outer, inner) = (pl.outer_centre(), pl.inner_centre());
        let (e1, e2) = (pl.e1, pl.e2);
        // seed 002 §2.6: the 7-point circle (degree 2, knots 0,0,0,1/3,1/3,2/3,2/3,1,1,1),
        // control points at angles 0, 60, ..., 360 deg, radius rho (w = 1) and 2 rho
        // (w = 1/2); a degree-1 axis direction (knots 0,0,1,1).
        let ring = |centre: DVec3| -> Vec<Vector4> {
            (0..7)
                .map(|k| {
                    let ang = (60.0 * k as f64).to_radians();
                    let (r, w) = if k % 2 == 0 {
                        (radius, 1.0)
                    } else {
                        (2.0 * radius, 0.5)
                    };
                    let q = centre + (e1 * ang.cos() + e2 * ang.sin()) * r;
                    Vector4::new(q.x * w, q.y * w, q.z * w, w)
                })
                .collect()
        };
        let third = 1.0 / 3.0;
        let kv = KnotVec::from(vec![
            0.0,
            0.0,
            0.0,
            third,
            third,
            2.0 * third,
            2.0 * third,
            1.0,
            1.0,
            1.0,
        ]);
        let ku = KnotVec::from(vec![0.0, 0.0, 1.0, 1.0]);
        let surface = match p.patch {
            Patch::Tube => NurbsSurface::new(
                BSplineSurface::try_new((ku, kv), vec![ring(outer), ring(inner)])
                    .map_err(|e| MethodError::Failed(format!("blend: NURBS tube: {e}")))?,
            ),
            Patch::File => read_patch(&p.patch_file)?,
        };
        let mut tube = Self {
            surface,
            foot,
            axis,
            radius,
            placement: pl,
            closed_v: true,
        };
        // Closed in v when the boundaries v = 0 and v = 1 coincide (to 1e-9 of the
        // patch's size), checked at 9 values of u.
        let size = (tube.eval(0.0, 0.0) - tube.eval(1.0, 0.5)).length()
            + (tube.eval(0.0, 0.0) - tube.eval(0.0, 0.5)).length();
        tube.closed_v = (0..=8).all(|i| {
            let u = i as f64 / 8.0;
            (tube.eval(u, 0.0) - tube.eval(u, 1.0)).length() <= 1e-9 * size
        });
        Ok(tube)
    }

    /// The control points (Cartesian) and weights of the patch, `u`-major, with its
    /// degrees and knot vectors: what [`write_patch`] writes.
    pub fn control_net(&self) -> PatchNet {
        let b = self.surface.non_rationalized();
        let (ku, kv) = b.knot_vecs();
        let cps = b.control_points();
        PatchNet {
            degrees: [b.udegree(), b.vdegree()],
            knots: [ku.to_vec(), kv.to_vec()],
            points: cps
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|q| [q.x / q.w, q.y / q.w, q.z / q.w, q.w])
                        .collect()
                })
                .collect(),
        }
    }

    /// The surface point at `(u, v)`.
    pub fn eval(&self, u: f64, v: f64) -> DVec3 {
        let p = self.surface.subs(u, v);
        DVec3::new(p.x, p.y, p.z)
    }

    /// `|dx/du|` at `(u, v)`.
    fn du_len(&self, u: f64, v: f64) -> f64 {
        let d = self.surface.uder(u, v);
        (d.x * d.x + d.y * d.y + d.z * d.z).sqrt()
    }

    /// Angle around the axis and distance from it.
    pub fn polar(&self, p: DVec3) -> (f64, f64) {
        self.placement.polar(p)
    }
}

/// A NURBS patch as its parts: degrees (u, v), knot vectors (u, v), control points
/// `[x, y, z, weight]` (Cartesian, not multiplied by the weight), `points[i][j]` the
/// `i`-th along `u` and `j`-th along `v`.
#[derive(Debug, Clone, PartialEq)]
pub struct PatchNet {
    /// Degrees in u and v.
    pub degrees: [usize; 2],
    /// Knot vectors in u and v.
    pub knots: [Vec<f64>; 2],
    /// Control points with their weights.
    pub points: Vec<Vec<[f64; 4]>>,
}

/// Writes `net` in the patch file format [`read_patch`] reads.
pub fn write_patch(net: &PatchNet) -> String {
    let join = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(" ");
    let mut out = String::from("# reconbench NURBS patch\n");
    out += &format!("degrees {} {}\n", net.degrees[0], net.degrees[1]);
    out += &format!("knots_u {}\n", join(&net.knots[0]));
    out += &format!("knots_v {}\n", join(&net.knots[1]));
    let nv = net.points.first().map_or(0, Vec::len);
    out += &format!("size {} {nv}\n", net.points.len());
    for row in &net.points {
        for q in row {
            out += &format!("{}\n", join(q));
        }
    }
    out
}

/// Reads a NURBS patch file: text, `#` starts a comment, blank lines ignored; the lines
/// `degrees DU DV`, `knots_u K...`, `knots_v K...`, `size NU NV` in this order, then
/// NU x NV lines `x y z w` (u-major: all of v for the first u first; Cartesian
/// coordinates, weight w > 0). Knot vectors are non-decreasing with `NU + DU + 1` and
/// `NV + DV + 1` entries and are normalised to [0, 1] by truck-geometry. Errors name the
/// file and line.
pub fn read_patch(path: &str) -> Result<NurbsSurface<Vector4>, MethodError> {
    let bad = |line: usize, m: String| {
        MethodError::InvalidInput(format!("blend: patch file '{path}', line {line}: {m}"))
    };
    if path.is_empty() {
        return Err(MethodError::InvalidParameter {
            name: "patch_file".into(),
            message: "patch = \"file\" needs a patch_file".into(),
        });
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| MethodError::InvalidInput(format!("blend: patch file '{path}': {e}")))?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());
    let mut keyed = |key: &str| -> Result<(usize, Vec<f64>), MethodError> {
        let Some((n, l)) = lines.next() else {
            return Err(bad(text.lines().count(), format!("missing '{key}' line")));
        };
        let mut it = l.split_whitespace();
        if it.next() != Some(key) {
            return Err(bad(n, format!("expected '{key} ...', got '{l}'")));
        }
        let v = it
            .map(|w| {
                w.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(n, format!("'{w}' is not a finite number")))
            })
            .collect::<Result<Vec<f64>, _>>()?;
        Ok((n, v))
    };
    let count = |n: usize, v: &[f64], what: &str| -> Result<[usize; 2], MethodError> {
        match v {
            [a, b]
                if a.fract() == 0.0
                    && b.fract() == 0.0
                    && *a >= 1.0
                    && *b >= 1.0
                    && *a < 1e6
                    && *b < 1e6 =>
            {
                Ok([*a as usize, *b as usize])
            }
            _ => Err(bad(
                n,
                format!("{what}: expected two integers >= 1, got {v:?}"),
            )),
        }
    };
    let (nd, d) = keyed("degrees")?;
    let degrees = count(nd, &d, "degrees")?;
    let (nku, ku) = keyed("knots_u")?;
    let (nkv, kv) = keyed("knots_v")?;
    let (ns, sz) = keyed("size")?;
    let size = count(ns, &sz, "size")?;
    for (n, k, deg, m, name) in [
        (nku, &ku, degrees[0], size[0], "knots_u"),
        (nkv, &kv, degrees[1], size[1], "knots_v"),
    ] {
        if k.len() != m + deg + 1 {
            return Err(bad(
                n,
                format!(
                    "{name} has {} knots; {m} control points of degree {deg} need {}",
                    k.len(),
                    m + deg + 1
                ),
            ));
        }
        if k.windows(2).any(|w| w[1] < w[0]) || k[0] == k[k.len() - 1] {
            return Err(bad(
                n,
                format!("{name} must be non-decreasing and not constant"),
            ));
        }
    }
    let mut rows = Vec::with_capacity(size[0]);
    for _ in 0..size[0] {
        let mut row = Vec::with_capacity(size[1]);
        for _ in 0..size[1] {
            let Some((n, l)) = lines.next() else {
                return Err(bad(
                    text.lines().count(),
                    format!("expected {} control points", size[0] * size[1]),
                ));
            };
            let v: Vec<f64> = l
                .split_whitespace()
                .map(|w| w.parse::<f64>().unwrap_or(f64::NAN))
                .collect();
            match v[..] {
                [x, y, z, w] if [x, y, z, w].iter().all(|c| c.is_finite()) && w > 0.0 => {
                    row.push(Vector4::new(x * w, y * w, z * w, w));
                }
                _ => {
                    return Err(bad(
                        n,
                        format!("expected 'x y z w' (finite, w > 0), got '{l}'"),
                    ));
                }
            }
        }
        rows.push(row);
    }
    if let Some((n, l)) = lines.next() {
        return Err(bad(
            n,
            format!("unexpected content after the control points: '{l}'"),
        ));
    }
    let b = BSplineSurface::try_new((KnotVec::from(ku), KnotVec::from(kv)), rows)
        .map_err(|e| bad(ns, format!("not a valid B-spline surface: {e}")))?;
    Ok(NurbsSurface::new(b))
}

/// Where every output point of [`blend_points`] came from, and what was built.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Blended {
    /// The kept scan points' input indices (P ∖ X), in input order.
    pub kept: Vec<u32>,
    /// The removed scan points (X), sorted.
    pub removed: Vec<u32>,
    /// NURBS samples S (the densified border A included).
    pub nurbs: Vec<DVec3>,
    /// Border points A after densification (also the last `border.len()` entries of
    /// `nurbs`).
    pub border: Vec<DVec3>,
    /// Scan-side border B after densification.
    pub scan_border: Vec<DVec3>,
    /// Collar points before thinning.
    pub collar_raw: usize,
    /// Collar points C after thinning.
    pub collar: Vec<DVec3>,
    /// Parameter lines that never came within t of the cloud.
    pub open_lines: usize,
}

/// One parameter line of step 1: its samples and its border point `(α, u*)`.
type Line = (Vec<DVec3>, Option<(DVec3, f64)>);

/// Step 1 on the line `v`: samples at 3-D step `d` from `u = 0` until one comes within
/// `t` of the cloud; the border point is refined by bisection to distance `t`.
fn sample_line(tube: &Tube, index: &PointIndex, v: f64, d: f64, t: f64) -> Line {
    let dist = |x: DVec3| index.nearest(x).map_or(f64::INFINITY, |n| n.dist2.sqrt());
    let mut out = Vec::new();
    let mut u = 0.0;
    let mut last_ok: Option<f64> = None;
    // Bounded: at most one sample per d along a line of finite length.
    for _ in 0..10_000_000 {
        let x = tube.eval(u, v);
        if dist(x) < t {
            let Some(mut lo) = last_ok else {
                return (out, Some((x, u)));
            };
            // ASSUMPTION W-44: bisection between the last sample farther than t and this
            // one, to |dist - t| <= 1e-3 d_avg (at most 60 halvings).
            let mut hi = u;
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let dm = dist(tube.eval(mid, v));
                if (dm - t).abs() <= 1e-3 * d {
                    lo = mid;
                    break;
                }
                if dm < t {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return (out, Some((tube.eval(lo, v), lo)));
        }
        out.push(x);
        last_ok = Some(u);
        let l = tube.du_len(u, v);
        if l.is_nan() || l <= 0.0 {
            break;
        }
        u += d / l;
        if u > 1.0 {
            break;
        }
    }
    (out, None)
}

/// Arc length of the start boundary `u = 0` (polyline of 1024 segments).
fn start_boundary_length(tube: &Tube) -> f64 {
    let n = 1024;
    (0..n)
        .map(|i| {
            let a = tube.eval(0.0, i as f64 / n as f64);
            let b = tube.eval(0.0, (i + 1) as f64 / n as f64);
            (b - a).length()
        })
        .sum()
}

/// Step 2: the points inserted between border points `(a, ua, va)` and `(b, ub, vb)` by
/// recursive parameter-domain midpoints until neighbours are at most `gap` apart.
fn densify_param(
    tube: &Tube,
    a: (DVec3, f64, f64),
    b: (DVec3, f64, f64),
    gap: f64,
    depth: u32,
    out: &mut Vec<(DVec3, f64, f64)>,
) {
    if (a.0 - b.0).length() <= gap || depth >= 24 {
        return;
    }
    let (um, vm) = (0.5 * (a.1 + b.1), 0.5 * (a.2 + b.2));
    let m = (tube.eval(um, vm), um, vm);
    densify_param(tube, a, m, gap, depth + 1, out);
    out.push(m);
    densify_param(tube, m, b, gap, depth + 1, out);
}

/// Steps 1-6 of seed 002 §7.2 on the scan `points` with mean spacing `d`: the blended set
/// before reconstruction. `seed` drives the thinning order. Errors when the patch never
/// comes within `t` of the scan.
pub fn blend_points(
    points: &[DVec3],
    tube: &Tube,
    p: &BlendParams,
    d: f64,
    seed: u64,
) -> Result<Blended, MethodError> {
    let (t, w) = (p.t_rel * d, p.w_rel * d);
    let index = PointIndex::new(points)?;
    // Step 1. ASSUMPTION W-45: v-lines at 3-D spacing d along the start boundary, the
    // boundary closed in v (the tube).
    // A closed patch (the tube) has lines at v = j / m, an open one at v = j / (m - 1)
    // (both boundaries), and no line pair across v = 1.
    let m = ((start_boundary_length(tube) / d).ceil() as usize).max(3);
    let v_of = |j: usize| {
        if tube.closed_v {
            j as f64 / m as f64
        } else {
            j as f64 / (m - 1) as f64
        }
    };
    let lines: Vec<Line> = (0..m)
        .into_par_iter()
        .map(|j| sample_line(tube, &index, v_of(j), d, t))
        .collect();
    let open_lines = lines.iter().filter(|l| l.1.is_none()).count();
    let mut nurbs: Vec<DVec3> = lines.iter().flat_map(|l| l.0.iter().copied()).collect();
    // Step 2: densify A between consecutive lines (cyclic) that both have a border point.
    let gap = d / p.border_density;
    let mut border: Vec<(DVec3, f64, f64)> = Vec::new();
    for j in 0..m {
        let Some((a, ua)) = lines[j].1 else { continue };
        let va = v_of(j);
        border.push((a, ua, va));
        if !tube.closed_v && j + 1 == m {
            break;
        }
        let jn = (j + 1) % m;
        if let Some((b, ub)) = lines[jn].1 {
            // The last pair closes the loop: v runs on to 1.
            let vb = if jn == 0 { 1.0 } else { v_of(jn) };
            densify_param(tube, (a, ua, va), (b, ub, vb), gap, 0, &mut border);
        }
    }
    if border.is_empty() {
        return Err(MethodError::InvalidInput(format!(
            "blend: the tube never comes within t = {t:.3e} of the {} scan points (check center_rel, axis, depth_rel)",
            points.len()
        )));
    }
    let alpha: Vec<DVec3> = border.iter().map(|b| b.0).collect();
    nurbs.extend_from_slice(&alpha);
    // Step 3a/b: spheres of radius w at every α, and swept from α_0 to every α_j
    // (ASSUMPTION W-46: α_0 = the first border point, step w / 2).
    let a0 = alpha[0];
    let hits: Vec<Vec<u32>> = alpha
        .par_iter()
        .map(|&a| {
            let mut v: Vec<u32> = index
                .radius(a, w)
                .map(|r| r.iter().map(|n| n.index).collect())
                .unwrap_or_default();
            let len = (a - a0).length();
            let steps = (len / (0.5 * w)).ceil() as usize;
            for s in 1..steps {
                let c = a0 + (a - a0) * (s as f64 / steps as f64);
                if let Ok(r) = index.radius(c, w) {
                    v.extend(r.iter().map(|n| n.index));
                }
            }
            v
        })
        .collect();
    let mut is_removed = vec![false; points.len()];
    for h in hits.iter().flatten() {
        is_removed[*h as usize] = true;
    }
    let removed: Vec<u32> = (0..points.len() as u32)
        .filter(|&i| is_removed[i as usize])
        .collect();
    let kept: Vec<u32> = (0..points.len() as u32)
        .filter(|&i| !is_removed[i as usize])
        .collect();
    if kept.is_empty() {
        return Err(MethodError::InvalidInput(
            "blend: the cut-back removed every scan point (w too large for the cloud)".into(),
        ));
    }
    let kept_pts: Vec<DVec3> = kept.iter().map(|&i| points[i as usize]).collect();
    let kept_index = PointIndex::new(&kept_pts)?;
    // Step 4: B = nearest kept point of each α, first occurrences in A order.
    let near = kept_index.nearest_batch(&alpha)?;
    let mut seen = vec![false; kept_pts.len()];
    let mut beta: Vec<DVec3> = Vec::new();
    for n in near {
        if !std::mem::replace(&mut seen[n.index as usize], true) {
            beta.push(kept_pts[n.index as usize]);
        }
    }
    // ASSUMPTION W-47: B densified like A, by straight segments (cyclically for a patch
    // closed in v).
    let mut scan_border = Vec::with_capacity(beta.len() * 2);
    for (i, &b0) in beta.iter().enumerate() {
        scan_border.push(b0);
        if beta.len() < 2 || (!tube.closed_v && i + 1 == beta.len()) {
            break;
        }
        let b1 = beta[(i + 1) % beta.len()];
        let n = ((b1 - b0).length() / gap).ceil() as usize;
        for s in 1..n {
            scan_border.push(b0 + (b1 - b0) * (s as f64 / n as f64));
        }
    }
    // Step 5: collar segments from every α to its collar_k nearest border points.
    let b_index = PointIndex::new(&scan_border)?;
    let fans = b_index.knn_batch(&alpha, p.collar_k)?;
    let raw: Vec<DVec3> = alpha
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, &a)| {
            let mut v = Vec::new();
            for &bj in fans.indices(i) {
                let b = scan_border[bj as usize];
                // ASSUMPTION W-43: ceil(oversample |b - a| / d) inner points per segment.
                let n = (p.collar_oversample * (b - a).length() / d).ceil() as usize;
                v.extend((1..=n).map(|s| a + (b - a) * (s as f64 / (n + 1) as f64)));
            }
            v
        })
        .collect();
    // Step 6: thinning in a seeded random order; a survivor deletes every other collar
    // point within the thinning radius.
    let collar = if raw.is_empty() {
        Vec::new()
    } else {
        let r = p.thin_radius_rel * d;
        let c_index = PointIndex::new(&raw)?;
        let mut order: Vec<usize> = (0..raw.len()).collect();
        order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed ^ 0xb1e4d));
        let mut alive = vec![true; raw.len()];
        for &c in &order {
            if !alive[c] {
                continue;
            }
            for nb in c_index.radius(raw[c], r)? {
                if nb.index as usize != c {
                    alive[nb.index as usize] = false;
                }
            }
        }
        (0..raw.len())
            .filter(|&i| alive[i])
            .map(|i| raw[i])
            .collect()
    };
    Ok(Blended {
        kept,
        removed,
        nurbs,
        border: alpha,
        scan_border,
        collar_raw: raw.len(),
        collar,
        open_lines,
    })
}

/// Reads the feature labels of `cloud`, if any (nonzero = feature).
fn feature_flags(cloud: &PointCloud) -> Option<Vec<i64>> {
    match cloud.channel(FEATURE_CHANNEL) {
        Some(Channel::Label(v)) => Some(v.clone()),
        Some(Channel::Scalar(v)) => Some(v.iter().map(|&x| i64::from(x != 0.0)).collect()),
        None => None,
    }
}

impl Filter for Blend {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        let p = &self.params;
        if cloud.len() < 3 {
            return Err(MethodError::InvalidInput(format!(
                "blend needs a scan of at least 3 points, got {}",
                cloud.len()
            )));
        }
        let features = feature_flags(cloud);
        if p.reconstruct == Reconstruct::Sharp && features.is_none() {
            return Err(MethodError::InvalidInput(format!(
                "blend with reconstruct = \"sharp\" needs feature labels in the '{FEATURE_CHANNEL}' channel: put a feature detector before it (steps = [\"gauss-map-adaptive\", \"blend\"]) or use reconstruct = \"smooth\""
            )));
        }
        let points = cloud.positions();
        let d = ctx
            .phase("spacing", || mean_spacing(points, 1))
            .map_err(|e| MethodError::InvalidInput(format!("blend: spacing of the scan: {e}")))?;
        let bb = cloud.aabb();
        let tube = Tube::new(p, bb.min, bb.max)?;
        ctx.checkpoint()?;
        let b = ctx.phase("blend", || blend_points(points, &tube, p, d, ctx.seed))?;
        ctx.checkpoint()?;
        // Step 7: G = P' ∪ S ∪ C with origin tags.
        let (ns, nn, nc) = (b.kept.len(), b.nurbs.len(), b.collar.len());
        let mut pos: Vec<DVec3> = b.kept.iter().map(|&i| points[i as usize]).collect();
        pos.extend_from_slice(&b.nurbs);
        pos.extend_from_slice(&b.collar);
        let mut origin = vec![ORIGIN_SCAN; ns];
        origin.extend(std::iter::repeat_n(ORIGIN_NURBS, nn));
        origin.extend(std::iter::repeat_n(ORIGIN_COLLAR, nc));
        let mut g = PointCloud::new(pos)?;
        g.set_channel(ORIGIN_CHANNEL, Channel::Label(origin))?;
        if let Some(f) = &features {
            // Collar points are never features (§6.5 blending exception); the tube is
            // smooth.
            let mut lab: Vec<i64> = b.kept.iter().map(|&i| f[i as usize]).collect();
            lab.resize(ns + nn + nc, 0);
            g.set_channel(FEATURE_CHANNEL, Channel::Label(lab))?;
        }
        // Step 8.
        let mut out = match p.reconstruct {
            Reconstruct::None => Filtered {
                cloud: g,
                source: None,
                diagnostics: Diagnostics::new(),
            },
            Reconstruct::Smooth => Mls { params: p.mls() }.filter(&g, ctx)?,
            Reconstruct::Sharp => {
                let sharp = MlsSharp::from_params(MlsSharpParams {
                    k: p.k,
                    h_rel: p.h_rel,
                    line_channels: false,
                    ..MlsSharpParams::default()
                })?;
                let mut f = sharp.filter(&g, ctx)?;
                smooth_collar(&g, &mut f.cloud, p, ns + nn)?;
                f
            }
        };
        out.source = None;
        ctx.checkpoint()?;
        let chart = chart_channels(out.cloud.positions(), &tube, &index_of(points)?, d);
        for (name, v) in CHART_CHANNELS.iter().zip(chart) {
            out.cloud.set_channel(*name, Channel::Scalar(v))?;
        }
        let dg = &mut out.diagnostics;
        let num = |x: usize| Diagnostic::Number(x as f64);
        dg.insert("blend_spacing".into(), Diagnostic::Number(d));
        dg.insert("blend_removed".into(), num(b.removed.len()));
        dg.insert("blend_scan_kept".into(), num(ns));
        dg.insert("blend_nurbs".into(), num(nn));
        dg.insert("blend_border".into(), num(b.border.len()));
        dg.insert("blend_scan_border".into(), num(b.scan_border.len()));
        dg.insert("blend_collar_raw".into(), num(b.collar_raw));
        dg.insert("blend_collar".into(), num(nc));
        dg.insert("blend_open_lines".into(), num(b.open_lines));
        Ok(out)
    }
}

fn index_of(points: &[DVec3]) -> Result<PointIndex, MethodError> {
    Ok(PointIndex::new(points)?)
}

/// Replaces the projections of the collar points (indices from `first_collar` on) in
/// `out` by their smooth MLS projection over the unedited neighbourhood in `g` (seed
/// 002 §5.4.3: collar points are always reconstructed smoothly).
fn smooth_collar(
    g: &PointCloud,
    out: &mut PointCloud,
    p: &BlendParams,
    first_collar: usize,
) -> Result<(), MethodError> {
    let n = g.len();
    if first_collar >= n {
        return Ok(());
    }
    let s = setup(g, &p.mls())?;
    let gp = g.positions();
    let index = PointIndex::new(gp)?;
    let knn = index.knn_batch(&gp[first_collar..], p.k)?;
    let proj: Vec<mls::Projected> = (first_collar..n)
        .into_par_iter()
        .map_init(Scratch::default, |sc, i| {
            sc.nbrs.clear();
            sc.nbrs.extend(
                knn.indices(i - first_collar)
                    .iter()
                    .map(|&j| gp[j as usize]),
            );
            project_or_keep(gp[i], &sc.nbrs, &s.cfg, DVec3::ZERO, &mut sc.w)
        })
        .collect();
    let mut pos = out.positions().to_vec();
    let mut nor = out
        .normals()
        .map(<[DVec3]>::to_vec)
        .unwrap_or_else(|| vec![DVec3::ZERO; n]);
    for (o, pr) in proj.iter().enumerate() {
        pos[first_collar + o] = pr.point;
        nor[first_collar + o] = pr.normal;
    }
    let mut c = std::mem::take(out).with_positions(pos)?;
    c.set_normals(Some(nor))?;
    *out = c;
    Ok(())
}

/// The [`CHART_CHANNELS`] of `pos` around `tube`, heights measured to the scan `index`.
fn chart_channels(pos: &[DVec3], tube: &Tube, index: &PointIndex, d: f64) -> [Vec<f64>; 5] {
    let rows: Vec<[f64; 5]> = pos
        .par_iter()
        .map(|&x| {
            let (theta, r) = tube.polar(x);
            let h = index.nearest(x).map_or(0.0, |n| n.dist2.sqrt());
            let axial = (x - tube.foot).dot(tube.axis);
            [theta, r / d, (r - tube.radius) / d, h / d, axial / d]
        })
        .collect();
    std::array::from_fn(|c| rows.iter().map(|r| r[c]).collect())
}
