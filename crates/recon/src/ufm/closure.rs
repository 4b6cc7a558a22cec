//! Delaunay hole closure: a step after the UFM loop (`mode = "closed"`; a deviation, not
//! in the thesis) that closes the holes the loop leaves, independently of umbrellas.
//!
//! The loop's matched facets form an edge-manifold set of Delaunay triangles with holes,
//! pinched vertices (two or more fans sharing a vertex), sliver bubbles and, after the
//! fold repair, sometimes a twisted strip. In order, [`close`]:
//!
//! 1. *untwists*: orients every piece and drops a face at each edge whose two faces
//!    disagree, until the surface is orientable;
//! 2. *pops* pieces of at most `MAX_BUBBLE` (8) faces (bubbles and crumbs; never the largest);
//! 3. *unpinches*: keeps the largest fan at a pinched vertex;
//! 4. *grows* from the hole boundaries: a boundary edge `ab` of face `abd` is extended by
//!    the Delaunay triangle `abc` that continues `abd` most flatly (turn = pi minus the
//!    angle between `d` and `c` seen along `ab`, at most `max_turn`; new edges at most
//!    2.5 local edge lengths (`MAX_SIZE`)), keeping edges in at most two faces, the surface
//!    orientable and every vertex one fan, or two fans of different pieces (a bridge
//!    between two fronts, merged when they meet; two loops of one piece are never joined,
//!    which would make a handle). All holes share one flattest-first queue; 2-4 repeat
//!    for up to 4 rounds (`ROUNDS`);
//! 5. fills the holes no Delaunay triangle can close (at most [`MAX_FILL`] edges) with the
//!    least-area triangulation of the loop, preferring one that crosses no nearby face;
//! 6. inserts every point the surface has not reached into the face it projects into.
//!
//! Delaunay triangles never cross each other, so only steps 5 and 6 can create
//! self-intersections; every input point stays a vertex (interpolation).

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap, HashSet};

use glam::DVec3;

use super::complex::Complex;

/// What the closure did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClosureStats {
    /// Faces removed to open pinched vertices.
    pub unpinched_faces: usize,
    /// Faces of the bubbles removed (small closed pieces).
    pub bubble_faces: usize,
    /// Faces removed to make the loop's output orientable.
    pub untwisted_faces: usize,
    /// Delaunay triangles added.
    pub added: usize,
    /// Holes closed by the polygon fill (no Delaunay triangle could).
    pub filled_holes: usize,
    /// Triangles of the polygon fill.
    pub fill_triangles: usize,
    /// Points inserted into a face they project into (the surface did not reach them).
    pub inserted_points: usize,
}

/// Hasher of edge keys (two vertex ids packed in a `u64`): one multiply-xorshift, much
/// cheaper than the default SipHash and enough for keys that are not adversarial.
#[derive(Default)]
struct EdgeHasher(u64);

impl std::hash::Hasher for EdgeHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(self.0 ^ u64::from(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        let h = (self.0 ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 = h ^ (h >> 32);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

type EdgeMap = HashMap<u64, [u32; 2], std::hash::BuildHasherDefault<EdgeHasher>>;

fn edge_key(a: u32, b: u32) -> u64 {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    (u64::from(a) << 32) | u64::from(b)
}

/// The surface being closed: faces as Delaunay facet ids, edge -> incident faces, and per
/// vertex the number of incident faces and of incident boundary edges.
struct Surface<'a> {
    cx: &'a Complex,
    pts: &'a [DVec3],
    in_s: Vec<bool>,
    edges: EdgeMap,
    faces_at: Vec<u32>,
    boundary_at: Vec<u32>,
    /// Per facet: oriented as its sorted vertex triple (`false`) or reversed (`true`).
    flip: Vec<bool>,
    /// Per facet in the surface: its orientation component (faces whose orientations
    /// are tied through shared edges), [`NONE`] outside.
    comp: Vec<u32>,
    /// Facets per component (may hold stale ids; filtered by `comp`).
    members: Vec<Vec<u32>>,
    /// Vertices whose faces changed since the last pinch check (flag and list).
    dirty: Vec<bool>,
    dirty_list: Vec<u32>,
}

const NONE: u32 = u32::MAX;

impl<'a> Surface<'a> {
    fn new(cx: &'a Complex, pts: &'a [DVec3], faces: &[u32]) -> Self {
        let nv = cx.n_vertices();
        let mut s = Surface {
            cx,
            pts,
            in_s: vec![false; cx.facets().len()],
            edges: EdgeMap::with_capacity_and_hasher(faces.len() * 3 / 2 + 16, Default::default()),
            faces_at: vec![0; nv],
            boundary_at: vec![0; nv],
            flip: vec![false; cx.facets().len()],
            comp: vec![NONE; cx.facets().len()],
            members: Vec::new(),
            dirty: vec![false; nv],
            dirty_list: Vec::new(),
        };
        for &f in faces {
            s.add(f);
        }
        s.orient_initial(faces);
        s
    }

    /// Removes the bubbles and crumbs: pieces of at most `MAX_BUBBLE` (8) faces, closed
    /// (the flat tetrahedra whose four faces are matched at every corner, the loop's
    /// first fixed point, `docs/methods/ufm.md`) or open (left over by the unpinching).
    /// Their points become free for the growth. Returns the faces removed.
    fn pop_bubbles(&mut self) -> usize {
        let mut size = vec![0usize; self.members.len()];
        for (f, &c) in self.comp.iter().enumerate() {
            if c != NONE && self.in_s[f] {
                size[c as usize] += 1;
            }
        }
        // A small input is what it is: only crumbs next to a real surface are popped.
        let total: usize = size.iter().sum();
        let largest = size.iter().copied().max().unwrap_or(0);
        if largest <= MAX_BUBBLE || total < MIN_FACES_FOR_BUBBLES {
            return 0;
        }
        let mut removed = 0;
        for c in 0..size.len() {
            if size[c] == 0 || size[c] > MAX_BUBBLE {
                continue;
            }
            let mut live: Vec<u32> = self.members[c]
                .iter()
                .copied()
                .filter(|&f| self.in_s[f as usize] && self.comp[f as usize] == c as u32)
                .collect();
            live.sort_unstable();
            live.dedup();
            for f in live {
                self.remove(f);
                removed += 1;
            }
        }
        removed
    }

    /// Removes faces until the surface is orientable: after orienting it, one face of
    /// every edge whose two faces run it the same way (the higher facet id) goes, and
    /// the orientation is redone (a loop output can hold a twisted strip). Returns the
    /// faces removed.
    fn untwist(&mut self) -> usize {
        let mut removed = 0;
        for _ in 0..16 {
            let mut bad: Vec<u32> = self
                .edges
                .iter()
                .filter(|(_, e)| e[0] != NONE && e[1] != NONE && e[0] != FILLED && e[1] != FILLED)
                .filter(|(k, e)| {
                    let (p, q) = ((**k >> 32) as u32, **k as u32);
                    self.has_dir(e[0], p, q) == self.has_dir(e[1], p, q)
                })
                .map(|(_, e)| e[0].max(e[1]))
                .collect();
            if bad.is_empty() {
                break;
            }
            bad.sort_unstable();
            bad.dedup();
            for f in bad {
                if self.in_s[f as usize] {
                    self.remove(f);
                    removed += 1;
                }
            }
            let faces: Vec<u32> = (0..self.in_s.len() as u32)
                .filter(|&f| self.in_s[f as usize])
                .collect();
            self.comp.iter_mut().for_each(|c| *c = NONE);
            self.members.clear();
            self.orient_initial(&faces);
        }
        removed
    }

    /// Orients the initial faces consistently per connected piece (breadth first over
    /// manifold edges, lowest facet first) and gives each piece a component.
    fn orient_initial(&mut self, faces: &[u32]) {
        let mut sorted = faces.to_vec();
        sorted.sort_unstable();
        for &seed in &sorted {
            if self.comp[seed as usize] != NONE {
                continue;
            }
            let c = self.members.len() as u32;
            self.members.push(vec![seed]);
            self.comp[seed as usize] = c;
            let mut k = 0;
            while k < self.members[c as usize].len() {
                let f = self.members[c as usize][k];
                k += 1;
                let [x, y, z] = self.oriented(f);
                for (p, q) in [(x, y), (y, z), (z, x)] {
                    let e = self.edge_faces(p, q);
                    let g = if e[0] == f { e[1] } else { e[0] };
                    if g == NONE || self.comp[g as usize] != NONE {
                        continue;
                    }
                    // `g` must run the shared edge the other way.
                    if self.has_dir(g, p, q) {
                        self.flip[g as usize] = !self.flip[g as usize];
                    }
                    self.comp[g as usize] = c;
                    self.members[c as usize].push(g);
                }
            }
        }
    }

    /// Vertices of facet `f` in its orientation.
    fn oriented(&self, f: u32) -> [u32; 3] {
        let [a, b, c] = self.corners(f);
        if self.flip[f as usize] {
            [a, c, b]
        } else {
            [a, b, c]
        }
    }

    /// Whether facet `f`, as oriented, runs its edge from `x` to `y`.
    fn has_dir(&self, f: u32, x: u32, y: u32) -> bool {
        let [a, b, c] = self.oriented(f);
        (a, b) == (x, y) || (b, c) == (x, y) || (c, a) == (x, y)
    }

    /// How `t` extends boundary edge `ab` of face `f` orientably: its flip, and the
    /// components to flip so that every edge it shares runs the other way in the
    /// neighbour; `None` when a neighbour of `f`'s own component disagrees (the result
    /// would not be orientable).
    fn orientation_plan(&self, a: u32, b: u32, f: u32, t: u32) -> Option<(bool, Vec<u32>)> {
        // `t` runs `ab` opposite to `f`.
        let [x, y, z] = self.corners(t);
        let forward = [(x, y), (y, z), (z, x)];
        let f_ab = self.has_dir(f, a, b);
        let t_ab_unflipped = forward.contains(&(a, b));
        // Unflipped `t` has a->b iff t_ab_unflipped; we need a->b iff !f_ab.
        let t_flip = t_ab_unflipped == f_ab;
        let mut flips: Vec<u32> = Vec::new();
        let mut keep: Vec<u32> = vec![self.comp[f as usize]];
        let oriented = if t_flip { [x, z, y] } else { [x, y, z] };
        for (p, q) in [
            (oriented[0], oriented[1]),
            (oriented[1], oriented[2]),
            (oriented[2], oriented[0]),
        ] {
            if edge_key(p, q) == edge_key(a, b) {
                continue;
            }
            let g = self.edge_faces(p, q)[0];
            if g == NONE || g == FILLED {
                continue;
            }
            let c = self.comp[g as usize];
            let conflict = self.has_dir(g, p, q);
            match (conflict, keep.contains(&c), flips.contains(&c)) {
                (false, _, false) => keep.push(c),
                (true, false, _) => flips.push(c),
                (false, _, true) | (true, true, _) => return None,
            }
        }
        flips.dedup();
        Some((t_flip, flips))
    }

    /// Adds `t` at boundary edge `ab` of face `f` with the orientation plan, flipping the
    /// planned components and merging every component `t` touches into one.
    fn add_oriented(&mut self, a: u32, b: u32, f: u32, t: u32, plan: (bool, Vec<u32>)) {
        let (t_flip, flips) = plan;
        for c in flips {
            let mut m = std::mem::take(&mut self.members[c as usize]);
            m.sort_unstable();
            m.dedup();
            for &g in &m {
                if self.in_s[g as usize] && self.comp[g as usize] == c {
                    self.flip[g as usize] = !self.flip[g as usize];
                }
            }
            self.members[c as usize] = m;
        }
        self.add(t);
        self.flip[t as usize] = t_flip;
        let target = self.comp[f as usize];
        self.comp[t as usize] = target;
        self.members[target as usize].push(t);
        let [x, y, z] = self.corners(t);
        for (p, q) in [(x, y), (y, z), (x, z)] {
            if edge_key(p, q) == edge_key(a, b) {
                continue;
            }
            for g in self.edge_faces(p, q) {
                if g == NONE || g == FILLED || g == t {
                    continue;
                }
                let c = self.comp[g as usize];
                if c != target && c != NONE {
                    self.merge(target, c);
                }
            }
        }
    }

    /// Moves component `from` into `into`.
    fn merge(&mut self, into: u32, from: u32) {
        let m = std::mem::take(&mut self.members[from as usize]);
        for &g in &m {
            if self.in_s[g as usize] && self.comp[g as usize] == from {
                self.comp[g as usize] = into;
                self.members[into as usize].push(g);
            }
        }
    }

    fn corners(&self, f: u32) -> [u32; 3] {
        self.cx.facets()[f as usize].v
    }

    fn edge_faces(&self, a: u32, b: u32) -> [u32; 2] {
        self.edges
            .get(&edge_key(a, b))
            .copied()
            .unwrap_or([NONE; 2])
    }

    fn count(&self, a: u32, b: u32) -> usize {
        let e = self.edge_faces(a, b);
        (e[0] != NONE) as usize + (e[1] != NONE) as usize
    }

    /// Keeps `boundary_at` true when edge `ab` goes from `before` to `after` faces.
    fn set_boundary(&mut self, a: u32, b: u32, before: usize, after: usize) {
        let (was, is) = (before == 1, after == 1);
        for v in [a, b] {
            match (was, is) {
                (false, true) => self.boundary_at[v as usize] += 1,
                (true, false) => self.boundary_at[v as usize] -= 1,
                _ => {}
            }
        }
    }

    /// The boundary edges at `v`, as the other vertex.
    fn boundary_neighbours(&self, v: u32) -> Vec<u32> {
        let mut out = Vec::new();
        for &f in self.cx.row(v as usize) {
            if !self.in_s[f as usize] {
                continue;
            }
            for w in self.corners(f) {
                if w != v && self.count(v, w) == 1 && !out.contains(&w) {
                    out.push(w);
                }
            }
        }
        out
    }

    fn touch(&mut self, v: u32) {
        if !self.dirty[v as usize] {
            self.dirty[v as usize] = true;
            self.dirty_list.push(v);
        }
    }

    fn add(&mut self, f: u32) {
        self.in_s[f as usize] = true;
        let [a, b, c] = self.corners(f);
        for v in [a, b, c] {
            self.touch(v);
        }
        for (x, y) in [(a, b), (b, c), (a, c)] {
            let before = self.count(x, y);
            let e = self.edges.entry(edge_key(x, y)).or_insert([NONE; 2]);
            if e[0] == NONE {
                e[0] = f;
            } else {
                e[1] = f;
            }
            self.set_boundary(x, y, before, before + 1);
        }
        for v in [a, b, c] {
            self.faces_at[v as usize] += 1;
        }
    }

    fn remove(&mut self, f: u32) {
        self.in_s[f as usize] = false;
        self.comp[f as usize] = NONE;
        let [a, b, c] = self.corners(f);
        for v in [a, b, c] {
            self.touch(v);
        }
        for (x, y) in [(a, b), (b, c), (a, c)] {
            let before = self.count(x, y);
            let k = edge_key(x, y);
            if let Some(e) = self.edges.get_mut(&k) {
                if e[0] == f {
                    e[0] = e[1];
                }
                e[1] = NONE;
                if e[0] == NONE {
                    self.edges.remove(&k);
                }
            }
            self.set_boundary(x, y, before, before - 1);
        }
        for v in [a, b, c] {
            self.faces_at[v as usize] -= 1;
        }
    }

    /// Whether the faces at `v` form one fan (connected through their edges at `v`),
    /// without allocating: union-find over at most 64 faces, else [`fans`](Self::fans).
    fn single_fan(&self, v: u32) -> bool {
        let mut others = [[0u32; 2]; 64];
        let mut parent = [0u8; 64];
        let mut k = 0;
        for &f in self.cx.row(v as usize) {
            if !self.in_s[f as usize] {
                continue;
            }
            if k == 64 {
                return self.fans(v).len() == 1;
            }
            let c = self.corners(f);
            let mut o = [0u32; 2];
            let mut j = 0;
            for w in c {
                if w != v && j < 2 {
                    o[j] = w;
                    j += 1;
                }
            }
            others[k] = o;
            parent[k] = k as u8;
            k += 1;
        }
        fn root(p: &mut [u8; 64], mut x: usize) -> usize {
            while p[x] as usize != x {
                p[x] = p[p[x] as usize];
                x = p[x] as usize;
            }
            x
        }
        let mut groups = k;
        for i in 0..k {
            for j in i + 1..k {
                let (a, b) = (others[i], others[j]);
                if a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1] {
                    let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                    if ri != rj {
                        parent[ri] = rj as u8;
                        groups -= 1;
                    }
                }
            }
        }
        groups <= 1
    }

    /// Whether `abc` is already a face (its three edges all belong to one face).
    fn is_face(&self, a: u32, b: u32, c: u32) -> bool {
        let e = self.edge_faces(a, b);
        e.iter().any(|&f| {
            f != NONE
                && f != FILLED
                && self.edge_faces(b, c).contains(&f)
                && self.edge_faces(a, c).contains(&f)
        })
    }

    /// The faces at `v` grouped into fans (connected through edges at `v`).
    fn fans(&self, v: u32) -> Vec<Vec<u32>> {
        let at: Vec<u32> = self
            .cx
            .row(v as usize)
            .iter()
            .copied()
            .filter(|&f| self.in_s[f as usize])
            .collect();
        let mut seen = vec![false; at.len()];
        let mut fans = Vec::new();
        for i in 0..at.len() {
            if seen[i] {
                continue;
            }
            seen[i] = true;
            let mut fan = vec![at[i]];
            let mut k = 0;
            while k < fan.len() {
                let f = fan[k];
                k += 1;
                for w in self.corners(f) {
                    if w == v {
                        continue;
                    }
                    for g in self.edge_faces(v, w) {
                        if g == NONE {
                            continue;
                        }
                        if let Some(j) = at.iter().position(|&x| x == g)
                            && !seen[j]
                        {
                            seen[j] = true;
                            fan.push(g);
                        }
                    }
                }
            }
            fans.push(fan);
        }
        fans
    }

    /// The turn of the Delaunay triangle `abc` against the face `abd`: pi minus the angle
    /// between `c` and `d` seen along the edge (0: flat continuation, pi: folded back).
    fn turn(&self, a: u32, b: u32, c: u32, d: u32) -> f64 {
        let (pa, pb) = (self.pts[a as usize], self.pts[b as usize]);
        let u = (pb - pa).normalize_or_zero();
        let perp = |p: DVec3| {
            let w = p - pa;
            w - u * w.dot(u)
        };
        let (wc, wd) = (perp(self.pts[c as usize]), perp(self.pts[d as usize]));
        let cos = wc.dot(wd) / (wc.length() * wd.length());
        if !cos.is_finite() {
            return std::f64::consts::PI;
        }
        std::f64::consts::PI - cos.clamp(-1.0, 1.0).acos()
    }

    /// Whether adding facet `t` (not in the surface) keeps every edge in at most two
    /// faces and never closes a fan at a vertex that has other fans. A corner that has
    /// faces but shares no edge with `t` gets a second fan (a bridge between two fronts,
    /// as in advancing-front methods): allowed only at a boundary vertex, and resolved
    /// when the fronts meet (a face whose two edges at the vertex lie in different fans
    /// merges them).
    fn can_add(&self, t: u32) -> bool {
        let [a, b, c] = self.corners(t);
        let mut present = [false; 3];
        for (i, (x, y)) in [(a, b), (b, c), (a, c)].into_iter().enumerate() {
            match self.count(x, y) {
                0 => {}
                1 => present[i] = true,
                _ => return false,
            }
        }
        // Per corner: its two edges in `t` (as the other vertices) and whether present.
        for (v, (w1, p1), (w2, p2)) in [
            (a, (b, present[0]), (c, present[2])),
            (b, (a, present[0]), (c, present[1])),
            (c, (b, present[1]), (a, present[2])),
        ] {
            if self.faces_at[v as usize] == 0 {
                continue;
            }
            let bnd = self.boundary_at[v as usize];
            let ok = match (p1, p2) {
                // A bridge: a new fan at a boundary vertex.
                (false, false) => bnd >= 2,
                // Extends a fan at one of its boundary edges.
                (true, false) | (false, true) => true,
                // Closes the only fan, or merges two fans of different pieces (two
                // fans of one piece would join two of its boundary loops: a handle).
                (true, true) => bnd == 2 || self.fans_of_different_pieces(v, w1, w2),
            };
            if !ok {
                return false;
            }
        }
        true
    }

    /// Whether `abc` would bridge to vertex `c` (faces at `c`, no edge of `abc` there) of
    /// the component of `f`: joining two boundary loops of one piece makes a handle the
    /// surface does not have, so bridges only join different pieces.
    fn bridges_own_component(&self, a: u32, b: u32, c: u32, f: u32) -> bool {
        if self.faces_at[c as usize] == 0 || self.count(a, c) > 0 || self.count(b, c) > 0 {
            return false;
        }
        let own = self.comp[f as usize];
        self.cx
            .row(c as usize)
            .iter()
            .any(|&g| self.in_s[g as usize] && self.comp[g as usize] == own)
    }

    /// Whether the boundary edges `vw1` and `vw2` at `v` lie in fans of different pieces
    /// (then they are different fans, met through a bridge).
    fn fans_of_different_pieces(&self, v: u32, w1: u32, w2: u32) -> bool {
        let (f1, f2) = (self.edge_faces(v, w1)[0], self.edge_faces(v, w2)[0]);
        self.comp[f1 as usize] != self.comp[f2 as usize]
    }

    /// Opens every pinched vertex: keeps its largest fan (ties: the one holding the
    /// lowest facet) and removes the faces of the others. Returns the faces removed.
    fn unpinch(&mut self) -> usize {
        let mut total = 0;
        // Removing a fan can split a neighbour's fan: repeat until nothing changes.
        loop {
            let removed = self.unpinch_once();
            total += removed;
            if removed == 0 {
                return total;
            }
        }
    }

    /// One pass over the vertices whose faces changed since the last pass.
    fn unpinch_once(&mut self) -> usize {
        let mut removed = 0;
        let mut list = std::mem::take(&mut self.dirty_list);
        list.sort_unstable();
        for &v in &list {
            self.dirty[v as usize] = false;
        }
        for v in list {
            if self.faces_at[v as usize] < 2 || self.single_fan(v) {
                continue;
            }
            let mut fans = self.fans(v);
            if fans.len() < 2 {
                continue;
            }
            fans.sort_by_key(|f| (std::cmp::Reverse(f.len()), f.iter().copied().min()));
            for fan in &fans[1..] {
                for &f in fan {
                    if self.in_s[f as usize] {
                        self.remove(f);
                        removed += 1;
                    }
                }
            }
        }
        removed
    }

    /// Mean length of the surface edges at `v` (0 without any).
    fn local_edge(&self, v: u32) -> f64 {
        let (mut sum, mut n) = (0.0, 0usize);
        for &f in self.cx.row(v as usize) {
            if !self.in_s[f as usize] {
                continue;
            }
            for w in self.corners(f) {
                if w != v {
                    sum += (self.pts[w as usize] - self.pts[v as usize]).length();
                    n += 1;
                }
            }
        }
        if n == 0 { 0.0 } else { sum / n as f64 }
    }

    /// Whether triangle `abc` (extending edge `ab`) is no longer than [`MAX_SIZE`] times
    /// the local edge length at `a` and `b` (or `ab` itself): a Delaunay triangle spanning
    /// a concavity or a gap between sheets is flat enough but far too long.
    fn small_enough(&self, a: u32, b: u32, c: u32) -> bool {
        let p = |v: u32| self.pts[v as usize];
        let longest = (p(a) - p(c)).length().max((p(b) - p(c)).length());
        let reference = (p(a) - p(b))
            .length()
            .max(self.local_edge(a))
            .max(self.local_edge(b));
        longest <= MAX_SIZE * reference
    }

    /// The Delaunay facets through edge `ab` other than those in the surface.
    fn candidates(&self, a: u32, b: u32) -> Vec<u32> {
        let (ra, rb) = (self.cx.row(a as usize), self.cx.row(b as usize));
        let (mut i, mut j) = (0, 0);
        let mut out = Vec::new();
        while i < ra.len() && j < rb.len() {
            match ra[i].cmp(&rb[j]) {
                Ordering::Less => i += 1,
                Ordering::Greater => j += 1,
                Ordering::Equal => {
                    if !self.in_s[ra[i] as usize] {
                        out.push(ra[i]);
                    }
                    i += 1;
                    j += 1;
                }
            }
        }
        out
    }

    /// The turn of candidate `t` at boundary edge `ab` of face `f`, or why it is refused.
    fn check(&self, a: u32, b: u32, f: u32, t: u32, max_turn: f64) -> Result<f64, Reject> {
        let third = |x: u32| self.corners(x).into_iter().find(|&v| v != a && v != b);
        let (Some(c), Some(d)) = (third(t), third(f)) else {
            return Err(Reject::Turn);
        };
        let turn = self.turn(a, b, c, d);
        if turn > max_turn {
            return Err(Reject::Turn);
        }
        if !self.small_enough(a, b, c) {
            return Err(Reject::Size);
        }
        if !self.can_add(t) {
            return Err(Reject::Manifold);
        }
        if self.orientation_plan(a, b, f, t).is_none() {
            return Err(Reject::Orientation);
        }
        if self.bridges_own_component(a, b, c, f) {
            return Err(Reject::Handle);
        }
        Ok(turn)
    }

    /// Best Delaunay triangle extending boundary edge `ab` (of face `f`): the flattest
    /// valid one with a turn of at most `max_turn`; ties by facet id.
    fn best(&self, a: u32, b: u32, f: u32, max_turn: f64) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        for t in self.candidates(a, b) {
            if let Ok(turn) = self.check(a, b, f, t, max_turn)
                && best.is_none_or(|(bt, bf)| turn < bt || (turn == bt && t < bf))
            {
                best = Some((turn, t));
            }
        }
        best
    }
}

/// Why a Delaunay triangle cannot extend a boundary edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reject {
    /// It turns by more than `max_turn` against its neighbour (folds back).
    Turn,
    /// Its new edges are longer than 2.5 local edge lengths (`MAX_SIZE`).
    Size,
    /// Adding it would make an edge or a vertex non-manifold.
    Manifold,
    /// Adding it would make the surface non-orientable.
    Orientation,
    /// It would bridge two boundary loops of one piece (a handle).
    Handle,
}

/// One hole left after the closure, for diagnosis (`docs/methods/ufm.md`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct HoleReport {
    /// Boundary edges of the hole (its loop length).
    pub edges: usize,
    /// Boundary edges with no Delaunay facet at all besides the surface's.
    pub no_candidate: usize,
    /// Candidates refused for their turn.
    pub turn: usize,
    /// Candidates refused for their size.
    pub size: usize,
    /// Candidates refused for manifoldness or orientability.
    pub manifold: usize,
}

/// The holes of a closed-as-far-as-possible facet set and why each candidate at their
/// boundary is refused (holes as loops of boundary edges, by connectivity through shared
/// vertices).
pub fn diagnose(cx: &Complex, pts: &[DVec3], faces: &[u32], max_turn: f64) -> Vec<HoleReport> {
    let s = Surface::new(cx, pts, faces);
    let mut bedges: Vec<(u32, u32, u32)> = s
        .edges
        .iter()
        .filter(|(_, f)| f[1] == NONE && f[0] != NONE)
        .map(|(&k, f)| ((k >> 32) as u32, k as u32, f[0]))
        .collect();
    bedges.sort_unstable();
    // Union-find over vertices of boundary edges.
    let mut parent: HashMap<u32, u32> = HashMap::new();
    fn find(p: &mut HashMap<u32, u32>, x: u32) -> u32 {
        let mut r = x;
        while let Some(&q) = p.get(&r) {
            if q == r {
                break;
            }
            r = q;
        }
        p.insert(x, r);
        r
    }
    for &(a, b, _) in &bedges {
        parent.entry(a).or_insert(a);
        parent.entry(b).or_insert(b);
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent.insert(ra.max(rb), ra.min(rb));
        }
    }
    let mut holes: HashMap<u32, HoleReport> = HashMap::new();
    for &(a, b, f) in &bedges {
        let root = find(&mut parent, a);
        let h = holes.entry(root).or_default();
        h.edges += 1;
        let cands = s.candidates(a, b);
        if cands.is_empty() {
            h.no_candidate += 1;
        }
        for t in cands {
            match s.check(a, b, f, t, max_turn) {
                Ok(_) => {}
                Err(Reject::Turn) => h.turn += 1,
                Err(Reject::Size) => h.size += 1,
                Err(Reject::Manifold | Reject::Orientation | Reject::Handle) => h.manifold += 1,
            }
        }
    }
    let mut out: Vec<HoleReport> = holes.into_values().collect();
    out.sort_by_key(|h| std::cmp::Reverse(h.edges));
    out
}

#[derive(Debug, PartialEq)]
struct Cand {
    turn: f64,
    facet: u32,
    edge: (u32, u32),
}

impl Eq for Cand {}

impl Ord for Cand {
    // Smallest turn first, then lowest facet id (a max-heap, hence reversed).
    fn cmp(&self, o: &Self) -> Ordering {
        o.turn
            .total_cmp(&self.turn)
            .then(o.facet.cmp(&self.facet))
            .then(o.edge.cmp(&self.edge))
    }
}

impl PartialOrd for Cand {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Largest piece removed as a bubble or crumb, in faces.
const MAX_BUBBLE: usize = 8;

/// Fewest faces a surface needs before its small pieces count as crumbs.
const MIN_FACES_FOR_BUBBLES: usize = 64;

/// Longest new edge of an added triangle, in local edge lengths.
const MAX_SIZE: f64 = 2.5;

/// Rounds of unpinch-and-grow.
const ROUNDS: usize = 4;

/// Extends the boundary edges flattest first until no valid extension is left; returns
/// the triangles added.
fn grow(s: &mut Surface, max_turn: f64) -> usize {
    let mut heap = BinaryHeap::new();
    let push_edge = |s: &Surface, heap: &mut BinaryHeap<Cand>, a: u32, b: u32| {
        let e = s.edge_faces(a, b);
        if e[1] != NONE || e[0] == NONE {
            return;
        }
        if let Some((turn, facet)) = s.best(a, b, e[0], max_turn) {
            heap.push(Cand {
                turn,
                facet,
                edge: (a.min(b), a.max(b)),
            });
        }
    };
    let mut boundary: Vec<(u32, u32)> = s
        .edges
        .iter()
        .filter(|(_, f)| f[1] == NONE)
        .map(|(&k, _)| ((k >> 32) as u32, k as u32))
        .collect();
    boundary.sort_unstable();
    for (a, b) in boundary {
        push_edge(s, &mut heap, a, b);
    }
    let mut added = 0;
    while let Some(c) = heap.pop() {
        let (a, b) = c.edge;
        if s.count(a, b) != 1 {
            continue;
        }
        let f = s.edge_faces(a, b)[0];
        let plan = if s.in_s[c.facet as usize] || !s.can_add(c.facet) {
            None
        } else {
            s.orientation_plan(a, b, f, c.facet)
        };
        let Some(plan) = plan else {
            // Stale: look again at this edge.
            push_edge(s, &mut heap, a, b);
            continue;
        };
        s.add_oriented(a, b, f, c.facet, plan);
        added += 1;
        // The corners' fans changed: every boundary edge at them gets a fresh look.
        for v in s.corners(c.facet) {
            for w in s.boundary_neighbours(v) {
                push_edge(s, &mut heap, v, w);
            }
        }
    }
    added
}

/// Closes the holes of the facet set `faces` (Delaunay facet ids, edge-manifold) with
/// Delaunay triangles (see the module docs); returns the new facet set, sorted.
pub fn close(
    cx: &Complex,
    pts: &[DVec3],
    faces: &[u32],
    max_turn: f64,
) -> (Vec<u32>, Vec<[u32; 3]>, ClosureStats) {
    let mut s = Surface::new(cx, pts, faces);
    let mut stats = ClosureStats {
        untwisted_faces: s.untwist(),
        ..Default::default()
    };
    // Grow, then open what is still pinched, pop the bubbles growth closed, and grow
    // again.
    for _round in 0..ROUNDS {
        stats.unpinched_faces += s.unpinch();
        stats.bubble_faces += s.pop_bubbles();
        let added = grow(&mut s, max_turn);
        stats.added += added;
        if added == 0 {
            break;
        }
    }
    stats.unpinched_faces += s.unpinch();
    stats.bubble_faces += s.pop_bubbles();
    let mut extra = fill_small_holes(&mut s, &mut stats);
    extra.extend(insert_free_points(&mut s, &mut stats));
    let mut out: Vec<u32> = (0..s.in_s.len() as u32)
        .filter(|&f| s.in_s[f as usize])
        .collect();
    out.sort_unstable();
    (out, extra, stats)
}

/// Points the surface does not reach yet are inserted into the nearest surface face
/// (a Delaunay facet at one of their Delaunay neighbours) that they project into, which
/// is split in three: the output keeps every input point as a vertex. Returns the new
/// faces (the split facets leave the surface).
fn insert_free_points(s: &mut Surface, stats: &mut ClosureStats) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for v in 0..s.cx.n_vertices() as u32 {
        if s.faces_at[v as usize] > 0 {
            continue;
        }
        let p = s.pts[v as usize];
        let mut best: Option<(f64, u32)> = None;
        for &t in s.cx.row(v as usize) {
            for w in s.corners(t) {
                if w == v {
                    continue;
                }
                for &f in s.cx.row(w as usize) {
                    if !s.in_s[f as usize] {
                        continue;
                    }
                    let [a, b, c] = s.corners(f).map(|x| s.pts[x as usize]);
                    let Some(d) = projected_distance(p, a, b, c) else {
                        continue;
                    };
                    if best.is_none_or(|(bd, bf)| d < bd || (d == bd && f < bf)) {
                        best = Some((d, f));
                    }
                }
            }
        }
        let Some((_, f)) = best else { continue };
        let [a, b, c] = s.oriented(f);
        s.remove(f);
        for (x, y) in [(a, b), (b, c), (c, a)] {
            // The split triangles keep the face's edges (now marked as filled).
            let e = s.edges.entry(edge_key(x, y)).or_insert([NONE; 2]);
            if e[0] == NONE {
                e[0] = FILLED;
            } else {
                e[1] = FILLED;
            }
            out.push([x, y, v]);
        }
        s.faces_at[v as usize] += 3;
        stats.inserted_points += 1;
    }
    out
}

/// Distance from `p` to the plane of triangle `abc` when its projection falls inside
/// the triangle (`None` otherwise or for a degenerate triangle).
fn projected_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let n = (b - a).cross(c - a);
    let nn = n.length_squared();
    if nn <= 0.0 || !nn.is_finite() {
        return None;
    }
    let d = (p - a).dot(n) / nn;
    let q = p - n * d;
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(x, y)| (y - x).cross(q - x).dot(n) >= 0.0);
    inside.then(|| (p - q).length())
}

/// Longest hole loop the polygon fill triangulates.
pub const MAX_FILL: usize = 64;

/// Marks an edge's face slot taken by a fill triangle (not a Delaunay facet).
const FILLED: u32 = u32::MAX - 1;

/// The boundary loops as vertex cycles, each from its lowest vertex; loops through a
/// vertex with other than two boundary edges (none after unpinching) are left out.
fn boundary_loops(s: &Surface) -> Vec<Vec<u32>> {
    let mut nb: HashMap<u32, Vec<u32>> = HashMap::new();
    for (&k, f) in &s.edges {
        if f[0] != NONE && f[1] == NONE {
            let (a, b) = ((k >> 32) as u32, k as u32);
            nb.entry(a).or_default().push(b);
            nb.entry(b).or_default().push(a);
        }
    }
    let mut starts: Vec<u32> = nb.keys().copied().collect();
    starts.sort_unstable();
    let mut seen: HashSet<u32> = HashSet::new();
    let mut loops = Vec::new();
    for v0 in starts {
        if seen.contains(&v0) {
            continue;
        }
        let mut lp = vec![v0];
        seen.insert(v0);
        let mut ok = nb[&v0].len() == 2;
        let (mut prev, mut cur) = (v0, nb[&v0].iter().copied().min().unwrap_or(v0));
        while ok && cur != v0 {
            let n = &nb[&cur];
            if n.len() != 2 || !seen.insert(cur) {
                ok = false;
                break;
            }
            lp.push(cur);
            let next = if n[0] == prev { n[1] } else { n[0] };
            (prev, cur) = (cur, next);
        }
        if ok && lp.len() >= 3 {
            loops.push(lp);
        }
    }
    loops
}

/// A triangulation of the polygon `lp` of least total area whose diagonals are not
/// edges of the surface yet (and, with `check`, whose triangles cross no surface face
/// within two rings that they share no vertex with) (dynamic programming over sub-polygons, as in Liepa's hole
/// filling with the area weight); `None` when every triangulation would reuse an edge.
fn fill_polygon(s: &Surface, lp: &[u32], check: bool) -> Option<Vec<[u32; 3]>> {
    let n = lp.len();
    let p = |i: usize| s.pts[lp[i] as usize];
    let local = if check {
        local_faces(s, lp)
    } else {
        Vec::new()
    };
    // A candidate triangle must not cross a nearby face it shares no vertex with.
    let crosses = |t: [u32; 3]| {
        let tri = t.map(|v| s.pts[v as usize]);
        local.iter().any(|(ids, f)| {
            !ids.iter().any(|v| t.contains(v))
                && reconbench_geom::spatial::tri_tri_intersect(&tri, f)
        })
    };
    let free =
        |i: usize, j: usize| j - i == 1 || (i == 0 && j == n - 1) || s.count(lp[i], lp[j]) == 0;
    let mut cost = vec![f64::INFINITY; n * n];
    let mut split = vec![usize::MAX; n * n];
    for i in 0..n - 1 {
        cost[i * n + i + 1] = 0.0;
    }
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !free(i, j) {
                continue;
            }
            for k in i + 1..j {
                let c = cost[i * n + k] + cost[k * n + j];
                if !c.is_finite()
                    || s.is_face(lp[i], lp[k], lp[j])
                    || crosses([lp[i], lp[k], lp[j]])
                {
                    continue;
                }
                let area = 0.5 * (p(k) - p(i)).cross(p(j) - p(i)).length();
                if c + area < cost[i * n + j] {
                    cost[i * n + j] = c + area;
                    split[i * n + j] = k;
                }
            }
        }
    }
    if !cost[n - 1].is_finite() {
        return None;
    }
    let mut tris = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j - i < 2 {
            continue;
        }
        let k = split[i * n + j];
        tris.push([lp[i], lp[k], lp[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some(tris)
}

/// Longest hole loop whose fill is checked against crossing the surface around it.
const CHECKED_FILL: usize = 32;

/// The surface faces within two rings of a loop's vertices, with their corners.
fn local_faces(s: &Surface, lp: &[u32]) -> Vec<([u32; 3], [DVec3; 3])> {
    let mut ring: Vec<u32> = lp.to_vec();
    for &v in lp {
        for &f in s.cx.row(v as usize) {
            if s.in_s[f as usize] {
                ring.extend(s.corners(f));
            }
        }
    }
    ring.sort_unstable();
    ring.dedup();
    let mut faces: Vec<u32> = ring
        .iter()
        .flat_map(|&v| s.cx.row(v as usize).iter().copied())
        .filter(|&f| s.in_s[f as usize])
        .collect();
    faces.sort_unstable();
    faces.dedup();
    faces
        .into_iter()
        .map(|f| {
            let c = s.corners(f);
            (c, c.map(|v| s.pts[v as usize]))
        })
        .collect()
}

/// Fills the holes of at most [`MAX_FILL`] edges that no Delaunay triangle can close
/// (the last resort: their triangles are not Delaunay facets), loop by loop.
fn fill_small_holes(s: &mut Surface, stats: &mut ClosureStats) -> Vec<[u32; 3]> {
    let mut extra = Vec::new();
    for lp in boundary_loops(s) {
        if lp.len() > MAX_FILL {
            continue;
        }
        // Prefer a fill that crosses no nearby face; a closed surface comes first, so
        // without one the least-area fill is taken anyway.
        let checked = (lp.len() <= CHECKED_FILL)
            .then(|| fill_polygon(s, &lp, true))
            .flatten();
        let Some(tris) = checked.or_else(|| fill_polygon(s, &lp, false)) else {
            continue;
        };
        for t in &tris {
            for (x, y) in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                let e = s.edges.entry(edge_key(x, y)).or_insert([NONE; 2]);
                if e[0] == NONE {
                    e[0] = FILLED;
                } else {
                    e[1] = FILLED;
                }
            }
        }
        stats.filled_holes += 1;
        stats.fill_triangles += tris.len();
        extra.extend(tris);
    }
    extra
}
