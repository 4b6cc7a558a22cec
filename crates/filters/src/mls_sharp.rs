//! `mls-sharp`: sharp MLS by neighbourhood modification (seed 002 §6, thesis ch. 4).
//!
//! Input: a cloud whose `feature` channel labels the detected feature points (a
//! pipeline attaches it: `steps = ["gauss-map-adaptive", "mls-sharp"]`). Per query
//! point r (every input point, in input order):
//!
//! 1. N = the `k` nearest points of r (r included), F_N = its feature points;
//! 2. with at least `min_line_features` of them, the dominant line: the feature f*
//!    closest to r and its precomputed *connected features* (the features of f*'s
//!    neighbourhood on the same edge, found once per feature by a modified Gauss-map
//!    clustering, §6.3), through which a cubic Bézier B is fitted (§6.4);
//! 3. side test: a neighbour x stays when the vectors from r and from x to their closest
//!    points on B make an angle of at most `side_angle_deg` (eq. 4.5), i.e. x lies on
//!    r's sheet; the others are dropped and replaced one for one by samples on B;
//! 4. the projection MLS of `mls` with the edited neighbourhood.
//!
//! Neighbourhoods without enough feature evidence get the plain projection, so the
//! result equals `mls` away from features. Output: projected points with their plane
//! normals, and (with `line_channels`) the control points of the line each query used,
//! as scalar channels for the feature-line metric of Tables 3-4.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_features::AverageLinkage;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, FEATURE_CHANNEL, Filter, Filtered, MethodError, ParamDoc,
    RunCtx, Unit,
};
use reconbench_geom::spatial::{KnnHit, PointIndex, knn_self_map};
use reconbench_geom::{Channel, PointCloud};
use serde::{Deserialize, Serialize};

use crate::mls::bezier::{BezierInner, CubicBezier, bezier_from_features};
use crate::mls::{
    FLAG_SHARP, MLS_PARAM_DOCS, MlsConfig, MlsParams, PolyDegree, Projected, Scratch, finish,
    project_or_keep, setup,
};

/// Names of the scalar channels holding the line control points of each query
/// (`b0x, b0y, b0z, b1x, ...`; all zero where no line was used).
pub const LINE_CHANNELS: [&str; 12] = [
    "mls_line_b0x",
    "mls_line_b0y",
    "mls_line_b0z",
    "mls_line_b1x",
    "mls_line_b1y",
    "mls_line_b1z",
    "mls_line_b2x",
    "mls_line_b2y",
    "mls_line_b2z",
    "mls_line_b3x",
    "mls_line_b3y",
    "mls_line_b3z",
];

/// Label channel: 1 where the query's neighbourhood was edited along a line, else 0.
pub const LINE_FLAG_CHANNEL: &str = "mls_line";

/// Which features form the query's line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConnMode {
    /// The nearest feature and its connected features (seed 002 §6.3; default).
    #[default]
    Connected,
    /// Every feature of the neighbourhood (the thesis's single-line case; ablation).
    None,
}

/// Parameters of `mls-sharp`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MlsSharpParams {
    /// Neighbourhood size, the query included (thesis: 20, k >= 16; 40 at 2 % noise).
    pub k: usize,
    /// `h` in mean spacings (ASSUMPTION W-33).
    pub h_rel: f64,
    /// Plane fixed-point iterations (ASSUMPTION W-30).
    pub plane_iters: usize,
    /// Height polynomial degree (ASSUMPTION W-32).
    pub degree: PolyDegree,
    /// Fewest features for a line (thesis: 4, a cubic Bézier's control points).
    pub min_line_features: usize,
    /// Side-test angle (thesis: 45 degrees).
    pub side_angle_deg: f64,
    /// Points closer than this many mean spacings to the line count as on it
    /// (ASSUMPTION W-36: 0.1).
    pub on_line_eps_rel: f64,
    /// Line membership: `connected` (default) or `none` (all features of N).
    pub conn_mode: ConnMode,
    /// Neighbourhood of the connected-feature test, 0 = `k` (ASSUMPTION W-37).
    pub k_conn: usize,
    /// Clustering cut of the connected-feature test (ASSUMPTION W-37: 0.3 rad).
    pub sigma_conn_rad: f64,
    /// Smallest counted cluster as a fraction of the normals (ASSUMPTION W-37: 0.15).
    pub conn_min_frac: f64,
    /// Inner control points (ASSUMPTION W-34: `chord-thirds`; `random`).
    pub bezier_inner: BezierInner,
    /// Extend the line tangentially beyond its end points in the side test
    /// (ASSUMPTION W-38: false).
    pub extend_line: bool,
    /// Attach the line control points as channels for the feature-line metric.
    pub line_channels: bool,
}

impl Default for MlsSharpParams {
    fn default() -> Self {
        let m = MlsParams::default();
        Self {
            k: m.k,
            h_rel: m.h_rel,
            plane_iters: m.plane_iters,
            degree: m.degree,
            min_line_features: 4,
            side_angle_deg: 45.0,
            on_line_eps_rel: 0.1,
            conn_mode: ConnMode::Connected,
            k_conn: 0,
            sigma_conn_rad: 0.3,
            conn_min_frac: 0.15,
            bezier_inner: BezierInner::ChordThirds,
            extend_line: false,
            line_channels: true,
        }
    }
}

impl MlsSharpParams {
    fn mls(&self) -> MlsParams {
        MlsParams {
            k: self.k,
            h_rel: self.h_rel,
            plane_iters: self.plane_iters,
            degree: self.degree,
        }
    }
}

/// The `mls-sharp` filter.
#[derive(Debug, Clone, Default)]
pub struct MlsSharp {
    /// Parameters.
    pub params: MlsSharpParams,
}

impl Describe for MlsSharp {
    const NAME: &'static str = "mls-sharp";
    const SOURCE: &'static str = "seed 002 §6 (Weber 2011 ch. 4)";
    const SUMMARY: &'static str =
        "sharp MLS: neighbourhoods edited along a local Bezier feature line, then projection MLS";
    type Params = MlsSharpParams;
    const PARAMS: &'static [ParamDoc] = &[
        MLS_PARAM_DOCS[0],
        MLS_PARAM_DOCS[1],
        MLS_PARAM_DOCS[2],
        MLS_PARAM_DOCS[3],
        ParamDoc::new(
            "min_line_features",
            Unit::Count,
            "fewest features in N for a feature line (thesis: 4)",
        ),
        ParamDoc::new(
            "side_angle_deg",
            Unit::Deg,
            "neighbours whose line vector is more than this off the query's are dropped (thesis: 45)",
        ),
        ParamDoc::new(
            "on_line_eps_rel",
            Unit::Spacing,
            "closer than this to the line = on it (ASSUMPTION W-36: 0.1)",
        ),
        ParamDoc::new(
            "conn_mode",
            Unit::Choice,
            "line features: connected (nearest feature + its connected features) or none (all of N)",
        ),
        ParamDoc::new(
            "k_conn",
            Unit::Count,
            "neighbours of the connected-feature test, 0 = k (ASSUMPTION W-37)",
        ),
        ParamDoc::new(
            "sigma_conn_rad",
            Unit::Rad,
            "average-linkage cut of the connected-feature test (ASSUMPTION W-37: 0.3)",
        ),
        ParamDoc::new(
            "conn_min_frac",
            Unit::Fraction,
            "smallest counted cluster of that test, of the normals (ASSUMPTION W-37: 0.15)",
        ),
        ParamDoc::new(
            "bezier_inner",
            Unit::Choice,
            "inner control points: chord-thirds (ASSUMPTION W-34) or random (seeded)",
        ),
        ParamDoc::new(
            "extend_line",
            Unit::Flag,
            "extend the line tangentially in the side test (ASSUMPTION W-38: false)",
        ),
        ParamDoc::new(
            "line_channels",
            Unit::Flag,
            "attach each query's line control points as channels (feature-line metric)",
        ),
    ];

    fn from_params(params: MlsSharpParams) -> Result<Self, MethodError> {
        params.mls().validate()?;
        let bad = |name: &str, message: String| {
            Err(MethodError::InvalidParameter {
                name: name.into(),
                message,
            })
        };
        if params.min_line_features < 4 {
            return bad(
                "min_line_features",
                format!(
                    "a cubic Bezier needs at least 4 points, got {}",
                    params.min_line_features
                ),
            );
        }
        if !(params.side_angle_deg > 0.0 && params.side_angle_deg < 180.0) {
            return bad(
                "side_angle_deg",
                format!("must be in (0, 180), got {}", params.side_angle_deg),
            );
        }
        if !(params.on_line_eps_rel.is_finite() && params.on_line_eps_rel >= 0.0) {
            return bad(
                "on_line_eps_rel",
                format!("must be finite and >= 0, got {}", params.on_line_eps_rel),
            );
        }
        if !(params.sigma_conn_rad > 0.0 && params.sigma_conn_rad <= std::f64::consts::FRAC_PI_2) {
            return bad(
                "sigma_conn_rad",
                format!("must be in (0, pi/2], got {}", params.sigma_conn_rad),
            );
        }
        if !(params.conn_min_frac >= 0.0 && params.conn_min_frac <= 1.0) {
            return bad(
                "conn_min_frac",
                format!("must be in [0, 1], got {}", params.conn_min_frac),
            );
        }
        Ok(Self { params })
    }
}

/// The connected features of every feature point (seed 002 §6.3) in CSR form: the list
/// of feature `slot` is `list[offsets[slot]..offsets[slot + 1]]` (point indices).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConnectedFeatures {
    /// Row offsets, one per feature plus one.
    pub offsets: Vec<u32>,
    /// Connected point indices.
    pub list: Vec<u32>,
}

impl ConnectedFeatures {
    /// Connected features of feature slot `s`.
    pub fn of(&self, s: usize) -> &[u32] {
        &self.list[self.offsets[s] as usize..self.offsets[s + 1] as usize]
    }
}

/// The connected-feature map of seed 002 §6.3: for each feature f1 and each other
/// feature f2 among its `k_conn` nearest other points, the unit normals of the
/// triangles (f1, f2, x) over the non-feature neighbours x are clustered with average
/// linkage at `sigma`; f2 is on f1's edge when exactly two clusters of at least
/// `max(2, ceil(min_frac L))` normals remain (the two sheets through the edge). Runs in
/// parallel; each feature's list is in its neighbours' (distance, index) order.
pub fn connected_features(
    points: &[DVec3],
    features: &[u32],
    is_feature: &[bool],
    k_conn: usize,
    sigma: f64,
    min_frac: f64,
) -> Result<ConnectedFeatures, MethodError> {
    if features.is_empty() {
        return Ok(ConnectedFeatures {
            offsets: vec![0],
            list: Vec::new(),
        });
    }
    let index = PointIndex::new(points)?;
    let queries: Vec<DVec3> = features.iter().map(|&f| points[f as usize]).collect();
    let table = index.knn_batch(&queries, k_conn + 1)?;
    let rows: Vec<Vec<u32>> = features
        .par_iter()
        .enumerate()
        .map_init(
            || (AverageLinkage::new(), Vec::<DVec3>::new()),
            |(linkage, lines), (row, &f1)| {
                let nb = table.indices(row);
                // The k_conn nearest other points (f1 itself, or one extra point, out).
                let others = || nb.iter().copied().filter(move |&j| j != f1).take(k_conn);
                let p1 = points[f1 as usize];
                let mut conn = Vec::new();
                for f2 in others().filter(|&j| is_feature[j as usize]) {
                    let u = points[f2 as usize] - p1;
                    lines.clear();
                    for x in others().filter(|&j| !is_feature[j as usize]) {
                        let v = points[x as usize] - p1;
                        let n = u.cross(v);
                        let l = n.length();
                        // Degenerate triangles (collinear or coincident) give no normal.
                        if l > 1e-9 * u.length() * v.length() && l > 0.0 {
                            lines.push(n / l);
                        }
                    }
                    if lines.len() < 3 {
                        continue;
                    }
                    let min_size = ((min_frac * lines.len() as f64).ceil() as usize).max(2);
                    if linkage.count_big(lines, sigma, min_size) == 2 {
                        conn.push(f2);
                    }
                }
                conn
            },
        )
        .collect();
    let mut offsets = Vec::with_capacity(rows.len() + 1);
    let mut list = Vec::new();
    offsets.push(0u32);
    for r in rows {
        list.extend_from_slice(&r);
        offsets.push(list.len() as u32);
    }
    Ok(ConnectedFeatures { offsets, list })
}

/// Everything a sharp query needs besides its neighbours.
#[derive(Debug)]
struct SharpCtx<'a> {
    points: &'a [DVec3],
    hints: Option<&'a [DVec3]>,
    is_feature: &'a [bool],
    slot: &'a [u32],
    conn: &'a ConnectedFeatures,
    cfg: MlsConfig,
    min_features: usize,
    cos_side: f64,
    eps: f64,
    mode: ConnMode,
    inner: BezierInner,
    extend: bool,
    seed: u64,
}

/// Scratch of one rayon job.
#[derive(Debug, Default)]
struct SharpScratch {
    base: Scratch,
    line: Vec<(u32, DVec3)>,
}

/// Output of one query: the projection, the line used and how many neighbours it
/// replaced.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SharpOut {
    p: Projected,
    line: Option<CubicBezier>,
    dropped: u8,
}

impl SharpCtx<'_> {
    /// The feature line of the query `r` with neighbours `hits`, or `None` for the
    /// plain projection.
    fn line(&self, hits: &[KnnHit], i: usize, line: &mut Vec<(u32, DVec3)>) -> Option<CubicBezier> {
        let n_feat = hits
            .iter()
            .filter(|h| self.is_feature[h.index as usize])
            .count();
        if n_feat < self.min_features {
            return None;
        }
        line.clear();
        match self.mode {
            ConnMode::Connected => {
                // Dominant line only (corners, §4.3.6): the nearest feature and its
                // connected features, as stored (ASSUMPTION W-39).
                let fstar = hits.iter().find(|h| self.is_feature[h.index as usize])?;
                line.push((fstar.index, fstar.point));
                let s = self.slot[fstar.index as usize] as usize;
                line.extend(
                    self.conn
                        .of(s)
                        .iter()
                        .map(|&j| (j, self.points[j as usize])),
                );
            }
            ConnMode::None => line.extend(
                hits.iter()
                    .filter(|h| self.is_feature[h.index as usize])
                    .map(|h| (h.index, h.point)),
            ),
        }
        if line.len() < self.min_features {
            return None;
        }
        bezier_from_features(line, self.inner, self.seed ^ i as u64)
    }

    fn query(&self, sc: &mut SharpScratch, i: usize, hits: &[KnnHit]) -> SharpOut {
        let r = self.points[i];
        let hint = self.hints.map_or(DVec3::ZERO, |n| n[i]);
        let plain = |sc: &mut SharpScratch| {
            sc.base.nbrs.clear();
            sc.base.nbrs.extend(hits.iter().map(|h| h.point));
            SharpOut {
                p: project_or_keep(r, &sc.base.nbrs, &self.cfg, hint, &mut sc.base.w),
                line: None,
                dropped: 0,
            }
        };
        let Some(b) = self.line(hits, i, &mut sc.line) else {
            return plain(sc);
        };
        let foot = |x: DVec3| b.closest_point(x, self.extend) - x;
        let mut vr = foot(r);
        if vr.length() < self.eps {
            // ASSUMPTION W-36: a query on the line takes the side of the nearest
            // non-feature neighbour.
            match hits
                .iter()
                .find(|h| !self.is_feature[h.index as usize])
                .map(|h| foot(h.point))
            {
                Some(v) if v.length() >= self.eps => vr = v,
                _ => return plain(sc),
            }
        }
        let vr_len = vr.length();
        sc.base.nbrs.clear();
        let mut dropped = 0usize;
        for h in hits {
            // ASSUMPTION W-39: the line's own features are on both sides.
            if sc.line.iter().any(|e| e.0 == h.index) {
                sc.base.nbrs.push(h.point);
                continue;
            }
            let vx = foot(h.point);
            let l = vx.length();
            // On the line, or on r's side (eq. 4.5 with the normalised dot product).
            if l < self.eps || vr.dot(vx) >= self.cos_side * vr_len * l {
                sc.base.nbrs.push(h.point);
            } else {
                dropped += 1;
            }
        }
        // ASSUMPTION W-40: the dropped neighbours are replaced by samples on the line at
        // t = j / (m + 1), j = 1..m (end points excluded).
        for j in 1..=dropped {
            sc.base.nbrs.push(b.eval(j as f64 / (dropped + 1) as f64));
        }
        let mut p = project_or_keep(r, &sc.base.nbrs, &self.cfg, hint, &mut sc.base.w);
        p.flags |= FLAG_SHARP;
        SharpOut {
            p,
            line: Some(b),
            dropped: dropped.min(255) as u8,
        }
    }
}

/// Reads the feature labels of `cloud` (any nonzero label is a feature).
fn feature_flags(cloud: &PointCloud) -> Result<Vec<bool>, MethodError> {
    match cloud.channel(FEATURE_CHANNEL) {
        Some(Channel::Label(v)) => Ok(v.iter().map(|&x| x != 0).collect()),
        Some(Channel::Scalar(v)) => Ok(v.iter().map(|&x| x != 0.0).collect()),
        None => Err(MethodError::InvalidInput(format!(
            "mls-sharp needs feature labels in the '{FEATURE_CHANNEL}' channel: put a feature \
             detector before it (steps = [\"gauss-map-adaptive\", \"mls-sharp\"])"
        ))),
    }
}

impl Filter for MlsSharp {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        let p = &self.params;
        let is_feature = feature_flags(cloud)?;
        let s = ctx.phase("spacing", || setup(cloud, &p.mls()))?;
        ctx.checkpoint()?;
        let points = cloud.positions();
        let features: Vec<u32> = (0..points.len() as u32)
            .filter(|&i| is_feature[i as usize])
            .collect();
        let mut slot = vec![u32::MAX; points.len()];
        for (s, &f) in features.iter().enumerate() {
            slot[f as usize] = s as u32;
        }
        let k_conn = if p.k_conn == 0 { p.k } else { p.k_conn };
        let conn = match p.conn_mode {
            ConnMode::Connected => ctx.phase("connected", || {
                connected_features(
                    points,
                    &features,
                    &is_feature,
                    k_conn,
                    p.sigma_conn_rad,
                    p.conn_min_frac,
                )
            })?,
            ConnMode::None => ConnectedFeatures {
                offsets: vec![0; features.len() + 1],
                list: Vec::new(),
            },
        };
        ctx.checkpoint()?;
        let sc = SharpCtx {
            points,
            hints: cloud.normals(),
            is_feature: &is_feature,
            slot: &slot,
            conn: &conn,
            cfg: s.cfg,
            min_features: p.min_line_features,
            cos_side: p.side_angle_deg.to_radians().cos(),
            eps: p.on_line_eps_rel * s.spacing,
            mode: p.conn_mode,
            inner: p.bezier_inner,
            extend: p.extend_line,
            seed: ctx.seed,
        };
        let out = ctx.phase("project", || {
            knn_self_map(
                points,
                p.k,
                false,
                SharpScratch::default,
                |scr: &mut SharpScratch, i: usize, hits: &[KnnHit]| sc.query(scr, i, hits),
            )
        })?;
        ctx.checkpoint()?;
        let mut diagnostics = Diagnostics::new();
        let n = out.len();
        diagnostics.insert("features".into(), Diagnostic::Number(features.len() as f64));
        diagnostics.insert(
            "connected_mean".into(),
            Diagnostic::Number(conn.list.len() as f64 / features.len().max(1) as f64),
        );
        let lines = out.iter().filter(|o| o.line.is_some()).count();
        diagnostics.insert("line_queries".into(), Diagnostic::Number(lines as f64));
        let dropped: u64 = out.iter().map(|o| o.dropped as u64).sum();
        diagnostics.insert("dropped".into(), Diagnostic::Number(dropped as f64));
        let channels = p.line_channels.then(|| {
            let mut ch = vec![vec![0.0; n]; 12];
            let mut flag = vec![0i64; n];
            for (i, o) in out.iter().enumerate() {
                if let Some(b) = o.line {
                    flag[i] = 1;
                    for (j, c) in b.ctrl.iter().enumerate() {
                        for a in 0..3 {
                            ch[3 * j + a][i] = c[a];
                        }
                    }
                }
            }
            (ch, flag)
        });
        let projected: Vec<Projected> = out.iter().map(|o| o.p).collect();
        let mut f = finish(cloud, projected, &s, &p.mls(), diagnostics)?;
        if let Some((ch, flag)) = channels {
            for (name, v) in LINE_CHANNELS.iter().zip(ch) {
                f.cloud.set_channel(*name, Channel::Scalar(v))?;
            }
            f.cloud
                .set_channel(LINE_FLAG_CHANNEL, Channel::Label(flag))?;
        }
        Ok(f)
    }
}
