//! A small static bounding-box hierarchy over arbitrary items (triangles, segments):
//! overlap queries (self-intersection broad phase) and branch-and-bound nearest queries
//! (point-to-triangle and point-to-polyline distances).
//!
//! Median split on the longest centroid axis, leaves of up to [`LEAF`] items, nodes in
//! depth-first order in one flat array. Items are addressed by *slot* (their position in
//! the tree's leaf order, so that a leaf's items are contiguous in memory) and mapped back
//! to the caller's ids with [`BoxTree::item`]. The top of the tree is built in parallel.

use glam::DVec3;
use reconbench_geom::Aabb;

const LEAF: usize = 4;
/// Subtrees with more items than this are built with `rayon::join`.
const PAR_BUILD: usize = 1 << 15;

#[derive(Debug, Clone, Copy)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first slot; internal: index of the right child (the left one is the next
    /// node).
    first: u32,
    /// Items in a leaf; 0 for an internal node.
    count: u32,
}

/// The hierarchy (see the module docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct BoxTree {
    nodes: Vec<Node>,
    /// Slot -> item id.
    items: Vec<u32>,
    /// Box per slot.
    boxes: Vec<Aabb>,
}

#[inline]
fn box_dist2(min: DVec3, max: DVec3, p: DVec3) -> f64 {
    let d = (min - p).max(p - max).max(DVec3::ZERO);
    d.length_squared()
}

#[inline]
fn overlaps(min: DVec3, max: DVec3, b: &Aabb) -> bool {
    min.cmple(b.max).all() && b.min.cmple(max).all()
}

impl BoxTree {
    /// Builds the tree over `boxes` (item `i` has box `boxes[i]`); empty boxes are left out.
    pub fn new(boxes: &[Aabb]) -> Self {
        let mut items: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| !boxes[i as usize].is_empty())
            .collect();
        let centers: Vec<DVec3> = boxes.iter().map(Aabb::center).collect();
        let nodes = if items.is_empty() {
            Vec::new()
        } else {
            build(&mut items, 0, boxes, &centers)
        };
        let slot_boxes = items.iter().map(|&i| boxes[i as usize]).collect();
        BoxTree {
            nodes,
            items,
            boxes: slot_boxes,
        }
    }

    /// Item id of `slot`.
    #[inline]
    pub fn item(&self, slot: u32) -> u32 {
        self.items[slot as usize]
    }

    /// Slot -> item id.
    #[cfg(test)]
    pub fn items(&self) -> &[u32] {
        &self.items
    }

    /// Calls `f(item)` for every item whose box overlaps `q` (closed boxes).
    #[cfg(test)]
    pub fn for_each_overlap(&self, q: &Aabb, f: impl FnMut(u32)) {
        self.for_each_overlap_with(q, &mut Vec::new(), f)
    }

    /// [`for_each_overlap`](Self::for_each_overlap) with a caller-owned traversal stack.
    pub fn for_each_overlap_with(&self, q: &Aabb, stack: &mut Vec<u32>, mut f: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        stack.clear();
        stack.push(0u32);
        while let Some(i) = stack.pop() {
            let n = self.nodes[i as usize];
            if !overlaps(n.min, n.max, q) {
                continue;
            }
            if n.count > 0 {
                for s in n.first..n.first + n.count {
                    let b = &self.boxes[s as usize];
                    if overlaps(b.min, b.max, q) {
                        f(self.items[s as usize]);
                    }
                }
            } else {
                stack.push(n.first);
                stack.push(i + 1);
            }
        }
    }

    /// The slot minimising `dist2(slot)` (a squared distance from `p` that must be at
    /// least the squared distance from `p` to the slot's box) among those with
    /// `dist2 <= max_dist2`. `hint`, a slot likely to be close (e.g. the answer of the
    /// previous, nearby query), seeds the bound. Ties go to the first slot found.
    pub fn nearest(
        &self,
        p: DVec3,
        max_dist2: f64,
        hint: Option<u32>,
        stack: &mut Vec<(u32, f64)>,
        mut dist2: impl FnMut(u32) -> f64,
    ) -> Option<(u32, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<(u32, f64)> = None;
        let mut bound = max_dist2;
        if let Some(h) = hint {
            let d = dist2(h);
            if d <= bound {
                best = Some((h, d));
                bound = d;
            }
        }
        stack.clear();
        let root = self.nodes[0];
        stack.push((0, box_dist2(root.min, root.max, p)));
        while let Some((i, bd)) = stack.pop() {
            if bd > bound {
                continue;
            }
            let n = self.nodes[i as usize];
            if n.count > 0 {
                for s in n.first..n.first + n.count {
                    if Some(s) == hint {
                        continue;
                    }
                    let b = &self.boxes[s as usize];
                    if box_dist2(b.min, b.max, p) > bound {
                        continue;
                    }
                    let d = dist2(s);
                    if d <= bound && best.is_none_or(|(_, bd)| d < bd) {
                        best = Some((s, d));
                        bound = d;
                    }
                }
            } else {
                let (l, r) = (i + 1, n.first);
                let (nl, nr) = (self.nodes[l as usize], self.nodes[r as usize]);
                let dl = box_dist2(nl.min, nl.max, p);
                let dr = box_dist2(nr.min, nr.max, p);
                // Push the farther child first so the nearer one is explored first.
                if dl <= dr {
                    if dr <= bound {
                        stack.push((r, dr));
                    }
                    if dl <= bound {
                        stack.push((l, dl));
                    }
                } else {
                    if dl <= bound {
                        stack.push((l, dl));
                    }
                    if dr <= bound {
                        stack.push((r, dr));
                    }
                }
            }
        }
        best
    }
}

/// Bounds, centroid bounds and split axis of `items`.
fn bounds(items: &[u32], boxes: &[Aabb], centers: &[DVec3]) -> (Aabb, usize) {
    let mut bb = Aabb::EMPTY;
    let mut cb = Aabb::EMPTY;
    for &it in items {
        bb = bb.union(boxes[it as usize]);
        cb = cb.grow(centers[it as usize]);
    }
    let ext = cb.size();
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    (bb, axis)
}

/// Median split of `items` along `axis` (ties by id, so the tree is deterministic).
fn split(items: &mut [u32], axis: usize, centers: &[DVec3]) -> usize {
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |&a, &b| {
        centers[a as usize][axis]
            .total_cmp(&centers[b as usize][axis])
            .then(a.cmp(&b))
    });
    mid
}

/// Builds the subtree over `items` (whose first slot is `base`), returning its nodes with
/// the root first and child indices relative to the returned vector. Large subtrees are
/// built in parallel and concatenated (only the top few levels are copied).
fn build(items: &mut [u32], base: usize, boxes: &[Aabb], centers: &[DVec3]) -> Vec<Node> {
    let n = items.len();
    if n <= PAR_BUILD {
        let mut nodes = Vec::with_capacity(2 * n / LEAF + 1);
        build_seq(&mut nodes, items, base, boxes, centers);
        return nodes;
    }
    let (bb, axis) = bounds(items, boxes, centers);
    let mid = split(items, axis, centers);
    let (li, ri) = items.split_at_mut(mid);
    let (left, right) = rayon::join(
        || build(li, base, boxes, centers),
        || build(ri, base + mid, boxes, centers),
    );
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    let right_at = 1 + left.len() as u32;
    nodes.push(Node {
        min: bb.min,
        max: bb.max,
        first: right_at,
        count: 0,
    });
    let shift = |mut nd: Node, off: u32| {
        if nd.count == 0 {
            nd.first += off;
        }
        nd
    };
    nodes.extend(left.into_iter().map(|nd| shift(nd, 1)));
    nodes.extend(right.into_iter().map(|nd| shift(nd, right_at)));
    nodes
}

/// Appends the subtree over `items` to `nodes` (indices relative to `nodes`' start).
fn build_seq(
    nodes: &mut Vec<Node>,
    items: &mut [u32],
    base: usize,
    boxes: &[Aabb],
    centers: &[DVec3],
) {
    let n = items.len();
    let (bb, axis) = bounds(items, boxes, centers);
    let id = nodes.len();
    nodes.push(Node {
        min: bb.min,
        max: bb.max,
        first: base as u32,
        count: n as u32,
    });
    if n <= LEAF {
        return;
    }
    let mid = split(items, axis, centers);
    let (li, ri) = items.split_at_mut(mid);
    build_seq(nodes, li, base, boxes, centers);
    let right = nodes.len() as u32;
    build_seq(nodes, ri, base + mid, boxes, centers);
    nodes[id].first = right;
    nodes[id].count = 0;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_and_overlap_match_brute_force() {
        let mut s = 7u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let pts: Vec<DVec3> = (0..500).map(|_| DVec3::new(rnd(), rnd(), rnd())).collect();
        let boxes: Vec<Aabb> = pts.iter().map(|&p| Aabb::from_points(&[p])).collect();
        let t = BoxTree::new(&boxes);
        let mut stack = Vec::new();
        let mut hint = None;
        for _ in 0..50 {
            let q = DVec3::new(rnd(), rnd(), rnd());
            let (slot, d) = t
                .nearest(q, f64::INFINITY, hint, &mut stack, |s| {
                    (pts[t.item(s) as usize] - q).length_squared()
                })
                .unwrap();
            hint = Some(slot);
            let bf = pts
                .iter()
                .map(|p| (*p - q).length_squared())
                .fold(f64::INFINITY, f64::min);
            assert_eq!(d, bf);
            assert_eq!((pts[t.item(slot) as usize] - q).length_squared(), bf);
            let qb = Aabb::from_points(&[q - DVec3::splat(0.1), q + DVec3::splat(0.1)]);
            let mut got = Vec::new();
            t.for_each_overlap(&qb, |i| got.push(i));
            got.sort_unstable();
            let want: Vec<u32> = (0..500u32)
                .filter(|&i| qb.contains(pts[i as usize]))
                .collect();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn parallel_build_matches_brute_force() {
        let n = 3 * PAR_BUILD;
        let pts: Vec<DVec3> = (0..n)
            .map(|i| {
                let t = i as f64 * 0.618_033_988_749_895;
                DVec3::new(t.fract(), (t * 1.7).fract(), (t * 2.3).fract())
            })
            .collect();
        let boxes: Vec<Aabb> = pts.iter().map(|&p| Aabb::from_points(&[p])).collect();
        let t = BoxTree::new(&boxes);
        let mut seen = t.items().to_vec();
        seen.sort_unstable();
        assert_eq!(seen, (0..n as u32).collect::<Vec<_>>());
        let mut stack = Vec::new();
        for k in 0..20 {
            let q = DVec3::splat(k as f64 / 20.0);
            let (_, d) = t
                .nearest(q, f64::INFINITY, None, &mut stack, |s| {
                    (pts[t.item(s) as usize] - q).length_squared()
                })
                .unwrap();
            let bf = pts
                .iter()
                .map(|p| (*p - q).length_squared())
                .fold(f64::INFINITY, f64::min);
            assert_eq!(d, bf);
        }
    }
}
