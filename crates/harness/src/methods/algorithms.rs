//! Registry entries of the algorithm crates: one constructor and one parameter table per
//! method. The parameter docs mirror the `Params` doc comments of each crate (the
//! registry test checks that every default has a doc and vice versa).

use reconbench_features::{
    GaussMap, GaussMapAdaptive, GaussMapAdaptiveParams, GaussMapParams, PcaVariation,
    PcaVariationParams,
};
use reconbench_normals::{
    Jet, JetParams, LvmApprox, LvmApproxParams, PlaneFit, PlaneFitParams, WeightedPlaneFit,
    WeightedPlaneFitParams,
};
use reconbench_recon::{
    PriorityFront, PriorityFrontParams, Ufm, UfmMesh, UfmMeshParams, UfmParams,
};

use crate::registry::{MethodEntry, ParamDoc, features, normals, reconstruct};

const ORIENT_K: ParamDoc = ParamDoc {
    name: "orient_k",
    unit: "count",
    doc: "neighbours of the MST orientation graph (Hoppe); 0 leaves normals unoriented",
};

const PF_DOCS: &[ParamDoc] = &[
    ParamDoc {
        name: "k",
        unit: "count",
        doc: "neighbourhood size incl. the point itself (seed 000: 30, ASSUMPTION B-06/B-07)",
    },
    ORIENT_K,
];

const WPF_DOCS: &[ParamDoc] = &[
    ParamDoc {
        name: "k",
        unit: "count",
        doc: "neighbourhood size incl. the point itself (seed 000: 40, ASSUMPTION B-06)",
    },
    ParamDoc {
        name: "sigma_rule",
        unit: "",
        doc: "third-square: sigma^2 = d_k^2/3 (ASSUMPTION B-08); third-distance: sigma = d_k/3",
    },
    ORIENT_K,
];

const JET_DOCS: &[ParamDoc] = &[
    ParamDoc {
        name: "k",
        unit: "count",
        doc: "neighbourhood size incl. the point itself (CGAL examples: 18)",
    },
    ORIENT_K,
];

const LVM_DOCS: &[ParamDoc] = &[
    ParamDoc {
        name: "k",
        unit: "count",
        doc: "neighbourhood size incl. the point itself (ASSUMPTION B-09: 15; at most 64)",
    },
    ORIENT_K,
];

const FLAT_DOCS: [ParamDoc; 8] = [
    ParamDoc {
        name: "flat_tau",
        unit: "rad",
        doc: "flatness pre-test threshold (ASSUMPTION W-05: 0.15 pi/2); negative disables it",
    },
    ParamDoc {
        name: "flat_reference",
        unit: "",
        doc: "flatness reference line: principal-axis, medoid or mean (ASSUMPTION W-04)",
    },
    ParamDoc {
        name: "flat_min_sine",
        unit: "",
        doc: "ASSUMPTION W-18: sine floor for triangles in the flatness statistic (default 0.2, a deviation; 0 = all, spec-literal)",
    },
    ParamDoc {
        name: "min_cluster_frac",
        unit: "",
        doc: "drop clusters smaller than this share of the normals (ASSUMPTION W-06: 0.10)",
    },
    ParamDoc {
        name: "min_cluster_abs",
        unit: "count",
        doc: "drop clusters with fewer normals (ASSUMPTION W-06: 3)",
    },
    ParamDoc {
        name: "min_clusters",
        unit: "count",
        doc: "fewest surviving clusters for a feature (thesis: 2)",
    },
    ParamDoc {
        name: "max_clusters",
        unit: "count",
        doc: "most surviving clusters for a feature (thesis: 4)",
    },
    ParamDoc {
        name: "eps_deg",
        unit: "",
        doc: "degenerate-triangle threshold on the sine of the angle at p (ASSUMPTION W-02)",
    },
];

const GAUSS_MAP_DOCS: &[ParamDoc] = &[
    ParamDoc {
        name: "k",
        unit: "count",
        doc: "neighbours, the point excluded (ASSUMPTION W-01/W-08: 16)",
    },
    ParamDoc {
        name: "sigma",
        unit: "rad",
        doc: "average-linkage stop distance (ASSUMPTION W-08: 0.6)",
    },
    FLAT_DOCS[0],
    FLAT_DOCS[1],
    FLAT_DOCS[2],
    FLAT_DOCS[3],
    FLAT_DOCS[4],
    FLAT_DOCS[5],
    FLAT_DOCS[6],
    FLAT_DOCS[7],
];

const GAUSS_MAP_ADAPTIVE_DOCS: &[ParamDoc] = &[
    ParamDoc {
        name: "k0",
        unit: "count",
        doc: "initial neighbourhood size (thesis 20)",
    },
    ParamDoc {
        name: "sigma0",
        unit: "rad",
        doc: "initial clustering distance (thesis 0.1)",
    },
    ParamDoc {
        name: "sigma_growth",
        unit: "",
        doc: "factor on sigma per refinement step (thesis 1.1)",
    },
    ParamDoc {
        name: "k_step",
        unit: "count",
        doc: "decrement of k per refinement step (thesis 1)",
    },
    ParamDoc {
        name: "stop_share",
        unit: "",
        doc: "refine while this share of the neighbours are candidates (thesis 0.30)",
    },
    ParamDoc {
        name: "sigma_max",
        unit: "rad",
        doc: "refinement stops once sigma would exceed this (thesis 1.2)",
    },
    ParamDoc {
        name: "k_min",
        unit: "count",
        doc: "floor of k (thesis 8)",
    },
    ParamDoc {
        name: "kmin_is_break",
        unit: "",
        doc: "ASSUMPTION W-11: end the loop (true, default: thesis break condition) or clamp (false) at k_min",
    },
    ParamDoc {
        name: "max_inner",
        unit: "count",
        doc: "ASSUMPTION W-12: most refinement steps per candidate",
    },
    ParamDoc {
        name: "max_outer",
        unit: "count",
        doc: "ASSUMPTION W-12: most passes over the candidates",
    },
    ParamDoc {
        name: "isolated_rule",
        unit: "",
        doc: "ASSUMPTION W-13: drop candidates with at most one candidate neighbour",
    },
    ParamDoc {
        name: "isolated_sequential",
        unit: "",
        doc: "ASSUMPTION W-13: apply the isolated rule in index order with immediate effect (cascades along lines) instead of all at once",
    },
    ParamDoc {
        name: "recount_with_current_k",
        unit: "",
        doc: "ASSUMPTION W-10: count candidates in the current-k neighbourhood",
    },
    FLAT_DOCS[0],
    FLAT_DOCS[1],
    FLAT_DOCS[2],
    FLAT_DOCS[3],
    FLAT_DOCS[4],
    FLAT_DOCS[5],
    FLAT_DOCS[6],
    FLAT_DOCS[7],
];

const PCA_DOCS: &[ParamDoc] = &[
    ParamDoc {
        name: "mode",
        unit: "",
        doc: "single or multi (multi-scale with hysteresis, the thesis's comparison)",
    },
    ParamDoc {
        name: "k",
        unit: "count",
        doc: "single-mode neighbourhood size incl. the point (ASSUMPTION W-17: 16)",
    },
    ParamDoc {
        name: "threshold",
        unit: "",
        doc: "surface-variation threshold sigma_max (thesis 0.08)",
    },
    ParamDoc {
        name: "n_min",
        unit: "count",
        doc: "smallest multi-mode neighbourhood (thesis 10)",
    },
    ParamDoc {
        name: "n_max",
        unit: "count",
        doc: "largest multi-mode neighbourhood (thesis 40)",
    },
    ParamDoc {
        name: "omega_lo",
        unit: "count",
        doc: "lower hysteresis bound on the feature weight (thesis 25)",
    },
    ParamDoc {
        name: "omega_hi",
        unit: "count",
        doc: "upper hysteresis bound, seeds (thesis 30)",
    },
    ParamDoc {
        name: "hysteresis",
        unit: "",
        doc: "ASSUMPTION W-16: grow from seeds (true) or label omega >= omega_hi only",
    },
];

/// `reconbench-recon` documents its parameters as `(name, unit, doc)` tuples.
fn docs_from_tuples(
    t: &'static [(&'static str, &'static str, &'static str)],
) -> &'static [ParamDoc] {
    // Built once, when the registry is (see `registry()`), so the leak is bounded.
    Box::leak(
        t.iter()
            .map(|&(name, unit, doc)| ParamDoc { name, unit, doc })
            .collect::<Vec<_>>()
            .into_boxed_slice(),
    )
}

/// Every algorithm method, in `list` order.
pub fn entries() -> Vec<MethodEntry> {
    vec![
        normals::<PlaneFitParams>(
            "pf",
            "seed 000 §1.2.4",
            "k-NN plane fit (Hoppe et al. 1992)",
            PF_DOCS,
            |p, _| Ok(Box::new(PlaneFit { params: p })),
        ),
        normals::<WeightedPlaneFitParams>(
            "wpf",
            "seed 000 §1.2.5",
            "Gaussian-weighted plane fit (Pauly et al. 2003)",
            WPF_DOCS,
            |p, _| Ok(Box::new(WeightedPlaneFit { params: p })),
        ),
        normals::<JetParams>(
            "jet",
            "baseline (CGAL)",
            "degree-2 osculating jet (Cazals & Pouget 2005)",
            JET_DOCS,
            |p, _| Ok(Box::new(Jet { params: p })),
        ),
        normals::<LvmApproxParams>(
            "lvm-approx",
            "seed 000 §1.2.6",
            "local Voronoi mesh stand-in (ASSUMPTION B-09)",
            LVM_DOCS,
            |p, _| Ok(Box::new(LvmApprox { params: p })),
        ),
        normals::<UfmMeshParams>(
            "ufm-mesh",
            "seed 000 §1.2.3",
            "local-mesh matching normals (Ma 2011 ch. 4, Algorithm B) on the UFM state",
            docs_from_tuples(reconbench_recon::ufm::normals::PARAM_DOCS),
            |p, _| Ok(Box::new(UfmMesh::new(p)?)),
        ),
        features::<GaussMapParams>(
            "gauss-map",
            "seed 002 §3",
            "Gauss-map clustering, global method (Weber 2011 ch. 3.4-3.5)",
            GAUSS_MAP_DOCS,
            |p, _| Ok(Box::new(GaussMap::new(p))),
        ),
        features::<GaussMapAdaptiveParams>(
            "gauss-map-adaptive",
            "seed 002 §4",
            "Gauss-map clustering, local-adaptive refinement (Weber 2011 ch. 3.6)",
            GAUSS_MAP_ADAPTIVE_DOCS,
            |p, _| Ok(Box::new(GaussMapAdaptive::new(p))),
        ),
        features::<PcaVariationParams>(
            "pca-variation",
            "seed 002 §5.1",
            "PCA surface variation, single or multi-scale (Pauly et al. 2003)",
            PCA_DOCS,
            |p, _| Ok(Box::new(PcaVariation::new(p))),
        ),
        reconstruct::<PriorityFrontParams>(
            "priority-front",
            "seed 001 §4",
            "priority-driven advancing front (Li, Han & Wee); deviations in docs/methods/priority_front.md",
            docs_from_tuples(reconbench_recon::priority_front::PARAM_DOCS),
            |p, _| Ok(Box::new(PriorityFront::new(p)?)),
        ),
        reconstruct::<UfmParams>(
            "ufm",
            "seed 000 §1.1",
            "Umbrella Facet Matching on the 3D Delaunay triangulation (Ma 2011 ch. 3)",
            docs_from_tuples(reconbench_recon::ufm::PARAM_DOCS),
            |p, _| Ok(Box::new(Ufm::new(p)?)),
        ),
    ]
}
