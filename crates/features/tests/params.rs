//! Parameter structs: thesis defaults, serde behaviour.

use reconbench_features::{
    FlatReference, GaussMapAdaptiveParams, GaussMapParams, PcaMode, PcaVariationParams,
    THESIS_FLAT_TAU,
};

#[test]
fn defaults_are_the_thesis_values() {
    let g = GaussMapParams::default();
    assert_eq!(
        (g.k, g.sigma, g.min_clusters, g.max_clusters),
        (16, 0.6, 2, 4)
    );
    assert!((THESIS_FLAT_TAU - 0.2356).abs() < 1e-4);
    assert_eq!(g.flat_tau, THESIS_FLAT_TAU);
    let a = GaussMapAdaptiveParams::default();
    assert_eq!(
        (a.k0, a.sigma0, a.sigma_growth, a.k_step),
        (20, 0.1, 1.1, 1)
    );
    assert_eq!((a.stop_share, a.sigma_max, a.k_min), (0.3, 1.2, 8));
    // Documented deviations (docs/methods/features.md): W-06 0.10 (spec 0.05), W-18 0.2
    // (spec-literal 0), W-13 isolated rule at once (not cascading).
    assert_eq!((g.min_cluster_frac, g.flat_min_sine), (0.10, 0.2));
    assert_eq!((a.min_cluster_frac, a.flat_min_sine), (0.10, 0.2));
    assert!(a.isolated_rule && !a.isolated_sequential);
    let p = PcaVariationParams::default();
    assert_eq!(p.mode, PcaMode::Multi);
    assert_eq!(
        (p.threshold, p.n_min, p.n_max, p.omega_lo, p.omega_hi),
        (0.08, 10, 40, 25, 30)
    );
}

#[test]
fn unknown_fields_are_rejected_and_missing_fields_default() {
    assert!(serde_json::from_str::<GaussMapParams>(r#"{"k": 10, "sigmaa": 0.5}"#).is_err());
    assert!(serde_json::from_str::<GaussMapAdaptiveParams>(r#"{"k": 10}"#).is_err());
    assert!(serde_json::from_str::<PcaVariationParams>(r#"{"sigma": 1}"#).is_err());
    let g: GaussMapParams =
        serde_json::from_str(r#"{"k": 10, "sigma": 0.5, "flat_reference": "medoid"}"#).unwrap();
    assert_eq!(
        (g.k, g.sigma, g.flat_reference),
        (10, 0.5, FlatReference::Medoid)
    );
    assert_eq!(g.max_clusters, 4);
    let p: PcaVariationParams = serde_json::from_str(r#"{"mode": "single", "k": 20}"#).unwrap();
    assert_eq!((p.mode, p.k), (PcaMode::Single, 20));
    let s = serde_json::to_string(&GaussMapAdaptiveParams::default()).unwrap();
    assert_eq!(
        serde_json::from_str::<GaussMapAdaptiveParams>(&s).unwrap(),
        GaussMapAdaptiveParams::default()
    );
}

#[test]
fn adaptive_schedule_follows_the_thesis() {
    // Default (ASSUMPTION W-11, k_min a break condition): k 19, 18, ..., 8 = 12 steps,
    // sigma 0.1 * 1.1^s.
    let a = GaussMapAdaptiveParams::default();
    assert!(a.kmin_is_break);
    let s = a.schedule(20);
    assert_eq!(s.len(), 12);
    assert_eq!(s[0].0, 19);
    assert!((s[0].1 - 0.11).abs() < 1e-12);
    assert_eq!(s[11].0, 8);
    assert!((s[11].1 - 0.1 * 1.1f64.powi(12)).abs() < 1e-12);
    // k0 = k_min: no refinement step at all.
    assert!(a.schedule(8).is_empty());
    // Clamp reading: sigma0 * 1.1^26 = 1.19 <= 1.2 < 1.1^27 * 0.1: 26 steps, k clamped
    // at 8.
    let b = GaussMapAdaptiveParams {
        kmin_is_break: false,
        ..Default::default()
    };
    let s = b.schedule(20);
    assert_eq!(s.len(), 26);
    assert_eq!(s[11].0, 8);
    assert_eq!(s[25].0, 8);
}
