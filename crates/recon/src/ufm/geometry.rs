//! Geometric validity of an umbrella (not in the thesis's pseudo-code; see the fold
//! repair in `docs/methods/ufm.md`): the *fold angle* at a rib `v—p` is the angle
//! between the normals of the two umbrella facets that share the rib, both oriented by
//! the umbrella's cyclic order. A flat fan has fold angles near 0; an umbrella that
//! folds back over itself (e.g. the three faces at a corner of a flat "sliver"
//! tetrahedron) has fold angles near π.

use glam::DVec3;

/// Fold angles (radians) of the umbrella of `v` given by its ring `p_1..p_k` in cyclic
/// order (facets `(v, p_j, p_{j+1})`): entry `j` is the angle at rib `v—p_{j+1}`
/// between facets `j` and `j+1`. Degenerate facets (zero normal) give angle 0.
pub fn fold_angles(pts: &[DVec3], v: u32, ring: &[u32], out: &mut Vec<f64>) {
    out.clear();
    let k = ring.len();
    if k < 3 {
        return;
    }
    let c = pts[v as usize];
    let normal = |j: usize| {
        let a = pts[ring[j % k] as usize] - c;
        let b = pts[ring[(j + 1) % k] as usize] - c;
        a.cross(b).normalize_or_zero()
    };
    let mut prev = normal(0);
    for j in 0..k {
        let next = normal(j + 1);
        let d = prev.dot(next);
        out.push(if prev == DVec3::ZERO || next == DVec3::ZERO {
            0.0
        } else {
            d.clamp(-1.0, 1.0).acos()
        });
        prev = next;
    }
}

/// The ring `p_1..p_k` of an umbrella given by the rim edges `(a, b)` of its facets
/// `(v, a, b)` (a handful of pairs), walked in cyclic order. Returns `false` (and an
/// empty ring) when the pairs are not one simple cycle.
pub fn ring_from_pairs(pairs: &[(u32, u32)], ring: &mut Vec<u32>) -> bool {
    ring.clear();
    let k = pairs.len();
    if k < 3 {
        return false;
    }
    let (first, mut cur) = pairs[0];
    ring.push(first);
    let mut prev_edge = 0usize;
    while cur != first {
        if ring.len() == k || ring.contains(&cur) {
            ring.clear();
            return false;
        }
        ring.push(cur);
        let next = (0..k).find(|&e| e != prev_edge && (pairs[e].0 == cur || pairs[e].1 == cur));
        let Some(e) = next else {
            ring.clear();
            return false;
        };
        cur = if pairs[e].0 == cur {
            pairs[e].1
        } else {
            pairs[e].0
        };
        prev_edge = e;
    }
    if ring.len() != k {
        ring.clear();
        return false;
    }
    true
}

/// Largest fold angle of the umbrella of `v` with ring `ring` (0 for < 3 nodes).
pub fn max_fold(pts: &[DVec3], v: u32, ring: &[u32], buf: &mut Vec<f64>) -> f64 {
    fold_angles(pts, v, ring, buf);
    buf.iter().copied().fold(0.0, f64::max)
}

/// Test fixture: the origin and a regular unit hexagon around it in the plane z = 0
/// (the umbrella ring is points 1..=6).
#[cfg(test)]
pub(crate) fn hexagon_fan() -> Vec<DVec3> {
    let mut pts = vec![DVec3::ZERO];
    for j in 0..6 {
        let a = j as f64 * std::f64::consts::PI / 3.0;
        pts.push(DVec3::new(a.cos(), a.sin(), 0.0));
    }
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_fan_has_zero_folds_and_a_sliver_corner_folds_back() {
        let pts = hexagon_fan();
        let ring: Vec<u32> = (1..=6).collect();
        let mut f = Vec::new();
        fold_angles(&pts, 0, &ring, &mut f);
        assert_eq!(f.len(), 6);
        assert!(f.iter().all(|&x| x < 1e-9), "{f:?}");
        // Corner a of the flat tetrahedron a, b, c, d on a square (tiny lift of d):
        // the umbrella b-c-d of a folds back across the ribs a-b and a-d.
        let pts = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 1e-3),
        ];
        fold_angles(&pts, 0, &[1, 2, 3], &mut f);
        let big = f.iter().filter(|&&x| x > 3.0).count();
        assert_eq!(big, 2, "{f:?}");
    }

    #[test]
    fn rings_are_walked_from_unordered_pairs() {
        let mut r = Vec::new();
        assert!(ring_from_pairs(&[(1, 2), (3, 4), (2, 3), (4, 1)], &mut r));
        assert_eq!(r.len(), 4);
        for j in 0..4 {
            let (a, b) = (r[j], r[(j + 1) % 4]);
            assert!(
                [(1, 2), (3, 4), (2, 3), (4, 1)]
                    .iter()
                    .any(|&(x, y)| (x, y) == (a, b) || (y, x) == (a, b))
            );
        }
        // Two triangles are not one cycle; a path is not a cycle.
        assert!(!ring_from_pairs(
            &[(1, 2), (2, 3), (3, 1), (4, 5), (5, 6), (6, 4)],
            &mut r
        ));
        assert!(!ring_from_pairs(&[(1, 2), (2, 3), (3, 4)], &mut r));
        assert!(r.is_empty());
    }
}
