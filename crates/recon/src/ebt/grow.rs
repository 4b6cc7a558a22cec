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
    Proj, edge_key, enclosing_radius, face_cross, interior_distance, min_angle, orient,
    proper_cross, segment_distance, strictly_inside,
};
use super::grid::Grid;

const FREE: u8 = 0;
const BOUNDARY: u8 = 1;
const INTERIOR: u8 = 2;

/// T-junction tolerance, relative to Omega (spec §3.5 G3e).
const TJ_REL: f64 = 1e-3;

/// Seed candidates tried (nearest the centroid first) when no first triangle forms.
const SEED_TRIES: usize = 64;

/// Largest loop (vertices) a crack bridge may split off and fill.
const BRIDGE_LOOP: usize = 24;

/// Why a point could not link (its last failed try), for the diagnostics
/// `unmeshed_<reason>`: see [`REASONS`].
pub const REASONS: [&str; 9] = [
    "no_edge", "on_edge", "no_plane", "hidden", "crossing", "angle", "fold", "covered", "far",
];
const R_NO_EDGE: u8 = 0;
const R_ON_EDGE: u8 = 1;
const R_NO_PLANE: u8 = 2;
const R_HIDDEN: u8 = 3;
const R_CROSSING: u8 = 4;
const R_ANGLE: u8 = 5;
const R_FOLD: u8 = 6;
const R_COVERED: u8 = 7;
const R_FAR: u8 = 8;

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
    /// Crack closing after the growth (a named deviation): the longest closing edge, or
    /// `None` for the literal growth.
    pub crack_edge: Option<f64>,
    /// Longest edge of a growth facet (a named deviation above Omega: the facet must
    /// then fit in a disc of radius Omega / sqrt 2); Omega = Rule 1 and E13 literally.
    pub link_edge: f64,
    /// With crack closing: an ear that would break Rule 2 (a sliver) is closed together
    /// with an edge flip against the facet next to it when both facets then pass
    /// (a named deviation, docs/methods/ebt.md); false = no flip.
    pub sliver_flip: bool,
    /// With crack closing, after the growth: smallest angle (radians) of a crack-closing
    /// facet that breaks Rule 2 when neither a Rule-2 ear nor a flip closes the crack (a
    /// named deviation; such facets are bad facets, R2); `min_angle` = none.
    pub sliver_angle: f64,
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
    /// Facets added by crack closing.
    pub crack_facets: usize,
    /// Per facet: added by crack closing.
    pub crack_face: Vec<bool>,
    /// Crack-closing ears closed with an edge flip (sliver ears; [`GrowOpts::sliver_flip`]).
    pub crack_flips: usize,
    /// Crack-closing facets under Rule 2's angle ([`GrowOpts::sliver_angle`]).
    pub sliver_facets: usize,
    /// Points left unmeshed, by the rule that stopped their last try (see [`REASONS`]).
    pub unmeshed_by_reason: [usize; 9],
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
    /// Longest edge of a growth facet ([`GrowOpts::link_edge`]).
    link_edge: f64,
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
    /// Crack closing: the longest closing edge, `None` = literal growth.
    crack_edge: Option<f64>,
    /// Crack-closing facets added.
    crack_count: usize,
    /// Per facet: added by crack closing.
    crack_face: Vec<bool>,
    /// Edges inserted while a bridge is tentative (undone when it fails).
    edge_log: Vec<u64>,
    /// Whether a bridge is tentative.
    logging: bool,
    /// Sliver ears closed by a flip ([`GrowOpts::sliver_flip`]).
    sliver_flip: bool,
    /// Smallest angle of a crack-closing sliver facet (radians): Rule 2's theta during
    /// the growth, [`GrowOpts::sliver_angle`] after it.
    sliver_angle: f64,
    /// Sliver facets (under theta) added by crack closing.
    slivers: usize,
    /// Sliver facets added while a bridge is tentative.
    sliver_log: usize,
    /// Flips done.
    flips: usize,
    /// Facets a flip rewrote while a bridge is tentative: (slot, face, normal, crack flag).
    flip_log: Vec<(u32, [u32; 3], DVec3, bool)>,
    /// Edges a flip removed while a bridge is tentative.
    removed_log: Vec<u64>,
    /// Per point: the rule that stopped its last failed try (see [`REASONS`]).
    reason: Vec<u8>,
}

impl<'a> Front<'a> {
    fn add_face(&mut self, f: [u32; 3]) -> u32 {
        let (a, b, c) = (
            self.p[f[0] as usize],
            self.p[f[1] as usize],
            self.p[f[2] as usize],
        );
        self.faces.push(f);
        self.crack_face.push(false);
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

    /// G3: tries to link free point `qi` to the visible boundary; true when it joined
    /// (else the rule that stopped it is kept in `reason`).
    fn insert(&mut self, qi: u32, ear_filling: bool) -> bool {
        // The deviation (link_edge > Omega) is a fallback: links within Omega first, so
        // a long link never takes the place of short ones.
        let mut res = self.link(qi, ear_filling, self.omega);
        if res.is_err() && self.link_edge > self.omega {
            res = self.link(qi, ear_filling, self.link_edge);
        }
        match res {
            Ok(()) => true,
            Err(r) => {
                self.reason[qi as usize] = r;
                false
            }
        }
    }

    /// [`Self::insert`] with facet edges up to `om`; `Err` names the rule that stopped
    /// the point.
    fn link(&mut self, qi: u32, ear_filling: bool, om: f64) -> Result<(), u8> {
        let q = self.p[qi as usize];
        // Boundary edges with an endpoint within 2 Omega can cross a new facet.
        self.gather(q, 2.0 * om);
        // ASSUMPTION E13: candidate edges have both endpoints within Omega of q (within
        // link_edge with the deviation).
        // ASSUMPTION E14: ranked by the point-to-segment distance.
        self.cand.clear();
        for &u in &self.near {
            let v = self.next[u as usize];
            let (pu, pv) = (self.p[u as usize], self.p[v as usize]);
            // Rule 3: q on (or at) a boundary edge would make a T-junction.
            if segment_distance(q, pu, pv) < self.tj {
                return Err(R_ON_EDGE);
            }
            if (q - pu).length() <= om && (q - pv).length() <= om {
                self.cand.push((segment_distance(q, pu, pv), u));
            }
        }
        if self.cand.is_empty() {
            let near = self
                .near
                .iter()
                .any(|&u| (self.p[u as usize] - q).length() <= om);
            return Err(if near { R_NO_EDGE } else { R_FAR });
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
            return Err(R_NO_PLANE);
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
            return Err(R_HIDDEN);
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
                && self.within_bound_disc([a, qi, b])
                && nf.dot(self.normals[self.bface[a as usize] as usize]) > 0.0
                && self.empty_triangle(&pr, [a, qi, b])
                && !self.long_over_free(&pr, [a, qi, b]);
            self.ok.push(good);
        }
        self.seg = seg;
        if !self.ok[ci] {
            let (a, b) = (self.chain[ci], self.chain[ci + 1]);
            let (pa, pb) = (self.p[a as usize], self.p[b as usize]);
            return Err(if !(self.seg[ci] && self.seg[ci + 1]) {
                R_CROSSING
            } else if min_angle(pa, q, pb) <= self.min_angle {
                R_ANGLE
            } else if !self.within_bound_disc([a, qi, b]) || self.long_over_free(&pr, [a, qi, b]) {
                R_NO_EDGE
            } else if face_cross(pa, q, pb).dot(self.normals[self.bface[a as usize] as usize])
                <= 0.0
            {
                R_FOLD
            } else {
                R_COVERED
            });
        }
        // Two facets of the fan on a shared edge q-v_i must not fold over each other.
        let fan_n = |i: usize| {
            face_cross(
                self.p[self.chain[i] as usize],
                q,
                self.p[self.chain[i + 1] as usize],
            )
        };
        let (mut lo, mut hi) = (ci, ci);
        while lo > 0 && self.ok[lo - 1] && fan_n(lo - 1).dot(fan_n(lo)) > 0.0 {
            lo -= 1;
        }
        while hi + 1 < k && self.ok[hi + 1] && fan_n(hi).dot(fan_n(hi + 1)) > 0.0 {
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
                if self.state[w as usize] == BOUNDARY && self.try_fill(w) {
                    stack.push(self.prev[w as usize]);
                    stack.push(self.next[w as usize]);
                }
            }
        }
        Ok(())
    }

    /// Ear filling over the whole boundary loop until no ear
    /// closes; returns the number closed. Cracks where two arms of the front met behind
    /// a deferred point are zipped from their apex this way.
    fn sweep_ears(&mut self) -> usize {
        let before = self.ears;
        loop {
            let (start, start_cracks) = (self.ears, self.crack_count);
            let mut v = self.head;
            for _ in 0..self.loop_len + 1 {
                let n = self.next[v as usize];
                self.try_fill(v);
                v = n;
            }
            if self.ears == start && self.crack_count == start_cracks {
                return self.ears - before;
            }
        }
    }

    /// An E19 ear at `v`, else (with crack closing on) a crack-closing ear.
    fn try_fill(&mut self, v: u32) -> bool {
        if self.try_ear(v) {
            return true;
        }
        // During the growth a crack ear keeps its closing edge within Omega: a longer
        // boundary edge would stop later points from linking (E13) before they come.
        if self.crack_edge.is_none() {
            return false;
        }
        if self.try_close(v, self.omega) {
            self.crack_count += 1;
            return true;
        }
        false
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
        self.clip(v);
        self.ears += 1;
        true
    }

    /// Adds the facet `(v, prev v, next v)` and removes `v` from the boundary loop.
    fn clip(&mut self, v: u32) {
        let (p, n) = (self.prev[v as usize], self.next[v as usize]);
        let f = self.add_face([v, p, n]);
        self.log_edge(edge_key(p, n));
        self.state[v as usize] = INTERIOR;
        self.next[p as usize] = n;
        self.prev[n as usize] = p;
        self.bface[p as usize] = f;
        self.head = p;
        self.loop_len -= 1;
    }

    /// The gap angle at boundary vertex `v` (radians, in `[0, 2 pi)`): the angle outside
    /// the mesh between its two boundary edges, in the plane normal to the mean of the
    /// two boundary facets' normals. Below pi the gap is convex and an ear fits in it.
    fn gap_angle(&self, v: u32) -> Option<f64> {
        let (p, n) = (self.prev[v as usize], self.next[v as usize]);
        let nrm = (self.normals[self.bface[p as usize] as usize]
            + self.normals[self.bface[v as usize] as usize])
            .try_normalize()?;
        let pr = Proj::new(self.p[v as usize], nrm);
        // Mesh on the left of p -> v -> n: the gap turns clockwise from v->n to v->p.
        let (a, b) = (pr.at(self.p[n as usize]), pr.at(self.p[p as usize]));
        let g = b.perp_dot(a).atan2(b.dot(a));
        Some(if g < 0.0 {
            g + std::f64::consts::TAU
        } else {
            g
        })
    }

    /// Whether a point not yet meshed lies over the triangle `t` (inside its projection
    /// `pr`, within Omega of its plane): crack closing leaves such a gap to the point.
    fn covers_free_point(&self, pr: &Proj, t: [u32; 3]) -> bool {
        let [a, b, c] = t.map(|i| self.p[i as usize]);
        let Some(n) = face_cross(a, b, c).try_normalize() else {
            return true;
        };
        let (qa, qb, qc) = (pr.at(a), pr.at(b), pr.at(c));
        let centre = (a + b + c) / 3.0;
        let r = (a - centre)
            .length()
            .max((b - centre).length())
            .max((c - centre).length());
        let mut hit = false;
        self.grid.for_each_near(centre, r, |j| {
            let x = self.p[j as usize];
            if !hit
                && self.state[j as usize] == FREE
                && (x - a).dot(n).abs() < self.omega
                && strictly_inside(pr.at(x), qa, qb, qc)
            {
                hit = true;
            }
        });
        hit
    }

    /// Crack closing (a named deviation, not the paper's; docs/methods/ebt.md): the ear
    /// at `v` across a convex gap, its closing edge up to `max_edge`, under Rules 2-3,
    /// the fold test and the projected overlap tests of the ears.
    fn try_close(&mut self, v: u32, max_edge: f64) -> bool {
        if self.state[v as usize] != BOUNDARY || self.cycle_of_three(v) {
            return false;
        }
        let (p, n) = (self.prev[v as usize], self.next[v as usize]);
        let (pv, pp, pn) = (self.p[v as usize], self.p[p as usize], self.p[n as usize]);
        if (pp - pn).length() > max_edge || self.edges.contains(&edge_key(p, n)) {
            return false;
        }
        if !self.gap_angle(v).is_some_and(|g| g < std::f64::consts::PI) {
            return false;
        }
        let nf = face_cross(pv, pp, pn);
        let ang = min_angle(pv, pp, pn);
        let sliver = ang <= self.min_angle;
        if sliver {
            // The deviation for sliver cracks: a flip that keeps Rule 2 first, then
            // (after the growth) the sliver itself down to `sliver_angle`.
            if self.sliver_flip && self.close_by_flip(v, max_edge) {
                return true;
            }
            if ang <= self.sliver_angle {
                return false;
            }
        }
        if !self.within_bound_disc([v, p, n]) {
            return false;
        }
        if nf.dot(self.normals[self.bface[p as usize] as usize]) <= 0.0
            || nf.dot(self.normals[self.bface[v as usize] as usize]) <= 0.0
        {
            return false;
        }
        let Some(nu) = nf.try_normalize() else {
            return false;
        };
        // Every point of the ear is within Omega of v and a boundary edge is at most
        // max_edge <= 2 Omega long: edges that can cross it have an endpoint within 2 Omega.
        self.gather(pv, 2.0 * self.omega);
        let pr = Proj::new(pv, nu);
        if !self.segment_ok(&pr, p, n) {
            return false;
        }
        if !self.empty_triangle(&pr, [v, p, n]) {
            return false;
        }
        if self.covers_free_point(&pr, [v, p, n]) {
            return false;
        }
        self.clip(v);
        if let Some(x) = self.crack_face.last_mut() {
            *x = true;
        }
        if sliver {
            self.slivers += 1;
            if self.logging {
                self.sliver_log += 1;
            }
        }
        true
    }

    /// Sliver flip (a named deviation with crack closing, docs/methods/ebt.md): the ear
    /// `(v, prev v, next v)` across a convex gap breaks Rule 2, so it is closed together
    /// with a flip of one of its two edges at `v` against the facet on the other side:
    /// the quadrilateral of the sliver and that facet gets its other diagonal. Taken
    /// when both new facets pass Rule 2, fit in the disc of radius Omega / sqrt 2, lie
    /// within 90 degrees of each other, of the flipped facet and of the other boundary
    /// facet at `v`, the quadrilateral is convex in projection (the diagonals cross),
    /// the new diagonal is at most `max_edge` and not an edge yet, and the projected
    /// overlap and free-point tests of [`Self::try_close`] pass. `v` becomes interior
    /// as with an ear; one facet is added, one rewritten.
    fn close_by_flip(&mut self, v: u32, max_edge: f64) -> bool {
        let (p, n) = (self.prev[v as usize], self.next[v as usize]);
        // Two candidates: the edge v -> n (facet bface[v]) and the edge p -> v (facet
        // bface[p]); the first whose flip passes is taken.
        for flip_vn in [true, false] {
            let f = if flip_vn {
                self.bface[v as usize]
            } else {
                self.bface[p as usize]
            };
            let face = self.faces[f as usize];
            let (a, b) = if flip_vn { (v, n) } else { (p, v) };
            // The facet holds the directed edge a -> b; x is its third vertex.
            let Some(k) = (0..3).find(|&k| face[k] == a && face[(k + 1) % 3] == b) else {
                continue;
            };
            let x = face[(k + 2) % 3];
            if [v, p, n].contains(&x) {
                continue;
            }
            // New facets: the one on the new boundary edge p -> n takes the flipped
            // facet's slot (so a boundary edge of it keeps its bface entry), the one
            // at v is added.
            let (slot_face, new_face, diag, other) = if flip_vn {
                ([p, n, x], [x, v, p], (p, x), self.bface[p as usize])
            } else {
                ([x, p, n], [n, v, x], (n, x), self.bface[v as usize])
            };
            let [d0, d1] = [diag.0, diag.1].map(|i| self.p[i as usize]);
            if self.edges.contains(&edge_key(diag.0, diag.1)) || (d1 - d0).length() > max_edge {
                continue;
            }
            if !self.facet_fits(slot_face, &[f, other]) || !self.facet_fits(new_face, &[f, other]) {
                continue;
            }
            let [s0, s1, s2] = slot_face.map(|i| self.p[i as usize]);
            let [t0, t1, t2] = new_face.map(|i| self.p[i as usize]);
            let (ns, nt) = (face_cross(s0, s1, s2), face_cross(t0, t1, t2));
            if ns.dot(nt) <= 0.0 {
                continue;
            }
            let Some(nu) = (ns.normalize_or_zero() + nt.normalize_or_zero()).try_normalize() else {
                continue;
            };
            // No fold-over with the facets beyond the flipped facet's two other edges
            // (b -> x and x -> a), which the new facets take over.
            let beyond = |e0: u32, e1: u32, nrm: DVec3| {
                self.faces.iter().enumerate().all(|(g, t)| {
                    g == f as usize
                        || !(t.contains(&e0) && t.contains(&e1))
                        || nrm.dot(self.normals[g]) > 0.0
                })
            };
            let (nb, na) = if slot_face.contains(&b) {
                (ns, nt)
            } else {
                (nt, ns)
            };
            if !beyond(b, x, nb) || !beyond(x, a, na) {
                continue;
            }
            let pv = self.p[v as usize];
            self.gather(pv, 2.0 * self.omega);
            let pr = Proj::new(pv, nu);
            // Convex quadrilateral: the old diagonal (a-b) and the new one cross.
            let [pa, pb] = [a, b].map(|i| pr.at(self.p[i as usize]));
            if !proper_cross(pa, pb, pr.at(d0), pr.at(d1))
                || !self.segment_ok(&pr, p, n)
                || !self.empty_triangle(&pr, slot_face)
                || !self.empty_triangle(&pr, new_face)
                || self.covers_free_point(&pr, slot_face)
                || self.covers_free_point(&pr, new_face)
            {
                continue;
            }
            if self.logging {
                self.flip_log.push((
                    f,
                    face,
                    self.normals[f as usize],
                    self.crack_face[f as usize],
                ));
                self.removed_log.push(edge_key(a, b));
            }
            self.faces[f as usize] = slot_face;
            self.normals[f as usize] = ns.normalize_or_zero();
            self.crack_face[f as usize] = true;
            self.edges.remove(&edge_key(a, b));
            self.log_edge(edge_key(diag.0, diag.1));
            let g = self.add_face(new_face);
            self.crack_face[g as usize] = true;
            self.log_edge(edge_key(p, n));
            self.state[v as usize] = INTERIOR;
            self.next[p as usize] = n;
            self.prev[n as usize] = p;
            self.bface[p as usize] = f;
            self.head = p;
            self.loop_len -= 1;
            self.flips += 1;
            return true;
        }
        false
    }

    /// Whether the facet `t` has an edge longer than Omega (a long link, deviation
    /// `link_edge`) and covers a point not yet meshed (projection `pr`): such a link
    /// would skip the point.
    fn long_over_free(&self, pr: &Proj, t: [u32; 3]) -> bool {
        let l = |x: u32, y: u32| (self.p[x as usize] - self.p[y as usize]).length();
        let longest = l(t[0], t[1]).max(l(t[1], t[2])).max(l(t[2], t[0]));
        longest > self.omega && self.covers_free_point(pr, t)
    }

    /// Whether the facet `f` fits in a disc of radius Omega / sqrt 2 (a crack-closing
    /// facet: every point of it is then within Omega / sqrt 2 of a vertex, the distance
    /// bound of the paper's Appendix A; a facet whose edges are at most Omega has
    /// radius at most Omega / sqrt 3).
    fn within_bound_disc(&self, f: [u32; 3]) -> bool {
        let [a, b, c] = f.map(|i| self.p[i as usize]);
        enclosing_radius(a, b, c) <= self.omega * std::f64::consts::FRAC_1_SQRT_2 * (1.0 + 1e-9)
    }

    /// Whether the boundary cycle through `v` has three vertices (a triangular hole).
    fn cycle_of_three(&self, v: u32) -> bool {
        let n = |x: u32| self.next[x as usize];
        n(n(n(v))) == v
    }

    /// Whether the facet `f` passes Rule 2 and lies within 90 degrees of the facets
    /// `g` (boundary facets next to it).
    fn facet_fits(&self, f: [u32; 3], g: &[u32]) -> bool {
        let [a, b, c] = f.map(|i| self.p[i as usize]);
        let nf = face_cross(a, b, c);
        min_angle(a, b, c) > self.min_angle
            && self.within_bound_disc(f)
            && g.iter().all(|&h| nf.dot(self.normals[h as usize]) > 0.0)
    }

    /// Bridges a crack where two arms of the front met (a named deviation, with crack
    /// closing): the boundary edge `u -> v` and a facing boundary edge `a -> b` (`a`
    /// near `v`, `b` near `u`, every new edge at most `max_edge`) are joined by two
    /// facets over the shorter diagonal, which splits off the loop `v ... a`; that loop
    /// (at most `BRIDGE_LOOP` vertices) is then filled by crack-closing ears. When it
    /// cannot be filled completely, everything is undone, so the boundary stays one loop.
    fn try_bridge(&mut self, u: u32, max_edge: f64) -> bool {
        let v = self.next[u as usize];
        let (pu, pv) = (self.p[u as usize], self.p[v as usize]);
        let mut near = Vec::new();
        {
            let (state, p) = (&self.state, self.p);
            self.grid.for_each_near(pv, max_edge, |j| {
                if state[j as usize] == BOUNDARY && (p[j as usize] - pv).length() <= max_edge {
                    near.push(j);
                }
            });
        }
        near.sort_unstable_by(|&x, &y| {
            (self.p[x as usize] - pv)
                .length_squared()
                .total_cmp(&(self.p[y as usize] - pv).length_squared())
                .then(x.cmp(&y))
        });
        for a in near {
            let b = self.next[a as usize];
            if [u, v].contains(&a) || [u, v].contains(&b) {
                continue;
            }
            let (pa, pb) = (self.p[a as usize], self.p[b as usize]);
            if (pb - pu).length() > max_edge {
                continue;
            }
            // The split-off loop v ... a must be short.
            let mut len = 1;
            let mut w = v;
            while w != a && len <= BRIDGE_LOOP {
                w = self.next[w as usize];
                len += 1;
            }
            if w != a {
                continue;
            }
            let (fu, fa) = (self.bface[u as usize], self.bface[a as usize]);
            // Shorter diagonal: v-b or u-a.
            let (f1, f2, diag) = if (pv - pb).length() <= (pu - pa).length() {
                ([v, u, b], [b, a, v], (v, b))
            } else {
                ([v, u, a], [u, b, a], (u, a))
            };
            if [(u, b), (a, v), diag]
                .iter()
                .any(|&(x, y)| self.edges.contains(&edge_key(x, y)))
                || (self.p[diag.0 as usize] - self.p[diag.1 as usize]).length() > max_edge
                || !self.facet_fits(f1, &[fu, fa])
                || !self.facet_fits(f2, &[fu, fa])
            {
                continue;
            }
            let [q0, q1, q2] = f1.map(|i| self.p[i as usize]);
            let [r0, r1, r2] = f2.map(|i| self.p[i as usize]);
            if face_cross(q0, q1, q2).dot(face_cross(r0, r1, r2)) <= 0.0 {
                continue;
            }
            let Some(nrm) = (face_cross(q0, q1, q2).normalize_or_zero()
                + face_cross(r0, r1, r2).normalize_or_zero())
            .try_normalize() else {
                continue;
            };
            self.gather(pv, 2.0 * self.omega + max_edge);
            let pr = Proj::new(pv, nrm);
            if !self.segment_ok(&pr, u, b)
                || !self.segment_ok(&pr, a, v)
                || !self.segment_ok(&pr, diag.0, diag.1)
                || !self.empty_triangle(&pr, f1)
                || !self.empty_triangle(&pr, f2)
                || self.covers_free_point(&pr, f1)
                || self.covers_free_point(&pr, f2)
            {
                continue;
            }
            // Tentative: journal what changes, fill the split-off loop, or undo.
            let mut saved = Vec::with_capacity(len + 2);
            let mut w = v;
            loop {
                saved.push(self.save(w));
                if w == a {
                    break;
                }
                w = self.next[w as usize];
            }
            saved.push(self.save(u));
            saved.push(self.save(b));
            let (nfaces, edges_before, head, loop_len) = (
                self.faces.len(),
                self.edge_log.len(),
                self.head,
                self.loop_len,
            );
            let (flips_before, flip_log_before, removed_before) =
                (self.flips, self.flip_log.len(), self.removed_log.len());
            self.sliver_log = 0;
            self.logging = true;
            let g1 = self.add_face(f1);
            let g2 = self.add_face(f2);
            for (x, y) in [(u, b), (a, v), diag] {
                self.log_edge(edge_key(x, y));
            }
            let (bu, ba) = if diag == (v, b) { (g1, g2) } else { (g2, g1) };
            self.next[u as usize] = b;
            self.prev[b as usize] = u;
            self.bface[u as usize] = bu;
            self.next[a as usize] = v;
            self.prev[v as usize] = a;
            self.bface[a as usize] = ba;
            let filled = self.fill_loop(v, max_edge);
            self.logging = false;
            if filled {
                self.crack_face[nfaces..].fill(true);
                self.edge_log.truncate(edges_before);
                self.flip_log.truncate(flip_log_before);
                self.removed_log.truncate(removed_before);
                return true;
            }
            // Flips rewrote older facets and removed edges: restore them, newest first.
            while self.flip_log.len() > flip_log_before {
                let (f, face, nrm, crack) = self.flip_log.pop().expect("flip journal entry");
                let i = f as usize;
                (self.faces[i], self.normals[i], self.crack_face[i]) = (face, nrm, crack);
            }
            self.flips = flips_before;
            self.slivers -= self.sliver_log;
            self.sliver_log = 0;
            for (w, st) in saved.into_iter().rev() {
                self.restore(w, st);
            }
            for k in self.edge_log.drain(edges_before..) {
                self.edges.remove(&k);
            }
            for k in self.removed_log.drain(removed_before..) {
                self.edges.insert(k);
            }
            self.faces.truncate(nfaces);
            self.normals.truncate(nfaces);
            self.crack_face.truncate(nfaces);
            self.head = head;
            self.loop_len = loop_len;
        }
        false
    }

    /// The loop state of vertex `w` (next, prev, boundary facet, state).
    fn save(&self, w: u32) -> (u32, (u32, u32, u32, u8)) {
        let i = w as usize;
        (
            w,
            (self.next[i], self.prev[i], self.bface[i], self.state[i]),
        )
    }

    /// Restores what [`Self::save`] returned.
    fn restore(&mut self, w: u32, st: (u32, u32, u32, u8)) {
        let i = w as usize;
        (self.next[i], self.prev[i], self.bface[i], self.state[i]) = st;
    }

    /// Inserts an edge, recording it while a bridge is tentative.
    fn log_edge(&mut self, k: u64) {
        if self.edges.insert(k) && self.logging {
            self.edge_log.push(k);
        }
    }

    /// Fills the boundary cycle through `v` completely by crack-closing ears (smallest
    /// gap angle first) and a last triangle; false when an ear is missing.
    fn fill_loop(&mut self, v: u32, max_edge: f64) -> bool {
        let mut cur = v;
        loop {
            if self.cycle_of_three(cur) {
                let (p, n) = (self.prev[cur as usize], self.next[cur as usize]);
                let f = [cur, p, n];
                let g = [
                    self.bface[p as usize],
                    self.bface[cur as usize],
                    self.bface[n as usize],
                ];
                if !self.facet_fits(f, &g) {
                    return false;
                }
                self.add_face(f);
                for w in f {
                    self.state[w as usize] = INTERIOR;
                }
                return true;
            }
            let mut ring = vec![cur];
            let mut w = self.next[cur as usize];
            while w != cur {
                ring.push(w);
                w = self.next[w as usize];
            }
            let mut order: Vec<(f64, u32)> = ring
                .iter()
                .filter_map(|&w| self.gap_angle(w).map(|g| (g, w)))
                .filter(|&(g, _)| g < std::f64::consts::PI)
                .collect();
            order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            let Some(&(_, w)) = order.iter().find(|&&(_, w)| self.try_close(w, max_edge)) else {
                return false;
            };
            cur = self.prev[w as usize];
        }
    }

    /// Closes cracks after the growth: ears across convex gaps of the boundary loop,
    /// smallest gap angle first (a priority queue, stale entries re-queued with their
    /// current angle), until none passes. The loop stays one loop (the mesh a disc); a
    /// rim whose gaps are at least pi, or whose ears would break Rule 2, stays open.
    /// Returns the number of facets added.
    fn close_cracks(&mut self, max_edge: f64) -> usize {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let key = |g: f64| (g * 1e9) as u64;
        let mut heap = BinaryHeap::new();
        let mut v = self.head;
        for _ in 0..self.loop_len {
            if let Some(g) = self.gap_angle(v).filter(|&g| g < std::f64::consts::PI) {
                heap.push(Reverse((key(g), v)));
            }
            v = self.next[v as usize];
        }
        let mut added = 0;
        while let Some(Reverse((k, v))) = heap.pop() {
            if self.state[v as usize] != BOUNDARY || self.loop_len <= 3 {
                continue;
            }
            let Some(g) = self.gap_angle(v) else {
                continue;
            };
            if key(g) != k {
                if g < std::f64::consts::PI {
                    heap.push(Reverse((key(g), v)));
                }
                continue;
            }
            let (p, n) = (self.prev[v as usize], self.next[v as usize]);
            if self.try_close(v, max_edge) {
                added += 1;
                for w in [p, n] {
                    if let Some(g) = self.gap_angle(w).filter(|&g| g < std::f64::consts::PI) {
                        heap.push(Reverse((key(g), w)));
                    }
                }
            }
        }
        added
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
        link_edge: opts.link_edge,
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
        crack_edge: opts.crack_edge,
        crack_count: 0,
        crack_face: Vec::new(),
        edge_log: Vec::new(),
        logging: false,
        sliver_flip: opts.sliver_flip,
        sliver_angle: opts.min_angle,
        slivers: 0,
        sliver_log: 0,
        flips: 0,
        flip_log: Vec::new(),
        removed_log: Vec::new(),
        reason: vec![R_FAR; n],
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
                        fr.grid.for_each_near(px, opts.link_edge, |j| {
                            if wt[j as usize]
                                && st[j as usize] == FREE
                                && (p[j as usize] - px).length() <= opts.link_edge
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
    if let Some(e) = opts.crack_edge {
        // IMPL-CHOICE (sliver cracks, docs/methods/ebt.md): after the growth a crack
        // whose only closing facet breaks Rule 2 may be closed by it down to
        // sliver_angle; during the growth Rule 2 holds (a sliver there would steer the
        // points still to come).
        fr.sliver_angle = opts.sliver_angle.min(opts.min_angle);
        fr.crack_count += fr.close_cracks(e);
        let before = fr.faces.len();
        let mut u = fr.head;
        let mut seen = 0usize;
        let total = fr.loop_len;
        // One walk around the loop; a successful bridge fills a part of it.
        while seen <= total {
            seen += 1;
            let next = fr.next[u as usize];
            if fr.state[u as usize] == BOUNDARY && fr.try_bridge(u, e) {
                u = fr.next[u as usize];
                continue;
            }
            u = next;
        }
        fr.crack_count += fr.faces.len() - before;
    }
    let crack_facets = fr.crack_count;
    let mut unmeshed_by_reason = [0usize; 9];
    for (st, &r) in fr.state.iter().zip(&fr.reason) {
        if *st == FREE {
            unmeshed_by_reason[r as usize] += 1;
        }
    }
    Ok(Grown {
        unmeshed_by_reason,
        crack_facets,
        crack_flips: fr.flips,
        sliver_facets: fr.slivers,
        crack_face: fr.crack_face,
        meshed: fr.state.iter().map(|&x| x != FREE).collect(),
        faces: fr.faces,
        seed: s,
        passes,
        ears: fr.ears,
        deferrals,
    })
}
