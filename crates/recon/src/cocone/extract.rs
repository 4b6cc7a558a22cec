//! Cocone's manifold extraction (ACDL 2002 §3): prune triangles at sharp edges, then walk
//! the outer side of what is left so that every edge keeps at most one triangle on each
//! side.

use std::collections::VecDeque;

use glam::DVec3;
use reconbench_delaunay::{Delaunay, NO_TET};

use super::poles::{apex, outward_normal};
use crate::angle::pseudo_angle;

const NONE: u32 = u32::MAX;

/// Candidate triangles with their edges in compressed rows.
#[derive(Debug)]
pub struct Complex<'a> {
    dt: &'a Delaunay,
    /// Delaunay facet id of each candidate.
    pub facet: Vec<u32>,
    /// Sorted vertex triple of each candidate.
    tri: Vec<[u32; 3]>,
    /// Edge ids of each candidate, edge `k` opposite vertex `k` of `tri`.
    tri_edges: Vec<[u32; 3]>,
    /// Vertices of each edge (increasing).
    edge_v: Vec<[u32; 2]>,
    /// Candidates around each edge: `edge_items[edge_off[e]..edge_off[e + 1]]`.
    edge_off: Vec<u32>,
    edge_items: Vec<u32>,
    /// Whether the candidate survived pruning.
    pub alive: Vec<bool>,
}

/// Counts of the extraction.
#[derive(Debug, Clone, Copy, Default)]
pub struct ExtractStats {
    /// Cocone triangles before pruning.
    pub candidates: usize,
    /// Triangles removed by pruning.
    pub pruned: usize,
    /// Edge-connected components walked.
    pub components: usize,
    /// Triangles the walk reached but could not add without a third triangle or a
    /// misoriented pair at an edge.
    pub walk_conflicts: usize,
}

impl<'a> Complex<'a> {
    /// The complex of the Delaunay facets flagged in `keep`.
    pub fn new(dt: &'a Delaunay, keep: &[bool]) -> Self {
        let facets = dt.facets();
        let facet: Vec<u32> = (0..facets.len() as u32)
            .filter(|&f| keep[f as usize])
            .collect();
        let tri: Vec<[u32; 3]> = facet.iter().map(|&f| facets[f as usize].v).collect();
        // (upper end, candidate << 2 | opposite corner) of every edge, bucketed by the
        // lower end (the triples are sorted, so edge k of `t` has lower end
        // `t[usize::from(k == 0)]`) and each bucket sorted: the order of sorting all
        // (edge key, candidate << 2 | corner) pairs, without a comparison sort of them.
        let nv = dt.n_vertices();
        let lower = |t: &[u32; 3], k: usize| t[usize::from(k == 0)];
        let upper = |t: &[u32; 3], k: usize| t[if k == 2 { 1 } else { 2 }];
        let mut off = vec![0u32; nv + 1];
        for t in &tri {
            for k in 0..3 {
                off[lower(t, k) as usize + 1] += 1;
            }
        }
        for i in 0..nv {
            off[i + 1] += off[i];
        }
        let mut fill = off.clone();
        let mut pairs = vec![(0u32, 0u32); off[nv] as usize];
        for (j, t) in tri.iter().enumerate() {
            for k in 0..3 {
                let a = lower(t, k) as usize;
                pairs[fill[a] as usize] = (upper(t, k), ((j as u32) << 2) | k as u32);
                fill[a] += 1;
            }
        }
        drop(fill);
        let mut tri_edges = vec![[NONE; 3]; tri.len()];
        let mut edge_v = Vec::new();
        let mut edge_off = vec![0u32];
        let mut edge_items = Vec::with_capacity(pairs.len());
        for a in 0..nv {
            let row = &mut pairs[off[a] as usize..off[a + 1] as usize];
            row.sort_unstable();
            for run in row.chunk_by(|x, y| x.0 == y.0) {
                let e = edge_v.len() as u32;
                edge_v.push([a as u32, run[0].0]);
                for &(_, tag) in run {
                    let (j, c) = (tag >> 2, tag & 3);
                    tri_edges[j as usize][c as usize] = e;
                    edge_items.push(j);
                }
                edge_off.push(edge_items.len() as u32);
            }
        }
        let alive = vec![true; tri.len()];
        Complex {
            dt,
            facet,
            tri,
            tri_edges,
            edge_v,
            edge_off,
            edge_items,
            alive,
        }
    }

    fn around(&self, e: u32) -> &[u32] {
        &self.edge_items[self.edge_off[e as usize] as usize..self.edge_off[e as usize + 1] as usize]
    }

    fn third(&self, j: u32, e: u32) -> u32 {
        let [a, b] = self.edge_v[e as usize];
        let t = self.tri[j as usize];
        t[0] ^ t[1] ^ t[2] ^ a ^ b
    }

    /// Angles (radians, `[0, 2π)`) of the live triangles around edge `x→y`, measured
    /// about the axis `y − x` from the half-plane of `ref_third`.
    fn angles(&self, x: u32, y: u32, ref_third: u32, e: u32, out: &mut Vec<(f64, u32)>) {
        let p = self.dt.vertices();
        let (px, u) = (p[x as usize], (p[y as usize] - p[x as usize]).normalize());
        let perp = |q: DVec3| {
            let w = q - px;
            w - w.dot(u) * u
        };
        let e1 = perp(p[ref_third as usize]).normalize();
        let e2 = u.cross(e1);
        out.clear();
        for &j in self.around(e) {
            if !self.alive[j as usize] {
                continue;
            }
            let w = perp(p[self.third(j, e) as usize]);
            let mut a = w.dot(e2).atan2(w.dot(e1));
            if a < 0.0 {
                a += std::f64::consts::TAU;
            }
            out.push((a, j));
        }
    }

    /// The live triangle other than `j` with the smallest angle about `x→y` from the
    /// half-plane of `ref_third` (ties to the lower index), as [`Self::angles`] orders
    /// them. The triangles are ranked by a pseudo-angle (monotone in the angle, no
    /// `atan2`); the few within `1e-9` of the best are then ranked by the exact angles of
    /// [`Self::angles`], so the choice is the same as ranking everything by `atan2`.
    fn next_around(
        &self,
        x: u32,
        y: u32,
        ref_third: u32,
        e: u32,
        j: u32,
        buf: &mut Vec<(f64, u32)>,
    ) -> Option<u32> {
        let p = self.dt.vertices();
        let (px, u) = (p[x as usize], (p[y as usize] - p[x as usize]).normalize());
        let perp = |q: DVec3| {
            let w = q - px;
            w - w.dot(u) * u
        };
        let e1 = perp(p[ref_third as usize]).normalize();
        // One live triangle besides `j` (the usual case on a surface): the ranking
        // below returns it whenever its pseudo-angle is finite, i.e. whenever `e1` is
        // (the points are finite and `u` is a unit vector), and nothing otherwise.
        let mut others = self
            .around(e)
            .iter()
            .filter(|&&i| i != j && self.alive[i as usize]);
        if let (Some(&only), None) = (others.next(), others.next()) {
            return e1.is_finite().then_some(only);
        }
        let e2 = u.cross(e1);
        buf.clear();
        let mut best = f64::INFINITY;
        for &i in self.around(e) {
            if i == j || !self.alive[i as usize] {
                continue;
            }
            let w = perp(p[self.third(i, e) as usize]);
            let a = pseudo_angle(w.dot(e1), w.dot(e2));
            best = best.min(a);
            buf.push((a, i));
        }
        buf.retain(|&(a, _)| a <= best + 1e-9);
        if buf.len() == 1 {
            return Some(buf[0].1);
        }
        // Near-ties: the exact angles, as `angles` computes them.
        for c in buf.iter_mut() {
            let w = perp(p[self.third(c.1, e) as usize]);
            let mut a = w.dot(e2).atan2(w.dot(e1));
            if a < 0.0 {
                a += std::f64::consts::TAU;
            }
            c.0 = a;
        }
        buf.iter()
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map(|&(_, i)| i)
    }

    /// Removes sharp triangles until none is left (ACDL §3.1): an edge is sharp when two
    /// consecutive triangles around it leave a gap larger than `sharp` radians, i.e. all
    /// its triangles lie in a wedge narrower than `2π − sharp`; with `dangling`, an edge
    /// with a single triangle is sharp too (the paper's rule for closed surfaces).
    /// Returns the number of triangles removed.
    pub fn prune(&mut self, sharp: f64, dangling: bool) -> usize {
        // cos(2π − sharp): two triangles leave a gap above `sharp` when the angle between
        // them is below 2π − sharp, i.e. its cosine is above this.
        let cos_sharp = sharp.cos();
        let mut queue: Vec<u32> = (0..self.edge_v.len() as u32).collect();
        let mut queued = vec![true; self.edge_v.len()];
        let mut buf = Vec::new();
        let mut removed = 0;
        while let Some(e) = queue.pop() {
            queued[e as usize] = false;
            let live = self
                .around(e)
                .iter()
                .filter(|&&j| self.alive[j as usize])
                .count();
            let is_sharp = match live {
                0 => false,
                1 => dangling,
                2 => {
                    let [x, y] = self.edge_v[e as usize];
                    let mut two = self.around(e).iter().filter(|&&j| self.alive[j as usize]);
                    let (j1, j2) = (*two.next().expect("live"), *two.next().expect("live"));
                    let (r, k) = (self.third(j1, e), self.third(j2, e));
                    match self.wedge_cos(x, y, r, k) {
                        // Clear of the threshold: the wedge angle alone decides.
                        Some(c) if (c - cos_sharp).abs() > 1e-9 => c > cos_sharp,
                        _ => self.sharp_by_angles(x, y, r, e, sharp, &mut buf),
                    }
                }
                _ => {
                    let [x, y] = self.edge_v[e as usize];
                    let first = *self
                        .around(e)
                        .iter()
                        .find(|&&j| self.alive[j as usize])
                        .expect("live");
                    self.sharp_by_angles(x, y, self.third(first, e), e, sharp, &mut buf)
                }
            };
            if !is_sharp {
                continue;
            }
            let kill: Vec<u32> = self
                .around(e)
                .iter()
                .copied()
                .filter(|&j| self.alive[j as usize])
                .collect();
            for j in kill {
                self.alive[j as usize] = false;
                removed += 1;
                for &f in &self.tri_edges[j as usize] {
                    if f != e && !queued[f as usize] {
                        queued[f as usize] = true;
                        queue.push(f);
                    }
                }
            }
        }
        removed
    }

    /// Whether the live triangles around edge `x→y` leave a gap above `sharp` radians
    /// between two consecutive ones, from their exact angles ([`Self::angles`]).
    fn sharp_by_angles(
        &self,
        x: u32,
        y: u32,
        ref_third: u32,
        e: u32,
        sharp: f64,
        buf: &mut Vec<(f64, u32)>,
    ) -> bool {
        self.angles(x, y, ref_third, e, buf);
        buf.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut gap = std::f64::consts::TAU - buf[buf.len() - 1].0 + buf[0].0;
        for w in buf.windows(2) {
            gap = gap.max(w[1].0 - w[0].0);
        }
        gap > sharp
    }

    /// Cosine of the angle about edge `x→y` between the half-planes of `r` and `k`,
    /// from the same projections as [`Self::angles`] (there `atan2` of `(s, c)` below);
    /// `None` when a projection vanishes. Two triangles leave a gap of 2π minus this
    /// angle, up to rounding far below the `1e-9` margin `prune` keeps, so the
    /// decision is the one the `atan2` angles give, without the two `atan2` calls.
    fn wedge_cos(&self, x: u32, y: u32, r: u32, k: u32) -> Option<f64> {
        let p = self.dt.vertices();
        let (px, u) = (p[x as usize], (p[y as usize] - p[x as usize]).normalize());
        let perp = |q: DVec3| {
            let w = q - px;
            w - w.dot(u) * u
        };
        let e1 = perp(p[r as usize]).normalize();
        let e2 = u.cross(e1);
        let w = perp(p[k as usize]);
        let (c, s) = (w.dot(e1), w.dot(e2));
        let len = (c * c + s * s).sqrt();
        let cos = c / len;
        cos.is_finite().then_some(cos)
    }

    /// Edge-connected components of the live triangles, numbered in order of their
    /// smallest candidate; `NONE` for removed triangles.
    fn components(&self) -> (usize, Vec<u32>) {
        let n = self.tri.len();
        let mut comp = vec![NONE; n];
        let mut nc = 0u32;
        let mut stack = Vec::new();
        for s in 0..n {
            if !self.alive[s] || comp[s] != NONE {
                continue;
            }
            comp[s] = nc;
            stack.push(s as u32);
            while let Some(j) = stack.pop() {
                for &e in &self.tri_edges[j as usize] {
                    for &k in self.around(e) {
                        if self.alive[k as usize] && comp[k as usize] == NONE {
                            comp[k as usize] = nc;
                            stack.push(k);
                        }
                    }
                }
            }
            nc += 1;
        }
        (nc as usize, comp)
    }

    /// An outward-oriented seed of every component: a convex-hull facet when the
    /// component has one (its outer side is known), else the triangle at the
    /// component's largest-x vertex whose normal is closest to `+x`, oriented to `+x`.
    fn seeds(&self, nc: usize, comp: &[u32]) -> Vec<(u32, [u32; 3])> {
        let p = self.dt.vertices();
        let facets = self.dt.facets();
        let mut hull: Vec<Option<u32>> = vec![None; nc];
        let mut top: Vec<Option<(f64, u32)>> = vec![None; nc];
        for (j, &c) in comp.iter().enumerate() {
            if c == NONE {
                continue;
            }
            let c = c as usize;
            let f = facets[self.facet[j] as usize];
            if f.tets[1] == NO_TET && hull[c].is_none() {
                hull[c] = Some(j as u32);
            }
            for v in f.v {
                let x = p[v as usize].x;
                if top[c].is_none_or(|(bx, bv)| x > bx || (x == bx && v < bv)) {
                    top[c] = Some((x, v));
                }
            }
        }
        let mut best: Vec<Option<(f64, u32)>> = vec![None; nc];
        for (j, &c) in comp.iter().enumerate() {
            if c == NONE || hull[c as usize].is_some() {
                continue;
            }
            let t = self.tri[j];
            let (_, v) = top[c as usize].expect("vertex");
            if !t.contains(&v) {
                continue;
            }
            let [a, b, d] = t.map(|x| p[x as usize]);
            let nx = (b - a).cross(d - a).normalize_or_zero().x.abs();
            if best[c as usize].is_none_or(|(bn, _)| nx > bn) {
                best[c as usize] = Some((nx, j as u32));
            }
        }
        (0..nc)
            .filter_map(|c| {
                if let Some(j) = hull[c] {
                    // ASSUMPTION K-03: a hull facet of the component seeds the walk, with
                    // its outer side facing away from its Delaunay tetrahedron.
                    let f = facets[self.facet[j as usize] as usize];
                    let n = outward_normal(p, f.v, apex(self.dt.tet_vertices(f.tets[0]), f.v));
                    Some((j, orient(p, f.v, n)))
                } else {
                    // ASSUMPTION K-03 (no hull facet): the extreme-vertex seed.
                    let (_, j) = best[c]?;
                    Some((j, orient(p, self.tri[j as usize], DVec3::X)))
                }
            })
            .collect()
    }

    /// The walk (ACDL §3.2): from each seed, across every edge to the next live triangle
    /// met when turning from the current triangle towards its outer side. A triangle is
    /// added only when it keeps every edge at one triangle per direction, so the result is
    /// edge-manifold and consistently oriented. Returns oriented vertex triples (Delaunay
    /// ids) and their candidate index.
    pub fn walk(&self, stats: &mut ExtractStats) -> Vec<(u32, [u32; 3])> {
        let (nc, comp) = self.components();
        stats.components = nc;
        let seeds = self.seeds(nc, &comp);
        // Per edge, the triangle using it low→high and the one using it high→low.
        let mut slot = vec![[NONE; 2]; self.edge_v.len()];
        let mut placed = vec![false; self.tri.len()];
        let mut out = Vec::new();
        let mut queue = VecDeque::new();
        let mut buf = Vec::new();
        for (j, t) in seeds {
            if self.try_place(j, t, &mut slot, &mut placed) {
                out.push((j, t));
                queue.push_back((j, t));
            }
            while let Some((j, t)) = queue.pop_front() {
                for k in 0..3 {
                    let (x, y, z) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                    let e = self.edge_of(j, x, y);
                    // The next triangle turning towards the outer side: the smallest
                    // positive angle about x→y (the normal points that way).
                    let Some(i) = self.next_around(x, y, z, e, j, &mut buf) else {
                        continue;
                    };
                    if placed[i as usize] {
                        continue;
                    }
                    let w = self.third(i, e);
                    let tn = [y, x, w];
                    if self.try_place(i, tn, &mut slot, &mut placed) {
                        out.push((i, tn));
                        queue.push_back((i, tn));
                    } else {
                        stats.walk_conflicts += 1;
                    }
                }
            }
        }
        out
    }

    fn edge_of(&self, j: u32, x: u32, y: u32) -> u32 {
        let t = self.tri[j as usize];
        let z = t[0] ^ t[1] ^ t[2] ^ x ^ y;
        let c = t.iter().position(|&v| v == z).expect("corner");
        self.tri_edges[j as usize][c]
    }

    fn try_place(&self, j: u32, t: [u32; 3], slot: &mut [[u32; 2]], placed: &mut [bool]) -> bool {
        if placed[j as usize] {
            return false;
        }
        let mut use_ = [(0u32, 0usize); 3];
        for k in 0..3 {
            let (x, y) = (t[k], t[(k + 1) % 3]);
            let e = self.edge_of(j, x, y);
            let d = usize::from(x > y);
            if slot[e as usize][d] != NONE {
                return false;
            }
            use_[k] = (e, d);
        }
        for (e, d) in use_ {
            slot[e as usize][d] = j;
        }
        placed[j as usize] = true;
        true
    }
}

/// The triple `v` ordered so that its normal points along `dir`.
fn orient(p: &[DVec3], v: [u32; 3], dir: DVec3) -> [u32; 3] {
    let [a, b, c] = v.map(|x| p[x as usize]);
    if (b - a).cross(c - a).dot(dir) >= 0.0 {
        v
    } else {
        [v[0], v[2], v[1]]
    }
}
