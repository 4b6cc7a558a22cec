//! The "incorrect facets" of Table 1 (ASSUMPTION E22): every facet that breaks a rule of
//! the growth, by category, and their union.
//!
//! * R1: an edge longer than Omega (1 + 1e-6).
//! * R2: a smallest angle below theta.
//! * R3: a facet on a non-manifold edge (three or more facets), or a T-junction (a mesh
//!   vertex within 1e-3 Omega of the interior of an edge it does not belong to: the
//!   edge's facets count).
//! * overlap: a fold-over (two consistently oriented facets on an edge whose normals
//!   differ by more than 90 degrees) or an intersection between facets that share no
//!   vertex (exact triangle-triangle test on the candidates of a hash grid).

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::method::MethodError;
use reconbench_geom::spatial::tri_tri_intersect;
use reconbench_geom::topology::MeshTopology;

use super::geometry::{face_cross, interior_distance, min_angle};
use super::grid::Grid;

/// Facet flags of each category (bit set).
pub const R1: u8 = 1;
/// See [`R1`].
pub const R2: u8 = 2;
/// See [`R1`].
pub const R3: u8 = 4;
/// See [`R1`].
pub const OVERLAP: u8 = 8;

/// Counts of bad facets.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct BadFacets {
    /// Facets with an edge longer than Omega.
    pub r1: usize,
    /// Facets with a smallest angle below theta.
    pub r2: usize,
    /// Facets on a non-manifold edge or at a T-junction.
    pub r3: usize,
    /// Folded or intersecting facets.
    pub overlap: usize,
    /// Facets in any category.
    pub total: usize,
    /// Per facet, the OR of the category bits.
    pub flags: Vec<u8>,
}

/// Validates `faces` over `verts` against Omega and theta (radians).
pub fn bad_facets(
    verts: &[DVec3],
    faces: &[[u32; 3]],
    omega: f64,
    theta: f64,
) -> Result<BadFacets, MethodError> {
    bad_facets_with_closure(verts, faces, omega, theta, None)
}

/// [`bad_facets`] with crack closing on: R1 is checked against the longest closing
/// edge `closing_edge` (when larger than Omega) instead of Omega, on every facet, since
/// a closing edge becomes a boundary edge that later facets may take (the deviation
/// allows it; docs/methods/ebt.md). `None` is [`bad_facets`].
pub fn bad_facets_with_closure(
    verts: &[DVec3],
    faces: &[[u32; 3]],
    omega: f64,
    theta: f64,
    closing_edge: Option<f64>,
) -> Result<BadFacets, MethodError> {
    let nf = faces.len();
    let mut flags = vec![0u8; nf];
    let tri = |f: usize| faces[f].map(|i| verts[i as usize]);
    let lmax = closing_edge.map_or(omega, |e| e.max(omega)) * (1.0 + 1e-6);
    let mut longest = 0.0f64;
    for (f, fl) in flags.iter_mut().enumerate() {
        let [a, b, c] = tri(f);
        let l = (a - b).length().max((b - c).length()).max((c - a).length());
        longest = longest.max(l);
        if l > lmax {
            *fl |= R1;
        }
        if min_angle(a, b, c) < theta {
            *fl |= R2;
        }
    }
    let topo = MeshTopology::from_faces(verts.len(), faces);
    let mut used = vec![false; verts.len()];
    for f in faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    let used_ids: Vec<u32> = (0..verts.len() as u32)
        .filter(|&i| used[i as usize])
        .collect();
    if nf == 0 {
        return Ok(BadFacets::default());
    }
    let cell = longest.max(omega).max(f64::MIN_POSITIVE);
    let vgrid = Grid::new(verts, &used_ids, cell)?;
    let tj = 1e-3 * omega;
    for (e, &[a, b]) in topo.edges().iter().enumerate() {
        let ef = topo.edge_faces(e);
        let mut bad = ef.len() > 2;
        if !bad {
            let (pa, pb) = (verts[a as usize], verts[b as usize]);
            let mid = (pa + pb) * 0.5;
            let r = (pa - pb).length() * 0.5 + tj;
            vgrid.for_each_near(mid, r, |w| {
                if w != a
                    && w != b
                    && interior_distance(verts[w as usize], pa, pb).is_some_and(|d| d < tj)
                {
                    bad = true;
                }
            });
        }
        if bad {
            for &f in ef {
                flags[f as usize] |= R3;
            }
        }
        // Fold-over between two consistently oriented facets.
        if ef.len() == 2 && topo.edge_orientation_conflict(e) == Some(false) {
            let (f, g) = (ef[0] as usize, ef[1] as usize);
            let [a0, b0, c0] = tri(f);
            let [a1, b1, c1] = tri(g);
            if face_cross(a0, b0, c0).dot(face_cross(a1, b1, c1)) < 0.0 {
                flags[f] |= OVERLAP;
                flags[g] |= OVERLAP;
            }
        }
    }
    // Intersections between facets sharing no vertex.
    let centroids: Vec<DVec3> = (0..nf)
        .map(|f| {
            let [a, b, c] = tri(f);
            (a + b + c) / 3.0
        })
        .collect();
    let fids: Vec<u32> = (0..nf as u32).collect();
    let fgrid = Grid::new(&centroids, &fids, cell)?;
    let hits: Vec<(u32, u32)> = (0..nf)
        .into_par_iter()
        .flat_map_iter(|f| {
            let tf = tri(f);
            let mut out = Vec::new();
            fgrid.for_each_near(centroids[f], cell, |g| {
                let g = g as usize;
                if g > f
                    && !faces[g].iter().any(|v| faces[f].contains(v))
                    && tri_tri_intersect(&tf, &tri(g))
                {
                    out.push((f as u32, g as u32));
                }
            });
            out
        })
        .collect();
    for (f, g) in hits {
        flags[f as usize] |= OVERLAP;
        flags[g as usize] |= OVERLAP;
    }
    let count = |bit: u8| flags.iter().filter(|&&x| x & bit != 0).count();
    Ok(BadFacets {
        r1: count(R1),
        r2: count(R2),
        r3: count(R3),
        overlap: count(OVERLAP),
        total: flags.iter().filter(|&&x| x != 0).count(),
        flags,
    })
}
