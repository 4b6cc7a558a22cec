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

use super::mesher::{Mesher, tri_normal};

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
        while l.len() > 3 {
            let k = l.len();
            // Best ear: largest smallest angle, diagonal not yet an edge.
            let mut best: Option<(f64, usize)> = None;
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
                if q.is_finite() && best.is_none_or(|(bq, _)| q < bq) {
                    best = Some((q, i));
                }
            }
            let Some((_, i)) = best else {
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

/// Cosine of the smallest angle of triangle `(p, q, r)` (NaN when degenerate); smaller
/// is better.
fn min_angle_cos(p: DVec3, q: DVec3, r: DVec3) -> f64 {
    let c = |x: DVec3, y: DVec3, z: DVec3| {
        let (u, v) = (y - x, z - x);
        let d = (u.length_squared() * v.length_squared()).sqrt();
        if d > 0.0 { u.dot(v) / d } else { f64::NAN }
    };
    let (a, b, cc) = (c(p, q, r), c(q, r, p), c(r, p, q));
    if a.is_nan() || b.is_nan() || cc.is_nan() || (q - p).cross(r - p).length_squared() == 0.0 {
        return f64::NAN;
    }
    a.max(b).max(cc)
}
