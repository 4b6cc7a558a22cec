//! The mesh enhancements the paper's abstract names but never describes (spec §3.6),
//! as edge swaps on the grown mesh; both are ours, not the paper's, and off by default.
//!
//! * ASSUMPTION E21, feature alignment (run first): data-dependent swaps after Dyn,
//!   Hormann, Kim & Levin (2001) that lower the ABN cost (the sum over the quad's five
//!   edges of the angle between the normals of the two facets on the edge); afterwards
//!   interior edges whose dihedral exceeds the feature angle are locked.
//! * ASSUMPTION E20, near-equilateral adjustment: Lawson's max-min-angle swap in 3-D,
//!   constrained so that the surface moves by at most epsilon (the distance between the
//!   old and the new diagonal) and the dihedral grows by at most 5 degrees.
//!
//! Every swap keeps Rules 1-3: the new diagonal is at most Omega, is not an existing
//! edge, and both new facets have their smallest angle above theta.

use std::collections::{HashMap, HashSet, VecDeque};

use glam::DVec3;

use super::geometry::{edge_key, face_cross, min_angle};

/// Minimum drop of the ABN cost for an E21 swap (radians).
const ABN_MIN_GAIN: f64 = 1e-3;
/// Allowed growth of the dihedral by an E20 swap (degrees).
const E20_DIHEDRAL_SLACK_DEG: f64 = 5.0;
/// Swap attempts per edge before a pass gives up (the 10 |E| cap of the spec).
const CAP_PER_EDGE: usize = 10;

/// Limits shared by the swaps.
#[derive(Debug, Clone, Copy)]
pub struct SwapCfg {
    /// Maximum edge length Omega.
    pub omega: f64,
    /// Minimum angle theta (radians).
    pub min_angle: f64,
    /// Tolerance epsilon (E20's movement bound).
    pub eps: f64,
    /// Feature-edge dihedral (radians).
    pub feature_angle: f64,
}

/// What the swaps did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SwapStats {
    /// E21 swaps.
    pub feature_swaps: usize,
    /// E20 swaps.
    pub equilateral_swaps: usize,
    /// Feature edges locked after E21.
    pub feature_edges: usize,
}

/// Angle between two vectors (0 for a zero vector).
fn angle(a: DVec3, b: DVec3) -> f64 {
    if a == DVec3::ZERO || b == DVec3::ZERO {
        return 0.0;
    }
    a.angle_between(b)
}

/// Distance between segments `p0 p1` and `q0 q1`.
fn segment_segment(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let (s, t);
    if a <= f64::EPSILON && e <= f64::EPSILON {
        return r.length();
    }
    if a <= f64::EPSILON {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= f64::EPSILON {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let den = a * e - b * b;
            let s0 = if den > 0.0 {
                ((b * f - c * e) / den).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    ((p0 + d1 * s) - (q0 + d2 * t)).length()
}

struct Swapper<'a> {
    p: &'a [DVec3],
    faces: &'a mut Vec<[u32; 3]>,
    edge_faces: HashMap<u64, [u32; 2]>,
    locked: HashSet<u64>,
    cfg: SwapCfg,
}

/// The quad around an interior edge: `f = (u, v, w)` traverses u->v, `g = (v, u, x)`.
#[derive(Clone, Copy)]
struct Quad {
    u: u32,
    v: u32,
    w: u32,
    x: u32,
    f: u32,
    g: u32,
}

impl Swapper<'_> {
    fn new<'a>(p: &'a [DVec3], faces: &'a mut Vec<[u32; 3]>, cfg: SwapCfg) -> Swapper<'a> {
        let mut edge_faces: HashMap<u64, [u32; 2]> = HashMap::new();
        let mut bad = HashSet::new();
        for (fi, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let key = edge_key(f[k], f[(k + 1) % 3]);
                let e = edge_faces.entry(key).or_insert([u32::MAX; 2]);
                if e[0] == u32::MAX {
                    e[0] = fi as u32;
                } else if e[1] == u32::MAX {
                    e[1] = fi as u32;
                } else {
                    bad.insert(key);
                }
            }
        }
        // Non-manifold edges are never swapped.
        Swapper {
            p,
            faces,
            edge_faces,
            locked: bad,
            cfg,
        }
    }

    fn pos(&self, i: u32) -> DVec3 {
        self.p[i as usize]
    }

    fn normal(&self, f: [u32; 3]) -> DVec3 {
        face_cross(self.pos(f[0]), self.pos(f[1]), self.pos(f[2])).normalize_or_zero()
    }

    /// The quad of interior edge `key`, if it is a consistently oriented manifold edge.
    fn quad(&self, key: u64) -> Option<Quad> {
        let [f, g] = *self.edge_faces.get(&key)?;
        if g == u32::MAX || self.locked.contains(&key) {
            return None;
        }
        let (a, b) = ((key >> 32) as u32, key as u32);
        let ff = self.faces[f as usize];
        let k = (0..3).find(|&k| {
            let (s, t) = (ff[k], ff[(k + 1) % 3]);
            (s == a && t == b) || (s == b && t == a)
        })?;
        let (u, v, w) = (ff[k], ff[(k + 1) % 3], ff[(k + 2) % 3]);
        let gg = self.faces[g as usize];
        let j = (0..3).find(|&j| gg[j] == v && gg[(j + 1) % 3] == u)?;
        let x = gg[(j + 2) % 3];
        (w != x).then_some(Quad { u, v, w, x, f, g })
    }

    /// The facet across edge `a b` from facet `inner`, if any.
    fn across(&self, a: u32, b: u32, inner: u32) -> Option<u32> {
        let e = self.edge_faces.get(&edge_key(a, b))?;
        let o = if e[0] == inner { e[1] } else { e[0] };
        (o != u32::MAX).then_some(o)
    }

    /// Common checks of a swap `u v -> w x` (Rules 1-3, validity of the new facets).
    fn swap_valid(&self, q: &Quad) -> bool {
        let (pu, pv, pw, px) = (self.pos(q.u), self.pos(q.v), self.pos(q.w), self.pos(q.x));
        if (pw - px).length() > self.cfg.omega || self.edge_faces.contains_key(&edge_key(q.w, q.x))
        {
            return false;
        }
        if min_angle(pu, px, pw) <= self.cfg.min_angle
            || min_angle(px, pv, pw) <= self.cfg.min_angle
        {
            return false;
        }
        let (n1, n2) = (self.normal([q.u, q.x, q.w]), self.normal([q.x, q.v, q.w]));
        let avg = self.normal([q.u, q.v, q.w]) + self.normal([q.v, q.u, q.x]);
        n1.dot(n2) > 0.0 && n1.dot(avg) > 0.0 && n2.dot(avg) > 0.0
    }

    /// ABN cost of the quad with the old (`swapped = false`) or the new diagonal.
    fn abn(&self, q: &Quad, swapped: bool) -> f64 {
        let (fa, fb) = if swapped {
            ([q.u, q.x, q.w], [q.x, q.v, q.w])
        } else {
            ([q.u, q.v, q.w], [q.v, q.u, q.x])
        };
        let (na, nb) = (self.normal(fa), self.normal(fb));
        // Sides u-x, x-v, v-w, w-u and the facet that holds each in this configuration.
        let side = |a: u32, b: u32, old_inner: u32| -> f64 {
            let Some(o) = self.across(a, b, old_inner) else {
                return 0.0;
            };
            let inner = if fa.contains(&a) && fa.contains(&b) {
                na
            } else {
                nb
            };
            angle(inner, self.normal(self.faces[o as usize]))
        };
        angle(na, nb)
            + side(q.u, q.x, q.g)
            + side(q.x, q.v, q.g)
            + side(q.v, q.w, q.f)
            + side(q.w, q.u, q.f)
    }

    /// Performs the swap; returns the four side edges.
    fn swap(&mut self, q: &Quad) -> [u64; 4] {
        self.faces[q.f as usize] = [q.u, q.x, q.w];
        self.faces[q.g as usize] = [q.x, q.v, q.w];
        self.edge_faces.remove(&edge_key(q.u, q.v));
        self.edge_faces.insert(edge_key(q.w, q.x), [q.f, q.g]);
        let mut repl = |a: u32, b: u32, old: u32, new: u32| {
            if let Some(e) = self.edge_faces.get_mut(&edge_key(a, b)) {
                for s in e.iter_mut() {
                    if *s == old {
                        *s = new;
                    }
                }
            }
        };
        repl(q.u, q.x, q.g, q.f);
        repl(q.v, q.w, q.f, q.g);
        [
            edge_key(q.u, q.x),
            edge_key(q.x, q.v),
            edge_key(q.v, q.w),
            edge_key(q.w, q.u),
        ]
    }

    /// Runs swaps with a queue until none applies (or the cap); `accept` decides.
    fn run(&mut self, accept: &dyn Fn(&Self, &Quad) -> bool) -> usize {
        let mut keys: Vec<u64> = self.edge_faces.keys().copied().collect();
        keys.sort_unstable();
        let cap = CAP_PER_EDGE * keys.len().max(1);
        let mut queue: VecDeque<u64> = keys.into_iter().collect();
        let (mut swaps, mut tries) = (0usize, 0usize);
        while let Some(key) = queue.pop_front() {
            tries += 1;
            if tries > cap {
                break;
            }
            let Some(q) = self.quad(key) else {
                continue;
            };
            if self.swap_valid(&q) && accept(self, &q) {
                queue.extend(self.swap(&q));
                swaps += 1;
            }
        }
        swaps
    }
}

/// Applies E21 (when `align`) and then E20 (when `equilateral`) to `faces` in place.
pub fn enhance(
    p: &[DVec3],
    faces: &mut Vec<[u32; 3]>,
    cfg: &SwapCfg,
    align: bool,
    equilateral: bool,
) -> SwapStats {
    let mut st = SwapStats::default();
    let mut sw = Swapper::new(p, faces, *cfg);
    if align {
        // ASSUMPTION E21: swap when the ABN cost drops by more than 1e-3 rad.
        st.feature_swaps = sw.run(&|s, q| s.abn(q, false) - s.abn(q, true) > ABN_MIN_GAIN);
        // Then lock the feature edges (dihedral above the feature angle).
        let mut keys: Vec<u64> = sw.edge_faces.keys().copied().collect();
        keys.sort_unstable();
        for key in keys {
            let [f, g] = sw.edge_faces[&key];
            if g != u32::MAX {
                let (nf, ng) = (
                    sw.normal(sw.faces[f as usize]),
                    sw.normal(sw.faces[g as usize]),
                );
                if angle(nf, ng) > cfg.feature_angle {
                    sw.locked.insert(key);
                    st.feature_edges += 1;
                }
            }
        }
    }
    if equilateral {
        // ASSUMPTION E20: constrained 3-D Lawson swap.
        let slack = E20_DIHEDRAL_SLACK_DEG.to_radians();
        st.equilateral_swaps = sw.run(&|s, q| {
            let (pu, pv, pw, px) = (s.pos(q.u), s.pos(q.v), s.pos(q.w), s.pos(q.x));
            let old = min_angle(pu, pv, pw).min(min_angle(pv, pu, px));
            let new = min_angle(pu, px, pw).min(min_angle(px, pv, pw));
            let old_d = angle(s.normal([q.u, q.v, q.w]), s.normal([q.v, q.u, q.x]));
            let new_d = angle(s.normal([q.u, q.x, q.w]), s.normal([q.x, q.v, q.w]));
            new > old && segment_segment(pu, pv, pw, px) <= s.cfg.eps && new_d <= old_d + slack
        });
    }
    st
}
