//! Stray pieces (IMPL-CHOICE I18, not in the paper; issue 20; `stray_piece_max`).
//!
//! A restart seed laid in a small patch of points left Free beside finished mesh grows a
//! piece of a few triangles over or under that mesh, and closing its short boundary
//! (IMPL-CHOICE I7) can turn it into a closed pillow of two back-to-back layers. On the
//! real CAD sets every extra component of 3-10 vertices is of this kind: all its
//! vertices lie within a fraction of R of the surface of the larger pieces. Such a piece
//! is taken apart (its faces removed, its points Free again), so that the surface
//! completion (I15) inserts its points into the mesh they lie on, or the fill closes the
//! hole it sat in. A small piece farther than R from every larger piece is kept: it may
//! be a small part of its own.

use glam::DVec3;
use reconbench_geom::TriMesh;
use reconbench_geom::spatial::MeshBvh;

use super::mesher::FREE;
use crate::hc_it::cluster::UnionFind;

/// Removes every piece (component by shared vertices) of at most `max_vertices`
/// vertices whose vertices all lie within `max_dist` of the faces of the pieces larger
/// than that; its points become [`FREE`] and the front loops through them are dropped.
/// Returns the number of pieces removed.
pub(super) fn dissolve_stray_pieces(
    pts: &[DVec3],
    tris: &mut Vec<[u32; 3]>,
    state: &mut [u8],
    loops: &mut Vec<Vec<u32>>,
    max_vertices: usize,
    max_dist: f64,
) -> usize {
    if max_vertices == 0 || tris.is_empty() {
        return 0;
    }
    let mut root = UnionFind::new(pts.len());
    for t in tris.iter() {
        root.union(t[0], t[1]);
        root.union(t[0], t[2]);
    }
    let mut used = vec![false; pts.len()];
    for &v in tris.iter().flatten() {
        used[v as usize] = true;
    }
    // A set's size is its piece's vertex count (points without a face stay singletons).
    let small = |root: &mut UnionFind, v: u32| {
        let r = root.find(v);
        root.size(r) as usize <= max_vertices
    };
    let host: Vec<[u32; 3]> = tris
        .iter()
        .filter(|t| !small(&mut root, t[0]))
        .copied()
        .collect();
    if host.is_empty() || host.len() == tris.len() {
        return 0;
    }
    let Ok(bvh) = TriMesh::new(pts.to_vec(), host).and_then(|m| MeshBvh::new(&m)) else {
        return 0;
    };
    // A small piece stays when any of its vertices lies farther than `max_dist`.
    let mut keep = vec![false; pts.len()];
    for v in 0..pts.len() as u32 {
        if used[v as usize] && small(&mut root, v) {
            let near = bvh.distance(pts[v as usize]).is_ok_and(|d| d <= max_dist);
            if !near {
                keep[root.find(v) as usize] = true;
            }
        }
    }
    let mut gone = vec![false; pts.len()];
    let mut pieces = 0;
    for v in 0..pts.len() as u32 {
        let r = root.find(v);
        if used[v as usize] && small(&mut root, v) && !keep[r as usize] {
            gone[v as usize] = true;
            if r == v {
                pieces += 1;
            }
        }
    }
    if pieces == 0 {
        return 0;
    }
    tris.retain(|t| !gone[t[0] as usize]);
    loops.retain(|l| !l.iter().any(|&v| gone[v as usize]));
    for (s, &g) in state.iter_mut().zip(&gone) {
        if g {
            *s = FREE;
        }
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::priority_front::mesher::ACCEPTED;

    /// A 6 x 6 grid of unit squares in z = 0 (72 triangles, 49 vertices) plus a
    /// two-triangle quad at height `dz` over its middle, vertices 49-52.
    fn sheet_with_fan(dz: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut pts = Vec::new();
        for j in 0..7 {
            for i in 0..7 {
                pts.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let mut tris = Vec::new();
        for j in 0..6u32 {
            for i in 0..6u32 {
                let a = j * 7 + i;
                tris.push([a, a + 1, a + 8]);
                tris.push([a, a + 8, a + 7]);
            }
        }
        for q in [[3.1, 3.1], [3.9, 3.2], [3.8, 3.9], [3.2, 3.8]] {
            pts.push(DVec3::new(q[0], q[1], dz));
        }
        tris.extend([[49, 50, 51], [49, 51, 52]]);
        (pts, tris)
    }

    /// A small piece lying on a larger one is removed and its points freed; the same
    /// piece farther than the bound is kept, and so is every piece when the bound is 0.
    #[test]
    fn small_piece_on_the_mesh_is_dissolved_far_one_kept() {
        for (dz, removed) in [(0.2, 1), (2.0, 0)] {
            let (pts, mut tris) = sheet_with_fan(dz);
            let mut state = vec![ACCEPTED; pts.len()];
            let mut loops = vec![vec![49, 50, 51, 52], vec![0, 1, 2]];
            let n = dissolve_stray_pieces(&pts, &mut tris, &mut state, &mut loops, 20, 0.5);
            assert_eq!(n, removed, "dz {dz}");
            assert_eq!(tris.len(), 74 - 2 * removed, "dz {dz}");
            assert_eq!(loops.len(), 2 - removed, "dz {dz}");
            let freed = state.iter().filter(|&&s| s == FREE).count();
            assert_eq!(freed, 4 * removed, "dz {dz}");
        }
        let (pts, mut tris) = sheet_with_fan(0.2);
        let mut state = vec![ACCEPTED; pts.len()];
        assert_eq!(
            dissolve_stray_pieces(&pts, &mut tris, &mut state, &mut Vec::new(), 0, 0.5),
            0
        );
        // With the size bound above the sheet's 49 vertices no piece is a host.
        assert_eq!(
            dissolve_stray_pieces(&pts, &mut tris, &mut state, &mut Vec::new(), 100, 0.5),
            0
        );
    }
}
