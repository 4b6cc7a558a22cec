//! Sharp edges of a triangle mesh (creases between faces whose normals differ by more than
//! an angle) and their chaining into feature polylines: the ground-truth feature curves of
//! a mesh reference or a mesh data set.

use rayon::prelude::*;

use super::MeshTopology;
use crate::mesh::TriMesh;

/// A manifold edge whose two face normals differ by at least the asked angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SharpEdge {
    /// Vertex ids, `lo < hi`.
    pub v: [u32; 2],
    /// Angle between the two unit face normals, degrees (90 for a cube edge).
    pub angle_deg: f64,
}

/// Manifold edges (exactly two faces of non-zero area) whose unit face normals differ by
/// at least `min_angle_deg`, in edge-id order. Faces are compared as given: on a mesh
/// that is not consistently oriented a flipped neighbour reads as a 180 degree crease.
pub fn sharp_edges(mesh: &TriMesh, topo: &MeshTopology, min_angle_deg: f64) -> Vec<SharpEdge> {
    (0..topo.n_edges())
        .into_par_iter()
        .filter_map(|e| {
            let fs = topo.edge_faces(e);
            if fs.len() != 2 {
                return None;
            }
            let (n1, n2) = (
                mesh.face_normal(fs[0] as usize),
                mesh.face_normal(fs[1] as usize),
            );
            if n1 == glam::DVec3::ZERO || n2 == glam::DVec3::ZERO {
                return None;
            }
            let angle_deg = n1.dot(n2).clamp(-1.0, 1.0).acos().to_degrees();
            (angle_deg >= min_angle_deg).then(|| SharpEdge {
                v: topo.edges()[e],
                angle_deg,
            })
        })
        .collect()
}

/// A maximal run of sharp edges through vertices where exactly two sharp edges meet.
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureChain {
    /// Vertex ids along the chain; a closed loop repeats its first vertex at the end.
    pub vertices: Vec<u32>,
    /// Largest normal angle along the chain, degrees.
    pub max_angle_deg: f64,
}

/// Chains and corners of a set of sharp edges: every chain ends at a vertex where the
/// number of sharp edges is not two (an end or a junction), or closes on itself; corners
/// are the vertices where three or more sharp edges meet, each with the largest angle of
/// its edges. Deterministic: chains start at the lowest free vertex id.
pub fn feature_chains(
    n_vertices: usize,
    edges: &[SharpEdge],
) -> (Vec<FeatureChain>, Vec<(u32, f64)>) {
    // Vertex -> incident sharp edges, in CSR form.
    let mut offsets = vec![0usize; n_vertices + 1];
    for e in edges {
        offsets[e.v[0] as usize + 1] += 1;
        offsets[e.v[1] as usize + 1] += 1;
    }
    for i in 0..n_vertices {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut inc = vec![0u32; offsets[n_vertices]];
    for (i, e) in edges.iter().enumerate() {
        for &v in &e.v {
            inc[fill[v as usize]] = i as u32;
            fill[v as usize] += 1;
        }
    }
    let degree = |v: usize| offsets[v + 1] - offsets[v];
    let mut used = vec![false; edges.len()];
    let mut chains = Vec::new();
    let walk = |start: u32, first: usize, used: &mut Vec<bool>| {
        let mut vertices = vec![start];
        let mut max_angle_deg: f64 = 0.0;
        let (mut v, mut e) = (start, first);
        loop {
            used[e] = true;
            max_angle_deg = max_angle_deg.max(edges[e].angle_deg);
            let [a, b] = edges[e].v;
            v = if a == v { b } else { a };
            vertices.push(v);
            if degree(v as usize) != 2 || v == start {
                break;
            }
            match inc[offsets[v as usize]..offsets[v as usize + 1]]
                .iter()
                .find(|&&x| !used[x as usize])
            {
                Some(&next) => e = next as usize,
                None => break,
            }
        }
        FeatureChain {
            vertices,
            max_angle_deg,
        }
    };
    // Open chains from ends and junctions first, then the remaining closed loops.
    for pass in 0..2 {
        for v in 0..n_vertices {
            if pass == 0 && degree(v) == 2 {
                continue;
            }
            for k in offsets[v]..offsets[v + 1] {
                let e = inc[k] as usize;
                if !used[e] {
                    chains.push(walk(v as u32, e, &mut used));
                }
            }
        }
    }
    let corners = (0..n_vertices)
        .filter(|&v| degree(v) >= 3)
        .map(|v| {
            let a = inc[offsets[v]..offsets[v + 1]]
                .iter()
                .map(|&e| edges[e as usize].angle_deg)
                .fold(0.0, f64::max);
            (v as u32, a)
        })
        .collect();
    (chains, corners)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn unit_cube() -> TriMesh {
        let v: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut f = Vec::new();
        for q in quads {
            f.push([q[0], q[1], q[2]]);
            f.push([q[0], q[2], q[3]]);
        }
        TriMesh::new(v, f).unwrap()
    }

    #[test]
    fn cube_has_twelve_right_angle_edges_and_eight_corners() {
        let m = unit_cube();
        let topo = MeshTopology::new(&m);
        let sharp = sharp_edges(&m, &topo, 20.0);
        assert_eq!(sharp.len(), 12, "the 6 face diagonals are flat");
        assert!(sharp.iter().all(|e| (e.angle_deg - 90.0).abs() < 1e-9));
        let (chains, corners) = feature_chains(m.n_vertices(), &sharp);
        assert_eq!(corners.len(), 8);
        // Every vertex is a junction, so each edge is its own chain.
        assert_eq!(chains.len(), 12);
        assert!(chains.iter().all(|c| c.vertices.len() == 2));
        assert!(sharp_edges(&m, &topo, 90.0 + 1e-6).is_empty());
    }

    #[test]
    fn a_loop_of_degree_two_vertices_closes_on_itself() {
        // A square loop 0-1-2-3-0 plus a tail 3-4.
        let e = |a: u32, b: u32| SharpEdge {
            v: [a.min(b), a.max(b)],
            angle_deg: 30.0 + f64::from(a),
        };
        let (chains, corners) = feature_chains(6, &[e(0, 1), e(1, 2), e(2, 3), e(0, 3)]);
        assert!(corners.is_empty());
        assert_eq!(chains.len(), 1);
        assert_eq!(chains[0].vertices.first(), chains[0].vertices.last());
        assert_eq!(chains[0].vertices.len(), 5);
        assert_eq!(chains[0].max_angle_deg, 32.0);
        let (chains, corners) = feature_chains(6, &[e(0, 1), e(1, 2), e(2, 3), e(0, 3), e(3, 4)]);
        assert_eq!(corners, vec![(3, 33.0)]);
        // From junction 3: around the loop back to 3, and the tail.
        assert_eq!(chains.len(), 2);
        assert_eq!(
            chains.iter().map(|c| c.vertices.len() - 1).sum::<usize>(),
            5
        );
    }
}
