//! TRIANGULATE(e) (spec §4.4) and the main loop M1-M7 (§4.3).

use glam::DVec3;
use reconbench_geom::method::{MethodError, RunCtx};

use super::cross::{
    XNear, crosses, crosses_projected, front_inside_projected, inside_2d, plane_basis, project_near,
};
use super::density::knn;
use reconbench_geom::spatial::tri_tri_intersect;

use super::grid::NONE;
use super::mesher::{ACCEPTED, Cand, FREE, Mesher, REFUSED};

/// The operation chosen for a popped edge.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Op {
    Join(u32, DVec3),
    Fill(u32),
    LinkNext(u32, DVec3),
    LinkPrev(u32, DVec3),
    Glue(u32, DVec3, DVec3),
    GlueMirror(u32, DVec3, DVec3),
}

/// Per-edge constants of Steps 2-3, computed once per popped edge.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeCtx {
    pub a: u32,
    pub b: u32,
    pub pa: DVec3,
    pub pb: DVec3,
    /// Edge midpoint.
    pub o: DVec3,
    /// Unit normal of the triangle across the edge.
    pub n_old: DVec3,
    /// Unit edge direction.
    pub ev: DVec3,
    /// Unit fan normal at the edge (IMPL-CHOICE I5 reference plane).
    pub nv: DVec3,
}

/// Steps between two `ctx.checkpoint()` polls.
const CHECK_EVERY: u64 = 4096;

impl Mesher<'_> {
    /// Rule 1 (+ A12) and the degeneracy guard for triangle `(x, y, z)`; `all` also
    /// checks the angle at `y` (the apex for `(a, t, b)`). Returns the unnormalised
    /// cross product `(y - x) x (z - x)` when the triangle passes.
    #[inline]
    fn shape_ok(&self, x: DVec3, y: DVec3, z: DVec3, apex: bool) -> Option<DVec3> {
        let c = self.cfg.cos_alpha;
        // angle > alpha_max  <=>  cos < cos(alpha_max); strict as the paper (§2).
        let c2 = c * c;
        let ang_bad = |u: DVec3, v: DVec3| {
            let d = u.dot(v);
            // cos(angle) < c  <=>  d < c |u||v|, decided on squares (no square root):
            // for c < 0 it needs d < 0 and d^2 > c^2 |u|^2 |v|^2; for c >= 0 it holds
            // when d < 0 or d^2 < c^2 |u|^2 |v|^2.
            let m2 = c2 * u.length_squared() * v.length_squared();
            if c < 0.0 {
                d < 0.0 && d * d > m2
            } else {
                d < 0.0 || d * d < m2
            }
        };
        if ang_bad(y - x, z - x) || ang_bad(x - z, y - z) {
            return None;
        }
        // ASSUMPTION A12: Rule 1 also bounds the apex angle at t.
        if apex && ang_bad(x - y, z - y) {
            return None;
        }
        let cr = (y - x).cross(z - x);
        // ASSUMPTION A13 (degenerate guard): area < 1e-12 R^2 is rejected.
        let r = self.cfg.r;
        if cr.length() * 0.5 < 1e-12 * r * r {
            return None;
        }
        Some(cr)
    }

    /// Step 1: gathers the candidates, Free points and front points (but `a`, `b`)
    /// within R of `o`, into `pend` keyed by their squared distance to `o` (the caller
    /// rekeys them for the segment distance), the Free ones also into
    /// `free_near` (only with `reject_free_inside`, its one reader), and the front edges
    /// near `o` with their cull data for the crossing test into `xs`.
    // The steps of `triangulate` (gather, evaluate, validate, sector test) stay out of
    // line: inlined into one body their loops spill more (3 % more instructions).
    #[inline(never)]
    fn gather(&mut self, e: u32, a: u32, b: u32, o: DVec3) {
        let r = self.cfg.r;
        let r2 = r * r;
        // The output lists are moved into locals for the scans: the loops then keep
        // their lengths in registers (the scans were dominated by push bookkeeping).
        let mut free_near = std::mem::take(&mut self.free_near);
        let mut mesh_near = std::mem::take(&mut self.mesh_near);
        mesh_near.clear();
        let mut pend = std::mem::take(&mut self.pend);
        let mut xs = std::mem::take(&mut self.xs);
        let mut chunks = std::mem::take(&mut self.chunks);
        free_near.clear();
        pend.clear();
        xs.clear();
        let pts = self.pts;
        let state = &self.state;
        // `free_near` serves only the optional Free-inside test.
        let keep_free = self.cfg.reject_free_inside;
        let keep_mesh = self.cfg.interior_inside;
        let keep_done = self.cfg.self_check;
        let mut done_near = std::mem::take(&mut self.done_near);
        done_near.clear();
        let fin = &self.fin;
        // The meshed points are needed by I13 / I14 only.
        let keep_acc = keep_done || keep_mesh;
        self.grid.for_cells(o, r, |range| {
            let start = range.start;
            // One state read and at most one distance per point; the slices drop the
            // bounds checks.
            let (st, ps) = (&state[range.clone()], &pts[range]);
            if keep_acc {
                // Free and meshed points both need the distance: the ball test comes
                // first, so that the points outside it (most of the cells) skip the
                // state branch.
                for (j, (&s, &p)) in st.iter().zip(ps).enumerate() {
                    let d2 = (p - o).length_squared();
                    if d2 > r2 {
                        continue;
                    }
                    let i = start + j;
                    if s == FREE {
                        if keep_free {
                            free_near.push(i as u32);
                        }
                        pend.push((d2, i as u32));
                    } else if s == ACCEPTED {
                        if keep_done {
                            done_near.push(i as u32);
                        }
                        if keep_mesh && fin[i] == NONE {
                            mesh_near.push(i as u32);
                        }
                    }
                }
                return;
            }
            for (j, (&s, &p)) in st.iter().zip(ps).enumerate() {
                let i = start + j;
                if s == FREE {
                    let d2 = (p - o).length_squared();
                    if d2 <= r2 {
                        if keep_free {
                            free_near.push(i as u32);
                        }
                        pend.push((d2, i as u32));
                    }
                } else if keep_acc && s == ACCEPTED && (p - o).length_squared() <= r2 {
                    if keep_done {
                        done_near.push(i as u32);
                    }
                    if keep_mesh && fin[i] == NONE {
                        mesh_near.push(i as u32);
                    }
                }
            }
        });
        let xr = self.cfg.cross_factor * r;
        let xr2 = xr * xr;
        let (e_a, e_b, fin, fout) = (&self.e_a, &self.e_b, &self.fin, &self.fout);
        let e_len = &self.e_len;
        self.fidx.chunks_near(o, xr, &mut chunks);
        for &c in &chunks {
            let (ids, pos) = self.fidx.chunk(c);
            for (&v, &pv) in ids.iter().zip(pos) {
                let d2 = (pv - o).length_squared();
                if d2 > xr2 {
                    continue;
                }
                if d2 <= r2 && v != a && v != b {
                    pend.push((d2, v));
                }
                let out = fout[v as usize];
                if out != NONE && out != e {
                    xs.push(XNear {
                        w: pv - o,
                        ww: d2,
                        len: e_len[out as usize],
                        x: v,
                        y: e_b[out as usize],
                    });
                }
                let inn = fin[v as usize];
                if inn != NONE && inn != e {
                    let u = e_a[inn as usize];
                    let wu = pts[u as usize] - o;
                    let du2 = wu.length_squared();
                    if du2 > xr2 {
                        xs.push(XNear {
                            w: wu,
                            ww: du2,
                            len: e_len[inn as usize],
                            x: u,
                            y: v,
                        });
                    }
                }
            }
        }
        self.free_near = free_near;
        self.mesh_near = mesh_near;
        self.done_near = done_near;
        self.pend = pend;
        self.xs = xs;
        self.chunks = chunks;
    }

    /// During revisit passes (IMPL-CHOICE I2/I3) the front neighbours `z` (`z -> a`)
    /// and `c` (`b -> c`) are candidates even beyond R (up to the crossing radius), so that large small-count holes
    /// (whose third vertex lies outside the ball) can still be linked / filled.
    fn add_front_neighbours(&mut self, x: &EdgeCtx) {
        let (a, b) = (x.a, x.b);
        let z = self.e_a[self.fin[a as usize] as usize];
        let c = self.e_b[self.fout[b as usize] as usize];
        let o = (self.pts[a as usize] + self.pts[b as usize]) * 0.5;
        let lim = self.cfg.cross_factor * self.cfg.r;
        for v in [z, c] {
            // `pend` holds the front candidates within R (and Free points, never `v`).
            if v != a
                && v != b
                && (self.pts[v as usize] - o).length() <= lim
                && !self.pend.iter().any(|&(_, t)| t == v)
            {
                let key = if self.cfg.seg_dist {
                    -self.score_bound(x, v)
                } else {
                    (self.pts[v as usize] - x.o).length_squared()
                };
                self.pend.push((key, v));
            }
        }
    }

    /// Steps 2-3 for candidate `t`: the rules and the score. Returns the score and the
    /// unit normal of `(a, t, b)`, or `None` when a rule removes `t`.
    #[inline(never)]
    fn evaluate(&mut self, x: &EdgeCtx, t: u32) -> Option<(f64, DVec3)> {
        let EdgeCtx {
            a,
            b,
            pa,
            pb,
            o,
            n_old,
            ev,
            nv,
        } = *x;
        let pt = self.pts[t as usize];
        // ASSUMPTION A13: an existing edge {a,t} / {t,b} is allowed only when the
        // operation consumes it as the front edge t->a / b->t.
        let mut fill = false;
        if self.state[t as usize] == FREE {
            // IMPL-CHOICE I5: a Free point may not rise more than the elevation bound
            // above the mesh's tangent plane at o (normal: fan normals of a and b), nor
            // more than the height cap, unless it lies on the plane of its own
            // neighbourhood (IMPL-CHOICE I8: a point just across a crease).
            if self.cfg.sin_elev < 1.0 || self.cfg.height_r < 1.0 {
                let v = pt - o;
                let h = v.dot(nv).abs();
                // Squared compare of h > sin_elev |v| first (no square root).
                let se = self.cfg.sin_elev;
                if h * h > se * se * v.length_squared() {
                    return None;
                }
                if h > self.cfg.height_r * self.cfg.r {
                    if !self.supported(t) {
                        return None;
                    }
                    // IMPL-CHOICE I11 (not in the paper): the supporting plane must be
                    // that of a face across a crease, i.e. meet the tangent plane at o
                    // no farther from t than o is. Going down the support plane from t,
                    // the height h falls at the rate sin(phi) (phi: angle between the
                    // plane and the tangent plane), so the meeting line lies h / sin(phi)
                    // from t. The other sheet of a thin part (parallel, sin(phi) ~ 0)
                    // never meets it: I8 alone lets that sheet in and bridges the two.
                    if self.cfg.support_crease {
                        let ns = self.sup_nrm.get(&t).copied().unwrap_or(nv);
                        let sin_phi = ns.cross(nv).length();
                        if h > sin_phi * v.length() {
                            return None;
                        }
                    }
                }
            }
        } else {
            let ta = self.e_a[self.fin[a as usize] as usize] == t;
            let bt = self.e_b[self.fout[b as usize] as usize] == t;
            if (!ta && self.adj.has(a, t)) || (!bt && self.adj.has(b, t)) {
                return None;
            }
            fill = (ta && bt) || (self.revisiting && (ta || bt));
            // IMPL-CHOICE I10 (not in the paper): a front point whose fan faces away
            // from the fan at the edge lies on the other sheet of a thin part, meshed
            // with the opposite orientation; linking or gluing to it would bridge them.
            if !(ta && bt) && self.cfg.cos_front > -1.0 {
                let nt = self.vn[t as usize];
                if nt.dot(nv) < self.cfg.cos_front * nt.length() {
                    return None;
                }
            }
        }
        // IMPL-CHOICE I3: a FILL has exactly one possible triangle (the 3-edge hole);
        // with `fill_any_angle` Rule 1 is waived for it (only the degeneracy guard
        // stays), otherwise skinny 3-edge holes could never close. During revisit
        // passes (I2) the same holds for LINK (ear clipping): a hole whose angles all
        // exceed alpha_max (a regular 7-gon) could not close otherwise.
        let cr = if fill && self.cfg.fill_any_angle {
            let cr = (pt - pa).cross(pb - pa);
            if cr.length() * 0.5 < 1e-12 * self.cfg.r * self.cfg.r {
                return None;
            }
            cr
        } else {
            self.shape_ok(pa, pt, pb, self.cfg.apex_rule)?
        };
        let n_new = cr.normalize();
        let cos_b = n_new.dot(n_old);
        // Rule 2: remove t when beta > beta_max.
        if cos_b < self.cfg.cos_beta {
            return None;
        }
        let r = self.cfg.r;
        let v = pt - o;
        let vl = v.length();
        let v_perp = v - v.dot(ev) * ev;
        let cos_g = if vl > 0.0 { v_perp.length() / vl } else { 0.0 };
        // ASSUMPTION A11: d(t) is the distance to the midpoint o (segment as option).
        let d = if self.cfg.seg_dist {
            let s = (pt - pa).dot(pb - pa) / (pb - pa).length_squared();
            (pt - (pa + (pb - pa) * s.clamp(0.0, 1.0))).length()
        } else {
            vl
        };
        let w = self.cfg.w;
        let score = w[0] * cos_b + w[1] * cos_g + w[2] * ((r - d) / r).max(0.0);
        Some((score, n_new))
    }

    /// IMPL-CHOICE I8 (not in the paper): true when point `t` has a surface behind it:
    /// all of its `support_k` nearest other points lie within `support_radius` R, and a
    /// plane through `t` (and two of them) passes within `support_tol` of at least
    /// `support_share` of them. A point just across a crease lies on the plane of the face it belongs to,
    /// which holds half or more of its neighbours; an outlier above a surface sees its
    /// neighbours on a plane that misses it by its height, and any plane through it cuts
    /// that surface in a thin strip of few points; an outlier in the volume has fewer
    /// than `support_k` points within 2R. A per-point property of the input (cached), so
    /// the order of growth does not change it.
    fn supported(&mut self, t: u32) -> bool {
        match self.support[t as usize] {
            1 => return true,
            2 => return false,
            _ => {}
        }
        let ok = self.support_test(t);
        self.support[t as usize] = if ok { 1 } else { 2 };
        ok
    }

    fn support_test(&mut self, t: u32) -> bool {
        let k = self.cfg.support_k;
        if k < 3 {
            return false;
        }
        let pt = self.pts[t as usize];
        let state = &self.state;
        let mut buf = std::mem::take(&mut self.sup_buf);
        knn(
            self.grid,
            self.pts,
            pt,
            k,
            self.cfg.support_radius * self.cfg.r,
            |i| i != t as usize && state[i] != REFUSED,
            &mut buf,
        );
        // All k neighbours must lie within the radius: an outlier in the volume has only
        // a few other outliers that close (and any 3 points are coplanar).
        let mut dirs = std::mem::take(&mut self.sup_dirs);
        dirs.clear();
        dirs.extend(buf.iter().map(|&(_, q)| self.pts[q as usize] - pt));
        let plane = if buf.len() >= k {
            self.plane_through(&dirs)
        } else {
            None
        };
        if let Some(n) = plane {
            self.sup_nrm.insert(t, n);
        }
        let ok = plane.is_some();
        self.sup_dirs = dirs;
        self.sup_buf = buf;
        ok
    }

    /// True when some plane through the point and two of its neighbours (`d`: the
    /// neighbours minus the point) passes within the support tolerance of at least
    /// `support_share` of all of them (IMPL-CHOICE I8). Pairs nearly collinear with the
    /// point (sine of their angle below 0.2) are skipped. Returns the unit normal of the
    /// first such plane.
    fn plane_through(&self, d: &[DVec3]) -> Option<DVec3> {
        let tol = self.cfg.support_tol;
        let need = (self.cfg.support_share * d.len() as f64).ceil() as usize;
        for i in 0..d.len() {
            for j in i + 1..d.len() {
                let n = d[i].cross(d[j]);
                let l2 = n.length_squared();
                if l2 < 0.04 * d[i].length_squared() * d[j].length_squared() {
                    continue;
                }
                let tl = tol * l2.sqrt();
                let m = d.iter().filter(|q| q.dot(n).abs() <= tl).count();
                if m >= need {
                    return Some(n / l2.sqrt());
                }
            }
        }
        None
    }

    /// Second triangle `(x, y, z)` of a glue repair: Rule 1 (all angles), degeneracy,
    /// Rule 2 against `n_ref`, the new edge `{u, w}` must not exist, and the 2-D
    /// crossing test of that edge. Returns its unit normal.
    fn repair_ok(&self, tri: [u32; 3], n_ref: DVec3, new_edge: (u32, u32)) -> Option<DVec3> {
        let p = tri.map(|i| self.pts[i as usize]);
        let cr = self.shape_ok(p[0], p[1], p[2], true)?;
        let n2 = cr.normalize();
        if n2.dot(n_ref) < self.cfg.cos_beta || self.adj.has(new_edge.0, new_edge.1) {
            return None;
        }
        let o = (self.pts[new_edge.0 as usize] + self.pts[new_edge.1 as usize]) * 0.5;
        let np = plane_normal(n_ref, n2);
        if crosses(self.pts, &self.xs, np, o, self.cfg.r, &[new_edge]) {
            return None;
        }
        Some(n2)
    }

    /// TRIANGULATE(e): the reference point and its operation, or `None` (boundary).
    pub fn triangulate(&mut self, e: u32) -> Option<Op> {
        let (a, b) = (self.e_a[e as usize], self.e_b[e as usize]);
        let (pa, pb) = (self.pts[a as usize], self.pts[b as usize]);
        let o = (pa + pb) * 0.5;
        let n_old = self.e_nrm[e as usize];
        let nv = self.vn[a as usize] + self.vn[b as usize];
        let x = EdgeCtx {
            a,
            b,
            pa,
            pb,
            o,
            n_old,
            ev: (pb - pa).normalize(),
            nv: if nv.length_squared() > 1e-24 {
                nv.normalize()
            } else {
                n_old
            },
        };
        self.gather(e, a, b, o);
        if self.cfg.seg_dist {
            let mut pend = std::mem::take(&mut self.pend);
            for c in pend.iter_mut() {
                c.0 = -self.score_bound(&x, c.1);
            }
            self.pend = pend;
        }
        if self.revisiting {
            self.add_front_neighbours(&x);
        }
        // Steps 2-4, lazily. Every candidate's score is bounded above by
        // U(t) = w1 + w2 + w3 (R - d(t))/R (cos beta, cos gamma <= 1), known from its
        // distance alone. Candidates are evaluated in decreasing U; the best evaluated
        // one is validated as soon as its exact score is strictly above the U of every
        // unevaluated candidate. The validation order is therefore exactly that of the
        // full evaluation (decreasing score, ties by lower index), but most candidates
        // of an edge are never evaluated, because the first validated one usually wins.
        // `pend` holds keys, smallest first in U order: the squared distance to `o`
        // (U falls with it; U is computed only for the candidate taken), or -U for the
        // segment distance.
        let (w, r, seg) = (self.cfg.w, self.cfg.r, self.cfg.seg_dist);
        let mut pend = std::mem::take(&mut self.pend);
        self.cand.clear();
        let mut passed = 0usize;
        let mut result = None;
        let mut best_score = f64::NEG_INFINITY;
        loop {
            // Evaluate (largest bound first; a linear scan, as only a few are taken)
            // until the best evaluated score beats every pending bound.
            while !pend.is_empty() {
                // The first smallest key (the running minimum stays in a register).
                let mut m = 0;
                let mut mk = pend[0].0;
                for (k, &(key, _)) in pend.iter().enumerate().skip(1) {
                    if key < mk {
                        m = k;
                        mk = key;
                    }
                }
                let u = if seg {
                    -pend[m].0
                } else {
                    bound(w, r, pend[m].0.sqrt())
                };
                if best_score > u {
                    break;
                }
                let t = pend.swap_remove(m).1;
                if let Some((score, n_new)) = self.evaluate(&x, t) {
                    passed += 1;
                    best_score = best_score.max(score);
                    self.cand.push(Cand { t, score, n_new });
                }
            }
            let Some(best) = self.best_cand() else {
                break;
            };
            let c = self.cand.swap_remove(best);
            if let Some(op) = self.validate(e, a, b, o, n_old, c) {
                result = Some(op);
                break;
            }
            best_score = self
                .best_cand()
                .map_or(f64::NEG_INFINITY, |k| self.cand[k].score);
        }
        if passed == 0 {
            self.stats.fail_rules += 1;
        }
        self.pend = pend;
        result
    }

    /// Index in `cand` of the best candidate: highest score, ties by lower point index.
    #[inline]
    fn best_cand(&self) -> Option<usize> {
        if self.cand.is_empty() {
            return None;
        }
        let mut best = 0;
        for k in 1..self.cand.len() {
            let (c, bc) = (&self.cand[k], &self.cand[best]);
            if c.score > bc.score || (c.score == bc.score && c.t < bc.t) {
                best = k;
            }
        }
        Some(best)
    }

    /// Upper bound of the score C(t) of Eq. 8 from the distance term alone (cos beta and
    /// cos gamma are at most 1), with a relative slack against rounding.
    #[inline]
    fn score_bound(&self, x: &EdgeCtx, t: u32) -> f64 {
        let pt = self.pts[t as usize];
        let r = self.cfg.r;
        let d = if self.cfg.seg_dist {
            let (pa, pb) = (x.pa, x.pb);
            let s = (pt - pa).dot(pb - pa) / (pb - pa).length_squared();
            (pt - (pa + (pb - pa) * s.clamp(0.0, 1.0))).length()
        } else {
            (pt - x.o).length()
        };
        bound(self.cfg.w, r, d)
    }

    /// Crossing test and classification of candidate `c` (§4.4 Step 4, §4.5).
    #[inline(never)]
    fn validate(&mut self, e: u32, a: u32, b: u32, o: DVec3, n_old: DVec3, c: Cand) -> Option<Op> {
        let t = c.t;
        // ASSUMPTION A14: projection plane through o, normal normalize(n_old + n_new).
        let np = plane_normal(n_old, c.n_new);
        if self.cfg.sector_check && !self.in_sectors(a, b, t, np) {
            self.stats.sector_rejects += 1;
            return None;
        }
        // The nearby front edges that can reach the triangle are projected once for both
        // tests; the triangle lies within `rt` of `o` (`|a - o| = |b - o|`).
        let (u, v) = plane_basis(np);
        let rt = (self.pts[t as usize] - o)
            .length_squared()
            .max((self.pts[a as usize] - o).length_squared())
            .sqrt();
        let k = project_near(
            self.pts,
            &self.xs,
            rt,
            u,
            v,
            np,
            o,
            self.cfg.r,
            &mut self.xp,
        );
        let pr = |i: u32| {
            let q = self.pts[i as usize] - o;
            [q.dot(u), q.dot(v)]
        };
        let (qa, qt, qb) = (pr(a), pr(t), pr(b));
        let xp = &self.xp[..k];
        if crosses_projected(xp, [(a, qa, t, qt), (t, qt, b, qb)]) {
            self.stats.cross_rejects += 1;
            return None;
        }
        // IMPL-CHOICE I6: no front vertex may lie inside the new triangle (a fold).
        if self.cfg.front_inside_check && front_inside_projected(xp, [a, t, b], [qa, qt, qb]) {
            self.stats.cross_rejects += 1;
            return None;
        }
        // A FILL closes a 3-edge hole, its only possible triangle: a Free point inside
        // does not block it (it could never be meshed either way).
        let is_fill = self.state[t as usize] != FREE
            && self.e_b[self.fout[b as usize] as usize] == t
            && self.e_a[self.fin[a as usize] as usize] == t;
        // Spec §4.4 optional strictness flag; DEVIATION: on by default (issue 20).
        if self.cfg.reject_free_inside
            && !is_fill
            && self.covers(&self.free_near, [a, t, b], o, np, rt, c.n_new)
        {
            return None;
        }
        // DEVIATION I13 (issue 20, `interior_inside_check`): no triangle on top of the
        // mesh already made; the crossing test sees front edges only.
        if self.cfg.interior_inside
            && !is_fill
            && self.covers(&self.mesh_near, [a, t, b], o, np, rt, c.n_new)
        {
            self.stats.interior_rejects += 1;
            return None;
        }
        // IMPL-CHOICE I14 (issue 20, `self_intersection_check`): no triangle through a
        // mesh face it shares no vertex with; the 2-D tests above see one plane only.
        // A FILL is exempt: a 3-edge hole has one possible triangle.
        if self.cfg.self_check && !is_fill && self.hits_mesh([a, t, b]) {
            self.stats.self_rejects += 1;
            return None;
        }
        if self.state[t as usize] == FREE {
            return Some(Op::Join(t, c.n_new));
        }
        // ASSUMPTION A15: "connected with" = joined by a live front edge.
        let bt = self.e_b[self.fout[b as usize] as usize] == t;
        let ta = self.e_a[self.fin[a as usize] as usize] == t;
        match (bt, ta) {
            (true, true) => Some(Op::Fill(t)),
            (true, false) => Some(Op::LinkNext(t, c.n_new)),
            (false, true) => {
                if self.cfg.link_prev {
                    Some(Op::LinkPrev(t, c.n_new))
                } else {
                    None
                }
            }
            (false, false) => {
                // GLUE; ASSUMPTION A17: validate the repair triangle (p, q, b), else the
                // mirror (a, y, p), else reject p.
                let g = self.fin[t as usize];
                let q = self.e_a[g as usize];
                if let Some(n2) = self.repair_ok([t, q, b], self.e_nrm[g as usize], (q, b))
                    && !(self.cfg.self_check && self.hits_mesh([t, q, b]))
                {
                    // IMPL-CHOICE I4 for the repair: q->b leaves q inside q's free sector
                    // and b inside b's (b's edges being p->b, b->c after the first
                    // triangle).
                    let w = self.e_a[self.fin[q as usize] as usize];
                    let cc = self.e_b[self.fout[b as usize] as usize];
                    let np = plane_normal(self.e_nrm[g as usize], n2);
                    if !self.cfg.sector_check
                        || (self.sector_has(np, q, w, t, b) && self.sector_has(np, b, t, cc, q))
                    {
                        return Some(Op::Glue(t, c.n_new, n2));
                    }
                }
                if self.cfg.glue_mirror {
                    let h = self.fout[t as usize];
                    let y = self.e_b[h as usize];
                    if let Some(n2) = self.repair_ok([a, y, t], self.e_nrm[h as usize], (a, y))
                        && !(self.cfg.self_check && self.hits_mesh([a, y, t]))
                    {
                        let z = self.e_a[self.fin[a as usize] as usize];
                        let sy = self.e_b[self.fout[y as usize] as usize];
                        let np = plane_normal(self.e_nrm[h as usize], n2);
                        if !self.cfg.sector_check
                            || (self.sector_has(np, a, z, t, y) && self.sector_has(np, y, t, sy, a))
                        {
                            return Some(Op::GlueMirror(t, c.n_new, n2));
                        }
                    }
                }
                let _ = e;
                self.stats.glue_rejects += 1;
                None
            }
        }
    }

    /// True when one of the points `near` (but the triangle's own) lies inside the 2-D
    /// projection of `tri = (a, t, b)` on the plane through `o` with normal `np`, within
    /// `rt` of `o` and near the triangle's plane (normal `n_new`): within max(free_inside_h,
    /// free_inside_rel x longest edge) (IMPL-CHOICE I12). Points well off the plane (the
    /// other sheet of a thin part, outliers) do not count.
    fn covers(
        &self,
        near: &[u32],
        tri: [u32; 3],
        o: DVec3,
        np: DVec3,
        rt: f64,
        n_new: DVec3,
    ) -> bool {
        let (u, v) = plane_basis(np);
        let q2 = tri.map(|i| {
            let q = self.pts[i as usize] - o;
            [q.dot(u), q.dot(v)]
        });
        let [pa, pt, pb] = tri.map(|i| self.pts[i as usize]);
        let lmax2 = (pt - pa)
            .length_squared()
            .max((pb - pt).length_squared())
            .max((pb - pa).length_squared());
        let hmax = self
            .cfg
            .free_inside_h
            .max(self.cfg.free_inside_rel * lmax2.sqrt());
        let rt2 = rt * rt;
        near.iter().any(|&f| {
            let q = self.pts[f as usize] - o;
            !tri.contains(&f)
                && q.length_squared() < rt2
                && inside_2d(q2, [q.dot(u), q.dot(v)])
                && (self.pts[f as usize] - pa).dot(n_new).abs() <= hmax
        })
    }

    /// True when triangle `tri` intersects a mesh triangle that shares none of its
    /// vertices, among the triangles on the meshed points near the popped edge
    /// (`done_near`, within R of its midpoint) that can reach `tri`: a point's triangles
    /// lie within its longest incident edge of it (IMPL-CHOICE I14). Exact predicates,
    /// as the self-intersection metric. A triangle none of whose corners is within R of
    /// the edge's midpoint is not seen (it would need edges longer than about R).
    pub(crate) fn hits_mesh(&mut self, tri: [u32; 3]) -> bool {
        self.seen_stamp = self.seen_stamp.wrapping_add(1);
        if self.seen_stamp == 0 {
            self.faces.iter_mut().for_each(|f| f.seen = 0);
            self.seen_stamp = 1;
        }
        let stamp = self.seen_stamp;
        let pts = self.pts;
        let p = tri.map(|i| pts[i as usize]);
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let rt = p.iter().map(|&x| x.distance(c)).fold(0.0, f64::max);
        let sep = Separation::new(p, c, rt);
        let [t0, t1, t2] = tri;
        let (heads, v_reach) = (&self.vf_head, &self.v_reach);
        let faces = &mut self.faces;
        for &v in &self.done_near {
            // Every face on a corner of `tri` shares that corner and is skipped below:
            // its list need not be walked (exact, the walk would only mark them seen).
            if v == t0 || v == t1 || v == t2 {
                continue;
            }
            let reach = rt + v_reach[v as usize];
            if pts[v as usize].distance_squared(c) > reach * reach {
                continue;
            }
            let mut k = heads[v as usize];
            while k != NONE {
                let f = &mut faces[(k >> 2) as usize];
                k = f.next[(k & 3) as usize];
                if f.seen == stamp {
                    continue;
                }
                f.seen = stamp;
                let g = f.v;
                // Shares a vertex with `tri` (no short circuit: nine compares).
                let shared = (g[0] == t0)
                    | (g[0] == t1)
                    | (g[0] == t2)
                    | (g[1] == t0)
                    | (g[1] == t1)
                    | (g[1] == t2)
                    | (g[2] == t0)
                    | (g[2] == t1)
                    | (g[2] == t2);
                if shared {
                    continue;
                }
                let q = [pts[g[0] as usize], pts[g[1] as usize], pts[g[2] as usize]];
                let (glo, ghi) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
                if glo.cmple(hi).all()
                    && lo.cmple(ghi).all()
                    && !sep.apart(q)
                    && tri_tri_intersect(&p, &q)
                {
                    return true;
                }
            }
        }
        false
    }

    /// True when direction `x -> dir` lies strictly inside the free sector of `x` whose
    /// front edges are `w -> x -> y` (clockwise from `y - x` to `w - x` seen from `np`).
    fn sector_has(&self, np: DVec3, x: u32, w: u32, y: u32, dir: u32) -> bool {
        let (u, v) = plane_basis(np);
        let d2 = |to: u32| {
            let q = self.pts[to as usize] - self.pts[x as usize];
            [q.dot(u), q.dot(v)]
        };
        let s0 = d2(y);
        let a = cw_angle(s0, d2(dir));
        a > 0.0 && a < cw_angle(s0, d2(w))
    }

    /// IMPL-CHOICE I4 (not in the paper): the new edges must leave `a`, `b` (and a
    /// front point `t`) inside their free sector, the angle on the unmeshed side between
    /// the vertex's two front edges, in the projection plane. This catches triangles that
    /// fold over the mesh next to a reflex front vertex, which the edge-crossing test
    /// misses because edges sharing an endpoint are skipped.
    #[inline(never)]
    fn in_sectors(&self, a: u32, b: u32, t: u32, np: DVec3) -> bool {
        let (u, v) = plane_basis(np);
        let d2 = |from: u32, to: u32| {
            let q = self.pts[to as usize] - self.pts[from as usize];
            [q.dot(u), q.dot(v)]
        };
        // Free sector at vertex x with front edges w -> x -> y: clockwise from (y - x)
        // to (w - x) (the mesh lies left of every front edge).
        let inside = |x: u32, w: u32, y: u32, dir: u32| {
            let s0 = d2(x, y);
            let lim = cw_angle(s0, d2(x, w));
            let a = cw_angle(s0, d2(x, dir));
            a > 0.0 && a < lim
        };
        let z = self.e_a[self.fin[a as usize] as usize];
        let c = self.e_b[self.fout[b as usize] as usize];
        if z != t && !inside(a, z, b, t) {
            return false;
        }
        // At b the out-edge is b->c and the in-edge a->b.
        if c != t && !inside(b, a, c, t) {
            return false;
        }
        if self.state[t as usize] != FREE {
            let q = self.e_a[self.fin[t as usize] as usize];
            let y = self.e_b[self.fout[t as usize] as usize];
            if q != b && y != a {
                // glue: both a and b must lie in t's free sector
                if !inside(t, q, y, a) || !inside(t, q, y, b) {
                    return false;
                }
            } else if q == b && y != a {
                if !inside(t, q, y, a) {
                    return false;
                }
            } else if y == a && q != b && !inside(t, q, y, b) {
                return false;
            }
        }
        true
    }

    /// Main loop M1-M7 until the heap is empty; polls `ctx.checkpoint()` every few
    /// thousand pops.
    pub fn grow(&mut self, ctx: &RunCtx) -> Result<(), MethodError> {
        let mut passes = 0;
        let mut tris_at_pass = self.tris.len();
        loop {
            let Some(e) = self.pop() else {
                // IMPL-CHOICE I2 (not in the paper, whose M4 never retries an edge):
                // when the heap runs dry, push the live front edges again, up to
                // `revisit_passes` times and only while the last pass added triangles.
                // Edges that failed early often succeed once their neighbourhood has
                // been meshed (slits, narrow gaps between meeting fronts).
                if passes < self.cfg.revisit_passes
                    && (passes == 0 || self.tris.len() > tris_at_pass)
                {
                    passes += 1;
                    self.revisiting = true;
                    tris_at_pass = self.tris.len();
                    self.repush_all();
                    if self.heap_is_empty() {
                        break;
                    }
                    continue;
                }
                break;
            };
            self.stats.pops += 1;
            if self.stats.pops.is_multiple_of(CHECK_EVERY) {
                ctx.checkpoint()?;
            }
            match self.triangulate(e) {
                // M4: e stays in the front as a boundary edge (not pushed back).
                None => self.stats.boundary_pops += 1,
                Some(Op::Join(p, n)) => self.join(e, p, n),
                Some(Op::Fill(p)) => self.fill(e, p),
                Some(Op::LinkNext(p, n)) => self.link_next(e, p, n),
                Some(Op::LinkPrev(p, n)) => self.link_prev(e, p, n),
                Some(Op::Glue(p, n, n2)) => self.glue(e, p, n, n2),
                Some(Op::GlueMirror(p, n, n2)) => self.glue_mirror(e, p, n, n2),
            }
        }
        self.revisiting = false;
        Ok(())
    }
}

/// The score bound of [`Mesher::score_bound`] for distance `d` (weights `w`, radius
/// `r`).
#[inline]
fn bound(w: [f64; 3], r: f64, d: f64) -> f64 {
    let u = w[0] + w[1] + w[2] * ((r - d) / r).max(0.0);
    u + 1e-9 * (w[0] + w[1] + w[2])
}

/// Clockwise angle from 2-D direction `s` to `d`, as a *pseudo-angle* in [0, 4): a
/// strictly increasing function of the true clockwise angle in [0, 2 pi) with 0 <-> 0
/// ("diamond angle", no trigonometry). Callers only compare such values, so the sector
/// tests decide exactly as with `atan2`.
#[inline]
fn cw_angle(s: [f64; 2], d: [f64; 2]) -> f64 {
    // Counter-clockwise angle of d relative to s: the direction (dt, cr).
    let cr = s[0] * d[1] - s[1] * d[0];
    let dt = s[0] * d[0] + s[1] * d[1];
    let p = diamond(dt, cr);
    if p == 0.0 { 0.0 } else { 4.0 - p }
}

/// Pseudo-angle of the direction `(x, y)` in [0, 4), increasing with `atan2(y, x)` taken
/// in [0, 2 pi); 0 for the zero vector (as `atan2(0, 0) = 0`).
#[inline]
fn diamond(x: f64, y: f64) -> f64 {
    if x == 0.0 && y == 0.0 {
        return 0.0;
    }
    if y >= 0.0 {
        if x >= 0.0 {
            y / (x + y)
        } else {
            1.0 + (-x) / (y - x)
        }
    } else if x < 0.0 {
        2.0 + (-y) / (-x - y)
    } else {
        3.0 + x / (x - y)
    }
}

/// Projection-plane normal `normalize(n1 + n2)`, falling back to `n1` (A14).
#[inline]
pub(crate) fn plane_normal(n1: DVec3, n2: DVec3) -> DVec3 {
    let s = n1 + n2;
    if s.length_squared() > 1e-12 {
        s.normalize()
    } else {
        n1
    }
}

/// A fast, conservative disjointness test against one triangle: the projections on
/// the triangle's plane are separated along an edge normal of either by more than a
/// margin far above rounding (disjoint projections mean disjoint triangles). Spares
/// the exact test for the nearly coplanar neighbours of IMPL-CHOICE I14.
struct Separation {
    o: DVec3,
    u: DVec3,
    v: DVec3,
    p2: [[f64; 2]; 3],
    eps: f64,
}

impl Separation {
    fn new(p: [DVec3; 3], c: DVec3, rt: f64) -> Self {
        let (u, v) = plane_basis((p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero());
        let pr = |x: DVec3| [(x - c).dot(u), (x - c).dot(v)];
        Self {
            o: c,
            u,
            v,
            p2: p.map(pr),
            eps: 1e-9 * rt,
        }
    }

    /// True when `q` certainly does not meet the triangle.
    fn apart(&self, q: [DVec3; 3]) -> bool {
        let q2 = q.map(|x| [(x - self.o).dot(self.u), (x - self.o).dot(self.v)]);
        separated(&self.p2, &q2, self.eps) || separated(&q2, &self.p2, self.eps)
    }
}

/// Whether an edge line of 2-D triangle `a` has all of `b` beyond it, farther than
/// `eps` from it on the side away from `a`'s third corner.
fn separated(a: &[[f64; 2]; 3], b: &[[f64; 2]; 3], eps: f64) -> bool {
    (0..3).any(|k| {
        let (p, q) = (a[k], a[(k + 1) % 3]);
        let n = [q[1] - p[1], p[0] - q[0]];
        let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
        if len == 0.0 {
            return false;
        }
        let d = |x: [f64; 2]| ((x[0] - p[0]) * n[0] + (x[1] - p[1]) * n[1]) / len;
        let side = d(a[(k + 2) % 3]);
        let bs = b.map(d);
        if side >= 0.0 {
            bs.iter().all(|&x| x < -eps)
        } else {
            bs.iter().all(|&x| x > eps)
        }
    })
}

#[cfg(test)]
mod angle_tests {
    use super::*;

    /// The pseudo-angle orders directions exactly as the clockwise `atan2` angle.
    #[test]
    fn pseudo_angle_is_monotone_in_the_true_angle() {
        let true_cw = |s: [f64; 2], d: [f64; 2]| {
            let th = (s[0] * d[1] - s[1] * d[0]).atan2(s[0] * d[0] + s[1] * d[1]);
            if th <= 0.0 {
                -th
            } else {
                std::f64::consts::TAU - th
            }
        };
        let s = [0.6, -0.8];
        let dirs: Vec<[f64; 2]> = (0..720)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 720.0 + 0.001;
                [a.cos() * 2.0, a.sin() * 2.0]
            })
            .collect();
        for x in &dirs {
            for y in &dirs {
                let (tx, ty) = (true_cw(s, *x), true_cw(s, *y));
                let (px, py) = (cw_angle(s, *x), cw_angle(s, *y));
                if (tx - ty).abs() > 1e-9 {
                    assert_eq!(tx < ty, px < py, "{x:?} {y:?}");
                }
            }
        }
        assert_eq!(cw_angle(s, s), 0.0);
        assert_eq!(cw_angle(s, [0.0, 0.0]), 0.0);
    }
}

#[cfg(test)]
mod face_index_tests {
    use super::super::grid::Grid;
    use super::super::{PriorityFrontParams, mesher_cfg};
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The I14 walk over the face records (faces added by `add_tri` before and after
    /// `enable_self_check` rebuilt the index) answers as a brute-force scan of every
    /// face with a corner among the meshed points near the triangle: some face on such
    /// a point, sharing no vertex with the triangle, intersects it.
    #[test]
    fn face_index_walk_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let raw: Vec<DVec3> = (0..400)
            .map(|_| DVec3::new(rng.random(), rng.random(), 0.2 * rng.random::<f64>()))
            .collect();
        let (grid, order) = Grid::build(&raw, 0.15);
        let pts: Vec<DVec3> = order.iter().map(|&i| raw[i as usize]).collect();
        let r = 0.15;
        let mut cfg = mesher_cfg(&PriorityFrontParams::default(), r, 0.05);
        cfg.self_check = false;
        let mut m = Mesher::new(&pts, &grid, cfg, &vec![false; pts.len()]);
        // A random triple of distinct points near point `i` (within 0.2).
        let near_tri = |rng: &mut ChaCha8Rng| loop {
            let i = rng.random_range(0..pts.len());
            let mut t = [i as u32; 3];
            let mut k = 1;
            for _ in 0..200 {
                let j = rng.random_range(0..pts.len());
                if k < 3 && !t[..k].contains(&(j as u32)) && pts[j].distance(pts[i]) < 0.2 {
                    t[k] = j as u32;
                    k += 1;
                }
            }
            if k == 3 {
                return t;
            }
        };
        let tris: Vec<[u32; 3]> = (0..300).map(|_| near_tri(&mut rng)).collect();
        for &t in &tris[..150] {
            m.add_tri(t);
        }
        m.enable_self_check();
        for &t in &tris[150..] {
            m.add_tri(t);
        }
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..400 {
            let tri = near_tri(&mut rng);
            let p = tri.map(|i| pts[i as usize]);
            let o = (p[0] + p[1] + p[2]) / 3.0;
            // Meshed points within R of `o`, as the gather lists them.
            m.done_near = (0..pts.len() as u32)
                .filter(|&v| {
                    tris.iter().any(|t| t.contains(&v)) && pts[v as usize].distance(o) <= r
                })
                .collect();
            let want = tris.iter().any(|g| {
                g.iter().any(|v| m.done_near.contains(v))
                    && !g.iter().any(|v| tri.contains(v))
                    && tri_tri_intersect(&p, &g.map(|i| pts[i as usize]))
            });
            assert_eq!(m.hits_mesh(tri), want, "{tri:?}");
            if want {
                hits += 1;
            } else {
                misses += 1;
            }
        }
        assert!(hits > 20 && misses > 20, "{hits} hits, {misses} misses");
    }
}
