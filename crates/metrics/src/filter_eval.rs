//! Metrics of a projecting filter (seed 002 ch. 4: `mls`, `mls-sharp`): where its output
//! points lie relative to the noisy input (the thesis's Table 5/6 error) and to the true
//! surface, how good their normals are near and away from the sharp features, and how
//! far the local feature lines it built are from the true feature curves (Tables 3-4).
//!
//! Lengths are reported twice: as fractions of the reference's bounding-box diagonal
//! (`_dist_*`) and in mean input spacings (`_sp`), the unit in which the thesis's
//! model-unit figures compare (its models have spacing 0.125). Formulas: docs/METRICS.md.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::{PointIndex, mean_spacing};
use reconbench_synth::{FeatureCurve, Shape};
use serde::{Deserialize, Serialize};

use crate::error::{MetricsError, Result};
use crate::features::{CurveSet, curve_counts};
use crate::normals::unoriented_angle_deg;
use crate::report::{Entries, Report, put};

/// Options of the filter metrics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FilterEvalOptions {
    /// A point is near a feature when its closest surface point is within this many
    /// mean input spacings of a true feature curve (2, seed 002 §10.3 E15).
    pub near_feature_spacings: f64,
    /// Curves count as features from this turning angle (degrees, as the feature
    /// metrics).
    pub feature_angle_deg: f64,
    /// Samples of each feature line (101, seed 002 §8.2.1).
    pub line_samples: usize,
}

impl Default for FilterEvalOptions {
    fn default() -> Self {
        Self {
            near_feature_spacings: 2.0,
            feature_angle_deg: 20.0,
            line_samples: 101,
        }
    }
}

/// Statistics of one set of nonnegative values.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MaxMean {
    /// Number of values.
    pub count: usize,
    /// Largest value (0 without values).
    pub max: f64,
    /// Mean value (NaN without values).
    pub mean: f64,
}

impl MaxMean {
    /// Of `v` (sequential sums: independent of the thread count).
    pub fn of(v: &[f64]) -> Self {
        Self {
            count: v.len(),
            max: v.iter().copied().fold(0.0, f64::max),
            mean: if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            },
        }
    }
}

/// Error of the local feature lines against the true curves (Tables 3-4): each line is
/// sampled at `line_samples` uniform parameters (end points included) and every
/// sample's distance to the nearest true feature curve taken; per line the max, min and
/// mean of those, then averaged over the lines (`*_mean`) and the largest per-line max.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LineError {
    /// Lines measured.
    pub lines: usize,
    /// Mean over lines of the per-line maximum.
    pub max_mean: f64,
    /// Mean over lines of the per-line minimum.
    pub min_mean: f64,
    /// Mean over lines of the per-line mean.
    pub avg_mean: f64,
    /// Median over lines of the per-line maximum.
    pub max_median: f64,
    /// Largest per-line maximum.
    pub max_worst: f64,
}

/// The control points of a cubic Bézier feature line.
pub type BezierLine = [DVec3; 4];

fn bezier(b: &BezierLine, t: f64) -> DVec3 {
    let s = 1.0 - t;
    s * s * s * b[0] + 3.0 * s * s * t * b[1] + 3.0 * s * t * t * b[2] + t * t * t * b[3]
}

/// [`LineError`] of `lines` against `curves` (absolute units), computed in parallel.
pub fn feature_line_error(lines: &[BezierLine], curves: &CurveSet, samples: usize) -> LineError {
    let samples = samples.max(2);
    let per: Vec<(f64, f64, f64)> = lines
        .par_iter()
        .map(|b| {
            let (mut mx, mut mn, mut sum) = (0.0f64, f64::INFINITY, 0.0);
            for j in 0..samples {
                let d = curves.distance(bezier(b, j as f64 / (samples - 1) as f64));
                mx = mx.max(d);
                mn = mn.min(d);
                sum += d;
            }
            (mx, mn, sum / samples as f64)
        })
        .collect();
    if per.is_empty() {
        return LineError::default();
    }
    let n = per.len() as f64;
    let mut maxes: Vec<f64> = per.iter().map(|p| p.0).collect();
    maxes.sort_by(f64::total_cmp);
    LineError {
        lines: per.len(),
        max_mean: per.iter().map(|p| p.0).sum::<f64>() / n,
        min_mean: per.iter().map(|p| p.1).sum::<f64>() / n,
        avg_mean: per.iter().map(|p| p.2).sum::<f64>() / n,
        max_median: maxes[maxes.len() / 2],
        max_worst: maxes[maxes.len() - 1],
    }
}

/// Result of [`eval_filter`]; absolute lengths (the row divides them).
#[derive(Debug, Clone, PartialEq)]
pub struct FilterEval {
    /// Reference bounding-box diagonal.
    pub diagonal: f64,
    /// Mean nearest-neighbour spacing of the filter's input.
    pub spacing: f64,
    /// Distance of each output point to its nearest input point (Table 5/6).
    pub to_input: MaxMean,
    /// Distance to the true surface (`None` without ground truth).
    pub to_surface: Option<MaxMean>,
    /// Normal angles (degrees, unoriented) of points near features.
    pub normal_near: Option<MaxMean>,
    /// Normal angles of points away from features.
    pub normal_away: Option<MaxMean>,
    /// Points whose closest surface point lies on a feature curve (normal undefined,
    /// left out of both normal statistics) or whose normal is zero.
    pub normal_skipped: usize,
    /// Error of the feature lines, all of them.
    pub lines: Option<LineError>,
    /// Error of the lines attributed to curved true curves (the Table 3 hole rim and
    /// fandisk edge cases); `None` when no curve is curved.
    pub lines_curved: Option<LineError>,
}

/// The true curves counted at `feature_angle_deg`, and for each whether it is curved
/// (a polyline with a vertex off its chord by more than `1e-9 diag`).
fn curved_curves(curves: &[FeatureCurve], angle: f64, diag: f64) -> Vec<(Vec<DVec3>, bool)> {
    curves
        .iter()
        .filter(|c| curve_counts(c, angle) && !c.is_corner && c.points.len() >= 2)
        .map(|c| {
            let (a, b) = (c.points[0], c.points[c.points.len() - 1]);
            let off = c.points.iter().any(|&p| {
                let ab = b - a;
                let l2 = ab.length_squared();
                let t = if l2 > 0.0 { (p - a).dot(ab) / l2 } else { 0.0 };
                (a + t * ab - p).length() > 1e-9 * diag
            });
            (c.points.clone(), off)
        })
        .collect()
}

/// Whether the nearest of `curves` to `p` is curved.
fn nearest_is_curved(curves: &[(Vec<DVec3>, bool)], p: DVec3) -> bool {
    let mut best = (f64::INFINITY, false);
    for (pts, curved) in curves {
        for w in pts.windows(2) {
            let (q, _) = reconbench_geom::spatial::closest_point_on_segment(p, w[0], w[1]);
            let d = (q - p).length_squared();
            if d < best.0 {
                best = (d, *curved);
            }
        }
    }
    best.1
}

/// Evaluates a projecting filter's `output` (with its `normals`, if any) against its
/// `input` cloud and, when given, the true `shape` with its feature `curves`; `lines`
/// are the feature lines the filter built (may be empty).
///
/// Errors: an empty output or input, fewer than 2 distinct input points, a normal count
/// that does not match.
pub fn eval_filter(
    output: &[DVec3],
    normals: Option<&[DVec3]>,
    input: &[DVec3],
    truth: Option<(&dyn Shape, &[FeatureCurve])>,
    lines: &[BezierLine],
    diagonal: f64,
    opts: &FilterEvalOptions,
) -> Result<FilterEval> {
    if output.is_empty() || input.is_empty() {
        return Err(MetricsError::InvalidInput(
            "filter metrics need a nonempty input and output".into(),
        ));
    }
    if let Some(n) = normals
        && n.len() != output.len()
    {
        return Err(MetricsError::InvalidInput(format!(
            "{} normals for {} output points",
            n.len(),
            output.len()
        )));
    }
    let spacing = mean_spacing(input, 1)?;
    let index = PointIndex::new(input)?;
    let near = index.nearest_batch(output)?;
    let to_input: Vec<f64> = near.iter().map(|h| h.dist2.sqrt()).collect();
    let mut ev = FilterEval {
        diagonal,
        spacing,
        to_input: MaxMean::of(&to_input),
        to_surface: None,
        normal_near: None,
        normal_away: None,
        normal_skipped: 0,
        lines: None,
        lines_curved: None,
    };
    let Some((shape, curves)) = truth else {
        return Ok(ev);
    };
    let set = CurveSet::new(curves, opts.feature_angle_deg);
    let near_r = opts.near_feature_spacings * spacing;
    let on_feature = 1e-9 * diagonal;
    // Per point: distance to the surface, normal angle (NaN = skipped), near flag.
    let per: Vec<(f64, f64, bool)> = output
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            let cp = shape.closest_point(p);
            let Some(n) = normals.map(|n| n[i]) else {
                return (cp.distance, f64::NAN, false);
            };
            let fd = set.distance_within(cp.point, near_r.max(on_feature) * 1.5);
            if fd <= on_feature || n.length_squared() == 0.0 {
                return (cp.distance, f64::NAN, false);
            }
            (
                cp.distance,
                unoriented_angle_deg(n, cp.normal).unwrap_or(f64::NAN),
                fd <= near_r,
            )
        })
        .collect();
    let d: Vec<f64> = per.iter().map(|x| x.0).collect();
    ev.to_surface = Some(MaxMean::of(&d));
    if normals.is_some() {
        let pick = |near: bool| -> Vec<f64> {
            per.iter()
                .filter(|x| !x.1.is_nan() && x.2 == near)
                .map(|x| x.1)
                .collect()
        };
        ev.normal_near = Some(MaxMean::of(&pick(true)));
        ev.normal_away = Some(MaxMean::of(&pick(false)));
        ev.normal_skipped = per.iter().filter(|x| x.1.is_nan()).count();
    }
    if !lines.is_empty() && set.n_segments() > 0 {
        ev.lines = Some(feature_line_error(lines, &set, opts.line_samples));
        let cc = curved_curves(curves, opts.feature_angle_deg, diagonal);
        if cc.iter().any(|c| c.1) {
            let curved: Vec<BezierLine> = lines
                .par_iter()
                .filter(|b| nearest_is_curved(&cc, b[0]) && nearest_is_curved(&cc, b[3]))
                .copied()
                .collect();
            ev.lines_curved = Some(feature_line_error(&curved, &set, opts.line_samples));
        }
    }
    Ok(ev)
}

impl Report for FilterEval {
    fn entries(&self) -> Entries {
        let (d, s) = (self.diagonal, self.spacing);
        let fin = |x: f64| x.is_finite().then_some(x);
        let mut e = Entries::new();
        put(&mut e, "filter_spacing_abs", s);
        put(&mut e, "input_dist_max", self.to_input.max / d);
        put(&mut e, "input_dist_mean", self.to_input.mean / d);
        put(&mut e, "input_dist_max_sp", self.to_input.max / s);
        put(&mut e, "input_dist_mean_sp", self.to_input.mean / s);
        if let Some(m) = self.to_surface {
            put(&mut e, "surface_dist_max", m.max / d);
            put(&mut e, "surface_dist_mean", fin(m.mean / d));
            put(&mut e, "surface_dist_max_sp", m.max / s);
            put(&mut e, "surface_dist_mean_sp", fin(m.mean / s));
        }
        if let Some(m) = self.normal_near {
            put(&mut e, "normal_near_mean_deg", fin(m.mean));
            put(&mut e, "normal_near_max_deg", m.max);
            put(&mut e, "normal_near_points", m.count);
        }
        if let Some(m) = self.normal_away {
            put(&mut e, "normal_away_mean_deg", fin(m.mean));
            put(&mut e, "normal_away_max_deg", m.max);
            put(&mut e, "normal_away_points", m.count);
            put(&mut e, "normal_skipped_points", self.normal_skipped);
        }
        for (prefix, l) in [("line", self.lines), ("line_curved", self.lines_curved)] {
            let Some(l) = l else { continue };
            put(&mut e, format!("{prefix}_count"), l.lines);
            if l.lines == 0 {
                continue;
            }
            put(&mut e, format!("{prefix}_err_max_sp"), l.max_mean / s);
            put(&mut e, format!("{prefix}_err_min_sp"), l.min_mean / s);
            put(&mut e, format!("{prefix}_err_avg_sp"), l.avg_mean / s);
            put(
                &mut e,
                format!("{prefix}_err_max_median_sp"),
                l.max_median / s,
            );
            put(
                &mut e,
                format!("{prefix}_err_max_worst_sp"),
                l.max_worst / s,
            );
            put(&mut e, format!("{prefix}_err_max"), l.max_mean / d);
            put(&mut e, format!("{prefix}_err_avg"), l.avg_mean / d);
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn segment_curve(a: DVec3, b: DVec3) -> FeatureCurve {
        FeatureCurve {
            points: vec![a, b],
            dihedral_deg: 90.0,
            is_corner: false,
        }
    }

    #[test]
    fn line_error_is_zero_on_the_curve_and_the_offset_beside_it() {
        let (a, b) = (DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0));
        let set = CurveSet::new(&[segment_curve(a, b)], 20.0);
        // A Bezier with collinear control points on the segment.
        let on = [a, a.lerp(b, 0.2), a.lerp(b, 0.9), b];
        let e = feature_line_error(&[on], &set, 101);
        assert_eq!(e.lines, 1);
        assert!(e.max_mean < 1e-15 && e.avg_mean < 1e-15);
        // Shifted by 0.01 sideways: every sample at distance 0.01.
        let off = on.map(|p| p + DVec3::new(0.0, 0.01, 0.0));
        let e = feature_line_error(&[on, off], &set, 101);
        assert!((e.max_worst - 0.01).abs() < 1e-12);
        assert!((e.max_mean - 0.005).abs() < 1e-12);
        assert!((e.min_mean - 0.005).abs() < 1e-12);
        // Sticking out beyond the end by 0.1 along the line: max 0.1, min 0.
        let out = [
            b,
            b.lerp(b * 1.1, 1.0 / 3.0),
            b.lerp(b * 1.1, 2.0 / 3.0),
            b * 1.1,
        ];
        let e = feature_line_error(&[out], &set, 101);
        assert!((e.max_mean - 0.1).abs() < 1e-12 && e.min_mean == 0.0);
        // The uniform parametrisation: mean over 101 samples of 0.1 t = 0.05.
        assert!((e.avg_mean - 0.05).abs() < 1e-12);
    }

    #[test]
    fn box_projection_metrics_match_the_construction() {
        let shape = reconbench_synth::from_spec("box").unwrap();
        let curves = shape.feature_curves();
        let diag = shape.aabb().diagonal();
        let bb = shape.aabb();
        // Input: the centres of two faces' grids; output: moved off the surface by 0.001
        // along the face normal, normals tilted by 10 degrees.
        let (lo, hi) = (bb.min, bb.max);
        let mut input = Vec::new();
        let m = 20;
        for i in 0..m {
            for j in 0..m {
                let (u, v) = ((i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64);
                input.push(DVec3::new(
                    lo.x + u * (hi.x - lo.x),
                    lo.y + v * (hi.y - lo.y),
                    hi.z,
                ));
            }
        }
        let output: Vec<DVec3> = input.iter().map(|p| *p + DVec3::Z * 0.001).collect();
        let tilt = 10f64.to_radians();
        let normals: Vec<DVec3> = input
            .iter()
            .map(|_| DVec3::new(tilt.sin(), 0.0, tilt.cos()))
            .collect();
        let ev = eval_filter(
            &output,
            Some(&normals),
            &input,
            Some((shape.as_ref(), &curves)),
            &[],
            diag,
            &FilterEvalOptions::default(),
        )
        .unwrap();
        assert!((ev.to_input.max - 0.001).abs() < 1e-12);
        assert!((ev.to_input.mean - 0.001).abs() < 1e-12);
        let s = ev.to_surface.unwrap();
        assert!((s.max - 0.001).abs() < 1e-12 && (s.mean - 0.001).abs() < 1e-12);
        let (near, away) = (ev.normal_near.unwrap(), ev.normal_away.unwrap());
        assert_eq!(near.count + away.count + ev.normal_skipped, input.len());
        assert!(near.count > 0 && away.count > 0);
        assert!((near.mean - 10.0).abs() < 1e-9 && (away.mean - 10.0).abs() < 1e-9);
        // Near = within 2 spacings of a box edge: the outer two rings of the grid.
        let sp = ev.spacing;
        let want = input
            .iter()
            .filter(|p| {
                let e = [p.x - lo.x, hi.x - p.x, p.y - lo.y, hi.y - p.y];
                e.iter().any(|&d| d <= 2.0 * sp)
            })
            .count();
        assert_eq!(near.count, want);
        assert!(eval_filter(&[], None, &input, None, &[], 1.0, &Default::default()).is_err());
    }
}
