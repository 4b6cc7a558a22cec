//! Small meshes with known topology.
//!
//! All closed examples are consistently oriented with outward normals (positive signed
//! volume). Resolutions below the minimum that gives a valid surface are raised to it
//! (documented per function); non-finite size parameters give an empty mesh instead of a
//! panic.
//!
//! | builder | V | F | components | boundary loops | genus | notes |
//! |---|---|---|---|---|---|---|
//! | [`tetrahedron`] | 4 | 4 | 1 | 0 | 0 | |
//! | [`cube`] | 8 | 12 | 1 | 0 | 0 | unit cube `[0, 1]^3` |
//! | [`uv_sphere`] | `2 + (n_lat - 1) n_lon` | `2 n_lon (n_lat - 1)` | 1 | 0 | 0 | |
//! | [`torus_grid`] | `nu nv` | `2 nu nv` | 1 | 0 | 1 | |
//! | [`double_torus`] | `2 nu nv` | `4 nu nv + 4` | 1 | 0 | 2 | |
//! | [`square_grid`] | `(n + 1)^2` | `2 n^2` | 1 | 1 | 0 | open disk |
//! | [`moebius_strip`] | `2 n` | `2 n` | 1 | 1 | - | non-orientable |

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use reconbench_geom::TriMesh;

/// Builds the mesh, or an empty one if a parameter made a coordinate non-finite.
fn build(vertices: Vec<DVec3>, faces: Vec<[u32; 3]>) -> TriMesh {
    TriMesh::new(vertices, faces).unwrap_or_default()
}

/// Appends the two triangles `[a, b, c]`, `[a, c, d]` of the quad `a b c d`.
fn quad(faces: &mut Vec<[u32; 3]>, a: u32, b: u32, c: u32, d: u32) {
    faces.push([a, b, c]);
    faces.push([a, c, d]);
}

/// The tetrahedron with corners `0, x, y, z` (outward normals).
pub fn tetrahedron() -> TriMesh {
    let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    build(v, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
}

/// The unit cube `[0, 1]^3` as 12 triangles; vertex `i` is `(i & 1, i >> 1 & 1, i >> 2)`.
/// Faces `2k, 2k + 1` form the square with outward normal -z, +z, -y, +y, -x, +x for
/// `k = 0..6`.
pub fn cube() -> TriMesh {
    let v = (0..8)
        .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64))
        .collect();
    let mut f = Vec::with_capacity(12);
    for [a, b, c, d] in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        quad(&mut f, a, b, c, d);
    }
    build(v, f)
}

/// A latitude/longitude sphere of `radius` centred at the origin, with single pole
/// vertices: `n_lat >= 2` bands (raised to 2) and `n_lon >= 3` meridians (raised to 3).
/// Vertex 0 is the north pole `(0, 0, r)`, the last vertex the south pole.
pub fn uv_sphere(n_lat: usize, n_lon: usize, radius: f64) -> TriMesh {
    let (n_lat, n_lon) = (n_lat.max(2), n_lon.max(3));
    let mut v = vec![DVec3::new(0.0, 0.0, radius)];
    for i in 1..n_lat {
        let t = PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let p = TAU * j as f64 / n_lon as f64;
            v.push(radius * DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos()));
        }
    }
    v.push(DVec3::new(0.0, 0.0, -radius));
    let south = (v.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_lon + j % n_lon) as u32;
    let mut f = Vec::new();
    for j in 0..n_lon {
        f.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            quad(
                &mut f,
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
        }
    }
    for j in 0..n_lon {
        f.push([south, ring(n_lat - 1, j + 1), ring(n_lat - 1, j)]);
    }
    build(v, f)
}

/// Vertices and faces of a torus grid around the z axis; `skip` omits one quad.
fn torus_parts(
    nu: usize,
    nv: usize,
    major: f64,
    minor: f64,
    skip: Option<(usize, usize)>,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut v = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let u = TAU * i as f64 / nu as f64;
        for j in 0..nv {
            let w = TAU * j as f64 / nv as f64;
            let rho = major + minor * w.cos();
            v.push(DVec3::new(rho * u.cos(), rho * u.sin(), minor * w.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut f = Vec::with_capacity(2 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            if skip == Some((i, j)) {
                continue;
            }
            quad(
                &mut f,
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1),
            );
        }
    }
    (v, f)
}

/// A torus around the z axis with `nu >= 3` segments around the axis and `nv >= 3`
/// around the tube (both raised to 3), major radius `major` and tube radius `minor`
/// (`major > minor > 0` for an embedded surface). Vertex `(i, j)` is `i * nv + j`.
/// Genus 1, Euler characteristic 0.
pub fn torus_grid(nu: usize, nv: usize, major: f64, minor: f64) -> TriMesh {
    let (v, f) = torus_parts(nu.max(3), nv.max(3), major, minor, None);
    build(v, f)
}

/// A genus-2 surface: two [`torus_grid`]s side by side along x, each with the quad at
/// `(i, j) = (0, 0)` (on the outer equator) removed, the two square holes joined by a
/// straight tube of 4 quads. The second torus is the mirror image of the first through
/// the plane `x = major + 1.5 minor`, so the tube has length `minor`. Euler
/// characteristic -2. `nu >= 3` and `nv >= 3` (raised to 3).
pub fn double_torus(nu: usize, nv: usize, major: f64, minor: f64) -> TriMesh {
    let (nu, nv) = (nu.max(3), nv.max(3));
    let (va, fa) = torus_parts(nu, nv, major, minor, Some((0, 0)));
    let d = 2.0 * (major + minor) + minor;
    let n = va.len() as u32;
    let mut v = va.clone();
    v.extend(va.iter().map(|p| DVec3::new(d - p.x, p.y, p.z)));
    let mut f = fa.clone();
    // Mirroring reverses orientation: flip the copy's faces.
    f.extend(fa.iter().map(|t| [t[0] + n, t[2] + n, t[1] + n]));
    // The removed quad was q0 -> q1 -> q2 -> q3; the tube quad on side (q_k, q_k+1)
    // traverses it the same way, and the mirrored side the other way.
    let q = [0, nv as u32, nv as u32 + 1, 1];
    for k in 0..4 {
        let (a, b) = (q[k], q[(k + 1) % 4]);
        quad(&mut f, a, b, b + n, a + n);
    }
    build(v, f)
}

/// An `n x n` grid of squares (raised to 1) over `[0, 1]^2` in the plane z = 0, normals
/// +z: a disk with one boundary loop of `4 n` vertices and length 4. Vertex `(i, j)`
/// (x index i, y index j) is `j * (n + 1) + i`.
pub fn square_grid(n: usize) -> TriMesh {
    let n = n.max(1);
    let m = n + 1;
    let mut v = Vec::with_capacity(m * m);
    for j in 0..m {
        for i in 0..m {
            v.push(DVec3::new(i as f64 / n as f64, j as f64 / n as f64, 0.0));
        }
    }
    let id = |i: usize, j: usize| (j * m + i) as u32;
    let mut f = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            quad(
                &mut f,
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1),
            );
        }
    }
    build(v, f)
}

/// A Moebius strip of `n >= 4` (raised to 4) quads around a circle of radius `radius`,
/// strip half-width `half_width`: non-orientable, one boundary loop of `2 n` vertices,
/// Euler characteristic 0. Vertices `2 i` and `2 i + 1` are the two sides of rung `i`.
pub fn moebius_strip(n: usize, radius: f64, half_width: f64) -> TriMesh {
    let n = n.max(4);
    let mut v = Vec::with_capacity(2 * n);
    for i in 0..n {
        let u = TAU * i as f64 / n as f64;
        for s in [-1.0, 1.0] {
            let w = s * half_width;
            let rho = radius + w * (u / 2.0).cos();
            v.push(DVec3::new(
                rho * u.cos(),
                rho * u.sin(),
                w * (u / 2.0).sin(),
            ));
        }
    }
    let mut f = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (a, b) = (2 * i as u32, 2 * i as u32 + 1);
        // After a full turn the half-twist swaps the two sides.
        let (a2, b2) = if i + 1 < n {
            (2 * (i + 1) as u32, 2 * (i + 1) as u32 + 1)
        } else {
            (1, 0)
        };
        quad(&mut f, a, a2, b2, b);
    }
    build(v, f)
}
