//! Incremental Bowyer–Watson construction.
//!
//! Internal conventions:
//! * Vertices are numbered in insertion order ("internal ids"); the id is also the
//!   symbolic-perturbation rank, so the point being inserted always has the highest rank.
//! * Tetrahedron `t` has vertices `v[0..4]` with `orient3d(v0, v1, v2, v3) > 0`; face `i`
//!   is opposite vertex `i`. A ghost ("infinite") tetrahedron has exactly one vertex equal
//!   to [`INF`]; replacing it by any point strictly outside the hull facet gives a
//!   positively oriented tetrahedron.
//! * `n[i] = 4m + j` means face `i` of `t` is face `j` of `m` (the mirror index is kept
//!   so that gluing is O(1)).
//! * Vertices and neighbours of a tetrahedron share one 32-byte aligned record, so a
//!   tetrahedron costs one cache line access.

use crate::point::P3;
use crate::predicates::{insphere, orient3d};
use crate::sort::SplitMix;

/// The infinite vertex.
pub(crate) const INF: u32 = u32::MAX;

/// Marks a free slot (`v[0] == FREE`).
pub(crate) const FREE: u32 = u32::MAX - 1;

/// Largest number of steps of one visibility walk before falling back to a scan.
const MAX_WALK: usize = 1 << 20;

/// Largest number of tetrahedron slots (adjacency codes `4t + i` must fit in `u32`).
pub(crate) const MAX_SLOTS: usize = 1 << 30;

/// One tetrahedron: vertices and adjacency codes.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub(crate) struct Tet {
    pub(crate) v: [u32; 4],
    pub(crate) n: [u32; 4],
}

/// Cavity-search marks.
const UNKNOWN: u8 = 0;
const IN_CAVITY: u8 = 1;
const NO_CONFLICT: u8 = 2;

#[derive(Debug)]
pub(crate) struct Builder {
    pub(crate) pts: Vec<P3>,
    pub(crate) tets: Vec<Tet>,
    mark: Vec<u8>,
    /// Free tetrahedron slots.
    free: Vec<u32>,
    cav: Vec<u32>,
    /// Boundary facets of the cavity: (inner tet, face index, outer adjacency code).
    bnd: Vec<(u32, u32, u32)>,
    newv: Vec<[u32; 4]>,
    /// Edge hash table for gluing the new tetrahedra (stamped, never cleared).
    htab: Vec<HEntry>,
    stamp: u32,
    last: u32,
    rng: SplitMix,
    /// Number of walks that hit the step bound (expected 0).
    pub(crate) walk_fallbacks: usize,
    /// Set when the slot limit was reached (the construction is then abandoned).
    pub(crate) overflow: bool,
    /// Tetrahedra visited by walks and conflict tests made (diagnostics).
    pub(crate) walk_steps: u64,
    pub(crate) conflict_tests: u64,
}

pub(crate) enum Located {
    /// A tetrahedron in conflict with the point.
    Conflict(u32),
    /// The point coincides with this (internal) vertex.
    Duplicate(u32),
}

const HASH0: usize = 512;

/// Entry of the gluing hash table: edge key, adjacency code, generation stamp.
#[derive(Debug, Clone, Copy, Default)]
struct HEntry {
    key: u64,
    val: u32,
    stamp: u32,
}

impl Builder {
    /// Start with the tetrahedron of internal vertices 0..4 (which must not be coplanar)
    /// and its four ghosts.
    pub(crate) fn new(pts: Vec<P3>, seed: u64) -> Self {
        let n = pts.len();
        let cap = (7 * n + 16).min(MAX_SLOTS);
        let mut b = Builder {
            pts,
            tets: Vec::with_capacity(cap),
            mark: Vec::with_capacity(cap),
            free: Vec::new(),
            cav: Vec::new(),
            bnd: Vec::new(),
            newv: Vec::new(),
            htab: vec![HEntry::default(); HASH0],
            stamp: 0,
            last: 0,
            rng: SplitMix(seed ^ 0x5DEE_CE66_D1CE_4E5B),
            walk_fallbacks: 0,
            overflow: false,
            walk_steps: 0,
            conflict_tests: 0,
        };
        let o = orient3d(&b.pts[0], &b.pts[1], &b.pts[2], &b.pts[3]);
        debug_assert!(o != 0);
        let v: [u32; 4] = if o > 0 { [0, 1, 2, 3] } else { [0, 1, 3, 2] };
        b.push_tet(v);
        for i in 0..4 {
            // Ghost on face i: the face seen from outside, i.e. an odd permutation.
            let mut g = v;
            g[i] = INF;
            g.swap((i + 1) % 4, (i + 2) % 4);
            b.push_tet(g);
        }
        // Glue the five tetrahedra by matching faces.
        for t in 0..5u32 {
            for i in 0..4u32 {
                let ft = face_set(&b.tets[t as usize].v, i as usize);
                for m in 0..5u32 {
                    for j in 0..4u32 {
                        if m != t && face_set(&b.tets[m as usize].v, j as usize) == ft {
                            b.tets[t as usize].n[i as usize] = 4 * m + j;
                        }
                    }
                }
            }
        }
        b
    }

    fn push_tet(&mut self, v: [u32; 4]) -> u32 {
        let t = self.tets.len() as u32;
        if self.tets.len() + 1 >= MAX_SLOTS {
            self.overflow = true;
        }
        self.tets.push(Tet { v, n: [0; 4] });
        self.mark.push(UNKNOWN);
        t
    }

    #[inline]
    fn p(&self, v: u32) -> &P3 {
        &self.pts[v as usize]
    }

    /// Sign of `orient3d` of the tetrahedron `v` with vertex `i` replaced by `p`
    /// (all other vertices finite).
    #[inline]
    fn orient_replace(&self, v: &[u32; 4], i: usize, p: &P3) -> i32 {
        let q = |k: usize| -> &P3 { if k == i { p } else { self.p(v[k]) } };
        orient3d(q(0), q(1), q(2), q(3))
    }

    /// Conflict test of a finite tetrahedron with the point being inserted (which has
    /// the highest perturbation rank, so an exactly co-spherical point is outside).
    #[inline]
    fn finite_conflict(&self, v: &[u32; 4], p: &P3) -> bool {
        insphere(self.p(v[0]), self.p(v[1]), self.p(v[2]), self.p(v[3]), p) > 0
    }

    /// Conflict test of any tetrahedron with the point being inserted.
    #[inline]
    fn conflict(&self, t: u32, p: &P3) -> bool {
        self.conflict_rec(&self.tets[t as usize], p)
    }

    /// Conflict test of the tetrahedron record `tet` with the point being inserted.
    #[inline]
    fn conflict_rec(&self, tet: &Tet, p: &P3) -> bool {
        let v = tet.v;
        if !v.contains(&INF) {
            return self.finite_conflict(&v, p);
        }
        let k = v.iter().position(|&x| x == INF).unwrap_or(0);
        let s = self.orient_replace(&v, k, p);
        if s != 0 {
            return s > 0;
        }
        // On the hull facet's plane: decided by the finite neighbour, as for a sphere
        // through the facet and a point pushed to infinity.
        let m = tet.n[k] >> 2;
        self.finite_conflict(&self.tets[m as usize].v, p)
    }

    /// Visibility walk from the last created tetrahedron to one in conflict with `p`.
    fn locate(&mut self, p: &P3) -> Located {
        let mut t = self.last;
        let tet = &self.tets[t as usize];
        if tet.v[0] == FREE {
            return self.locate_brute(p);
        }
        if let Some(k) = tet.v.iter().position(|&x| x == INF) {
            t = tet.n[k] >> 2;
        }
        let mut from = u32::MAX;
        let mut r = self.rng.next_u64();
        for step in 0..MAX_WALK {
            let tet = self.tets[t as usize];
            if step % 32 == 0 {
                r = self.rng.next_u64();
            }
            let start = (r & 3) as usize;
            r >>= 2;
            let mut next = u32::MAX;
            for k in 0..4 {
                let i = (start + k) & 3;
                let code = 4 * t + i as u32;
                if code == from {
                    continue;
                }
                if self.orient_replace(&tet.v, i, p) < 0 {
                    next = tet.n[i];
                    break;
                }
            }
            if next == u32::MAX {
                for &x in &tet.v {
                    if self.p(x) == p {
                        // Later duplicates of this point start here.
                        self.last = t;
                        return Located::Duplicate(x);
                    }
                }
                return Located::Conflict(t);
            }
            from = next;
            self.walk_steps += 1;
            t = next >> 2;
            if self.tets[t as usize].v.contains(&INF) {
                return Located::Conflict(t);
            }
        }
        self.walk_fallbacks += 1;
        self.locate_brute(p)
    }

    /// Exhaustive location (never expected to run; a safety net against cycling).
    fn locate_brute(&self, p: &P3) -> Located {
        let mut ghost = None;
        for t in 0..self.tets.len() as u32 {
            let v = self.tets[t as usize].v;
            if v[0] == FREE {
                continue;
            }
            if v.contains(&INF) {
                if ghost.is_none() && self.conflict(t, p) {
                    ghost = Some(t);
                }
                continue;
            }
            if (0..4).all(|i| self.orient_replace(&v, i, p) >= 0) {
                for &x in &v {
                    if self.p(x) == p {
                        return Located::Duplicate(x);
                    }
                }
                return Located::Conflict(t);
            }
        }
        // p is outside the hull: some ghost sees it.
        Located::Conflict(ghost.unwrap_or(0))
    }

    /// Insert internal vertex `id`. Returns `Some(existing)` if it duplicates a vertex.
    pub(crate) fn insert(&mut self, id: u32) -> Option<u32> {
        let p = self.pts[id as usize];
        let seed = match self.locate(&p) {
            Located::Duplicate(x) => return Some(x),
            Located::Conflict(t) => t,
        };
        self.cavity(seed, &p);
        self.fill(id);
        None
    }

    /// Breadth-first search of the conflict region from `seed` (`cav` is the queue).
    fn cavity(&mut self, seed: u32, p: &P3) {
        self.cav.clear();
        self.bnd.clear();
        self.mark[seed as usize] = IN_CAVITY;
        self.cav.push(seed);
        let mut head = 0;
        while head < self.cav.len() {
            let t = self.cav[head];
            head += 1;
            let nb = self.tets[t as usize].n;
            // Load the four neighbours up front so that their cache misses overlap.
            let recs = nb.map(|c| self.tets[(c >> 2) as usize]);
            let marks = nb.map(|c| self.mark[(c >> 2) as usize]);
            for i in 0..4u32 {
                let code = nb[i as usize];
                let m = code >> 2;
                match marks[i as usize] {
                    IN_CAVITY => continue,
                    NO_CONFLICT => {}
                    _ => {
                        // The four neighbours are distinct, so `marks` is still current.
                        self.conflict_tests += 1;
                        if self.conflict_rec(&recs[i as usize], p) {
                            self.mark[m as usize] = IN_CAVITY;
                            self.cav.push(m);
                            continue;
                        }
                        self.mark[m as usize] = NO_CONFLICT;
                    }
                }
                self.bnd.push((t, i, code));
            }
        }
    }

    /// Replace the cavity by the cone from vertex `id` to its boundary.
    fn fill(&mut self, id: u32) {
        let nb = self.bnd.len();
        // Hash table for gluing: 3 edges per boundary facet, each seen twice.
        let need = (4 * nb).next_power_of_two().max(HASH0);
        if self.htab.len() < need {
            self.htab = vec![HEntry::default(); need];
        }
        let hmask = self.htab.len() - 1;
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.htab.iter_mut().for_each(|e| e.stamp = 0);
            self.stamp = 1;
        }
        let hcur = self.stamp;
        // Vertices of the new tets, read before any cavity slot is overwritten; reset
        // the marks of the outer tetrahedra.
        let mut newv = std::mem::take(&mut self.newv);
        newv.clear();
        for &(t, i, out) in &self.bnd {
            let mut v = self.tets[t as usize].v;
            v[i as usize] = id;
            newv.push(v);
            self.mark[(out >> 2) as usize] = UNKNOWN;
        }
        let nc = self.cav.len();
        for k in nb..nc {
            let t = self.cav[k];
            self.tets[t as usize].v = [FREE; 4];
            self.mark[t as usize] = UNKNOWN;
            self.free.push(t);
        }
        let mut first = u32::MAX;
        for k in 0..nb {
            // Slots: reuse the cavity, then the free list, then grow.
            let t = if k < nc {
                self.cav[k]
            } else if let Some(f) = self.free.pop() {
                f
            } else {
                self.push_tet([FREE; 4])
            };
            self.mark[t as usize] = UNKNOWN;
            if k == 0 {
                first = t;
            }
            let (_, i, out) = self.bnd[k];
            let v = newv[k];
            let tet = &mut self.tets[t as usize];
            tet.v = v;
            tet.n[i as usize] = out;
            self.tets[(out >> 2) as usize].n[(out & 3) as usize] = 4 * t + i;
            // Faces j != i contain the new vertex and the edge {v[a], v[b]}, a, b ∉ {i, j}.
            for j in 0..4u32 {
                if j == i {
                    continue;
                }
                let (ea, eb) = OTHER_TWO[i as usize][j as usize];
                let (x, y) = (v[ea], v[eb]);
                let key = if x < y {
                    (u64::from(x) << 32) | u64::from(y)
                } else {
                    (u64::from(y) << 32) | u64::from(x)
                };
                let mut h = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as usize & hmask;
                loop {
                    let e = &mut self.htab[h];
                    if e.stamp != hcur {
                        *e = HEntry {
                            key,
                            val: 4 * t + j,
                            stamp: hcur,
                        };
                        break;
                    }
                    if e.key == key {
                        let other = e.val;
                        self.tets[t as usize].n[j as usize] = other;
                        self.tets[(other >> 2) as usize].n[(other & 3) as usize] = 4 * t + j;
                        break;
                    }
                    h = (h + 1) & hmask;
                }
            }
        }
        self.last = first;
        self.newv = newv;
    }
}

/// Sorted vertices of face `i`.
fn face_set(v: &[u32; 4], i: usize) -> [u32; 3] {
    let mut f = [0u32; 3];
    let mut n = 0;
    for k in 0..4 {
        if k != i {
            f[n] = v[k];
            n += 1;
        }
    }
    f.sort_unstable();
    f
}

/// `OTHER_TWO[i][j]`: the two indices of `0..4` other than `i` and `j` (`i != j`).
const OTHER_TWO: [[(usize, usize); 4]; 4] = [
    [(0, 0), (2, 3), (1, 3), (1, 2)],
    [(2, 3), (0, 0), (0, 3), (0, 2)],
    [(1, 3), (0, 3), (0, 0), (0, 1)],
    [(1, 2), (0, 2), (0, 1), (0, 0)],
];
