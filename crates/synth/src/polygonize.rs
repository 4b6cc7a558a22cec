//! Marching tetrahedra on a regular grid (Kuhn/Freudenthal split of every cube into six
//! tetrahedra sharing the main diagonal). The piecewise-linear zero set of a grid
//! function without exact zeros is a closed 2-manifold, so the output is watertight and
//! manifold by construction at every resolution; vertices are keyed by grid edges.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::Aabb;

/// Polygonises `{ sdf < 0 }` over `bounds` (enlarged by two cells) with `res` cells along
/// the longest axis. Returns vertices (on grid edges, linearly interpolated) and outward
/// oriented faces. `sdf` must be positive outside and on the grid boundary.
pub fn marching_tetrahedra(
    sdf: &(dyn Fn(DVec3) -> f64 + Sync),
    bounds: Aabb,
    res: usize,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let res = res.max(2);
    let size = bounds.size();
    let h = size.max_element() / res as f64;
    let lo = bounds.min - DVec3::splat(2.0 * h);
    let dims = ((size + DVec3::splat(4.0 * h)) / h).ceil().as_uvec3() + glam::UVec3::ONE;
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let id = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
    let pos = |i: usize, j: usize, k: usize| lo + DVec3::new(i as f64, j as f64, k as f64) * h;
    let values: Vec<f64> = (0..nx * ny * nz)
        .into_par_iter()
        .map(|g| {
            let i = g % nx;
            let j = (g / nx) % ny;
            let k = g / (nx * ny);
            sdf(pos(i, j, k))
        })
        .collect();
    const PERMS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut verts: Vec<DVec3> = Vec::new();
    let mut vmap: HashMap<(usize, usize), u32> = HashMap::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    // Vertex on the grid edge (a inside, b outside); `t` is kept off the grid points so
    // that no face degenerates to a point.
    let mut edge_vertex =
        |a: (usize, DVec3, f64), b: (usize, DVec3, f64), verts: &mut Vec<DVec3>| -> u32 {
            let key = if a.0 < b.0 { (a.0, b.0) } else { (b.0, a.0) };
            *vmap.entry(key).or_insert_with(|| {
                let t = (a.2 / (a.2 - b.2)).clamp(1e-3, 1.0 - 1e-3);
                verts.push(a.1 + (b.1 - a.1) * t);
                (verts.len() - 1) as u32
            })
        };
    let mid = |a: (usize, DVec3, f64), b: (usize, DVec3, f64)| 0.5 * (a.1 + b.1);
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let base = [i, j, k];
                for perm in PERMS {
                    let mut c = base;
                    let mut tet = [(0usize, DVec3::ZERO, 0.0f64); 4];
                    for (m, slot) in tet.iter_mut().enumerate() {
                        if m > 0 {
                            c[perm[m - 1]] += 1;
                        }
                        let g = id(c[0], c[1], c[2]);
                        *slot = (g, pos(c[0], c[1], c[2]), values[g]);
                    }
                    let inside: Vec<usize> = (0..4).filter(|&m| tet[m].2 < 0.0).collect();
                    let outside: Vec<usize> = (0..4).filter(|&m| tet[m].2 >= 0.0).collect();
                    // Orientation is decided on the edge midpoints (a non-degenerate
                    // triangle or parallelogram of the tetrahedron), not on the
                    // interpolated vertices, which may nearly coincide.
                    match inside.len() {
                        1 | 3 => {
                            let (lone, others, lone_inside) = if inside.len() == 1 {
                                (inside[0], outside, true)
                            } else {
                                (outside[0], inside, false)
                            };
                            let mut tri = [0u32; 3];
                            let mut mids = [DVec3::ZERO; 3];
                            for (s, &o) in others.iter().enumerate() {
                                tri[s] = if lone_inside {
                                    edge_vertex(tet[lone], tet[o], &mut verts)
                                } else {
                                    edge_vertex(tet[o], tet[lone], &mut verts)
                                };
                                mids[s] = mid(tet[lone], tet[o]);
                            }
                            let away = if lone_inside { 1.0 } else { -1.0 };
                            faces.push(oriented(tri, mids, tet[lone].1, away));
                        }
                        2 => {
                            let (i0, i1, o0, o1) = (inside[0], inside[1], outside[0], outside[1]);
                            let q = [
                                edge_vertex(tet[i0], tet[o0], &mut verts),
                                edge_vertex(tet[i0], tet[o1], &mut verts),
                                edge_vertex(tet[i1], tet[o1], &mut verts),
                                edge_vertex(tet[i1], tet[o0], &mut verts),
                            ];
                            let m = [
                                mid(tet[i0], tet[o0]),
                                mid(tet[i0], tet[o1]),
                                mid(tet[i1], tet[o1]),
                                mid(tet[i1], tet[o0]),
                            ];
                            let ci = 0.5 * (tet[i0].1 + tet[i1].1);
                            faces.push(oriented([q[0], q[1], q[2]], [m[0], m[1], m[2]], ci, 1.0));
                            faces.push(oriented([q[0], q[2], q[3]], [m[0], m[2], m[3]], ci, 1.0));
                        }
                        _ => {}
                    }
                }
            }
        }
    }
    (verts, faces)
}

/// `tri` oriented so that the normal of its stand-in `pos` points away from `from`
/// (`away = 1`) or towards it (`away = -1`).
fn oriented(tri: [u32; 3], pos: [DVec3; 3], from: DVec3, away: f64) -> [u32; 3] {
    let [a, b, c] = pos;
    let n = (b - a).cross(c - a);
    let centroid = (a + b + c) / 3.0;
    if n.dot(centroid - from) * away >= 0.0 {
        tri
    } else {
        [tri[0], tri[2], tri[1]]
    }
}
