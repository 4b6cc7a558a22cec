//! Tests of the thinning filters: EBT's error-bounded thinning against its stage
//! function, the budget baselines against their targets and a brute-force grid rule.

use glam::DVec3;
use reconbench_filters::thinning::grid_thin;
use reconbench_filters::{EbtThinning, GridThinning, RandomThinning};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Describe, Diagnostic, Filter, RunCtx};
use reconbench_recon::ebt::{self, ThinningParams};

/// A wavy sheet, 60 x 60 jittered samples over 20 x 20 units.
fn sheet() -> PointCloud {
    let mut p = Vec::new();
    for i in 0..60 {
        for j in 0..60 {
            let jx = ((i * 7 + j * 13) as f64 * 0.618_034).fract() - 0.5;
            let jy = ((i * 11 + j * 5) as f64 * 0.414_214).fract() - 0.5;
            let x = -10.0 + 20.0 * (i as f64 + 0.5 + 0.3 * jx) / 60.0;
            let y = -10.0 + 20.0 * (j as f64 + 0.5 + 0.3 * jy) / 60.0;
            p.push(DVec3::new(x, y, 2.0 * (0.2 * x).sin() * (0.15 * y).cos()));
        }
    }
    PointCloud::new(p).unwrap()
}

fn q_points(d: &reconbench_geom::method::Diagnostics) -> f64 {
    match d.get("q_points") {
        Some(Diagnostic::Number(x)) => *x,
        o => panic!("{o:?}"),
    }
}

#[test]
fn ebt_thinning_keeps_the_stage_result_and_sources() {
    let c = sheet();
    let p = ThinningParams {
        epsilon: 0.002,
        ..ThinningParams::default()
    };
    let f = EbtThinning::from_params(p.clone()).unwrap();
    let out = f.filter(&c, &mut RunCtx::new(5)).unwrap();
    let t = ebt::thin(&c, &p, &mut RunCtx::new(5)).unwrap();
    assert_eq!(out.source.as_deref(), Some(&t.kept[..]));
    assert_eq!(out.cloud.len(), t.kept.len());
    assert_eq!(q_points(&out.diagnostics), t.kept.len() as f64);
    for (k, &i) in t.kept.iter().enumerate() {
        assert_eq!(out.cloud.positions()[k], c.positions()[i as usize]);
    }
    // A larger tolerance keeps fewer points (B grows as sqrt(eps)).
    let coarse = ThinningParams {
        epsilon: 0.008,
        ..p
    };
    let out2 = EbtThinning::from_params(coarse)
        .unwrap()
        .filter(&c, &mut RunCtx::new(5))
        .unwrap();
    let ratio = out.cloud.len() as f64 / out2.cloud.len() as f64;
    // |Q| ~ area / B^2 and B ~ sqrt(eps): 4x eps -> about 4x fewer points.
    assert!(ratio > 2.5 && ratio < 6.0, "ratio {ratio}");
}

#[test]
fn random_thinning_hits_the_budget_deterministically() {
    let c = sheet();
    let f = RandomThinning::from_params(reconbench_filters::thinning::BudgetParams { target: 500 })
        .unwrap();
    let a = f.filter(&c, &mut RunCtx::new(1)).unwrap();
    let b = f.filter(&c, &mut RunCtx::new(1)).unwrap();
    let other = f.filter(&c, &mut RunCtx::new(2)).unwrap();
    assert_eq!(a.cloud.len(), 500);
    assert_eq!(a.source, b.source);
    assert_ne!(a.source, other.source);
    let s = a.source.unwrap();
    assert!(s.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn grid_thinning_is_near_the_budget_and_matches_brute_force() {
    let c = sheet();
    let f = GridThinning::from_params(reconbench_filters::thinning::BudgetParams { target: 400 })
        .unwrap();
    let out = f.filter(&c, &mut RunCtx::new(0)).unwrap();
    let n = out.cloud.len() as f64;
    assert!((n - 400.0).abs() <= 0.1 * 400.0, "kept {n}");
    // The per-cell rule against brute force on a fixed cell size.
    let p = c.positions();
    let h = 1.3;
    let lo = p.iter().fold(DVec3::splat(f64::INFINITY), |m, x| m.min(*x));
    let cell = |x: DVec3| ((x - lo) / h).floor().as_ivec3();
    let got = grid_thin(p, h);
    let mut want = Vec::new();
    for (i, &x) in p.iter().enumerate() {
        let members: Vec<usize> = (0..p.len()).filter(|&j| cell(p[j]) == cell(x)).collect();
        let cen = members.iter().map(|&j| p[j]).sum::<DVec3>() / members.len() as f64;
        let d = |j: usize| (p[j] - cen).length_squared();
        let best = members
            .iter()
            .copied()
            .min_by(|&a, &b| d(a).total_cmp(&d(b)).then(a.cmp(&b)))
            .unwrap();
        if best == i {
            want.push(i as u32);
        }
    }
    assert_eq!(got, want);
}

#[test]
fn bad_input_and_parameters_are_errors() {
    let empty = PointCloud::new(vec![]).unwrap();
    for f in [
        Box::new(EbtThinning::default()) as Box<dyn Filter>,
        Box::new(RandomThinning::default()),
        Box::new(GridThinning::default()),
    ] {
        let e = f.filter(&empty, &mut RunCtx::new(0)).unwrap_err();
        assert!(e.to_string().contains("no points"), "{e}");
    }
    let e = RandomThinning::from_params(reconbench_filters::thinning::BudgetParams { target: 0 })
        .unwrap_err();
    assert!(e.to_string().contains("target"));
    let e = EbtThinning::from_params(ThinningParams {
        epsilon: -1.0,
        ..ThinningParams::default()
    })
    .unwrap_err();
    assert!(e.to_string().contains("epsilon"));
    // All points coincident: a named error, no panic.
    let dup = PointCloud::new(vec![DVec3::ONE; 50]).unwrap();
    let e = EbtThinning::default()
        .filter(&dup, &mut RunCtx::new(0))
        .unwrap_err();
    assert!(e.to_string().contains("coincide"), "{e}");
    let g = GridThinning::default()
        .filter(&dup, &mut RunCtx::new(0))
        .unwrap();
    assert_eq!(g.cloud.len(), 1); // one occupied cell
}
