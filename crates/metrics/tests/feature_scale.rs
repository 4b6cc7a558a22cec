//! Feature evaluation on clouds at the wrong scale for their reference: refused with an
//! error before any large allocation, never an abort.

use glam::DVec3;
use reconbench_metrics::Reference;
use reconbench_metrics::features::{FeatureOptions, MAX_LENGTH_SAMPLES, eval_features};

/// A 10 x 10 x 10 grid in the unit cube, labelled on its edges.
fn cube_grid(scale: f64) -> (Vec<DVec3>, Vec<bool>) {
    let mut pts = Vec::new();
    let mut det = Vec::new();
    for i in 0..10 {
        for j in 0..10 {
            for k in 0..10 {
                let on = [i, j, k].iter().filter(|&&c| c == 0 || c == 9).count() >= 2;
                pts.push(DVec3::new(i as f64, j as f64, k as f64) / 9.0 - 0.5);
                det.push(on);
            }
        }
    }
    (pts.iter().map(|p| *p * scale).collect(), det)
}

fn run(scale: f64) -> Result<f64, String> {
    let reference = Reference::from_arg("box").map_err(|e| e.to_string())?;
    let opts = FeatureOptions::default();
    let curves = reference.feature_curves(opts.feature_angle_deg);
    let (pts, det) = cube_grid(scale);
    eval_features(&pts, &pts, &det, &curves, reference.diagonal(), &opts)
        .map(|e| e.spacing)
        .map_err(|e| e.to_string())
}

#[test]
fn a_cloud_at_the_reference_scale_evaluates() {
    let s = run(1.0).unwrap();
    assert!(s > 0.0 && s < 1.0, "{s}");
}

#[test]
fn tiny_and_subnormal_clouds_are_refused_naming_the_limit() {
    for scale in [1e-9, 1e-160, f64::from_bits(1 << 40)] {
        let err = run(scale).unwrap_err();
        assert!(
            err.contains(&MAX_LENGTH_SAMPLES.to_string()),
            "{scale:e}: {err}"
        );
        assert!(err.contains("same scale"), "{scale:e}: {err}");
    }
}
