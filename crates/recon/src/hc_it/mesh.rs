//! The growing triangle mesh of all NC clusters (spec §2): triangles in stored order, an
//! undirected edge -> triangles map, and vertex -> triangles lists. A boundary (BTM)
//! edge is an edge with one triangle, directed as that triangle traverses it.
//!
//! Every insertion keeps the mesh edge-manifold and consistently oriented: a triangle
//! whose edge already has two triangles, or is traversed in the same direction by its
//! one triangle, is refused.

use foldhash::HashMap;
use glam::DVec3;

/// No triangle.
pub const NONE: u32 = u32::MAX;

/// Key of the undirected edge {a, b}.
#[inline]
pub fn key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// Unnormalized normal (v1 - v0) x (v2 - v0) of a triangle in stored order (Eq. 1).
#[inline]
pub fn cross(p: &[DVec3], t: [u32; 3]) -> DVec3 {
    let a = p[t[0] as usize];
    (p[t[1] as usize] - a).cross(p[t[2] as usize] - a)
}

/// Angle between two vectors in [0, pi] (pi/2 when one is zero).
#[inline]
pub fn angle(a: DVec3, b: DVec3) -> f64 {
    let d = a.length() * b.length();
    if d <= 0.0 {
        return std::f64::consts::FRAC_PI_2;
    }
    (a.dot(b) / d).clamp(-1.0, 1.0).acos()
}

/// An angle threshold with its cosine, for deciding `angle(a, b) >= rad` (and the like)
/// without `acos` where the cosine decides it.
///
/// `acos` has a slope of magnitude at least 1 and is evaluated to about one ulp, and
/// `cos` is the threshold's cosine to well within 1e-12: so when the cosine x that
/// [`angle`] takes the arc cosine of is more than [`COS_MARGIN`] from `cos`, `acos(x)`
/// is more than 1e-10 from `rad` on the side the comparison of x gives, and the answer
/// is the one `angle` would give; otherwise `acos` is evaluated as `angle` does.
#[derive(Debug, Clone, Copy)]
pub struct AngleBound {
    rad: f64,
    cos: f64,
}

/// Cosines closer than this to a threshold's cosine are decided by `acos` itself.
pub const COS_MARGIN: f64 = 1e-9;

/// 1 degree (the smallest angle of an acceptable triangle).
pub const ONE_DEGREE: AngleBound = AngleBound {
    rad: 1f64.to_radians(),
    cos: 0.999_847_695_156_391_2,
};

/// 1e-3 rad (the smallest angle of a split or flipped triangle).
pub const MILLIRAD: AngleBound = AngleBound {
    rad: 1e-3,
    cos: 0.999_999_500_000_041_7,
};

/// pi / 2.
pub const RIGHT: AngleBound = AngleBound {
    rad: std::f64::consts::FRAC_PI_2,
    cos: 0.0,
};

impl AngleBound {
    /// The threshold `rad`.
    pub fn new(rad: f64) -> Self {
        Self {
            rad,
            cos: rad.cos(),
        }
    }

    /// The threshold `rad` with its cosine given (for constants; it must be within
    /// 1e-12 of cos(rad)).
    pub const fn with_cos(rad: f64, cos: f64) -> Self {
        Self { rad, cos }
    }

    /// `angle(a, b)` against the threshold, as [`angle`] computes it.
    #[inline]
    fn cmp(&self, a: DVec3, b: DVec3) -> std::cmp::Ordering {
        use std::cmp::Ordering;
        let d = a.length() * b.length();
        if d <= 0.0 {
            return std::f64::consts::FRAC_PI_2
                .partial_cmp(&self.rad)
                .unwrap_or(Ordering::Less);
        }
        let x = (a.dot(b) / d).clamp(-1.0, 1.0);
        if x < self.cos - COS_MARGIN {
            Ordering::Greater
        } else if x > self.cos + COS_MARGIN {
            Ordering::Less
        } else {
            x.acos().partial_cmp(&self.rad).unwrap_or(Ordering::Less)
        }
    }

    /// `angle(a, b) >= rad`.
    #[inline]
    pub fn reached_by(&self, a: DVec3, b: DVec3) -> bool {
        self.cmp(a, b).is_ge()
    }

    /// `min_angle(a, b, c) <= rad`.
    #[inline]
    pub fn min_angle_at_most(&self, a: DVec3, b: DVec3, c: DVec3) -> bool {
        self.cmp(b - a, c - a).is_le()
            || self.cmp(c - b, a - b).is_le()
            || self.cmp(a - c, b - c).is_le()
    }
}

/// Smallest interior angle of a triangle (0 for a degenerate one).
pub fn min_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let ang = |p: DVec3, q: DVec3, r: DVec3| angle(q - p, r - p);
    ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b))
}

/// Whether the 2-D projection (plane normal `nrm`) of segment p-q crosses r-s in their
/// interiors.
#[inline]
pub fn crosses(nrm: DVec3, p: DVec3, q: DVec3, r: DVec3, s: DVec3) -> bool {
    let orient = |a: DVec3, b: DVec3, c: DVec3| (b - a).cross(c - a).dot(nrm);
    let (d1, d2) = (orient(p, q, r), orient(p, q, s));
    let (d3, d4) = (orient(r, s, p), orient(r, s, q));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Circumradius of the triangle (a, b, c); infinite for a degenerate one.
pub fn circumradius(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac) = (b - a, c - a);
    let n2 = ab.cross(ac).length_squared();
    if n2 <= 0.0 {
        return f64::INFINITY;
    }
    (ab.length_squared() * ac.length_squared() * (b - c).length_squared() / (4.0 * n2)).sqrt()
}

/// Triangle whose stored order traverses a -> b, rotated to start at `a`.
#[inline]
pub fn rotate_to(t: [u32; 3], a: u32) -> [u32; 3] {
    if t[0] == a {
        t
    } else if t[1] == a {
        [t[1], t[2], t[0]]
    } else {
        [t[2], t[0], t[1]]
    }
}

/// The mesh under construction.
///
/// Besides the edge map it keeps, updated on every link and unlink, what the closure
/// pass and the winner fallback would otherwise recompute by walking every triangle:
/// the boundary edges of each triangle as bits, the outgoing and incoming boundary
/// edges of each vertex, a modification stamp per vertex and, when asked for, a log of
/// the directed edges that became boundary edges.
#[derive(Debug, Default)]
pub struct Mesh {
    /// Triangles in stored order (orientation from their NC's first triangle).
    pub tris: Vec<[u32; 3]>,
    edges: HashMap<u64, [u32; 2]>,
    /// Triangles incident to each vertex.
    pub vt: Vec<Vec<u32>>,
    /// Bit k of `bmask[t]`: edge `t[k] -> t[k + 1]` is a boundary edge (t is its only
    /// triangle).
    bmask: Vec<u8>,
    /// Boundary edges leaving / entering each vertex.
    bout: Vec<u32>,
    bin: Vec<u32>,
    /// Number of links and unlinks so far, and its value at the last change of a
    /// triangle at each vertex.
    clock: u64,
    stamp: Vec<u64>,
    /// Stamps overwritten since [`Self::savepoint`] (vertex, old stamp), and the clock then.
    journal: Vec<(u32, u64)>,
    journaling: bool,
    saved_clock: u64,
    /// Directed edges that became boundary edges with their slot 3 t + k, in order
    /// (only after [`Self::log_boundary`]).
    log: Vec<(u32, u32, u32)>,
    logging: bool,
}

impl Mesh {
    /// An empty mesh over `n` vertices.
    pub fn new(n: usize) -> Self {
        Self {
            tris: Vec::new(),
            edges: HashMap::default(),
            vt: vec![Vec::new(); n],
            bmask: Vec::new(),
            bout: vec![0; n],
            bin: vec![0; n],
            clock: 0,
            stamp: vec![0; n],
            journal: Vec::new(),
            journaling: false,
            saved_clock: 0,
            log: Vec::new(),
            logging: false,
        }
    }

    /// An empty mesh over `n` vertices with room for `tris` triangles (and their edges)
    /// before it reallocates.
    pub fn with_capacity(n: usize, tris: usize) -> Self {
        let mut m = Self::new(n);
        m.tris.reserve(tris);
        m.bmask.reserve(tris);
        m.edges.reserve(tris * 3 / 2 + 16);
        m
    }

    /// Empties the mesh: afterwards it is as [`Self::new`] made it (clock, stamps and all),
    /// but keeps its allocations (a rebuild then reallocates no per-vertex list).
    pub fn clear(&mut self) {
        self.tris.clear();
        self.edges.clear();
        for l in &mut self.vt {
            l.clear();
        }
        self.bmask.clear();
        self.bout.fill(0);
        self.bin.fill(0);
        self.clock = 0;
        self.stamp.fill(0);
        self.journal.clear();
        self.journaling = false;
        self.saved_clock = 0;
        self.log.clear();
        self.logging = false;
    }

    /// Starts logging the directed edges that become boundary edges (see
    /// [`Self::boundary_log`]).
    pub fn log_boundary(&mut self) {
        self.logging = true;
    }

    /// Every directed edge a -> b that became a boundary edge since logging started, in
    /// order, with its slot 3 t + k (edge k of triangle t); an entry may since have
    /// stopped being one (see [`Self::is_boundary_slot`]), or appear again.
    pub fn boundary_log(&self) -> &[(u32, u32, u32)] {
        &self.log
    }

    /// Whether slot 3 t + k is a boundary edge a -> b now (then t is its one triangle).
    #[inline]
    pub fn is_boundary_slot(&self, a: u32, b: u32, slot: u32) -> bool {
        let (t, k) = ((slot / 3) as usize, (slot % 3) as usize);
        let tri = self.tris[t];
        self.bmask[t] & (1 << k) != 0 && tri[k] == a && tri[(k + 1) % 3] == b
    }

    /// Whether `v` has a boundary edge (equivalently, [`Self::boundary_at`] finds one).
    #[inline]
    pub fn on_boundary(&self, v: u32) -> bool {
        self.bout[v as usize] + self.bin[v as usize] > 0
    }

    /// Boundary edges leaving `v`: more than one means several fans at `v`.
    #[inline]
    pub fn boundary_out(&self, v: u32) -> u32 {
        self.bout[v as usize]
    }

    /// The boundary-edge bits of triangle `t` (bit k: edge `t[k] -> t[k + 1]`).
    #[inline]
    pub fn boundary_bits(&self, t: u32) -> u8 {
        self.bmask[t as usize]
    }

    /// The modification clock: it advances whenever a triangle is linked or unlinked.
    #[inline]
    pub fn clock(&self) -> u64 {
        self.clock
    }

    /// The clock at the last change of a triangle at `v` (0 if none).
    #[inline]
    pub fn stamp(&self, v: u32) -> u64 {
        self.stamp[v as usize]
    }

    /// Starts recording stamp changes, so that a trial that is undone (every triangle
    /// added since popped again) can also undo its stamps ([`Self::rollback_stamps`]).
    pub fn savepoint(&mut self) {
        self.journal.clear();
        self.journaling = true;
        self.saved_clock = self.clock;
    }

    /// Keeps the changes since [`Self::savepoint`].
    pub fn commit(&mut self) {
        self.journal.clear();
        self.journaling = false;
    }

    /// Restores the stamps and the clock of the [`Self::savepoint`]; the caller has
    /// undone every change since (the mesh is as it was then).
    pub fn rollback_stamps(&mut self) {
        for &(v, old) in self.journal.iter().rev() {
            self.stamp[v as usize] = old;
        }
        self.clock = self.saved_clock;
        self.commit();
    }

    /// The (up to two) triangles of edge {a, b}.
    pub fn edge_tris(&self, a: u32, b: u32) -> [u32; 2] {
        self.edges.get(&key(a, b)).copied().unwrap_or([NONE, NONE])
    }

    /// Whether the edge {a, b} exists.
    pub fn has_edge(&self, a: u32, b: u32) -> bool {
        self.edges.contains_key(&key(a, b))
    }

    /// The triangle across edge {a, b} from `t`, if any.
    pub fn across(&self, t: u32, a: u32, b: u32) -> Option<u32> {
        let [t0, t1] = self.edge_tris(a, b);
        let o = if t0 == t { t1 } else { t0 };
        (o != NONE && o != t).then_some(o)
    }

    /// Whether directed a -> b is a boundary edge (one triangle, traversing a -> b).
    pub fn is_boundary(&self, a: u32, b: u32) -> bool {
        let [t0, t1] = self.edge_tris(a, b);
        if t0 == NONE || t1 != NONE {
            return false;
        }
        let t = self.tris[t0 as usize];
        (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b)
    }

    /// Boundary edges a -> b with `a == v` (outgoing) or `b == v` (incoming), pushed to
    /// `out` as `(a, b, triangle)`.
    pub fn boundary_at(&self, v: u32, out: &mut Vec<(u32, u32, u32)>) {
        for &t in &self.vt[v as usize] {
            let bits = self.bmask[t as usize];
            if bits == 0 {
                continue;
            }
            let tri = self.tris[t as usize];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if (a == v || b == v) && bits & (1 << k) != 0 {
                    out.push((a, b, t));
                }
            }
        }
    }

    /// Whether triangle `t` can be added: distinct vertices, every edge has at most one
    /// triangle and that one traverses it the other way.
    pub fn can_add(&self, t: [u32; 3]) -> bool {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return false;
        }
        (0..3).all(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let [t0, t1] = self.edge_tris(a, b);
            t0 == NONE || (t1 == NONE && self.is_boundary(b, a))
        })
    }

    /// Adds `t` if [`Self::can_add`]; returns its id.
    pub fn add(&mut self, t: [u32; 3]) -> Option<u32> {
        if !self.can_add(t) {
            return None;
        }
        let id = self.tris.len() as u32;
        self.tris.push(t);
        self.bmask.push(0);
        self.link(id, t);
        Some(id)
    }

    /// Adds `t`, which the caller knows [`Self::can_add`] accepts (a triangle of a valid
    /// mesh whose triangles are re-added in order, some left out); returns its id.
    pub fn add_known(&mut self, t: [u32; 3]) -> u32 {
        debug_assert!(self.can_add(t), "triangle {t:?} cannot be added");
        let id = self.tris.len() as u32;
        self.tris.push(t);
        self.bmask.push(0);
        self.link(id, t);
        id
    }

    /// Removes the triangle added last (undoes [`Self::add`]).
    pub fn pop(&mut self) {
        if let Some(last) = self.tris.len().checked_sub(1) {
            self.unlink(last as u32);
            self.tris.pop();
            self.bmask.pop();
        }
    }

    /// Slot k of triangle `t` whose edge is {a, b}, with the edge as `t` traverses it.
    fn slot(&self, t: u32, a: u32, b: u32) -> Option<(usize, u32, u32)> {
        let tri = self.tris[t as usize];
        (0..3).find_map(|k| {
            let (x, y) = (tri[k], tri[(k + 1) % 3]);
            ((x == a && y == b) || (x == b && y == a)).then_some((k, x, y))
        })
    }

    /// Marks slot k (edge x -> y) of triangle `t` as a boundary edge or not.
    fn set_boundary(&mut self, t: u32, k: usize, x: u32, y: u32, on: bool) {
        let bit = 1u8 << k;
        let m = &mut self.bmask[t as usize];
        if on && *m & bit == 0 {
            *m |= bit;
            self.bout[x as usize] += 1;
            self.bin[y as usize] += 1;
            if self.logging {
                self.log.push((x, y, 3 * t + k as u32));
            }
        } else if !on && *m & bit != 0 {
            *m &= !bit;
            self.bout[x as usize] -= 1;
            self.bin[y as usize] -= 1;
        }
    }

    /// Advances the clock and stamps the vertices of `t`.
    fn touch(&mut self, t: [u32; 3]) {
        self.clock += 1;
        for v in t {
            if self.journaling {
                self.journal.push((v, self.stamp[v as usize]));
            }
            self.stamp[v as usize] = self.clock;
        }
    }

    fn link(&mut self, id: u32, t: [u32; 3]) {
        self.touch(t);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let e = self.edges.entry(key(a, b)).or_insert([NONE, NONE]);
            let other = if e[0] == NONE {
                e[0] = id;
                NONE
            } else {
                e[1] = id;
                e[0]
            };
            if other == NONE {
                self.set_boundary(id, k, a, b, true);
            } else {
                if let Some((j, x, y)) = self.slot(other, a, b) {
                    self.set_boundary(other, j, x, y, false);
                }
                self.set_boundary(id, k, a, b, false);
            }
            self.vt[t[k] as usize].push(id);
        }
    }

    fn unlink(&mut self, id: u32) {
        let t = self.tris[id as usize];
        self.touch(t);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let kk = key(a, b);
            let mut left = NONE;
            if let Some(e) = self.edges.get_mut(&kk) {
                if e[0] == id {
                    e[0] = e[1];
                }
                e[1] = NONE;
                left = e[0];
                if e[0] == NONE {
                    self.edges.remove(&kk);
                }
            }
            self.set_boundary(id, k, a, b, false);
            if left != NONE
                && let Some((j, x, y)) = self.slot(left, a, b)
            {
                self.set_boundary(left, j, x, y, true);
            }
            let l = &mut self.vt[t[k] as usize];
            if let Some(pos) = l.iter().position(|&x| x == id) {
                l.swap_remove(pos);
            }
        }
    }

    /// Replaces triangle `id` by `t` (used by splits and flips); the caller guarantees
    /// the result is manifold.
    pub fn replace(&mut self, id: u32, t: [u32; 3]) {
        self.unlink(id);
        self.tris[id as usize] = t;
        self.link(id, t);
    }

    /// Replaces triangles `a` and `b` together (an edge flip): both are unlinked before
    /// either is relinked, so the shared outer edges never see three triangles.
    pub fn replace_pair(&mut self, a: u32, ta: [u32; 3], b: u32, tb: [u32; 3]) {
        self.unlink(a);
        self.unlink(b);
        self.tris[a as usize] = ta;
        self.tris[b as usize] = tb;
        self.link(a, ta);
        self.link(b, tb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cosine decisions agree with comparing [`angle`] and [`min_angle`], also for
    /// angles within rounding of the thresholds.
    #[test]
    fn angle_bounds_decide_as_the_angles_do() {
        let bounds = [
            ONE_DEGREE,
            MILLIRAD,
            RIGHT,
            AngleBound::new(1.0),
            AngleBound::new(std::f64::consts::FRAC_PI_3),
        ];
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for b in bounds {
            for i in 0..20_000 {
                let a = DVec3::new(1.0, 0.0, 0.0);
                // Angles spread over [0, pi], every other one next to the threshold.
                let t = if i % 2 == 0 {
                    next() * std::f64::consts::PI
                } else {
                    (b.rad + (next() - 0.5) * 1e-8).max(0.0)
                };
                let v = DVec3::new(t.cos(), t.sin() * next(), t.sin()) * (0.5 + next());
                assert_eq!(b.reached_by(a, v), angle(a, v) >= b.rad, "{t}");
                let c = DVec3::new(next(), next(), 0.0);
                assert_eq!(
                    b.min_angle_at_most(DVec3::ZERO, v, c),
                    min_angle(DVec3::ZERO, v, c) <= b.rad
                );
            }
            assert_eq!(
                b.reached_by(DVec3::ZERO, DVec3::X),
                angle(DVec3::ZERO, DVec3::X) >= b.rad
            );
        }
    }
}
