//! The closure pass of `hc-it` (a named deviation, `closure = "zip"`, see
//! `docs/methods/hc_it.md`): after the sweep, meshes the points the sweep never
//! revisited and zips the cracks between NC meshes (failure modes 1 and 2 of spec §3.5).
//!
//! Every boundary edge a -> b of the sweep's mesh looks, on the far side from its
//! triangle W, for the point c within rho of both a and b that sees a-b under the largest
//! angle (the 2-D Delaunay choice, so no nearby point lies inside the new triangle). The
//! triangle (b, a, c) is added only if
//!
//! * c is unmeshed or on a boundary (never an interior vertex of a mesh);
//! * it keeps the mesh edge-manifold and consistently oriented (`Mesh::can_add`);
//! * its normal is within `theta` of W's and of every triangle it closes against (the
//!   sweep's fold test);
//! * its circumradius is at most `max_radius`: a gap is covered only where a ball of that
//!   radius fits through it, so a hole wider than that stays open (all triangles on the
//!   rim of a round hole share the hole's circumcircle);
//! * its new edges cross no edge of the triangles at its vertices (in its own plane).
//!
//! New boundary edges are queued; rounds repeat over every remaining boundary edge until
//! one adds nothing (at most [`MAX_ROUNDS`]). Between rounds, slits are split shut
//! (`split_slits`), the fans of a vertex with several are joined (`join_fans`) and
//! small loops are filled; at the end a vertex that still has several fans keeps only its
//! largest (`cut_fans`), so the output has no non-manifold vertex. The order is that of
//! the triangles, so the result is deterministic and independent of the thread count.

use std::collections::VecDeque;

use glam::DVec3;
use rayon::prelude::*;

use super::mesh::{
    AngleBound, Mesh, NONE, ONE_DEGREE, angle, circumradius, cross, min_angle, rotate_to,
};

/// Sweep triangles with an edge longer than this many rho are left out: they are the
/// bridges of the winner fallback (the nearest boundary edge of the whole NC when none
/// is at P's neighbours), which span holes and cracks; the pass re-meshes around them.
const BRIDGE: f64 = 1.5;

/// Passes of the fold vote at most.
const UNFOLD_PASSES: usize = 4;

/// Rounds over the remaining boundary edges at most.
pub const MAX_ROUNDS: usize = 8;

/// Marks of the triangles one overlap test has seen (each is tested once).
#[derive(Debug, Default)]
struct Visit {
    mark: Vec<u32>,
    generation: u32,
}

impl Visit {
    /// Starts a visit of a mesh with `tris` triangles.
    fn start(&mut self, tris: usize) {
        self.mark.resize(tris, 0);
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.mark.fill(0);
            self.generation = 1;
        }
    }

    /// Whether triangle `t` is seen for the first time in this visit.
    #[inline]
    fn first(&mut self, t: u32) -> bool {
        let m = &mut self.mark[t as usize];
        let fresh = *m != self.generation;
        *m = self.generation;
        fresh
    }
}

/// Options of the pass (lengths in input units).
#[derive(Debug, Clone)]
pub struct ZipOpts {
    /// rho: the largest edge (the neighbour lists hold the points strictly within it).
    pub rho: f64,
    /// Fold threshold theta (rad).
    pub theta: f64,
    /// Largest circumradius of a closing triangle.
    pub max_radius: f64,
}

/// Counters of the pass.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ZipStats {
    /// Triangles added.
    pub triangles: usize,
    /// Points the sweep left unmeshed that the pass meshed.
    pub attached: usize,
    /// Rounds run.
    pub rounds: usize,
    /// Folded sweep triangles left out.
    pub unfolded: usize,
    /// Triangles filling small boundary loops.
    pub filled: usize,
    /// Boundary triangles split at a slit's vertex (`split_slits`).
    pub slits: usize,
    /// Triangles joining two fans at a vertex (`join_fans`).
    pub joined: usize,
    /// Triangles removed to cut a second fan loose from a vertex (`cut_fans`).
    pub cut: usize,
}

/// Makes every vertex manifold: at a vertex with several fans (triangle groups around
/// it connected through its edges), every fan but the largest loses its triangles at
/// that vertex. Returns the rebuilt mesh and the triangles removed.
fn cut_fans(mut mesh: Mesh, n: usize) -> (Mesh, usize) {
    let mut drop = vec![false; mesh.tris.len()];
    // (triangle, fan label, its two vertices other than v)
    let mut fan: Vec<(u32, u32, [u32; 2])> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    for v in 0..n as u32 {
        let ts = &mesh.vt[v as usize];
        if ts.len() < 2 {
            continue;
        }
        // Fans: flood over the triangles at v through the edges (v, w).
        fan.clear();
        fan.extend(ts.iter().map(|&t| {
            let r = rotate_to(mesh.tris[t as usize], v);
            (t, u32::MAX, [r[1], r[2]])
        }));
        let mut label = 0u32;
        for s in 0..fan.len() {
            if fan[s].1 != u32::MAX {
                continue;
            }
            fan[s].1 = label;
            stack.clear();
            stack.push(s);
            while let Some(i) = stack.pop() {
                for w in fan[i].2 {
                    // The triangles of edge (v, w): those at v that contain w.
                    for (j, e) in fan.iter_mut().enumerate() {
                        if e.1 == u32::MAX && e.2.contains(&w) {
                            e.1 = label;
                            stack.push(j);
                        }
                    }
                }
            }
            label += 1;
        }
        if label < 2 {
            continue;
        }
        let size = |l: u32| fan.iter().filter(|e| e.1 == l).count();
        let keep = (0..label)
            .max_by(|&a, &b| size(a).cmp(&size(b)).then(b.cmp(&a)))
            .unwrap_or(0);
        for &(t, l, _) in &fan {
            if l != keep {
                drop[t as usize] = true;
            }
        }
    }
    let cut = drop.iter().filter(|&&d| d).count();
    if cut == 0 {
        return (mesh, 0);
    }
    // A subset of an edge-manifold, consistently oriented mesh is one: every triangle
    // can be added again.
    // Rebuilt in place (the state of a new mesh, without reallocating its lists).
    let tris = std::mem::take(&mut mesh.tris);
    mesh.clear();
    mesh.tris.reserve(tris.len() - cut);
    for (t, d) in tris.iter().zip(&drop) {
        if !d {
            mesh.add_known(*t);
        }
    }
    (mesh, cut)
}

/// Longest new edge (in rho) of a triangle joining two fans: the two fans' edges at the
/// vertex are each shorter than rho, so the gap's third side may be longer.
const JOIN_MAX_EDGE: f64 = 1.5;

/// Joins the fans of every vertex v that has more than one (a non-manifold vertex, left
/// by the bridging rounds): for each boundary edge a -> v, the triangle (v, a, b) with
/// the outgoing boundary edge v -> b that turns least from a around v (the gap between
/// the two fans), under the checks of [`try_triangle`] except the circumradius (the gap
/// is a wedge, not a hole). Returns the triangles added.
fn join_fans<'b>(
    mesh: &mut Mesh,
    p: &[DVec3],
    nbrs: &impl Fn(u32) -> &'b [u32],
    o: &ZipOpts,
) -> usize {
    let mut buf = Vec::new();
    let mut seen = Visit::default();
    (0..p.len() as u32)
        .map(|v| join_at(mesh, &mut seen, p, nbrs, o, v, &mut buf))
        .sum()
}

/// Outgoing boundary edges at `v`: more than one means several fans (a non-manifold
/// vertex).
fn gaps_at(mesh: &Mesh, v: u32) -> usize {
    mesh.boundary_out(v) as usize
}

/// [`join_fans`] at one vertex; returns the triangles added.
#[allow(clippy::too_many_arguments)]
fn join_at<'b>(
    mesh: &mut Mesh,
    seen: &mut Visit,
    p: &[DVec3],
    nbrs: &impl Fn(u32) -> &'b [u32],
    o: &ZipOpts,
    v: u32,
    buf: &mut Vec<(u32, u32, u32)>,
) -> usize {
    if gaps_at(mesh, v) <= 1 {
        return 0;
    }
    buf.clear();
    mesh.boundary_at(v, buf);
    let loose = ZipOpts {
        max_radius: f64::INFINITY,
        ..o.clone()
    };
    let ins: Vec<(u32, u32)> = buf
        .iter()
        .filter(|&&(_, b, _)| b == v)
        .map(|&(a, _, t)| (a, t))
        .collect();
    let mut added = 0;
    for (a, t) in ins {
        if !mesh.is_boundary(a, v) {
            continue;
        }
        let n = cross(p, mesh.tris[t as usize]);
        let back = p[a as usize] - p[v as usize];
        buf.clear();
        mesh.boundary_at(v, buf);
        let ccw = |w: u32| {
            let d = p[w as usize] - p[v as usize];
            let x = back.cross(d).dot(n).atan2(back.dot(d));
            if x <= 0.0 {
                x + std::f64::consts::TAU
            } else {
                x
            }
        };
        let Some(b) = buf
            .iter()
            .filter(|&&(x, w, _)| x == v && w != a)
            .map(|&(_, w, _)| w)
            .min_by(|&x, &y| ccw(x).total_cmp(&ccw(y)).then(x.cmp(&y)))
        else {
            continue;
        };
        if p[a as usize].distance(p[b as usize]) < JOIN_MAX_EDGE * o.rho
            && try_triangle(mesh, seen, p, nbrs, &loose, [v, a, b], n)
        {
            added += 1;
        }
    }
    added
}

/// Largest angle (rad) at which a slit's sides meet: a boundary vertex y after (or
/// before) boundary edge u -> v is zipped into that edge only when the gap between them,
/// seen from v (or u), is narrower than this. A round hole's rim turns by far more.
const SLIT_ANGLE: f64 = 0.5;

/// [`SLIT_ANGLE`] with its cosine (cos 0.5), for deciding the test on the cosine.
const SLIT_BOUND: AngleBound = AngleBound::with_cos(SLIT_ANGLE, 0.877_582_561_890_372_8);

/// Closes slits: gaps between a boundary edge u -> v of triangle T = (u, v, d) and the
/// boundary vertex y next to it along the boundary (edge v -> y, or y -> u) where y lies
/// in the gap close to segment u-v (angle u-v-y, or v-u-y, under [`SLIT_ANGLE`], y's
/// projection inside the segment). Such a gap is a sliver no non-degenerate triangle
/// (u, v, y) closes, as on exact grids where y is collinear with u and v; instead T is
/// split at y into (u, y, d) and (y, v, d), which closes the gap's side next to y and
/// leaves the rest of the slit to the same step. The split keeps the mesh edge-manifold
/// and consistently oriented, and both halves within `theta` of T's normal. Returns the
/// triangles split.
fn split_slits(mesh: &mut Mesh, p: &[DVec3], theta: f64) -> usize {
    let mut queue: VecDeque<(u32, u32)> = boundary_edges(mesh).collect();
    let mut buf = Vec::new();
    let mut cands: Vec<(u32, u32)> = Vec::new();
    let mut split = 0;
    while let Some((u, v)) = queue.pop_front() {
        if !mesh.is_boundary(u, v) {
            continue;
        }
        // Boundary neighbours: y after v (v -> y), then x before u (x -> u).
        cands.clear();
        buf.clear();
        mesh.boundary_at(v, &mut buf);
        cands.extend(buf.iter().filter(|e| e.0 == v).map(|e| (e.1, v)));
        buf.clear();
        mesh.boundary_at(u, &mut buf);
        cands.extend(buf.iter().filter(|e| e.1 == u).map(|e| (e.0, u)));
        for &(y, at) in &cands {
            if let Some((e1, e2)) = try_split(mesh, p, theta, u, v, y, at) {
                split += 1;
                queue.push_back(e1);
                queue.push_back(e2);
                break;
            }
        }
    }
    split
}

/// Splits the triangle of boundary edge u -> v at y when y closes a slit at `at` (u or
/// v); returns the new boundary edges to revisit.
fn try_split(
    mesh: &mut Mesh,
    p: &[DVec3],
    theta: f64,
    u: u32,
    v: u32,
    y: u32,
    at: u32,
) -> Option<((u32, u32), (u32, u32))> {
    if y == u || y == v {
        return None;
    }
    let id = mesh.edge_tris(u, v)[0];
    let t = rotate_to(mesh.tris[id as usize], u);
    let d = t[2];
    if y == d {
        return None;
    }
    let (pu, pv, py) = (p[u as usize], p[v as usize], p[y as usize]);
    let other = if at == v { pu } else { pv };
    let pa = p[at as usize];
    let (e, f) = (other - pa, py - pa);
    if SLIT_BOUND.reached_by(e, f) || f.length_squared() >= e.length_squared() {
        return None;
    }
    // y on the gap's side of u-v, or on the line up to a twentieth of |u-v| (curved
    // surfaces): not inside T.
    let n_t = cross(p, t);
    let uv = pv - pu;
    if (uv.cross(py - pu).dot(n_t.normalize_or_zero()) / uv.length()) > 0.05 * uv.length() {
        return None;
    }
    let (t1, t2) = ([u, y, d], [y, v, d]);
    if mesh.has_edge(y, d) {
        return None;
    }
    // The new boundary-side edges u -> y and y -> v: free, or closing a boundary edge.
    for (a, b) in [(u, y), (y, v)] {
        if mesh.has_edge(a, b) && !mesh.is_boundary(b, a) {
            return None;
        }
    }
    let (n1, n2) = (cross(p, t1), cross(p, t2));
    if n1.length_squared() == 0.0
        || n2.length_squared() == 0.0
        || angle(n1, n_t) >= theta
        || angle(n2, n_t) >= theta
    {
        return None;
    }
    mesh.replace(id, t1);
    if mesh.add(t2).is_none() {
        mesh.replace(id, t);
        return None;
    }
    Some(((u, y), (y, v)))
}

/// Loops of at most this many edges may be filled.
const FILL_MAX_EDGES: usize = 16;

/// Fills every boundary loop of at most [`FILL_MAX_EDGES`] edges whose vertices all lie
/// within `max_radius` of their centroid (a pore a ball of that radius cannot pass) by
/// ear clipping, the ear with the largest smallest angle first; a loop stays open when
/// no ear keeps the mesh edge-manifold and consistently oriented. Returns the triangles
/// added.
fn fill_small_loops(mesh: &mut Mesh, p: &[DVec3], max_radius: f64, theta: f64) -> usize {
    let edges: Vec<(u32, u32)> = boundary_edges(mesh).collect();
    // The outgoing boundary edges of each vertex in edge order, as flat arrays: `start`
    // indexes `head` by vertex, `pos[i]` is edge i's slot.
    let n = p.len();
    let mut start = vec![0u32; n + 1];
    for &(a, _) in &edges {
        start[a as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut head = vec![0u32; edges.len()];
    let mut pos = vec![0u32; edges.len()];
    for (i, &(a, b)) in edges.iter().enumerate() {
        let f = &mut fill[a as usize];
        head[*f as usize] = b;
        pos[i] = *f;
        *f += 1;
    }
    // Slots of the edges of the loops found so far.
    let mut used = vec![false; edges.len()];
    // The trace (by its start edge, plus one) that holds each slot.
    let mut in_trace = vec![0u32; edges.len()];
    let mut loops = Vec::new();
    let mut trace: Vec<u32> = Vec::new();
    let mut lp: Vec<u32> = Vec::new();
    for (i, &(a0, b0)) in edges.iter().enumerate() {
        if used[pos[i] as usize] {
            continue;
        }
        // Edges of a loop are marked once it closes; an open trace marks nothing.
        trace.clear();
        trace.push(pos[i]);
        let trace_id = i as u32 + 1;
        in_trace[pos[i] as usize] = trace_id;
        lp.clear();
        lp.push(a0);
        let (mut u, mut v) = (a0, b0);
        let closed = loop {
            if v == a0 {
                break true;
            }
            if lp.len() > FILL_MAX_EDGES {
                break false;
            }
            lp.push(v);
            // At a vertex with several outgoing boundary edges (a bow-tie), the one that
            // turns least counter-clockwise from the way back bounds the same gap.
            let slots = start[v as usize]..start[v as usize + 1];
            let free = |k: &u32| !used[*k as usize] && in_trace[*k as usize] != trace_id;
            let next = if slots.clone().filter(free).count() <= 1 {
                slots.clone().find(free)
            } else {
                let n = cross(p, mesh.tris[mesh.edge_tris(u, v)[0] as usize]);
                let back = p[u as usize] - p[v as usize];
                let ccw = |w: u32| {
                    let d = p[w as usize] - p[v as usize];
                    let a = back.cross(d).dot(n).atan2(back.dot(d));
                    if a <= 0.0 {
                        a + std::f64::consts::TAU
                    } else {
                        a
                    }
                };
                let mut best: Option<u32> = None;
                for k in slots.clone().filter(free) {
                    let w = head[k as usize];
                    if best.is_none_or(|b| {
                        let bw = head[b as usize];
                        ccw(w).total_cmp(&ccw(bw)).then(w.cmp(&bw)).is_lt()
                    }) {
                        best = Some(k);
                    }
                }
                best
            };
            let Some(k) = next else {
                break false;
            };
            trace.push(k);
            in_trace[k as usize] = trace_id;
            (u, v) = (v, head[k as usize]);
        };
        if closed && lp.len() >= 3 {
            for &k in &trace {
                used[k as usize] = true;
            }
            loops.push(lp.clone());
        }
    }
    let mut added = 0;
    for lp in loops {
        let c = lp.iter().map(|&v| p[v as usize]).sum::<DVec3>() / lp.len() as f64;
        if lp
            .iter()
            .all(|&v| (p[v as usize] - c).length() <= max_radius)
        {
            added += clip_ears(mesh, p, theta, lp);
        }
    }
    added
}

/// Ear clipping of one boundary loop (in boundary-edge order); returns the triangles added.
fn clip_ears(mesh: &mut Mesh, p: &[DVec3], theta: f64, mut lp: Vec<u32>) -> usize {
    let mut added = 0;
    while lp.len() >= 3 {
        let m = lp.len();
        let mut best: Option<(f64, usize)> = None;
        for i in 0..m {
            let (v0, v1, v2) = (lp[i], lp[(i + 1) % m], lp[(i + 2) % m]);
            let t = [v1, v0, v2];
            if !mesh.can_add(t) {
                continue;
            }
            // An ear: no fold against the triangles on its two loop edges, no other loop
            // vertex inside it.
            let n_t = cross(p, t);
            let folds = [(v0, v1), (v1, v2)].iter().any(|&(a, b)| {
                let f = mesh.edge_tris(a, b)[0];
                f != NONE && angle(n_t, cross(p, mesh.tris[f as usize])) >= theta
            });
            if folds || n_t.length_squared() == 0.0 {
                continue;
            }
            let nu = n_t.normalize();
            let inside = lp.iter().any(|&q| {
                if q == v0 || q == v1 || q == v2 {
                    return false;
                }
                let x = p[q as usize];
                let side = |a: u32, b: u32| {
                    let (pa, pb) = (p[a as usize], p[b as usize]);
                    (pb - pa).cross(x - pa).dot(nu) > 0.0
                };
                side(v1, v0) && side(v0, v2) && side(v2, v1)
            });
            if inside {
                continue;
            }
            let q = min_angle(p[v0 as usize], p[v1 as usize], p[v2 as usize]);
            if best.is_none_or(|(bq, _)| q > bq) {
                best = Some((q, i));
            }
        }
        let Some((_, i)) = best else {
            break;
        };
        let (v0, v1, v2) = (lp[i], lp[(i + 1) % m], lp[(i + 2) % m]);
        if mesh.add([v1, v0, v2]).is_none() {
            break;
        }
        added += 1;
        lp.remove((i + 1) % m);
        if lp.len() == 2 {
            break;
        }
    }
    added
}

/// Runs the pass over `tris` (the sweep's mesh, a valid edge-manifold one) and returns the
/// extended triangle list. `nbrs(i)` lists every point of the same run strictly within
/// rho of point `i` (both earlier and later ones).
pub fn zip<'b>(
    p: &[DVec3],
    tris: Vec<[u32; 3]>,
    nbrs: impl Fn(u32) -> &'b [u32] + Sync,
    o: &ZipOpts,
    checkpoint: &mut dyn FnMut() -> Result<(), reconbench_geom::method::MethodError>,
) -> Result<(Vec<[u32; 3]>, ZipStats), reconbench_geom::method::MethodError> {
    let meshed_before: Vec<bool> = {
        let mut m = vec![false; p.len()];
        for t in &tris {
            for &v in t {
                m[v as usize] = true;
            }
        }
        m
    };
    let mut stats = ZipStats::default();
    let (mut mesh, folded) = unfold(p, tris, &nbrs, o.theta, o.rho);
    stats.unfolded = folded;
    let mut ctx = Rounds {
        buf: Vec::new(),
        cands: Vec::new(),
        tried: 0,
        seen: Visit::default(),
        failed: foldhash::HashMap::default(),
    };
    // Phase 1 never gives a vertex a second fan; phase 2 may (to bridge two pieces that
    // meet along a crack without a common vertex), and its later rounds fill the gaps;
    // then the small loops left are filled, and all of it again while it adds triangles.
    for _ in 0..CYCLES {
        let mut added = 0;
        for bowtie in [false, true] {
            for _ in 0..MAX_ROUNDS {
                stats.rounds += 1;
                let a = ctx.round(&mut mesh, p, &nbrs, o, bowtie, checkpoint)?;
                added += a;
                stats.triangles += a;
                if a == 0 {
                    break;
                }
            }
        }
        let s = split_slits(&mut mesh, p, o.theta);
        stats.slits += s;
        let j = join_fans(&mut mesh, p, &nbrs, o);
        stats.joined += j;
        let f = fill_small_loops(&mut mesh, p, o.max_radius, o.theta);
        stats.filled += f;
        if added + s + j + f == 0 {
            break;
        }
    }
    // The last bridging round may leave a vertex with two fans: join them, else cut the
    // smaller fan loose from it, and close the slits that leaves.
    stats.joined += join_fans(&mut mesh, p, &nbrs, o);
    let (m, cut) = cut_fans(mesh, p.len());
    mesh = m;
    stats.cut = cut;
    // A rebuilt mesh has a new clock: the recorded failures no longer apply.
    ctx.failed.clear();
    if cut > 0 {
        for bowtie in [false, true] {
            for _ in 0..MAX_ROUNDS {
                stats.rounds += 1;
                let a = ctx.round(&mut mesh, p, &nbrs, o, bowtie, checkpoint)?;
                stats.triangles += a;
                if a == 0 {
                    break;
                }
            }
        }
        stats.slits += split_slits(&mut mesh, p, o.theta);
        stats.filled += fill_small_loops(&mut mesh, p, o.max_radius, o.theta);
        // Those steps may pinch a vertex again (a filled loop through it): cut once more,
        // with nothing after it.
        let (m, again) = cut_fans(mesh, p.len());
        mesh = m;
        stats.cut += again;
    }
    stats.attached = mesh
        .vt
        .iter()
        .zip(&meshed_before)
        .filter(|(l, before)| !l.is_empty() && !**before)
        .count();
    Ok((mesh.tris, stats))
}

/// Cycles of zipping and loop filling at most.
const CYCLES: usize = 3;

/// Scratch space of the zipping rounds.
struct Rounds {
    buf: Vec<(u32, u32, u32)>,
    cands: Vec<(f64, u32)>,
    tried: usize,
    /// Scratch of the overlap test.
    seen: Visit,
    /// Boundary edges whose closing failed: the mesh clock after the attempt, and the
    /// phase (`bowtie`) it ran in.
    failed: foldhash::HashMap<(u32, u32), (u64, bool)>,
}

impl Rounds {
    /// Whether closing a -> b in phase `bowtie` is known to fail: it failed in the same
    /// phase and no triangle at a, b or a's rho-neighbours changed since. Everything
    /// [`close_edge`] reads is a triangle at one of those points (c is one of the
    /// neighbours; the overlap and inside tests look at the neighbours' triangles), so it
    /// would fail again: skipping it gives the same mesh.
    fn known_to_fail<'b>(
        &self,
        mesh: &Mesh,
        nbrs: &impl Fn(u32) -> &'b [u32],
        a: u32,
        b: u32,
        bowtie: bool,
    ) -> bool {
        match self.failed.get(&(a, b)) {
            Some(&(at, phase)) if phase == bowtie => {
                mesh.stamp(a) <= at
                    && mesh.stamp(b) <= at
                    && nbrs(a).iter().all(|&v| mesh.stamp(v) <= at)
            }
            _ => false,
        }
    }
}

impl Rounds {
    /// One round over every boundary edge (and the edges it creates); returns the
    /// triangles added.
    fn round<'b>(
        &mut self,
        mesh: &mut Mesh,
        p: &[DVec3],
        nbrs: &impl Fn(u32) -> &'b [u32],
        o: &ZipOpts,
        bowtie: bool,
        checkpoint: &mut dyn FnMut() -> Result<(), reconbench_geom::method::MethodError>,
    ) -> Result<usize, reconbench_geom::method::MethodError> {
        let mut queue: VecDeque<(u32, u32)> = boundary_edges(mesh).collect();
        let mut added = 0usize;
        while let Some((a, b)) = queue.pop_front() {
            self.tried += 1;
            if self.tried.is_multiple_of(4096) {
                checkpoint()?;
            }
            if !mesh.is_boundary(a, b) || self.known_to_fail(mesh, nbrs, a, b, bowtie) {
                continue;
            }
            // A bridge that is undone below leaves the mesh as it was: its stamps are
            // undone too, so it does not void the failures recorded around it.
            mesh.savepoint();
            let Some(c) = close_edge(
                mesh,
                &mut self.seen,
                p,
                nbrs,
                o,
                a,
                b,
                bowtie,
                &mut self.cands,
            ) else {
                mesh.commit();
                self.failed.insert((a, b), (mesh.clock(), bowtie));
                continue;
            };
            let mut n_new = 1;
            if bowtie && gaps_at(mesh, c) > 1 {
                // A bridge to another fan of c is kept only if the gap it leaves between
                // the fans closes at once, so no vertex is left with two fans.
                n_new += join_at(mesh, &mut self.seen, p, nbrs, o, c, &mut self.buf);
                if gaps_at(mesh, c) > 1 {
                    for _ in 0..n_new {
                        mesh.pop();
                    }
                    mesh.rollback_stamps();
                    self.failed.insert((a, b), (mesh.clock(), bowtie));
                    continue;
                }
            }
            mesh.commit();
            added += n_new;
            self.buf.clear();
            mesh.boundary_at(c, &mut self.buf);
            for &(u, v, _) in &self.buf {
                queue.push_back((u, v));
            }
            for (u, v) in [(a, c), (c, b)] {
                if mesh.is_boundary(u, v) {
                    queue.push_back((u, v));
                }
            }
        }
        Ok(added)
    }
}

/// Builds the mesh of `tris` without its folded triangles and its overlaps: first the
/// triangles whose normal is at `theta` or more from the normals of more of the
/// triangles across their edges than it agrees with are left out (repeated, so strips
/// go too), such as the fold a split leaves when P lies outside the winner triangle in
/// its plane; then, in the sweep's order, every
/// triangle that overlaps one kept before it ([`overlaps`]). Returns the mesh and the
/// number of triangles left out.
fn unfold<'b>(
    p: &[DVec3],
    tris: Vec<[u32; 3]>,
    nbrs: &(impl Fn(u32) -> &'b [u32] + Sync),
    theta: f64,
    rho: f64,
) -> (Mesh, usize) {
    let mut full = Mesh::with_capacity(p.len(), tris.len());
    for &t in &tris {
        // The sweep's triangles passed the same checks in the same order.
        let added = full.add(t);
        debug_assert!(added.is_some(), "sweep triangle {t:?} re-added");
    }
    let mut keep = vec![true; tris.len()];
    let fold_bound = AngleBound::new(theta);
    // Majority vote, repeated so that strips of folded triangles go too.
    for _ in 0..UNFOLD_PASSES {
        // Each vote reads only the previous pass's `keep`: computed in parallel, the
        // same set.
        let fold: Vec<usize> = (0..tris.len())
            .into_par_iter()
            .filter(|&id| keep[id])
            .filter(|&id| {
                let t = full.tris[id];
                let n = cross(p, t);
                let (mut agree, mut against) = (0, 0);
                for k in 0..3 {
                    if let Some(o) = full.across(id as u32, t[k], t[(k + 1) % 3])
                        && keep[o as usize]
                    {
                        if !fold_bound.reached_by(n, cross(p, full.tris[o as usize])) {
                            agree += 1;
                        } else {
                            against += 1;
                        }
                    }
                }
                against > agree
            })
            .collect();
        if fold.is_empty() {
            break;
        }
        for id in fold {
            keep[id] = false;
        }
    }
    let bridge2 = (BRIDGE * rho).powi(2);
    let cand: Vec<bool> = tris
        .iter()
        .zip(&keep)
        .map(|(t, &k)| {
            k && !(0..3)
                .any(|k| p[t[k] as usize].distance_squared(p[t[(k + 1) % 3] as usize]) > bridge2)
        })
        .collect();
    // The triangles kept before a candidate are some of the candidates before it, so
    // when it overlaps none of those (tested in parallel on the full mesh, whose ids are
    // the sweep's order) it overlaps none of the kept ones: the test below is needed
    // only where this one finds an overlap.
    let maybe: Vec<bool> = {
        let full = &full;
        let cand = &cand;
        let tris = &tris;
        (0..tris.len())
            .into_par_iter()
            .chunks(4096)
            .flat_map_iter(|ids| {
                let mut seen = Visit::default();
                ids.into_iter().map(move |i| {
                    cand[i]
                        && overlaps_among(full, &mut seen, p, tris[i], nbrs(tris[i][0]), |j| {
                            (j as usize) < i && cand[j as usize]
                        })
                })
            })
            .collect()
    };
    // The full mesh is not needed any more: its allocations are reused.
    let mut mesh = full;
    mesh.clear();
    let mut seen = Visit::default();
    let mut dropped = 0;
    for (i, t) in tris.into_iter().enumerate() {
        if cand[i]
            && !(maybe[i] && overlaps(&mesh, &mut seen, p, t, nbrs(t[0])))
            && mesh.add(t).is_some()
        {
            continue;
        }
        dropped += 1;
    }
    (mesh, dropped)
}

/// Bounding box of a triangle.
fn bbox(p: &[DVec3], t: [u32; 3]) -> (DVec3, DVec3) {
    let [a, b, c] = t.map(|v| p[v as usize]);
    (a.min(b).min(c), a.max(b).max(c))
}

/// Bit of the vertex pair t[a] == o[b] (indices mod 3).
const fn shared_bit(a: usize, b: usize) -> u16 {
    1u16 << (3 * (a % 3) + b % 3)
}

/// `SHARED[k][j]`: the bits (3 k' + j', see [`overlaps_among`]) of the vertex pairs
/// t[k'] == o[j'] that give t's edge k and o's edge j a common vertex.
const SHARED: [[u16; 3]; 3] = {
    let mut m = [[0u16; 3]; 3];
    let mut k = 0;
    while k < 3 {
        let mut j = 0;
        while j < 3 {
            m[k][j] = shared_bit(k, j)
                | shared_bit(k + 1, j)
                | shared_bit(k, j + 1)
                | shared_bit(k + 1, j + 1);
            j += 1;
        }
        k += 1;
    }
    m
};

/// Whether triangle `t` overlaps a triangle of `mesh` at its vertices or at the points
/// `near` (those whose centroid is within t's longest edge of t's plane): seen along t's
/// normal, an edge of one crosses an edge of the other, or a vertex of one lies inside
/// the other (shared vertices and edges excepted).
///
/// Each triangle is tested once (it is reached from up to three of the points), and
/// the 18 orientations a pair needs are computed once: the crossing tests and the
/// inside tests use the same signs (the same expressions as `mesh::crosses`); which
/// vertices the two share is found once, as bits.
fn overlaps(mesh: &Mesh, seen: &mut Visit, p: &[DVec3], t: [u32; 3], near: &[u32]) -> bool {
    overlaps_among(mesh, seen, p, t, near, |_| true)
}

/// [`overlaps`] with only the triangles of `mesh` that `include` accepts.
fn overlaps_among(
    mesh: &Mesh,
    seen: &mut Visit,
    p: &[DVec3],
    t: [u32; 3],
    near: &[u32],
    include: impl Fn(u32) -> bool,
) -> bool {
    let n_t = cross(p, t);
    if n_t.length_squared() == 0.0 {
        return true;
    }
    let nu = n_t.normalize();
    // Triangles farther from t's plane than its longest edge belong to another sheet.
    let p0 = p[t[0] as usize];
    let reach = (0..3)
        .map(|k| (p[t[k] as usize] - p[t[(k + 1) % 3] as usize]).length())
        .fold(0.0, f64::max);
    let pt = t.map(|v| p[v as usize]);
    // Edge vectors of t (as `orient(a, b, c) = (b - a).cross(c - a).dot(nu)` forms them).
    let te = [pt[1] - pt[0], pt[2] - pt[1], pt[0] - pt[2]];
    // Only triangles whose box meets t's box grown by `reach` can overlap it.
    let (lo, hi) = bbox(p, t);
    let (lo, hi) = (lo - DVec3::splat(reach), hi + DVec3::splat(reach));
    seen.start(mesh.tris.len());
    for &x in t.iter().chain(near) {
        for &f in &mesh.vt[x as usize] {
            if !include(f) || !seen.first(f) {
                continue;
            }
            let o = mesh.tris[f as usize];
            let (olo, ohi) = bbox(p, o);
            if olo.cmpgt(hi).any() || ohi.cmplt(lo).any() {
                continue;
            }
            let po = o.map(|v| p[v as usize]);
            let oc = (po[0] + po[1] + po[2]) / 3.0;
            if (oc - p0).dot(nu).abs() > reach {
                continue;
            }
            // d[k][j]: o[j] against t's edge k; e[j][k]: t[k] against o's edge j.
            let oe = [po[1] - po[0], po[2] - po[1], po[0] - po[2]];
            let mut d = [[0.0; 3]; 3];
            let mut e = [[0.0; 3]; 3];
            for k in 0..3 {
                for j in 0..3 {
                    d[k][j] = te[k].cross(po[j] - pt[k]).dot(nu);
                    e[j][k] = oe[j].cross(pt[k] - po[j]).dot(nu);
                }
            }
            // Bit 3 k + j: t[k] == o[j].
            let mut eq = 0u16;
            for k in 0..3 {
                for j in 0..3 {
                    eq |= u16::from(t[k] == o[j]) << (3 * k + j);
                }
            }
            for k in 0..3 {
                for j in 0..3 {
                    // Edges with a common vertex are not tested.
                    if eq & SHARED[k][j] != 0 {
                        continue;
                    }
                    // `crosses(nu, t[k], t[k + 1], o[j], o[j + 1])`.
                    let (d1, d2) = (d[k][j], d[k][(j + 1) % 3]);
                    let (d3, d4) = (e[j][k], e[j][(k + 1) % 3]);
                    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
                        return true;
                    }
                }
            }
            let strictly_inside = |s: [f64; 3]| {
                (s[0] > 0.0 && s[1] > 0.0 && s[2] > 0.0) || (s[0] < 0.0 && s[1] < 0.0 && s[2] < 0.0)
            };
            for j in 0..3 {
                // o[j] is not a vertex of t.
                if eq & (0b001_001_001 << j) == 0 && strictly_inside([d[0][j], d[1][j], d[2][j]]) {
                    return true;
                }
            }
            for k in 0..3 {
                // t[k] is not a vertex of o.
                if eq & (0b111 << (3 * k)) == 0 && strictly_inside([e[0][k], e[1][k], e[2][k]]) {
                    return true;
                }
            }
        }
    }
    false
}

/// The directed boundary edges of `mesh`, in triangle order.
fn boundary_edges(mesh: &Mesh) -> impl Iterator<Item = (u32, u32)> + '_ {
    mesh.tris
        .iter()
        .enumerate()
        .filter(|&(id, _)| mesh.boundary_bits(id as u32) != 0)
        .flat_map(move |(id, t)| {
            let bits = mesh.boundary_bits(id as u32);
            (0..3).filter_map(move |k| (bits & (1 << k) != 0).then_some((t[k], t[(k + 1) % 3])))
        })
}

/// Candidates tried per boundary edge, in order of the angle they see it under.
const TRIES: usize = 6;

/// Tries to close the boundary edge a -> b; returns c when the triangle (b, a, c) was
/// added. With `bowtie` off, a meshed c must already share an edge with the triangle, so
/// no vertex gets a second fan.
#[allow(clippy::too_many_arguments)]
fn close_edge<'b>(
    mesh: &mut Mesh,
    seen: &mut Visit,
    p: &[DVec3],
    nbrs: &impl Fn(u32) -> &'b [u32],
    o: &ZipOpts,
    a: u32,
    b: u32,
    bowtie: bool,
    cands: &mut Vec<(f64, u32)>,
) -> Option<u32> {
    let w = mesh.edge_tris(a, b)[0];
    let n_w = cross(p, mesh.tris[w as usize]);
    let (pa, pb) = (p[a as usize], p[b as usize]);
    // Free or boundary points on the far side of a-b, by the angle they see it under.
    cands.clear();
    for &c in nbrs(a) {
        if c == b {
            continue;
        }
        let pc = p[c as usize];
        if (pc - pb).length() >= o.rho || (pa - pb).cross(pc - pb).dot(n_w) <= 0.0 {
            continue;
        }
        if !mesh.vt[c as usize].is_empty() {
            if !mesh.on_boundary(c) {
                continue;
            }
            if !bowtie && !mesh.has_edge(a, c) && !mesh.has_edge(c, b) {
                continue;
            }
        }
        cands.push((angle(pa - pc, pb - pc), c));
    }
    cands.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    cands
        .iter()
        .take(TRIES)
        .map(|&(_, c)| c)
        .find(|&c| try_triangle(mesh, seen, p, nbrs, o, [b, a, c], n_w))
}

/// The checks of the module docs on t = (b, a, c) against W's normal `n_w`; adds t when
/// they pass.
#[allow(clippy::too_many_arguments)]
fn try_triangle<'b>(
    mesh: &mut Mesh,
    seen: &mut Visit,
    p: &[DVec3],
    nbrs: &impl Fn(u32) -> &'b [u32],
    o: &ZipOpts,
    t: [u32; 3],
    n_w: DVec3,
) -> bool {
    let [b, a, c] = t;
    let (pa, pb, pc) = (p[a as usize], p[b as usize], p[c as usize]);
    if !mesh.can_add(t) {
        return false;
    }
    if ONE_DEGREE.min_angle_at_most(pa, pb, pc) {
        return false;
    }
    if circumradius(pa, pb, pc) > o.max_radius {
        return false;
    }
    let n_t = cross(p, t);
    let fold = AngleBound::new(o.theta);
    if fold.reached_by(n_t, n_w) {
        return false;
    }
    // The fold test against every triangle the new one closes against.
    for (u, v) in [(a, c), (c, b)] {
        let [t0, _] = mesh.edge_tris(u, v);
        if t0 != NONE && fold.reached_by(n_t, cross(p, mesh.tris[t0 as usize])) {
            return false;
        }
    }
    // No other point inside the triangle (seen along its normal, within its
    // circumradius), no overlap with the triangles around.
    let nu = n_t.normalize();
    let h = circumradius(pa, pb, pc);
    let inside = |q: DVec3| {
        let side = |x: DVec3, y: DVec3| (y - x).cross(q - x).dot(nu) > 0.0;
        (q - pa).dot(nu).abs() < h && side(pb, pa) && side(pa, pc) && side(pc, pb)
    };
    if nbrs(a)
        .iter()
        .any(|&q| q != b && q != c && inside(p[q as usize]))
    {
        return false;
    }
    if overlaps(mesh, seen, p, t, nbrs(a)) {
        return false;
    }
    mesh.add(t).is_some()
}
