//! Tests of `ufm` (issue 7): spec 000 §4.1 invariants on toy and synthetic closed
//! shapes, BuildUmbrella properties on real DT_v, determinism across thread counts,
//! bad input, a non-converging input that must still be edge-manifold.

use glam::DVec3;
use reconbench_delaunay::Delaunay;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, MethodError, Reconstruction, Reconstructor, RunCtx};
use reconbench_geom::topology::analyze;
use reconbench_recon::ufm::engine::{self, Complex};
use reconbench_recon::ufm::nvc::{NvcCfg, NvcStats, mean_dihedral, nvc_flags};
use reconbench_recon::ufm::umbrella::LinkGraph;
use reconbench_recon::ufm::{
    Init, Mode, Nvc, NvcLevel, NvcStart, OutputSet, StopRule, Update, run_ufm,
};
use reconbench_recon::{Ufm, UfmParams};
use reconbench_synth::{DatasetSpec, Density};

fn synth(shape: &str, sampler: &str, n: usize, perturb: Option<&str>, seed: u64) -> Vec<DVec3> {
    let spec = DatasetSpec {
        shape: shape.parse().expect("shape"),
        sampler: sampler.parse().expect("sampler"),
        density: Density::Count(n),
        perturbations: perturb
            .map(|p| p.parse().expect("perturb"))
            .into_iter()
            .collect(),
        scan: None,
    };
    reconbench_synth::generate(&spec, seed)
        .expect("data")
        .positions
}

fn genus_of(shape: &str) -> u32 {
    shape
        .parse::<reconbench_synth::ShapeSpec>()
        .unwrap()
        .build()
        .unwrap()
        .info()
        .genus
}

fn run(pts: &[DVec3], params: UfmParams) -> Reconstruction {
    let cloud = PointCloud::new(pts.to_vec()).expect("finite");
    Ufm::new(params)
        .expect("params")
        .reconstruct(&cloud, &mut RunCtx::new(1))
        .expect("ufm")
}

fn diag(r: &Reconstruction, k: &str) -> f64 {
    match r.diagnostics.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        other => panic!("diagnostic {k}: {other:?}"),
    }
}

/// Closed, right genus, one component, ΔF = 0, F = 2V + 4(G − 1), consistently oriented
/// with positive volume, every input point a vertex.
fn assert_closed(r: &Reconstruction, n: usize, genus: u32, what: &str) {
    let t = analyze(&r.mesh);
    assert_eq!(diag(r, "matching"), 100.0, "{what}: {:?}", r.diagnostics);
    assert!(t.watertight, "{what}: {t:?}");
    assert_eq!(t.genus, Some(genus), "{what}");
    assert_eq!(t.components, 1, "{what}");
    assert!(t.consistently_oriented, "{what}");
    assert_eq!(t.vertices, n);
    assert_eq!(t.referenced_vertices, n, "{what}");
    assert_eq!(
        t.faces as i64,
        2 * n as i64 + 4 * (genus as i64 - 1),
        "{what}: F = 2V + 4(G - 1)"
    );
    assert_eq!(diag(r, "delta_f"), 0.0, "{what}");
    assert_eq!(diag(r, "pinched_vertices"), 0.0);
    assert!(signed_volume(r) > 0.0, "{what}: outward orientation");
}

fn signed_volume(r: &Reconstruction) -> f64 {
    let v = r.mesh.vertices();
    r.mesh
        .faces()
        .iter()
        .map(|f| v[f[0] as usize].dot(v[f[1] as usize].cross(v[f[2] as usize])) / 6.0)
        .sum()
}

fn params_g(genus: u32) -> UfmParams {
    UfmParams {
        genus: Some(genus),
        ..Default::default()
    }
}

/// Spec §4.1: toy closed shapes (octahedron, icosahedron vertices) converge to 100 %
/// with ΔF = 0 (their convex hull is the answer).
#[test]
fn platonic_vertices_give_their_hull() {
    let oct: Vec<DVec3> = [
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::Z,
        -DVec3::Z,
    ]
    .to_vec();
    let r = run(&oct, params_g(0));
    assert_closed(&r, 6, 0, "octahedron");
    assert_eq!(r.mesh.n_faces(), 8);
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let mut ico = Vec::new();
    for s1 in [-1.0, 1.0] {
        for s2 in [-1.0, 1.0] {
            ico.push(DVec3::new(0.0, s1, s2 * phi));
            ico.push(DVec3::new(s1, s2 * phi, 0.0));
            ico.push(DVec3::new(s2 * phi, 0.0, s1));
        }
    }
    let r = run(&ico, params_g(0));
    assert_closed(&r, 12, 0, "icosahedron");
    assert_eq!(r.mesh.n_faces(), 20);
}

/// Spec §4.1: a sampled sphere and the 60 x 60 torus of Table 4.1 converge with ΔF = 0.
#[test]
fn sphere_and_grid_torus_converge() {
    let pts = synth("sphere", "blue-noise", 3000, None, 1);
    assert_closed(&run(&pts, params_g(0)), pts.len(), 0, "sphere");
    let pts = synth("torus:R=2,r=1", "grid:nu=60,nv=60", 3600, None, 1);
    assert_closed(&run(&pts, params_g(1)), pts.len(), 1, "torus 60x60");
}

/// Issue 7 target: every closed analogue of Table 3.2 at adequate density is
/// watertight with the right genus, one component and ΔF = 0 (blue noise) — with the
/// documented deviations on (`max_fold = 90`: folded umbrellas are rebuilt; `escapes`:
/// membership-free updates when stuck). The thesis's literal loop stalls at 97-99.7 %
/// on these shapes (sliver bubbles and 2-2 splits, docs/methods/ufm.md);
/// `closed_analogues_stay_manifold_and_nearly_matched` checks what holds for it.
#[test]
fn closed_analogues_are_watertight() {
    for (shape, n) in [
        ("ellipsoid", 4000),
        ("torus", 4000),
        ("torus-knot", 6000),
        ("double-torus", 6000),
        ("three-holes", 6000),
    ] {
        let pts = synth(shape, "blue-noise", n, None, 2);
        let g = genus_of(shape);
        let p = UfmParams {
            max_fold: 90.0,
            escapes: 20,
            ..params_g(g)
        };
        assert_closed(&run(&pts, p), pts.len(), g, shape);
    }
}

/// The fold repair: with the literal loop some final umbrellas fold back over
/// themselves (fold angle near 180°, e.g. the corners of fully matched sliver
/// tetrahedra); with `max_fold = 90` none does, and the matching does not drop.
#[test]
fn fold_repair_removes_folded_umbrellas() {
    let pts = synth("torus-knot", "blue-noise", 6000, None, 2);
    let folded = |p: &UfmParams| {
        let st = run_ufm(&pts, p, &mut RunCtx::new(1)).expect("ufm");
        let bound = 90f64.to_radians();
        let n = (0..st.cx.n_vertices())
            .filter(|&v| engine::umbrella_folds(&st.cx, &st.inu, v, bound))
            .count();
        (n, *st.trace.last().unwrap())
    };
    let (lit, mu_lit) = folded(&UfmParams::default());
    let (rep, mu_rep) = folded(&UfmParams {
        max_fold: 90.0,
        ..Default::default()
    });
    assert!(
        lit > 0,
        "the literal loop leaves folded umbrellas on this input"
    );
    assert_eq!(rep, 0, "folded umbrellas left by the repair");
    assert!(mu_rep >= mu_lit, "{mu_rep} < {mu_lit}");
}

/// `reorder` (Morton order for locality) changes only the numbering: on points in
/// general position the loop's output face set (in input indices) and the diagnostics
/// are the same, with and without the fold repair. (The closure of `mode = "closed"`
/// breaks ties between equal fans by facet id, so it may differ.)
#[test]
fn reorder_does_not_change_the_result() {
    let pts = synth("torus-knot", "blue-noise", 3000, None, 3);
    let literal = UfmParams {
        mode: Mode::Literal,
        ..Default::default()
    };
    for base in [
        literal.clone(),
        UfmParams {
            max_fold: 90.0,
            escapes: 5,
            ..literal.clone()
        },
    ] {
        let faces = |reorder: bool| {
            let r = run(
                &pts,
                UfmParams {
                    reorder,
                    ..base.clone()
                },
            );
            let mut f: Vec<[u32; 3]> = r
                .mesh
                .faces()
                .iter()
                .map(|t| {
                    let mut t = *t;
                    t.sort_unstable();
                    t
                })
                .collect();
            f.sort_unstable();
            (f, diag(&r, "matching"), diag(&r, "iterations"))
        };
        let (a, b) = (faces(false), faces(true));
        assert!(!a.0.is_empty());
        assert_eq!(a, b, "{base:?}");
    }
}

/// What holds on the harder analogues: high matching, no non-manifold edge, every
/// vertex's umbrella a cycle, ΔF small relative to F.
#[test]
fn closed_analogues_stay_manifold_and_nearly_matched() {
    for (shape, n, min_matching) in [
        ("torus", 6000, 99.0),
        ("torus-knot", 8000, 97.0),
        ("double-torus", 8000, 99.0),
        ("three-holes", 8000, 98.5),
    ] {
        let pts = synth(shape, "blue-noise", n, None, 2);
        let g = genus_of(shape);
        let r = run(&pts, params_g(g));
        let t = analyze(&r.mesh);
        assert!(
            diag(&r, "matching") >= min_matching,
            "{shape}: {:?}",
            r.diagnostics
        );
        assert_eq!(t.non_manifold_edges, 0, "{shape}");
        assert!(t.consistently_oriented, "{shape}");
        assert!(diag(&r, "delta_f") < 0.02 * n as f64, "{shape}");
    }
}

/// The ellipsoid (high curvature tips) converges like the sphere (data seed 1; seed 2
/// stalls at 99.8 % with one 11-edge hole, see the ignored test above).
#[test]
fn ellipsoid_converges() {
    let pts = synth("ellipsoid", "blue-noise", 6000, None, 1);
    assert_closed(&run(&pts, params_g(0)), pts.len(), 0, "ellipsoid");
}

/// A point set that cannot converge (heavy noise, uniform in a ball of 1.5 spacings)
/// still yields an edge-manifold mesh; pinched vertices are counted, not assumed zero.
#[test]
fn non_converging_input_is_still_edge_manifold() {
    let pts = synth(
        "sphere",
        "uniform",
        3000,
        Some("ball:radius=1.5,rel=spacing"),
        4,
    );
    for output in [OutputSet::MatchedFacets, OutputSet::FullUmbrellas] {
        let r = run(
            &pts,
            UfmParams {
                max_iter: 30,
                output,
                mode: Mode::Literal,
                ..params_g(0)
            },
        );
        let t = analyze(&r.mesh);
        assert!(diag(&r, "matching") < 100.0, "{:?}", r.diagnostics);
        assert_eq!(t.non_manifold_edges, 0, "{t:?}");
        assert_eq!(diag(&r, "non_manifold_edges"), 0.0);
        assert_eq!(diag(&r, "pinched_vertices"), t.non_manifold_vertices as f64);
        assert_eq!(t.duplicate_faces, 0);
        assert!(t.consistently_oriented);
        assert!(!t.watertight);
        assert!(diag(&r, "unmatched_points") > 0.0);
    }
    // The default closed mode adds to what the loop leaves and stays a clean
    // 2-manifold (this much noise is beyond what it closes: its pieces stay open).
    let r = run(&pts, params_g(0));
    let t = analyze(&r.mesh);
    assert!(diag(&r, "closure_added") > 0.0, "{:?}", r.diagnostics);
    assert_eq!(t.non_manifold_edges + t.non_manifold_vertices, 0, "{t:?}");
    assert_eq!(t.duplicate_faces, 0, "{t:?}");
    assert!(t.orientable);
}

/// Synchronous updates: identical output with 1 and 2 threads.
#[test]
fn deterministic_across_thread_counts() {
    let pts = synth("torus-knot", "blue-noise", 5000, None, 5);
    let go = |threads: usize, p: UfmParams| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(&pts, p))
    };
    let repaired = UfmParams {
        max_fold: 90.0,
        escapes: 5,
        ..params_g(1)
    };
    for p in [params_g(1), repaired] {
        let (a, b) = (go(1, p.clone()), go(2, p));
        assert_eq!(a.mesh.faces(), b.mesh.faces());
        assert_eq!(
            a.diagnostics.get("matching_trace"),
            b.diagnostics.get("matching_trace")
        );
    }
}

/// Exact duplicates are merged (A-01): unreferenced vertices, listed as refused; the
/// rest is unchanged.
#[test]
fn duplicates_are_refused() {
    let mut pts = synth("sphere", "blue-noise", 2000, None, 6);
    let clean = run(&pts, params_g(0));
    pts.push(pts[10]);
    pts.push(pts[20]);
    let r = run(&pts, params_g(0));
    assert_eq!(r.refused, vec![2000, 2001]);
    assert_eq!(r.mesh.faces(), clean.mesh.faces());
    assert_eq!(diag(&r, "delta_f"), 0.0);
    assert_eq!(diag(&r, "duplicates"), 2.0);
}

#[test]
fn bad_input_is_an_error() {
    let ufm = Ufm::default();
    for pts in [
        vec![],
        vec![DVec3::ZERO, DVec3::X, DVec3::Y],
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)],
    ] {
        let cloud = PointCloud::new(pts).unwrap();
        let e = ufm.reconstruct(&cloud, &mut RunCtx::new(1));
        assert!(matches!(e, Err(MethodError::InvalidInput(_))), "{e:?}");
    }
    assert!(
        Ufm::new(UfmParams {
            patience: 0,
            ..Default::default()
        })
        .is_err()
    );
    for bad in [-1.0, 181.0, f64::NAN] {
        let e = Ufm::new(UfmParams {
            max_fold: bad,
            ..Default::default()
        });
        assert!(
            matches!(&e, Err(MethodError::InvalidParameter { name, .. }) if name == "max_fold_deg"),
            "{bad}: {e:?}"
        );
    }
}

/// Spec §1.1.3 facts on real Delaunay links: BuildUmbrella on DT_v (no lock) never
/// fails, leaves only degrees 0 or 2, returns one simple cycle of length >= 3; with the
/// Gabriel subset it may fail (counted), never with a non-cycle.
#[test]
fn build_umbrella_on_dt_v_is_one_cycle() {
    let mut pts = synth("torus", "uniform", 1500, None, 7);
    // Plus some interior points (link = triangulated sphere).
    pts.extend((0..50).map(|i| DVec3::new(0.01 * i as f64, 0.002 * i as f64, 0.0)));
    let dt = Delaunay::new(&pts).unwrap();
    let cx = Complex::new(dt, Default::default()).unwrap();
    let mut g = LinkGraph::default();
    let (mut f, mut r) = (Vec::new(), Vec::new());
    for v in 0..cx.n_vertices() {
        cx.prepare(v, &mut g);
        let row = cx.row(v);
        // Any order: by id, and reversed.
        for rev in [false, true] {
            let mut order: Vec<u32> = (0..row.len() as u32).collect();
            if rev {
                order.reverse();
            }
            g.build(|_| true, &order, None)
                .expect("DT_v always holds an umbrella");
            for x in 0..g.nodes.len() as u32 {
                assert!(matches!(g.degree(x), 0 | 2), "vertex {v}");
            }
            let alive = g.alive.clone();
            g.cycle(|i| alive[i], &mut f, &mut r);
            let k = alive.iter().filter(|&&a| a).count();
            assert!(k >= 3 && f.len() == k, "vertex {v}: one simple cycle");
            let mut rs = r.clone();
            rs.sort_unstable();
            rs.dedup();
            assert_eq!(rs.len(), k, "ring vertices distinct");
        }
    }
}

/// A-05/A-08: a fully matched umbrella is reproduced unchanged by a rebuild from DT_v,
/// with and without locks; and freezing does not change the result of a run.
#[test]
fn fully_matched_umbrellas_are_reproduced() {
    let pts = synth("double-torus", "blue-noise", 4000, None, 8);
    let mut ctx = RunCtx::new(1);
    let st = run_ufm(&pts, &UfmParams::default(), &mut ctx).unwrap();
    let g = engine::grades(&st.cx, &st.inu, &st.m);
    let mut n_full = 0;
    for v in 0..st.cx.n_vertices() {
        if !g[v] {
            continue;
        }
        n_full += 1;
        let base = st.cx.off[v] as usize;
        let old = &st.inu[base..base + st.cx.row(v).len()];
        for lock in [false, true] {
            assert_eq!(engine::rebuild_one(&st.cx, v, &st.inu, &st.m, lock), old);
        }
    }
    assert!(n_full > 3000);
    // Freezing is exact: same trace and output with freeze_full off.
    let noisy = synth(
        "sphere",
        "uniform",
        2500,
        Some("ball:radius=0.6,rel=spacing"),
        9,
    );
    for lock_matched in [true, false] {
        let a = run(
            &noisy,
            UfmParams {
                lock_matched,
                max_iter: 15,
                ..Default::default()
            },
        );
        let b = run(
            &noisy,
            UfmParams {
                lock_matched,
                max_iter: 15,
                freeze_full: false,
                ..Default::default()
            },
        );
        assert_eq!(a.mesh.faces(), b.mesh.faces());
        assert_eq!(
            a.diagnostics.get("matching_trace"),
            b.diagnostics.get("matching_trace")
        );
    }
}

/// Invariants of every state: m <= 3 and Σ_t m[t] = Σ_v |U_v|; the output is the set of
/// facets with m = 3; the trace starts with the initial matching.
#[test]
fn matching_invariants_and_ablations_run() {
    let pts = synth("three-holes", "uniform", 3000, None, 10);
    for p in [
        UfmParams::default(),
        UfmParams {
            init: Init::Delaunay,
            ..Default::default()
        },
        UfmParams {
            update: Update::GaussSeidel,
            ..Default::default()
        },
        UfmParams {
            lock_matched: false,
            size_order: reconbench_recon::ufm::SizeOrder::SmallFirst,
            ..Default::default()
        },
        UfmParams {
            max_iter: 0,
            ..Default::default()
        },
    ] {
        let st = run_ufm(&pts, &p, &mut RunCtx::new(1)).unwrap();
        let sum_m: u64 = st.m.iter().map(|&x| x as u64).sum();
        let sum_u = st.inu.iter().filter(|&&x| x).count() as u64;
        assert_eq!(sum_m, sum_u);
        assert!(st.m.iter().all(|&x| x <= 3));
        assert_eq!(st.trace.len(), st.iterations + 1);
        assert!(st.iterations <= p.max_iter);
        if p.max_iter == 0 {
            assert_eq!(st.iterations, 0);
            assert!(matches!(st.stop, StopRule::MaxIter | StopRule::Converged));
        }
        // Every vertex has an umbrella.
        for v in 0..st.cx.n_vertices() {
            let base = st.cx.off[v] as usize;
            let k = st.inu[base..base + st.cx.row(v).len()]
                .iter()
                .filter(|&&x| x)
                .count();
            assert!(k >= 3);
        }
    }
}

// ---------------------------------------------------------------------------------
// Algorithm C (chapter 5): Normal Vector Cone filtering, the `nvc` option.

fn nvc(mode: Nvc, genus: u32) -> UfmParams {
    UfmParams {
        nvc: mode,
        ..params_g(genus)
    }
}

/// With NVC filtering on, the closed CAD analogues (sharp edges) still give an
/// edge-manifold, consistently oriented mesh, every umbrella is rebuilt without
/// failure, the cones are used (and flat points found with the flatness-sensitive
/// cone, whose angle is 2θ̄ clamped to π/4), and the matching stays high.
#[test]
fn nvc_keeps_cad_analogues_edge_manifold() {
    for shape in ["cube-with-hole", "fandisk-like"] {
        let pts = synth(shape, "blue-noise", 3000, None, 2);
        let g = genus_of(shape);
        let off = diag(&run(&pts, params_g(g)), "matching");
        for (p, what) in [
            (nvc(Nvc::Generic, g), "generic"),
            (nvc(Nvc::Flatness, g), "flatness"),
            (
                UfmParams {
                    max_fold: 90.0,
                    escapes: 20,
                    ..nvc(Nvc::Flatness, g)
                },
                "fold+escape+flatness",
            ),
            (
                UfmParams {
                    nvc_start: NvcStart::Stagnation,
                    ..nvc(Nvc::Flatness, g)
                },
                "late flatness",
            ),
            (nvc(Nvc::FlatOnly, g), "flat-only"),
            (
                UfmParams {
                    update: Update::GaussSeidel,
                    ..nvc(Nvc::Flatness, g)
                },
                "gauss-seidel flatness",
            ),
        ] {
            let flat = p.nvc != Nvc::Generic;
            let flat_only = p.nvc == Nvc::FlatOnly;
            let late = p.nvc_start == NvcStart::Stagnation;
            let r = run(&pts, p);
            let t = analyze(&r.mesh);
            let what = format!("{shape} {what}");
            assert_eq!(t.non_manifold_edges, 0, "{what}");
            assert_eq!(diag(&r, "non_manifold_edges"), 0.0, "{what}");
            assert!(t.consistently_oriented, "{what}");
            assert_eq!(t.duplicate_faces, 0, "{what}");
            assert_eq!(diag(&r, "build_failures"), 0.0, "{what}");
            assert!(diag(&r, "nvc_points") > 0.0, "{what}: {:?}", r.diagnostics);
            assert!(diag(&r, "nvc_triangles") > 0.0, "{what}");
            assert_eq!(
                diag(&r, "nvc_from_iteration") > 0.0,
                late,
                "{what}: C-06 start"
            );
            if flat_only {
                // Only flat points are filtered.
                assert_eq!(
                    diag(&r, "nvc_points"),
                    diag(&r, "nvc_flat_points"),
                    "{what}"
                );
            } else {
                assert!(
                    diag(&r, "nvc_points") > diag(&r, "nvc_flat_points"),
                    "{what}"
                );
            }
            if flat {
                assert!(diag(&r, "nvc_flat_points") > 0.0, "{what}");
                let a = diag(&r, "nvc_alpha_flat_deg");
                assert!(a > 0.0 && a <= 45.0, "{what}: alpha_flat {a}");
            } else {
                assert_eq!(diag(&r, "nvc_flat_points"), 0.0, "{what}");
                assert!(!r.diagnostics.contains_key("nvc_alpha_flat_deg"));
            }
            let mu = diag(&r, "matching");
            // Measured (3,000 points): from the first iteration on NVC costs 2-3
            // points of matching on these off-edge samplings (see docs/methods/ufm.md);
            // started at the plain loop's fixed point (C-06 ablation) it only adds.
            assert!(mu >= off - 5.0 && mu <= 100.0, "{what}: {mu} (off: {off})");
            if late {
                assert!(mu >= off, "{what}: {mu} (off: {off})");
            }
        }
    }
}

/// `nvc = off` (the default) ignores every other `nvc_*` parameter: the chapter 3
/// result is unchanged, and no NVC diagnostic is reported.
#[test]
fn nvc_off_leaves_the_result_unchanged() {
    let pts = synth("cube-with-hole", "blue-noise", 3000, None, 3);
    let a = run(&pts, params_g(1));
    let b = run(
        &pts,
        UfmParams {
            nvc_angle: 20.0,
            nvc_flat_factor: 5.0,
            nvc_range: 1,
            nvc_start: NvcStart::Stagnation,
            nvc_level: NvcLevel::BelowClass,
            ..params_g(1)
        },
    );
    assert_eq!(a.mesh.faces(), b.mesh.faces());
    assert_eq!(
        a.diagnostics.get("matching_trace"),
        b.diagnostics.get("matching_trace")
    );
    assert!(!a.diagnostics.contains_key("nvc_points"));
    // And NVC on does change the iterations (the option is not a no-op).
    let c = run(&pts, nvc(Nvc::Flatness, 1));
    assert_ne!(
        a.diagnostics.get("matching_trace"),
        c.diagnostics.get("matching_trace")
    );
}

/// NVC filtering keeps the update synchronous: identical output with 1 and 2 threads.
#[test]
fn nvc_is_deterministic_across_thread_counts() {
    let pts = synth("cube-with-hole", "blue-noise", 3000, None, 5);
    let go = |threads: usize, p: UfmParams| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(&pts, p))
    };
    let repaired = UfmParams {
        max_fold: 90.0,
        escapes: 5,
        ..nvc(Nvc::Flatness, 1)
    };
    for p in [nvc(Nvc::Flatness, 1), nvc(Nvc::Generic, 1), repaired] {
        let (a, b) = (go(1, p.clone()), go(2, p));
        assert_eq!(a.mesh.faces(), b.mesh.faces());
        assert_eq!(
            a.diagnostics.get("matching_trace"),
            b.diagnostics.get("matching_trace")
        );
        for k in ["nvc_points", "nvc_flat_points", "nvc_triangles"] {
            assert_eq!(diag(&a, k), diag(&b, k), "{k}");
        }
    }
}

/// The NVC sets on a real state (the initial umbrellas of a cube with a hole): only
/// unmatched triangles of points with `G_v = 0`, whose other corners are in the
/// limitation range; wider cones and the larger range give supersets; the pass does
/// not depend on the thread count; `θ̄` is a mean of angles in [0, π].
#[test]
fn nvc_sets_respect_cone_and_range() {
    let pts = synth("cube-with-hole", "blue-noise", 2000, None, 4);
    let st = run_ufm(
        &pts,
        &UfmParams {
            max_iter: 0,
            ..Default::default()
        },
        &mut RunCtx::new(1),
    )
    .unwrap();
    let cx = &st.cx;
    let g = engine::grades(cx, &st.inu, &st.m);
    assert!(g.iter().any(|&x| !x), "some umbrella unmatched");
    let flags = |mode: Nvc, deg: f64, range: u32| {
        let cfg = NvcCfg {
            mode,
            generic: deg.to_radians(),
            flat_factor: 2.0,
            range,
        };
        let mut out = vec![true; cx.items.len()];
        let s = nvc_flags(cx, &st.inu, &st.m, &g, &cfg, &mut out);
        (out, s)
    };
    let (f30, _) = flags(Nvc::Generic, 30.0, 2);
    let (f45, s45) = flags(Nvc::Generic, 45.0, 2);
    let (f90, _) = flags(Nvc::Generic, 90.0, 2);
    let (f45r1, _) = flags(Nvc::Generic, 45.0, 1);
    let facets = cx.facets();
    // Ring sets from the umbrellas of the initial state.
    let ring1 = |v: usize| -> Vec<u32> {
        let base = cx.off[v] as usize;
        let mut r: Vec<u32> = cx
            .row(v)
            .iter()
            .enumerate()
            .filter(|&(i, _)| st.inu[base + i])
            .flat_map(|(_, &f)| facets[f as usize].v)
            .filter(|&x| x as usize != v)
            .collect();
        r.sort_unstable();
        r.dedup();
        r
    };
    let mut n45 = 0u64;
    for v in 0..cx.n_vertices() {
        let base = cx.off[v] as usize;
        let r1 = ring1(v);
        let mut r2 = r1.clone();
        for &p in &r1 {
            r2.extend(ring1(p as usize));
            r2.push(p);
        }
        r2.sort_unstable();
        r2.dedup();
        for (i, &f) in cx.row(v).iter().enumerate() {
            let s = base + i;
            assert!(!f30[s] || f45[s], "30° ⊆ 45°");
            assert!(!f45[s] || f90[s], "45° ⊆ 90°");
            assert!(!f45r1[s] || f45[s], "R = 1 ⊆ R = 2");
            if f90[s] {
                assert!(!g[v], "no filter at fully matched points (C-07)");
                assert!(st.m[f as usize] < 3, "only unmatched triangles");
                let others = facets[f as usize]
                    .v
                    .into_iter()
                    .filter(|&x| x as usize != v);
                assert!(
                    others.clone().all(|x| r2.binary_search(&x).is_ok()),
                    "R = 2"
                );
            }
            if f45r1[s] {
                let mut others = facets[f as usize]
                    .v
                    .into_iter()
                    .filter(|&x| x as usize != v);
                assert!(others.all(|x| r1.binary_search(&x).is_ok()), "R = 1");
            }
            n45 += f45[s] as u64;
        }
    }
    assert_eq!(n45, s45.members);
    assert!(n45 > 0);
    // Strictly narrower: some triangle is in the 45° set but not in the 30° one.
    assert!(f45.iter().zip(&f30).any(|(a, b)| *a && !*b));
    // flat-only = the flatness mode restricted to its flat points.
    let (ff, sf) = flags(Nvc::Flatness, 45.0, 2);
    let (fo, so) = flags(Nvc::FlatOnly, 45.0, 2);
    assert!(
        fo.iter().zip(&ff).all(|(o, f)| !*o || *f),
        "flat-only ⊆ flatness"
    );
    assert!(
        so.flat > 0 && so.filtered == so.flat && so.flat == sf.flat,
        "{so:?} {sf:?}"
    );
    assert!(so.members < sf.members);
    // Deterministic across thread counts, also the flatness modes.
    for mode in [Nvc::Generic, Nvc::Flatness, Nvc::FlatOnly] {
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| flags(mode, 45.0, 2));
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(|| flags(mode, 45.0, 2));
        assert_eq!(one.0, two.0);
        let key = |s: NvcStats| (s.filtered, s.flat, s.members, s.last_alpha_flat.to_bits());
        assert_eq!(key(one.1), key(two.1));
        if mode != Nvc::Generic {
            assert!(one.1.flat > 0 && one.1.last_alpha_flat > 0.0, "{:?}", one.1);
        }
    }
    let tb = mean_dihedral(cx, &st.m).expect("matched edge pairs exist");
    assert!(tb > 0.0 && tb < std::f64::consts::PI, "{tb}");
}

#[test]
fn bad_nvc_parameters_are_errors() {
    let cases: [(&str, UfmParams); 8] = [
        (
            "nvc_angle_deg",
            UfmParams {
                nvc_angle: 0.0,
                ..Default::default()
            },
        ),
        (
            "nvc_angle_deg",
            UfmParams {
                nvc_angle: 91.0,
                ..Default::default()
            },
        ),
        (
            "nvc_angle_deg",
            UfmParams {
                nvc_angle: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "nvc_flat_factor",
            UfmParams {
                nvc_flat_factor: 0.0,
                ..Default::default()
            },
        ),
        (
            "nvc_flat_factor",
            UfmParams {
                nvc_flat_factor: f64::INFINITY,
                ..Default::default()
            },
        ),
        (
            "nvc_flat_factor",
            UfmParams {
                nvc_flat_factor: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "nvc_range",
            UfmParams {
                nvc_range: 0,
                ..Default::default()
            },
        ),
        (
            "nvc_range",
            UfmParams {
                nvc_range: 3,
                ..Default::default()
            },
        ),
    ];
    for (what, p) in cases {
        let e = Ufm::new(p);
        assert!(
            matches!(&e, Err(MethodError::InvalidParameter { name, .. }) if name == what),
            "{what}: {e:?}"
        );
    }
    // Parsed from the harness's JSON/TOML form; unknown modes are rejected.
    let p: UfmParams = serde_json::from_str(
        r#"{"nvc": "flat-only", "nvc_start": "stagnation", "nvc_level": "below-class"}"#,
    )
    .unwrap();
    assert_eq!(
        (p.nvc, p.nvc_start, p.nvc_level),
        (Nvc::FlatOnly, NvcStart::Stagnation, NvcLevel::BelowClass)
    );
    assert!(serde_json::from_str::<UfmParams>(r#"{"nvc": "on"}"#).is_err());
    // Degenerate input with NVC on is still an error, not a panic.
    let cloud = PointCloud::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y]).unwrap();
    let e = Ufm::new(nvc(Nvc::Flatness, 0))
        .unwrap()
        .reconstruct(&cloud, &mut RunCtx::new(1));
    assert!(matches!(e, Err(MethodError::InvalidInput(_))), "{e:?}");
}

use reconbench_testkit::box_edges;

/// The sharp-feature claim of chapter 5 on a box sampled like a CAD mesh (edge samples
/// at half the face spacing): with the fold repair and escapes, restricting NVC cones
/// to the flat points (`flat-only`) keeps at least as many box edges, cuts off no
/// more of them and matches at least as well as without NVC, on every seed, and
/// strictly fewer faces cut an edge off in total (measured: 0 against 6-16 per seed;
/// docs/methods/ufm.md).
#[test]
fn nvc_flat_cones_keep_sampled_box_edges() {
    let h = 0.1;
    let (mut bevel_off, mut bevel_nvc) = (0, 0);
    for seed in 1..=3 {
        let b = box_edges::box_samples(h, true, 2, 0.25, seed);
        let base = UfmParams {
            max_fold: 90.0,
            escapes: 20,
            ..params_g(0)
        };
        let off = run(&b.pts, base.clone());
        let on = run(
            &b.pts,
            UfmParams {
                nvc: Nvc::FlatOnly,
                ..base
            },
        );
        let (eo, en) = (
            box_edges::edge_stats(&b, off.mesh.faces(), h),
            box_edges::edge_stats(&b, on.mesh.faces(), h),
        );
        assert_eq!(diag(&on, "non_manifold_edges"), 0.0);
        assert!(diag(&on, "nvc_flat_points") > 0.0);
        assert!(en.recovery >= eo.recovery, "seed {seed}: {en:?} vs {eo:?}");
        assert!(
            en.bevel_faces <= eo.bevel_faces,
            "seed {seed}: {en:?} vs {eo:?}"
        );
        assert!(
            diag(&on, "matching") >= diag(&off, "matching"),
            "seed {seed}: {:?}",
            on.diagnostics
        );
        bevel_off += eo.bevel_faces;
        bevel_nvc += en.bevel_faces;
    }
    assert!(bevel_nvc < bevel_off, "{bevel_nvc} vs {bevel_off}");
}

/// The closure alone: holes cut around ten vertices of a converged sphere (each a disk
/// with its centre freed) are closed again with Delaunay triangles only, back to a
/// watertight genus-0 surface on every point.
#[test]
fn closure_recloses_holes_cut_into_a_converged_sphere() {
    use reconbench_recon::ufm::{closure, output_facets};
    let pts = synth("sphere", "blue-noise", 2000, None, 1);
    let st = run_ufm(&pts, &UfmParams::default(), &mut RunCtx::new(1)).expect("ufm");
    let facets = st.cx.facets();
    let mut out = output_facets(&st, OutputSet::MatchedFacets);
    let n_full = out.len();
    out.retain(|&f| facets[f as usize].v.iter().all(|&v| v % 200 != 7));
    assert!(out.len() < n_full - 40, "holes were cut");
    let (closed, extra, stats) =
        closure::close(&st.cx, st.cx.dt.vertices(), &out, 120f64.to_radians());
    assert!(extra.is_empty(), "Delaunay triangles suffice: {stats:?}");
    assert!(stats.added >= n_full - out.len(), "{stats:?}");
    let faces: Vec<[u32; 3]> = closed.iter().map(|&f| facets[f as usize].v).collect();
    let mesh = reconbench_geom::TriMesh::new(st.cx.dt.vertices().to_vec(), faces).unwrap();
    let t = analyze(&mesh);
    assert!(t.watertight, "{t:?}");
    assert_eq!(t.genus, Some(0));
    assert_eq!(t.referenced_vertices, pts.len());
    assert_eq!(t.faces, 2 * pts.len() - 4);
}
