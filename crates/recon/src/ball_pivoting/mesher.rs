//! The ball-pivoting state and its three operations (Bernardini et al. 1999, §3-4):
//! seed triangle search, pivoting a front edge (with join / glue of the new triangle's
//! edges), and re-activating boundary edges for the next, larger radius.
//!
//! Every vertex is a distinct input point. An edge is stored once (undirected key) with
//! the direction it has in its first triangle; it is *front* while it has one triangle
//! and may still be pivoted, *boundary* when the pivot failed at the current radius, and
//! *inner* with two triangles. The front is a FIFO queue of edge ids, so a run is a pure
//! function of the input order.

use std::collections::VecDeque;

use glam::DVec3;
use rayon::prelude::*;

use super::geometry::{PivotFrame, ball_centre};
use super::grid::CellGrid;

/// Edge status.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum EdgeState {
    /// One triangle; queued for pivoting.
    Front,
    /// One triangle; the pivot failed at the current radius.
    Boundary,
    /// Two triangles.
    Inner,
}

/// One mesh edge.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Edge {
    /// Direction in its first triangle (counter-clockwise about the outward normal).
    pub from: u32,
    /// See `from`.
    pub to: u32,
    /// Third vertex of its first triangle.
    pub opp: u32,
    /// Centre of the ball resting on its first triangle (for the radius it has).
    pub centre: DVec3,
    /// Status.
    pub state: EdgeState,
}

/// Why a pivot produced no triangle (counted in the diagnostics).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Counts {
    /// Pivots that touched no point.
    pub no_hit: usize,
    /// Pivots whose hit point was an inner vertex.
    pub inner_hit: usize,
    /// Pivots whose triangle would make a non-manifold or misoriented edge.
    pub edge_conflict: usize,
    /// Pivots whose triangle disagrees with the point normals.
    pub normal_conflict: usize,
    /// Triangles created by glueing at least one existing front edge.
    pub glued: usize,
    /// Seed triangles.
    pub seeds: usize,
    /// Boundary edges re-activated for a larger radius.
    pub reactivated: usize,
}

/// The mesher.
#[derive(Debug)]
pub(crate) struct Mesher<'a> {
    pos: &'a [DVec3],
    nrm: &'a [DVec3],
    /// Rank of each point in the working (input) order: ties and seeds follow it.
    rank: &'a [u32],
    /// Point of each rank.
    by_rank: Vec<u32>,
    /// The grid of `pos` with cells of side `2 * rho` (the current radius).
    grid: Option<CellGrid>,
    /// Per point: its row of neighbours within `2 * rho` for the current radius
    /// (`NO_ROW` until first needed), as `(start, len)` into `nb_idx`.
    nb_row: Vec<u32>,
    nb_span: Vec<(u32, u32)>,
    nb_idx: Vec<u32>,
    /// Whether a point has been used by a triangle.
    used: Vec<bool>,
    /// Per vertex: incident edges with exactly one triangle.
    open: Vec<u32>,
    edges: Vec<Edge>,
    /// Per vertex: the first edge whose lower end point it is (`NONE`: none); the
    /// others follow through `next_edge`. Replaces a hash map from the end points:
    /// a vertex has a few edges, and its list is close in memory to its neighbours'.
    first_edge: Vec<u32>,
    /// Per edge: the next edge of its lower end point's list (`NONE` at the end).
    next_edge: Vec<u32>,
    queue: VecDeque<u32>,
    /// Output triangles (counter-clockwise about the outward normal).
    pub tris: Vec<[u32; 3]>,
    /// Diagnostics counts.
    pub counts: Counts,
    rho: f64,
    /// Reused buffer of pivot contacts: (angle, rank, candidate, cos, sin) with the ball
    /// centre at `m + R (cos e1 + sin e2) / (cos² + sin²)^½` on the pivot circle.
    cand: Vec<(f64, u32, u32, f64, f64)>,
}

/// End of an edge list.
const NONE: u32 = u32::MAX;

/// Tolerance of the emptiness test: a point counts as inside the ball when it is closer
/// to the centre than `rho * (1 - EMPTY_TOL)`.
const EMPTY_TOL: f64 = 1e-9;

/// No neighbour row yet in this pass.
const NO_ROW: u32 = u32::MAX;

impl<'a> Mesher<'a> {
    /// A mesher over `pos` with unit normals `nrm` (zero: unusable point); `rank` (a
    /// permutation of `0..n`) is the order that decides ties and the seed search, so the
    /// mesh does not depend on how `pos` is laid out in memory.
    pub fn new(pos: &'a [DVec3], nrm: &'a [DVec3], rank: &'a [u32]) -> Self {
        let n = pos.len();
        let mut by_rank = vec![0u32; n];
        for (i, &r) in rank.iter().enumerate() {
            by_rank[r as usize] = i as u32;
        }
        Self {
            pos,
            nrm,
            rank,
            by_rank,
            grid: None,
            nb_row: vec![NO_ROW; n],
            nb_span: Vec::new(),
            nb_idx: Vec::new(),
            used: vec![false; n],
            open: vec![0; n],
            edges: Vec::with_capacity(3 * n),
            first_edge: vec![NONE; n],
            next_edge: Vec::with_capacity(3 * n),
            queue: VecDeque::new(),
            tris: Vec::with_capacity(2 * n),
            counts: Counts::default(),
            rho: 0.0,
            cand: Vec::new(),
        }
    }

    /// Sets the ball radius of the next operations, buckets the points in a grid of
    /// cells of side `2 rho` (`grid` when given: it must be that grid of `pos`) and
    /// computes, in parallel, the neighbour rows of `active` (the points the pass
    /// starts from); other points get theirs when the front first reaches them. Every
    /// ball of radius `rho` touching a point lies within `2 rho` of it, so the row holds
    /// every candidate.
    pub fn begin_pass(&mut self, rho: f64, active: &[u32], grid: Option<CellGrid>) {
        self.rho = rho;
        self.nb_row.fill(NO_ROW);
        self.nb_span.clear();
        self.nb_idx.clear();
        let grid = grid.unwrap_or_else(|| CellGrid::new(self.pos, 2.0 * rho));
        let (pos, r2) = (self.pos, 4.0 * rho * rho);
        if active.len() == pos.len() {
            // Every point (the first pass): each close pair is tested once for both
            // rows. IMPL-CHOICE: only then; a later pass starts from about half the
            // points (boundary edges' ends), where rows for all at the larger radius
            // cost more than the active points' rows (measured on the 100k torus).
            let (start, idx) = grid.all_rows(pos, r2);
            self.nb_span = start.windows(2).map(|w| (w[0], w[1] - w[0])).collect();
            for (i, r) in self.nb_row.iter_mut().enumerate() {
                *r = i as u32;
            }
            self.nb_idx = idx;
            self.grid = Some(grid);
            return;
        }
        // In cell order, so that neighbouring rows share their cells (cache and
        // look-ups); rows in chunks (one buffer per chunk, not per point), in order.
        let mut mark = vec![false; pos.len()];
        for &i in active {
            mark[i as usize] = true;
        }
        let order = grid.in_cell_order(&mark);
        let chunks: Vec<(Vec<u32>, Vec<u32>)> = order
            .par_chunks(1024)
            .map(|ch| {
                let (mut idx, mut lens) = (Vec::new(), Vec::with_capacity(ch.len()));
                grid.rows(pos, ch, r2, &mut idx, &mut lens);
                (idx, lens)
            })
            .collect();
        self.nb_idx
            .reserve(chunks.iter().map(|c| c.0.len()).sum::<usize>());
        let mut k = 0;
        for (idx, lens) in chunks {
            let mut s = 0usize;
            for l in lens {
                let i = order[k];
                k += 1;
                self.nb_row[i as usize] = self.nb_span.len() as u32;
                self.nb_span.push((self.nb_idx.len() as u32, l));
                self.nb_idx.extend_from_slice(&idx[s..s + l as usize]);
                s += l as usize;
            }
        }
        self.grid = Some(grid);
    }

    /// Computes the neighbour row of `i` if this pass has none yet.
    #[inline]
    fn ensure(&mut self, i: u32) {
        if self.nb_row[i as usize] != NO_ROW {
            return;
        }
        let Some(grid) = &self.grid else {
            return;
        };
        let start = self.nb_idx.len();
        let p = self.pos[i as usize];
        grid.near_into(self.pos, p, 4.0 * self.rho * self.rho, &mut self.nb_idx);
        self.nb_row[i as usize] = self.nb_span.len() as u32;
        self.nb_span
            .push((start as u32, (self.nb_idx.len() - start) as u32));
    }

    /// Neighbours of `i` within `2 * rho` (itself included), in no particular order
    /// (every use is independent of it); `i`'s row must have been computed
    /// ([`Self::ensure`]).
    #[inline]
    fn near(&self, i: u32) -> &[u32] {
        let r = self.nb_row[i as usize];
        debug_assert!(r != NO_ROW, "no neighbour row for {i}");
        match self.nb_span.get(r as usize) {
            Some(&(s, l)) => &self.nb_idx[s as usize..(s + l) as usize],
            None => &[],
        }
    }

    /// Points a pass after the first starts from: the end points of boundary edges and
    /// the unused points with a normal.
    pub fn active_points(&self) -> Vec<u32> {
        let mut mark = vec![false; self.pos.len()];
        for e in &self.edges {
            if e.state == EdgeState::Boundary {
                mark[e.from as usize] = true;
                mark[e.to as usize] = true;
            }
        }
        for (i, m) in mark.iter_mut().enumerate() {
            if !self.used[i] && self.nrm[i] != DVec3::ZERO {
                *m = true;
            }
        }
        (0..self.pos.len() as u32)
            .filter(|&i| mark[i as usize])
            .collect()
    }

    /// Whether no point near `i` lies strictly inside the ball at `c` (the points in
    /// `skip` excepted).
    #[inline]
    fn empty(&self, i: u32, c: DVec3, skip: [u32; 3]) -> bool {
        let lim = self.rho * self.rho * (1.0 - EMPTY_TOL);
        self.near(i)
            .iter()
            .all(|&q| skip.contains(&q) || self.pos[q as usize].distance_squared(c) >= lim)
    }

    /// Whether triangle `t`'s normal agrees with its vertices' normals (positive dot
    /// products), as Bernardini's consistency test.
    #[inline]
    fn compatible(&self, t: [u32; 3]) -> bool {
        let [a, b, c] = t.map(|v| self.pos[v as usize]);
        let n = (b - a).cross(c - a);
        t.iter().all(|&v| n.dot(self.nrm[v as usize]) > 0.0)
    }

    /// Whether `v` may receive a new triangle (unused, or on the front).
    #[inline]
    fn usable(&self, v: u32) -> bool {
        !self.used[v as usize] || self.open[v as usize] > 0
    }

    /// The edge between `a` and `b` (either direction), if any.
    #[inline]
    fn find_edge(&self, a: u32, b: u32) -> Option<u32> {
        let (lo, hi) = (a.min(b), a.max(b));
        let mut e = self.first_edge[lo as usize];
        while e != NONE {
            let ed = &self.edges[e as usize];
            if ed.from.max(ed.to) == hi {
                return Some(e);
            }
            e = self.next_edge[e as usize];
        }
        None
    }

    /// Whether the directed edge `a -> b` can be added to a new triangle: absent, or
    /// present once in the opposite direction (then the triangle glues onto it).
    #[inline]
    fn edge_ok(&self, a: u32, b: u32) -> Option<bool> {
        match self.find_edge(a, b) {
            None => Some(false),
            Some(e) => {
                let e = &self.edges[e as usize];
                (e.state != EdgeState::Inner && e.from == b && e.to == a).then_some(true)
            }
        }
    }

    /// Adds triangle `(a, b, c)` whose ball centre is `centre`: edges already present
    /// (in the opposite direction) become inner, the others join the front.
    fn add_triangle(&mut self, t: [u32; 3], centre: DVec3) {
        self.tris.push(t);
        let mut glued = false;
        for k in 0..3 {
            let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            self.used[a as usize] = true;
            match self.find_edge(a, b) {
                Some(e) => {
                    self.edges[e as usize].state = EdgeState::Inner;
                    self.open[a as usize] -= 1;
                    self.open[b as usize] -= 1;
                    glued = true;
                }
                None => {
                    let id = self.edges.len() as u32;
                    self.edges.push(Edge {
                        from: a,
                        to: b,
                        opp: o,
                        centre,
                        state: EdgeState::Front,
                    });
                    let lo = a.min(b) as usize;
                    self.next_edge.push(self.first_edge[lo]);
                    self.first_edge[lo] = id;
                    self.open[a as usize] += 1;
                    self.open[b as usize] += 1;
                    self.queue.push_back(id);
                }
            }
        }
        if glued {
            self.counts.glued += 1;
        }
    }

    /// Pivots every queued front edge until the queue is empty; returns the number of
    /// triangles added. `poll` is called every 4096 pivots and stops the loop when it
    /// returns false.
    pub fn expand(&mut self, poll: &mut dyn FnMut(usize) -> bool) -> usize {
        let before = self.tris.len();
        let mut pivots = 0usize;
        while let Some(e) = self.queue.pop_front() {
            pivots += 1;
            if pivots.is_multiple_of(4096) && !poll(self.tris.len()) {
                break;
            }
            let edge = self.edges[e as usize];
            if edge.state != EdgeState::Front {
                continue;
            }
            match self.pivot(&edge) {
                Some((k, c)) => self.add_triangle([edge.to, edge.from, k], c),
                None => self.edges[e as usize].state = EdgeState::Boundary,
            }
        }
        self.tris.len() - before
    }

    /// Pivots the ball about front edge `a -> b` of triangle `(a, b, o)`: the first point
    /// the sphere touches ([`PivotFrame::contact`]) gives the triangle `(b, a, k)` if it
    /// is valid.
    fn pivot(&mut self, e: &Edge) -> Option<(u32, DVec3)> {
        let (a, b, o) = (e.from, e.to, e.opp);
        self.ensure(a);
        let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
        let frame = PivotFrame::new(pa, pb, e.centre)?;
        let u = frame.u;
        let w = {
            let po = self.pos[o as usize] - frame.m;
            po - u * po.dot(u)
        };
        let half2 = 0.25 * pa.distance_squared(pb);
        let r2 = self.rho * self.rho - half2;
        if r2.is_nan() || r2 <= 0.0 {
            return None;
        }
        let rad = r2.sqrt();
        let lim = 4.0 * self.rho * self.rho;
        let mut cand = std::mem::take(&mut self.cand);
        cand.clear();
        for &k in self.near(a) {
            if k == a || k == b || k == o {
                continue;
            }
            let pk = self.pos[k as usize];
            if pk.distance_squared(pb) > lim {
                continue;
            }
            let Some((t, c, s)) = frame.contact(pk, rad, half2) else {
                continue;
            };
            // A point co-spherical with the current ball on o's side would fold the
            // new triangle back over the old one.
            if t < 1e-9 && (pk - frame.m).dot(w) > 0.0 {
                continue;
            }
            cand.push((t, self.rank[k as usize], k, c, s));
        }
        let mut out = None;
        let mut hit = false;
        // Contacts in rotation order (ties to the lower rank): usually the first one
        // is taken, so the minimum is selected instead of sorting them all.
        while let Some(best) = (0..cand.len()).min_by(|&x, &y| {
            cand[x]
                .0
                .total_cmp(&cand[y].0)
                .then(cand[x].1.cmp(&cand[y].1))
        }) {
            let (_, _, k, c, s) = cand.swap_remove(best);
            let pk = self.pos[k as usize];
            let centre = frame.centre(c, s, rad);
            // Numerical safety: the first hit's ball must be empty; otherwise try the next.
            if !self.empty(a, centre, [a, b, k]) {
                continue;
            }
            hit = true;
            // A hit from below (the ball entering through the wrong side of (b, a, k)) stops
            // the ball, and the triangle is rejected.
            if (centre - pb).dot((pa - pb).cross(pk - pb)) < 0.0 {
                self.counts.normal_conflict += 1;
                break;
            }
            if !self.usable(k) {
                self.counts.inner_hit += 1;
                break;
            }
            let t = [b, a, k];
            if !self.compatible(t) {
                self.counts.normal_conflict += 1;
                break;
            }
            if self.edge_ok(a, k).is_none() || self.edge_ok(k, b).is_none() {
                self.counts.edge_conflict += 1;
                break;
            }
            out = Some((k, centre));
            break;
        }
        if !hit {
            self.counts.no_hit += 1;
        }
        self.cand = cand;
        out
    }

    /// Looks for a seed triangle among unused points, starting at `*cursor` (advanced
    /// past every point tried). Adds it and returns true when one is found.
    pub fn find_seed(&mut self, cursor: &mut usize) -> bool {
        let n = self.pos.len();
        while *cursor < n {
            let s = self.by_rank[*cursor];
            *cursor += 1;
            if self.used[s as usize] || self.nrm[s as usize] == DVec3::ZERO {
                continue;
            }
            self.ensure(s);
            if let Some((t, c)) = self.seed_at(s) {
                self.counts.seeds += 1;
                self.add_triangle(t, c);
                return true;
            }
        }
        false
    }

    /// The first valid seed triangle at `s`: pairs of unused neighbours in distance
    /// order, oriented by `s`'s normal, consistent with all three normals, whose
    /// ρ-ball on the normal side is empty.
    fn seed_at(&self, s: u32) -> Option<([u32; 3], DVec3)> {
        let ps = self.pos[s as usize];
        // Partners in distance order (ties to the lower index).
        let mut near = self.near(s).to_vec();
        near.sort_unstable_by(|&x, &y| {
            let (dx, dy) = (
                self.pos[x as usize].distance_squared(ps),
                self.pos[y as usize].distance_squared(ps),
            );
            dx.total_cmp(&dy)
                .then(self.rank[x as usize].cmp(&self.rank[y as usize]))
        });
        let lim = 4.0 * self.rho * self.rho;
        let free = |v: u32| v != s && !self.used[v as usize] && self.nrm[v as usize] != DVec3::ZERO;
        for (i, &a) in near.iter().enumerate() {
            if !free(a) {
                continue;
            }
            for &b in &near[i + 1..] {
                if !free(b) {
                    continue;
                }
                let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
                if pa.distance_squared(pb) > lim {
                    continue;
                }
                let n = (pa - ps).cross(pb - ps);
                let t = if n.dot(self.nrm[s as usize]) >= 0.0 {
                    [s, a, b]
                } else {
                    [s, b, a]
                };
                if !self.compatible(t) {
                    continue;
                }
                let [p0, p1, p2] = t.map(|v| self.pos[v as usize]);
                let Some(c) = ball_centre(p0, p1, p2, self.rho) else {
                    continue;
                };
                if self.empty(s, c, t) {
                    return Some((t, c));
                }
            }
        }
        None
    }

    /// Re-activates every boundary edge whose triangle's ball of the current radius is
    /// empty (Bernardini §4.3, multiple passes); returns how many.
    pub fn reactivate(&mut self) -> usize {
        let mut n = 0;
        for e in 0..self.edges.len() {
            let edge = self.edges[e];
            if edge.state != EdgeState::Boundary {
                continue;
            }
            let t = [edge.from, edge.to, edge.opp];
            let [p0, p1, p2] = t.map(|v| self.pos[v as usize]);
            let Some(c) = ball_centre(p0, p1, p2, self.rho) else {
                continue;
            };
            self.ensure(edge.from);
            if self.empty(edge.from, c, t) {
                let ed = &mut self.edges[e];
                ed.centre = c;
                ed.state = EdgeState::Front;
                self.queue.push_back(e as u32);
                n += 1;
            }
        }
        self.counts.reactivated += n;
        n
    }

    /// Directed boundary edges (one triangle) of the mesh, in edge order.
    pub fn boundary_edges(&self) -> Vec<(u32, u32)> {
        self.edges
            .iter()
            .filter(|e| e.state != EdgeState::Inner)
            .map(|e| (e.from, e.to))
            .collect()
    }

    /// Whether point `i` is used by a triangle.
    pub fn is_used(&self, i: usize) -> bool {
        self.used[i]
    }
}

/// Number of closed loops the directed boundary edges form (each edge in one loop;
/// at a vertex with several outgoing edges the lowest unused one is taken).
pub(crate) fn count_loops(n: usize, edges: &[(u32, u32)]) -> usize {
    let mut start = vec![0u32; n + 1];
    for &(a, _) in edges {
        start[a as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut out = vec![0u32; edges.len()];
    for (i, &(a, _)) in edges.iter().enumerate() {
        out[fill[a as usize] as usize] = i as u32;
        fill[a as usize] += 1;
    }
    let mut next_free = start.clone();
    let mut seen = vec![false; edges.len()];
    let mut loops = 0;
    for s in 0..edges.len() {
        if seen[s] {
            continue;
        }
        loops += 1;
        let mut e = s;
        loop {
            seen[e] = true;
            let v = edges[e].1 as usize;
            if v == edges[s].0 as usize {
                break;
            }
            let mut found = None;
            while next_free[v] < start[v + 1] {
                let cand = out[next_free[v] as usize] as usize;
                next_free[v] += 1;
                if !seen[cand] {
                    found = Some(cand);
                    break;
                }
            }
            match found {
                Some(c) => e = c,
                None => break,
            }
        }
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::count_loops;

    #[test]
    fn loops_of_two_squares_sharing_a_vertex_count_two() {
        // 0-1-2-3 and 0-4-5-6, both through vertex 0 (a pinch).
        let e = [
            (0, 1),
            (1, 2),
            (2, 3),
            (3, 0),
            (0, 4),
            (4, 5),
            (5, 6),
            (6, 0),
        ];
        assert_eq!(count_loops(7, &e), 2);
        assert_eq!(count_loops(7, &[]), 0);
    }
}
