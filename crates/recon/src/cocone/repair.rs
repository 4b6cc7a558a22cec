//! Manifold repair of a tetrahedron labelling (a deviation from Tight Cocone, which
//! outputs the interface as it is): where the interface between inside and outside is
//! not a 2-manifold — an edge with four or more interface triangles, or a vertex whose
//! interface triangles are not one closed fan — the smallest group of same-label
//! tetrahedra there is relabelled, so that the two regions no longer touch in an edge or
//! a point. The output stays the boundary of a union of tetrahedra, so it stays closed.

use reconbench_delaunay::{Delaunay, INFINITE};

use super::tight::{good_samples, interface};

/// Counts of the repair.
#[derive(Debug, Clone, Copy, Default)]
pub struct RepairStats {
    /// Rounds run.
    pub rounds: usize,
    /// Tetrahedra relabelled in all.
    pub flipped: usize,
    /// Non-manifold edges left after the last round.
    pub edges_left: usize,
    /// Pinched vertices left after the last round.
    pub vertices_left: usize,
}

/// Every tetrahedron (ghosts included) incident to each vertex, in compressed rows.
struct Stars {
    off: Vec<u32>,
    items: Vec<u32>,
}

impl Stars {
    fn new(dt: &Delaunay) -> Self {
        let nv = dt.n_vertices();
        let mut off = vec![0u32; nv + 1];
        for t in 0..dt.n_all_tets() as u32 {
            for v in dt.tet_vertices(t) {
                if v != INFINITE {
                    off[v as usize + 1] += 1;
                }
            }
        }
        for i in 0..nv {
            off[i + 1] += off[i];
        }
        let mut fill = off.clone();
        let mut items = vec![0u32; off[nv] as usize];
        for t in 0..dt.n_all_tets() as u32 {
            for v in dt.tet_vertices(t) {
                if v != INFINITE {
                    items[fill[v as usize] as usize] = t;
                    fill[v as usize] += 1;
                }
            }
        }
        Stars { off, items }
    }

    fn of(&self, v: u32) -> &[u32] {
        &self.items[self.off[v as usize] as usize..self.off[v as usize + 1] as usize]
    }
}

/// Components of same-label tetrahedra among `set`, linked through shared faces that
/// contain all of `keep` (the edge's two vertices, or the one vertex). Returns
/// `(label, tets)` per component.
fn groups(dt: &Delaunay, set: &[u32], keep: &[u32], inside: &[bool]) -> Vec<(bool, Vec<u32>)> {
    let mut seen = vec![false; set.len()];
    let mut out = Vec::new();
    for s in 0..set.len() {
        if seen[s] {
            continue;
        }
        seen[s] = true;
        let lab = inside[set[s] as usize];
        let mut comp = vec![set[s]];
        let mut k = 0;
        while k < comp.len() {
            let t = comp[k];
            k += 1;
            let tv = dt.tet_vertices(t);
            for (i, &n) in dt.tet_neighbors(t).iter().enumerate() {
                // The shared face is opposite vertex i: it must keep every vertex of `keep`.
                if keep.contains(&tv[i]) || inside[n as usize] != lab {
                    continue;
                }
                if let Some(j) = set.iter().position(|&x| x == n)
                    && !seen[j]
                {
                    seen[j] = true;
                    comp.push(n);
                }
            }
        }
        out.push((lab, comp));
    }
    out
}

/// Relabels until the interface is a 2-manifold or `max_rounds` pass; returns the
/// counts and the final interface (see [`interface`]).
pub fn repair(
    dt: &Delaunay,
    inside: &mut [bool],
    max_rounds: usize,
) -> (RepairStats, Vec<[u32; 3]>) {
    let nt = dt.n_tets() as u32;
    let mut stars: Option<Stars> = None;
    let mut st = RepairStats::default();
    let mut edge_set = Vec::new();
    let mut tris;
    let mut round = 0;
    loop {
        tris = interface(dt, inside);
        let (bad_edges, bad_vertices) = defects(dt.n_vertices(), &tris);
        st.edges_left = bad_edges.len();
        st.vertices_left = bad_vertices.len();
        if round == max_rounds || (bad_edges.is_empty() && bad_vertices.is_empty()) {
            break;
        }
        round += 1;
        st.rounds += 1;
        let stars = stars.get_or_insert_with(|| Stars::new(dt));
        let mut touched = vec![false; inside.len()];
        let mut flips: Vec<u32> = Vec::new();
        let plan = |comp: &[u32], touched: &mut Vec<bool>, flips: &mut Vec<u32>| {
            if comp.iter().any(|&t| t >= nt || touched[t as usize]) {
                return;
            }
            for &t in comp {
                touched[t as usize] = true;
                flips.push(t);
            }
        };
        for &[a, b] in &bad_edges {
            edge_set.clear();
            edge_set.extend(
                stars
                    .of(a)
                    .iter()
                    .copied()
                    .filter(|&t| dt.tet_vertices(t).contains(&b)),
            );
            let g = groups(dt, &edge_set, &[a, b], inside);
            if let Some((_, c)) = smallest_flippable(&g, nt) {
                plan(c, &mut touched, &mut flips);
            }
        }
        for &v in &bad_vertices {
            let g = groups(dt, stars.of(v), &[v], inside);
            // Only a label split into several groups around v pinches there.
            let ins = g.iter().filter(|(l, _)| *l).count();
            let outs = g.len() - ins;
            let pick: Vec<(bool, Vec<u32>)> = g
                .into_iter()
                .filter(|(l, _)| if *l { ins > 1 } else { outs > 1 })
                .collect();
            if let Some((_, c)) = smallest_flippable(&pick, nt) {
                plan(c, &mut touched, &mut flips);
            }
        }
        if flips.is_empty() {
            break;
        }
        for &t in &flips {
            inside[t as usize] = !inside[t as usize];
        }
        st.flipped += flips.len();
    }
    (st, tris)
}

fn smallest_flippable(g: &[(bool, Vec<u32>)], nt: u32) -> Option<&(bool, Vec<u32>)> {
    g.iter()
        .filter(|(_, c)| c.iter().all(|&t| t < nt))
        .min_by_key(|(_, c)| (c.len(), c.iter().min().copied()))
}

/// Non-manifold edges (more than two triangles) and vertices whose triangles are not one
/// closed fan, of a closed triangle set.
pub fn defects(nv: usize, tris: &[[u32; 3]]) -> (Vec<[u32; 2]>, Vec<u32>) {
    let bad_edges = crowded_edges(nv, tris);
    let good = good_samples(nv, tris);
    let mut used = vec![false; nv];
    for t in tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let on_bad: std::collections::HashSet<u32> = bad_edges.iter().flatten().copied().collect();
    let bad_vertices = (0..nv as u32)
        .filter(|&v| used[v as usize] && !good[v as usize] && !on_bad.contains(&v))
        .collect();
    (bad_edges, bad_vertices)
}

/// The edges `[a, b]` (`a < b`) of more than two triangles of `tris`, in increasing
/// order. The edges are bucketed by their lower end (a counting sort) and each short
/// row is sorted on its own: the same order as sorting all `3 · tris` edges, which was
/// the largest sort of the repair check.
fn crowded_edges(nv: usize, tris: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let ends = |t: &[u32; 3], k: usize| {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        (a.min(b), a.max(b))
    };
    let mut off = vec![0u32; nv + 1];
    for t in tris {
        for k in 0..3 {
            off[ends(t, k).0 as usize + 1] += 1;
        }
    }
    for i in 0..nv {
        off[i + 1] += off[i];
    }
    let mut fill = off.clone();
    let mut upper = vec![0u32; off[nv] as usize];
    for t in tris {
        for k in 0..3 {
            let (a, b) = ends(t, k);
            upper[fill[a as usize] as usize] = b;
            fill[a as usize] += 1;
        }
    }
    let mut bad = Vec::new();
    for a in 0..nv {
        let row = &mut upper[off[a] as usize..off[a + 1] as usize];
        if row.len() < 3 {
            continue;
        }
        row.sort_unstable();
        for run in row.chunk_by(|x, y| x == y) {
            if run.len() > 2 {
                bad.push([a as u32, run[0]]);
            }
        }
    }
    bad
}

/// Relabels every face-connected region of one label with fewer than `share` times the
/// inside tetrahedra: small inside blobs become outside, small enclosed outside cavities
/// inside (the region holding the ghosts is never touched). Returns the tetrahedra
/// relabelled.
pub fn drop_pockets(dt: &Delaunay, inside: &mut [bool], share: f64) -> usize {
    let nt = dt.n_tets();
    let nall = dt.n_all_tets();
    let total_in = inside[..nt].iter().filter(|&&x| x).count();
    let limit = (share * total_in as f64).floor() as usize;
    if limit == 0 {
        return 0;
    }
    // Union-find over same-label face neighbours, one pass in tetrahedron order (the
    // tetrahedra are read in sequence, only the small parent array is read at random).
    let mut parent: Vec<u32> = (0..nall as u32).collect();
    fn root(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let up = parent[parent[x as usize] as usize];
            parent[x as usize] = up;
            x = up;
        }
        x
    }
    for t in 0..nall as u32 {
        for n in dt.tet_neighbors(t) {
            if n > t && inside[n as usize] == inside[t as usize] {
                let (a, b) = (root(&mut parent, t), root(&mut parent, n));
                if a != b {
                    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                    parent[hi as usize] = lo;
                }
            }
        }
    }
    let mut size = vec![0u32; nall];
    let mut ghost = vec![false; nall];
    for t in 0..nall as u32 {
        let r = root(&mut parent, t) as usize;
        size[r] += 1;
        ghost[r] |= t as usize >= nt;
    }
    let mut flipped = 0;
    for t in 0..nt {
        let r = root(&mut parent, t as u32) as usize;
        if !ghost[r] && (size[r] as usize) < limit {
            inside[t] = !inside[t];
            flipped += 1;
        }
    }
    flipped
}
