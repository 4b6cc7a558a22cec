//! Growth state (spec §3): point states, front loops of directed edges, the edge heap,
//! the triangle list, and the topological operations JOIN / FILL / LINK / GLUE (§4.5).
//!
//! Invariants kept by construction:
//! * every front edge `a -> b` has exactly one incident triangle, which traverses
//!   `a -> b`; a new triangle on it is stored `(a, t, b)` (opposite direction);
//! * every front vertex has exactly one incoming and one outgoing front edge (`fin`,
//!   `fout`), so its triangles form one fan;
//! * no triangle is added whose edge already exists unless the operation consumes that
//!   edge as a front edge (checked by the caller with [`Adjacency::has`]).
//!
//! Hence every mesh edge has at most two faces, every vertex link is a single fan, and
//! neighbouring triangles are oriented consistently.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;

use super::adjacency::Adjacency;
use super::cross::{XNear, XProj};
use super::grid::{FrontIndex, Grid, NONE};

/// Point state `Free` (spec §3.1; the transient `Close` state is the candidate buffer).
pub(crate) const FREE: u8 = 0;
/// Point state `Accepted` (a mesh vertex; a front point when it has front edges).
pub(crate) const ACCEPTED: u8 = 1;
/// Point state `Refused` (noise; also exact duplicates from the start).
pub(crate) const REFUSED: u8 = 2;

/// Resolved numeric configuration of one growth.
#[derive(Debug, Clone)]
pub(crate) struct Cfg {
    /// Candidate ball radius R.
    pub r: f64,
    pub cos_alpha: f64,
    pub cos_beta: f64,
    pub w: [f64; 3],
    pub seg_dist: bool,
    pub apex_rule: bool,
    pub link_prev: bool,
    pub glue_mirror: bool,
    /// Crossing-test radius, in units of R.
    pub cross_factor: f64,
    pub reject_free_inside: bool,
    /// Height bound of the Free points that block a triangle (IMPL-CHOICE I12; absolute).
    pub free_inside_h: f64,
    /// Relative height bound of the blocking Free points, share of the longest edge
    /// (IMPL-CHOICE I12).
    pub free_inside_rel: f64,
    /// IMPL-CHOICE I13: interior mesh vertices inside (a, t, b) block it.
    pub interior_inside: bool,
    /// IMPL-CHOICE I14: a triangle that intersects a mesh face sharing none of its
    /// vertices is refused.
    pub self_check: bool,
    /// IMPL-CHOICE I6: reject triangles that contain a front vertex in 2-D.
    pub front_inside_check: bool,
    pub fill_any_angle: bool,
    pub sector_check: bool,
    pub revisit_passes: u32,
    /// sin of the largest elevation of a Free candidate (IMPL-CHOICE I5); >= 1 = off.
    pub sin_elev: f64,
    /// Largest height of a Free candidate in units of R (IMPL-CHOICE I5).
    pub height_r: f64,
    /// Cosine of the largest angle between a front candidate's fan normal and the
    /// edge's (IMPL-CHOICE I10); < -1 = off.
    pub cos_front: f64,
    /// Neighbours of the support plane (IMPL-CHOICE I8); < 3 = off.
    pub support_k: usize,
    /// Neighbour search radius of the support test, in units of R (IMPL-CHOICE I8).
    pub support_radius: f64,
    /// Plane distance tolerance of the support test (absolute; IMPL-CHOICE I8).
    pub support_tol: f64,
    /// Share of the neighbours the support plane must hold (IMPL-CHOICE I8).
    pub support_share: f64,
    /// IMPL-CHOICE I11: an I8-supported candidate must lie on a plane that meets the
    /// tangent plane at the edge within its distance from the edge midpoint.
    pub support_crease: bool,
}

/// Operation counters (diagnostics).
#[derive(Debug, Clone, Default)]
pub(crate) struct Stats {
    pub pops: u64,
    pub boundary_pops: u64,
    pub joins: u64,
    pub fills: u64,
    pub link_next: u64,
    pub link_prev: u64,
    pub glues: u64,
    pub glue_mirrors: u64,
    pub glue_rejects: u64,
    pub cross_rejects: u64,
    pub seeds: u64,
    pub fail_rules: u64,
    pub sector_rejects: u64,
    /// Candidates refused by IMPL-CHOICE I13 (an interior mesh vertex inside).
    pub interior_rejects: u64,
    /// Candidates refused by IMPL-CHOICE I14 (they would cross a mesh face).
    pub self_rejects: u64,
    pub holes_closed: u64,
    pub holes_filled: u64,
}

impl Stats {
    pub fn add(&mut self, o: &Stats) {
        self.pops += o.pops;
        self.boundary_pops += o.boundary_pops;
        self.joins += o.joins;
        self.fills += o.fills;
        self.link_next += o.link_next;
        self.link_prev += o.link_prev;
        self.glues += o.glues;
        self.glue_mirrors += o.glue_mirrors;
        self.glue_rejects += o.glue_rejects;
        self.cross_rejects += o.cross_rejects;
        self.seeds += o.seeds;
        self.fail_rules += o.fail_rules;
        self.sector_rejects += o.sector_rejects;
        self.interior_rejects += o.interior_rejects;
        self.self_rejects += o.self_rejects;
        self.holes_closed += o.holes_closed;
        self.holes_filled += o.holes_filled;
    }
}

/// A candidate (spec §4.4 Steps 1-3).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cand {
    pub t: u32,
    pub score: f64,
    pub n_new: DVec3,
}

/// One triangle of the IMPL-CHOICE I14 face index: its corners (a copy of its entry in
/// `tris`), the number of the check that last visited it (deduplication), and per corner
/// `k` the next corner `4 f' + k'` of the list of faces on that corner's point (`NONE` at
/// the end; the fourth entry is unused: a power-of-two size, indexable by `k & 3` without
/// a bounds check). One 32-byte record, so that a face visit of the check reads one cache line
/// instead of three arrays indexed by face (the walk is memory-bound at 1M points).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub(crate) struct FaceRec {
    pub v: [u32; 3],
    pub seen: u32,
    pub next: [u32; 4],
}

/// Heap entry: (cost bits, FIFO counter, edge, stamp), smallest first.
type HeapItem = Reverse<(u64, u64, u32, u32)>;

/// The growth state over the points of one grid (grid order).
#[derive(Debug)]
pub(crate) struct Mesher<'g> {
    pub pts: &'g [DVec3],
    pub grid: &'g Grid,
    pub cfg: Cfg,
    pub state: Vec<u8>,
    pub fin: Vec<u32>,
    pub fout: Vec<u32>,
    // Front edges, slot arrays (slots of dead edges are recycled; the stamp tells stale
    // heap entries apart).
    pub e_a: Vec<u32>,
    pub e_b: Vec<u32>,
    pub e_prev: Vec<u32>,
    pub e_next: Vec<u32>,
    pub e_stamp: Vec<u32>,
    pub e_alive: Vec<bool>,
    pub e_nrm: Vec<DVec3>,
    pub e_cost: Vec<f64>,
    /// Length of each edge slot's edge `|b - a|`.
    pub e_len: Vec<f64>,
    free_slots: Vec<u32>,
    heap: BinaryHeap<HeapItem>,
    fifo: u64,
    pub tris: Vec<[u32; 3]>,
    /// Per point: sum of the unit normals of its triangles (fan normal, IMPL-CHOICE I5).
    pub vn: Vec<DVec3>,
    pub adj: Adjacency,
    pub fidx: FrontIndex,
    pub cand: Vec<Cand>,
    pub free_near: Vec<u32>,
    /// Interior mesh vertices within R of the popped edge's midpoint (scratch of
    /// IMPL-CHOICE I13).
    pub mesh_near: Vec<u32>,
    /// Meshed points (front or interior) within R of the popped edge's midpoint
    /// (scratch of IMPL-CHOICE I14).
    pub done_near: Vec<u32>,
    /// Per point: the corner `4 f + k` of the last triangle `f` added on it, `NONE` if
    /// none (IMPL-CHOICE I14).
    pub vf_head: Vec<u32>,
    /// Per point: its longest incident mesh edge, the reach of its triangles.
    pub v_reach: Vec<f64>,
    /// Per triangle: its record in the IMPL-CHOICE I14 face index (see [`FaceRec`]).
    pub faces: Vec<FaceRec>,
    /// The current check's number for [`FaceRec::seen`].
    pub seen_stamp: u32,
    /// Pending candidates `(key, point)` of the lazy evaluation (scratch; key: squared
    /// distance to the edge midpoint, or minus the score bound for the segment distance).
    pub pend: Vec<(f64, u32)>,
    /// Front edges near the popped edge, with their cull data (scratch).
    pub xs: Vec<XNear>,
    /// Front-index chunks near the popped edge (scratch).
    pub chunks: Vec<u32>,
    /// `xs` projected into the current validation plane (scratch).
    pub xp: Vec<XProj>,
    pub stats: Stats,
    /// True during the revisit passes (IMPL-CHOICE I2/I3).
    pub revisiting: bool,
    /// Per point: IMPL-CHOICE I8 support test, 0 = not computed, 1 = pass, 2 = fail.
    pub support: Vec<u8>,
    /// kNN scratch of the support test.
    pub sup_buf: Vec<(f64, u32)>,
    /// Neighbour directions scratch of the support test.
    pub sup_dirs: Vec<DVec3>,
    /// Unit normal of the support plane of each point that passed the I8 test.
    pub sup_nrm: std::collections::HashMap<u32, DVec3>,
}

/// Unit normal of the triangle `(p0, p1, p2)`, `n = (p1 - p0) x (p2 - p0)` normalised
/// (zero for a degenerate triangle).
#[inline]
pub(crate) fn tri_normal(p0: DVec3, p1: DVec3, p2: DVec3) -> DVec3 {
    (p1 - p0).cross(p2 - p0).normalize_or_zero()
}

/// Edge cost T = 1 - cos(normal change), Eq. (1), clamped to [0, 2].
#[inline]
pub(crate) fn cost(n_new: DVec3, n_old: DVec3) -> f64 {
    (1.0 - n_new.dot(n_old)).clamp(0.0, 2.0)
}

impl<'g> Mesher<'g> {
    /// A fresh state: every point Free except those in `refused`.
    pub fn new(pts: &'g [DVec3], grid: &'g Grid, cfg: Cfg, refused: &[bool]) -> Self {
        let n = pts.len();
        let self_check = cfg.self_check;
        let state = (0..n)
            .map(|i| if refused[i] { REFUSED } else { FREE })
            .collect();
        let fidx = FrontIndex::new(grid, n, 2.0 * grid.lat.h());
        Self {
            pts,
            grid,
            cfg,
            state,
            fin: vec![NONE; n],
            fout: vec![NONE; n],
            e_a: Vec::new(),
            e_b: Vec::new(),
            e_prev: Vec::new(),
            e_next: Vec::new(),
            e_stamp: Vec::new(),
            e_alive: Vec::new(),
            e_nrm: Vec::new(),
            e_cost: Vec::new(),
            e_len: Vec::new(),
            free_slots: Vec::new(),
            heap: BinaryHeap::new(),
            fifo: 0,
            tris: Vec::new(),
            vn: vec![DVec3::ZERO; n],
            adj: Adjacency::new(n),
            fidx,
            cand: Vec::new(),
            free_near: Vec::new(),
            mesh_near: Vec::new(),
            done_near: Vec::new(),
            vf_head: if self_check {
                vec![NONE; n]
            } else {
                Vec::new()
            },
            v_reach: if self_check { vec![0.0; n] } else { Vec::new() },
            faces: Vec::new(),
            seen_stamp: 0,
            pend: Vec::new(),
            xs: Vec::new(),
            chunks: Vec::new(),
            xp: Vec::new(),
            stats: Stats::default(),
            revisiting: false,
            support: vec![0; n],
            sup_buf: Vec::new(),
            sup_dirs: Vec::new(),
            sup_nrm: std::collections::HashMap::new(),
        }
    }

    /// Appends triangle `t` to L and adds its unit normal to its vertices' fan normals.
    #[inline]
    pub fn add_tri(&mut self, t: [u32; 3]) {
        let p = t.map(|i| self.pts[i as usize]);
        let n = tri_normal(p[0], p[1], p[2]);
        for &v in &t {
            self.vn[v as usize] += n;
        }
        if self.cfg.self_check {
            self.index_face(t, p);
        }
        self.tris.push(t);
    }

    /// Appends triangle `t` (corner positions `p`) to the IMPL-CHOICE I14 face index as
    /// face number `faces.len()`: links it into its corners' face lists and widens
    /// their reach.
    #[inline]
    pub(crate) fn index_face(&mut self, t: [u32; 3], p: [DVec3; 3]) {
        let f = self.faces.len() as u32;
        let mut next = [NONE; 4];
        for (k, &v) in t.iter().enumerate() {
            let v = v as usize;
            next[k] = self.vf_head[v];
            self.vf_head[v] = 4 * f + k as u32;
            let far = p[(k + 1) % 3]
                .distance(p[k])
                .max(p[(k + 2) % 3].distance(p[k]));
            self.v_reach[v] = self.v_reach[v].max(far);
        }
        self.faces.push(FaceRec {
            v: t,
            seen: 0,
            next,
        });
    }

    /// True when `v` has front edges.
    #[inline]
    pub fn is_front(&self, v: u32) -> bool {
        self.fout[v as usize] != NONE
    }

    /// Pushes live edge `e` onto the heap with cost `t`.
    // ASSUMPTION A3: ties of T are broken by a FIFO insertion counter (determinism).
    #[inline]
    pub fn push(&mut self, e: u32, t: f64) {
        self.fifo += 1;
        let bits = t.max(0.0).to_bits();
        self.heap
            .push(Reverse((bits, self.fifo, e, self.e_stamp[e as usize])));
    }

    /// Pops the cheapest live edge (lazy deletion: stale entries are skipped).
    #[inline]
    pub fn pop(&mut self) -> Option<u32> {
        while let Some(Reverse((_, _, e, stamp))) = self.heap.pop() {
            if self.e_alive[e as usize] && self.e_stamp[e as usize] == stamp {
                return Some(e);
            }
        }
        None
    }

    /// True when no entry (live or stale) is queued.
    pub fn heap_is_empty(&self) -> bool {
        self.heap.is_empty()
    }

    /// Pushes every live front edge again (multi-seed / slab stitching).
    pub fn repush_all(&mut self) {
        self.heap.clear();
        for e in 0..self.e_a.len() as u32 {
            if self.e_alive[e as usize] {
                let t = self.e_cost[e as usize];
                self.push(e, t);
            }
        }
    }

    /// Clears the heap and pushes the live edges among `edges` (slab stitching).
    pub fn push_only(&mut self, edges: &[u32]) {
        self.heap.clear();
        for &e in edges {
            if self.e_alive[e as usize] {
                let t = self.e_cost[e as usize];
                self.push(e, t);
            }
        }
    }

    /// Creates front edge `a -> b` whose incident triangle has unit normal `nrm`; it is
    /// not linked into a loop yet.
    #[inline]
    fn new_edge(&mut self, a: u32, b: u32, nrm: DVec3, t: f64, push: bool) -> u32 {
        let len = (self.pts[b as usize] - self.pts[a as usize]).length();
        let e = if let Some(e) = self.free_slots.pop() {
            let i = e as usize;
            self.e_a[i] = a;
            self.e_b[i] = b;
            self.e_prev[i] = NONE;
            self.e_next[i] = NONE;
            self.e_alive[i] = true;
            self.e_nrm[i] = nrm;
            self.e_cost[i] = t;
            self.e_len[i] = len;
            e
        } else {
            self.e_a.push(a);
            self.e_b.push(b);
            self.e_prev.push(NONE);
            self.e_next.push(NONE);
            self.e_stamp.push(0);
            self.e_alive.push(true);
            self.e_nrm.push(nrm);
            self.e_cost.push(t);
            self.e_len.push(len);
            (self.e_a.len() - 1) as u32
        };
        self.fout[a as usize] = e;
        self.fin[b as usize] = e;
        if push {
            self.push(e, t);
        }
        e
    }

    #[inline]
    fn kill_edge(&mut self, e: u32) {
        let i = e as usize;
        debug_assert!(self.e_alive[i]);
        self.e_alive[i] = false;
        self.e_stamp[i] = self.e_stamp[i].wrapping_add(1);
        let (a, b) = (self.e_a[i], self.e_b[i]);
        if self.fout[a as usize] == e {
            self.fout[a as usize] = NONE;
        }
        if self.fin[b as usize] == e {
            self.fin[b as usize] = NONE;
        }
        self.free_slots.push(e);
    }

    #[inline]
    fn link(&mut self, e: u32, f: u32) {
        self.e_next[e as usize] = f;
        self.e_prev[f as usize] = e;
    }

    /// Removes `v` from the front bookkeeping when it has no front edge left.
    #[inline]
    fn retire_if_interior(&mut self, v: u32) {
        if self.fin[v as usize] == NONE && self.fout[v as usize] == NONE {
            self.fidx.remove(v);
            self.adj.release(v);
        }
    }

    /// Registers the seed triangle `(v0, v1, v2)` as a 3-edge loop with T = 0.
    pub fn add_seed(&mut self, v: [u32; 3]) {
        let p = v.map(|i| self.pts[i as usize]);
        let n = tri_normal(p[0], p[1], p[2]);
        self.add_tri(v);
        for k in 0..3 {
            self.state[v[k] as usize] = ACCEPTED;
            self.fidx.insert(v[k], p[k]);
        }
        self.adj.add(v[0], v[1]);
        self.adj.add(v[1], v[2]);
        self.adj.add(v[2], v[0]);
        let e0 = self.new_edge(v[0], v[1], n, 0.0, true);
        let e1 = self.new_edge(v[1], v[2], n, 0.0, true);
        let e2 = self.new_edge(v[2], v[0], n, 0.0, true);
        self.link(e0, e1);
        self.link(e1, e2);
        self.link(e2, e0);
        self.stats.seeds += 1;
    }

    /// JOIN (§4.5.1): `p` was Free.
    #[inline]
    pub fn join(&mut self, e: u32, p: u32, n_new: DVec3) {
        let (a, b) = (self.e_a[e as usize], self.e_b[e as usize]);
        let t = cost(n_new, self.e_nrm[e as usize]);
        let (zp, bn) = (self.e_prev[e as usize], self.e_next[e as usize]);
        self.add_tri([a, p, b]);
        self.state[p as usize] = ACCEPTED;
        self.fidx.insert(p, self.pts[p as usize]);
        self.adj.add(a, p);
        self.adj.add(p, b);
        self.kill_edge(e);
        // ASSUMPTION A18: both new edges get the bend across the consumed edge.
        let e1 = self.new_edge(a, p, n_new, t, true);
        let e2 = self.new_edge(p, b, n_new, t, true);
        self.link(zp, e1);
        self.link(e1, e2);
        self.link(e2, bn);
        self.stats.joins += 1;
    }

    /// FILL (§4.5.2): the loop is the triangle `a -> b -> p -> a`.
    #[inline]
    pub fn fill(&mut self, e: u32, p: u32) {
        let (a, b) = (self.e_a[e as usize], self.e_b[e as usize]);
        let bp = self.fout[b as usize];
        let pa = self.fout[p as usize];
        self.add_tri([a, p, b]);
        self.kill_edge(e);
        self.kill_edge(bp);
        self.kill_edge(pa);
        for v in [a, b, p] {
            self.retire_if_interior(v);
        }
        self.stats.fills += 1;
    }

    /// LINK-next (§4.5.3): `b -> p` is a front edge.
    #[inline]
    pub fn link_next(&mut self, e: u32, p: u32, n_new: DVec3) {
        let (a, b) = (self.e_a[e as usize], self.e_b[e as usize]);
        let t = cost(n_new, self.e_nrm[e as usize]);
        let f = self.fout[b as usize];
        let (zp, pn) = (self.e_prev[e as usize], self.e_next[f as usize]);
        self.add_tri([a, p, b]);
        self.adj.add(a, p);
        self.kill_edge(e);
        self.kill_edge(f);
        let e1 = self.new_edge(a, p, n_new, t, true);
        self.link(zp, e1);
        self.link(e1, pn);
        self.retire_if_interior(b);
        self.stats.link_next += 1;
    }

    /// LINK-prev (§4.5.3, ASSUMPTION A16 — the mirror of the paper's link): `p -> a` is
    /// a front edge.
    #[inline]
    pub fn link_prev(&mut self, e: u32, p: u32, n_new: DVec3) {
        let (a, b) = (self.e_a[e as usize], self.e_b[e as usize]);
        let t = cost(n_new, self.e_nrm[e as usize]);
        let g = self.fin[a as usize];
        let (zp, bn) = (self.e_prev[g as usize], self.e_next[e as usize]);
        self.add_tri([a, p, b]);
        self.adj.add(p, b);
        self.kill_edge(g);
        self.kill_edge(e);
        let e1 = self.new_edge(p, b, n_new, t, true);
        self.link(zp, e1);
        self.link(e1, bn);
        self.retire_if_interior(a);
        self.stats.link_prev += 1;
    }

    /// GLUE (§4.5.4) with the repair triangle `(p, q, b)`, `q -> p` the front
    /// predecessor edge of `p`; `n2` is the repair triangle's normal.
    #[inline]
    pub fn glue(&mut self, e: u32, p: u32, n_new: DVec3, n2: DVec3) {
        let (a, b) = (self.e_a[e as usize], self.e_b[e as usize]);
        let t1 = cost(n_new, self.e_nrm[e as usize]);
        let g = self.fin[p as usize];
        let q = self.e_a[g as usize];
        let t2 = cost(n2, self.e_nrm[g as usize]);
        let (zp, bn) = (self.e_prev[e as usize], self.e_next[e as usize]);
        let (qprev, py) = (self.e_prev[g as usize], self.e_next[g as usize]);
        self.add_tri([a, p, b]);
        self.add_tri([p, q, b]);
        self.adj.add(a, p);
        self.adj.add(p, b);
        self.adj.add(q, b);
        self.kill_edge(e);
        self.kill_edge(g);
        let e1 = self.new_edge(a, p, n_new, t1, true);
        let e2 = self.new_edge(q, b, n2, t2, true);
        self.link(zp, e1);
        self.link(e1, py);
        self.link(qprev, e2);
        self.link(e2, bn);
        self.stats.glues += 1;
    }

    /// Mirrored GLUE repair (ASSUMPTION A17): second triangle `(a, y, p)`, `p -> y` the
    /// front successor edge of `p`; `n2` is its normal.
    #[inline]
    pub fn glue_mirror(&mut self, e: u32, p: u32, n_new: DVec3, n2: DVec3) {
        let (a, b) = (self.e_a[e as usize], self.e_b[e as usize]);
        let t1 = cost(n_new, self.e_nrm[e as usize]);
        let h = self.fout[p as usize];
        let y = self.e_b[h as usize];
        let t2 = cost(n2, self.e_nrm[h as usize]);
        let (zp, bn) = (self.e_prev[e as usize], self.e_next[e as usize]);
        let (qp, ys) = (self.e_prev[h as usize], self.e_next[h as usize]);
        self.add_tri([a, p, b]);
        self.add_tri([a, y, p]);
        self.adj.add(a, p);
        self.adj.add(p, b);
        self.adj.add(a, y);
        self.kill_edge(e);
        self.kill_edge(h);
        let e1 = self.new_edge(a, y, n2, t2, true);
        let e2 = self.new_edge(p, b, n_new, t1, true);
        self.link(zp, e1);
        self.link(e1, ys);
        self.link(qp, e2);
        self.link(e2, bn);
        self.stats.glue_mirrors += 1;
    }

    /// Live front loops as vertex cycles (hole / boundary report), in a deterministic
    /// order (by lowest edge slot).
    pub fn loops(&self) -> Vec<Vec<u32>> {
        let mut seen = vec![false; self.e_a.len()];
        let mut out = Vec::new();
        for e0 in 0..self.e_a.len() {
            if !self.e_alive[e0] || seen[e0] {
                continue;
            }
            let mut l = Vec::new();
            let mut e = e0;
            while !seen[e] {
                seen[e] = true;
                l.push(self.e_a[e]);
                e = self.e_next[e] as usize;
                if e == NONE as usize || l.len() > self.e_a.len() {
                    break;
                }
            }
            out.push(l);
        }
        out
    }

    /// Rebuilds a state from a finished sub-run: triangles, accepted points and live
    /// front loops given as `(a, b, next-index-in-list, normal, cost)`; `a`, `b` are
    /// indices of this mesher's points.
    pub fn import(
        &mut self,
        tris: &[[u32; 3]],
        accepted: &[u32],
        edges: &[(u32, u32, u32, DVec3, f64)],
    ) {
        for &t in tris {
            self.add_tri(t);
        }
        for &v in accepted {
            self.state[v as usize] = ACCEPTED;
        }
        let base = self.e_a.len() as u32;
        for &(a, b, _, nrm, t) in edges {
            self.new_edge(a, b, nrm, t, false);
            self.fidx.insert(a, self.pts[a as usize]);
        }
        for (k, &(_, _, nx, _, _)) in edges.iter().enumerate() {
            self.link(base + k as u32, base + nx);
        }
        // Adjacency of front vertices: every triangle edge joining two front vertices.
        for tri in tris {
            for k in 0..3 {
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                if self.is_front(u) && self.is_front(v) && !self.adj.has(u, v) {
                    self.adj.add(u, v);
                }
            }
        }
    }
}
