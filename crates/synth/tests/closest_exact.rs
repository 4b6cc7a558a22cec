//! Strict exactness of `closest_point` for every built-in shape.
//!
//! A true closest point can never be farther than any point of the surface, so against
//! a dense set of exact surface samples `closest_point(q).distance <= min_i |q - s_i|`
//! must hold to rounding (1e-12), for every query, anywhere. The queries cover the
//! whole inflated bounding box, the exact coordinate planes (rays of the region parity
//! test run along them, through hole centres and arc end points: the junction of the
//! double-torus' two holes lies on them), and both sides of the reference-mesh surface.
//!
//! Regression: `double-torus` at (0, 0, -0.04834) must report ~3e-6 (the bottom cap lies
//! at z = -0.0483368), not 0.077 (the distance to the hole rims, which is what a region
//! that loses the point between the holes would give).

use glam::{DVec2, DVec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointIndex;
use reconbench_synth::Shape;
use reconbench_synth::shapes::{ShapeSpec, definitions, from_spec};

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn all_shapes() -> Vec<Box<dyn Shape>> {
    definitions()
        .iter()
        .map(|d| from_spec(d.name).unwrap())
        .collect()
}

/// Queries: uniform in the bounding box inflated by 0.1, the same points snapped onto
/// each exact coordinate plane, and reference-mesh vertices offset along their normals
/// by +-0.05 (and +-0.01).
fn queries(s: &dyn Shape, seed: u64) -> Vec<DVec3> {
    let b = s.aabb();
    let (lo, hi) = (b.min - DVec3::splat(0.1), b.max + DVec3::splat(0.1));
    let mut r = rng(seed);
    let mut out = Vec::new();
    for _ in 0..2000 {
        let t = DVec3::new(r.random(), r.random(), r.random());
        out.push(lo + (hi - lo) * t);
    }
    for k in 0..600 {
        let p = out[k];
        out.push(DVec3::new(0.0, p.y, p.z));
        out.push(DVec3::new(p.x, 0.0, p.z));
        out.push(DVec3::new(p.x, p.y, 0.0));
        out.push(DVec3::new(p.x, 0.0, 0.0));
    }
    let m = s.reference_mesh(48);
    let step = (m.n_vertices() / 500).max(1);
    for &v in m.vertices().iter().step_by(step) {
        let n = s.closest_point(v).normal;
        for off in [-0.05, -0.01, 0.01, 0.05] {
            out.push(v + n * off);
        }
    }
    out
}

#[test]
fn reference_mesh_vertices_are_on_the_surface() {
    for s in all_shapes() {
        let m = s.reference_mesh(48);
        let worst = m
            .vertices()
            .iter()
            .map(|&v| s.distance(v))
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{}: vertex off surface by {worst}", s.name());
    }
}

#[test]
fn closest_points_are_never_beaten_by_a_surface_sample() {
    for s in all_shapes() {
        let dense: Vec<DVec3> = s
            .sample_uniform(20_000, &mut rng(23))
            .into_iter()
            .map(|x| x.position)
            .collect();
        let index = PointIndex::new(&dense).unwrap();
        let mut worst_excess = f64::NEG_INFINITY;
        let mut r = rng(29);
        for q in queries(&*s, 31) {
            let c = s.closest_point(q);
            let nearest = index.nearest(q).unwrap().dist2.sqrt();
            worst_excess = worst_excess.max(c.distance - nearest);
            assert!(
                c.distance <= nearest + 1e-12,
                "{}: closest_point({q}) reports {} but a surface sample is {nearest} away",
                s.name(),
                c.distance
            );
            assert!(
                (c.distance - (q - c.point).length()).abs() < 1e-12,
                "{}: distance {} vs |q - point| {} at {q}",
                s.name(),
                c.distance,
                (q - c.point).length()
            );
            let on = s.distance(c.point);
            assert!(
                on < 1e-9,
                "{}: closest point {} of {q} off surface by {on}",
                s.name(),
                c.point
            );
            assert!((c.normal.length() - 1.0).abs() < 1e-9, "{}", s.name());
            // The distance to a set is 1-Lipschitz.
            let q2 = q + reconbench_synth::util::unit_vector(&mut r) * 1e-3;
            let jump = (s.distance(q2) - c.distance).abs();
            assert!(
                jump <= (q2 - q).length() + 1e-12,
                "{}: distance jumps by {jump} between {q} and {q2}",
                s.name()
            );
        }
        eprintln!(
            "{}: max(closest - nearest sample) = {worst_excess:.3e}",
            s.name()
        );
    }
}

/// Independent closed form for the holed stadium slabs (`double-torus`, `three-holes`):
/// distance to the offset by `r` of {stadium (half-length d, radius ro)} minus the
/// discs of radius `ri` at `(x, 0)` for each hole centre `x`.
fn holed_slab_distance(p: DVec3, d: f64, ro: f64, ri: f64, r: f64, xs: &[f64]) -> f64 {
    let q = DVec2::new(p.x, p.y);
    let outside = (q - DVec2::new(q.x.clamp(-d, d), 0.0)).length() - ro;
    let mut dist2d = outside.max(0.0);
    if outside <= 0.0 {
        for &x in xs {
            dist2d = dist2d.max(ri - (q - DVec2::new(x, 0.0)).length());
        }
    }
    ((dist2d * dist2d + p.z * p.z).sqrt() - r).abs()
}

#[test]
fn holed_slabs_match_an_independent_closed_form() {
    for (name, holes) in [("double-torus", 2), ("three-holes", 3)] {
        let def = definitions().iter().find(|d| d.name == name).unwrap();
        let param = |k: &str| def.params.iter().find(|p| p.0 == k).unwrap().1;
        let (d, ro, ri, r) = (param("d"), param("ro"), param("ri"), param("r"));
        let xs: Vec<f64> = if holes == 2 {
            vec![-d, d]
        } else {
            vec![-d, 0.0, d]
        };
        let s = ShapeSpec::named(name).build().unwrap();
        let sc = s.scale();
        let check = |p: DVec3| {
            let got = s.distance(p);
            let want = holed_slab_distance(p / sc, d, ro, ri, r, &xs) * sc;
            assert!(
                (got - want).abs() < 1e-12,
                "{name}: distance({p}) = {got}, exact {want}"
            );
        };
        // The reported query, and the line through the hole centres (the parity rays of
        // the region test pass through the rims' end points there).
        check(DVec3::new(0.0, 0.0, -0.04834));
        let b = s.aabb();
        let n = 400;
        for i in 0..=n {
            let x = b.min.x - 0.05 + (b.max.x - b.min.x + 0.1) * i as f64 / n as f64;
            for z in [0.0, -0.04834, 0.3 * b.min.z, b.min.z, 1.5 * b.max.z] {
                check(DVec3::new(x, 0.0, z));
                check(DVec3::new(x, 1e-300, z));
                check(DVec3::new(x, -1e-300, z));
            }
        }
        let mut g = rng(37);
        for _ in 0..20_000 {
            let t = DVec3::new(g.random(), g.random(), g.random());
            check(b.min - DVec3::splat(0.05) + (b.max - b.min + DVec3::splat(0.1)) * t);
        }
    }
}
