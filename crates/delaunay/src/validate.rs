//! Exhaustive, exact validation of a triangulation (for tests and debugging).

use rayon::prelude::*;

use crate::predicates::{insphere_sos, orient3d, orient3d_exact};
use crate::{Delaunay, INFINITE};

impl Delaunay {
    /// Conflict of point `d` (a vertex) with tetrahedron `t` under the symbolic
    /// perturbation used during construction.
    pub(crate) fn conflict_sos(&self, t: u32, d: u32) -> bool {
        let v = self.tets[t as usize].v;
        let p = self.p(d);
        match v.iter().position(|&x| x == INFINITE) {
            None => self.finite_conflict_sos(t, d),
            Some(k) => {
                let mut q = v.map(|x| if x == INFINITE { p } else { self.p(x) });
                q[k] = p;
                let s = orient3d(q[0], q[1], q[2], q[3]);
                if s != 0 {
                    return s > 0;
                }
                let n = self.tets[t as usize].n[k] >> 2;
                self.finite_conflict_sos(n, d)
            }
        }
    }

    fn finite_conflict_sos(&self, t: u32, d: u32) -> bool {
        let v = self.tets[t as usize].v;
        let pts = v.map(|x| self.p(x));
        let ranks = v.map(|x| self.rank[x as usize]);
        insphere_sos(pts, ranks, self.p(d), self.rank[d as usize]) > 0
    }

    /// Checks, exactly:
    /// * combinatorics: finite tetrahedra have 4 distinct finite vertices, infinite ones
    ///   exactly one [`INFINITE`] vertex; neighbour relations are symmetric and neighbours
    ///   share the right three vertices;
    /// * every vertex is used by a finite tetrahedron; the duplicate map is consistent;
    /// * every finite tetrahedron is positively oriented (non-zero volume);
    /// * every facet is locally Delaunay under the symbolic perturbation (the apex of each
    ///   neighbour is outside the circumsphere; for hull facets this is local convexity),
    ///   which together with the above implies a Delaunay triangulation;
    /// * Euler relations: `V − E + F − T = 1` for the tetrahedralization (a 3-ball) and
    ///   `V − E + F = 2` for its convex-hull surface.
    ///
    /// The geometric checks read the coordinates the construction rescaled exactly by a
    /// power of two into the predicates' safe window, so they are exact at any scale the
    /// construction accepts.
    /// Cost: a few seconds per million points (parallel).
    pub fn validate(&self) -> Result<(), String> {
        let nv = self.n_vertices() as u32;
        let nall = self.n_all_tets() as u32;
        let nf = self.n_finite as u32;
        let mut used = vec![false; nv as usize];
        for t in 0..nall {
            let v = self.tets[t as usize].v;
            let n_inf = v.iter().filter(|&&x| x == INFINITE).count();
            if (t < nf && n_inf != 0) || (t >= nf && n_inf != 1) {
                return Err(format!("tet {t} {v:?}: wrong number of infinite vertices"));
            }
            for i in 0..4 {
                if v[i] != INFINITE && v[i] >= nv {
                    return Err(format!("tet {t}: vertex {} out of range", v[i]));
                }
                for j in 0..i {
                    if v[i] == v[j] {
                        return Err(format!("tet {t} {v:?}: repeated vertex"));
                    }
                }
                if t < nf {
                    used[v[i] as usize] = true;
                }
                let code = self.tets[t as usize].n[i];
                let (n, j) = (code >> 2, (code & 3) as usize);
                if n >= nall || n == t {
                    return Err(format!("tet {t}: bad neighbour {n}"));
                }
                if self.tets[n as usize].n[j] != 4 * t + i as u32 {
                    return Err(format!(
                        "tet {t} face {i}: neighbour {n} does not point back"
                    ));
                }
                let w = self.tets[n as usize].v;
                if w[j] == v[i] {
                    return Err(format!("tets {t} and {n} have the same vertices"));
                }
                for k in 0..4 {
                    if k != i && !(0..4).any(|l| l != j && w[l] == v[k]) {
                        return Err(format!(
                            "tets {t} {v:?} and {n} {w:?} do not share face {i}/{j}"
                        ));
                    }
                }
            }
        }
        if let Some(v) = used.iter().position(|&u| !u) {
            return Err(format!("vertex {v} is in no finite tetrahedron"));
        }
        for (i, &v) in self.vertex_of_input.iter().enumerate() {
            if v >= nv {
                return Err(format!("input {i} maps to missing vertex {v}"));
            }
        }
        for v in 0..nv {
            let i = self.input_of_vertex[v as usize];
            if self.vertex_of_input[i as usize] != v {
                return Err(format!("vertex {v} / input {i}: inconsistent maps"));
            }
        }
        for &(i, v) in &self.duplicates {
            if self.vertex_of_input[i as usize] != v || self.input_of_vertex[v as usize] >= i {
                return Err(format!("duplicate ({i}, {v}) inconsistent"));
            }
        }

        // Geometry, exactly.
        (0..nf).into_par_iter().try_for_each(|t| {
            let v = self.tets[t as usize].v.map(|x| self.p(x));
            if orient3d_exact(v[0], v[1], v[2], v[3]) <= 0 {
                return Err(format!(
                    "tet {t} {:?} is not positively oriented",
                    self.tets[t as usize].v
                ));
            }
            Ok(())
        })?;
        (0..nall).into_par_iter().try_for_each(|t| {
            for i in 0..4 {
                let code = self.tets[t as usize].n[i];
                let d = self.tets[(code >> 2) as usize].v[(code & 3) as usize];
                if d != INFINITE && self.conflict_sos(t, d) {
                    return Err(format!(
                        "facet {i} of tet {t} {:?} is not locally Delaunay: vertex {d} of tet {} conflicts",
                        self.tets[t as usize].v,
                        code >> 2
                    ));
                }
            }
            Ok(())
        })?;

        // Euler relations.
        let e: usize = (0..nv)
            .map(|v| self.edges_of_vertex(v).len())
            .sum::<usize>()
            / 2;
        let f = self.facets().len();
        let chi = nv as i64 - e as i64 + f as i64 - nf as i64;
        if chi != 1 {
            return Err(format!(
                "Euler characteristic V-E+F-T = {nv}-{e}+{f}-{nf} = {chi}, expected 1"
            ));
        }
        let mut hull_edges: Vec<(u32, u32)> = Vec::new();
        let mut hull_verts: Vec<u32> = Vec::new();
        for t in nf..nall {
            let w: Vec<u32> = self.tets[t as usize]
                .v
                .iter()
                .copied()
                .filter(|&x| x != INFINITE)
                .collect();
            for a in 0..3 {
                hull_verts.push(w[a]);
                let (x, y) = (w[a], w[(a + 1) % 3]);
                hull_edges.push((x.min(y), x.max(y)));
            }
        }
        hull_edges.sort_unstable();
        hull_edges.dedup();
        hull_verts.sort_unstable();
        hull_verts.dedup();
        let hf = (nall - nf) as i64;
        let chi_h = hull_verts.len() as i64 - hull_edges.len() as i64 + hf;
        if chi_h != 2 || 2 * hull_edges.len() as i64 != 3 * hf {
            return Err(format!(
                "hull Euler characteristic {chi_h} (V={}, E={}, F={hf}), expected 2",
                hull_verts.len(),
                hull_edges.len()
            ));
        }
        Ok(())
    }
}
