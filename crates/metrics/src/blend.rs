//! Metrics of a blended point set (seed 002 §7, experiment E18): how uniform the collar
//! between the scan and the NURBS samples is, how smoothly its normals turn, how large
//! the largest hole of the blend region is, and how many points each step contributed or
//! removed. The cloud must carry the origin tags ([`ORIGIN_CHANNEL`]) and, for the gap,
//! the chart channels ([`BLEND_CHART_CHANNELS`]) of the `blend` filter. Formulas:
//! docs/METRICS.md, "Blend collar".

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::method::{
    BLEND_CHART_CHANNELS, ORIGIN_CHANNEL, ORIGIN_COLLAR, ORIGIN_NURBS, ORIGIN_SCAN,
};
use reconbench_geom::{Channel, PointCloud, PointIndex};
use reconbench_synth::Shape;
use serde::{Deserialize, Serialize};

use crate::error::{MetricsError, Result, check_positive};
use crate::filter_eval::MaxMean;
use crate::normals::unoriented_angle_deg;
use crate::report::{Entries, Report, put};

/// Options of the blend metrics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlendOptions {
    /// Half-width of the charted blend region in spacings, on either side of the
    /// junction (the profile coordinate, see [`eval_blend`]).
    pub band_sp: f64,
    /// Probe spacing of the gap search, in spacings.
    pub probe_sp: f64,
    /// Neighbours of each collar point whose normals it is compared with.
    pub normal_k: usize,
    /// Extent of the blend region whose normals are compared with the truth, in
    /// spacings from the junction (see [`eval_blend_truth`]).
    pub region_sp: f64,
}

impl Default for BlendOptions {
    fn default() -> Self {
        Self {
            band_sp: 8.0,
            probe_sp: 0.25,
            normal_k: 6,
            region_sp: 4.0,
        }
    }
}

/// The blend metrics of one cloud.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BlendEval {
    /// Scan points kept.
    pub scan: usize,
    /// NURBS samples.
    pub nurbs: usize,
    /// Collar points.
    pub collar: usize,
    /// Input scan points removed (input size minus kept scan points), when the input
    /// size is known.
    pub removed: Option<usize>,
    /// Coefficient of variation (std / mean) of the collar points' nearest-neighbour
    /// distances in the whole set (NaN with fewer than 2 collar points).
    pub collar_nn_cv: f64,
    /// Mean over collar points of the mean unoriented angle (degrees) between its normal
    /// and those of its `normal_k` nearest points (NaN without normals).
    pub collar_normal_var_deg: f64,
    /// Width (diameter, in spacings) of the largest empty disc of the charted blend
    /// region (NaN without chart channels).
    pub gap_sp: f64,
}

fn labels(cloud: &PointCloud) -> Option<Vec<i64>> {
    match cloud.channel(ORIGIN_CHANNEL)? {
        Channel::Label(v) => Some(v.clone()),
        Channel::Scalar(v) => Some(v.iter().map(|&x| x as i64).collect()),
    }
}

fn scalar(cloud: &PointCloud, name: &str) -> Option<Vec<f64>> {
    let c = cloud.channel(name)?;
    Some((0..c.len()).map(|i| c.get_f64(i)).collect())
}

/// The blend metrics of `cloud`, or `None` when it has no origin tags. `n_input` is the
/// size of the scan the blend started from (for the removed count).
///
/// Gap: every point is charted as `(theta, Y)`: the angle around the tube axis and the
/// arc length Y along the profile tube -> collar -> scan (offset = distance from the axis
/// minus the radius, height = distance to the nearest input point, in spacings). The
/// collar is charted as the segment from the tube at height H (its highest point) to
/// the scan at offset S (its outermost point): a NURBS point has
/// `Y = H - height`, a collar point its position along the segment, `Y = lambda L` with
/// `L = hypot(H, S)`, a scan point `Y = L + offset - S - height` (without collar
/// points H = S = 0). Arc lengths around the axis are `theta (rho + max(Y, 0))`. Scan points inside the
/// tube (offset < -0.5) are left out. Probes on a grid of step `probe_sp` over all
/// angles measure their distance to the nearest charted point
/// (angles wrap, distances in the probe's tangent frame: angle difference times its arc
/// radius) up to 5 spacings, over `|Y| <= band_sp` where both NURBS and scan points
/// reach; the gap is twice the largest such distance (so at most 10).
/// A uniform sample at spacing 1 gives about 1.2-1.4; a missing band of width W gives
/// at least min(W, 10).
pub fn eval_blend(
    cloud: &PointCloud,
    n_input: Option<usize>,
    opts: &BlendOptions,
) -> Result<Option<BlendEval>> {
    check_positive("band_sp", opts.band_sp)?;
    check_positive("probe_sp", opts.probe_sp)?;
    let Some(tag) = labels(cloud) else {
        return Ok(None);
    };
    let count = |v: i64| tag.iter().filter(|&&t| t == v).count();
    let mut ev = BlendEval {
        scan: count(ORIGIN_SCAN),
        nurbs: count(ORIGIN_NURBS),
        collar: count(ORIGIN_COLLAR),
        removed: n_input.map(|n| n.saturating_sub(count(ORIGIN_SCAN))),
        collar_nn_cv: f64::NAN,
        collar_normal_var_deg: f64::NAN,
        gap_sp: f64::NAN,
    };
    if cloud.len() < 2 {
        return Ok(Some(ev));
    }
    let pos = cloud.positions();
    let index = PointIndex::new(pos)?;
    let collar: Vec<usize> = (0..pos.len())
        .filter(|&i| tag[i] == ORIGIN_COLLAR)
        .collect();
    let k = opts.normal_k.max(1) + 1;
    let rows: Vec<(f64, f64)> = collar
        .par_iter()
        .map(|&i| {
            let nb = index.knn(pos[i], k).unwrap_or_default();
            let others: Vec<u32> = nb
                .iter()
                .filter(|n| n.index as usize != i)
                .map(|n| n.index)
                .collect();
            let nn = nb
                .iter()
                .find(|n| n.index as usize != i)
                .map_or(f64::NAN, |n| n.dist2.sqrt());
            let var = cloud.normals().map_or(f64::NAN, |ns| {
                let a: Vec<f64> = others
                    .iter()
                    .filter_map(|&j| {
                        let (p, q) = (ns[i], ns[j as usize]);
                        (p != DVec3::ZERO && q != DVec3::ZERO)
                            .then(|| unoriented_angle_deg(p, q))
                            .flatten()
                    })
                    .collect();
                if a.is_empty() {
                    f64::NAN
                } else {
                    a.iter().sum::<f64>() / a.len() as f64
                }
            });
            (nn, var)
        })
        .collect();
    let nn: Vec<f64> = rows.iter().map(|r| r.0).filter(|x| x.is_finite()).collect();
    if nn.len() >= 2 {
        let m = nn.iter().sum::<f64>() / nn.len() as f64;
        let var = nn.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / nn.len() as f64;
        ev.collar_nn_cv = if m > 0.0 { var.sqrt() / m } else { f64::NAN };
    }
    let nv: Vec<f64> = rows.iter().map(|r| r.1).filter(|x| x.is_finite()).collect();
    if !nv.is_empty() {
        ev.collar_normal_var_deg = nv.iter().sum::<f64>() / nv.len() as f64;
    }
    ev.gap_sp = chart_gap(cloud, &tag, opts)?;
    Ok(Some(ev))
}

/// The gap of [`eval_blend`] (NaN without chart channels or charted points).
fn chart_gap(cloud: &PointCloud, tag: &[i64], opts: &BlendOptions) -> Result<f64> {
    let ch: Vec<Vec<f64>> = match BLEND_CHART_CHANNELS
        .iter()
        .map(|n| scalar(cloud, n))
        .collect::<Option<Vec<_>>>()
    {
        Some(c) => c,
        None => return Ok(f64::NAN),
    };
    let (theta, radial, offset, height) = (&ch[0], &ch[1], &ch[2], &ch[3]);
    let n = cloud.len();
    let rho = (0..n)
        .map(|i| radial[i] - offset[i])
        .find(|r| r.is_finite())
        .unwrap_or(0.0)
        .max(0.0);
    if rho.is_nan() || rho <= 0.0 {
        return Err(MetricsError::InvalidInput(
            "blend chart: the tube radius (radial - offset) is not positive".into(),
        ));
    }
    let band = opts.band_sp;
    let tau = std::f64::consts::TAU;
    // Profile radius of the arc length around the axis (the face grows with Y).
    let arc_r = |y: f64| rho + y.max(0.0);
    // Chart points binned by angle (bins of one spacing at the tube) and by Y.
    let nt = ((tau * rho).ceil() as usize).max(8);
    let dt = tau / nt as f64;
    let (y0, ny) = (-band - 2.0, (2.0 * band + 4.0).ceil() as usize + 1);
    let bin_of = |t: f64| ((t.rem_euclid(tau) / dt) as usize).min(nt - 1);
    // The collar's profile segment from the tube at height H to the scan at offset S
    // (the highest and the outermost collar point).
    let (mut h, mut s) = (0.0f64, 0.0f64);
    for i in 0..n {
        if tag[i] == ORIGIN_COLLAR {
            h = h.max(height[i]);
            s = s.max(offset[i]);
        }
    }
    let l = h.hypot(s);
    let mut bins: Vec<Vec<(f64, f64)>> = vec![Vec::new(); nt * ny];
    let mut any = false;
    // The charted extent: probes stay between the NURBS samples' lowest and the scan's
    // highest profile coordinate (the tube may end inside the band).
    let (mut y_lo, mut y_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..n {
        if tag[i] == ORIGIN_SCAN && offset[i] < -0.5 || !theta[i].is_finite() {
            continue;
        }
        // Arc length along the profile tube -> collar -> scan, 0 where the collar meets
        // the tube.
        let y = match tag[i] {
            ORIGIN_NURBS => h - height[i],
            ORIGIN_COLLAR if l > 0.0 => {
                let lam = ((offset[i] * s - (height[i] - h) * h) / (l * l)).clamp(0.0, 1.0);
                lam * l
            }
            _ => l + offset[i] - s - height[i],
        };
        if y.is_nan() || y.abs() > band + 2.0 {
            continue;
        }
        match tag[i] {
            ORIGIN_NURBS => y_lo = y_lo.min(y),
            ORIGIN_SCAN => y_hi = y_hi.max(y),
            _ => {}
        }
        let t = theta[i].rem_euclid(tau);
        let by = (((y - y0).floor()) as usize).min(ny - 1);
        bins[by * nt + bin_of(t)].push((t, y));
        any = true;
    }
    if !any {
        return Ok(f64::NAN);
    }
    // Probes: rows of step probe_sp in Y, probe_sp apart along each row's arc. Each
    // probe's distance to the charted points is taken in its own tangent frame
    // (angle differences times its arc radius), up to SEARCH spacings.
    const SEARCH: f64 = 5.0;
    let step = opts.probe_sp;
    let (y_lo, y_hi) = (y_lo.max(-band), y_hi.min(band));
    if y_lo.is_nan() || y_hi.is_nan() || y_lo >= y_hi {
        return Ok(f64::NAN);
    }
    let rows = ((y_hi - y_lo) / step).floor() as usize;
    let probes: Vec<(f64, f64)> = (0..=rows)
        .flat_map(|j| {
            let y = y_lo + j as f64 * step;
            let m = ((tau * arc_r(y) / step).ceil() as usize).max(8);
            (0..m).map(move |i| (tau * i as f64 / m as f64, y))
        })
        .collect();
    let r = probes
        .par_iter()
        .map(|&(tp, yp)| {
            let rr = arc_r(yp);
            let half = ((SEARCH / rr / dt).ceil() as i64 + 1).min(nt as i64 / 2 + 1);
            let bt = (tp / dt) as i64;
            let lo = ((yp - SEARCH - y0).floor().max(0.0)) as usize;
            let hi = ((yp + SEARCH - y0).floor().max(0.0) as usize).min(ny - 1);
            let mut best = SEARCH * SEARCH;
            for by in lo..=hi {
                for k in -half..=half {
                    let b = (bt + k).rem_euclid(nt as i64) as usize;
                    for &(t, y) in &bins[by * nt + b] {
                        let mut a = (t - tp).abs();
                        if a > std::f64::consts::PI {
                            a = tau - a;
                        }
                        let dx = a * rr;
                        let dy = y - yp;
                        best = best.min(dx * dx + dy * dy);
                    }
                }
            }
            best.sqrt()
        })
        .reduce(|| 0.0, f64::max);
    Ok(2.0 * r)
}

impl Report for BlendEval {
    fn entries(&self) -> Entries {
        let fin = |x: f64| x.is_finite().then_some(x);
        let mut e = Entries::new();
        put(&mut e, "blend_scan_points", self.scan);
        put(&mut e, "blend_nurbs_points", self.nurbs);
        put(&mut e, "blend_collar_points", self.collar);
        if let Some(r) = self.removed {
            put(&mut e, "blend_removed_points", r);
        }
        put(&mut e, "blend_collar_nn_cv", fin(self.collar_nn_cv));
        put(
            &mut e,
            "blend_collar_normal_var_deg",
            fin(self.collar_normal_var_deg),
        );
        put(&mut e, "blend_gap_sp", fin(self.gap_sp));
        e
    }
}

/// A blended set against the true blended surface (a blend shape such as `box-tube`):
/// distances per origin, in spacings, and the normal error in the blend region.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BlendTruthEval {
    /// Distances of the scan points to the truth (spacings).
    pub scan: MaxMean,
    /// Distances of the NURBS samples (spacings).
    pub nurbs: MaxMean,
    /// Distances of the collar points (spacings).
    pub collar: MaxMean,
    /// Unoriented angle (degrees) between the output normal and the true normal at the
    /// closest point, over the blend region (`None` without normals or chart channels).
    pub region_normal: Option<MaxMean>,
}

/// [`BlendTruthEval`] of `cloud` against `truth`, lengths in `spacing` (the input scan's
/// mean spacing), or `None` when the cloud has no origin tags. The blend region: every
/// collar point, the NURBS samples at most `region_sp` spacings above the scan (chart
/// height) and the scan points at most `region_sp` spacings out from the tube wall
/// (chart offset in `[-0.5, region_sp]`).
pub fn eval_blend_truth(
    cloud: &PointCloud,
    truth: &dyn Shape,
    spacing: f64,
    opts: &BlendOptions,
) -> Result<Option<BlendTruthEval>> {
    check_positive("spacing", spacing)?;
    check_positive("region_sp", opts.region_sp)?;
    let Some(tag) = labels(cloud) else {
        return Ok(None);
    };
    let pos = cloud.positions();
    let hits: Vec<(f64, DVec3)> = pos
        .par_iter()
        .map(|&p| {
            let c = truth.closest_point(p);
            (c.distance / spacing, c.normal)
        })
        .collect();
    let of = |o: i64| {
        let v: Vec<f64> = (0..pos.len())
            .filter(|&i| tag[i] == o)
            .map(|i| hits[i].0)
            .collect();
        MaxMean::of(&v)
    };
    let mut ev = BlendTruthEval {
        scan: of(ORIGIN_SCAN),
        nurbs: of(ORIGIN_NURBS),
        collar: of(ORIGIN_COLLAR),
        region_normal: None,
    };
    let offset = scalar(cloud, BLEND_CHART_CHANNELS[2]);
    let height = scalar(cloud, BLEND_CHART_CHANNELS[3]);
    if let (Some(ns), Some(off), Some(hgt)) = (cloud.normals(), offset, height) {
        let r = opts.region_sp;
        let angles: Vec<f64> = (0..pos.len())
            .filter(|&i| match tag[i] {
                ORIGIN_COLLAR => true,
                ORIGIN_NURBS => hgt[i] <= r,
                _ => off[i] >= -0.5 && off[i] <= r,
            })
            .filter_map(|i| {
                (ns[i] != DVec3::ZERO)
                    .then(|| unoriented_angle_deg(ns[i], hits[i].1))
                    .flatten()
            })
            .collect();
        ev.region_normal = Some(MaxMean::of(&angles));
    }
    Ok(Some(ev))
}

impl Report for BlendTruthEval {
    fn entries(&self) -> Entries {
        let fin = |x: f64| x.is_finite().then_some(x);
        let mut e = Entries::new();
        for (name, m) in [
            ("scan", &self.scan),
            ("nurbs", &self.nurbs),
            ("collar", &self.collar),
        ] {
            if m.count > 0 {
                put(&mut e, format!("blend_{name}_dist_max_sp"), m.max);
                put(&mut e, format!("blend_{name}_dist_mean_sp"), fin(m.mean));
            }
        }
        if let Some(m) = &self.region_normal
            && m.count > 0
        {
            put(&mut e, "blend_region_normal_mean_deg", fin(m.mean));
            put(&mut e, "blend_region_normal_max_deg", m.max);
            put(&mut e, "blend_region_points", m.count);
        }
        e
    }
}
