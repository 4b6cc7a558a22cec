//! Tests of `priority-front` (issue 8): closed surfaces, open sheet, outliers,
//! degenerate input, determinism, threads, parameters, time budget.

use std::time::Duration;

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::method::{MethodError, Reconstruction, Reconstructor, RunCtx};
use reconbench_geom::topology::{TopologyReport, analyze};
use reconbench_geom::{MeshBvh, PointCloud};
use reconbench_recon::priority_front::NAME;
use reconbench_recon::{PriorityFront, PriorityFrontParams};
use reconbench_testkit::surfaces::{Surface, uniform_outliers};

/// Parameters used for the closed-surface tests: the defaults (ASSUMPTION A12 off by
/// default since issue 8; see docs/methods/priority_front.md).
fn closing_params() -> PriorityFrontParams {
    PriorityFrontParams::default()
}

fn run(pts: Vec<DVec3>, params: PriorityFrontParams, seed: u64) -> Reconstruction {
    let cloud = PointCloud::new(pts).expect("finite points");
    let pf = PriorityFront::new(params).expect("valid params");
    let mut ctx = RunCtx::new(seed);
    pf.reconstruct(&cloud, &mut ctx).expect("reconstruction")
}

fn blue(s: Surface, n: usize, seed: u64) -> Vec<DVec3> {
    s.sample_blue_noise(n, &mut ChaCha8Rng::seed_from_u64(seed))
}

fn assert_manifold_oriented(t: &TopologyReport) {
    assert_eq!(t.non_manifold_edges, 0, "{t:?}");
    assert_eq!(t.non_manifold_vertices, 0, "{t:?}");
    assert!(t.consistently_oriented, "{t:?}");
    assert_eq!(t.degenerate_faces, 0, "{t:?}");
    assert_eq!(t.duplicate_faces, 0, "{t:?}");
}

/// Issue 8 target: a closed torus at adequate density is watertight with genus 1, for
/// several samplings and seeds, and few clean points are refused.
#[test]
fn torus_is_watertight_genus_one() {
    for seed in [1, 2, 3] {
        let rec = run(
            blue(Surface::Torus(1.0, 0.35), 6000, seed),
            closing_params(),
            seed,
        );
        let t = analyze(&rec.mesh);
        assert_manifold_oriented(&t);
        assert!(t.watertight, "seed {seed}: {t:?}");
        assert_eq!(t.components, 1, "seed {seed}");
        assert_eq!(t.genus, Some(1), "seed {seed}");
        assert!(rec.refused.len() < 150, "refused {}", rec.refused.len());
    }
}

/// Without the small-hole closing (I7 off, the paper's behaviour) the same tori keep
/// only a few small loops: the growth itself gets close, I7 only finishes it.
#[test]
fn torus_without_hole_closing_keeps_only_small_loops() {
    for seed in [1, 2, 3] {
        let rec = run(
            blue(Surface::Torus(1.0, 0.35), 6000, seed),
            PriorityFrontParams {
                close_holes_max: 0,
                ..closing_params()
            },
            seed,
        );
        let t = analyze(&rec.mesh);
        assert_manifold_oriented(&t);
        assert_eq!(t.genus, Some(1), "seed {seed}");
        assert!(t.n_boundary_loops() <= 3, "seed {seed}: {t:?}");
        assert!(
            t.boundary_loops.iter().all(|l| l.vertices <= 10),
            "seed {seed}: {t:?}"
        );
    }
}

/// The spec's A12 reading (apex rule on) stays available: still manifold and closed,
/// but it refuses clearly more clean points (the evidence for the default change).
#[test]
fn apex_rule_variant_refuses_more_clean_points() {
    let pts = blue(Surface::Torus(1.0, 0.35), 6000, 2);
    // The growth's refusals, before IMPL-CHOICE I15 inserts the covered points.
    let growth = PriorityFrontParams {
        insert_covered: false,
        ..closing_params()
    };
    let off = run(pts.clone(), growth.clone(), 2);
    let on = run(
        pts,
        PriorityFrontParams {
            apex_angle_rule: true,
            ..growth
        },
        2,
    );
    let t = analyze(&on.mesh);
    assert_manifold_oriented(&t);
    assert_eq!(t.genus, Some(1));
    // Measured 73 vs 51 with the issue-20 defaults (reject_free_inside); 270 vs 94
    // before, when covered points were not kept out from under triangles.
    assert!(
        on.refused.len() * 4 > off.refused.len() * 5,
        "refused with A12 {} vs without {}",
        on.refused.len(),
        off.refused.len()
    );
}

#[test]
fn sphere_is_watertight_genus_zero() {
    let rec = run(blue(Surface::Sphere(1.0), 4000, 3), closing_params(), 3);
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert!(t.watertight, "{t:?}");
    assert_eq!(t.genus, Some(0));
    // Outward orientation (ASSUMPTION A9): positive signed volume.
    let v: f64 = rec
        .mesh
        .faces()
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| rec.mesh.vertices()[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!(v > 3.5, "signed volume {v}");
}

#[test]
fn open_sheet_keeps_one_boundary_loop() {
    let s = Surface::Sheet {
        size: 4.0,
        amp: 0.3,
    };
    let rec = run(blue(s, 5000, 4), closing_params(), 4);
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert_eq!(t.n_boundary_loops(), 1, "{t:?}");
    assert_eq!(t.genus, Some(0));
    let d = &rec.diagnostics;
    assert_eq!(
        d.get("boundary_loops"),
        Some(&reconbench_geom::method::Diagnostic::Number(1.0))
    );
}

/// 20 % uniform outliers on a blue-noise sphere: (outlier recall, one-sided Hausdorff
/// distance noisy mesh -> clean mesh as a fraction of the diagonal).
fn outlier_run(n: usize, w1: f64) -> (f64, f64) {
    let surf = Surface::Sphere(1.0);
    let clean = blue(surf, n, 5);
    let params = PriorityFrontParams {
        w1,
        ..closing_params()
    };
    let clean_rec = run(clean.clone(), params.clone(), 5);
    let mut rng = ChaCha8Rng::seed_from_u64(55);
    let out = uniform_outliers(&clean, clean.len() / 5, &mut rng);
    let n_clean = clean.len();
    let mut noisy = clean;
    noisy.extend_from_slice(&out);
    let rec = run(noisy, params, 5);
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    // Outliers are the indices >= n_clean.
    let refused_out = rec
        .refused
        .iter()
        .filter(|&&i| i as usize >= n_clean)
        .count();
    let recall = refused_out as f64 / out.len() as f64;
    let bvh = MeshBvh::new(&clean_rec.mesh).expect("bvh");
    let diag = 2.0 * 3f64.sqrt();
    let mut worst = 0.0f64;
    for f in rec.mesh.faces() {
        let [a, b, c] = f.map(|i| rec.mesh.vertices()[i as usize]);
        for q in [a, b, c, (a + b + c) / 3.0] {
            worst = worst.max(bvh.distance(q).expect("distance"));
        }
    }
    // Symmetric: also clean mesh -> noisy mesh (a hole in the noisy run shows here).
    let bvh_noisy = MeshBvh::new(&rec.mesh).expect("bvh");
    for f in clean_rec.mesh.faces() {
        let [a, b, c] = f.map(|i| clean_rec.mesh.vertices()[i as usize]);
        for q in [a, b, c, (a + b + c) / 3.0] {
            worst = worst.max(bvh_noisy.distance(q).expect("distance"));
        }
    }
    eprintln!(
        "outliers n={n} w1={w1}: recall {recall:.4}, Hausdorff {:.5} diag, loops {}",
        worst / diag,
        t.n_boundary_loops()
    );
    (recall, worst / diag)
}

/// Issue 8 targets with default parameters (w1 = 1): >= 95 % of outliers refused and
/// the symmetric Hausdorff distance between the noisy and the clean run <= 1 % of the
/// diagonal. Needs IMPL-CHOICE I5 (elevation / height bound of Free candidates); with
/// the paper's rules alone recall was 0.34 here.
#[test]
fn outliers_twenty_percent_issue_targets() {
    let (recall, h) = outlier_run(4000, 1.0);
    assert!(recall >= 0.95, "outlier recall {recall}");
    assert!(h <= 0.01, "Hausdorff {h} of the diagonal");
}

/// The paper's advice for noisy data (w1 = 3) on a denser sphere. Measured with the
/// issue-20 default `reject_free_inside`: recall 0.972, Hausdorff 0.0186 of the diagonal
/// (one chain of four outliers 0.01-0.064 above the sphere); before it 0.987 / 0.0037.
/// An outlier within 0.5 ρ of a triangle's plane now blocks the triangle and is often
/// meshed later instead of being left under it. Over `li_outliers` (w1 = 1, 2 seeds)
/// the change costs 0.2-1.1 points of recall and brings topology_ok at 30-40 % from
/// 0-0.5 to 1 (docs/methods/priority_front.md, "Real data").
#[test]
fn outliers_twenty_percent_w1_three() {
    let (recall, h) = outlier_run(16_000, 3.0);
    assert!(recall >= 0.96, "outlier recall {recall}");
    assert!(h <= 0.02, "Hausdorff {h} of the diagonal");
}

/// I5 is what brings the recall up: with the elevation / height bound off (the
/// paper's rules only) far fewer outliers are refused on the same input.
#[test]
fn outlier_recall_needs_the_elevation_bound() {
    let surf = Surface::Sphere(1.0);
    let clean = blue(surf, 4000, 5);
    let mut rng = ChaCha8Rng::seed_from_u64(55);
    let out = uniform_outliers(&clean, clean.len() / 5, &mut rng);
    let mut noisy = clean;
    noisy.extend_from_slice(&out);
    let recall = |p: PriorityFrontParams| {
        let rec = run(noisy.clone(), p, 5);
        rec.refused.iter().filter(|&&i| i >= 4000).count() as f64 / out.len() as f64
    };
    let on = recall(closing_params());
    let off = recall(PriorityFrontParams {
        free_elevation_max_deg: 90.0,
        free_height_max: 1000.0,
        ..closing_params()
    });
    assert!(
        on >= 0.95 && off < on - 0.2,
        "recall with I5 {on}, without {off}"
    );
}

#[test]
fn uniform_random_input_stays_manifold_with_default_params() {
    let pts = Surface::Torus(1.0, 0.4).sample_uniform(4000, &mut ChaCha8Rng::seed_from_u64(6));
    let rec = run(pts, PriorityFrontParams::default(), 6);
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert!(rec.mesh.n_faces() > 6000, "faces {}", rec.mesh.n_faces());
}

#[test]
fn degenerate_inputs_do_not_panic() {
    let pf = PriorityFront::default();
    let mut ctx = RunCtx::new(1);
    // Fewer than 3 points: a clear error.
    let two = PointCloud::new(vec![DVec3::ZERO, DVec3::X]).expect("cloud");
    assert!(matches!(
        pf.reconstruct(&two, &mut ctx),
        Err(MethodError::InvalidInput(_))
    ));
    // Collinear points: empty mesh, every point refused.
    let line: Vec<DVec3> = (0..50).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
    let rec = pf
        .reconstruct(&PointCloud::new(line).expect("cloud"), &mut ctx)
        .expect("collinear");
    assert_eq!(rec.mesh.n_faces(), 0);
    assert_eq!(rec.refused.len(), 50);
    // All points identical: empty mesh, every point refused.
    let same = vec![DVec3::ONE; 20];
    let rec = pf
        .reconstruct(&PointCloud::new(same).expect("cloud"), &mut ctx)
        .expect("duplicates");
    assert_eq!(rec.mesh.n_faces(), 0);
    assert_eq!(rec.refused.len(), 20);
    // A regular coplanar grid (many ties) with duplicated points.
    let mut grid: Vec<DVec3> = (0..900)
        .map(|i| DVec3::new((i % 30) as f64, (i / 30) as f64, 0.0))
        .collect();
    grid.extend_from_within(..100);
    let rec = pf
        .reconstruct(&PointCloud::new(grid).expect("cloud"), &mut ctx)
        .expect("grid");
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert!(rec.mesh.n_faces() > 1500, "faces {}", rec.mesh.n_faces());
    for i in 900..1000u32 {
        assert!(rec.refused.contains(&i), "duplicate {i} not refused");
    }
}

/// Extreme coordinate scales: the method runs on the exact power-of-two working-scale
/// copy, so at 1e±200 (where the spacing estimate's squared distances would over- or
/// underflow) it still meshes the sphere on the input's own points, and at 2^±40 (exact
/// scalings) the mesh is the unscaled one.
#[test]
fn extreme_coordinate_scales_mesh_on_the_input_points() {
    let pts = blue(Surface::Sphere(1.0), 1500, 4);
    let pf = PriorityFront::default();
    let at = |s: f64| {
        let cloud = PointCloud::new(pts.iter().map(|p| *p * s).collect()).expect("cloud");
        pf.reconstruct(&cloud, &mut RunCtx::new(1))
    };
    let base = at(1.0).expect("unit scale");
    assert!(base.mesh.n_faces() > 2000);
    for s in [2f64.powi(40), 2f64.powi(-40)] {
        let rec = at(s).expect("scaled by a power of two");
        assert_eq!(rec.mesh.faces(), base.mesh.faces(), "scale {s:e}");
    }
    for s in [1e200, 1e-200] {
        let rec = at(s).unwrap_or_else(|e| panic!("scale {s:e}: {e}"));
        assert!(
            rec.mesh.n_faces() > 2000,
            "scale {s:e}: {} faces",
            rec.mesh.n_faces()
        );
        let want: Vec<DVec3> = pts.iter().map(|p| *p * s).collect();
        assert_eq!(rec.mesh.vertices(), &want[..], "scale {s:e}: input points");
        // (`analyze` calls every face degenerate at 1e200: its areas overflow.)
        let t = analyze(&rec.mesh);
        assert!(t.watertight && t.genus == Some(0), "scale {s:e}: {t:?}");
        assert_eq!(t.non_manifold_edges + t.non_manifold_vertices, 0, "{t:?}");
    }
}

#[test]
fn deterministic_for_fixed_seed_and_thread_count() {
    let pts = blue(Surface::Torus(1.0, 0.35), 4000, 7);
    for threads in [1, 2] {
        let p = PriorityFrontParams {
            threads,
            ..closing_params()
        };
        let a = run(pts.clone(), p.clone(), 9);
        let b = run(pts.clone(), p, 9);
        assert_eq!(a.mesh.faces(), b.mesh.faces(), "threads {threads}");
        assert_eq!(a.refused, b.refused);
    }
}

#[test]
fn two_threads_give_a_manifold_closed_torus() {
    let pts = blue(Surface::Torus(1.0, 0.35), 6000, 8);
    let rec = run(
        pts,
        PriorityFrontParams {
            threads: 2,
            ..closing_params()
        },
        8,
    );
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert_eq!(t.components, 1, "{t:?}");
    // The Free band along the slab cut lets the slab fronts meet: no strip holes.
    assert!(t.watertight, "{t:?}");
    assert_eq!(t.genus, Some(1));
}

#[test]
fn params_serde_defaults_and_validation() {
    let p: PriorityFrontParams = serde_json::from_str("{}").expect("defaults");
    assert_eq!(p, PriorityFrontParams::default());
    assert_eq!(p.k, 4.0);
    assert_eq!(p.alpha_max_deg, 120.0);
    assert_eq!(p.beta_max_deg, 90.0);
    assert_eq!((p.w1, p.w2, p.w3), (1.0, 1.0, 1.0));
    assert_eq!(p.threads, 1);
    assert!(!p.apex_angle_rule);
    assert!(serde_json::from_str::<PriorityFrontParams>(r#"{"kk": 3}"#).is_err());
    let p: PriorityFrontParams =
        serde_json::from_str(r#"{"rho_sample": "fixed100", "score_distance": "segment"}"#)
            .expect("enums");
    assert_eq!(
        p.rho_sample,
        reconbench_recon::priority_front::RhoSample::Fixed100
    );
    let bad = PriorityFrontParams {
        k: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        PriorityFront::new(bad),
        Err(MethodError::InvalidParameter { .. })
    ));
    // The regrowth depths of I20-I22 are bounded (each depth costs a front rebuild).
    for set in [
        |p: &mut PriorityFrontParams| p.regrow_loops_depth = 9,
        |p: &mut PriorityFrontParams| p.regrow_points_depth = 9,
        |p: &mut PriorityFrontParams| p.regrow_handles_depth = 9,
    ] {
        let mut p = PriorityFrontParams::default();
        set(&mut p);
        let name = match PriorityFront::new(p) {
            Err(MethodError::InvalidParameter { name, .. }) => name,
            other => panic!("depth 9 accepted: {:?}", other.is_ok()),
        };
        assert!(
            name.starts_with("regrow_") && name.ends_with("_depth"),
            "{name}"
        );
    }
    assert_eq!(PriorityFront::default().name(), NAME);
    assert_eq!(NAME, "priority-front");
}

#[test]
fn zero_budget_stops_cleanly() {
    let pts = blue(Surface::Sphere(1.0), 20_000, 10);
    let cloud = PointCloud::new(pts).expect("cloud");
    let mut ctx = RunCtx::new(1).with_budget(Duration::ZERO);
    let r = PriorityFront::default().reconstruct(&cloud, &mut ctx);
    assert!(matches!(r, Err(MethodError::Stopped(_))), "{r:?}");
}

#[test]
fn diagnostics_and_phases_are_reported() {
    let pts = blue(Surface::Sphere(1.0), 2000, 11);
    let cloud = PointCloud::new(pts).expect("cloud");
    let mut ctx = RunCtx::new(1);
    let rec = PriorityFront::new(closing_params())
        .expect("params")
        .reconstruct(&cloud, &mut ctx)
        .expect("run");
    for k in [
        "seeds",
        "triangles",
        "front_edges_processed",
        "joins",
        "fills",
        "links",
        "glues",
        "refused_points",
        "boundary_loops",
        "triangles_per_second",
        "rho",
        "assumptions",
    ] {
        assert!(rec.diagnostics.contains_key(k), "missing diagnostic {k}");
    }
    for ph in ["density", "grid", "grow", "output"] {
        assert!(
            ctx.phases().iter().any(|(n, _)| n == ph),
            "missing phase {ph}"
        );
    }
}

/// A synthetic CAD-like cloud from `reconbench-synth` (`shape` spec, sampler, count).
fn synth_cloud(shape: &str, blue_noise: bool, n: usize, seed: u64) -> Vec<DVec3> {
    use reconbench_synth::{DatasetSpec, Density, SamplerSpec, ShapeSpec};
    let spec = DatasetSpec {
        shape: shape.parse::<ShapeSpec>().expect("shape spec"),
        sampler: if blue_noise {
            SamplerSpec::BlueNoise { oversample: 5.0 }
        } else {
            SamplerSpec::Uniform
        },
        density: Density::Count(n),
        perturbations: Vec::new(),
        scan: None,
    };
    reconbench_synth::generate(&spec, seed)
        .expect("synthetic cloud")
        .positions
}

/// Sharp features (issue 8 regression): clean blue-noise box (90 deg creases),
/// fandisk-like (30-150 deg) and cube-with-hole (90 deg, genus 1) at 8,000 points give
/// watertight meshes of the right genus with at most 2 % refused points. The I5 height
/// cap alone (0.5 rho above the tangent plane at the edge midpoint) rejects Free points
/// just across a crease; IMPL-CHOICE I8 (support plane through the candidate) lets them
/// in.
#[test]
fn creases_are_meshed_watertight_with_few_refused_points() {
    for (shape, genus) in [("box", 0), ("fandisk-like", 0), ("cube-with-hole", 1)] {
        let pts = synth_cloud(shape, true, 8000, 1);
        let rec = run(pts, PriorityFrontParams::default(), 0);
        let t = analyze(&rec.mesh);
        assert_manifold_oriented(&t);
        assert!(t.watertight, "{shape}: {t:?}");
        assert_eq!(t.components, 1, "{shape}: {t:?}");
        assert_eq!(t.genus, Some(genus), "{shape}: {t:?}");
        let share = rec.refused.len() as f64 / 8000.0;
        eprintln!("{shape}: refused {} ({share:.4})", rec.refused.len());
        assert!(share <= 0.02, "{shape}: refused share {share}");
    }
}

/// The lead's regression case: a uniform-random 6,000-point box (seed 1). With the I5
/// height cap alone 597 points (10 %) were refused, most of them along the creases the
/// front could not cross; with the I8 support test at most 2 %.
#[test]
fn uniform_box_crease_regression() {
    let pts = synth_cloud("box", false, 6000, 1);
    // I8's evidence was measured without `reject_free_inside` (the default since issue
    // 20, which keeps points from being covered and refuses 66-80 here either way) and
    // without I14 / I15 (with I14 I8 refuses about 600 points here: triangles across a
    // crease that would cross the other face's mesh; I15 then inserts them, below).
    let refused = |k: usize| {
        let p = PriorityFrontParams {
            support_neighbours: k,
            reject_free_inside: false,
            self_intersection_check: false,
            insert_covered: false,
            ..PriorityFrontParams::default()
        };
        let rec = run(pts.clone(), p, 0);
        let t = analyze(&rec.mesh);
        assert_manifold_oriented(&t);
        rec.refused.len()
    };
    let (on, off) = (refused(12), refused(0));
    assert!(
        on <= 120 && off > 3 * on,
        "refused with I8 {on}, without {off}"
    );
    let rec = run(pts.clone(), PriorityFrontParams::default(), 0);
    assert!(rec.refused.len() <= 120, "defaults: {}", rec.refused.len());
}

/// The 2-thread stitch used to leave a thin ring slit around the tube at the far edge of
/// a slab band on some inputs (two parallel loops of ~25 vertices 0.4 rho apart, edges
/// up to 9 rho): the harness torus `torus:R=2,r=0.7`, 35,947 blue-noise points, seed 3.
/// IMPL-CHOICE I9 (`stitch_zip`) zips such loop pairs; without it (and without I16) the
/// mesh keeps boundary loops (checked too, so the test sees the fix work). I16 removes
/// the cause: the two slabs' pieces had opposite orientations. Measured with I14 and
/// I15 off.
#[test]
fn two_thread_stitch_closes_the_band_on_a_36k_torus() {
    let pts = synth_cloud("torus:R=2,r=0.7", true, 35_947, 3);
    let p = PriorityFrontParams {
        threads: 2,
        self_intersection_check: false,
        insert_covered: false,
        ..PriorityFrontParams::default()
    };
    let rec = run(pts.clone(), p.clone(), 0);
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert!(t.watertight, "{t:?}");
    assert_eq!(t.genus, Some(1), "{t:?}");
    // The slit the zip closes comes from slab pieces grown with opposite orientations
    // (A9 orients a seed on the inner ring towards the centroid): with both the zip and
    // I16 off the band keeps loops; with I16 alone the fronts merge.
    let off = run(
        pts.clone(),
        PriorityFrontParams {
            stitch_zip: false,
            seed_orient_front: false,
            ..p.clone()
        },
        0,
    );
    let t_off = analyze(&off.mesh);
    assert_manifold_oriented(&t_off);
    assert!(t_off.n_boundary_loops() > 0, "{t_off:?}");
    // The zip only adds triangles over the slit: no point changes state.
    let zip_only = run(
        pts.clone(),
        PriorityFrontParams {
            seed_orient_front: false,
            ..p.clone()
        },
        0,
    );
    assert_eq!(zip_only.refused, off.refused);
    assert!(zip_only.mesh.n_faces() > off.mesh.n_faces());
    let i16_only = run(
        pts,
        PriorityFrontParams {
            stitch_zip: false,
            ..p
        },
        0,
    );
    let t16 = analyze(&i16_only.mesh);
    assert!(t16.watertight && t16.genus == Some(1), "{t16:?}");
}

/// I9 zips loops that lie side by side on the surface, not the boundaries of two
/// stacked sheets closer than 2R: with 2 threads the two sheets stay two components
/// with one boundary loop each, as with `stitch_zip` off.
#[test]
fn stitch_zip_keeps_stacked_sheets_apart() {
    let pts = blue(Surface::TwoSheets { gap: 0.05 }, 12_000, 4);
    let mk = |zip: bool| {
        run(
            pts.clone(),
            PriorityFrontParams {
                threads: 2,
                stitch_zip: zip,
                ..PriorityFrontParams::default()
            },
            4,
        )
    };
    let (on, off) = (mk(true), mk(false));
    let t = analyze(&on.mesh);
    assert_manifold_oriented(&t);
    assert_eq!(t.components, 2, "{t:?}");
    assert_eq!(t.n_boundary_loops(), 2, "{t:?}");
    assert_eq!(on.mesh.faces(), off.mesh.faces());
}
