//! Tests of `hc-it` (spec 003): an open sheet, a closed sphere, the first-triangle
//! orientation by k, the spare part's bolt holes (the closure pass against the literal
//! sweep), the scan-like stand-ins of `reconbench-synth`, bad input and determinism under
//! a shuffled input order.

use std::f64::consts::PI;

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Describe, Diagnostic, Reconstruction, Reconstructor, RunCtx};
use reconbench_geom::topology::analyze;
use reconbench_recon::hc_it::cluster::UnionFind;
use reconbench_recon::hc_it::{
    Closure, ConflictRule, EdgeDistance, HcIt, HcItParams, WinnerScan, sweep_order,
};
// The golden hashes below refer to these exact points (shared with the bench and
// `hcit_run`).
use reconbench_testkit::hc_it_inputs::{
    golden_spiral_sphere as sphere, jittered_sheet as sheet, wavy,
};

fn run(p: &[DVec3], params: HcItParams) -> Reconstruction {
    let m = HcIt::from_params(params).unwrap();
    m.reconstruct(&PointCloud::new(p.to_vec()).unwrap(), &mut RunCtx::new(1))
        .unwrap()
}

fn num(r: &Reconstruction, k: &str) -> f64 {
    match r.diagnostics.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        other => panic!("diagnostic {k}: {other:?}"),
    }
}

fn with_rho(rho: f64) -> HcItParams {
    HcItParams {
        rho,
        ..Default::default()
    }
}

#[test]
fn open_sheet_gives_one_boundary_loop_and_a_manifold_mesh() {
    let pts = sheet(30, wavy);
    let r = run(&pts, with_rho(3.0));
    let t = analyze(&r.mesh);
    assert_eq!(t.n_boundary_loops(), 1, "{:?}", t.boundary_loops);
    assert_eq!(t.components, 1);
    assert_eq!(t.non_manifold_edges, 0);
    assert!(t.consistently_oriented);
    assert_eq!(num(&r, "nc_meshes"), 1.0);
    // Measured 1533 faces and 101 unmeshed points (the sweep's first column and points
    // that joined only through case 1); a complete grid mesh has 2 * 29^2 = 1682 faces.
    assert!(t.faces > 1400, "{} faces", t.faces);
    assert!(num(&r, "unmeshed") < 150.0);
    assert_eq!(r.refused.len() as f64, num(&r, "unmeshed"));
    // The sheet's normals agree with k = +z: the first triangle was oriented by k and
    // the growth keeps the orientation, up to a few folded faces.
    let up = (0..r.mesh.n_faces())
        .filter(|&f| r.mesh.face_normal(f).z > 0.0)
        .count();
    // Measured: 1531 of 1533 (two faces folded by the sweep).
    assert!(
        up as f64 >= 0.995 * r.mesh.n_faces() as f64,
        "{up} of {}",
        r.mesh.n_faces()
    );
    // Edges much longer than rho: the literal winner search falls back to every BTM
    // edge of the NC when none is at P's rho-neighbours, which bridges (measured: 7
    // face-edges above 4 rho, 17 above 2 rho).
    let rho = num(&r, "rho_abs");
    let long = r
        .mesh
        .faces()
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k] as usize, f[(k + 1) % 3] as usize)))
        .filter(|&(a, b)| (pts[a] - pts[b]).length() > 4.0 * rho)
        .count();
    assert!(long <= 12, "{long} face-edges above 4 rho");
}

#[test]
fn reference_vector_orients_the_sheet() {
    let pts = sheet(12, wavy);
    let down = HcItParams {
        reference: [0.0, 0.0, -1.0],
        ..with_rho(3.0)
    };
    let r = run(&pts, down);
    assert!(r.mesh.n_faces() > 100);
    for f in 0..r.mesh.n_faces() {
        assert!(r.mesh.face_normal(f).z < 0.0, "face {f}");
    }
}

#[test]
fn sheet_at_rho_two_stays_manifold() {
    for rho in [1.5, 2.0] {
        // The literal sweep is manifold at every vertex.
        let r = run(&sheet(30, wavy), literal(rho));
        let t = analyze(&r.mesh);
        assert_eq!(t.non_manifold_edges, 0, "rho {rho}");
        assert_eq!(t.non_manifold_vertices, 0, "rho {rho}");
        assert!(t.consistently_oriented, "rho {rho}");
        // The closure pass keeps every edge and every vertex manifold and the
        // orientation consistent, and joins the sweep's pieces.
        let z = run(&sheet(30, wavy), with_rho(rho));
        let tz = analyze(&z.mesh);
        eprintln!(
            "rho {rho}: literal {} pieces, zip {} pieces {} loops",
            t.components,
            tz.components,
            tz.n_boundary_loops()
        );
        assert_eq!(tz.non_manifold_edges, 0, "rho {rho}");
        assert_eq!(tz.non_manifold_vertices, 0, "rho {rho}");
        assert!(tz.consistently_oriented, "rho {rho}");
        // Pieces the sweep left touching only at a vertex stay apart (measured: 115 -> 10
        // pieces at rho = 1.5, 2 -> 4 at rho = 2).
        assert!(tz.components <= t.components.max(4), "rho {rho}");
        assert!(tz.faces > t.faces, "rho {rho}");
    }
}

#[test]
fn closed_sphere_gives_a_nearly_closed_mesh() {
    let pts = sphere(1500);
    let r = run(&pts, with_rho(2.0));
    let t = analyze(&r.mesh);
    // Measured: 2995 faces of the 2996 = 2n - 4 of a closed triangulation, one small
    // boundary loop, no unmeshed point.
    assert_eq!(t.components, 1);
    assert_eq!(t.non_manifold_edges, 0);
    assert!(t.consistently_oriented);
    assert!(t.faces >= 2980, "{} faces", t.faces);
    assert!(t.n_boundary_loops() <= 2, "{:?}", t.boundary_loops);
    let open: usize = t.boundary_loops.iter().map(|l| l.vertices).sum();
    assert!(open <= 12, "{open} boundary vertices");
    assert!(num(&r, "unmeshed") <= 3.0);
    // Interpolating: every mesh vertex is an input point, unchanged.
    assert_eq!(r.mesh.vertices(), &pts[..]);
}

#[test]
fn literal_variants_run_and_stay_manifold() {
    let pts = sheet(16, wavy);
    let lit = HcItParams {
        edge_distance: EdgeDistance::Literal,
        winner_scan: WinnerScan::All,
        conflict_rule: ConflictRule::Phi,
        ear_max_edge: 0.0,
        strict_rho: true,
        ..with_rho(3.0)
    };
    let bare = HcItParams {
        neighbourhood: false,
        flips: false,
        closure: Closure::None,
        ..with_rho(3.0)
    };
    for p in [lit, bare] {
        let r = run(&pts, p.clone());
        let t = analyze(&r.mesh);
        assert!(t.faces > 100, "{p:?}: {} faces", t.faces);
        assert_eq!(t.non_manifold_edges, 0, "{p:?}");
        assert!(t.consistently_oriented, "{p:?}");
        if !p.flips {
            assert_eq!(num(&r, "flips"), 0.0);
            assert_eq!(num(&r, "neighbourhood_triangles"), 0.0);
        }
    }
}

#[test]
fn shuffled_input_gives_the_same_mesh() {
    let pts = sheet(20, wavy);
    let a = run(&pts, with_rho(2.5));
    let b = run(&pts, with_rho(2.5));
    assert_eq!(a.mesh.faces(), b.mesh.faces());
    assert_eq!(a.diagnostics, b.diagnostics);
    // A fixed permutation of the input: the same triangles up to the relabelling.
    let n = pts.len();
    let perm: Vec<usize> = (0..n).map(|i| (i * 173 + 29) % n).collect();
    let shuffled: Vec<DVec3> = perm.iter().map(|&i| pts[i]).collect();
    let c = run(&shuffled, with_rho(2.5));
    let canon = |faces: &[[u32; 3]], map: &dyn Fn(u32) -> u32| {
        let mut v: Vec<[u32; 3]> = faces
            .iter()
            .map(|f| {
                let g = f.map(map);
                let k = (0..3).min_by_key(|&k| g[k]).unwrap();
                [g[k], g[(k + 1) % 3], g[(k + 2) % 3]]
            })
            .collect();
        v.sort_unstable();
        v
    };
    let fa = canon(a.mesh.faces(), &|v| v);
    let fc = canon(c.mesh.faces(), &|v| perm[v as usize] as u32);
    assert_eq!(fa, fc);
}

#[test]
fn sweep_order_breaks_ties_by_y_then_z() {
    let p = [
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 1.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, 0.0, 5.0),
    ];
    assert_eq!(sweep_order(&p), [3, 2, 1, 0]);
}

#[test]
fn union_find_merges_and_counts() {
    let mut u = UnionFind::new(5);
    let r = u.union(0, 1);
    assert_eq!(u.size(r), 2);
    let r = u.union(3, 1);
    assert_eq!(u.size(r), 3);
    assert_eq!(u.find(0), u.find(3));
    assert_ne!(u.find(2), u.find(0));
    u.shrink(r);
    let r0 = u.find(0);
    assert_eq!(u.size(r0), 2);
}

#[test]
fn bad_input_is_an_error_naming_the_problem() {
    let m = HcIt::default();
    let mut ctx = RunCtx::new(1);
    let err = |p: Vec<DVec3>, ctx: &mut RunCtx| {
        m.reconstruct(&PointCloud::new(p).unwrap(), ctx)
            .unwrap_err()
            .to_string()
    };
    assert!(err(vec![], &mut ctx).contains("at least 3"));
    assert!(err(vec![DVec3::X, DVec3::Y], &mut ctx).contains("at least 3"));
    let mut p = sheet(5, wavy);
    p.push(p[3]);
    assert!(err(p, &mut ctx).contains("coincide"));
    if let Ok(c) = PointCloud::new(vec![DVec3::X, DVec3::Y, DVec3::new(f64::NAN, 0.0, 0.0)]) {
        let e = m.reconstruct(&c, &mut ctx).unwrap_err().to_string();
        assert!(e.contains("non-finite"), "{e}");
    }
    // Collinear points: no triangle, no panic.
    let line: Vec<DVec3> = (0..10).map(|i| DVec3::X * i as f64).collect();
    let r = m
        .reconstruct(&PointCloud::new(line).unwrap(), &mut ctx)
        .unwrap();
    assert_eq!(r.mesh.n_faces(), 0);
    assert_eq!(r.refused.len(), 10);
    for (bad, name) in [
        (
            HcItParams {
                rho: 0.0,
                ..Default::default()
            },
            "rho",
        ),
        (
            HcItParams {
                psi_rad: PI,
                ..Default::default()
            },
            "psi_rad",
        ),
        (
            HcItParams {
                reference: [0.0; 3],
                ..Default::default()
            },
            "reference",
        ),
    ] {
        let e = HcIt::from_params(bad).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}

/// A flat 40 x 40 jittered plate with two bolt holes of radius 0.12 (spacing 0.025).
const HOLES: [(f64, f64); 2] = [(0.3, 0.5), (0.7, 0.5)];

fn bolt_plate() -> Vec<DVec3> {
    sheet(40, |_, _| 0.0)
        .into_iter()
        .filter(|p| {
            HOLES
                .iter()
                .all(|&(cx, cy)| (p.x - cx).hypot(p.y - cy) > 0.12)
        })
        .collect()
}

/// Faces with their centroid within `r` of a bolt-hole centre.
fn faces_in_holes(r: &Reconstruction, pts: &[DVec3], within: f64) -> usize {
    r.mesh
        .faces()
        .iter()
        .filter(|f| {
            let c = (pts[f[0] as usize] + pts[f[1] as usize] + pts[f[2] as usize]) / 3.0;
            HOLES
                .iter()
                .any(|&(cx, cy)| (c.x - cx).hypot(c.y - cy) < within)
        })
        .count()
}

fn literal(rho: f64) -> HcItParams {
    HcItParams {
        closure: Closure::None,
        ..with_rho(rho)
    }
}

#[test]
fn spare_part_keeps_exactly_its_two_bolt_holes() {
    let pts = bolt_plate();
    // At rho = 2. Measured at rho = 3: one piece, but 7 loops (4 small cracks the pass
    // cannot close next to long sweep edges); docs/methods/hc_it.md.
    let r = run(&pts, with_rho(2.0));
    let t = analyze(&r.mesh);
    // The closure pass zips the sweep's cracks: the outer rim and the two holes are each
    // their own loop, and every vertex is manifold. Measured: 2 pieces, 4 loops (a piece
    // the sweep split off along a crack and the pass could not join without leaving a
    // two-fan vertex keeps its own loop); the catalogue's `bolt-plate` grid gets exactly
    // 3 (`scan_like_standins_...`).
    eprintln!("jittered plate: {} pieces", t.components);
    assert!(t.components <= 2);
    let n_loops = t.n_boundary_loops();
    assert!((3..=4).contains(&n_loops), "{:?}", t.boundary_loops);
    assert_eq!(t.non_manifold_edges, 0);
    assert_eq!(t.non_manifold_vertices, 0);
    assert!(t.consistently_oriented);
    // No triangle covers a hole, and the two hole loops run round the holes: each has
    // about 2 pi 0.12 / 0.025 = 30 vertices.
    assert_eq!(faces_in_holes(&r, &pts, 0.11), 0);
    let sizes: Vec<usize> = t.boundary_loops.iter().map(|l| l.vertices).collect();
    let holes = sizes.iter().filter(|&&k| (20..=45).contains(&k)).count();
    assert_eq!(holes, 2, "{sizes:?}");
    assert!(num(&r, "unmeshed") < num(&r, "sweep_unmeshed"));
    assert!(num(&r, "zip_triangles") > 0.0);
}

#[test]
fn literal_sweep_joins_the_bolt_holes_to_the_rim() {
    // The literal method (no closure pass): cracks of unmeshed points, left where the
    // sweep's NCs start and meet around the holes, join the holes to the outer boundary.
    // Measured at rho = 2: 2 components, 2 loops (79 and 175 vertices).
    let pts = bolt_plate();
    let r = run(&pts, literal(2.0));
    let t = analyze(&r.mesh);
    assert_eq!(t.non_manifold_edges, 0);
    assert!(t.faces > 2000, "{} faces", t.faces);
    assert_eq!(faces_in_holes(&r, &pts, 0.1), 0);
    assert!(t.n_boundary_loops() < 3, "{:?}", t.boundary_loops);
    assert_eq!(num(&r, "zip_triangles"), 0.0);
    assert_eq!(num(&r, "unmeshed"), num(&r, "sweep_unmeshed"));
}

#[test]
fn bolt_holes_stay_open_for_wider_zip_radii() {
    // A ball of radius 3 rho = 6 spacings would pass a bolt hole (4.8 spacings), but the
    // pass covers gaps only from their rims' edges, under the fold and overlap tests and
    // small loops alone by ear clipping: the holes stay open.
    let pts = bolt_plate();
    let wide = HcItParams {
        zip_radius: 3.0,
        ..with_rho(2.0)
    };
    let r = run(&pts, wide);
    assert_eq!(faces_in_holes(&r, &pts, 0.11), 0);
    let e = HcIt::from_params(HcItParams {
        zip_radius: 0.0,
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("zip_radius"), "{e}");
}

/// The scan-like grid of a catalogue shape at about `n` points.
fn standin_grid(name: &str, n: usize) -> (Box<dyn reconbench_synth::Shape>, Vec<DVec3>) {
    let s = reconbench_synth::shapes::from_spec(name).unwrap();
    let (nu, nv) = s.grid_dims_for_count(n);
    let pts = s
        .parametric_grid(nu, nv)
        .unwrap()
        .into_iter()
        .map(|x| x.position)
        .collect();
    (s, pts)
}

#[test]
fn scan_like_standins_are_meshed_in_one_piece_with_their_holes_open() {
    // The spare part and face 2 at the paper's point counts, sampled as a range image
    // from +z. The literal sweep leaves half of the exact grid unmeshed or splits it into
    // pieces; with the closure pass: one piece, almost every point meshed, no face over a
    // hole. Measured at rho = 2: spare part 8 loops, face 2 151 loops (the hole loops
    // plus small cracks along the grid lines the pass cannot close; docs/methods/hc_it.md).
    for (name, n) in [("bolt-plate", 6642), ("eye-face", 17_992)] {
        let (s, pts) = standin_grid(name, n);
        assert_eq!(s.boundary_loops(), 3);
        assert!(
            pts.len().abs_diff(n) < n / 20,
            "{name}: {} points",
            pts.len()
        );
        let lr = run(&pts, literal(2.0));
        let lit = analyze(&lr.mesh);
        let r = run(&pts, with_rho(2.0));
        let t = analyze(&r.mesh);
        eprintln!(
            "{name}: literal {} loops {} pieces; zip {} loops {} pieces",
            lit.n_boundary_loops(),
            lit.components,
            t.n_boundary_loops(),
            t.components
        );
        // Measured at rho = 2: spare part 3 loops (the truth) in 2 pieces, face 2 9 loops
        // in 2 pieces; 0 non-manifold vertices (before the slit split and the fan rules:
        // 8 and 151 loops, 66 and 117 non-manifold vertices).
        assert!(t.components <= 2, "{name}");
        assert!(lit.components >= t.components, "{name}");
        assert!(t.n_boundary_loops() as u32 >= s.boundary_loops(), "{name}");
        let most = if name == "bolt-plate" { 3 } else { 12 };
        assert!(t.n_boundary_loops() <= most, "{name}");
        assert_eq!(t.non_manifold_edges, 0, "{name}");
        assert_eq!(t.non_manifold_vertices, 0, "{name}");
        assert!(num(&r, "unmeshed") < 0.02 * pts.len() as f64, "{name}");
        // No face over a hole from the pass: a face across a hole (or a bridge of the
        // sweep's winner fallback) has its centroid off the true surface; the pass adds
        // none (measured at rho = 2: 2 on each, all from the sweep).
        let spacing = num(&r, "spacing");
        let off = |m: &reconbench_geom::TriMesh| {
            (0..m.n_faces())
                .filter(|&f| {
                    let [a, b, c] = m.triangle(f);
                    s.distance((a + b + c) / 3.0) > 0.25 * spacing
                })
                .count()
        };
        assert!(off(&r.mesh) <= off(&lr.mesh), "{name}");
        // Interpolating, and on the true surface.
        for v in r.mesh.vertices().iter().step_by(97) {
            assert!(s.distance(*v) < 1e-12, "{name}");
        }
    }
}

#[test]
fn closed_grooved_handle_is_joined_into_one_piece() {
    // The pan handle (closed, 0 holes) from its ring grid at rho = 3: the literal sweep
    // gives 4 pieces. The closure pass meshes almost every point with manifold vertices
    // but cannot join pieces the sweep started with opposite orientation (failure mode 4):
    // measured 5 pieces, 9 loops. At rho = 2 the ring grid (1.03 mm along a ring, 1.97 mm
    // between rings, mean spacing pulled down by the crowded poles) never reaches across
    // rings: 150 pieces (docs/methods/hc_it.md).
    let (s, pts) = standin_grid("grooved-handle", 5271);
    assert!(s.is_closed() && s.boundary_loops() == 0);
    let lit = analyze(&run(&pts, literal(3.0)).mesh);
    let r = run(&pts, with_rho(3.0));
    let t = analyze(&r.mesh);
    assert_eq!(t.non_manifold_edges, 0);
    assert_eq!(t.non_manifold_vertices, 0);
    assert!(lit.components > 1);
    assert!(t.components <= 8, "{} pieces", t.components);
    let open: usize = t.boundary_loops.iter().map(|l| l.vertices).sum();
    assert!(open < pts.len() / 10, "{open} boundary vertices");
}

#[test]
fn orient_by_k_flips_components_against_k() {
    // ASSUMPTION H14: every component's area-weighted normal agrees with k afterwards,
    // the faces are the same up to orientation.
    let pts = sphere(1500);
    let base = run(&pts, with_rho(1.5));
    let k = DVec3::new(0.3, -0.2, 0.9).normalize();
    let p = HcItParams {
        reference: k.to_array(),
        orient_by_k: true,
        ..with_rho(1.5)
    };
    let plain = run(
        &pts,
        HcItParams {
            orient_by_k: false,
            ..p.clone()
        },
    );
    let r = run(&pts, p);
    let canon = |f: &[u32; 3]| {
        let mut g = *f;
        g.sort_unstable();
        g
    };
    let mut a: Vec<[u32; 3]> = plain.mesh.faces().iter().map(canon).collect();
    let mut b: Vec<[u32; 3]> = r.mesh.faces().iter().map(canon).collect();
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b);
    let flipped = r
        .mesh
        .faces()
        .iter()
        .zip(plain.mesh.faces())
        .filter(|(x, y)| x != y)
        .count();
    assert_eq!(flipped as f64, num(&r, "oriented_flips"));
    let topo = reconbench_geom::topology::MeshTopology::from_faces(pts.len(), r.mesh.faces());
    let (n, comp) = topo.face_components();
    let mut sum = vec![0.0; n];
    for f in 0..r.mesh.n_faces() {
        let [x, y, z] = r.mesh.triangle(f);
        sum[comp[f] as usize] += (y - x).cross(z - x).dot(k);
    }
    assert!(sum.iter().all(|&s| s >= 0.0), "{sum:?}");
    assert!(base.mesh.n_faces() > 0);
}

#[test]
fn slabs_and_portions() {
    let pts = sheet(30, wavy);
    let whole = run(&pts, with_rho(3.0));
    // ASSUMPTION H3: slabs covering everything, one sweep: the same mesh as no slabs.
    let swept = run(
        &pts,
        HcItParams {
            slabs: vec![0.0, 0.5, 1.0],
            ..with_rho(3.0)
        },
    );
    assert_eq!(whole.mesh.faces(), swept.mesh.faces());
    // A slab over the left half only: every point right of it is ignored.
    let xs: Vec<f64> = pts.iter().map(|p| p.x).collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let half = run(
        &pts,
        HcItParams {
            slabs: vec![0.0, 0.5],
            ..with_rho(3.0)
        },
    );
    let cut = lo + 0.5 * (hi - lo);
    let right = pts.iter().filter(|p| p.x > cut).count();
    assert_eq!(num(&half, "ignored"), right as f64);
    for f in half.mesh.faces() {
        for &v in f {
            assert!(pts[v as usize].x <= cut);
        }
    }
    // ASSUMPTION H15: two portions meshed separately and concatenated leave the seam
    // open: two components, more boundary, no triangle across the seam.
    let parts = run(
        &pts,
        HcItParams {
            slabs: vec![0.0, 0.5, 1.0],
            portions: true,
            ..with_rho(3.0)
        },
    );
    let (tw, tp) = (analyze(&whole.mesh), analyze(&parts.mesh));
    assert!(tp.components >= 2 && tp.components > tw.components);
    assert_eq!(tp.non_manifold_edges, 0);
    assert!(tp.boundary_edges > tw.boundary_edges);
    for f in parts.mesh.faces() {
        let left = f.iter().filter(|&&v| pts[v as usize].x <= cut).count();
        assert!(left == 0 || left == 3, "{f:?} crosses the seam");
    }
    eprintln!(
        "seam: whole {} faces {} boundary edges {} loops; portions {} faces {} boundary edges {} loops",
        tw.faces,
        tw.boundary_edges,
        tw.n_boundary_loops(),
        tp.faces,
        tp.boundary_edges,
        tp.n_boundary_loops()
    );
    let bad = HcIt::from_params(HcItParams {
        slabs: vec![0.5, 0.2],
        ..Default::default()
    });
    assert!(bad.unwrap_err().to_string().contains("slabs"));
}

#[test]
fn jittered_bolt_plate_grid_has_exactly_its_three_loops() {
    // The catalogue's spare part at the paper's count, its range-image grid moved in the
    // plate by up to 0.15 spacings (deterministic offsets, projected back on the shape):
    // the outer rim and the two bolt holes, one piece, every vertex manifold.
    let (s, grid) = standin_grid("bolt-plate", 6642);
    let sp = reconbench_geom::spatial::mean_spacing(&grid, 1).unwrap();
    let pts: Vec<DVec3> = grid
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let jx = ((i * 7) as f64 * 0.618_034).fract() - 0.5;
            let jy = ((i * 11) as f64 * 0.414_214).fract() - 0.5;
            s.closest_point(*p + DVec3::new(0.3 * sp * jx, 0.3 * sp * jy, 0.0))
                .point
        })
        .collect();
    let r = run(&pts, with_rho(2.0));
    let t = analyze(&r.mesh);
    assert_eq!(t.n_boundary_loops(), 3, "{:?}", t.boundary_loops);
    assert_eq!(t.components, 1);
    assert_eq!(t.non_manifold_edges, 0);
    assert_eq!(t.non_manifold_vertices, 0);
    assert!(num(&r, "unmeshed") < 0.01 * pts.len() as f64);
}

/// FNV-1a hash of the faces in order (their vertex indices as little-endian u32).
fn face_hash(r: &Reconstruction) -> u64 {
    let bytes: Vec<u8> = r
        .mesh
        .faces()
        .iter()
        .flat_map(|f| f.iter().flat_map(|v| v.to_le_bytes()))
        .collect();
    reconbench_geom::io::fnv1a64(&bytes)
}

/// The issue-24 speed work (incremental boundary bookkeeping, the zipping rounds'
/// failure cache, the per-NC boundary lists of the winner fallback) must not change a
/// single face: these hashes were computed with the code before it (commit 4b30d1a,
/// `tools/src/bin/hcit_run.rs`). The noisy height field exercises every step of the
/// closure pass (232 cut, 113 joined, 60 slit and 320 filled triangles), `winner_scan =
/// "all"` the whole-NC boundary scan at every point.
#[test]
fn faces_are_bit_identical_to_the_code_before_the_speed_work() {
    let literal_all = HcItParams {
        closure: Closure::None,
        winner_scan: WinnerScan::All,
        ..Default::default()
    };
    let literal = HcItParams {
        closure: Closure::None,
        ..Default::default()
    };
    let spec = reconbench_synth::DatasetSpec {
        shape: "height-field".parse().unwrap(),
        sampler: "grid".parse().unwrap(),
        density: reconbench_synth::Density::Count(10_000),
        perturbations: vec!["ma-uniform:level=0.3".parse().unwrap()],
        scan: None,
    };
    let hf = reconbench_synth::generate(&spec, 1).unwrap().positions;
    let sheet = sheet(50, wavy);
    let sphere = sphere(3000);
    let cases: [(&str, &[DVec3], HcItParams, usize, u64); 7] = [
        (
            "sheet",
            &sheet,
            HcItParams::default(),
            4623,
            0xbd8ae77f95224aaf,
        ),
        (
            "sheet all",
            &sheet,
            literal_all.clone(),
            4450,
            0xf8e2fa89913c7467,
        ),
        (
            "sphere",
            &sphere,
            HcItParams::default(),
            5996,
            0x41942be9912c658f,
        ),
        (
            "sphere all",
            &sphere,
            literal_all.clone(),
            5995,
            0x6db411b234213171,
        ),
        (
            "height field",
            &hf,
            HcItParams::default(),
            13288,
            0x1891c39804ec2e47,
        ),
        (
            "height field all",
            &hf,
            literal_all,
            10150,
            0x8f3aa6927eaa9c5c,
        ),
        (
            "height field literal",
            &hf,
            literal,
            10122,
            0x9972484c2661c1e1,
        ),
    ];
    for (name, pts, params, faces, hash) in cases {
        let r = run(pts, params);
        assert_eq!(r.mesh.faces().len(), faces, "{name}: face count");
        assert_eq!(face_hash(&r), hash, "{name}: faces differ");
    }
}
