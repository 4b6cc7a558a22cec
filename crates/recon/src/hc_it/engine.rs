//! The point-at-a-time engine: clustering (spec §3.2) and incremental triangulation
//! (§3.3) over the x-sorted points.

use std::collections::VecDeque;
use std::f64::consts::FRAC_PI_2;

use glam::DVec3;

use super::cluster::UnionFind;
use super::edge_grid::EdgeGrid;
use super::mesh::{
    AngleBound, MILLIRAD, Mesh, NONE, ONE_DEGREE, RIGHT, angle, cross, crosses, rotate_to,
};
use super::params::{ConflictRule, EdgeDistance, WinnerScan};

/// A boundary edge a -> b with its triangle.
type BEdge = (u32, u32, u32);

/// Resolved options of one run (lengths in input units).
#[derive(Debug, Clone)]
pub struct Opts {
    /// rho in input units.
    pub rho: f64,
    /// theta threshold (rad).
    pub theta: f64,
    /// psi threshold (rad).
    pub psi: f64,
    /// Unit reference vector k.
    pub k: DVec3,
    /// ASSUMPTION H8.
    pub strict_rho: bool,
    /// ASSUMPTION H7.
    pub edge_distance: EdgeDistance,
    /// Winner search scope.
    pub winner_scan: WinnerScan,
    /// ASSUMPTION H11 on/off.
    pub neighbourhood: bool,
    /// Cap on a neighbourhood triangle's new edge (input units; infinite = none).
    pub ear_max_edge: f64,
    /// ASSUMPTION H12.
    pub conflict_rule: ConflictRule,
    /// ASSUMPTION H13 on/off.
    pub flips: bool,
}

/// Counters reported as diagnostics.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Stats {
    /// First triangles of clusters (§3.3.1 and H6).
    pub first_triangles: usize,
    /// Tentative triangles created after the theta / gamma / psi tests.
    pub created: usize,
    /// Winner triangles split into three.
    pub splits: usize,
    /// Extra cases: points detached into a new partition.
    pub extra_cases: usize,
    /// Neighbourhood (ear / fan) triangles.
    pub neighbourhood: usize,
    /// Shortest-diagonal flips.
    pub flips: usize,
    /// Triangles refused because they would break manifoldness or orientation.
    pub refused: usize,
    /// Points with a winner search that found no boundary edge.
    pub no_winner: usize,
    /// Triangles of the sweep alone (before the closure pass).
    pub sweep_triangles: usize,
    /// Points the sweep alone left unmeshed.
    pub sweep_unmeshed: usize,
    /// Triangles added by the closure pass.
    pub zip_triangles: usize,
    /// Sweep-unmeshed points the closure pass meshed.
    pub zip_attached: usize,
    /// Folded or overlapping sweep triangles the closure pass left out.
    pub zip_unfolded: usize,
    /// Triangles the closure pass added to fill small loops.
    pub zip_filled: usize,
    /// Triangles the closure pass split to close slits.
    pub zip_slits: usize,
    /// Triangles the closure pass added to join two fans at a vertex.
    pub zip_joined: usize,
    /// Triangles the closure pass removed to cut a second fan loose from a vertex.
    pub zip_cut: usize,
    /// Faces reversed by the orientation by k (H14).
    pub oriented_flips: usize,
}

/// Unnormalized normal of `t` (Eq. 1), for callers outside the engine.
pub fn normal_of(p: &[DVec3], t: [u32; 3]) -> DVec3 {
    cross(p, t)
}

impl Stats {
    /// Adds another run's counters (portions, H15).
    pub fn add(&mut self, o: &Stats) {
        self.first_triangles += o.first_triangles;
        self.created += o.created;
        self.splits += o.splits;
        self.extra_cases += o.extra_cases;
        self.neighbourhood += o.neighbourhood;
        self.flips += o.flips;
        self.refused += o.refused;
        self.no_winner += o.no_winner;
        self.sweep_triangles += o.sweep_triangles;
        self.sweep_unmeshed += o.sweep_unmeshed;
        self.zip_triangles += o.zip_triangles;
        self.zip_attached += o.zip_attached;
        self.zip_unfolded += o.zip_unfolded;
        self.zip_filled += o.zip_filled;
        self.zip_slits += o.zip_slits;
        self.zip_joined += o.zip_joined;
        self.zip_cut += o.zip_cut;
        self.oriented_flips += o.oriented_flips;
    }
}

/// Result of [`run`].
#[derive(Debug)]
pub struct Outcome {
    /// The mesh (input vertex indices).
    pub tris: Vec<[u32; 3]>,
    /// NC root of every point (ids up to `2n`).
    pub nc: Vec<u32>,
    /// SM root of every point.
    pub sm: Vec<u32>,
    /// Counters.
    pub stats: Stats,
}

struct State<'a> {
    p: &'a [DVec3],
    o: &'a Opts,
    mesh: Mesh,
    nc: UnionFind,
    sm: UnionFind,
    /// NC / SM node of each point (`n + i` once detached).
    nc_id: Vec<u32>,
    sm_id: Vec<u32>,
    /// Triangles per NC root.
    nc_tris: Vec<u32>,
    stats: Stats,
    buf: Vec<(u32, u32, u32)>,
    flip_cap: usize,
    /// Boundary edges a -> b per NC root of a, for the winner scan over a whole NC:
    /// filled lazily from the mesh's boundary log (`logged` entries taken so far),
    /// moved along when NCs merge, pruned of edges that stopped being boundary edges
    /// when scanned.
    nc_boundary: Vec<Vec<(u32, u32, u32)>>,
    logged: usize,
    /// Per triangle slot (3 t + k): the scan (`edge_gen`) that last saw it.
    edge_mark: Vec<u32>,
    edge_gen: u32,
    /// Boundary edges by place, for the fallback search (made at its first use).
    grid: Option<EdgeGrid>,
    /// Cell indices of one ring of the grid search.
    ring: Vec<usize>,
    /// The theta threshold.
    fold: AngleBound,
}

/// Runs HC-IT over `order` (the processing order of §3.1). `nbrs(i)` yields the
/// points strictly within rho of point `i` that come before it in `order`, nearest first.
pub fn run<'b>(
    p: &[DVec3],
    order: &[u32],
    nbrs: impl Fn(u32) -> &'b [u32],
    o: &Opts,
    checkpoint: &mut dyn FnMut() -> Result<(), reconbench_geom::method::MethodError>,
) -> Result<Outcome, reconbench_geom::method::MethodError> {
    let n = p.len();
    // ASSUMPTION H1: SM and NC as union-find forests over point ids (plus one fresh id
    // per point for the extra case), each NC root owning its triangle count; the meshes
    // of all NCs live in one edge-manifold structure.
    let mut s = State {
        p,
        o,
        mesh: Mesh::with_capacity(n, 2 * n),
        nc: UnionFind::new(2 * n),
        sm: UnionFind::new(2 * n),
        nc_id: (0..n as u32).collect(),
        sm_id: (0..n as u32).collect(),
        nc_tris: vec![0; 2 * n],
        stats: Stats::default(),
        buf: Vec::new(),
        flip_cap: 0,
        nc_boundary: vec![Vec::new(); 2 * n],
        logged: 0,
        edge_mark: Vec::new(),
        edge_gen: 1,
        grid: None,
        ring: Vec::new(),
        fold: AngleBound::new(o.theta),
    };
    s.mesh.log_boundary();
    let mut groups: Vec<(u32, u32)> = Vec::new();
    for (step, &i) in order.iter().enumerate() {
        if step % 4096 == 0 {
            checkpoint()?;
        }
        // C2: group the rho-neighbours (Lg) by their NC; g = count per NC.
        groups.clear();
        for &v in nbrs(i) {
            let r = s.nc.find(s.nc_id[v as usize]);
            match groups.iter_mut().find(|(root, _)| *root == r) {
                Some(g) => g.1 += 1,
                None => groups.push((r, 1)),
            }
            // Every g >= 1 case (1, 3, 4) merges the SM.
            let sv = s.sm_id[v as usize];
            s.sm.union(s.sm_id[i as usize], sv);
        }
        // ASSUMPTION H4: an NC with g == 0 (whatever its size d) is left alone (case 2).
        let mut case4 = false;
        for &(r, g) in &groups {
            let d = s.nc.size(r);
            if g == 1 && d == 1 {
                // case 1: P joins a singleton.
                s.union_nc(s.nc_id[i as usize], r);
            } else if g > 1 {
                // case 4 (ASSUMPTION H5: every case-4 NC is merged, meshes united).
                s.union_nc(s.nc_id[i as usize], r);
                case4 = true;
            }
            // case 3 (g == 1, d > 1): the SM merge above only.
        }
        let root = s.nc.find(s.nc_id[i as usize]);
        if case4 && s.nc.size(root) >= 3 {
            s.triangulate(i, root, nbrs(i));
        }
    }
    let mut nc = Vec::with_capacity(n);
    let mut sm = Vec::with_capacity(n);
    for i in 0..n {
        nc.push(s.nc.find(s.nc_id[i]));
        sm.push(s.sm.find(s.sm_id[i]));
    }
    Ok(Outcome {
        tris: s.mesh.tris,
        nc,
        sm,
        stats: s.stats,
    })
}

impl State<'_> {
    fn union_nc(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.nc.find(a), self.nc.find(b));
        if ra == rb {
            return;
        }
        let t = self.nc_tris[ra as usize] + self.nc_tris[rb as usize];
        let r = self.nc.union(ra, rb);
        self.nc_tris[r as usize] = t;
        // The merged NC's boundary edges: the shorter list appended to the longer.
        let gone = if r == ra { rb } else { ra };
        let mut moved = std::mem::take(&mut self.nc_boundary[gone as usize]);
        let kept = &mut self.nc_boundary[r as usize];
        if moved.len() > kept.len() {
            std::mem::swap(&mut moved, kept);
        }
        kept.extend_from_slice(&moved);
    }

    /// Every boundary edge (a, b, triangle) of the NC `root` (a in it), each once, in no
    /// particular order (the winner is the minimum of a total order, so the order does
    /// not matter).
    fn nc_boundary_edges(&mut self, root: u32, out: &mut Vec<BEdge>) {
        self.feed_nc_lists();
        let mut list = std::mem::take(&mut self.nc_boundary[root as usize]);
        // Keep each current boundary edge once: an entry is current when its slot still
        // holds the edge as a boundary edge (every slot that became one was logged, so
        // each current boundary edge has an entry); a repeat is known by its slot's mark.
        self.edge_mark.resize(3 * self.mesh.tris.len(), 0);
        list.retain(|&(a, b, slot)| {
            if !self.mesh.is_boundary_slot(a, b, slot) {
                return false;
            }
            let m = &mut self.edge_mark[slot as usize];
            if *m == self.edge_gen {
                return false;
            }
            *m = self.edge_gen;
            out.push((a, b, slot / 3));
            true
        });
        self.edge_gen += 1;
        debug_assert!(
            out.iter()
                .all(|c| self.nc.find(self.nc_id[c.0 as usize]) == root)
        );
        self.nc_boundary[root as usize] = list;
    }

    /// Takes the boundary log's new entries into the per-NC lists, those that are still
    /// boundary edges (one that becomes a boundary edge again is logged again).
    fn feed_nc_lists(&mut self) {
        let log_len = self.mesh.boundary_log().len();
        for k in self.logged..log_len {
            let e = self.mesh.boundary_log()[k];
            if !self.mesh.is_boundary_slot(e.0, e.1, e.2) {
                continue;
            }
            let r = self.root_of(e.0);
            self.nc_boundary[r as usize].push(e);
        }
        self.logged = log_len;
    }

    /// The nearest boundary edge a -> b of NC `root` to `pp` by the segment distance,
    /// ties by (a, b): the minimum [`Self::winner`]'s scan over every boundary edge of
    /// the NC finds, searched in the grid of boundary edges ring by ring from P's cell
    /// (see `edge_grid`). `Err(())` when the search visited more cells than four times
    /// the NC's list of boundary edges (the caller then scans the list).
    fn nearest_in_grid(&mut self, pp: DVec3, root: u32) -> Result<Option<BEdge>, ()> {
        self.feed_nc_lists();
        let budget = 4 * self.nc_boundary[root as usize].len() + 64;
        let mut grid = self.grid.take().unwrap_or_else(|| {
            // At most 4 cells per point: the lists of empty cells cost 24 bytes each.
            EdgeGrid::new(self.p, self.o.rho, 4 * self.p.len() + 64)
        });
        let mesh = &self.mesh;
        grid.feed(self.p, mesh.boundary_log(), |e| {
            mesh.is_boundary_slot(e.0, e.1, e.2)
        });
        self.edge_mark.resize(3 * self.mesh.tris.len(), 0);
        let gen_ = self.edge_gen;
        self.edge_gen += 1;
        let c = grid.cell(pp);
        let mut ring = std::mem::take(&mut self.ring);
        let mut best: Option<(f64, (u32, u32), BEdge)> = None;
        let mut visited = 0usize;
        let mut result = Err(());
        for k in 0i64.. {
            ring.clear();
            let all = grid.ring(c, k, &mut ring);
            visited += ring.len();
            for &ci in &ring {
                let mut i = 0;
                while i < grid.cells[ci].len() {
                    let (a, b, slot) = grid.cells[ci][i];
                    if !self.mesh.is_boundary_slot(a, b, slot) {
                        grid.cells[ci].swap_remove(i);
                        continue;
                    }
                    i += 1;
                    let m = &mut self.edge_mark[slot as usize];
                    if *m == gen_ {
                        continue;
                    }
                    *m = gen_;
                    if self.root_of(a) != root {
                        continue;
                    }
                    let d = self.edge_dist(pp, a, b);
                    let kk = (a, b);
                    if best.is_none_or(|(bd, bk, _)| d < bd || (d == bd && kk < bk)) {
                        best = Some((d, kk, (a, b, slot / 3)));
                    }
                }
            }
            // Every edge not seen is at least k cells from P (margin: an eighth of a
            // cell, far above the rounding of the cell and distance computations).
            let bound = (k as f64 - 0.125) * grid.h;
            if all || best.is_some_and(|(bd, _, _)| bd < bound) {
                result = Ok(best.map(|b| b.2));
                break;
            }
            if visited > budget {
                break;
            }
        }
        self.ring = ring;
        self.grid = Some(grid);
        result
    }

    fn root_of(&mut self, v: u32) -> u32 {
        self.nc.find(self.nc_id[v as usize])
    }

    fn pt(&self, v: u32) -> DVec3 {
        self.p[v as usize]
    }

    fn add(&mut self, t: [u32; 3], root: u32) -> Option<u32> {
        // Degenerate triangles (min angle below 1 degree) are refused like non-manifold
        // ones: their normal, which every test uses, is meaningless.
        let ok = !ONE_DEGREE.min_angle_at_most(self.pt(t[0]), self.pt(t[1]), self.pt(t[2]));
        match ok.then(|| self.mesh.add(t)).flatten() {
            Some(id) => {
                self.nc_tris[root as usize] += 1;
                self.flip_cap += 10;
                Some(id)
            }
            None => {
                self.stats.refused += 1;
                None
            }
        }
    }

    /// Detaches `i` from its NC into a fresh partition (the "extra case", rule 2).
    fn detach(&mut self, i: u32, root: u32) {
        let n = self.p.len() as u32;
        self.nc.shrink(root);
        self.nc_id[i as usize] = n + i;
        self.sm_id[i as usize] = n + i;
        self.stats.extra_cases += 1;
    }

    fn triangulate(&mut self, i: u32, root: u32, lg: &[u32]) {
        if self.nc_tris[root as usize] == 0 {
            self.first_triangle(i, root, lg);
            return;
        }
        let Some((x, y, w_id)) = self.winner(i, root, lg) else {
            self.stats.no_winner += 1;
            return;
        };
        let w = rotate_to(self.mesh.tris[w_id as usize], x);
        let t_new = [i, y, x];
        let n_w = cross(self.p, w);
        let n_new = cross(self.p, t_new);
        if !self.fold.reached_by(n_new, n_w) {
            self.create(i, root, t_new);
            return;
        }
        // ASSUMPTION H9: check triangles K_j = (a, b, P) over W's other edges f_j = a -> b,
        // in W's direction; gamma_j against the neighbour across f_j, psi_j against W.
        let others = [(w[1], w[2]), (w[2], w[0])];
        let mut best: Option<(f64, f64)> = None; // (gamma, psi) of j* = argmin gamma
        let mut min_psi = f64::INFINITY;
        for &(a, b) in &others {
            let n_k = cross(self.p, [a, b, i]);
            let psi = angle(n_w, n_k);
            min_psi = min_psi.min(psi);
            if let Some(nj) = self.mesh.across(w_id, a, b) {
                let gamma = angle(cross(self.p, self.mesh.tris[nj as usize]), n_k);
                if best.is_none_or(|(g, _)| gamma < g) {
                    best = Some((gamma, psi));
                }
            }
        }
        match best {
            Some((gamma, psi)) if gamma < FRAC_PI_2 => {
                if psi < self.o.psi {
                    self.split(i, root, w_id);
                } else {
                    // Rule 1, psi >= psi threshold: a steep surface is accepted.
                    self.create(i, root, t_new);
                }
            }
            Some(_) => self.detach(i, root),
            // ASSUMPTION H10: W without neighbours: the psi-only split test, else a new
            // partition.
            None if min_psi < self.o.psi => self.split(i, root, w_id),
            None => self.detach(i, root),
        }
    }

    /// §3.3.1 / ASSUMPTION H6: P and its two nearest NC members within rho (non-degenerate,
    /// min angle > 1 degree), oriented so the normal lies in the k half-space (Eq. 2).
    fn first_triangle(&mut self, i: u32, root: u32, lg: &[u32]) {
        // ASSUMPTION H6: the two nearest members within rho, min angle > 1 degree.
        let mut mem = [NONE; 2];
        let mut m = 0;
        for &v in lg {
            if self.root_of(v) == root {
                if m == 1 && ONE_DEGREE.min_angle_at_most(self.pt(i), self.pt(mem[0]), self.pt(v)) {
                    continue;
                }
                mem[m] = v;
                m += 1;
                if m == 2 {
                    break;
                }
            }
        }
        if m < 2 {
            return;
        }
        // C2 = P, C1 = the nearest, C0 = the second; n = (C1 - C2) x (C0 - C2).
        let (c2, c1, c0) = (i, mem[0], mem[1]);
        let n = (self.pt(c1) - self.pt(c2)).cross(self.pt(c0) - self.pt(c2));
        let beta = angle(n, self.o.k);
        let t = if beta <= FRAC_PI_2 {
            [c2, c1, c0]
        } else {
            [c2, c0, c1]
        };
        if self.add(t, root).is_some() {
            self.stats.first_triangles += 1;
        }
    }

    /// Distance from P to the boundary edge x -> y (ASSUMPTION H7).
    fn edge_dist(&self, pp: DVec3, x: u32, y: u32) -> f64 {
        let (a, b) = (self.pt(x), self.pt(y));
        let (d45, e) = (pp - a, b - a);
        let d34 = e.length();
        // ASSUMPTION H7: exact segment distance; `literal` is the paper's formula.
        match self.o.edge_distance {
            EdgeDistance::Segment => {
                let t = (d45.dot(e) / e.length_squared()).clamp(0.0, 1.0);
                (pp - (a + e * t)).length()
            }
            EdgeDistance::Literal => {
                let beta = angle(e, d45);
                let l = d45.length();
                if l * beta.cos() > d34 {
                    (pp - b).length()
                } else {
                    l * beta.sin()
                }
            }
        }
    }

    /// The winner edge x -> y and its triangle W (§3.3.2).
    fn winner(&mut self, i: u32, root: u32, lg: &[u32]) -> Option<(u32, u32, u32)> {
        let pp = self.pt(i);
        let mut cand = std::mem::take(&mut self.buf);
        cand.clear();
        if self.o.winner_scan == WinnerScan::Local {
            for &v in lg {
                if self.root_of(v) == root {
                    self.mesh.boundary_at(v, &mut cand);
                }
            }
        }
        if cand.is_empty() {
            // IMPL-CHOICE: with a true distance and no strict_rho, the nearest edge of the
            // NC is searched by place (the same edge as the full scan below, see
            // `edge_grid`); the full scan when that search would visit too many cells.
            if self.o.edge_distance == EdgeDistance::Segment
                && !self.o.strict_rho
                && let Ok(found) = self.nearest_in_grid(pp, root)
            {
                #[cfg(debug_assertions)]
                {
                    // The same edge as the full scan.
                    let mut all = Vec::new();
                    self.nc_boundary_edges(root, &mut all);
                    let full = all
                        .iter()
                        .map(|c| (self.edge_dist(pp, c.0, c.1), (c.0, c.1), *c))
                        .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                        .map(|b| b.2);
                    debug_assert_eq!(found, full, "grid search differs from the full scan");
                }
                self.buf = cand;
                return found;
            }
            // The paper's scan over every BTM edge of this NC.
            self.nc_boundary_edges(root, &mut cand);
            #[cfg(debug_assertions)]
            {
                // The same set as a walk over every triangle.
                let mut all = Vec::new();
                for (t, tri) in self.mesh.tris.iter().enumerate() {
                    for k in 0..3 {
                        let (a, b) = (tri[k], tri[(k + 1) % 3]);
                        if self.mesh.edge_tris(a, b)[1] == NONE {
                            all.push((a, b, t as u32));
                        }
                    }
                }
                all.retain(|c| self.nc.find(self.nc_id[c.0 as usize]) == root);
                all.sort_unstable();
                let mut got = cand.clone();
                got.sort_unstable();
                debug_assert_eq!(got, all, "NC boundary lists out of date");
            }
        }
        let rho = self.o.rho;
        let within = |s: &Self, c: &(u32, u32, u32)| {
            (s.pt(c.0) - pp).length() < rho && (s.pt(c.1) - pp).length() < rho
        };
        // ASSUMPTION H8: with strict_rho only edges with both endpoints within rho, unless
        // there is none.
        let strict = self.o.strict_rho && cand.iter().any(|c| within(self, c));
        let mut best: Option<(f64, (u32, u32), BEdge)> = None;
        for c in &cand {
            if strict && !within(self, c) {
                continue;
            }
            let d = self.edge_dist(pp, c.0, c.1);
            let kk = (c.0, c.1);
            if best.is_none_or(|(bd, bk, _)| d < bd || (d == bd && kk < bk)) {
                best = Some((d, kk, *c));
            }
        }
        self.buf = cand;
        best.map(|b| b.2)
    }

    /// Creates T_new = (P, y, x), then its neighbourhood triangles and the flips.
    fn create(&mut self, i: u32, root: u32, t_new: [u32; 3]) {
        let Some(id) = self.add(t_new, root) else {
            return;
        };
        self.stats.created += 1;
        let mut queue = VecDeque::new();
        queue.push_back((t_new[1], t_new[2]));
        if self.o.neighbourhood {
            self.neighbourhood(i, root, id, &mut queue);
        }
        if self.o.flips {
            self.flip_queue(queue);
        }
    }

    /// Splits W = (a, b, c) into (P, b, c), (a, P, c), (a, b, P) (orientation kept).
    fn split(&mut self, i: u32, root: u32, w_id: u32) {
        let [a, b, c] = self.mesh.tris[w_id as usize];
        let parts = [[i, b, c], [a, i, c], [a, b, i]];
        let deg = parts
            .iter()
            .any(|t| MILLIRAD.min_angle_at_most(self.pt(t[0]), self.pt(t[1]), self.pt(t[2])));
        if deg {
            self.stats.refused += 1;
            return;
        }
        self.mesh.replace(w_id, parts[0]);
        self.mesh.tris.reserve(2);
        for t in &parts[1..] {
            // Cannot fail: the new edges end at the new vertex P, the outer ones are W's.
            let _ = self.mesh.add(*t);
        }
        self.nc_tris[root as usize] += 2;
        self.flip_cap += 20;
        self.stats.splits += 1;
        if self.o.flips {
            self.flip_queue(VecDeque::from([(a, b), (b, c), (c, a)]));
        }
    }

    /// ASSUMPTION H11 guards of a candidate (u, v, w) whose new edge is a-b: non-fold
    /// against T_new, the edge cap, the edge not yet present, and no 2-D overlap (in the
    /// plane of n_new) with the triangles at the candidate's vertices.
    fn ear_ok(&self, cand: [u32; 3], a: u32, b: u32, n_new: DVec3) -> bool {
        // ASSUMPTION H11: new edge absent, edge cap, non-fold, no local 2-D overlap.
        if self.mesh.has_edge(a, b) || !self.mesh.can_add(cand) {
            return false;
        }
        let len = (self.pt(a) - self.pt(b)).length();
        if len > self.o.ear_max_edge || (self.o.strict_rho && len > self.o.rho) {
            return false;
        }
        let nc = cross(self.p, cand);
        if RIGHT.reached_by(n_new, nc) {
            return false;
        }
        let (pa, pb) = (self.pt(a), self.pt(b));
        for &v in &cand {
            for &t in &self.mesh.vt[v as usize] {
                let tri = self.mesh.tris[t as usize];
                for k in 0..3 {
                    let (r, s) = (tri[k], tri[(k + 1) % 3]);
                    if r == a || r == b || s == a || s == b {
                        continue;
                    }
                    if crosses(n_new, pa, pb, self.pt(r), self.pt(s)) {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// The boundary edge of this NC ending at `v` (u -> v) or starting at it (v -> z).
    fn boundary_neighbour(&mut self, v: u32, incoming: bool) -> Option<u32> {
        let mut out = std::mem::take(&mut self.buf);
        out.clear();
        self.mesh.boundary_at(v, &mut out);
        let r = out
            .iter()
            .filter(|&&(a, b, _)| if incoming { b == v } else { a == v })
            .map(|&(a, b, _)| if incoming { a } else { b })
            .min();
        self.buf = out;
        r
    }

    /// §3.3.3: ears at x and y beside T_new = (P, y, x), with fan continuation.
    fn neighbourhood(&mut self, i: u32, root: u32, id: u32, queue: &mut VecDeque<(u32, u32)>) {
        let t_new = self.mesh.tris[id as usize];
        let (y, x) = (t_new[1], t_new[2]);
        let n_new = cross(self.p, t_new);
        let pp = self.pt(i);
        // Side 0: ear at x, candidate (u, P, x) for boundary u -> x; new edge u - P.
        // Side 1: ear at y, candidate (P, z, y) for boundary y -> z; new edge P - z.
        let mut ends = [x, y];
        let mut open = [true, true];
        let ear = |s: &mut Self, side: usize, at: u32| -> Option<([u32; 3], u32)> {
            let o = s.boundary_neighbour(at, side == 0)?;
            if o == i {
                return None;
            }
            let cand = if side == 0 { [o, i, at] } else { [i, o, at] };
            Some((cand, o))
        };
        for _ in 0..16 {
            let mut cands: Vec<(f64, usize, [u32; 3], u32)> = Vec::with_capacity(2);
            for side in 0..2 {
                if !open[side] {
                    continue;
                }
                match ear(self, side, ends[side]) {
                    Some((cand, o)) if self.ear_ok(cand, o, i, n_new) => {
                        let at = self.pt(ends[side]);
                        let key = match self.o.conflict_rule {
                            // ASSUMPTION H12: smaller wedge angle at the shared vertex.
                            ConflictRule::Wedge => angle(self.pt(o) - at, pp - at),
                            // Literal: smaller paper-phi, the normals with the shared
                            // edge in the same direction (= pi - our angle).
                            ConflictRule::Phi => {
                                std::f64::consts::PI - angle(n_new, cross(self.p, cand))
                            }
                        };
                        cands.push((key, side, cand, o));
                    }
                    _ => open[side] = false,
                }
            }
            if cands.is_empty() {
                break;
            }
            cands.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut any = false;
            for (_, side, cand, o) in cands {
                // The second candidate is re-checked after the first was added.
                if !self.ear_ok(cand, o, i, n_new) {
                    open[side] = false;
                    continue;
                }
                if self.add(cand, root).is_some() {
                    self.stats.neighbourhood += 1;
                    queue.push_back((ends[side], o));
                    queue.push_back((ends[side], i));
                    ends[side] = o;
                    any = true;
                } else {
                    open[side] = false;
                }
            }
            if !any {
                break;
            }
        }
    }

    /// ASSUMPTION H13: Lawson-style queue of shortest-diagonal flips; a flip needs both
    /// flipped normals within pi/2 (the paper's phi > pi/2), a shorter diagonal, and a
    /// diagonal not yet present. Boundary edges are never flipped.
    fn flip_queue(&mut self, mut queue: VecDeque<(u32, u32)>) {
        // ASSUMPTION H13: at most 64 flips per insertion and 10 per triangle overall.
        let mut budget = 64usize;
        while let Some((a, b)) = queue.pop_front() {
            if budget == 0 || self.flip_cap == 0 {
                break;
            }
            let [t1, t2] = self.mesh.edge_tris(a, b);
            if t1 == NONE || t2 == NONE {
                continue;
            }
            // t1 = (a, b, c) traversing a -> b, t2 = (b, a, d).
            let (mut t1, mut t2) = (t1, t2);
            let mut r1 = rotate_to(self.mesh.tris[t1 as usize], a);
            if r1[1] != b {
                std::mem::swap(&mut t1, &mut t2);
                r1 = rotate_to(self.mesh.tris[t1 as usize], a);
            }
            let r2 = rotate_to(self.mesh.tris[t2 as usize], b);
            let (c, d) = (r1[2], r2[2]);
            if r1[1] != b || r2[1] != a || c == d || self.mesh.has_edge(c, d) {
                continue;
            }
            let share = (self.pt(a) - self.pt(b)).length();
            let diag = (self.pt(c) - self.pt(d)).length();
            if share <= diag {
                continue;
            }
            let (n1, n2) = ([a, d, c], [d, b, c]);
            let c1 = cross(self.p, n1);
            let c2 = cross(self.p, n2);
            if RIGHT.reached_by(c1, c2)
                || RIGHT.reached_by(c1, cross(self.p, r1))
                || MILLIRAD.min_angle_at_most(self.pt(a), self.pt(d), self.pt(c))
                || MILLIRAD.min_angle_at_most(self.pt(d), self.pt(b), self.pt(c))
            {
                continue;
            }
            self.mesh.replace_pair(t1, n1, t2, n2);
            self.stats.flips += 1;
            self.flip_cap -= 1;
            budget -= 1;
            for e in [(a, d), (d, b), (b, c), (c, a)] {
                queue.push_back(e);
            }
        }
    }
}
