//! BuildUmbrella (spec 000 §1.1.3): an umbrella is built from a facet cluster
//! `C ⊆ DT_v` by the ordered removal of pocket triangles, deleting fins as soon as they
//! appear, on the *link graph* of `v` (nodes = the other vertices of the triangles, one
//! edge `a—b` per triangle `(v, a, b)`; spec §1.0.3).
//!
//! Everything lives in a reusable [`LinkGraph`] scratch structure (flat arrays of a few
//! tens of entries, no allocation once warmed up), so the per-vertex work of every
//! iteration allocates nothing.

/// Why [`LinkGraph::build`] found no umbrella.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildFail {
    /// After fin pruning the cluster has no edge left: it contains no cycle (spec line 3).
    NoCycle,
    /// A node kept degree > 2 because of locked facets (spec line 13).
    Locked,
}

/// What a successful build did (for diagnostics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BuildInfo {
    /// Disjoint cycles dropped by the A-05 rule (a non-manifold vertex resolved).
    pub dropped_cycles: u32,
    /// Pocket removals skipped because their fin cascade would delete a locked facet
    /// (ASSUMPTION A-04).
    pub skipped_cascades: u32,
}

/// The link graph of one vertex over its Delaunay triangles `DT_v`, with the state of
/// one BuildUmbrella run. Local facet `i` is the `i`-th entry of the facet list given to
/// [`prepare`](Self::prepare); it is the link edge `ea[i]—eb[i]` between local nodes.
#[derive(Debug, Default, Clone)]
pub struct LinkGraph {
    /// Global vertex id of every local node, increasing.
    pub nodes: Vec<u32>,
    /// Link edge endpoints (local node ids) per local facet.
    pub ea: Vec<u32>,
    /// Second endpoint per local facet.
    pub eb: Vec<u32>,
    /// Node -> incident local facets (CSR offsets into `inc`).
    inc_off: Vec<u32>,
    inc: Vec<u32>,
    /// Whether local facet `i` is still in the cluster.
    pub alive: Vec<bool>,
    deg: Vec<u32>,
    queue: Vec<u32>,
    undo: Vec<u32>,
    tmp: Vec<u32>,
    pos: Vec<u32>,
    comp: Vec<u32>,
}

impl LinkGraph {
    /// Builds the link graph of vertex `v` over the triangles `tris` (global vertex
    /// triples, each containing `v`).
    pub fn prepare(&mut self, v: u32, tris: impl Iterator<Item = [u32; 3]> + Clone) {
        self.tmp.clear();
        self.ea.clear();
        self.eb.clear();
        for t in tris.clone() {
            let (a, b) = others(t, v);
            self.tmp.push(a);
            self.tmp.push(b);
        }
        self.nodes.clear();
        self.nodes.extend_from_slice(&self.tmp);
        self.nodes.sort_unstable();
        self.nodes.dedup();
        let nn = self.nodes.len();
        self.inc_off.clear();
        self.inc_off.resize(nn + 1, 0);
        for t in tris {
            let (a, b) = others(t, v);
            let la = self.local(a);
            let lb = self.local(b);
            self.ea.push(la);
            self.eb.push(lb);
            self.inc_off[la as usize + 1] += 1;
            self.inc_off[lb as usize + 1] += 1;
        }
        for i in 0..nn {
            self.inc_off[i + 1] += self.inc_off[i];
        }
        let nf = self.ea.len();
        self.inc.clear();
        self.inc.resize(2 * nf, 0);
        // Fill with a cursor per node (reuse `deg` as the cursor).
        self.deg.clear();
        self.deg.extend_from_slice(&self.inc_off[..nn]);
        for i in 0..nf {
            for x in [self.ea[i], self.eb[i]] {
                let c = &mut self.deg[x as usize];
                self.inc[*c as usize] = i as u32;
                *c += 1;
            }
        }
    }

    fn local(&self, g: u32) -> u32 {
        self.nodes
            .binary_search(&g)
            .expect("node of the link graph") as u32
    }

    /// Number of local facets.
    pub fn n_facets(&self) -> usize {
        self.ea.len()
    }

    fn incident(&self, x: u32) -> &[u32] {
        &self.inc[self.inc_off[x as usize] as usize..self.inc_off[x as usize + 1] as usize]
    }

    /// Degree of local node `x` in the current cluster (number of alive triangles that
    /// contain the rib `v—x`).
    pub fn degree(&self, x: u32) -> u32 {
        self.deg[x as usize]
    }

    fn remove(&mut self, e: u32) {
        let i = e as usize;
        debug_assert!(self.alive[i]);
        self.alive[i] = false;
        self.deg[self.ea[i] as usize] -= 1;
        self.deg[self.eb[i] as usize] -= 1;
        self.undo.push(e);
    }

    /// PruneFins: repeatedly deletes the link edges that have an endpoint of degree 1
    /// (fins), starting from the nodes in `queue`. Removed facets are appended to `undo`.
    fn prune(&mut self) {
        while let Some(x) = self.queue.pop() {
            if self.deg[x as usize] != 1 {
                continue;
            }
            let e = self
                .incident(x)
                .iter()
                .copied()
                .find(|&e| self.alive[e as usize])
                .expect("a degree-1 node has one alive edge");
            self.remove(e);
            let i = e as usize;
            let y = if self.ea[i] == x {
                self.eb[i]
            } else {
                self.ea[i]
            };
            if self.deg[y as usize] == 1 {
                self.queue.push(y);
            }
        }
    }

    /// BuildUmbrella (spec §1.1.3, lines 1–16) on the prepared graph.
    ///
    /// * `in_c(i)`: whether local facet `i` belongs to the cluster `C`;
    /// * `order`: the local facets of `C` sorted by the key, ascending (= removed first);
    ///   facets outside `C` are ignored;
    /// * `locked(i)`: facets never removed as pockets (`None` = no lock).
    ///
    /// On success `alive` marks the umbrella's facets: exactly one simple cycle of the
    /// link graph of length ≥ 3.
    pub fn build(
        &mut self,
        in_c: impl Fn(usize) -> bool,
        order: &[u32],
        locked: Option<&dyn Fn(usize) -> bool>,
    ) -> Result<BuildInfo, BuildFail> {
        let nf = self.n_facets();
        let nn = self.nodes.len();
        let mut info = BuildInfo::default();
        // Line 1: L <- link graph of C.
        self.alive.clear();
        self.alive.extend((0..nf).map(&in_c));
        self.deg.clear();
        self.deg.resize(nn, 0);
        for i in 0..nf {
            if self.alive[i] {
                self.deg[self.ea[i] as usize] += 1;
                self.deg[self.eb[i] as usize] += 1;
            }
        }
        // Line 2: PruneFins(L).
        self.queue.clear();
        self.undo.clear();
        self.queue
            .extend((0..nn as u32).filter(|&x| self.deg[x as usize] == 1));
        self.prune();
        // Line 3: no edge left -> no umbrella in C.
        if !self.alive.iter().any(|&a| a) {
            return Err(BuildFail::NoCycle);
        }
        // Lines 4–12: ordered pocket removal.
        for &t in order {
            let i = t as usize;
            // Line 5.
            if !self.alive[i] {
                continue;
            }
            // Line 7: not in a pocket now; degrees only decrease later, so it can only
            // still die as a fin.
            if self.deg[self.ea[i] as usize] <= 2 && self.deg[self.eb[i] as usize] <= 2 {
                continue;
            }
            // Line 9.
            if locked.is_some_and(|l| l(i)) {
                continue;
            }
            // Lines 10–12: remove t and its fin cascade K; undo when K hits a locked
            // facet.
            self.undo.clear();
            self.remove(t);
            for x in [self.ea[i], self.eb[i]] {
                if self.deg[x as usize] == 1 {
                    self.queue.push(x);
                }
            }
            self.prune();
            if let Some(l) = locked
                && self.undo.iter().any(|&e| l(e as usize))
            {
                // ASSUMPTION A-04: a pocket removal whose cascade would turn a protected
                // facet into a fin is skipped (the caller rebuilds without protection if
                // the result is invalid).
                for k in 0..self.undo.len() {
                    let e = self.undo[k] as usize;
                    self.alive[e] = true;
                    self.deg[self.ea[e] as usize] += 1;
                    self.deg[self.eb[e] as usize] += 1;
                }
                info.skipped_cascades += 1;
            }
        }
        // Line 13: only possible when locked facets kept a pocket.
        if self.deg.iter().any(|&d| d > 2) {
            return Err(BuildFail::Locked);
        }
        // Lines 14–15: components (simple cycles); ASSUMPTION A-05: keep the cycle whose
        // most removable facet (smallest key) is the least removable, i.e. drop cycles
        // in order of their minimum key. Facets are totally ordered (the facet id ends
        // every key, A-02), so there are no ties between cycles.
        self.pos.clear();
        self.pos.resize(nf, u32::MAX);
        for (k, &t) in order.iter().enumerate() {
            self.pos[t as usize] = k as u32;
        }
        self.comp.clear();
        self.comp.resize(nf, u32::MAX);
        let mut best: Option<(u32, u32)> = None; // (min position, component id)
        let mut n_comp = 0u32;
        for s in 0..nf {
            if !self.alive[s] || self.comp[s] != u32::MAX {
                continue;
            }
            let c = n_comp;
            n_comp += 1;
            let mut min_pos = u32::MAX;
            // Walk the cycle: from facet s, leave through eb[s].
            let mut e = s;
            let mut node = self.eb[s];
            loop {
                self.comp[e] = c;
                min_pos = min_pos.min(self.pos[e]);
                let next =
                    self.incident(node)
                        .iter()
                        .copied()
                        .find(|&f| f as usize != e && self.alive[f as usize])
                        .expect("every node of a cycle has degree 2") as usize;
                if next == s {
                    break;
                }
                node = if self.ea[next] == node {
                    self.eb[next]
                } else {
                    self.ea[next]
                };
                e = next;
            }
            if best.is_none_or(|(p, _)| min_pos > p) {
                best = Some((min_pos, c));
            }
        }
        let (_, keep) = best.expect("a non-empty 2-regular graph has a cycle");
        if n_comp > 1 {
            info.dropped_cycles = n_comp - 1;
            for i in 0..nf {
                if self.alive[i] && self.comp[i] != keep {
                    self.alive[i] = false;
                }
            }
        }
        Ok(info)
    }

    /// The umbrella marked by `member(i)` (local facets forming one simple cycle) in
    /// cyclic order: `(facets, ring)` with facet `facets[j] = (v, ring[j], ring[j+1])`
    /// (indices mod k), `ring` as global vertex ids. Empty when `member` marks no
    /// facet or not a single simple cycle.
    pub fn cycle(
        &self,
        member: impl Fn(usize) -> bool,
        facets: &mut Vec<u32>,
        ring: &mut Vec<u32>,
    ) {
        facets.clear();
        ring.clear();
        let nf = self.n_facets();
        let Some(s) = (0..nf).find(|&i| member(i)) else {
            return;
        };
        let total = (0..nf).filter(|&i| member(i)).count();
        let mut e = s;
        let mut node = self.ea[s];
        loop {
            facets.push(e as u32);
            ring.push(self.nodes[node as usize]);
            let other = if self.ea[e] == node {
                self.eb[e]
            } else {
                self.ea[e]
            };
            let mut nexts = self
                .incident(other)
                .iter()
                .copied()
                .filter(|&f| f as usize != e && member(f as usize));
            let (Some(next), None) = (nexts.next(), nexts.next()) else {
                facets.clear();
                ring.clear();
                return;
            };
            node = other;
            e = next as usize;
            if e == s {
                break;
            }
            if facets.len() > total {
                break;
            }
        }
        if facets.len() != total {
            facets.clear();
            ring.clear();
        }
    }
}

/// The two vertices of `t` other than `v`.
fn others(t: [u32; 3], v: u32) -> (u32, u32) {
    if t[0] == v {
        (t[1], t[2])
    } else if t[1] == v {
        (t[0], t[2])
    } else {
        debug_assert_eq!(t[2], v);
        (t[0], t[1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangles (0, a, b) for the given link edges.
    fn graph(edges: &[(u32, u32)]) -> LinkGraph {
        let mut g = LinkGraph::default();
        let tris: Vec<[u32; 3]> = edges.iter().map(|&(a, b)| [0, a, b]).collect();
        g.prepare(0, tris.iter().copied());
        g
    }

    fn alive_edges(g: &LinkGraph, edges: &[(u32, u32)]) -> Vec<(u32, u32)> {
        (0..edges.len())
            .filter(|&i| g.alive[i])
            .map(|i| edges[i])
            .collect()
    }

    #[test]
    fn a_plain_cycle_is_kept() {
        let e = [(1, 2), (2, 3), (3, 4), (4, 1)];
        let mut g = graph(&e);
        let order: Vec<u32> = (0..4).collect();
        let info = g.build(|_| true, &order, None).unwrap();
        assert_eq!(info, BuildInfo::default());
        assert_eq!(alive_edges(&g, &e).len(), 4);
    }

    #[test]
    fn fins_are_pruned_and_a_tree_fails() {
        // A square with a dangling path 1-5-6: the fins go.
        let e = [(1, 2), (2, 3), (3, 4), (4, 1), (1, 5), (5, 6)];
        let mut g = graph(&e);
        let order: Vec<u32> = (0..6).collect();
        g.build(|_| true, &order, None).unwrap();
        assert_eq!(alive_edges(&g, &e), &e[..4]);
        // A path has no cycle.
        let e = [(1, 2), (2, 3), (3, 4)];
        let mut g = graph(&e);
        assert_eq!(g.build(|_| true, &[0, 1, 2], None), Err(BuildFail::NoCycle));
    }

    #[test]
    fn pocket_removal_follows_the_order() {
        // Square 1-2-3-4 with the diagonal 1-3: nodes 1 and 3 have degree 3. Removing
        // the diagonal first keeps the square; removing (1,2) first leaves the
        // triangle 1-3-4 after the fin (2,3) goes.
        let e = [(1, 2), (2, 3), (3, 4), (4, 1), (1, 3)];
        let mut g = graph(&e);
        g.build(|_| true, &[4, 0, 1, 2, 3], None).unwrap();
        assert_eq!(alive_edges(&g, &e), &e[..4]);
        let mut g = graph(&e);
        g.build(|_| true, &[0, 1, 2, 3, 4], None).unwrap();
        assert_eq!(alive_edges(&g, &e), vec![(3, 4), (4, 1), (1, 3)]);
    }

    #[test]
    fn locks_skip_cascades_and_may_fail() {
        // Same graph; lock (2,3): removing (1,2) would orphan it, so that removal is
        // skipped and the diagonal goes next.
        let e = [(1, 2), (2, 3), (3, 4), (4, 1), (1, 3)];
        let mut g = graph(&e);
        let lock = |i: usize| i == 1;
        let info = g.build(|_| true, &[0, 4, 1, 2, 3], Some(&lock)).unwrap();
        assert_eq!(info.skipped_cascades, 1);
        assert_eq!(alive_edges(&g, &e), &e[..4]);
        // Locking all three edges at node 1 keeps a degree-3 node: failure.
        let mut g = graph(&e);
        let lock = |i: usize| i == 0 || i == 3 || i == 4;
        assert_eq!(
            g.build(|_| true, &[0, 1, 2, 3, 4], Some(&lock)),
            Err(BuildFail::Locked)
        );
    }

    #[test]
    fn two_cycles_keep_the_one_with_the_largest_minimum_key() {
        // Two disjoint triangles 1-2-3 and 4-5-6 (a pinched vertex).
        let e = [(1, 2), (2, 3), (3, 1), (4, 5), (5, 6), (6, 4)];
        let mut g = graph(&e);
        let info = g.build(|_| true, &[0, 3, 1, 4, 2, 5], None).unwrap();
        assert_eq!(info.dropped_cycles, 1);
        assert_eq!(alive_edges(&g, &e), &e[3..]);
        let mut g = graph(&e);
        g.build(|_| true, &[3, 0, 1, 4, 2, 5], None).unwrap();
        assert_eq!(alive_edges(&g, &e), &e[..3]);
    }

    #[test]
    fn cycle_order_walks_the_ring() {
        let e = [(1, 2), (3, 4), (2, 3), (4, 1)];
        let g = graph(&e);
        let (mut f, mut r) = (Vec::new(), Vec::new());
        g.cycle(|_| true, &mut f, &mut r);
        assert_eq!(f.len(), 4);
        for j in 0..4 {
            let (a, b) = e[f[j] as usize];
            let (p, q) = (r[j], r[(j + 1) % 4]);
            assert!((a, b) == (p, q) || (a, b) == (q, p), "{f:?} {r:?}");
        }
        // Two cycles are not one umbrella.
        let e = [(1, 2), (2, 3), (3, 1), (4, 5), (5, 6), (6, 4)];
        let g = graph(&e);
        g.cycle(|_| true, &mut f, &mut r);
        assert!(f.is_empty());
    }
}
