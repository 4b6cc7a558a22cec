//! `ebt` across creases (docs/methods/ebt.md, deviation `link_edge`): on two stand-ins
//! with a sharp crease (two planes at 90 degrees; a cylindrical ridge meeting a plane at
//! 78 degrees, the poly-part's profile) the growth reaches nearly every thinned point
//! and the single open patch keeps exactly one boundary loop; the literal growth
//! (`link_edge = 1`) leaves more of them unmeshed.

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostic, MethodError, Reconstruction, Reconstructor, RunCtx,
};
use reconbench_geom::topology::MeshTopology;
use reconbench_recon::ebt::{Ebt, EbtParams};

/// Points of the ruled surface over the profile curve `prof` (arc length -> (x, z), of
/// length `len`) times `y` in `[-h, h]`: a jittered grid of spacing about `s` in arc
/// length and `y` (deterministic irrational offsets), so the walls are sampled as
/// densely as the flats.
fn ruled(len: f64, h: f64, s: f64, prof: impl Fn(f64) -> (f64, f64)) -> Vec<DVec3> {
    let (nu, nv) = ((len / s) as usize, (2.0 * h / s) as usize);
    let mut out = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let ju = ((i * 7 + j * 13) as f64 * 0.618_034).fract() - 0.5;
            let jv = ((i * 11 + j * 5) as f64 * 0.414_214).fract() - 0.5;
            let (x, z) = prof(len * (i as f64 + 0.5 + 0.3 * ju) / nu as f64);
            let y = -h + 2.0 * h * (j as f64 + 0.5 + 0.3 * jv) / nv as f64;
            out.push(DVec3::new(x, y, z));
        }
    }
    out
}

/// Two half-planes at 90 degrees: z = 0 for x in [-10, 0], then the wall x = 0 up to
/// z = 10 (a convex crease seen from the outside normal -x, +z).
fn right_angle() -> Vec<DVec3> {
    ruled(20.0, 10.0, 0.2, |t| {
        if t < 10.0 {
            (t - 10.0, 0.0)
        } else {
            (0.0, t - 10.0)
        }
    })
}

/// The poly-part's ridge profile: the plane z = 0 for |x| >= 24.49, between them the
/// arc of a circle of radius 25 centred at z = -5 (20 high; it meets the plane at 78.5
/// degrees), the plane out to |x| = 40.
fn ridge() -> Vec<DVec3> {
    let r = 25.0f64;
    let a = (5.0 / r).acos(); // half-angle of the arc about the vertical
    let x0 = r * a.sin();
    let flat = 40.0 - x0;
    let arc = 2.0 * a * r;
    ruled(2.0 * flat + arc, 12.0, 0.5, move |t| {
        if t < flat {
            (-40.0 + t, 0.0)
        } else if t < flat + arc {
            let phi = -a + (t - flat) / r;
            (r * phi.sin(), r * phi.cos() - 5.0)
        } else {
            (x0 + (t - flat - arc), 0.0)
        }
    })
}

fn num(r: &Reconstruction, k: &str) -> f64 {
    match r.diagnostics.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        other => panic!("diagnostic {k}: {other:?}"),
    }
}

/// Runs `ebt` with B forced to `bin_abs` (cloud units; the quadric fits across a crease
/// say nothing useful about Omega) and the growth link edge `link` (multiple of Omega);
/// returns the reconstruction and the unmeshed share of Q.
fn run(p: Vec<DVec3>, bin_abs: f64, link: f64) -> (Reconstruction, f64) {
    let c = PointCloud::new(p).unwrap();
    let params = EbtParams {
        bin_size: bin_abs / c.aabb().diagonal(),
        link_edge: link,
        ..EbtParams::default()
    };
    let r = Ebt::from_params(params)
        .unwrap()
        .reconstruct(&c, &mut RunCtx::new(7))
        .unwrap();
    let share = num(&r, "unmeshed") / num(&r, "q_points");
    (r, share)
}

/// One boundary loop, no bad facet, no non-manifold or inconsistently oriented edge.
fn assert_disc(r: &Reconstruction) {
    let topo = MeshTopology::new(&r.mesh);
    for e in 0..topo.n_edges() {
        assert!(topo.edge_valence(e) <= 2, "non-manifold edge {e}");
        assert_ne!(topo.edge_orientation_conflict(e), Some(true));
    }
    assert_eq!(topo.boundary_loops().len(), 1);
    assert_eq!(num(r, "bad_facets"), 0.0);
}

#[test]
fn growth_crosses_a_right_angle_crease() {
    // B = 1 over a 0.2 sampling: about 380 kept points, 10 rows on the wall.
    let (r, share) = run(right_angle(), 1.0, std::f64::consts::SQRT_2);
    assert_disc(&r);
    assert!(share <= 0.02, "unmeshed share {share}");
    // The literal growth (E13 at Omega = sqrt 2 B exactly) stops much earlier
    // (0.49 when written).
    let (lit, lit_share) = run(right_angle(), 1.0, 1.0);
    assert_disc(&lit);
    assert!(
        lit_share > share + 0.1,
        "literal {lit_share}, deviation {share}"
    );
}

#[test]
fn growth_crosses_the_ridge_creases() {
    // B = 2 over a 0.5 sampling: about 650 kept points across both creases.
    let (r, share) = run(ridge(), 2.0, std::f64::consts::SQRT_2);
    assert_disc(&r);
    assert!(share <= 0.02, "unmeshed share {share}");
    // The literal growth stalls near its seed here (0.99 unmeshed when written).
    let (lit, lit_share) = run(ridge(), 2.0, 1.0);
    assert_disc(&lit);
    assert!(
        lit_share > share + 0.1,
        "literal {lit_share}, deviation {share}"
    );
}

#[test]
fn link_edge_outside_its_range_is_refused() {
    let c = PointCloud::new(right_angle()).unwrap();
    for bad in [0.5, 1.5, f64::NAN] {
        let p = EbtParams {
            link_edge: bad,
            ..EbtParams::default()
        };
        let res = Ebt::from_params(p).and_then(|m| m.reconstruct(&c, &mut RunCtx::new(7)));
        match res {
            Err(MethodError::InvalidParameter { name, .. }) => assert_eq!(name, "link_edge"),
            other => panic!("link_edge = {bad}: {:?}", other.map(|_| ())),
        }
    }
}
