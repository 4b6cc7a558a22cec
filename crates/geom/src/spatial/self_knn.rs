//! The kNN of every point of a set ([`knn_self_table`], [`knn_self_map`]) on a k-d tree
//! specialised for all-points queries.

use glam::DVec3;
use rayon::prelude::*;

#[cfg(doc)]
use super::PointIndex;
use super::checks::check_k;
use super::tables::KnnTable;
use crate::error::{GeomError, Result, check_finite};

/// One neighbour reported by [`knn_self_map`]: index, squared distance to the query and
/// the neighbour's position (so callers need not look it up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnnHit {
    /// Index of the point in the input slice.
    pub index: u32,
    /// Squared Euclidean distance to the query, `(q - p).length_squared()`.
    pub dist2: f64,
    /// The neighbour's position.
    pub point: DVec3,
}

/// Validates the input of the all-points kNN and returns the effective `k`.
fn self_knn_k(points: &[DVec3], k: usize, exclude_self: bool) -> Result<usize> {
    check_k(k)?;
    if points.is_empty() {
        return Err(GeomError::InvalidInput(
            "kNN of every point needs at least one point".to_string(),
        ));
    }
    if points.len() > u32::MAX as usize {
        return Err(GeomError::InvalidInput(format!(
            "{} points exceed the u32 index range",
            points.len()
        )));
    }
    check_finite("point", points)?;
    let n = points.len();
    let keff = if exclude_self { k.min(n - 1) } else { k.min(n) };
    if keff == 0 {
        return Err(GeomError::InvalidInput(
            "kNN excluding the point itself needs at least 2 points".to_string(),
        ));
    }
    Ok(keff)
}

/// The kNN of every point of `points` as a table in input order, rows sorted by
/// (squared distance, index); the same contract as [`PointIndex::knn_all`] without
/// building a [`PointIndex`].
///
/// Errors: `k == 0`, no points, a non-finite point (naming it), more than `u32::MAX`
/// points, or a clamped `k` of 0 (a single point with `exclude_self`).
pub fn knn_self_table(points: &[DVec3], k: usize, exclude_self: bool) -> Result<KnnTable> {
    let keff = self_knn_k(points, k, exclude_self)?;
    let n = points.len();
    let tree = SelfKnnTree::new(points);
    // Rows are computed in tree order (consecutive queries share tree nodes and
    // neighbours, so they hit the cache) and gathered back to input order. Each row is
    // independent of the others, so the result does not depend on the thread split.
    let mut sorted_idx = vec![0u32; n * keff];
    let mut sorted_d2 = vec![0.0; n * keff];
    sorted_idx
        .par_chunks_mut(keff)
        .zip(sorted_d2.par_chunks_mut(keff))
        .enumerate()
        .with_min_len(SELF_MIN_BATCH)
        .for_each_init(SelfScratch::default, |scratch, (slot, (ri, rd))| {
            let buf = tree.self_row(slot, keff, exclude_self, scratch);
            for (j, c) in buf.iter().enumerate() {
                ri[j] = c.index();
                rd[j] = c.dist2();
            }
        });
    let rank = tree.rank();
    let mut indices = vec![0u32; n * keff];
    let mut dist2 = vec![0.0; n * keff];
    indices
        .par_chunks_mut(keff)
        .zip(dist2.par_chunks_mut(keff))
        .enumerate()
        .for_each(|(i, (ri, rd))| {
            let r = rank[i] as usize * keff;
            ri.copy_from_slice(&sorted_idx[r..r + keff]);
            rd.copy_from_slice(&sorted_d2[r..r + keff]);
        });
    Ok(KnnTable {
        k: keff,
        indices,
        dist2,
    })
}

/// Computes `f(state, i, neighbours_of_i)` for every point `i` of `points`, in parallel,
/// and returns the values in input order, without materialising a neighbour table.
///
/// The neighbours are exactly the rows of [`knn_self_table`] with the same arguments
/// (the `k` nearest points by (squared distance, index), the point itself included
/// unless `exclude_self`, `k` clamped the same way), sorted the same way, with their
/// positions. `init` creates one scratch state per rayon work item (as in
/// `map_init`). The calls run in tree order, not index order; since each call only sees
/// its own row, the output does not depend on the order or the thread count.
///
/// Errors: as [`knn_self_table`].
pub fn knn_self_map<T, S, I, F>(
    points: &[DVec3],
    k: usize,
    exclude_self: bool,
    init: I,
    f: F,
) -> Result<Vec<T>>
where
    T: Copy + Send + Sync,
    I: Fn() -> S + Sync + Send,
    F: Fn(&mut S, usize, &[KnnHit]) -> T + Sync + Send,
{
    let keff = self_knn_k(points, k, exclude_self)?;
    let tree = SelfKnnTree::new(points);
    let in_tree_order: Vec<T> = (0..points.len())
        .into_par_iter()
        .with_min_len(SELF_MIN_BATCH)
        .map_init(
            || (init(), SelfScratch::default(), Vec::new()),
            |(state, scratch, hits), slot| {
                let buf = tree.self_row(slot, keff, exclude_self, scratch);
                hits.clear();
                hits.extend(buf.iter().map(|c| KnnHit {
                    index: c.index(),
                    dist2: c.dist2(),
                    point: tree.items[c.slot() as usize].0,
                }));
                f(state, tree.items[slot].1 as usize, hits)
            },
        )
        .collect();
    let rank = tree.rank();
    Ok(rank
        .par_iter()
        .map(|&r| in_tree_order[r as usize])
        .collect())
}

/// Points per leaf of [`SelfKnnTree`]. Measured with callgrind (`pf`, k = 16, 100k torus
/// points): 8 / 16 / 32 points per leaf cost 1.016 / 1 / 1.059 times the instructions.
const SELF_LEAF: usize = 16;

/// Fewest consecutive queries per rayon work item: each item starts with an empty leaf
/// cache, so tiny items would rebuild candidate lists their neighbours already built.
const SELF_MIN_BATCH: usize = 1024;

/// Points sampled to choose a node's split axis.
const SELF_AXIS_SAMPLE: usize = 256;

/// Subtrees with more points than this are built by two rayon tasks.
const SELF_PAR_BUILD: usize = 1 << 15;

/// Internal node of [`SelfKnnTree`] (pre-order layout: the left child follows its
/// parent, the right child is at `right`).
#[derive(Debug, Clone, Copy, Default)]
struct SelfNode {
    split: f64,
    right: u32,
    axis: u32,
    /// Smallest input index in the left / right subtree: lets a query skip a subtree
    /// whose points can only tie with its current k-th neighbour and would lose the tie
    /// (keeps exact duplicates from making every query visit every copy).
    left_min: u32,
    right_min: u32,
}

/// A candidate neighbour during a query: squared distance, input index and tree slot
/// packed into one integer whose order is the (distance, index) order of all neighbour
/// lists (a squared distance is never negative or NaN, and the bits of non-negative
/// floats order like the floats; the slot, last, never decides between two points since
/// indices are unique). One integer comparison replaces a float and an index comparison
/// in the insertion loop.
#[derive(Debug, Clone, Copy)]
struct Cand(u128);

impl Cand {
    #[inline]
    fn new(dist2: f64, index: u32, slot: u32) -> Self {
        Self(((dist2.to_bits() as u128) << 64) | ((index as u128) << 32) | slot as u128)
    }

    /// The key of "distance `dist2`, index `index`", below every slot.
    #[inline]
    fn floor(dist2: f64, index: u32) -> Self {
        Self::new(dist2, index, 0)
    }

    #[inline]
    fn dist2(self) -> f64 {
        f64::from_bits((self.0 >> 64) as u64)
    }

    #[inline]
    fn index(self) -> u32 {
        (self.0 >> 32) as u32
    }

    #[inline]
    fn slot(self) -> u32 {
        self.0 as u32
    }
}

/// A balanced k-d tree specialised for "the k nearest neighbours of every indexed point"
/// (used by [`knn_self_table`] and [`knn_self_map`]).
///
/// Why not kiddo for this: a kNN query must return the lowest indices among points tied
/// at the k-th distance, which kiddo does not guarantee (PointIndex pays an extra
/// neighbour and sometimes a radius query for it), and at 16 neighbours kiddo's query
/// cost about 8,700 instructions per point here. This tree orders candidates by
/// (distance, index) directly, prunes exactly (a subtree is skipped only when its lower
/// bound exceeds the k-th distance, or equals it and every index in it is larger), and
/// the queries run in tree order over points stored contiguously by leaf.
///
/// Median splits along the longest side of each node's bounding box; leaves hold at most
/// [`SELF_LEAF`] points. The shape depends only on the number of points, which is what
/// makes the pre-order node layout computable for the parallel build.
struct SelfKnnTree {
    /// Points with their input index, in tree order (leaves are contiguous ranges).
    items: Vec<(DVec3, u32)>,
    /// Internal nodes in pre-order.
    nodes: Vec<SelfNode>,
    /// Leaves in slot order, with their bounding boxes.
    leaves: Vec<SelfLeaf>,
    /// Per internal node, the id of the first leaf of its right subtree.
    right_leaf: Vec<u32>,
}

/// A leaf of [`SelfKnnTree`]: its slot range, bounding box and smallest input index.
#[derive(Debug, Clone, Copy)]
struct SelfLeaf {
    lo: u32,
    hi: u32,
    min_index: u32,
    bmin: DVec3,
    bmax: DVec3,
}

/// Slot ranges of the leaves of the subtree at `node` over slots `lo..hi`, appended in
/// order; `right_leaf[node]` gets the id of the first leaf of each node's right subtree.
fn self_leaf_ranges(
    nodes: &[SelfNode],
    node: usize,
    lo: usize,
    hi: usize,
    out: &mut Vec<(u32, u32)>,
    right_leaf: &mut [u32],
) {
    if hi - lo <= SELF_LEAF {
        out.push((lo as u32, hi as u32));
    } else {
        let mid = lo + (hi - lo) / 2;
        self_leaf_ranges(nodes, node + 1, lo, mid, out, right_leaf);
        right_leaf[node] = out.len() as u32;
        self_leaf_ranges(nodes, nodes[node].right as usize, mid, hi, out, right_leaf);
    }
}

/// Squared distance between the boxes `[amin, amax]` and `[bmin, bmax]` (0 if they
/// overlap).
#[inline]
fn box_gap2(amin: DVec3, amax: DVec3, bmin: DVec3, bmax: DVec3) -> f64 {
    (amin - bmax)
        .max(bmin - amax)
        .max(DVec3::ZERO)
        .length_squared()
}

/// Number of internal nodes of a [`SelfKnnTree`] over `len` points.
fn self_node_count(len: usize) -> usize {
    if len <= SELF_LEAF {
        0
    } else {
        let half = len / 2;
        1 + self_node_count(half) + self_node_count(len - half)
    }
}

/// Builds the subtree over `items` into `nodes` (its pre-order block, starting at
/// absolute index `base`); returns the smallest input index in the subtree.
fn self_build(items: &mut [(DVec3, u32)], nodes: &mut [SelfNode], base: usize) -> u32 {
    let len = items.len();
    if len <= SELF_LEAF {
        return items.iter().map(|it| it.1).min().unwrap_or(u32::MAX);
    }
    // The split axis is the longest side of the bounding box, taken over an even sample
    // of at most SELF_AXIS_SAMPLE points in large nodes; the axis only shapes the tree
    // (and so the speed), never the neighbours found.
    let step = (len / SELF_AXIS_SAMPLE).max(1);
    let (mut lo, mut hi) = (items[0].0, items[0].0);
    for it in items.iter().step_by(step) {
        lo = lo.min(it.0);
        hi = hi.max(it.0);
    }
    let ext = hi - lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = len / 2;
    // One comparator per axis: indexing the point by a run-time axis inside the
    // comparator cost 4 % of `pf`'s instructions.
    match axis {
        0 => items.select_nth_unstable_by(mid, |a, b| a.0.x.total_cmp(&b.0.x)),
        1 => items.select_nth_unstable_by(mid, |a, b| a.0.y.total_cmp(&b.0.y)),
        _ => items.select_nth_unstable_by(mid, |a, b| a.0.z.total_cmp(&b.0.z)),
    };
    let split = items[mid].0[axis];
    let n_left = self_node_count(mid);
    let (left_items, right_items) = items.split_at_mut(mid);
    let (this, rest) = nodes.split_at_mut(1);
    let (left_nodes, right_nodes) = rest.split_at_mut(n_left);
    let right = base + 1 + n_left;
    let (left_min, right_min) = if len > SELF_PAR_BUILD {
        rayon::join(
            || self_build(left_items, left_nodes, base + 1),
            || self_build(right_items, right_nodes, right),
        )
    } else {
        (
            self_build(left_items, left_nodes, base + 1),
            self_build(right_items, right_nodes, right),
        )
    };
    this[0] = SelfNode {
        split,
        right: right as u32,
        axis: axis as u32,
        left_min,
        right_min,
    };
    left_min.min(right_min)
}

/// Query state: the candidates so far, `best[..len]` sorted ascending, and the current
/// k-th one (`worst`; until there are k candidates, the starting bound with the largest
/// index and slot).
struct SelfQuery<'a> {
    len: usize,
    best: &'a mut [Cand],
    worst: Cand,
}

impl<'a> SelfQuery<'a> {
    /// An empty query for `best.len()` neighbours among the points within squared
    /// distance `start` (infinite for no bound).
    fn new(best: &'a mut [Cand], start: f64) -> Self {
        Self {
            len: 0,
            best,
            worst: Cand::new(start, u32::MAX, u32::MAX),
        }
    }

    /// Whether a subtree with lower bound `bound` and smallest index `min_index` can
    /// still contribute: its best possible key must precede the k-th candidate's.
    #[inline]
    fn may_enter(&self, bound: f64, min_index: u32) -> bool {
        Cand::floor(bound, min_index).0 < (self.worst.0 & !(u32::MAX as u128))
    }

    /// Offers the points of one leaf (at most [`SELF_LEAF`], starting at tree slot
    /// `lo`) to the query at `q`. The distances come first, then only the points within
    /// the current bound are offered: that filter is branch-free, so its unpredictable
    /// outcome costs no misprediction.
    #[inline]
    fn offer_leaf(&mut self, q: DVec3, pts: &[(DVec3, u32)], lo: usize) {
        let w = self.worst.dist2();
        let mut d2s = [0.0f64; SELF_LEAF];
        let mut pass = [0u8; SELF_LEAF];
        let mut m = 0;
        for (s, it) in pts.iter().enumerate() {
            // Same expression as everywhere else in this module, so distances (and
            // therefore ties) agree bit for bit with PointIndex and brute force.
            let d2 = (q - it.0).length_squared();
            d2s[s] = d2;
            pass[m] = s as u8;
            m += (d2 <= w) as usize;
        }
        for &s in &pass[..m] {
            let s = s as usize;
            self.offer(d2s[s], pts[s].1, (lo + s) as u32);
        }
    }

    #[inline]
    fn offer(&mut self, dist2: f64, index: u32, slot: u32) {
        let c = Cand::new(dist2, index, slot);
        if c.0 > self.worst.0 {
            return;
        }
        let k = self.best.len();
        let mut pos = if self.len < k {
            self.len += 1;
            self.len - 1
        } else {
            k - 1
        };
        while pos > 0 && self.best[pos - 1].0 > c.0 {
            self.best[pos] = self.best[pos - 1];
            pos -= 1;
        }
        self.best[pos] = c;
        if self.len == k {
            self.worst = self.best[k - 1];
        }
    }
}

impl SelfKnnTree {
    fn new(points: &[DVec3]) -> Self {
        let mut items: Vec<(DVec3, u32)> = points
            .par_iter()
            .enumerate()
            .map(|(i, &p)| (p, i as u32))
            .collect();
        let mut nodes = vec![SelfNode::default(); self_node_count(points.len())];
        self_build(&mut items, &mut nodes, 0);
        let mut ranges = Vec::new();
        let mut right_leaf = vec![0u32; nodes.len()];
        if !items.is_empty() {
            self_leaf_ranges(&nodes, 0, 0, items.len(), &mut ranges, &mut right_leaf);
        }
        let leaves = ranges
            .par_iter()
            .map(|&(lo, hi)| {
                let pts = &items[lo as usize..hi as usize];
                let (mut bmin, mut bmax, mut min_index) = (pts[0].0, pts[0].0, u32::MAX);
                for it in pts {
                    bmin = bmin.min(it.0);
                    bmax = bmax.max(it.0);
                    min_index = min_index.min(it.1);
                }
                SelfLeaf {
                    lo,
                    hi,
                    min_index,
                    bmin,
                    bmax,
                }
            })
            .collect();
        Self {
            items,
            nodes,
            leaves,
            right_leaf,
        }
    }

    /// `rank[i]` = tree slot of input point `i`.
    fn rank(&self) -> Vec<u32> {
        let mut rank = vec![0u32; self.items.len()];
        for (slot, it) in self.items.iter().enumerate() {
            rank[it.1 as usize] = slot as u32;
        }
        rank
    }

    /// The `k` nearest points of `q` into `best` (resized to `k`), sorted by
    /// (squared distance, index). `k` must be in `1..=len`.
    ///
    /// `hint` is the previous query of the same `k` (its point and the distance of its
    /// k-th neighbour): by the triangle inequality its k neighbours all lie within
    /// `|q - p| + r` of `q`, so that radius (inflated far beyond rounding) bounds the
    /// search from the start without changing the result. Consecutive queries in tree
    /// order are neighbours, which makes the bound tight. Updated on return.
    fn knn(&self, q: DVec3, k: usize, best: &mut Vec<Cand>, hint: &mut Option<(DVec3, f64)>) {
        best.resize(k, Cand(0));
        let start = match *hint {
            Some((p, r)) => {
                let b = ((q - p).length() + r) * (1.0 + 1e-9);
                b * b
            }
            None => f64::INFINITY,
        };
        let mut st = SelfQuery::new(best, start);
        self.search(q, 0, 0, self.items.len(), [0.0; 3], &mut st);
        debug_assert_eq!(st.len, k);
        *hint = Some((q, best[k - 1].dist2().sqrt()));
    }

    fn search(
        &self,
        q: DVec3,
        node: usize,
        lo: usize,
        hi: usize,
        off: [f64; 3],
        st: &mut SelfQuery,
    ) {
        if hi - lo <= SELF_LEAF {
            for (s, &(p, index)) in self.items[lo..hi].iter().enumerate() {
                // Same expression as in `offer_leaf`, so distances (and therefore ties)
                // agree bit for bit with PointIndex and brute force.
                let d2 = (q - p).length_squared();
                st.offer(d2, index, (lo + s) as u32);
            }
            return;
        }
        let nd = self.nodes[node];
        let axis = nd.axis as usize;
        let diff = q[axis] - nd.split;
        let mid = lo + (hi - lo) / 2;
        let left = (node + 1, lo, mid, nd.left_min);
        let right = (nd.right as usize, mid, hi, nd.right_min);
        let (near, far) = if diff <= 0.0 {
            (left, right)
        } else {
            (right, left)
        };
        self.search(q, near.0, near.1, near.2, off, st);
        // Every point of the far side is at least |diff| away along `axis` (rounding is
        // monotone, so fl(|p - q|) >= fl(|split - q|)), and at least off[a] along the
        // other axes: the bound never exceeds a computed distance, so pruning is exact.
        let mut far_off = off;
        far_off[axis] = diff;
        let bound = far_off[0] * far_off[0] + far_off[1] * far_off[1] + far_off[2] * far_off[2];
        if st.may_enter(bound, far.3) {
            self.search(q, far.0, far.1, far.2, far_off, st);
        }
    }

    /// Row of tree slot `slot`: its `keff` nearest points (itself excluded when
    /// `exclude_self`), sorted by (squared distance, index).
    ///
    /// Queries of one leaf share one list of candidate leaves (see [`LeafCands`]), built
    /// when `slot` leaves the cached leaf; a leaf whose list would be too long (exact
    /// duplicates, very uneven density) queries the tree point by point instead.
    fn self_row<'s>(
        &self,
        slot: usize,
        keff: usize,
        exclude_self: bool,
        s: &'s mut SelfScratch,
    ) -> &'s [Cand] {
        let (p, i) = self.items[slot];
        let kq = if exclude_self { keff + 1 } else { keff };
        let l = &s.leaf;
        if !(l.lo <= slot && slot < l.hi && l.k == kq) {
            self.load_leaf(slot, kq, s);
        }
        if s.leaf.usable {
            self.scan_leaves(p, kq, &s.leaf, &mut s.order, &mut s.buf);
        } else {
            self.knn(p, kq, &mut s.buf, &mut s.hint);
        }
        if exclude_self {
            match s.buf.iter().position(|c| c.index() == i) {
                Some(j) => {
                    s.buf.remove(j);
                }
                None => s.buf.truncate(keff),
            }
        }
        &s.buf
    }

    /// Leaf id of tree slot `slot`.
    fn leaf_of(&self, slot: usize) -> usize {
        self.leaves.partition_point(|l| l.hi as usize <= slot)
    }

    /// Fills `s.leaf` with the candidate leaves of the leaf holding `slot` for `kq`-NN
    /// queries: every leaf within `rho + r_c` of its bounding box, where `c` is the leaf
    /// point nearest the box centre, `r_c` its exact `kq`-th neighbour distance and `rho`
    /// the largest distance from `c` to a leaf point. By the triangle inequality the `kq`
    /// nearest points of any leaf point `q` lie within `|q - c| + r_c <= rho + r_c` of
    /// `q`, so they are all in candidate leaves. Each query orders the list by its own
    /// distance to the leaves (see `scan_leaves`).
    fn load_leaf(&self, slot: usize, kq: usize, s: &mut SelfScratch) {
        let me = self.leaves[self.leaf_of(slot)];
        let leaf = &self.items[me.lo as usize..me.hi as usize];
        let mid = (me.bmin + me.bmax) * 0.5;
        let c = leaf
            .iter()
            .map(|it| it.0)
            .min_by(|a, b| {
                (*a - mid)
                    .length_squared()
                    .total_cmp(&(*b - mid).length_squared())
            })
            .unwrap_or(mid);
        self.knn(c, kq, &mut s.buf, &mut s.hint);
        let rc = s.buf[kq - 1].dist2().sqrt();
        let rho = leaf
            .iter()
            .map(|it| (it.0 - c).length())
            .fold(0.0, f64::max);
        // The same inflation as the query hint: far beyond rounding, so no needed point
        // is missed by a rounded comparison.
        let r = (rho + rc) * (1.0 + 1e-9);
        let l = &mut s.leaf;
        l.lo = me.lo as usize;
        l.hi = me.hi as usize;
        l.k = kq;
        l.c = c;
        l.rc = rc;
        l.ids.clear();
        let cap = LEAF_CANDS_BASE + kq.div_ceil(SELF_LEAF) * LEAF_CANDS_PER_K;
        l.usable = self.gather(0, 0, self.items.len(), 0, &me, r * r, cap, &mut l.ids);
        // The speculative bound of every leaf query is at most `t`, so its leaves are the
        // listed ones within `t` of the box.
        let t = spec_bound(rc, rho) * (1.0 + 1e-9);
        l.spec_ids.clear();
        if l.usable {
            l.spec_ids.extend(l.ids.iter().copied().filter(|&id| {
                let leaf = &self.leaves[id as usize];
                box_gap2(me.bmin, me.bmax, leaf.bmin, leaf.bmax) <= t * t
            }));
        }
    }

    /// Appends to `out` the id of every leaf of the subtree over slots `lo..hi`
    /// (whose first leaf has id `first`) within squared distance `r2` of leaf `me`'s
    /// box; false (and stops) once more than `cap` are found.
    #[allow(clippy::too_many_arguments)]
    fn gather(
        &self,
        node: usize,
        lo: usize,
        hi: usize,
        first: usize,
        me: &SelfLeaf,
        r2: f64,
        cap: usize,
        out: &mut Vec<u32>,
    ) -> bool {
        if hi - lo <= SELF_LEAF {
            let l = &self.leaves[first];
            if box_gap2(me.bmin, me.bmax, l.bmin, l.bmax) <= r2 {
                out.push(first as u32);
            }
            return out.len() <= cap;
        }
        let nd = self.nodes[node];
        let axis = nd.axis as usize;
        let mid = lo + (hi - lo) / 2;
        // Left points have coordinate <= split, right ones >= split.
        let (below, above) = (me.bmin[axis] - nd.split, nd.split - me.bmax[axis]);
        if (below <= 0.0 || below * below <= r2)
            && !self.gather(node + 1, lo, mid, first, me, r2, cap, out)
        {
            return false;
        }
        if above > 0.0 && above * above > r2 {
            return true;
        }
        let right_first = self.right_leaf[node] as usize;
        self.gather(nd.right as usize, mid, hi, right_first, me, r2, cap, out)
    }

    /// The `k` nearest points of leaf point `q` into `best`, sorted by (squared
    /// distance, index), from the candidate leaves `l` (see `load_leaf`), visited in
    /// order of their distance to `q` (`order` is scratch).
    fn scan_leaves(
        &self,
        q: DVec3,
        k: usize,
        l: &LeafCands,
        order: &mut Vec<(f64, u32)>,
        best: &mut Vec<Cand>,
    ) {
        best.resize(k, Cand(0));
        let dq = (q - l.c).length();
        let b = (dq + l.rc) * (1.0 + 1e-9);
        let b2 = b * b;
        // A tight speculative bound first: exact whenever k points lie within it (the k-th
        // distance is then no larger), which is the common case; otherwise the loose one.
        let t = spec_bound(l.rc, dq);
        let t2 = t * t;
        if t2 < b2 {
            self.order_leaves(q, t2, &l.spec_ids, order);
            if self.scan_ordered(q, t2, order, best) {
                return;
            }
        }
        self.order_leaves(q, b2, &l.ids, order);
        let full = self.scan_ordered(q, b2, order, best);
        debug_assert!(full);
    }

    /// The leaves `ids` within squared distance `b2` of `q` into `order`,
    /// nearest first: the k-th distance then falls fast, so fewer points are inserted and
    /// the far leaves are skipped. The order does not change the result.
    fn order_leaves(&self, q: DVec3, b2: f64, ids: &[u32], order: &mut Vec<(f64, u32)>) {
        order.clear();
        for &id in ids {
            let leaf = &self.leaves[id as usize];
            // The box distance never exceeds a computed point distance (rounding is
            // monotone), so skipping on it is exact.
            let bound = box_gap2(q, q, leaf.bmin, leaf.bmax);
            if bound <= b2 {
                order.push((bound, id));
            }
        }
        insertion_sort_by_key(order);
    }

    /// The `best.len()` nearest points of `q` among those of the leaves `order` (sorted
    /// by their box distance to `q`) within squared distance `b2`, into `best`; false
    /// when fewer lie within it.
    fn scan_ordered(&self, q: DVec3, b2: f64, order: &[(f64, u32)], best: &mut [Cand]) -> bool {
        let k = best.len();
        let mut st = SelfQuery::new(best, b2);
        for &(bound, id) in order {
            let leaf = &self.leaves[id as usize];
            if !st.may_enter(bound, leaf.min_index) {
                if bound > st.worst.dist2() {
                    break;
                }
                continue;
            }
            let (lo, hi) = (leaf.lo as usize, leaf.hi as usize);
            st.offer_leaf(q, &self.items[lo..hi], lo);
        }
        st.len == k
    }
}

/// The speculative bound of a leaf query, `SPEC_RC r_c + SPEC_OFFSET |q - c|`: it
/// holds the k nearest for most queries of an evenly sampled surface, and a query whose
/// k-th neighbour lies beyond it is simply rerun with the safe bound. Chosen by
/// instruction count (callgrind, `pf` k = 16, 100k torus points; 854 M against 898 M
/// without, the best of the (1.0-1.4) x (0-0.4) pairs tried); it never changes a result.
const SPEC_RC: f64 = 1.15;
const SPEC_OFFSET: f64 = 0.1;

/// The speculative bound for a query at distance `d` from `c`. One expression for the
/// queries and for the leaf's speculative list: it is monotone in `d`, so the bound at
/// the leaf radius is never below a query's.
#[inline]
fn spec_bound(rc: f64, d: f64) -> f64 {
    rc * SPEC_RC + d * SPEC_OFFSET
}

/// Sorts a short list by its first element (insertion sort: the lists hold a few dozen
/// entries).
fn insertion_sort_by_key(v: &mut [(f64, u32)]) {
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && v[j - 1].0 > x.0 {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

/// Candidate leaves of a leaf's shared list above which it is abandoned for per-point
/// tree queries: `LEAF_CANDS_BASE` plus `LEAF_CANDS_PER_K` per leaf's worth of
/// neighbours (an evenly sampled surface needs about 10-15 leaves at k = 16).
const LEAF_CANDS_BASE: usize = 48;
const LEAF_CANDS_PER_K: usize = 8;

/// Per-thread scratch of the all-points kNN: the result row, the tree-query hint and
/// the current leaf's candidate leaves.
#[derive(Default)]
struct SelfScratch {
    buf: Vec<Cand>,
    hint: Option<(DVec3, f64)>,
    leaf: LeafCands,
    order: Vec<(f64, u32)>,
}

/// The candidate leaves shared by the queries of one leaf (slots `lo..hi`).
#[derive(Default)]
struct LeafCands {
    lo: usize,
    hi: usize,
    k: usize,
    usable: bool,
    /// The leaf point the list was built around and its k-th neighbour distance.
    c: DVec3,
    rc: f64,
    /// Candidate leaf ids, in tree order.
    ids: Vec<u32>,
    /// Those within the largest speculative bound of the box (see `scan_leaves`).
    spec_ids: Vec<u32>,
}
