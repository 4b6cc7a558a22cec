//! Queries: Delaunay triangles, vertex incidences, circumspheres, the Gabriel test.

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::predicates::in_diametral_sphere;
use crate::{Csr, Delaunay, INFINITE, NO_TET};

/// A Delaunay triangle (a 2-face of the finite tetrahedralization).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Facet {
    /// Vertices, sorted increasingly.
    pub v: [u32; 3],
    /// The incident finite tetrahedra, `tets[0] < tets[1]`; for a convex-hull facet
    /// `tets[1] == NO_TET`.
    pub tets: [u32; 2],
}

impl Facet {
    /// Whether the facet lies on the convex hull (has one finite tetrahedron).
    pub fn is_hull(&self) -> bool {
        self.tets[1] == NO_TET
    }
}

/// Vertex indices of face `i` of a tetrahedron (any order).
const FACE: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

fn sorted3(mut v: [u32; 3]) -> [u32; 3] {
    if v[0] > v[1] {
        v.swap(0, 1);
    }
    if v[1] > v[2] {
        v.swap(1, 2);
    }
    if v[0] > v[1] {
        v.swap(0, 1);
    }
    v
}

impl Delaunay {
    /// All Delaunay triangles, each once, in lexicographic order of their sorted vertex
    /// triples (so the facet id is a deterministic tie-breaker). Computed on first use.
    pub fn facets(&self) -> &[Facet] {
        self.facets.get_or_init(|| {
            let nf = self.n_finite as u32;
            let out: Vec<Facet> = (0..nf)
                .into_par_iter()
                .fold(Vec::new, |mut acc, t| {
                    let v = self.tets[t as usize].v;
                    let nb = self.tets[t as usize].n;
                    for i in 0..4 {
                        let n = nb[i] >> 2;
                        if n >= nf || t < n {
                            let f = FACE[i];
                            acc.push(Facet {
                                v: sorted3([v[f[0]], v[f[1]], v[f[2]]]),
                                tets: [t, if n >= nf { NO_TET } else { n }],
                            });
                        }
                    }
                    acc
                })
                .reduce(Vec::new, |mut a, mut b| {
                    if a.len() < b.len() {
                        std::mem::swap(&mut a, &mut b);
                    }
                    a.extend_from_slice(&b);
                    a
                });
            // Counting sort by the first vertex, then each (small) bucket in parallel.
            let nv = self.n_vertices();
            let mut start = vec![0usize; nv + 1];
            for f in &out {
                start[f.v[0] as usize + 1] += 1;
            }
            for i in 0..nv {
                start[i + 1] += start[i];
            }
            let mut sorted = vec![
                Facet {
                    v: [0; 3],
                    tets: [0; 2]
                };
                out.len()
            ];
            for f in out {
                let s = &mut start[f.v[0] as usize];
                sorted[*s] = f;
                *s += 1;
            }
            sorted
                .par_chunk_by_mut(|a, b| a.v[0] == b.v[0])
                .for_each(|c| c.sort_unstable_by_key(|f| f.v));
            sorted
        })
    }

    /// Number of convex-hull facets.
    pub fn n_hull_facets(&self) -> usize {
        self.n_all_tets() - self.n_finite
    }

    /// Ids (into [`facets`](Self::facets)) of the Delaunay triangles incident to vertex
    /// `v`, increasing. Computed for all vertices on first use.
    pub fn facets_of_vertex(&self, v: u32) -> &[u32] {
        self.vertex_facets
            .get_or_init(|| {
                let facets = self.facets();
                let nv = self.n_vertices();
                let mut offsets = vec![0u32; nv + 1];
                for f in facets {
                    for &x in &f.v {
                        offsets[x as usize + 1] += 1;
                    }
                }
                for i in 0..nv {
                    offsets[i + 1] += offsets[i];
                }
                let mut fill = offsets.clone();
                let mut items = vec![0u32; offsets[nv] as usize];
                for (id, f) in facets.iter().enumerate() {
                    for &x in &f.v {
                        items[fill[x as usize] as usize] = id as u32;
                        fill[x as usize] += 1;
                    }
                }
                Csr { offsets, items }
            })
            .row(v as usize)
    }

    /// Vertices joined to `v` by a Delaunay edge, increasing. Computed for all vertices
    /// on first use.
    pub fn edges_of_vertex(&self, v: u32) -> &[u32] {
        self.vertex_edges
            .get_or_init(|| {
                // Vertex -> finite tetrahedra, then the union of their vertices.
                let nv = self.n_vertices();
                let finite = &self.tets[..self.n_finite];
                let mut vt_off = vec![0u32; nv + 1];
                for t in finite {
                    for &x in &t.v {
                        vt_off[x as usize + 1] += 1;
                    }
                }
                for i in 0..nv {
                    vt_off[i + 1] += vt_off[i];
                }
                let mut fill = vt_off.clone();
                let mut vt = vec![0u32; vt_off[nv] as usize];
                for (t, tet) in finite.iter().enumerate() {
                    for &x in &tet.v {
                        vt[fill[x as usize] as usize] = t as u32;
                        fill[x as usize] += 1;
                    }
                }
                drop(fill);
                let rows: Vec<Vec<u32>> = (0..nv)
                    .into_par_iter()
                    .map_init(Vec::new, |scratch: &mut Vec<u32>, x| {
                        scratch.clear();
                        for &t in &vt[vt_off[x] as usize..vt_off[x + 1] as usize] {
                            for &y in &finite[t as usize].v {
                                if y != x as u32 {
                                    scratch.push(y);
                                }
                            }
                        }
                        scratch.sort_unstable();
                        scratch.dedup();
                        scratch.clone()
                    })
                    .collect();
                let mut offsets = Vec::with_capacity(nv + 1);
                offsets.push(0u32);
                let mut items = Vec::with_capacity(rows.iter().map(Vec::len).sum());
                for r in rows {
                    items.extend_from_slice(&r);
                    offsets.push(items.len() as u32);
                }
                Csr { offsets, items }
            })
            .row(v as usize)
    }

    /// Circumcentre of tetrahedron `t` (a Voronoi vertex). Non-finite for an infinite
    /// tetrahedron. Computed in `f64` relative to the first vertex.
    pub fn circumcenter(&self, t: u32) -> DVec3 {
        let v = self.tets[t as usize].v;
        if v.contains(&INFINITE) {
            return DVec3::splat(f64::INFINITY);
        }
        let a = self.points[v[0] as usize];
        let b = self.points[v[1] as usize] - a;
        let c = self.points[v[2] as usize] - a;
        let d = self.points[v[3] as usize] - a;
        let det = b.dot(c.cross(d));
        let num = b.length_squared() * c.cross(d)
            + c.length_squared() * d.cross(b)
            + d.length_squared() * b.cross(c);
        a + num / (2.0 * det)
    }

    /// Circumradius of tetrahedron `t` (`+∞` for an infinite one).
    pub fn circumradius(&self, t: u32) -> f64 {
        let v = self.tets[t as usize].v;
        if v.contains(&INFINITE) {
            return f64::INFINITY;
        }
        let c = self.circumcenter(t);
        c.distance(self.points[v[0] as usize])
    }

    /// Smallest sphere through the three vertices of facet `f` (centre in the facet's
    /// plane, radius = circumradius of the triangle). A degenerate triangle gives an
    /// infinite radius (cannot happen for facets of this triangulation).
    pub fn facet_circumsphere(&self, f: u32) -> (DVec3, f64) {
        let v = self.facets()[f as usize].v;
        let a = self.points[v[0] as usize];
        let u = self.points[v[1] as usize] - a;
        let w = self.points[v[2] as usize] - a;
        let n = u.cross(w);
        let nn = n.length_squared();
        if nn == 0.0 {
            return (DVec3::splat(f64::INFINITY), f64::INFINITY);
        }
        let off = (u.length_squared() * w.cross(n) + w.length_squared() * n.cross(u)) / (2.0 * nn);
        (a + off, off.length())
    }

    /// Exact Gabriel test of facet `f`: `true` iff no vertex lies strictly inside the
    /// smallest sphere through its three vertices (points on the sphere count as outside).
    ///
    /// Only the apexes of the (one or two) incident finite tetrahedra are tested; this is
    /// exact. Proof: the centres of the spheres through the triangle `abc` form the line
    /// `c(s) = c_t + s·n` (`c_t` the triangle's circumcentre, `n` its normal), and the
    /// power `|p − c(s)|² − r(s)²` of a point `p` is affine in `s`, so the set of `s`
    /// whose open ball is empty is an interval `I`. Every finite tetrahedron of the
    /// triangulation is non-flat, and its circumscribed open ball is empty (it is the
    /// limit of the empty balls of the symbolically perturbed triangulation), so the
    /// parameters `s1, s2` of the two incident circumspheres lie in `I`. The apex `d_k`
    /// of tetrahedron `k` is strictly on one side of the plane, so its own constraint is
    /// exactly a half-line ending at `s_k`; the two half-lines point in opposite
    /// directions, hence `I = [s2, s1]` = the intersection of the two apex constraints.
    /// For a hull facet, no point lies strictly outside the hull, so the outer side is
    /// unconstrained and `I = [s2, ∞)`. Thus `0 ∈ I` — the diametral ball is empty — iff
    /// neither apex is strictly inside it.
    pub fn is_gabriel(&self, f: u32) -> bool {
        let facet = &self.facets()[f as usize];
        let [a, b, c] = facet.v.map(|x| self.p(x));
        for &t in &facet.tets {
            if t == NO_TET {
                continue;
            }
            let tv = self.tets[t as usize].v;
            let d = tv[0] ^ tv[1] ^ tv[2] ^ tv[3] ^ facet.v[0] ^ facet.v[1] ^ facet.v[2];
            if in_diametral_sphere(a, b, c, self.p(d)) {
                return false;
            }
        }
        true
    }

    /// [`is_gabriel`](Self::is_gabriel) for every facet, in parallel.
    pub fn gabriel_flags(&self) -> Vec<bool> {
        let n = self.facets().len() as u32;
        (0..n).into_par_iter().map(|f| self.is_gabriel(f)).collect()
    }

    /// One finite tetrahedron incident to each vertex (useful to start local searches).
    pub fn vertex_tets(&self) -> Vec<u32> {
        let mut out = vec![NO_TET; self.n_vertices()];
        for (t, tet) in self.tets[..self.n_finite].iter().enumerate() {
            for &x in &tet.v {
                out[x as usize] = t as u32;
            }
        }
        out
    }
}
