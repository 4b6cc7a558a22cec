//! `priority-front` on the vertices of the vendored real sets (issue 20) and on two
//! close parallel sheets. The targets of issue 20 that the method does not meet yet are
//! `#[ignore]`d tests with the measured state in their reason (see
//! docs/methods/priority_front.md, "Real data"); run them with `--ignored`.

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::method::{Reconstruction, Reconstructor, RunCtx};
use reconbench_geom::topology::{TopologyReport, analyze};
use reconbench_geom::{PointCloud, TriMesh};
use reconbench_recon::{PriorityFront, PriorityFrontParams};
use reconbench_testkit::surfaces::Surface;

fn real(name: &str) -> TriMesh {
    let path = format!(
        "{}/../../datasets/real/{name}.ply",
        env!("CARGO_MANIFEST_DIR")
    );
    reconbench_geom::io::read_mesh(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn run(pts: Vec<DVec3>, threads: usize, seed: u64) -> Reconstruction {
    let cloud = PointCloud::new(pts).expect("finite points");
    let pf = PriorityFront::new(PriorityFrontParams {
        threads,
        ..PriorityFrontParams::default()
    })
    .expect("valid params");
    pf.reconstruct(&cloud, &mut RunCtx::new(seed))
        .expect("reconstruction")
}

fn assert_manifold_oriented(t: &TopologyReport) {
    assert_eq!(t.non_manifold_edges, 0, "{t:?}");
    assert_eq!(t.non_manifold_vertices, 0, "{t:?}");
    assert!(t.consistently_oriented, "{t:?}");
}

/// Every run on one and two threads with ctx seeds 1-3, each checked manifold and
/// consistently oriented: (threads, seed, result, topology).
fn all_runs(mesh: &TriMesh) -> Vec<(usize, u64, Reconstruction, TopologyReport)> {
    let mut out = Vec::new();
    for threads in [1, 2] {
        for seed in [1, 2, 3] {
            let rec = run(mesh.vertices().to_vec(), threads, seed);
            let t = analyze(&rec.mesh);
            assert_manifold_oriented(&t);
            out.push((threads, seed, rec, t));
        }
    }
    out
}

/// Refused points that a face of the input mesh uses (points on the surface).
fn refused_on_surface(mesh: &TriMesh, rec: &Reconstruction) -> usize {
    let mut used = vec![false; mesh.n_vertices()];
    for f in mesh.faces() {
        for &i in f {
            used[i as usize] = true;
        }
    }
    rec.refused.iter().filter(|&&i| used[i as usize]).count()
}

/// Output faces that point against the reference mesh's (area-weighted) vertex normals
/// summed over their corners: faces grown inside out. The output's vertices are the
/// input points, i.e. the reference's vertices, index for index.
fn inside_out_faces(mesh: &TriMesh, rec: &Reconstruction) -> usize {
    let v = mesh.vertices();
    let mut nrm = vec![DVec3::ZERO; v.len()];
    for f in mesh.faces() {
        let [a, b, c] = f.map(|i| v[i as usize]);
        for &i in f {
            nrm[i as usize] += (b - a).cross(c - a);
        }
    }
    rec.mesh
        .faces()
        .iter()
        .filter(|f| {
            let [a, b, c] = f.map(|i| v[i as usize]);
            let sum: DVec3 = f.iter().map(|&i| nrm[i as usize]).sum();
            (b - a).cross(c - a).dot(sum) < 0.0
        })
        .count()
}

/// The issue-20 target on one set: the mesh's genus, one component, at most the holes
/// the input has (`loops`), no refused on-surface point.
fn assert_issue_20_target(name: &str, genus: u32, loops: usize, threads: usize) {
    let mesh = real(name);
    for seed in [1, 2, 3] {
        let rec = run(mesh.vertices().to_vec(), threads, seed);
        let t = analyze(&rec.mesh);
        assert_manifold_oriented(&t);
        assert_eq!(t.components, 1, "{name} seed {seed}: {t:?}");
        assert_eq!(t.genus, Some(genus), "{name} seed {seed}");
        assert!(t.n_boundary_loops() <= loops, "{name} seed {seed}: {t:?}");
        assert_eq!(refused_on_surface(&mesh, &rec), 0, "{name} seed {seed}");
    }
}

/// Rocker arm (10,044 vertices, genus 1, closed), one and two threads, three seeds:
/// watertight with genus 1 in one piece. Four of the six runs left one 4-edge loop that
/// every ear folds or crosses (its rim faces overlap); IMPL-CHOICE I17 peels the rim and
/// closes it, and the same runs with `fill_holes_peel = 0` (and I20's regrowth, which
/// would close it too, off) keep it.
#[test]
fn rocker_arm_vertices_are_watertight_genus_one() {
    let mesh = real("rocker-arm");
    let mut kept_without_peel = 0;
    for (threads, seed, _, t) in all_runs(&mesh) {
        assert!(t.watertight, "threads {threads} seed {seed}: {t:?}");
        assert_eq!(t.components, 1, "threads {threads} seed {seed}");
        assert_eq!(t.genus, Some(1), "threads {threads} seed {seed}");
        let pf = PriorityFront::new(PriorityFrontParams {
            threads,
            fill_holes_peel: 0,
            regrow_loops_depth: 0,
            ..PriorityFrontParams::default()
        })
        .expect("valid params");
        let cloud = PointCloud::new(mesh.vertices().to_vec()).expect("finite points");
        let lit = pf.reconstruct(&cloud, &mut RunCtx::new(seed)).expect("run");
        kept_without_peel += analyze(&lit.mesh).n_boundary_loops();
    }
    assert!(kept_without_peel >= 3, "{kept_without_peel}");
}

/// Fandisk (6,475 vertices, genus 0, closed; CAD edges up to several ρ, 90-150 degree
/// creases), one and two threads, three seeds: issue 20's target, one watertight
/// genus-0 piece with no point of the surface refused. Before the I15 insertion reached
/// crease vertices above the chamfer growth cuts under them, and points under folds,
/// 2-23 were refused per run (0-1 before IMPL-CHOICE I21); before IMPL-CHOICE I20 the
/// one-thread runs kept 2-4 loops (slits along the top face's creases).
#[test]
fn fandisk_vertices_are_one_watertight_genus_zero_piece() {
    let mesh = real("fandisk");
    for (threads, seed, rec, t) in all_runs(&mesh) {
        assert!(t.watertight, "threads {threads} seed {seed}: {t:?}");
        assert_eq!(t.components, 1, "threads {threads} seed {seed}: {t:?}");
        assert_eq!(t.genus, Some(0), "threads {threads} seed {seed}");
        let on = refused_on_surface(&mesh, &rec);
        assert_eq!(on, 0, "threads {threads} seed {seed}: {on} refused");
        // Scattered slivers at creases only (measured 58-139 of 12,946 faces); the
        // bottom grown inside out (1,029 faces on one thread, seed 2) is grown again
        // by IMPL-CHOICE I19.
        let rev = inside_out_faces(&mesh, &rec);
        assert!(
            rev <= 300,
            "threads {threads} seed {seed}: {rev} faces inside out"
        );
    }
}

/// IMPL-CHOICE I20: the loops the fills leave open are grown again from a wider border.
/// On fandisk (one thread, seed 1: a 68-edge slit along the top face's crease among 4
/// loops) and mechpart (one thread, seed 1, and two threads, seed 3: genus 4 with 2-3
/// loops) the runs without it keep their loops; with it they are watertight with the
/// right genus.
#[test]
fn open_loops_are_grown_again_without_a_handle() {
    for (name, genus, threads, seed) in [
        ("fandisk", 0, 1, 1),
        ("mechpart", 3, 1, 1),
        ("mechpart", 3, 2, 3),
    ] {
        let mesh = real(name);
        let with = |depth: usize| {
            // I21's regrowth around unmeshed points closes some of these loops too.
            let points = if depth == 0 {
                0
            } else {
                PriorityFrontParams::default().regrow_points_depth
            };
            let p = PriorityFrontParams {
                threads,
                regrow_loops_depth: depth,
                regrow_points_depth: points,
                ..PriorityFrontParams::default()
            };
            let (t, _) = run_with(&mesh, p, seed);
            assert_manifold_oriented(&t);
            t
        };
        let off = with(0);
        assert!(
            off.n_boundary_loops() >= 2,
            "{name} {threads} t seed {seed}: {off:?} (fixture closed without I20)"
        );
        let on = with(PriorityFrontParams::default().regrow_loops_depth);
        assert!(on.watertight, "{name} {threads} t seed {seed}: {on:?}");
        assert_eq!(
            (on.genus, on.components),
            (Some(genus), 1),
            "{name} {threads} t seed {seed}"
        );
    }
}

/// Mechpart (7,607 vertices, genus 3, closed), two threads, seeds 1 and 3: without
/// IMPL-CHOICE I19 a box side of 2,179-2,357 faces is grown inside out and meets the
/// rest along a 150-200-edge open seam; with it that region is removed and grown again,
/// leaving scattered slivers (measured 185-195 faces) and at most 14 open edges. I20's
/// regrowth, which closes those loops afterwards, is off in both runs.
#[test]
fn mechpart_inside_out_side_is_grown_again() {
    let mesh = real("mechpart");
    let cloud = PointCloud::new(mesh.vertices().to_vec()).expect("finite points");
    for seed in [1, 3] {
        let with = |min_faces: usize| {
            let pf = PriorityFront::new(PriorityFrontParams {
                threads: 2,
                inside_out_min_faces: min_faces,
                regrow_loops_depth: 0,
                ..PriorityFrontParams::default()
            })
            .expect("valid params");
            let rec = pf.reconstruct(&cloud, &mut RunCtx::new(seed)).expect("run");
            let t = analyze(&rec.mesh);
            assert_manifold_oriented(&t);
            (inside_out_faces(&mesh, &rec), t.boundary_edges)
        };
        let (rev_off, open_off) = with(0);
        assert!(
            rev_off > 1000,
            "seed {seed}: {rev_off} (fixture no longer inside out)"
        );
        assert!(open_off > 100, "seed {seed}: {open_off}");
        let (rev, open) = with(PriorityFrontParams::default().inside_out_min_faces);
        assert!(rev <= 300, "seed {seed}: {rev} faces inside out");
        assert!(open <= 20, "seed {seed}: {open} open edges");
    }
}

/// 3holes (3,596 vertices, genus 3, closed; nearly uniform vertex spacing: mesh edges
/// at most 2.1 ρ): watertight with genus 3 in one piece for three seeds on one and two
/// threads, and no vertex refused (11-16 before IMPL-CHOICE I15 inserted the covered
/// points, 25-26 without `reject_free_inside`; they lie under a neighbouring triangle).
#[test]
fn three_holes_vertices_are_watertight_genus_three() {
    let mesh = real("3holes");
    for (threads, seed, rec, t) in all_runs(&mesh) {
        assert!(t.watertight, "threads {threads} seed {seed}: {t:?}");
        assert_eq!(t.components, 1, "threads {threads} seed {seed}");
        assert_eq!(t.genus, Some(3), "threads {threads} seed {seed}");
        let on = refused_on_surface(&mesh, &rec);
        assert_eq!(on, 0, "threads {threads} seed {seed}");
    }
}

/// The bunny's 35,947 vertices (the open scan, 5 holes in the bottom) with one thread:
/// one genus-0 piece with at most the scan's 5 holes, for three seeds (measured:
/// watertight, the fill closes the scan holes; before issue 20's `reject_free_inside`
/// default, seed 2 gave 4 pieces), and none of the vertices used by the scan's faces
/// refused (1-2 before IMPL-CHOICE I21 regrew the faces around them, 16 before the I15
/// insertion took points on curved patches and creases, 268-292 before I15): issue
/// 20's target on one thread.
#[test]
fn bunny_vertices_are_one_genus_zero_piece_on_one_thread() {
    let mesh = real("bunny");
    for seed in [1, 2, 3] {
        let rec = run(mesh.vertices().to_vec(), 1, seed);
        let t = analyze(&rec.mesh);
        assert_manifold_oriented(&t);
        assert_eq!(t.genus, Some(0), "seed {seed}: {t:?}");
        assert_eq!(t.components, 1, "seed {seed}");
        assert!(t.n_boundary_loops() <= 5, "seed {seed}: {t:?}");
        let on = refused_on_surface(&mesh, &rec);
        assert_eq!(on, 0, "seed {seed}: {on} refused");
    }
}

/// IMPL-CHOICE I21: the points left unmeshed near the mesh are offered to a regrowth
/// of the faces around them. Mechpart, one thread, seeds 1 and 2: without it 5 points
/// of the surface stay refused (box corners above the chamfer growth cut, points under
/// folds); with it at most one (measured 1, a box corner), with the same genus and no
/// loop.
#[test]
fn unmeshed_points_are_taken_by_a_regrowth() {
    let mesh = real("mechpart");
    for seed in [1, 2] {
        let with = |depth: usize| {
            let p = PriorityFrontParams {
                regrow_points_depth: depth,
                ..PriorityFrontParams::default()
            };
            let (t, on) = run_with(&mesh, p, seed);
            assert_manifold_oriented(&t);
            assert!(t.watertight, "seed {seed} depth {depth}: {t:?}");
            assert_eq!((t.genus, t.components), (Some(3), 1), "seed {seed}");
            on
        };
        let off = with(0);
        assert!(
            off >= 4,
            "seed {seed}: {off} refused without I21 (fixture changed)"
        );
        let on = with(PriorityFrontParams::default().regrow_points_depth);
        assert!(on <= 1, "seed {seed}: {on} refused with I21");
    }
}

/// IMPL-CHOICE I13 (`interior_inside_check`, opt-in): on fandisk's vertices with one
/// thread, no triangle is laid over finished mesh, and the false handles go: genus 0 in
/// one piece for seeds 1-3 (measured; holes stay, 8-11 loops). Without it seed 2 has
/// genus 2, so a no-op check fails here (the handles are folds made in the revisit
/// passes, see docs/methods/priority_front.md, "Real data").
#[test]
fn interior_inside_check_removes_fandisk_false_handles() {
    let mesh = real("fandisk");
    let with = |check: bool, seed: u64| {
        let cloud = PointCloud::new(mesh.vertices().to_vec()).expect("finite points");
        let pf = PriorityFront::new(PriorityFrontParams {
            interior_inside_check: check,
            ..PriorityFrontParams::default()
        })
        .expect("valid params");
        let rec = pf
            .reconstruct(&cloud, &mut RunCtx::new(seed))
            .expect("reconstruction");
        analyze(&rec.mesh)
    };
    for seed in [1, 2, 3] {
        let t = with(true, seed);
        assert_manifold_oriented(&t);
        assert_eq!(t.genus, Some(0), "seed {seed}: {t:?}");
        assert_eq!(t.components, 1, "seed {seed}: {t:?}");
    }
}

/// IMPL-CHOICE I14 (`self_intersection_check`, opt-in): on the vertices of the golf
/// club and the rocker arm, one thread, at most 20 crossing face pairs remain (the
/// metric's exact test; measured 4-13, all at FILLs of 3-edge holes, which are exempt).
/// With the check off the golf club has over 1,000 per seed (measured 1,215-1,403), so
/// a no-op check fails here.
#[test]
fn self_intersection_check_removes_crossing_faces() {
    let pairs = |name: &str, check: bool, seed: u64| {
        let mesh = real(name);
        let cloud = PointCloud::new(mesh.vertices().to_vec()).expect("finite points");
        let defaults = PriorityFrontParams::default();
        let pf = PriorityFront::new(PriorityFrontParams {
            self_intersection_check: check,
            // I20's regrowth runs with the check on, and would repair part of the off run.
            regrow_loops_depth: if check {
                defaults.regrow_loops_depth
            } else {
                0
            },
            ..defaults
        })
        .expect("valid params");
        let rec = pf
            .reconstruct(&cloud, &mut RunCtx::new(seed))
            .expect("reconstruction");
        assert_manifold_oriented(&analyze(&rec.mesh));
        reconbench_metrics::topology::count_self_intersections(&rec.mesh)
    };
    for name in ["golf-club", "rocker-arm"] {
        for seed in [1, 2] {
            let on = pairs(name, true, seed);
            assert!(on <= 20, "{name} seed {seed}: {on} crossing pairs");
        }
    }
    let off = pairs("golf-club", false, 1);
    assert!(
        off > 500,
        "golf-club without the check: {off} crossing pairs"
    );
}

/// Two parallel square sheets 1 x 1, `gap` apart, blue noise.
fn two_sheets(gap: f64, n: usize, seed: u64) -> Vec<DVec3> {
    Surface::TwoSheets { gap }.sample_blue_noise(n, &mut ChaCha8Rng::seed_from_u64(seed))
}

/// Faces with vertices on both sheets of [`two_sheets`] (z = 0 and z = gap).
fn bridging_faces(rec: &Reconstruction, gap: f64) -> usize {
    let v = rec.mesh.vertices();
    rec.mesh
        .faces()
        .iter()
        .filter(|f| {
            let up = f.iter().filter(|&&i| v[i as usize].z > gap / 2.0).count();
            up != 0 && up != 3
        })
        .count()
}

/// Two close parallel sheets 2.3 ρ apart (inside the candidate ball R = 4ρ), 1 and 2
/// threads: no face joins the sheets, so there is no handle; with one thread each sheet
/// is one open piece. Before issue 20 the two-thread run had 724 faces joining the
/// sheets (genus 2): links / glues between the fronts of the two sheets, which are
/// meshed with opposite orientations (IMPL-CHOICE I10 rejects them). With two threads
/// each sheet still comes out in two pieces split at the slab cut (4 components).
#[test]
fn close_parallel_sheets_are_not_bridged() {
    // 8,000 blue-noise points on area 2: rho (mean nearest-neighbour distance) 0.0129.
    let gap = 0.03;
    let pts = two_sheets(gap, 8000, 5);
    for threads in [1, 2] {
        let rec = run(pts.clone(), threads, 5);
        let t = analyze(&rec.mesh);
        assert_manifold_oriented(&t);
        assert_eq!(bridging_faces(&rec, gap), 0, "threads {threads}: {t:?}");
        assert_eq!(t.genus, Some(0), "threads {threads}");
        if threads == 1 {
            assert_eq!(t.components, 2, "{t:?}");
            assert_eq!(t.n_boundary_loops(), 2, "{t:?}");
        }
    }
}

/// Closer still (1.25 ρ, about the sample spacing): with the I11 crease check on
/// I8-supported candidates, fewer than 1 % of the faces join the sheets and the result
/// has genus 0 (measured 34 faces of 15,649; without I11 127; with the defaults before
/// issue 20 310 and genus 4).
#[test]
fn very_close_parallel_sheets_have_genus_zero() {
    let gap = 0.016;
    let rec = run(two_sheets(gap, 8000, 5), 1, 5);
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert_eq!(t.genus, Some(0), "{t:?}");
    assert!(bridging_faces(&rec, gap) * 100 < rec.mesh.n_faces());
}

// Measured states below: default parameters, seeds 1-3.

#[test]
#[ignore = "issue 20 open: genus 1, 1 component, watertight, but 1 crease vertex (121 degrees) refused"]
fn rocker_arm_vertices_issue_20_target() {
    assert_issue_20_target("rocker-arm", 1, 0, 1);
}

#[test]
#[ignore = "issue 20 open: genus 3, 1 component, watertight, but 1 box-corner point refused"]
fn mechpart_vertices_issue_20_target() {
    assert_issue_20_target("mechpart", 3, 0, 1);
}

#[test]
#[ignore = "issue 20 open: genus 0, no loop, 0-4 refused, but the shaft a second piece"]
fn golf_club_vertices_issue_20_target() {
    assert_issue_20_target("golf-club", 0, 1, 1);
}

/// The bunny on two threads, seeds 1-3: issue 20's target (one genus-0 piece, at most
/// the scan's 5 loops, no point of the surface refused). Seed 2 had a false handle
/// across an ear's thickness (edges of 5-7 ρ between points with opposite normals),
/// which IMPL-CHOICE I22 cuts and grows again; with it off the handle stays.
#[test]
fn bunny_two_threads_issue_20_target_and_the_ear_handle() {
    assert_issue_20_target("bunny", 0, 5, 2);
    let mesh = real("bunny");
    let off = PriorityFrontParams {
        threads: 2,
        regrow_handles_depth: 0,
        ..PriorityFrontParams::default()
    };
    let (t, _) = run_with(&mesh, off, 2);
    assert_eq!(t.genus, Some(1), "fixture: the handle without I22: {t:?}");
}

/// Runs `priority-front` with parameters `p` and returns the topology and
/// the number of refused points the input mesh uses.
fn run_with(mesh: &TriMesh, p: PriorityFrontParams, seed: u64) -> (TopologyReport, usize) {
    let cloud = PointCloud::new(mesh.vertices().to_vec()).expect("finite points");
    let rec = PriorityFront::new(p)
        .expect("valid params")
        .reconstruct(&cloud, &mut RunCtx::new(seed))
        .expect("reconstruction");
    (analyze(&rec.mesh), refused_on_surface(mesh, &rec))
}

/// IMPL-CHOICE I15 (surface completion, on by default): on the rocker arm's vertices
/// the leftover slits are closed and the covered points inserted, so the mesh is
/// watertight with the arm's genus 1 in one piece and almost no point refused
/// (measured 2 of 10,044; 10-11 before the insertion reached the corners of long CAD
/// triangles and crease vertices). With both completion steps off (the paper) the same runs
/// keep 1-3 loops and over 100 refused points on the surface, so a no-op fails here.
#[test]
fn surface_completion_closes_slits_and_inserts_covered_points() {
    let mesh = real("rocker-arm");
    let paper = PriorityFrontParams {
        fill_holes_max_edge: 0.0,
        insert_covered: false,
        ..PriorityFrontParams::default()
    };
    for seed in [1, 2] {
        let (t, refused) = run_with(&mesh, PriorityFrontParams::default(), seed);
        assert_manifold_oriented(&t);
        assert!(t.watertight, "seed {seed}: {t:?}");
        assert_eq!((t.genus, t.components), (Some(1), 1), "seed {seed}");
        assert!(
            refused <= 4,
            "seed {seed}: {refused} refused on the surface"
        );
        let (t0, refused0) = run_with(&mesh, paper.clone(), seed);
        assert!(t0.n_boundary_loops() >= 1, "seed {seed}: {t0:?}");
        assert!(
            refused0 > 100,
            "seed {seed}: {refused0} refused without I15"
        );
    }
}

/// I15 keeps real holes: a blue-noise sphere with its polar cap z > 0.6 removed (a
/// hole 1.6 wide, about 8 R) comes out as one genus-0 piece whose only boundary loop is
/// that hole's rim, untouched by the fill; and far outliers stay refused (the point
/// insertion takes only points within the I12 height bound of a triangle).
#[test]
fn surface_completion_keeps_a_wide_hole_and_refuses_outliers() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut pts: Vec<DVec3> = Surface::Sphere(1.0)
        .sample_blue_noise(5000, &mut rng)
        .into_iter()
        .filter(|p| p.z <= 0.6)
        .collect();
    let n = pts.len();
    pts.extend([DVec3::new(0.0, 0.0, 1.6), DVec3::new(1.4, 0.0, 0.0)]);
    let rec = run(pts.clone(), 1, 3);
    let t = analyze(&rec.mesh);
    assert_manifold_oriented(&t);
    assert_eq!((t.genus, t.components), (Some(0), 1), "{t:?}");
    assert_eq!(t.n_boundary_loops(), 1, "{t:?}");
    assert!(rec.refused.contains(&(n as u32)) && rec.refused.contains(&(n as u32 + 1)));
    // The kept loop is the cap's rim: every boundary vertex lies near z = 0.6.
    let v = rec.mesh.vertices();
    let mut count = std::collections::HashMap::<(u32, u32), i32>::new();
    for f in rec.mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k].min(f[(k + 1) % 3]), f[k].max(f[(k + 1) % 3]));
            *count.entry((a, b)).or_default() += 1;
        }
    }
    let rim_low = count
        .iter()
        .filter(|(_, c)| **c == 1)
        .flat_map(|((a, b), _)| [*a, *b])
        .map(|i| v[i as usize].z)
        .fold(f64::INFINITY, f64::min);
    assert!(rim_low > 0.4, "a boundary vertex at z = {rim_low}");
}
