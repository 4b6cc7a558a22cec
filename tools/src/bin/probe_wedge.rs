//! Diagnostic probe (not part of the API): `gauss-map-adaptive` on a grid wedge with
//! small k0 (the thesis's §3.7.1 setting), printing the refinement's diagnostics.
//!
//! `cargo run --release -p reconbench-tools --bin probe_wedge [ANGLE] [K0]`

use reconbench_testkit::feature_fixtures as common;

use reconbench_features::{GaussMapAdaptive, GaussMapAdaptiveParams};
use reconbench_geom::method::{FeatureClass, FeatureDetector, RunCtx};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let angle = args.first().copied().unwrap_or(140.0);
    let k0 = args.get(1).copied().unwrap_or(8.0) as usize;
    let t = common::wedge(angle, 2.0, 1.0, 0.05);
    for (iso, recount) in [(true, false), (false, false), (true, true)] {
        let d = GaussMapAdaptive::new(GaussMapAdaptiveParams {
            k0,
            k_min: 8.min(k0),
            isolated_rule: iso,
            recount_with_current_k: recount,
            ..Default::default()
        });
        let out = d.detect(&t.cloud(), &mut RunCtx::new(1)).unwrap();
        let s = common::score(&t, &out.labels, 0.5 * t.spacing);
        let det = out
            .labels
            .iter()
            .filter(|c| **c != FeatureClass::None)
            .count();
        println!(
            "wedge {angle} k0 {k0} isolated_rule {iso} recount {recount}: detected {det}, {s:?}\n  {:?}",
            out.diagnostics
        );
    }
}
