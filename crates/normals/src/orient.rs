//! Consistent normal orientation by minimum-spanning-tree propagation (Hoppe et al.
//! 1992), usable after any estimator.
//!
//! The graph is the symmetrised k-NN graph with edge cost `1 - |n_i . n_j|`, so
//! propagation prefers nearly parallel neighbours. In each connected component the
//! point with the largest z coordinate is oriented towards +z (outward for a closed
//! surface) and the orientation is propagated along the MST (Prim), flipping a normal
//! whenever it disagrees with its tree parent.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;
use reconbench_geom::method::MethodError;
use reconbench_geom::spatial::knn_self_table;

/// What orientation did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OrientReport {
    /// Connected components of the k-NN graph (each oriented independently).
    pub components: usize,
    /// Normals flipped.
    pub flipped: usize,
}

/// Symmetrised k-NN adjacency in CSR form.
fn knn_graph(points: &[DVec3], k: usize) -> Result<(Vec<u32>, Vec<u32>), MethodError> {
    let n = points.len();
    let table = knn_self_table(points, k, true)?;
    let k = table.k;
    let mut degree = vec![0u32; n + 1];
    for (i, row) in table.indices.chunks(k).enumerate() {
        for &j in row {
            degree[i] += 1;
            degree[j as usize] += 1;
        }
    }
    let mut offsets = vec![0u32; n + 1];
    for i in 0..n {
        offsets[i + 1] = offsets[i] + degree[i];
    }
    let mut fill = offsets.clone();
    let mut adj = vec![0u32; offsets[n] as usize];
    for (i, row) in table.indices.chunks(k).enumerate() {
        for &j in row {
            adj[fill[i] as usize] = j;
            fill[i] += 1;
            adj[fill[j as usize] as usize] = i as u32;
            fill[j as usize] += 1;
        }
    }
    Ok((offsets, adj))
}

/// Orients `normals` in place (see the module documentation). Zero normals are left as
/// they are and pass their parent's orientation on. Fewer than 2 points: nothing to do.
pub fn orient_mst(
    points: &[DVec3],
    normals: &mut [DVec3],
    k: usize,
) -> Result<OrientReport, MethodError> {
    let n = points.len();
    if normals.len() != n {
        return Err(MethodError::InvalidInput(format!(
            "{} normals for {n} points",
            normals.len()
        )));
    }
    let mut report = OrientReport::default();
    if n == 0 {
        return Ok(report);
    }
    if n == 1 || k == 0 {
        report.components = n;
        return Ok(report);
    }
    let (offsets, adj) = knn_graph(points, k)?;
    let nbrs = |i: usize| &adj[offsets[i] as usize..offsets[i + 1] as usize];

    // Components by BFS, each rooted at its highest point.
    let mut comp = vec![u32::MAX; n];
    let mut roots = Vec::new();
    let mut stack = Vec::new();
    for s in 0..n {
        if comp[s] != u32::MAX {
            continue;
        }
        let c = roots.len() as u32;
        let mut root = s;
        comp[s] = c;
        stack.push(s);
        while let Some(i) = stack.pop() {
            if points[i].z > points[root].z || (points[i].z == points[root].z && i < root) {
                root = i;
            }
            for &j in nbrs(i) {
                if comp[j as usize] == u32::MAX {
                    comp[j as usize] = c;
                    stack.push(j as usize);
                }
            }
        }
        roots.push(root);
    }
    report.components = roots.len();

    // Prim from each root; `reference[v]` is the nearest non-zero normal on the tree
    // path to v, used to decide v's children.
    let mut done = vec![false; n];
    let mut reference = vec![DVec3::ZERO; n];
    let mut heap: BinaryHeap<Reverse<(u64, u32, u32)>> = BinaryHeap::new();
    let cost = |a: DVec3, b: DVec3| (1.0 - a.dot(b).abs()).max(0.0).to_bits();
    for &root in &roots {
        if normals[root].z < 0.0 {
            normals[root] = -normals[root];
            report.flipped += 1;
        }
        done[root] = true;
        reference[root] = normals[root];
        for &j in nbrs(root) {
            heap.push(Reverse((
                cost(normals[root], normals[j as usize]),
                j,
                root as u32,
            )));
        }
        while let Some(Reverse((_, v, parent))) = heap.pop() {
            let v = v as usize;
            if done[v] {
                continue;
            }
            done[v] = true;
            let r = reference[parent as usize];
            if normals[v] == DVec3::ZERO {
                reference[v] = r;
            } else {
                if normals[v].dot(r) < 0.0 {
                    normals[v] = -normals[v];
                    report.flipped += 1;
                }
                reference[v] = normals[v];
            }
            for &j in nbrs(v) {
                if !done[j as usize] {
                    heap.push(Reverse((
                        cost(reference[v], normals[j as usize]),
                        j,
                        v as u32,
                    )));
                }
            }
        }
    }
    Ok(report)
}
