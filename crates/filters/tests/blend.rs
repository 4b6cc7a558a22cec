//! `blend` (seed 002 §7) on a grid box with a tube standing on its top face: the collar
//! closes the gap between them, every point carries an origin tag and the counts add
//! up, the cut-back removes exactly the points the spec's spheres reach, the output is
//! bit-identical across runs and thread counts, and bad parameters are errors.

use glam::DVec3;
use reconbench_filters::blend::{
    Blend, BlendParams, Patch, Reconstruct, Tube, blend_points, write_patch,
};
use reconbench_geom::method::{
    Describe, Diagnostic, FEATURE_CHANNEL, Filter, Filtered, MethodError, ORIGIN_CHANNEL,
    ORIGIN_COLLAR, ORIGIN_NURBS, ORIGIN_SCAN, RunCtx,
};
use reconbench_geom::{Channel, PointCloud, mean_spacing};
use reconbench_metrics::{BlendOptions, eval_blend, eval_blend_truth};
use reconbench_synth::{Density, Shape, ShapeSpec, sample_or_scan};
use reconbench_testkit::feature_fixtures::{Truth, grid_box};

/// The unit cube on a 24-interval grid (3458 points, spacing 1/24), with exact feature
/// labels.
fn cube() -> (Truth, PointCloud) {
    let t = grid_box(1.0, 24);
    let mut c = t.cloud();
    let lab: Vec<i64> = t
        .points
        .iter()
        .map(|&p| i64::from(t.edge_distance(p) < 1e-9))
        .collect();
    c.set_channel(FEATURE_CHANNEL, Channel::Label(lab)).unwrap();
    (t, c)
}

fn params(reconstruct: Reconstruct) -> BlendParams {
    BlendParams {
        reconstruct,
        radius_rel: 0.1,
        length_rel: 0.2,
        ..BlendParams::default()
    }
}

fn run(cloud: &PointCloud, p: BlendParams, seed: u64) -> Filtered {
    Blend::from_params(p)
        .unwrap()
        .filter(cloud, &mut RunCtx::new(seed))
        .unwrap()
}

fn tags(f: &Filtered) -> Vec<i64> {
    match f.cloud.channel(ORIGIN_CHANNEL) {
        Some(Channel::Label(v)) => v.clone(),
        other => panic!("no origin labels: {other:?}"),
    }
}

fn number(f: &Filtered, key: &str) -> f64 {
    match f.diagnostics.get(key) {
        Some(Diagnostic::Number(x)) => *x,
        other => panic!("diagnostic {key}: {other:?}"),
    }
}

fn gap(cloud: &PointCloud) -> f64 {
    eval_blend(cloud, None, &BlendOptions::default())
        .unwrap()
        .unwrap()
        .gap_sp
}

#[test]
fn the_collar_closes_the_gap_between_box_and_tube() {
    let (_, c) = cube();
    for rec in [Reconstruct::None, Reconstruct::Sharp] {
        let f = run(&c, params(rec), 7);
        let g = gap(&f.cloud);
        assert!(g <= 2.0, "{rec:?}: gap {g} spacings with the collar");
        let t = tags(&f);
        assert!(t.iter().filter(|&&x| x == ORIGIN_COLLAR).count() > 50);
        // Without the collar the cut-back leaves a band about w - t wide: the metric
        // must see it.
        let no_collar: Vec<usize> = (0..t.len()).filter(|&i| t[i] != ORIGIN_COLLAR).collect();
        let bare = f.cloud.select(&no_collar).unwrap();
        let g0 = gap(&bare);
        assert!(g0 > 2.0, "{rec:?}: gap without the collar only {g0}");
    }
}

#[test]
fn every_point_is_tagged_and_the_counts_add_up() {
    let (t, c) = cube();
    let f = run(&c, params(Reconstruct::Sharp), 3);
    let tag = tags(&f);
    assert_eq!(tag.len(), f.cloud.len());
    assert!(
        tag.iter()
            .all(|x| [ORIGIN_SCAN, ORIGIN_NURBS, ORIGIN_COLLAR].contains(x))
    );
    let n = |v: i64| tag.iter().filter(|&&x| x == v).count() as f64;
    assert_eq!(n(ORIGIN_SCAN), number(&f, "blend_scan_kept"));
    assert_eq!(n(ORIGIN_NURBS), number(&f, "blend_nurbs"));
    assert_eq!(n(ORIGIN_COLLAR), number(&f, "blend_collar"));
    let removed = number(&f, "blend_removed");
    assert!(removed > 0.0);
    assert_eq!(n(ORIGIN_SCAN) + removed, t.points.len() as f64);
    assert!(number(&f, "blend_collar") < number(&f, "blend_collar_raw"));
    // The reconstruction gives every point a normal.
    let normals = f.cloud.normals().expect("normals");
    assert!(normals.iter().all(|n| n.length() > 0.5));
    let ev = eval_blend(&f.cloud, Some(t.points.len()), &BlendOptions::default())
        .unwrap()
        .unwrap();
    assert_eq!(ev.removed, Some(removed as usize));
    assert!(
        ev.collar_nn_cv.is_finite() && ev.collar_nn_cv < 0.5,
        "{ev:?}"
    );
}

/// Distance from `p` to the segment `a b`.
fn seg_dist(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let s = if l2 == 0.0 {
        0.0
    } else {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    };
    (a + ab * s - p).length()
}

#[test]
fn the_cut_back_removes_exactly_what_the_spheres_reach() {
    let (t, c) = cube();
    let p = params(Reconstruct::None);
    let d = mean_spacing(&t.points, 1).unwrap();
    let bb = c.aabb();
    let tube = Tube::new(&p, bb.min, bb.max).unwrap();
    let b = blend_points(&t.points, &tube, &p, d, 1).unwrap();
    let (tt, w) = (p.t_rel * d, p.w_rel * d);
    let dist_p = |x: DVec3| {
        t.points
            .iter()
            .map(|q| (*q - x).length())
            .fold(f64::INFINITY, f64::min)
    };
    // Border points sit at height t (bisection tolerance 1e-3 d), NURBS samples above.
    for a in &b.border[..] {
        let h = dist_p(*a);
        assert!(
            h > tt - 0.05 * d && h < tt + 0.05 * d,
            "border at {h} vs t {tt}"
        );
    }
    for x in &b.nurbs {
        assert!(dist_p(*x) >= tt - 0.05 * d);
    }
    // Brute force over the spec's spheres: radius w at every border point and along
    // the sweep from the first border point (step w / 2).
    let a0 = b.border[0];
    let reached = |q: DVec3| {
        b.border.iter().any(|&a| {
            if (q - a).length() <= w {
                return true;
            }
            let steps = ((a - a0).length() / (0.5 * w)).ceil() as usize;
            (1..steps).any(|s| (q - (a0 + (a - a0) * (s as f64 / steps as f64))).length() <= w)
        })
    };
    let expected: Vec<u32> = (0..t.points.len() as u32)
        .filter(|&i| reached(t.points[i as usize]))
        .collect();
    assert_eq!(b.removed, expected);
    // Every removed point is within w of the swept segments, every kept one farther
    // than w from every border point: the cut-back is the footprint plus a w margin.
    for &i in &b.removed {
        let q = t.points[i as usize];
        assert!(b.border.iter().any(|&a| seg_dist(q, a0, a) <= w + 1e-12));
    }
    for &i in &b.kept {
        let q = t.points[i as usize];
        assert!(b.border.iter().all(|&a| (q - a).length() > w));
    }
    assert_eq!(b.removed.len() + b.kept.len(), t.points.len());
}

#[test]
fn output_is_bit_identical_across_runs_and_thread_counts() {
    let (_, c) = cube();
    let go = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(&c, params(Reconstruct::Sharp), seed))
    };
    let a = go(1, 5);
    let b = go(2, 5);
    let a2 = go(2, 5);
    assert_eq!(a.cloud, b.cloud);
    assert_eq!(b.cloud, a2.cloud);
    // The seed drives the thinning order only: another seed keeps the scan and NURBS
    // parts and changes the collar.
    let other = go(2, 6);
    assert_ne!(a.cloud, other.cloud);
    assert_eq!(number(&a, "blend_nurbs"), number(&other, "blend_nurbs"));
}

fn build_err(p: BlendParams) -> String {
    match Blend::from_params(p) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_parameters_and_inputs_are_errors() {
    let e = build_err(BlendParams {
        t_rel: 5.0,
        w_rel: 5.0,
        ..BlendParams::default()
    });
    assert!(e.contains("w_rel") && e.contains("exceed"), "{e}");
    let e = build_err(BlendParams {
        t_rel: f64::NAN,
        ..BlendParams::default()
    });
    assert!(e.contains("t_rel"), "{e}");
    let e = build_err(BlendParams {
        axis: [0.0; 3],
        ..BlendParams::default()
    });
    assert!(e.contains("axis"), "{e}");
    let e = build_err(BlendParams {
        radius_rel: -1.0,
        ..BlendParams::default()
    });
    assert!(e.contains("radius_rel"), "{e}");
    let e = build_err(BlendParams {
        collar_k: 0,
        ..BlendParams::default()
    });
    assert!(e.contains("collar_k"), "{e}");
    let f = Blend::from_params(BlendParams::default()).unwrap();
    let mut ctx = RunCtx::new(1);
    let empty = PointCloud::new(Vec::new()).unwrap();
    let e = f.filter(&empty, &mut ctx).unwrap_err();
    assert!(matches!(e, MethodError::InvalidInput(_)), "{e}");
    assert!(e.to_string().contains("at least 3"), "{e}");
    // Sharp reconstruction without feature labels says what to put before it.
    let (t, _) = cube();
    let e = f.filter(&t.cloud(), &mut ctx).unwrap_err().to_string();
    assert!(
        e.contains("feature") && e.contains("gauss-map-adaptive"),
        "{e}"
    );
    // A tube that never comes near the scan.
    let away = Blend::from_params(BlendParams {
        center_rel: [5.0, 5.0, 5.0],
        reconstruct: Reconstruct::Smooth,
        ..BlendParams::default()
    })
    .unwrap();
    let e = away.filter(&t.cloud(), &mut ctx).unwrap_err().to_string();
    assert!(e.contains("never comes within"), "{e}");
}

/// The scan of the `box-tube` ground truth: its box sampled on the grid (the union's
/// scale; 3458 points, 24 intervals per edge), with exact feature labels.
fn box_tube_scan() -> (Box<dyn Shape>, PointCloud) {
    let shape = ShapeSpec::named("box-tube").build().unwrap();
    let g = sample_or_scan(
        shape.as_ref(),
        &"grid".parse().unwrap(),
        Density::Count(3458),
        None,
        1,
    )
    .unwrap();
    let mut c = PointCloud::new(g.positions.clone()).unwrap();
    let lab = g
        .feature_distance
        .iter()
        .map(|&d| i64::from(d < 1e-9))
        .collect();
    c.set_channel(FEATURE_CHANNEL, Channel::Label(lab)).unwrap();
    (shape, c)
}

/// The blend of a noiseless box+tube scan against the exact union (`box-tube`): the
/// unprojected set has its scan and NURBS points exactly on the union (the filter and
/// the shape share the tube's placement) and its collar within the chord bound; after
/// the sharp reconstruction the scan and NURBS points move by less than h / 4, the collar
/// stays within the bound, and no hole is wider than 2 spacings.
///
/// The bound: a collar segment runs from a border point at height <= t on the wall to a
/// scan border point at most w + d out on the face, so a point of it is at most
/// min(lambda (w + d), (1 - lambda) t) <= t (w + d) / (t + w + d) from the union's
/// concave junction (2 spacings for t = 3, w = 5).
#[test]
fn the_blend_of_a_noiseless_box_tube_lies_near_the_true_union() {
    let (shape, c) = box_tube_scan();
    let d = mean_spacing(c.positions(), 1).unwrap();
    let p = params(Reconstruct::None);
    let chord = p.t_rel * (p.w_rel + 1.0) / (p.t_rel + p.w_rel + 1.0);
    let h = p.h_rel;
    for (rec, on_surface) in [(Reconstruct::None, 1e-9), (Reconstruct::Sharp, 0.25 * h)] {
        let f = run(&c, params(rec), 7);
        let t = tags(&f);
        let mut worst = [0.0f64; 3];
        for (i, x) in f.cloud.positions().iter().enumerate() {
            let o = t[i] as usize;
            worst[o] = worst[o].max(shape.distance(*x) / d);
        }
        let [scan, nurbs, collar] = worst;
        // The metric of the harness rows reports the same distances.
        let ev = eval_blend_truth(&f.cloud, shape.as_ref(), d, &BlendOptions::default())
            .unwrap()
            .unwrap();
        assert!((ev.collar.max - collar).abs() < 1e-12 && (ev.scan.max - scan).abs() < 1e-12);
        assert!((ev.nurbs.max - nurbs).abs() < 1e-12);
        assert_eq!(ev.region_normal.is_some(), rec == Reconstruct::Sharp);
        assert!(
            scan <= on_surface,
            "{rec:?}: scan point {scan} spacings off the union"
        );
        assert!(
            nurbs <= on_surface,
            "{rec:?}: NURBS point {nurbs} spacings off the union"
        );
        assert!(
            collar <= chord,
            "{rec:?}: collar point {collar} > {chord} spacings off"
        );
        // The collar does cut the corner: its farthest point is more than half the bound
        // away (a collar on the union would mean the chart or the test is wrong).
        assert!(collar > 0.5 * chord, "{rec:?}: collar only {collar} off");
        let g = gap(&f.cloud);
        assert!(g <= 2.0, "{rec:?}: gap {g} spacings");
    }
}

/// With noise the scan's bounding box grows and the tube placed in it drifts off the
/// truth; placed in the part's frame (`frame`) its samples stay exactly on the union.
#[test]
fn the_frame_places_the_tube_of_a_noisy_scan_where_the_truth_has_it() {
    let (shape, c) = box_tube_scan();
    let d = mean_spacing(c.positions(), 1).unwrap();
    // Outward noise of 0.5 spacings on every point of the top face's rim region.
    let moved: Vec<DVec3> = c
        .positions()
        .iter()
        .map(|&p| if p.z > 0.0 { p + DVec3::Z * 0.5 * d } else { p })
        .collect();
    let noisy = c.with_positions(moved).unwrap();
    let b = shape.scanned_part().unwrap().aabb();
    let nurbs_off = |frame: Option<[[f64; 3]; 2]>| {
        let f = run(
            &noisy,
            BlendParams {
                frame,
                ..params(Reconstruct::None)
            },
            7,
        );
        let t = tags(&f);
        f.cloud
            .positions()
            .iter()
            .zip(&t)
            .filter(|(_, o)| **o == ORIGIN_NURBS)
            .map(|(x, _)| shape.distance(*x) / d)
            .fold(0.0, f64::max)
    };
    let exact = nurbs_off(Some([b.min.to_array(), b.max.to_array()]));
    let drifted = nurbs_off(None);
    assert!(exact < 1e-9, "{exact}");
    assert!(drifted > 1e-3, "{drifted}");
    let e = build_err(BlendParams {
        frame: Some([[0.0; 3], [0.0, f64::NAN, 0.0]]),
        ..BlendParams::default()
    });
    assert!(e.contains("frame"), "{e}");
}

/// A file in the temporary directory holding `text`, named after the test.
fn temp_file(name: &str, text: &str) -> String {
    let path = std::env::temp_dir().join(format!("reconbench-blend-{}-{name}", std::process::id()));
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

/// `patch = "file"` with a file describing the thesis's tube (written from the tube's
/// own control net) gives the output of `patch = "tube"`, bit for bit.
#[test]
fn a_patch_file_of_the_tube_gives_the_tubes_output() {
    let (_, c) = cube();
    let p = params(Reconstruct::Sharp);
    let bb = c.aabb();
    let tube = Tube::new(&p, bb.min, bb.max).unwrap();
    assert!(tube.closed_v);
    let net = tube.control_net();
    assert_eq!(net.degrees, [1, 2]);
    let path = temp_file("tube.txt", &write_patch(&net));
    let from_file = BlendParams {
        patch: Patch::File,
        patch_file: path.clone(),
        ..params(Reconstruct::Sharp)
    };
    let a = run(&c, p, 5);
    let b = run(&c, from_file, 5);
    std::fs::remove_file(&path).ok();
    assert_eq!(a.cloud, b.cloud);
    assert_eq!(number(&a, "blend_nurbs"), number(&b, "blend_nurbs"));
}

/// Malformed patch files are errors naming the file and the line at fault.
#[test]
fn malformed_patch_files_are_errors_naming_the_line() {
    let (_, c) = cube();
    let bb = c.aabb();
    let tube = Tube::new(&params(Reconstruct::None), bb.min, bb.max).unwrap();
    let good = write_patch(&tube.control_net());
    // Line 6 is the first control point: give it a negative weight.
    let mut negative: Vec<String> = good.lines().map(String::from).collect();
    let mut words: Vec<&str> = negative[5].split_whitespace().collect();
    words[3] = "-1";
    negative[5] = words.join(" ");
    let negative = negative.join("\n");
    let cases = [
        (
            "knots",
            good.replace("knots_u 0 0 1 1", "knots_u 0 0 1"),
            "line 3",
            "knots_u has 3 knots",
        ),
        (
            "number",
            good.replace("degrees 1 2", "degrees 1 two"),
            "line 2",
            "not a finite number",
        ),
        (
            "order",
            good.replace("knots_v", "knots_w"),
            "line 4",
            "expected 'knots_v",
        ),
        ("weight", negative, "line 6", "w > 0"),
        (
            "short",
            good.lines().take(8).collect::<Vec<_>>().join("\n"),
            "line",
            "expected 14 control points",
        ),
    ];
    for (name, text, line, what) in cases {
        let path = temp_file(name, &text);
        let e = build_err(BlendParams {
            patch: Patch::File,
            patch_file: path.clone(),
            ..BlendParams::default()
        });
        std::fs::remove_file(&path).ok();
        assert!(
            e.contains(&path) && e.contains(line) && e.contains(what),
            "{name}: {e}"
        );
    }
    let e = build_err(BlendParams {
        patch: Patch::File,
        ..BlendParams::default()
    });
    assert!(e.contains("patch_file"), "{e}");
    let e = build_err(BlendParams {
        patch: Patch::File,
        patch_file: "/nonexistent/patch.txt".into(),
        ..BlendParams::default()
    });
    assert!(e.contains("/nonexistent/patch.txt"), "{e}");
}
