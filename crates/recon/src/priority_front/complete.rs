//! Surface completion after growth (IMPL-CHOICE I15, not in the paper; issue 20).
//!
//! The paper leaves every loop that survives growth as a hole and every point no front
//! reached as refused noise. On real vertex sets both are mostly artefacts: thin slits
//! where two fronts met at a crease, and points left *under* a triangle whose front
//! passed over them (`docs/methods/priority_front.md`, "Real data"). Two steps:
//!
//! 1. [`Mesher::fill_holes`]: a loop is closed when ear clipping can close it **whole**
//!    with every new edge at most `max_edge` long, no ear folded against its neighbour
//!    (more than 150 degrees) and no ear crossing a mesh face or another ear (the exact
//!    test of IMPL-CHOICE I14). Otherwise nothing is added to it. A hole wider than
//!    `max_edge` (a scan hole, an open end) cannot be closed under that bound and is
//!    kept, with its rim untouched; a slit between two fronts is zipped. A loop whose
//!    greedy ears run into a dead end is then triangulated by the least-fold programme
//!    of `fill_dp.rs` under the same bounds (`fill_holes_dp`).
//! 2. [`insert_covered`]: every point left unmeshed that lies on the surface of its
//!    meshed neighbours (their plane, or their quadric on a curved patch: `insert_height`,
//!    `insert_rel`, `insert_quadric`; or the crease line of two mesh triangles near it;
//!    so that outliers near the surface stay refused) and
//!    projects into a triangle within the I12 height bound of it (the definition of a
//!    covered point; up to the neighbours' own band beside a crease, where growth cut
//!    the corner under a crease vertex) is inserted there: the triangle is split in
//!    three, or an edge it projects onto and its two triangles in two. Candidates are
//!    tried lowest first until one makes no new crossing with a triangle near it. The
//!    mesh stays interpolating, manifold and consistently oriented; its topology does
//!    not change. Points that are above no triangle or farther from it (outliers) stay
//!    refused.

use glam::DVec3;
use reconbench_geom::linalg::{covariance, sym_eigen3_smallest, weighted_least_squares};
use reconbench_geom::spatial::{closest_point_on_triangle, tri_tri_intersect};

use super::grid::{Grid, NONE};
use super::mesher::{ACCEPTED, Mesher, tri_normal};

/// Cosine of the largest fold allowed between an ear and the face across its old edges
/// (150 degrees: an acute crease, such as the fandisk's, stays closable; a sheet folded
/// back onto itself does not).
pub(super) const COS_MAX_FOLD: f64 = -0.866;

/// One planned ear: the loop corner it removes (`z -> a -> b`) and its normal.
#[derive(Clone, Copy)]
pub(super) struct Ear {
    pub(super) z: u32,
    pub(super) a: u32,
    pub(super) b: u32,
    pub(super) n: DVec3,
}

impl Mesher<'_> {
    /// Builds the IMPL-CHOICE I14 face index of the triangles made so far and turns the
    /// check on (the completion always checks for crossings).
    pub fn enable_self_check(&mut self) {
        if self.cfg.self_check {
            return;
        }
        self.cfg.self_check = true;
        let n = self.pts.len();
        self.vf_head = vec![NONE; n];
        self.v_reach = vec![0.0; n];
        let tris = std::mem::take(&mut self.tris);
        self.faces = Vec::with_capacity(tris.len());
        for &t in &tris {
            self.index_face(t, t.map(|i| self.pts[i as usize]));
        }
        self.tris = tris;
    }

    /// Closes every loop of at most `max_len` vertices that ear clipping can close whole
    /// under the bounds of the module doc: new edges at most `max_edge`, or `edge_rel`
    /// times the loop's longest edge where that is longer (sparse regions, where the
    /// input's own spacing exceeds R). With `dp`, a loop the ears cannot close is given
    /// to the least-fold programme (`fill_dp.rs`). Returns the number of loops closed.
    pub fn fill_holes(&mut self, max_edge: f64, edge_rel: f64, max_len: usize, dp: bool) -> u64 {
        if max_edge <= 0.0 {
            return 0;
        }
        let loops: Vec<Vec<u32>> = self
            .loops()
            .into_iter()
            .filter(|l| l.len() >= 3 && l.len() <= max_len)
            .collect();
        self.fill_loops(loops, max_edge, edge_rel, dp)
    }

    /// Closes those of the front loops `loops` (vertex cycles in front order) that the
    /// planners of [`Mesher::fill_holes`] can close whole; returns how many.
    pub(super) fn fill_loops(
        &mut self,
        loops: Vec<Vec<u32>>,
        max_edge: f64,
        edge_rel: f64,
        dp: bool,
    ) -> u64 {
        if loops.is_empty() {
            return 0;
        }
        self.enable_self_check();
        let mut closed = 0;
        for l in loops {
            // An isolated triangle (a lone seed) must not be doubled.
            if l.len() == 3 && l.iter().all(|&v| self.adj.degree(v) == 2) {
                continue;
            }
            let k = l.len();
            let longest = (0..k)
                .map(|i| self.pts[l[i] as usize].distance(self.pts[l[(i + 1) % k] as usize]))
                .fold(0.0, f64::max);
            let bound = max_edge.max(edge_rel * longest);
            let plan = match self.plan_fill(&l, bound) {
                None if dp => self.plan_fill_dp(&l, bound),
                plan => plan,
            };
            if let Some(plan) = plan {
                self.apply_fill(&plan);
                closed += 1;
            }
        }
        closed
    }

    /// The ears that close loop `l` (front order) whole, best ear first by smallest
    /// angle, or `None` when some stage has no acceptable ear.
    fn plan_fill(&mut self, l: &[u32], max_edge: f64) -> Option<Vec<Ear>> {
        let lim2 = max_edge * max_edge;
        let mut l = l.to_vec();
        // Normal of the face on the mesh side of each loop edge l[i] -> l[i + 1].
        let mut en: Vec<DVec3> = l
            .iter()
            .map(|&v| self.e_nrm[self.fout[v as usize] as usize])
            .collect();
        let mut plan: Vec<Ear> = Vec::with_capacity(l.len());
        let mut diagonals: Vec<(u32, u32)> = Vec::new();
        let mut cands: Vec<(f64, usize)> = Vec::new();
        while l.len() >= 3 {
            let k = l.len();
            cands.clear();
            for i in 0..k {
                let (z, a, b) = (l[(i + k - 1) % k], l[i], l[(i + 1) % k]);
                let (pz, pa, pb) = (
                    self.pts[z as usize],
                    self.pts[a as usize],
                    self.pts[b as usize],
                );
                if k > 3
                    && (pz.distance_squared(pb) > lim2
                        || self.adj.has(z, b)
                        || diagonals.contains(&(z.min(b), z.max(b))))
                {
                    continue;
                }
                let n = tri_normal(pz, pb, pa);
                if n == DVec3::ZERO
                    || n.dot(en[(i + k - 1) % k]) < COS_MAX_FOLD
                    || n.dot(en[i]) < COS_MAX_FOLD
                    || (k == 3 && n.dot(en[(i + 1) % k]) < COS_MAX_FOLD)
                {
                    continue;
                }
                let q = min_angle_cos(pz, pa, pb);
                if q.is_finite() {
                    cands.push((q, i));
                }
            }
            cands.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            let mut chosen = None;
            for &(_, i) in &cands {
                let (z, a, b) = (l[(i + k - 1) % k], l[i], l[(i + 1) % k]);
                let tri = [z, b, a];
                if self.crosses_mesh(tri) || crosses_planned(self.pts, &plan, tri) {
                    continue;
                }
                chosen = Some(i);
                break;
            }
            let i = chosen?;
            let (z, a, b) = (l[(i + k - 1) % k], l[i], l[(i + 1) % k]);
            let n = tri_normal(
                self.pts[z as usize],
                self.pts[b as usize],
                self.pts[a as usize],
            );
            plan.push(Ear { z, a, b, n });
            if k == 3 {
                break;
            }
            diagonals.push((z.min(b), z.max(b)));
            // Edge z -> b replaces z -> a and a -> b; its mesh side is the new ear.
            en[(i + k - 1) % k] = n;
            en.remove(i);
            l.remove(i);
        }
        Some(plan)
    }

    /// Adds the planned ears with the front operations (LINK-next for each ear, FILL for
    /// the last triangle), so the front stays consistent.
    fn apply_fill(&mut self, plan: &[Ear]) {
        let (last, ears) = plan.split_last().expect("a plan has at least one ear");
        for ear in ears {
            let g = self.fin[ear.a as usize];
            self.link_next(g, ear.b, ear.n);
        }
        let e = self.fout[last.z as usize];
        debug_assert_eq!(self.e_b[e as usize], last.a);
        self.fill(e, last.b);
    }
}

/// Whether triangle `tri` crosses a planned ear that shares none of its vertices.
pub(super) fn crosses_planned(pts: &[DVec3], plan: &[Ear], tri: [u32; 3]) -> bool {
    let p = tri.map(|i| pts[i as usize]);
    plan.iter().any(|e| {
        let t = [e.z, e.b, e.a];
        !t.iter().any(|v| tri.contains(v)) && tri_tri_intersect(&p, &t.map(|i| pts[i as usize]))
    })
}

/// Cosine of the smallest angle of triangle `(p, q, r)` (NaN when degenerate); smaller
/// is better.
pub(crate) fn min_angle_cos(p: DVec3, q: DVec3, r: DVec3) -> f64 {
    let c = |x: DVec3, y: DVec3, z: DVec3| {
        let (u, v) = (y - x, z - x);
        let d = (u.length_squared() * v.length_squared()).sqrt();
        if d > 0.0 { u.dot(v) / d } else { f64::NAN }
    };
    let (a, b, cc) = (c(p, q, r), c(q, r, p), c(r, p, q));
    if a.is_nan() || b.is_nan() || cc.is_nan() || (q - p).cross(r - p).length_squared() == 0.0 {
        return f64::NAN;
    }
    a.max(b).max(cc)
}

/// Bounds of a covered point that is inserted.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CoverBound {
    /// Absolute part of the height bound over the triangle (I12: `free_inside_height`
    /// rho).
    pub h_abs: f64,
    /// Part relative to the triangle's longest edge (I12: `free_inside_rel`).
    pub h_rel: f64,
    /// Search radius for the triangles' corners (R).
    pub radius: f64,
    /// First search radius for the neighbours whose plane the point must lie on.
    pub plane_radius: f64,
    /// Largest height over that plane (`insert_height` rho) ...
    pub plane_abs: f64,
    /// ... or this times the neighbours' RMS residual from it, where larger (curved or
    /// creased neighbourhoods; `insert_rel`).
    pub plane_rel: f64,
    /// Whether a point off that plane may lie on the neighbours' quadric instead
    /// (`insert_quadric`).
    pub quadric: bool,
}

/// Neighbours whose plane a point must lie on (the k of `pf`'s plane fit).
const PLANE_K: usize = 12;

/// When `p` lies on the least-squares plane of its [`PLANE_K`] nearest meshed points
/// (searched out to 4 `plane_radius`): the band it lies within, max(`plane_abs`,
/// `plane_rel` x their RMS residual); `None` when it lies farther from the plane. Only
/// meshed points count, so other outliers nearby do not widen the band. A point on the
/// sampled surface passes wherever its neighbours do; a point floating above a clean
/// surface does not.
fn local_plane_band(
    pts: &[DVec3],
    state: &[u8],
    grid: &Grid,
    p: u32,
    bound: &CoverBound,
    nb: &mut Vec<(f64, u32)>,
) -> Option<f64> {
    let pp = pts[p as usize];
    let mut r = bound.plane_radius;
    for _ in 0..3 {
        nb.clear();
        grid.for_cells(pp, r, |range| {
            for v in range {
                let d = pts[v].distance_squared(pp);
                if v != p as usize && state[v] == ACCEPTED && d <= r * r {
                    nb.push((d, v as u32));
                }
            }
        });
        if nb.len() >= PLANE_K {
            break;
        }
        r *= 2.0;
    }
    if nb.len() < 6 {
        return None;
    }
    nb.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let q: Vec<DVec3> = nb
        .iter()
        .take(PLANE_K)
        .map(|&(_, v)| pts[v as usize])
        .collect();
    let cov = covariance(&q, None).ok()?;
    let eig = sym_eigen3_smallest(cov.matrix).ok()?;
    let rms = eig.values[0].max(0.0).sqrt();
    let h = (pp - cov.centroid).dot(eig.vector).abs();
    let band = bound.plane_abs.max(bound.plane_rel * rms);
    let on =
        h <= band || (bound.quadric && on_local_quadric(&q, cov.centroid, eig.vector, pp, bound));
    on.then_some(band)
}

/// Whether `p` lies on the least-squares quadric height function over the plane
/// (centroid `c`, normal `n`) of the points `q`: within max(`plane_abs`, `plane_rel` x
/// the fit's residual standard error). On a curved patch the plane's residual is mostly
/// curvature, so a surface point can stand off the plane by more than its band while
/// lying on the quadric; an outlier above a curved surface lies off both.
fn on_local_quadric(q: &[DVec3], c: DVec3, n: DVec3, p: DVec3, bound: &CoverBound) -> bool {
    const TERMS: usize = 6;
    if q.len() <= TERMS {
        return false;
    }
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let row = |x: DVec3| {
        let d = x - c;
        let (a, b) = (d.dot(u), d.dot(v));
        ([a * a, a * b, b * b, a, b, 1.0], d.dot(n))
    };
    let mut rows = Vec::with_capacity(q.len() * TERMS);
    let mut z = Vec::with_capacity(q.len());
    for &x in q {
        let (r, h) = row(x);
        rows.extend_from_slice(&r);
        z.push(h);
    }
    let Ok(coef) = weighted_least_squares(&rows, &z, &[], TERMS) else {
        return false;
    };
    let eval = |r: &[f64]| r.iter().zip(&coef).map(|(a, b)| a * b).sum::<f64>();
    let ssr: f64 = rows
        .chunks_exact(TERMS)
        .zip(&z)
        .map(|(r, h)| (eval(r) - h).powi(2))
        .sum();
    let se = (ssr / (q.len() - TERMS) as f64).sqrt();
    let (r, h) = row(p);
    (eval(&r) - h).abs() <= bound.plane_abs.max(bound.plane_rel * se)
}

/// Inserts every point whose `state` is not [`ACCEPTED`] (and that is not flagged in
/// `skip`: duplicates) and that lies on its meshed neighbours' surface into the mesh
/// where it is covered: into a triangle of `tris` it projects into (split in three), or
/// else onto an interior edge it projects onto (its two triangles split in two), within
/// [`height_bound`] of that triangle or edge. The candidates are tried lowest first;
/// the first whose new triangles make no new crossing is taken. Orientation is kept.
/// Points are taken in index order (deterministic). Returns the number inserted; their
/// state becomes [`ACCEPTED`].
pub(crate) fn insert_covered(
    pts: &[DVec3],
    grid: &Grid,
    tris: &mut Vec<[u32; 3]>,
    state: &mut [u8],
    skip: &[bool],
    bound: CoverBound,
) -> usize {
    let n = pts.len();
    let todo: Vec<u32> = (0..n as u32)
        .filter(|&i| state[i as usize] != ACCEPTED && !skip[i as usize])
        .collect();
    if todo.is_empty() || tris.is_empty() {
        return 0;
    }
    let n0 = tris.len();
    let vf = VertexFaces::new(n, &tris[..n0]);
    let reach = corner_reach(pts, &tris[..n0], bound.radius);
    let mut tree = SplitTree::new(n0);
    let mut near: Vec<u32> = Vec::new();
    let mut leaves: Vec<u32> = Vec::new();
    let mut nb: Vec<(f64, u32)> = Vec::new();
    let mut cands: Vec<Split> = Vec::new();
    let mut inserted = 0;
    for &p in &todo {
        let pp = pts[p as usize];
        // NaN until decided: a point off its neighbours' plane and quadric may still lie
        // on a crease or corner of the mesh (`on_feature_planes`, decided on the
        // triangles near it), where it may stand up to a triangle's longest edge above
        // the chamfer growth cut under it.
        let mut band = local_plane_band(pts, state, grid, p, &bound, &mut nb).unwrap_or(f64::NAN);
        // Corners within R first; the wider reach only for a point that no triangle or
        // edge near it can take.
        let mut done = false;
        let radii = [bound.radius, reach];
        for &r in &radii[..if reach > bound.radius { 2 } else { 1 }] {
            if done {
                break;
            }
            near.clear();
            grid.for_cells(pp, r, |range| {
                for v in range {
                    if v < n && state[v] == ACCEPTED && pts[v].distance_squared(pp) <= r * r {
                        near.push(v as u32);
                    }
                }
            });
            leaves.clear();
            for &v in &near {
                for &f in vf.of(v) {
                    tree.leaves_under(f, &mut leaves);
                }
            }
            leaves.sort_unstable();
            leaves.dedup();
            if band.is_nan() {
                if !on_feature_planes(pts, tris, &leaves, pp, bound.plane_abs) {
                    continue;
                }
                band = f64::INFINITY;
            }
            // Faces first (lowest first), then, where none can take the point, edges
            // (nearest first).
            cands.clear();
            face_splits(pts, tris, &leaves, pp, bound, band, &mut cands);
            done = try_splits(pts, tris, &mut tree, &leaves, &mut cands, p);
            if !done {
                cands.clear();
                edge_splits(pts, tris, &leaves, pp, bound, band, &mut cands);
                done = try_splits(pts, tris, &mut tree, &leaves, &mut cands, p);
            }
        }
        if done {
            state[p as usize] = ACCEPTED;
            inserted += 1;
        }
    }
    if inserted > 0 {
        // Keep the leaves in order: an original face's place goes to its leaves.
        let mut out = Vec::with_capacity(tris.len());
        for f in 0..n0 {
            tree.leaves_under(f as u32, &mut out);
        }
        *tris = out.iter().map(|&f| tris[f as usize]).collect();
    }
    inserted
}

/// Sorts `cands` lowest first and takes the first whose new triangles make no new
/// crossing with `leaves`: splits it in `tree` / `tris` with point `p`. Returns whether
/// one was taken.
fn try_splits(
    pts: &[DVec3],
    tris: &mut Vec<[u32; 3]>,
    tree: &mut SplitTree,
    leaves: &[u32],
    cands: &mut [Split],
    p: u32,
) -> bool {
    cands.sort_unstable_by(|a, b| a.h.total_cmp(&b.h).then(a.f.cmp(&b.f)));
    for c in cands.iter() {
        let (kids, parents) = c.kids(tris, p);
        if crosses_leaves(pts, tris, leaves, &kids, &parents) {
            continue;
        }
        match c.g {
            NONE => tree.split(tris, c.f, &kids),
            g => {
                tree.split(tris, c.f, &kids[..2]);
                tree.split(tris, g, &kids[2..]);
            }
        }
        return true;
    }
    false
}

/// Cosine of the smallest angle between the normals of two triangles whose planes meet
/// at a crease or corner (30 degrees).
const COS_FEATURE: f64 = 0.866;

/// Whether `p` lies, within `tol`, on the planes of two triangles of `leaves` whose
/// normals differ by more than 30 degrees, each within its longest edge of `p`: on the
/// crease line where two flat sides of the mesh meet (or a corner of three), which
/// growth cut with a chamfer (IMPL-CHOICE I15). Points off such a line, outliers among
/// them, fail: two bands of width 2 `tol` meet in a thin prism. Twice the longest edge
/// let in 2 % of `li_outliers`' torus outliers (planes of triangles far apart on a
/// curved surface meet near it).
fn on_feature_planes(pts: &[DVec3], tris: &[[u32; 3]], leaves: &[u32], p: DVec3, tol: f64) -> bool {
    let mut on: Vec<DVec3> = Vec::new();
    for &f in leaves {
        let [a, b, c] = tris[f as usize].map(|i| pts[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        if n == DVec3::ZERO || (p - a).dot(n).abs() > tol {
            continue;
        }
        let lmax = a.distance(b).max(b.distance(c)).max(c.distance(a));
        if p.distance(closest_point_on_triangle(p, a, b, c)) > lmax {
            continue;
        }
        if on.iter().any(|m| m.dot(n) < COS_FEATURE) {
            return true;
        }
        on.push(n);
    }
    false
}

/// How far from a point the corners of a triangle it projects into can lie: the corner
/// search radius R, or the mesh's longest edge where that is longer (sparse CAD regions
/// have triangles of several R), at most 3 R (IMPL-CHOICE I15; the cap bounds the
/// search on meshes with a few very long edges).
fn corner_reach(pts: &[DVec3], tris: &[[u32; 3]], radius: f64) -> f64 {
    let longest = tris
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .map(|(u, v)| pts[u as usize].distance_squared(pts[v as usize]))
        .fold(0.0, f64::max)
        .sqrt();
    radius.max(longest.min(3.0 * radius))
}

/// One way to insert a point: split leaf `f` in three (`g == NONE`), or split the edge
/// `u -> v` of `f` and its twin leaf `g` in two each; `h` is the point's height over
/// the triangle or its distance from the edge.
#[derive(Clone, Copy)]
struct Split {
    h: f64,
    f: u32,
    g: u32,
    u: u32,
    v: u32,
}

impl Split {
    /// The new triangles with point `p` (orientation kept) and the triangles they
    /// replace.
    fn kids(&self, tris: &[[u32; 3]], p: u32) -> (Vec<[u32; 3]>, Vec<u32>) {
        let t = tris[self.f as usize];
        if self.g == NONE {
            let [a, b, c] = t;
            return (vec![[a, b, p], [b, c, p], [c, a, p]], vec![self.f]);
        }
        let (u, v) = (self.u, self.v);
        let w = third(t, u, v);
        let x = third(tris[self.g as usize], v, u);
        (
            vec![[u, p, w], [p, v, w], [v, p, x], [p, u, x]],
            vec![self.f, self.g],
        )
    }
}

/// Whether a new triangle of `kids` would cross a leaf triangle near it that shares
/// none of its vertices (an inserted point must not make the mesh pass through itself).
/// A crossing that a replaced triangle of `parents` already has (with a leaf sharing no
/// vertex with it) is not new and does not count: the new triangles lie within the
/// height bound of the old ones, and a fold left by growth must not keep the points
/// under it refused.
fn crosses_leaves(
    pts: &[DVec3],
    tris: &[[u32; 3]],
    leaves: &[u32],
    kids: &[[u32; 3]],
    parents: &[u32],
) -> bool {
    let tri = |t: [u32; 3]| t.map(|i| pts[i as usize]);
    kids.iter().any(|k| {
        let q = tri(*k);
        leaves.iter().any(|&g| {
            let t = tris[g as usize];
            !t.iter().any(|v| k.contains(v))
                && tri_tri_intersect(&q, &tri(t))
                && !parents.iter().any(|&f| {
                    let pt = tris[f as usize];
                    !t.iter().any(|v| pt.contains(v)) && tri_tri_intersect(&tri(pt), &tri(t))
                })
        })
    })
}

/// Height bound of an insertion next to a triangle or edge of longest length `lmax`:
/// the I12 bound max(`h_abs`, `h_rel` x `lmax`), or the point's own plane band where
/// that is wider (a crease vertex above the chamfer growth cut under it), at most
/// `lmax`.
fn height_bound(bound: CoverBound, band: f64, lmax: f64) -> f64 {
    bound.h_abs.max(bound.h_rel * lmax).max(band.min(lmax))
}

/// Appends a [`Split`] in three of every leaf of `leaves` that `p` projects into within
/// [`height_bound`].
fn face_splits(
    pts: &[DVec3],
    tris: &[[u32; 3]],
    leaves: &[u32],
    p: DVec3,
    bound: CoverBound,
    band: f64,
    out: &mut Vec<Split>,
) {
    for &f in leaves {
        if let Some((h, lmax)) = covers(pts, tris[f as usize], p)
            && h <= height_bound(bound, band, lmax)
        {
            out.push(Split {
                h,
                f,
                g: NONE,
                u: NONE,
                v: NONE,
            });
        }
    }
}

/// Appends a [`Split`] of every interior edge `u -> v` of a leaf `f` (twin leaf `g`
/// holds `v -> u`) that `p` projects onto strictly between its ends within
/// [`height_bound`] (by the edge's length).
fn edge_splits(
    pts: &[DVec3],
    tris: &[[u32; 3]],
    leaves: &[u32],
    p: DVec3,
    bound: CoverBound,
    band: f64,
    out: &mut Vec<Split>,
) {
    for &f in leaves {
        let t = tris[f as usize];
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            let (pu, pv) = (pts[u as usize], pts[v as usize]);
            let e = pv - pu;
            let ll = e.length_squared();
            if ll.is_nan() || ll <= 0.0 {
                continue;
            }
            let s = (p - pu).dot(e) / ll;
            if !(s > 1e-3 && s < 1.0 - 1e-3) {
                continue;
            }
            let d = p.distance(pu + s * e);
            if d > height_bound(bound, band, ll.sqrt()) {
                continue;
            }
            let twin = leaves.iter().copied().find(|&g| {
                let t = tris[g as usize];
                (0..3).any(|k| t[k] == v && t[(k + 1) % 3] == u)
            });
            // Each interior edge once: from the leaf that holds it as u < v.
            if let Some(g) = twin
                && u < v
            {
                out.push(Split { h: d, f, g, u, v });
            }
        }
    }
}

/// The vertex of triangle `t` other than `u`, `v`.
fn third(t: [u32; 3], u: u32, v: u32) -> u32 {
    t.into_iter()
        .find(|&x| x != u && x != v)
        .expect("the edge's triangle has a third vertex")
}

/// Triangles split by inserted points: each original or split triangle keeps the range
/// of its children, so the current leaves under any original triangle can be found.
struct SplitTree {
    /// Per triangle: its first child, `NONE` while it is a leaf.
    start: Vec<u32>,
    /// Per triangle: its number of children (2 or 3).
    count: Vec<u8>,
}

impl SplitTree {
    fn new(n: usize) -> Self {
        Self {
            start: vec![NONE; n],
            count: vec![0; n],
        }
    }

    /// Replaces leaf `f` by the triangles `kids` (appended to `tris`).
    fn split(&mut self, tris: &mut Vec<[u32; 3]>, f: u32, kids: &[[u32; 3]]) {
        self.start[f as usize] = tris.len() as u32;
        self.count[f as usize] = kids.len() as u8;
        tris.extend_from_slice(kids);
        self.start.extend(std::iter::repeat_n(NONE, kids.len()));
        self.count.extend(std::iter::repeat_n(0, kids.len()));
    }

    /// Appends the leaves under triangle `f` (depth first, children in order).
    fn leaves_under(&self, f: u32, out: &mut Vec<u32>) {
        if self.start[f as usize] == NONE {
            out.push(f);
            return;
        }
        let (s, c) = (self.start[f as usize], u32::from(self.count[f as usize]));
        for g in s..s + c {
            self.leaves_under(g, out);
        }
    }
}

/// When the projection of `p` along the normal of triangle `t` falls strictly inside
/// it: the distance of `p` from its plane and the triangle's longest edge.
fn covers(pts: &[DVec3], t: [u32; 3], p: DVec3) -> Option<(f64, f64)> {
    let [a, b, c] = t.map(|i| pts[i as usize]);
    let nrm = (b - a).cross(c - a);
    let nn = nrm.length_squared();
    if nn.is_nan() || nn <= 0.0 {
        return None;
    }
    // Signed areas of the sub-triangles with p, along the normal: all positive inside.
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(p - u).dot(nrm) > 0.0);
    if !inside {
        return None;
    }
    let h = (p - a).dot(nrm).abs() / nn.sqrt();
    let lmax = a
        .distance_squared(b)
        .max(b.distance_squared(c))
        .max(c.distance_squared(a))
        .sqrt();
    Some((h, lmax))
}

/// Faces incident to each vertex, in compressed rows.
pub(super) struct VertexFaces {
    start: Vec<u32>,
    faces: Vec<u32>,
}

impl VertexFaces {
    pub(super) fn new(n: usize, tris: &[[u32; 3]]) -> Self {
        let mut start = vec![0u32; n + 1];
        for t in tris {
            for &v in t {
                start[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut faces = vec![0u32; 3 * tris.len()];
        for (f, t) in tris.iter().enumerate() {
            for &v in t {
                faces[fill[v as usize] as usize] = f as u32;
                fill[v as usize] += 1;
            }
        }
        Self { start, faces }
    }

    /// The faces around vertex `v`.
    pub(super) fn of(&self, v: u32) -> &[u32] {
        &self.faces[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bound(quadric: bool) -> CoverBound {
        CoverBound {
            h_abs: 0.5,
            h_rel: 0.25,
            radius: 4.0,
            plane_radius: 2.5,
            plane_abs: 0.1,
            plane_rel: 3.0,
            quadric,
        }
    }

    /// Twelve points of the paraboloid z = 0.15 (x² + y²) on two rings (spacing ~1), a
    /// curved patch whose plane residual is mostly curvature.
    fn paraboloid() -> Vec<DVec3> {
        let z = |x: f64, y: f64| 0.15 * (x * x + y * y);
        (0..12)
            .map(|i| {
                let r = if i % 2 == 0 { 1.0 } else { 2.0 };
                let a = i as f64 * std::f64::consts::TAU / 12.0;
                let (x, y) = (r * a.cos(), r * a.sin());
                DVec3::new(x, y, z(x, y))
            })
            .collect()
    }

    /// A ridge of two triangles at 90 degrees (along the x axis, the roof's faces
    /// x-y and x-z), and a flat third triangle in the x-y plane.
    fn ridge() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let pts = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(3.0, 1.0, 0.0),
        ];
        (pts, vec![[0, 1, 2], [1, 0, 3], [1, 4, 2]])
    }

    /// A point on the crease line of two triangles lies on both planes; one beside it
    /// lies on one plane only, one above it on none; two coplanar triangles make no
    /// crease.
    #[test]
    fn feature_planes_take_crease_points_only() {
        let (pts, tris) = ridge();
        let all = [0, 1, 2];
        let on = |p: DVec3, leaves: &[u32]| on_feature_planes(&pts, &tris, leaves, p, 0.05);
        assert!(on(DVec3::new(2.5, 0.0, 0.0), &all));
        assert!(on(DVec3::new(2.5, 0.03, -0.03), &all));
        assert!(!on(DVec3::new(2.5, 0.3, 0.0), &all));
        assert!(!on(DVec3::new(2.5, -0.2, 0.2), &all));
        assert!(!on(DVec3::new(2.5, 0.0, 0.0), &[0, 2]));
    }

    /// A point on the paraboloid beyond its neighbours lies off their plane by more than
    /// the plane's band but on their quadric; the same point 0.3 above (an outlier) lies
    /// on neither.
    #[test]
    fn quadric_test_takes_curved_surface_points_not_outliers() {
        let q = paraboloid();
        let cov = covariance(&q, None).unwrap();
        let eig = sym_eigen3_smallest(cov.matrix).unwrap();
        let rms = eig.values[0].sqrt();
        let on = DVec3::new(2.8, 0.5, 0.15 * (2.8f64 * 2.8 + 0.25));
        let h = (on - cov.centroid).dot(eig.vector).abs();
        assert!(h > 0.1f64.max(3.0 * rms), "h {h}, rms {rms}");
        let b = bound(true);
        assert!(on_local_quadric(&q, cov.centroid, eig.vector, on, &b));
        let off = on + DVec3::Z * 0.3;
        assert!(!on_local_quadric(&q, cov.centroid, eig.vector, off, &b));
    }
}
