//! Closing of small leftover front loops (IMPL-CHOICE I7, not in the paper).
//!
//! The paper leaves every front loop that survives the main loop as a hole and names an
//! external hole filler as the remedy (spec §1). On closed surfaces sampled densely, a
//! few loops of 3-8 vertices remain where the local fronts met folded or every
//! candidate failed a rule; they are not features of the surface. This pass closes loops
//! of at most `max_len` vertices whose edges are all shorter than `2 R`, by ear clipping
//! with the front operations themselves (LINK-next for each ear, FILL for the last
//! triangle), so orientation and manifoldness are kept: an ear is taken only when its
//! new diagonal is not already a mesh edge. Larger loops (true boundaries, real holes)
//! are left and reported.

use glam::DVec3;

use super::complete::min_angle_cos;
use super::mesher::{ACCEPTED, Mesher, tri_normal};

impl Mesher<'_> {
    /// Closes the small loops; returns the number of loops closed.
    pub fn close_small_holes(&mut self, max_len: usize) -> u64 {
        if max_len < 3 {
            return 0;
        }
        let lim2 = (2.0 * self.cfg.r) * (2.0 * self.cfg.r);
        let mut closed = 0;
        for l in self.loops() {
            if l.len() > max_len || l.len() < 3 {
                continue;
            }
            let k = l.len();
            let short = (0..k).all(|i| {
                let (u, v) = (l[i], l[(i + 1) % k]);
                (self.pts[u as usize] - self.pts[v as usize]).length_squared() <= lim2
            });
            if short && self.clip_loop(l) {
                closed += 1;
            }
        }
        closed
    }

    /// Ear-clips the loop with vertices `l` (in front order). Returns true when closed.
    fn clip_loop(&mut self, mut l: Vec<u32>) -> bool {
        // An isolated triangle (e.g. a lone seed) must not be doubled.
        if l.len() == 3 && l.iter().all(|&v| self.adj.degree(v) == 2) {
            return false;
        }
        let mut ears: Vec<(f64, usize)> = Vec::new();
        while l.len() > 3 {
            let k = l.len();
            // Best ear: largest smallest angle, diagonal not yet an edge, and (with
            // IMPL-CHOICE I14) no crossing of a mesh face.
            ears.clear();
            for i in 0..k {
                let (z, a, b) = (l[(i + k - 1) % k], l[i], l[(i + 1) % k]);
                if self.adj.has(z, b) {
                    continue;
                }
                let q = min_angle_cos(
                    self.pts[z as usize],
                    self.pts[a as usize],
                    self.pts[b as usize],
                );
                if q.is_finite() {
                    ears.push((q, i));
                }
            }
            ears.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            let Some(&(_, i)) = ears
                .iter()
                .find(|&&(_, i)| !self.crosses_mesh([l[(i + k - 1) % k], l[i], l[(i + 1) % k]]))
            else {
                return false;
            };
            let (z, a, b) = (l[(i + k - 1) % k], l[i], l[(i + 1) % k]);
            let g = self.fin[a as usize];
            let n = tri_normal(
                self.pts[z as usize],
                self.pts[b as usize],
                self.pts[a as usize],
            );
            self.link_next(g, b, n);
            l.remove(i);
        }
        let (a, b) = (l[0], l[1]);
        let e = self.fout[a as usize];
        debug_assert_eq!(self.e_b[e as usize], b);
        self.fill(e, l[2]);
        true
    }
}

impl Mesher<'_> {
    /// With IMPL-CHOICE I14 on: whether triangle `tri` (a hole's ear, a restart's seed)
    /// would intersect a mesh face sharing none of its vertices, among the faces on the
    /// meshed points within R of the triangle's corners' bounding sphere.
    pub(crate) fn crosses_mesh(&mut self, tri: [u32; 3]) -> bool {
        if !self.cfg.self_check {
            return false;
        }
        let p = tri.map(|i| self.pts[i as usize]);
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let rad = p.iter().map(|&x| x.distance(c)).fold(0.0, f64::max) + self.cfg.r;
        let mut near = std::mem::take(&mut self.done_near);
        near.clear();
        let (pts, state) = (self.pts, &self.state);
        self.grid.for_cells(c, rad, |range| {
            for i in range {
                if state[i] == ACCEPTED && pts[i].distance_squared(c) <= rad * rad {
                    near.push(i as u32);
                }
            }
        });
        self.done_near = near;
        self.hits_mesh(tri)
    }
}

impl Mesher<'_> {
    /// Zips pairs of parallel front loops left along a slab cut by the multi-threaded
    /// stitch (IMPL-CHOICE I9, not in the paper; `stitch_zip`). Two loops qualify when
    /// each vertex of either lies within `2 R` of the other loop, and these offsets lie
    /// mostly in the tangent plane (|offset . fan normal| <= offset / 2: side by side
    /// on the surface, not two stacked sheets). The pair is bridged by the two triangles
    /// of the quad between the closest pair of facing, antiparallel edges (a GLUE, which
    /// merges the loops into one thin ring-shaped loop), and that loop is then closed by
    /// the ear clipping of I7 (each ear a LINK, the last a FILL; a diagonal that is a
    /// mesh edge already is never added). Returns the number of pairs zipped.
    pub fn zip_parallel_loops(&mut self) -> u64 {
        let gap = 2.0 * self.cfg.r;
        let mut zipped = 0;
        loop {
            let loops = self.loops();
            // Bounding boxes: a qualifying pair has each box inside the other's grown by
            // the gap (a necessary condition that prunes the pairs in O(1) each).
            let boxes: Vec<(DVec3, DVec3)> = loops
                .iter()
                .map(|l| {
                    l.iter().fold(
                        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                        |(lo, hi), &v| (lo.min(self.pts[v as usize]), hi.max(self.pts[v as usize])),
                    )
                })
                .collect();
            let inside = |a: (DVec3, DVec3), b: (DVec3, DVec3)| {
                a.0.cmpge(b.0 - gap).all() && a.1.cmple(b.1 + gap).all()
            };
            let mut done = false;
            'pairs: for i in 0..loops.len() {
                for j in i + 1..loops.len() {
                    let (l1, l2) = (&loops[i], &loops[j]);
                    if l1.len() < 3 || l2.len() < 3 || l1.len() > 4096 || l2.len() > 4096 {
                        continue;
                    }
                    if !inside(boxes[i], boxes[j]) || !inside(boxes[j], boxes[i]) {
                        continue;
                    }
                    if !self.parallel(l1, l2, gap) || !self.parallel(l2, l1, gap) {
                        continue;
                    }
                    if let Some(m) = self.bridge(l1, l2) {
                        // The merged loop: ear-clip it whole (no length limit).
                        let merged = self.loop_from(m);
                        if self.clip_loop(merged) {
                            zipped += 1;
                        }
                        done = true;
                        break 'pairs;
                    }
                }
            }
            if !done {
                return zipped;
            }
        }
    }

    /// True when every vertex of `l1` has a vertex of `l2` within `gap`, the nearest one
    /// offset mostly along the surface (see [`Mesher::zip_parallel_loops`]).
    fn parallel(&self, l1: &[u32], l2: &[u32], gap: f64) -> bool {
        let g2 = gap * gap;
        l1.iter().all(|&p| {
            let pp = self.pts[p as usize];
            let mut best = (f64::INFINITY, DVec3::ZERO);
            for &q in l2 {
                let d = self.pts[q as usize] - pp;
                let l = d.length_squared();
                if l < best.0 {
                    best = (l, d);
                }
            }
            let n = self.vn[p as usize].normalize_or_zero();
            best.0 <= g2 && n != DVec3::ZERO && {
                let h = best.1.dot(n);
                4.0 * h * h <= best.0
            }
        })
    }

    /// Bridges loops `l1`, `l2` by the quad between the closest (by midpoints) pair of
    /// antiparallel front edges `a -> b` of `l1` and `q -> p` of `l2`: triangles
    /// `(a, p, b)` and `(p, q, b)` as one GLUE. Returns a vertex of the merged loop, or
    /// `None` when no pair passes (shared edges, degenerate or folded triangles).
    fn bridge(&mut self, l1: &[u32], l2: &[u32]) -> Option<u32> {
        let mut best: Option<(f64, u32, u32)> = None;
        for &a in l1 {
            let e = self.fout[a as usize];
            let b = self.e_b[e as usize];
            let (pa, pb) = (self.pts[a as usize], self.pts[b as usize]);
            for &q in l2 {
                let f = self.fout[q as usize];
                let p = self.e_b[f as usize];
                let (pq, pp) = (self.pts[q as usize], self.pts[p as usize]);
                if (pb - pa).dot(pp - pq) >= 0.0 {
                    continue;
                }
                let d = ((pa + pb) - (pq + pp)).length_squared();
                if best.is_none_or(|(bd, _, _)| d < bd)
                    && !self.adj.has(a, p)
                    && !self.adj.has(p, b)
                    && !self.adj.has(q, b)
                {
                    let n1 = super::mesher::tri_normal(pa, pp, pb);
                    let n2 = super::mesher::tri_normal(pp, pq, pb);
                    // Both halves of the quad face the same way as their old sides.
                    if n1.dot(self.e_nrm[e as usize]) > 0.0
                        && n2.dot(self.e_nrm[f as usize]) > 0.0
                        && n1.dot(n2) > 0.0
                    {
                        best = Some((d, e, p));
                    }
                }
            }
        }
        let (_, e, p) = best?;
        let a = self.e_a[e as usize];
        let (b, q) = (
            self.e_b[e as usize],
            self.e_a[self.fin[p as usize] as usize],
        );
        let n1 = super::mesher::tri_normal(
            self.pts[a as usize],
            self.pts[p as usize],
            self.pts[b as usize],
        );
        let n2 = super::mesher::tri_normal(
            self.pts[p as usize],
            self.pts[q as usize],
            self.pts[b as usize],
        );
        self.glue(e, p, n1, n2);
        Some(a)
    }

    /// The vertices of the live front loop through vertex `v`, in front order.
    fn loop_from(&self, v: u32) -> Vec<u32> {
        let mut l = vec![v];
        let mut e = self.fout[v as usize];
        while self.e_b[e as usize] != v && l.len() <= self.e_a.len() {
            l.push(self.e_b[e as usize]);
            e = self.e_next[e as usize];
        }
        l
    }
}
