//! Average-linkage agglomerative clustering of unoriented unit normals ("lines") with a
//! distance cut, the core of the Gauss-map detectors (seed 002 §3.5).
//!
//! Distance between two lines with unit directions `a`, `b` (seed 002 eq. 3.4 and §1.5):
//! `d(a, b) = atan2(|a x b|, |a . b|)`, the angle between the lines, in `[0, pi/2]`. It is
//! the minimum of the geodesic distances from `a` to `b` and to `-b`, so clustering the
//! `L = k(k-1)/2` unordered-pair normals is exactly equivalent to clustering the
//! `k(k-1)` ordered ones of the thesis with every size doubled (seed 002 §3.2).
//!
//! Linkage (eq. 3.5): `D(S1, S2)` = mean pairwise distance. Merging stops as soon as the
//! smallest inter-cluster distance exceeds `sigma`, i.e. every merge at a distance
//! `<= sigma` is done. Average linkage is reducible, so this equals cutting the dendrogram
//! at `sigma`.
//!
//! Algorithm: nearest-neighbour chain with the Lance-Williams update
//! `D(A u B, C) = (|A| D(A, C) + |B| D(B, C)) / (|A| + |B|)` over a dense `L x L` matrix,
//! `O(L^2)` time per call (`O(k^4)` in the neighbourhood size). Pruning: when the top of the
//! chain has no active cluster within `sigma`, no cluster of the chain can ever merge at a
//! distance `<= sigma` again (reducibility: a merged cluster is never closer than the
//! nearer of its parts), so the whole chain is retired at once. Ties are broken towards
//! the previous chain element, then the lowest index, so results are deterministic.
//!
//! All buffers live in [`AverageLinkage`] and are reused between calls: create one per
//! thread (rayon `map_init`) and the hot loop does not allocate once the buffers have
//! grown to the largest neighbourhood.

use glam::DVec3;

/// Angle between the unoriented lines spanned by the **unit** vectors `a` and `b`, in
/// `[0, pi/2]`: `acos(|a . b|)`, switching to `asin(|a x b|)` when `|a . b| > 0.99`
/// where `acos` loses accuracy (seed 002 §1.5 recommends `atan2(|a x b|, |a . b|)`; all
/// three are the same value). The small-angle branch (angles below 0.1415 rad, the most
/// common case on smooth and flat neighbourhoods) evaluates `asin` by its Taylor series
/// to the 17th power, whose truncation error is below 1e-17 relative there: about
/// three times faster than `atan2`, which dominated the clustering's profile.
#[inline]
pub fn line_distance(a: DVec3, b: DVec3) -> f64 {
    let c = a.dot(b).abs();
    if c < 0.99 {
        c.acos()
    } else {
        small_asin(a.cross(b).length().min(1.0))
    }
}

/// `asin(x)` for `0 <= x <= 0.1415` (`sqrt(1 - 0.99^2)`) by its Taylor series
/// `sum (2n)! / (4^n (n!)^2 (2n + 1)) x^(2n+1)`, n = 0..=8 (Horner in `x^2`).
#[inline]
fn small_asin(x: f64) -> f64 {
    const C: [f64; 9] = [
        1.0,
        1.0 / 6.0,
        3.0 / 40.0,
        5.0 / 112.0,
        35.0 / 1152.0,
        63.0 / 2816.0,
        231.0 / 13312.0,
        143.0 / 10240.0,
        6435.0 / 557056.0,
    ];
    let x2 = x * x;
    let mut p = C[8];
    for &c in C[..8].iter().rev() {
        p = p * x2 + c;
    }
    x * p
}

/// Reusable workspace for average-linkage clustering of lines (see the module docs).
#[derive(Debug, Default, Clone)]
pub struct AverageLinkage {
    /// Number of items of the current matrix.
    n: usize,
    /// Dense symmetric `n x n` distance matrix, row-major; overwritten by merges.
    dist: Vec<f64>,
    /// Cluster size per representative index.
    size: Vec<u32>,
    /// Whether a representative can still merge.
    active: Vec<bool>,
    /// The nearest-neighbour chain.
    chain: Vec<usize>,
    /// Sizes of the final clusters of the last [`AverageLinkage::cut`].
    finals: Vec<u32>,
    /// Union-find parents of [`AverageLinkage::count_big`] (sigma-linked components).
    parent: Vec<u32>,
    /// Items of the component being clustered.
    members: Vec<usize>,
    /// Item order grouped by component root.
    order: Vec<(u32, u32)>,
    /// Directions of the component being clustered.
    sub: Vec<DVec3>,
}

impl AverageLinkage {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of items loaded by [`AverageLinkage::load`].
    pub fn len(&self) -> usize {
        self.n
    }

    /// True when no items are loaded.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Loads unit line directions and fills the pairwise [`line_distance`] matrix
    /// (`L(L-1)/2` distance evaluations). The diagonal holds `+inf`.
    pub fn load(&mut self, lines: &[DVec3]) {
        let n = lines.len();
        self.n = n;
        self.dist.clear();
        self.dist.resize(n * n, f64::INFINITY);
        for i in 0..n {
            let a = lines[i];
            for j in i + 1..n {
                let d = line_distance(a, lines[j]);
                self.dist[i * n + j] = d;
                self.dist[j * n + i] = d;
            }
        }
    }

    /// Index of the medoid of the loaded lines: the item with the smallest sum of
    /// distances to all others (lowest index on ties). `None` when empty. Valid only
    /// between [`AverageLinkage::load`] and [`AverageLinkage::cut`] (the cut overwrites
    /// the matrix).
    pub fn medoid(&self) -> Option<usize> {
        let n = self.n;
        (0..n)
            .map(|i| (i, (0..n).map(|j| self.distance(i, j)).sum::<f64>()))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
            .map(|(i, _)| i)
    }

    /// Distance between loaded items `i` and `j` (0 for `i == j`; before a cut).
    pub fn distance(&self, i: usize, j: usize) -> f64 {
        if i == j {
            0.0
        } else {
            self.dist[i * self.n + j]
        }
    }

    /// Marks `x` as unable to merge: its column becomes `+inf`, so row scans skip it.
    fn deactivate(&mut self, x: usize) {
        let n = self.n;
        self.active[x] = false;
        for c in 0..n {
            self.dist[c * n + x] = f64::INFINITY;
        }
    }

    /// Clusters the loaded lines, merging while the smallest average-linkage distance is
    /// `<= sigma`, and returns the sizes of the final clusters (in the order they were
    /// closed; use them as a multiset). Destroys the matrix (load again to re-cut).
    ///
    /// Inactive clusters (merged away or retired) and the diagonal are `+inf` in the
    /// matrix, so the nearest-neighbour search is a branch-light minimum over one row.
    pub fn cut(&mut self, sigma: f64) -> &[u32] {
        let n = self.n;
        self.finals.clear();
        self.size.clear();
        self.size.resize(n, 1);
        self.active.clear();
        self.active.resize(n, true);
        self.chain.clear();
        let mut n_active = n;
        let mut next_start = 0usize;
        while n_active > 0 {
            if self.chain.is_empty() {
                while !self.active[next_start] {
                    next_start += 1;
                }
                self.chain.push(next_start);
            }
            let len = self.chain.len();
            let a = self.chain[len - 1];
            let prev = if len >= 2 {
                Some(self.chain[len - 2])
            } else {
                None
            };
            let row = &self.dist[a * n..(a + 1) * n];
            // Prefer the previous chain element on ties (guarantees termination), then
            // the lowest index.
            let (mut best, mut bd) = match prev {
                Some(p) => (p, row[p]),
                None => (usize::MAX, f64::INFINITY),
            };
            for (c, &d) in row.iter().enumerate() {
                if d < bd {
                    best = c;
                    bd = d;
                }
            }
            if best == usize::MAX || bd > sigma {
                // Nothing within sigma of the top, hence of any chain element: retire all.
                for i in 0..self.chain.len() {
                    let x = self.chain[i];
                    self.finals.push(self.size[x]);
                    self.deactivate(x);
                }
                n_active -= self.chain.len();
                self.chain.clear();
                continue;
            }
            if Some(best) == prev {
                self.chain.truncate(len - 2);
                let (keep, gone) = if a < best { (a, best) } else { (best, a) };
                let sk = f64::from(self.size[keep]);
                let sg = f64::from(self.size[gone]);
                let inv = 1.0 / (sk + sg);
                for c in 0..n {
                    let dk = self.dist[keep * n + c];
                    let dg = self.dist[gone * n + c];
                    // Both finite <=> c is active and differs from keep and gone.
                    if dk.is_finite() && dg.is_finite() {
                        let v = (sk * dk + sg * dg) * inv;
                        self.dist[keep * n + c] = v;
                        self.dist[c * n + keep] = v;
                    }
                }
                self.size[keep] += self.size[gone];
                self.deactivate(gone);
                n_active -= 1;
            } else {
                self.chain.push(best);
            }
        }
        &self.finals
    }
}

impl AverageLinkage {
    /// Number of final clusters with at least `min_size` items when `lines` are
    /// clustered with cut `sigma`: the same value as counting the sizes returned by
    /// [`AverageLinkage::load`] + [`AverageLinkage::cut`], computed faster.
    ///
    /// Exact pruning: the average-linkage distance of two clusters is at least the
    /// smallest distance between their members, so clusters never merge across the
    /// connected components of the graph "line distance <= sigma" (single linkage at
    /// sigma). The components come from cheap dot products (`|a . b| >= cos sigma`, with
    /// a margin that can only join components, never split one); a component with fewer
    /// than `min_size` items can only yield dropped clusters and is skipped; the others
    /// are clustered one by one, so the `acos` matrix is built only inside components.
    /// Leaves the workspace's matrix holding the last component (not the input).
    pub fn count_big(&mut self, lines: &[DVec3], sigma: f64, min_size: usize) -> usize {
        let l = lines.len();
        if l == 0 {
            return 0;
        }
        let min_size = min_size.max(1);
        // Margin on the safe side: a pair whose true angle is <= sigma is always linked.
        let cos_s = sigma.min(std::f64::consts::FRAC_PI_2).cos() - 1e-12;
        self.parent.clear();
        self.parent.extend(0..l as u32);
        fn find(parent: &mut [u32], mut x: u32) -> u32 {
            while parent[x as usize] != x {
                let p = parent[x as usize];
                parent[x as usize] = parent[p as usize];
                x = p;
            }
            x
        }
        let mut components = l;
        'pairs: for i in 0..l {
            let a = lines[i];
            for (j, b) in lines.iter().enumerate().skip(i + 1) {
                if a.dot(*b).abs() >= cos_s {
                    let (ri, rj) = (
                        find(&mut self.parent, i as u32),
                        find(&mut self.parent, j as u32),
                    );
                    if ri != rj {
                        // Lower root wins: deterministic.
                        let (lo, hi) = if ri < rj { (ri, rj) } else { (rj, ri) };
                        self.parent[hi as usize] = lo;
                        components -= 1;
                        if components == 1 {
                            break 'pairs;
                        }
                    }
                }
            }
        }
        if components == 1 {
            // One component (typical of smooth regions): cluster the input directly.
            if l < min_size {
                return 0;
            }
            self.load(lines);
            return self
                .cut(sigma)
                .iter()
                .filter(|&&s| s as usize >= min_size)
                .count();
        }
        self.order.clear();
        for i in 0..l as u32 {
            let r = find(&mut self.parent, i);
            self.order.push((r, i));
        }
        self.order.sort_unstable();
        let mut big = 0usize;
        let mut start = 0usize;
        while start < l {
            let root = self.order[start].0;
            let mut end = start;
            while end < l && self.order[end].0 == root {
                end += 1;
            }
            if end - start >= min_size {
                self.members.clear();
                self.members
                    .extend(self.order[start..end].iter().map(|&(_, i)| i as usize));
                let mut sub = std::mem::take(&mut self.sub);
                sub.clear();
                sub.extend(self.members.iter().map(|&i| lines[i]));
                self.load(&sub);
                self.sub = sub;
                big += self
                    .cut(sigma)
                    .iter()
                    .filter(|&&s| s as usize >= min_size)
                    .count();
            }
            start = end;
        }
        big
    }
}

/// Reference implementation: repeatedly merges the globally closest pair of clusters
/// (average linkage, lowest index pair on ties) while its distance is `<= sigma`.
/// `O(L^3)`; for tests and small inputs only. Returns the cluster sizes, sorted
/// descending.
pub fn average_linkage_naive(lines: &[DVec3], sigma: f64) -> Vec<u32> {
    let mut clusters: Vec<Vec<usize>> = (0..lines.len()).map(|i| vec![i]).collect();
    loop {
        let mut best: Option<(usize, usize, f64)> = None;
        for i in 0..clusters.len() {
            for j in i + 1..clusters.len() {
                let mut s = 0.0;
                for &a in &clusters[i] {
                    for &b in &clusters[j] {
                        s += line_distance(lines[a], lines[b]);
                    }
                }
                let d = s / (clusters[i].len() * clusters[j].len()) as f64;
                if best.is_none_or(|(_, _, bd)| d < bd) {
                    best = Some((i, j, d));
                }
            }
        }
        match best {
            Some((i, j, d)) if d <= sigma => {
                let b = clusters.remove(j);
                clusters[i].extend(b);
            }
            _ => break,
        }
    }
    let mut sizes: Vec<u32> = clusters.iter().map(|c| c.len() as u32).collect();
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64) / ((1u64 << 53) as f64)
    }

    fn random_dir(state: &mut u64) -> DVec3 {
        loop {
            let v = DVec3::new(
                lcg(state) * 2.0 - 1.0,
                lcg(state) * 2.0 - 1.0,
                lcg(state) * 2.0 - 1.0,
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }

    #[test]
    fn small_angle_series_matches_atan2() {
        let mut st = 99u64;
        for _ in 0..20000 {
            let a = random_dir(&mut st);
            let t = lcg(&mut st) * 0.14;
            let perp = a.any_orthonormal_vector();
            let b = (a * t.cos() + perp * t.sin()).normalize();
            let want = a.cross(b).length().atan2(a.dot(b).abs());
            let got = line_distance(a, b);
            assert!(
                (got - want).abs() <= 4.0 * f64::EPSILON * want.max(1e-300),
                "{t}: {got} vs {want}"
            );
        }
        assert_eq!(line_distance(DVec3::Z, DVec3::Z), 0.0);
    }

    #[test]
    fn line_distance_is_unoriented_angle() {
        let a = DVec3::X;
        for t in [1e-9f64, 1e-4, 0.1, 0.14, 0.15, 0.5, 1.0, 1.5] {
            let b = DVec3::new(t.cos(), t.sin(), 0.0);
            assert!((line_distance(a, b) - t).abs() < 1e-12, "{t}");
            assert!((line_distance(a, -b) - t).abs() < 1e-12, "{t}");
        }
        assert_eq!(line_distance(a, a), 0.0);
        assert_eq!(line_distance(a, -a), 0.0);
        assert!((line_distance(a, DVec3::Y) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        let b = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!((line_distance(a, b) - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
        assert!((line_distance(-a, b) - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    }

    #[test]
    fn nn_chain_matches_naive_on_random_and_clustered_data() {
        let mut st = 12345u64;
        let mut ws = AverageLinkage::new();
        for trial in 0..60 {
            let n = 2 + trial % 37;
            // Mixture: a few centres with jitter plus uniform noise.
            let centres: Vec<DVec3> = (0..1 + trial % 4).map(|_| random_dir(&mut st)).collect();
            let lines: Vec<DVec3> = (0..n)
                .map(|i| {
                    if i % 3 == 0 {
                        random_dir(&mut st)
                    } else {
                        let c = centres[i % centres.len()];
                        (c + 0.15 * random_dir(&mut st)).normalize()
                    }
                })
                .collect();
            for &sigma in &[0.0, 0.05, 0.2, 0.6, 1.0, 2.0] {
                ws.load(&lines);
                let mut got = ws.cut(sigma).to_vec();
                got.sort_unstable_by(|a, b| b.cmp(a));
                let want = average_linkage_naive(&lines, sigma);
                assert_eq!(got, want, "trial {trial} n {n} sigma {sigma}");
                assert_eq!(got.iter().sum::<u32>() as usize, n);
            }
        }
    }

    #[test]
    fn component_pruning_counts_like_the_full_cut() {
        let mut st = 777u64;
        let mut full = AverageLinkage::new();
        let mut fast = AverageLinkage::new();
        for trial in 0..80 {
            let n = 3 + trial % 61;
            let centres: Vec<DVec3> = (0..1 + trial % 5).map(|_| random_dir(&mut st)).collect();
            let spread = [0.02, 0.1, 0.3][trial % 3];
            let lines: Vec<DVec3> = (0..n)
                .map(|i| {
                    if i % 4 == 0 {
                        random_dir(&mut st)
                    } else {
                        let c = centres[i % centres.len()];
                        (c + spread * random_dir(&mut st)).normalize()
                    }
                })
                .collect();
            for &sigma in &[0.0, 0.05, 0.1, 0.3, 0.6, 1.2, std::f64::consts::FRAC_PI_2] {
                for min_size in [1usize, 3, 6, 12] {
                    full.load(&lines);
                    let want = full
                        .cut(sigma)
                        .iter()
                        .filter(|&&s| s as usize >= min_size)
                        .count();
                    let got = fast.count_big(&lines, sigma, min_size);
                    assert_eq!(
                        got, want,
                        "trial {trial} n {n} sigma {sigma} min {min_size}"
                    );
                }
            }
        }
        // Exact duplicates and an empty input.
        let dup = vec![DVec3::Z; 9];
        assert_eq!(fast.count_big(&dup, 0.0, 9), 1);
        assert_eq!(fast.count_big(&dup, 0.0, 10), 0);
        assert_eq!(fast.count_big(&[], 0.3, 1), 0);
    }

    #[test]
    fn two_perpendicular_bundles_stay_apart() {
        let mut lines = vec![DVec3::Z; 10];
        lines.extend(std::iter::repeat_n(DVec3::X, 7));
        let mut ws = AverageLinkage::new();
        ws.load(&lines);
        let mut s = ws.cut(0.6).to_vec();
        s.sort_unstable();
        assert_eq!(s, vec![7, 10]);
        ws.load(&lines);
        assert_eq!(ws.cut(1.6).to_vec(), vec![17]);
    }

    #[test]
    fn empty_and_single() {
        let mut ws = AverageLinkage::new();
        ws.load(&[]);
        assert!(ws.cut(0.5).is_empty());
        assert_eq!(ws.medoid(), None);
        ws.load(&[DVec3::Y]);
        assert_eq!(ws.cut(0.5), &[1]);
    }

    #[test]
    fn medoid_is_central() {
        let lines = [
            DVec3::X,
            DVec3::new(1.0, 0.1, 0.0).normalize(),
            DVec3::new(1.0, 0.2, 0.0).normalize(),
        ];
        let mut ws = AverageLinkage::new();
        ws.load(&lines);
        assert_eq!(ws.medoid(), Some(1));
    }
}
