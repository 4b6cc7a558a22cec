//! Seed triangle selection (spec §4.2, Eqs. 2-6; ASSUMPTIONS A4-A9).

use glam::{DMat3, DVec3};
use reconbench_geom::linalg::sym_eigen3;

use super::cross::{inside_2d, plane_basis};
use super::density::knn;
use super::mesher::{FREE, Mesher};

/// Seed search settings.
#[derive(Debug, Clone)]
pub(crate) struct SeedCfg {
    /// Neighbours per patch (A5) = fan triangles (A6).
    pub n_nb: usize,
    /// Neighbour search radius (infinite for the first seed).
    pub rmax: f64,
    /// Maximum flatness score (IMPL-CHOICE I1; 1.0 disables).
    pub max_flatness: f64,
    /// Require all `n_nb` neighbours within `rmax` (IMPL-CHOICE I1, restarts only).
    pub full_patch: bool,
    /// Orient the seed away from this point (A9), when set.
    pub outward_from: Option<DVec3>,
}

/// A measured patch.
#[derive(Debug, Clone)]
struct Patch {
    centre: u32,
    flatness: f64,
    normal: DVec3,
    /// Neighbours sorted by (distance, index).
    nb: Vec<u32>,
}

impl Mesher<'_> {
    /// Builds and scores the patch around `c` (S2-S3); `None` if it has < 2 neighbours.
    fn patch(&self, c: u32, cfg: &SeedCfg, buf: &mut Vec<(f64, u32)>) -> Option<Patch> {
        let pc = self.pts[c as usize];
        let state = &self.state;
        // ASSUMPTION A5: the patch is the centre plus its n_nb nearest Free neighbours.
        knn(
            self.grid,
            self.pts,
            pc,
            cfg.n_nb,
            cfg.rmax,
            |i| i != c as usize && state[i] == FREE,
            buf,
        );
        if buf.len() < 2 || (cfg.full_patch && buf.len() < cfg.n_nb) {
            return None;
        }
        let nb: Vec<u32> = buf.iter().map(|x| x.1).collect();
        // ASSUMPTION A6: PCA plane, neighbours sorted by polar angle, fan triangles.
        let mut mean = pc;
        for &q in &nb {
            mean += self.pts[q as usize];
        }
        mean /= (nb.len() + 1) as f64;
        let mut cov = DMat3::ZERO;
        for p in std::iter::once(pc).chain(nb.iter().map(|&q| self.pts[q as usize])) {
            let d = p - mean;
            cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let normal = sym_eigen3(cov).ok()?.vectors[0];
        let (u, v) = plane_basis(normal);
        let mut ang: Vec<(f64, u32)> = nb
            .iter()
            .map(|&q| {
                let d = self.pts[q as usize] - pc;
                (d.dot(v).atan2(d.dot(u)), q)
            })
            .collect();
        ang.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let m = ang.len();
        let mut normals = Vec::with_capacity(m);
        for i in 0..m {
            let (q1, q2) = (ang[i].1, ang[(i + 1) % m].1);
            if m == 2 && i == 1 {
                break;
            }
            // Eq. (2)-(3): N_i = V_i1 x V_i2, normalised.
            let n = (self.pts[q1 as usize] - pc)
                .cross(self.pts[q2 as usize] - pc)
                .normalize_or_zero();
            if n != DVec3::ZERO {
                normals.push(n);
            }
        }
        if normals.is_empty() {
            return None;
        }
        // Eq. (4)-(5); ASSUMPTION A7: flatness = trace(Var) = mean |Nbar - N_i|^2.
        let nbar = normals.iter().copied().sum::<DVec3>() / normals.len() as f64;
        let flatness = normals
            .iter()
            .map(|&n| (nbar - n).length_squared())
            .sum::<f64>()
            / normals.len() as f64;
        Some(Patch {
            centre: c,
            flatness,
            normal,
            nb,
        })
    }

    /// S5-S6 (ASSUMPTION A8): the seed triangle of a patch, if any.
    fn seed_in(&self, p: &Patch) -> Option<[u32; 3]> {
        let c = p.centre;
        let pc = self.pts[c as usize];
        let (u, v) = plane_basis(p.normal);
        let proj = |i: u32| {
            let d = self.pts[i as usize] - pc;
            [d.dot(u), d.dot(v)]
        };
        let cos_alpha = self.cfg.cos_alpha;
        let angles_ok = |x: DVec3, y: DVec3, z: DVec3| {
            let ok = |a: DVec3, b: DVec3| {
                a.dot(b) >= cos_alpha * (a.length_squared() * b.length_squared()).sqrt()
            };
            ok(y - x, z - x) && ok(x - y, z - y) && ok(x - z, y - z)
        };
        let r = self.cfg.r;
        for &un in &p.nb {
            let pu = self.pts[un as usize];
            let mut best: Option<(f64, u32)> = None;
            for &w in &p.nb {
                if w == un {
                    continue;
                }
                let pw = self.pts[w as usize];
                let cr = (pu - pc).cross(pw - pc).length();
                if cr * 0.5 < 1e-12 * r * r || !angles_ok(pc, pu, pw) {
                    continue;
                }
                let tri = [proj(c), proj(un), proj(w)];
                // 2-D circumradius R = abc / (4 area).
                let (a2, b2, c2) = (
                    dist2(tri[0], tri[1]),
                    dist2(tri[1], tri[2]),
                    dist2(tri[2], tri[0]),
                );
                let area2 = ((tri[1][0] - tri[0][0]) * (tri[2][1] - tri[0][1])
                    - (tri[1][1] - tri[0][1]) * (tri[2][0] - tri[0][0]))
                    .abs();
                if area2 <= 0.0 {
                    continue;
                }
                let circ = (a2 * b2 * c2).sqrt() / (2.0 * area2);
                if best.is_some_and(|(bc, bw)| circ > bc || (circ == bc && w > bw)) {
                    continue;
                }
                let empty =
                    p.nb.iter()
                        .all(|&o| o == un || o == w || !inside_2d(tri, proj(o)));
                if empty {
                    best = Some((circ, w));
                }
            }
            if let Some((_, w)) = best {
                return Some([c, un, w]);
            }
        }
        None
    }

    /// S1-S7: tries the patches around `centres` from the flattest on and returns an
    /// oriented seed triangle.
    pub fn find_seed(&self, centres: &[u32], cfg: &SeedCfg) -> Option<[u32; 3]> {
        let mut buf = Vec::new();
        let mut patches: Vec<Patch> = centres
            .iter()
            .filter(|&&c| self.state[c as usize] == FREE)
            .filter_map(|&c| self.patch(c, cfg, &mut buf))
            .collect();
        // Eq. (6): flattest first (ties: lower centre index).
        patches.sort_by(|a, b| {
            a.flatness
                .total_cmp(&b.flatness)
                .then(a.centre.cmp(&b.centre))
        });
        for p in &patches {
            if p.flatness > cfg.max_flatness {
                break;
            }
            if let Some(mut tri) = self.seed_in(p) {
                let [a, b, c] = tri.map(|i| self.pts[i as usize]);
                let n = (b - a).cross(c - a);
                // ASSUMPTION A9: the seed normal points away from the cloud centroid.
                let flip = match cfg.outward_from {
                    Some(o) => n.dot((a + b + c) / 3.0 - o) < 0.0,
                    None => n.dot(p.normal) < 0.0,
                };
                if flip {
                    tri.swap(1, 2);
                }
                return Some(tri);
            }
        }
        None
    }
}

fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}
