//! Stage 4 of EBT (paper §5): the mesh grown from a seed over the thinned set Q. Points
//! are taken in order of increasing distance from the seed and linked to the visible
//! boundary edges of the growing mesh under the five rules: edges <= Omega, smallest
//! angle > theta, manifold edges (no T-junction), boundary-only linking, visibility.
//!
//! The mesh stays a topological disc: a point joins by a fan over a run of consecutive
//! boundary edges and becomes a boundary vertex; the run's inner vertices become
//! interior; ears close gaps. So there is always one boundary loop, stored as a doubly
//! linked list over the vertices (`next`, `prev`) with the facet owning each boundary
//! edge (`bface`).

use std::collections::HashSet;

use glam::DVec3;
use reconbench_geom::linalg::{covariance, sym_eigen3};
use reconbench_geom::method::MethodError;

use super::geometry::{
    Proj, edge_key, face_cross, interior_distance, min_angle, orient, proper_cross,
    segment_distance, strictly_inside,
};
use super::grid::Grid;

const FREE: u8 = 0;
const BOUNDARY: u8 = 1;
const INTERIOR: u8 = 2;

/// T-junction tolerance, relative to Omega (spec §3.5 G3e).
const TJ_REL: f64 = 1e-3;

/// Seed candidates tried (nearest the centroid first) when no first triangle forms.
const SEED_TRIES: usize = 64;

/// Insertions between two calls of the cancellation check.
const CHECK_EVERY: usize = 2048;

/// Options of [`grow`].
#[derive(Debug, Clone, Copy)]
pub struct GrowOpts {
    /// Maximum edge length Omega (Rule 1).
    pub omega: f64,
    /// Minimum angle theta, radians (Rule 2).
    pub min_angle: f64,
    /// ASSUMPTION E19: ear filling.
    pub ear_filling: bool,
    /// Largest gap angle an ear may close (radians; E19: 90 degrees).
    pub ear_angle: f64,
    /// Retry deferred points as soon as a point within Omega joins (else only in the
    /// next pass, G4 literally).
    pub wake_deferred: bool,
    /// Seed as an index into the points; `None` = ASSUMPTION E11.
    pub seed: Option<u32>,
}

/// The grown mesh over the points given to [`grow`].
#[derive(Debug, Clone, PartialEq)]
pub struct Grown {
    /// Facets (indices into the points), consistently oriented.
    pub faces: Vec<[u32; 3]>,
    /// Per point: whether it is a mesh vertex.
    pub meshed: Vec<bool>,
    /// The seed point.
    pub seed: u32,
    /// Passes over the remaining points (G4).
    pub passes: usize,
    /// Ears closed (E19).
    pub ears: usize,
    /// Points still deferred at the end of each pass, summed (E18).
    pub deferrals: usize,
}

/// The point of `points` nearest `x` (ties to the lower index): a user seed that
/// binning did not keep is replaced by it.
pub fn default_seed_near(points: &[DVec3], x: DVec3) -> u32 {
    let mut best = (f64::INFINITY, 0u32);
    for (i, p) in points.iter().enumerate() {
        let d = (*p - x).length_squared();
        if d < best.0 {
            best = (d, i as u32);
        }
    }
    best.1
}

struct Front<'a> {
    p: &'a [DVec3],
    omega: f64,
    min_angle: f64,
    tj: f64,
    grid: Grid,
    state: Vec<u8>,
    next: Vec<u32>,
    prev: Vec<u32>,
    bface: Vec<u32>,
    faces: Vec<[u32; 3]>,
    normals: Vec<DVec3>,
    edges: HashSet<u64>,
    loop_len: usize,
    ear_angle: f64,
    head: u32,
    ears: usize,
    near: Vec<u32>,
    cand: Vec<(f64, u32)>,
    alive: Vec<bool>,
    visible: Vec<u32>,
    chain: Vec<u32>,
    ok: Vec<bool>,
    seg: Vec<bool>,
}

impl<'a> Front<'a> {
    fn add_face(&mut self, f: [u32; 3]) -> u32 {
        let (a, b, c) = (
            self.p[f[0] as usize],
            self.p[f[1] as usize],
            self.p[f[2] as usize],
        );
        self.faces.push(f);
        self.normals.push(face_cross(a, b, c).normalize_or_zero());
        (self.faces.len() - 1) as u32
    }

    /// Boundary vertices within `r` of `x` into `self.near`, ascending.
    fn gather(&mut self, x: DVec3, r: f64) {
        self.near.clear();
        let (state, p, near) = (&self.state, self.p, &mut self.near);
        self.grid.for_each_near(x, r, |j| {
            if state[j as usize] == BOUNDARY && (p[j as usize] - x).length() <= r {
                near.push(j);
            }
        });
        self.near.sort_unstable();
    }

    /// Whether segment `a`-`b` (new edge, in the projection `pr`) is free of
    /// T-junctions with and proper crossings of the boundary near it.
    fn segment_ok(&self, pr: &Proj, a: u32, b: u32) -> bool {
        let (pa, pb) = (self.p[a as usize], self.p[b as usize]);
        let (qa, qb) = (pr.at(pa), pr.at(pb));
        for &w in &self.near {
            if w != a
                && w != b
                && interior_distance(self.p[w as usize], pa, pb).is_some_and(|d| d < self.tj)
            {
                return false;
            }
            let x = self.next[w as usize];
            if proper_cross(qa, qb, pr.at(self.p[w as usize]), pr.at(self.p[x as usize])) {
                return false;
            }
        }
        true
    }

    /// Whether no near boundary vertex other than the corners lies inside `a b c`.
    fn empty_triangle(&self, pr: &Proj, t: [u32; 3]) -> bool {
        let (a, b, c) = (
            pr.at(self.p[t[0] as usize]),
            pr.at(self.p[t[1] as usize]),
            pr.at(self.p[t[2] as usize]),
        );
        self.near
            .iter()
            .all(|&w| t.contains(&w) || !strictly_inside(pr.at(self.p[w as usize]), a, b, c))
    }

    /// G3: tries to link free point `qi` to the visible boundary; true when it joined.
    fn insert(&mut self, qi: u32, ear_filling: bool) -> bool {
        let q = self.p[qi as usize];
        let om = self.omega;
        // Boundary edges with an endpoint within 2 Omega can cross a new facet.
        self.gather(q, 2.0 * om);
        // ASSUMPTION E13: candidate edges have both endpoints within Omega of q.
        // ASSUMPTION E14: ranked by the point-to-segment distance.
        self.cand.clear();
        for &u in &self.near {
            let v = self.next[u as usize];
            let (pu, pv) = (self.p[u as usize], self.p[v as usize]);
            // Rule 3: q on (or at) a boundary edge would make a T-junction.
            if segment_distance(q, pu, pv) < self.tj {
                return false;
            }
            if (q - pu).length() <= om && (q - pv).length() <= om {
                self.cand.push((segment_distance(q, pu, pv), u));
            }
        }
        if self.cand.is_empty() {
            return false;
        }
        self.cand
            .sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        // ASSUMPTION E15: the plane through q normal to the mean normal of the facets on
        // the candidate edges.
        let n: DVec3 = self
            .cand
            .iter()
            .map(|&(_, u)| self.normals[self.bface[u as usize] as usize])
            .sum();
        let Some(n) = n.try_normalize() else {
            return false;
        };
        let pr = Proj::new(q, n);
        let o = pr.at(q);
        // Visibility by shadowing (G3c).
        self.alive.clear();
        self.alive.resize(self.cand.len(), true);
        self.visible.clear();
        for i in 0..self.cand.len() {
            if !self.alive[i] {
                continue;
            }
            self.alive[i] = false;
            let u = self.cand[i].1;
            let v = self.next[u as usize];
            let (pu, pv) = (pr.at(self.p[u as usize]), pr.at(self.p[v as usize]));
            // ASSUMPTION E16: q strictly on the outer side (right of u->v: the edge's
            // facet is on its left).
            if orient(pu, pv, o) >= 0.0 {
                continue;
            }
            self.visible.push(u);
            for j in i + 1..self.cand.len() {
                if self.alive[j] {
                    let a = self.cand[j].1;
                    let b = self.next[a as usize];
                    let (pa, pb) = (pr.at(self.p[a as usize]), pr.at(self.p[b as usize]));
                    if proper_cross(o, pu, pa, pb) || proper_cross(o, pv, pa, pb) {
                        self.alive[j] = false;
                    }
                }
            }
        }
        if self.visible.is_empty() {
            return false;
        }
        // ASSUMPTION E17: the maximal run of consecutive visible edges containing the
        // closest visible one; at most loop_len - 1 edges so that the loop survives.
        let c0 = self.visible[0];
        let (mut start, mut end, mut count) = (c0, c0, 1usize);
        while count + 1 < self.loop_len && self.visible.contains(&self.prev[start as usize]) {
            start = self.prev[start as usize];
            count += 1;
        }
        while count + 1 < self.loop_len && self.visible.contains(&self.next[end as usize]) {
            end = self.next[end as usize];
            count += 1;
        }
        self.chain.clear();
        let mut v = start;
        self.chain.push(v);
        for _ in 0..count {
            v = self.next[v as usize];
            self.chain.push(v);
        }
        let ci = self
            .chain
            .iter()
            .position(|&x| x == c0)
            .expect("c0 in chain");
        // G3e: per chain edge, the facet (v_i, q, v_i+1) against Rules 2-3 and overlap.
        let k = count;
        let mut seg = std::mem::take(&mut self.seg);
        seg.clear();
        seg.extend((0..=k).map(|i| self.segment_ok(&pr, qi, self.chain[i])));
        self.ok.clear();
        for i in 0..k {
            let (a, b) = (self.chain[i], self.chain[i + 1]);
            let (pa, pb) = (self.p[a as usize], self.p[b as usize]);
            let nf = face_cross(pa, q, pb);
            let good = seg[i]
                && seg[i + 1]
                && min_angle(pa, q, pb) > self.min_angle
                && nf.dot(self.normals[self.bface[a as usize] as usize]) > 0.0
                && self.empty_triangle(&pr, [a, qi, b]);
            self.ok.push(good);
        }
        self.seg = seg;
        if !self.ok[ci] {
            return false;
        }
        let (mut lo, mut hi) = (ci, ci);
        while lo > 0 && self.ok[lo - 1] {
            lo -= 1;
        }
        while hi + 1 < k && self.ok[hi + 1] {
            hi += 1;
        }
        // G3f: add the fan, splice v_lo -> q -> v_hi+1.
        let mut first = 0;
        let mut last = 0;
        for i in lo..=hi {
            let (a, b) = (self.chain[i], self.chain[i + 1]);
            let f = self.add_face([a, qi, b]);
            if i == lo {
                first = f;
            }
            last = f;
        }
        for i in lo..=hi + 1 {
            self.edges.insert(edge_key(qi, self.chain[i]));
        }
        for i in lo + 1..=hi {
            self.state[self.chain[i] as usize] = INTERIOR;
        }
        let (v0, vk) = (self.chain[lo], self.chain[hi + 1]);
        self.next[v0 as usize] = qi;
        self.prev[qi as usize] = v0;
        self.next[qi as usize] = vk;
        self.prev[vk as usize] = qi;
        self.bface[v0 as usize] = first;
        self.bface[qi as usize] = last;
        self.state[qi as usize] = BOUNDARY;
        self.head = qi;
        self.loop_len = self.loop_len + 1 - (hi - lo);
        if ear_filling {
            let mut stack = vec![v0, vk];
            while let Some(w) = stack.pop() {
                if self.state[w as usize] == BOUNDARY && self.try_ear(w) {
                    stack.push(self.prev[w as usize]);
                    stack.push(self.next[w as usize]);
                }
            }
        }
        true
    }

    /// Ear filling over the whole boundary loop until no ear
    /// closes; returns the number closed. Cracks where two arms of the front met behind
    /// a deferred point are zipped from their apex this way.
    fn sweep_ears(&mut self) -> usize {
        let before = self.ears;
        loop {
            let start = self.ears;
            let mut v = self.head;
            for _ in 0..self.loop_len + 1 {
                let n = self.next[v as usize];
                self.try_ear(v);
                v = n;
            }
            if self.ears == start {
                return self.ears - before;
            }
        }
    }

    /// ASSUMPTION E19 (G3g): closes the ear at boundary vertex `v` when the gap angle is
    /// below 90 degrees and the ear facet passes Rules 1-3.
    fn try_ear(&mut self, v: u32) -> bool {
        if self.loop_len <= 3 {
            return false;
        }
        let (p, n) = (self.prev[v as usize], self.next[v as usize]);
        let (pv, pp, pn) = (self.p[v as usize], self.p[p as usize], self.p[n as usize]);
        if (pp - pn).length() > self.omega || self.edges.contains(&edge_key(p, n)) {
            return false;
        }
        if (pp - pv).angle_between(pn - pv) >= self.ear_angle {
            return false;
        }
        let nf = face_cross(pv, pp, pn);
        if min_angle(pv, pp, pn) <= self.min_angle
            || nf.dot(self.normals[self.bface[p as usize] as usize]) <= 0.0
            || nf.dot(self.normals[self.bface[v as usize] as usize]) <= 0.0
        {
            return false;
        }
        let Some(nu) = nf.try_normalize() else {
            return false;
        };
        self.gather(pv, 2.0 * self.omega);
        let pr = Proj::new(pv, nu);
        if !self.segment_ok(&pr, p, n) || !self.empty_triangle(&pr, [v, p, n]) {
            return false;
        }
        let f = self.add_face([v, p, n]);
        self.edges.insert(edge_key(p, n));
        self.state[v as usize] = INTERIOR;
        self.next[p as usize] = n;
        self.prev[n as usize] = p;
        self.bface[p as usize] = f;
        self.head = p;
        self.loop_len -= 1;
        self.ears += 1;
        true
    }
}

/// ASSUMPTION E12: the first triangle: the seed, its nearest point, and the first later
/// point in distance order that passes Rules 1-2 (the nearest point advances when none
/// does). Oriented so that its normal points into the half-space of `up`.
fn first_triangle(
    p: &[DVec3],
    s: u32,
    order: &[u32],
    opts: &GrowOpts,
    up: DVec3,
) -> Option<[u32; 3]> {
    let ps = p[s as usize];
    for (i1, &a) in order.iter().enumerate() {
        let pa = p[a as usize];
        if (pa - ps).length() > opts.omega {
            break;
        }
        for &b in &order[i1 + 1..] {
            let pb = p[b as usize];
            if (pb - ps).length() > opts.omega {
                break;
            }
            if (pb - pa).length() <= opts.omega && min_angle(ps, pa, pb) > opts.min_angle {
                return Some(if face_cross(ps, pa, pb).dot(up) >= 0.0 {
                    [s, a, b]
                } else {
                    [s, b, a]
                });
            }
        }
    }
    None
}

/// Grows the mesh over `p` (G0-G4). `check` is polled now and then (cancellation).
pub fn grow(
    p: &[DVec3],
    opts: &GrowOpts,
    check: &mut dyn FnMut() -> Result<(), MethodError>,
) -> Result<Grown, MethodError> {
    let n = p.len();
    if n < 3 {
        return Err(MethodError::InvalidInput(format!(
            "the thinned set has {n} points; a mesh needs at least 3 (epsilon or bin_size too large?)"
        )));
    }
    // Seed candidates: the user's seed, or (ASSUMPTION E11) the points by distance from
    // the centroid of Q; the next candidate is tried when no first triangle forms (an
    // isolated point nearest the centroid).
    let candidates: Vec<u32> = match opts.seed {
        Some(s) if (s as usize) < n => vec![s],
        Some(s) => {
            return Err(MethodError::InvalidParameter {
                name: "seed_point".into(),
                message: format!("index {s} is outside the {n} points"),
            });
        }
        None => {
            let c = p.iter().copied().sum::<DVec3>() / n as f64;
            let mut all: Vec<u32> = (0..n as u32).collect();
            all.sort_by(|&a, &b| {
                (p[a as usize] - c)
                    .length_squared()
                    .total_cmp(&(p[b as usize] - c).length_squared())
                    .then(a.cmp(&b))
            });
            all.truncate(SEED_TRIES);
            all
        }
    };
    // The global PCA normal of the single patch orients the first triangle.
    let up = sym_eigen3(covariance(p, None)?.matrix)?.vectors[0];
    let mut found = None;
    for &s in &candidates {
        // G1: the other points by ascending distance from the seed, ties by index.
        let ps = p[s as usize];
        let mut order: Vec<u32> = (0..n as u32).filter(|&i| i != s).collect();
        order.sort_by(|&a, &b| {
            (p[a as usize] - ps)
                .length_squared()
                .total_cmp(&(p[b as usize] - ps).length_squared())
                .then(a.cmp(&b))
        });
        if let Some(t0) = first_triangle(p, s, &order, opts, up) {
            found = Some((s, order, t0));
            break;
        }
    }
    let Some((s, order, t0)) = found else {
        return Err(MethodError::Failed(format!(
            "no first triangle at the seed (point {}): no two points within Omega = {:.4e} \
             form a triangle with all angles above the minimum",
            candidates[0], opts.omega
        )));
    };
    let ids: Vec<u32> = (0..n as u32).collect();
    let mut fr = Front {
        p,
        omega: opts.omega,
        min_angle: opts.min_angle,
        tj: TJ_REL * opts.omega,
        grid: Grid::new(p, &ids, opts.omega)?,
        state: vec![FREE; n],
        next: vec![u32::MAX; n],
        prev: vec![u32::MAX; n],
        bface: vec![u32::MAX; n],
        faces: Vec::new(),
        normals: Vec::new(),
        edges: HashSet::new(),
        loop_len: 3,
        ear_angle: opts.ear_angle,
        head: t0[0],
        ears: 0,
        near: Vec::new(),
        cand: Vec::new(),
        alive: Vec::new(),
        visible: Vec::new(),
        chain: Vec::new(),
        ok: Vec::new(),
        seg: Vec::new(),
    };
    let f0 = fr.add_face(t0);
    for k in 0..3 {
        let (a, b) = (t0[k], t0[(k + 1) % 3]);
        fr.state[a as usize] = BOUNDARY;
        fr.next[a as usize] = b;
        fr.prev[b as usize] = a;
        fr.bface[a as usize] = f0;
        fr.edges.insert(edge_key(a, b));
    }
    // G3-G4: passes over the remaining points until one adds nothing.
    let mut pending: Vec<u32> = order
        .iter()
        .copied()
        .filter(|&i| fr.state[i as usize] == FREE)
        .collect();
    let (mut passes, mut deferrals, mut tries) = (0usize, 0usize, 0usize);
    // Rank of each point in the distance order (woken points are retried in it).
    let mut rank = vec![0u32; n];
    for (r, &i) in order.iter().enumerate() {
        rank[i as usize] = r as u32;
    }
    let mut waiting = vec![false; n];
    let mut stack: Vec<u32> = Vec::new();
    let mut woken: Vec<u32> = Vec::new();
    loop {
        passes += 1;
        let mut deferred = Vec::new();
        let mut added = 0usize;
        for &qi in &pending {
            tries += 1;
            if tries.is_multiple_of(CHECK_EVERY) {
                check()?;
            }
            if fr.state[qi as usize] != FREE {
                continue;
            }
            if fr.insert(qi, opts.ear_filling) {
                added += 1;
                if opts.wake_deferred {
                    // Retry the deferred points within Omega of each point that joins,
                    // nearest-to-the-seed first, and so on from the ones that join.
                    stack.push(qi);
                    while let Some(x) = stack.pop() {
                        woken.clear();
                        let px = p[x as usize];
                        let (st, wt) = (&fr.state, &waiting);
                        fr.grid.for_each_near(px, opts.omega, |j| {
                            if wt[j as usize]
                                && st[j as usize] == FREE
                                && (p[j as usize] - px).length() <= opts.omega
                            {
                                woken.push(j);
                            }
                        });
                        woken.sort_unstable_by_key(|&j| rank[j as usize]);
                        for &j in &woken {
                            tries += 1;
                            if fr.state[j as usize] == FREE && fr.insert(j, opts.ear_filling) {
                                waiting[j as usize] = false;
                                added += 1;
                                stack.push(j);
                            }
                        }
                    }
                }
            } else {
                // ASSUMPTION E18: an unlinkable point is deferred and retried.
                waiting[qi as usize] = true;
                deferred.push(qi);
            }
        }
        if opts.ear_filling {
            added += fr.sweep_ears();
        }
        deferred.retain(|&i| fr.state[i as usize] == FREE);
        deferrals += deferred.len();
        if added == 0 || deferred.is_empty() {
            break;
        }
        pending = deferred;
    }
    Ok(Grown {
        meshed: fr.state.iter().map(|&x| x != FREE).collect(),
        faces: fr.faces,
        seed: s,
        passes,
        ears: fr.ears,
        deferrals,
    })
}
