//! Regrowth of a damaged area: IMPL-CHOICE I20 (not in the paper; issue 20;
//! `regrow_loops_depth`), the loops still open after the fills grown again from a
//! wider border; I21, the points left unmeshed offered to such a regrowth; I22, false
//! handles cut at their sheet-crossing edges and grown again.
//!
//! Where two fronts meet at a crease or at a narrow wall, the last faces made often
//! bridge the wrong sheets or fold over one another beside the gap: on the real fandisk
//! a slit along the top face's crease is overhung by faces joining the top to the wall
//! under it, so every triangle that would close the slit crosses one of them, and the
//! peel of I17 (which takes whole edge rings but keeps the interior points out of the
//! refill) cannot help. The remedy is to forget the growth around the loop and redo
//! it: every face with a vertex within `d` vertex steps of the loop is removed (and,
//! where the cut's border pinches at a vertex, the faces around that vertex), its
//! points become Free, and the growth resumes from the new border, followed by the I7
//! and I15 fills and the I15 insertion of the points the cut freed. The same growth,
//! from a border that now lies on clean faces, meets the other fronts differently.
//! Points that were Free before the cut stay out: the growth and the insertion refused
//! them once, and beside a second sheet they are that sheet's border.
//!
//! The result is kept only if it leaves fewer open boundary edges, joins no two pieces,
//! and adds no handle and no Free point; otherwise depth `d + 1` is tried, up to
//! `regrow_loops_depth`, and then the loop is left as it was. Loops are tried shortest
//! first, at most [`MAX_LOOPS`] of them: each try rebuilds the front over the whole
//! mesh, so its cost is linear in the cloud.
//!
//! IMPL-CHOICE I21 (`regrow_points_depth`) applies the same regrowth to the points
//! still unmeshed after the insertion (box corners above the chamfer growth cut under
//! them, points beside folds): each one with a meshed point within R is released from
//! the hold and offered to a regrowth of the faces within d = 0, 1, ... vertex steps of
//! those meshed points; the result is kept when fewer points stay Free, with the same
//! pieces, no handle and no open edge more. Nearest points first, at most
//! [`MAX_POINTS`], and not at all when more than [`MAX_FREE_SHARE`] of the cloud is
//! Free: the regrowth would take outliers near the surface as readily.
//!
//! IMPL-CHOICE I22 (`regrow_handles_depth`) applies it to false handles: when the mesh
//! has handles, its edges that cross a thin part's thickness (edges of at least 0.75 R
//! that run along the cloud's local plane normal at both ends, as across the bunny's
//! ear) are found, the faces within d vertex steps of their ends are cut, and the
//! regrowth is kept when it has fewer handles, the same pieces and no open edge or Free
//! point more. The test costs a neighbour search at the ends of the long edges only.
//!
//! The removal and regrowth is shared with IMPL-CHOICE I19 (`inside_out.rs`), which
//! applies it to whole regions grown inside out.

use std::collections::HashSet;

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::linalg::{covariance, sym_eigen3_smallest};
use reconbench_geom::method::{MethodError, RunCtx};

use super::complete::{CoverBound, VertexFaces, insert_covered};
use super::density::knn;
use super::grid::Grid;
use super::mesher::{Cfg, FREE, REFUSED};
use super::peel::{FillBounds, PeelMesh, half_edge_face, mesher_from_faces};
use crate::hc_it::cluster::UnionFind;

/// The growth context of a regrowth.
pub(super) struct Regrow<'a> {
    pub pts: &'a [DVec3],
    pub grid: &'a Grid,
    pub cfg: &'a Cfg,
    pub refused0: &'a [bool],
    /// `close_holes_max` (IMPL-CHOICE I7).
    pub close_max: usize,
    pub fill: FillBounds,
    /// The bounds of the point insertion of IMPL-CHOICE I15, run on a regrown mesh
    /// before it is judged; `None` where the insertion runs later.
    pub insert: Option<CoverBound>,
}

/// Loops tried by I20 per run (see the module doc).
const MAX_LOOPS: usize = 64;

/// Points tried by I21 per run (see the module doc).
const MAX_POINTS: usize = 64;

/// Share of Free points above which I21 does not run. The regrowth cannot tell an
/// outlier near the surface from a surface point the growth missed (it takes both);
/// the leftovers of a clean scan are a few per thousand at most (0.15 % on the real
/// sets), while a cloud with outliers leaves their share Free (5-40 % in
/// `li_outliers`).
const MAX_FREE_SHARE: f64 = 0.005;

/// A regrown mesh, not yet accepted.
struct Candidate {
    tris: Vec<[u32; 3]>,
    state: Vec<u8>,
    loops: Vec<Vec<u32>>,
}

/// Removes every face with a vertex flagged in `touched` and grows the area again (see
/// the module doc). The result is kept when it leaves fewer open boundary edges (the
/// rule of I19); returns the number of faces removed (0 when nothing changed, also when
/// the new border is not a set of simple cycles).
pub(super) fn regrow_without(
    g: &Regrow,
    mut mesh: PeelMesh,
    touched: &[bool],
    ctx: &RunCtx,
) -> Result<usize, MethodError> {
    let Some((c, removed)) = candidate(g, &mesh, touched, CUT_I19, &[], ctx)? else {
        return Ok(0);
    };
    if open_edges(&c.loops) >= open_edges(mesh.loops) {
        return Ok(0);
    }
    accept(&mut mesh, c);
    Ok(removed)
}

/// IMPL-CHOICE I20: each open loop is regrown at depths 1 to `max_depth` until a
/// regrowth is kept (see the module doc). Returns the number of regrowths kept.
pub(super) fn regrow_open_loops(
    g: &Regrow,
    mut mesh: PeelMesh,
    max_depth: usize,
    ctx: &RunCtx,
) -> Result<u64, MethodError> {
    if max_depth == 0 {
        return Ok(0);
    }
    // A loop is named by its smallest vertex: a kept regrowth rebuilds the loop list,
    // and a loop it leaves untouched keeps its name and is not tried twice.
    let mut tried: HashSet<u32> = HashSet::new();
    let mut kept = 0;
    while tried.len() < MAX_LOOPS {
        let Some(l) = mesh
            .loops
            .iter()
            .filter(|l| l.iter().min().is_some_and(|v| !tried.contains(v)))
            .min_by_key(|l| l.len())
            .cloned()
        else {
            break;
        };
        tried.insert(*l.iter().min().expect("loops are not empty"));
        let try_ = Try {
            around: &l,
            depths: 1..=max_depth,
            release: &[],
            keep: Score::closes_more,
        };
        kept += u64::from(try_.run(g, &mut mesh, ctx)?);
    }
    Ok(kept)
}

/// IMPL-CHOICE I21: each unmeshed point near the mesh is offered to a regrowth of the
/// faces around it (see the module doc). Returns the number of regrowths kept.
pub(super) fn regrow_free_points(
    g: &Regrow,
    mut mesh: PeelMesh,
    max_depth: usize,
    ctx: &RunCtx,
) -> Result<u64, MethodError> {
    if max_depth == 0 {
        return Ok(0);
    }
    let mut kept = 0;
    for (p, near) in free_near_mesh(g, &mesh) {
        if mesh.state[p as usize] != FREE {
            continue; // taken by an earlier regrowth
        }
        let try_ = Try {
            around: &near,
            depths: 0..=max_depth - 1,
            release: &[p],
            keep: Score::meshes_more,
        };
        kept += u64::from(try_.run(g, &mut mesh, ctx)?);
    }
    Ok(kept)
}

/// The Free points (not duplicates) with a meshed point within R, nearest first, each
/// with those meshed points; none when more than [`MAX_FREE_SHARE`] of the points are
/// Free (a cloud with outliers), at most [`MAX_POINTS`] otherwise.
fn free_near_mesh(g: &Regrow, mesh: &PeelMesh) -> Vec<(u32, Vec<u32>)> {
    let n = g.pts.len();
    let free: Vec<usize> = (0..n)
        .filter(|&v| mesh.state[v] == FREE && !g.refused0[v])
        .collect();
    if free.len() as f64 > MAX_FREE_SHARE * n as f64 {
        return Vec::new();
    }
    let r = g.cfg.r;
    let mut meshed = vec![false; n];
    for &v in mesh.tris.iter().flatten() {
        meshed[v as usize] = true;
    }
    let mut out: Vec<(f64, u32, Vec<u32>)> = Vec::new();
    for p in free {
        let pp = g.pts[p];
        let mut near = Vec::new();
        let mut closest = f64::INFINITY;
        g.grid.for_cells(pp, r, |range| {
            for w in range.filter(|&w| w < n && meshed[w]) {
                let d2 = g.pts[w].distance_squared(pp);
                if d2 <= r * r {
                    near.push(w as u32);
                    closest = closest.min(d2);
                }
            }
        });
        if !near.is_empty() {
            out.push((closest, p as u32, near));
        }
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    out.truncate(MAX_POINTS);
    out.into_iter().map(|(_, p, near)| (p, near)).collect()
}

/// One regrowth attempt: cuts around the points `around` at each depth in turn (vertex
/// steps, see [`within_steps`]), offers the held Free points in `release` to the
/// regrowth, and keeps the first result that `keep` prefers to the mesh as it was.
struct Try<'a, D> {
    around: &'a [u32],
    depths: D,
    release: &'a [u32],
    keep: fn(&Score, &Score) -> bool,
}

impl<D: Iterator<Item = usize>> Try<'_, D> {
    /// Whether a regrowth was kept.
    fn run(self, g: &Regrow, mesh: &mut PeelMesh, ctx: &RunCtx) -> Result<bool, MethodError> {
        let n = g.pts.len();
        let before = Score::of(mesh, n);
        for d in self.depths {
            let touched = within_steps(mesh.tris, self.around, d, n);
            let Some((c, _)) = candidate(g, mesh, &touched, CUT_I20, self.release, ctx)? else {
                continue;
            };
            if (self.keep)(&Score::of_candidate(&c, n), &before) {
                accept(mesh, c);
                return Ok(true);
            }
        }
        Ok(false)
    }
}

/// IMPL-CHOICE I22: when the mesh has handles, the faces around its sheet-crossing
/// edges are cut and grown again (see the module doc). Returns whether a regrowth was
/// kept.
pub(super) fn regrow_handles(
    g: &Regrow,
    mut mesh: PeelMesh,
    max_depth: usize,
    ctx: &RunCtx,
) -> Result<bool, MethodError> {
    let n = g.pts.len();
    if max_depth == 0 {
        return Ok(false);
    }
    let seeds = crossing_edge_ends(g, mesh.tris);
    if seeds.is_empty() || Score::of(&mesh, n).twice_genus <= 0 {
        return Ok(false);
    }
    let try_ = Try {
        around: &seeds,
        depths: 0..=max_depth - 1,
        release: &[],
        keep: Score::fewer_handles,
    };
    try_.run(g, &mut mesh, ctx)
}

/// Points whose neighbourhood plane the I22 test fits.
const NORMAL_K: usize = 12;

/// Edges shorter than this times R are not tested (an edge across a part's thickness
/// spans it; most surface edges are shorter, and the test costs a neighbour search at
/// each end).
const MIN_CROSSING: f64 = 0.75;

/// |cos| between an edge and the plane normals at both its ends above which the edge
/// crosses between two sheets (an edge along the surface has |cos| near 0).
const CROSSING_COS: f64 = 0.8;

/// The ends (sorted) of the edges of `tris`, at least [`MIN_CROSSING`] R long, that run
/// along the least-squares plane normal of the [`NORMAL_K`] nearest points of the cloud
/// at both ends: edges across the thickness of a thin part (an ear), which make a false
/// handle.
fn crossing_edge_ends(g: &Regrow, tris: &[[u32; 3]]) -> Vec<u32> {
    let n = g.pts.len();
    let min2 = (MIN_CROSSING * g.cfg.r).powi(2);
    let mut edges: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .filter(|&(u, v)| g.pts[u as usize].distance_squared(g.pts[v as usize]) > min2)
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut ends: Vec<u32> = edges.iter().flat_map(|&(u, v)| [u, v]).collect();
    ends.sort_unstable();
    ends.dedup();
    let normals: Vec<DVec3> = ends
        .par_iter()
        .map_init(Vec::new, |nb, &v| {
            let keep = |i: usize| i < n && i != v as usize;
            knn(
                g.grid,
                g.pts,
                g.pts[v as usize],
                NORMAL_K,
                3.0 * g.cfg.r,
                keep,
                nb,
            );
            let q: Vec<DVec3> = nb.iter().map(|&(_, i)| g.pts[i as usize]).collect();
            (q.len() >= 6)
                .then(|| covariance(&q, None).ok())
                .flatten()
                .and_then(|c| sym_eigen3_smallest(c.matrix).ok())
                .map_or(DVec3::ZERO, |e| e.vector)
        })
        .collect();
    let normal = |w: u32| normals[ends.binary_search(&w).expect("an end")];
    let mut out = Vec::new();
    for (u, v) in edges {
        let e = (g.pts[v as usize] - g.pts[u as usize]).normalize_or_zero();
        if e.dot(normal(u)).abs() > CROSSING_COS && e.dot(normal(v)).abs() > CROSSING_COS {
            out.extend([u, v]);
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The acceptance figures of I20: open boundary edges, pieces, twice the summed genus
/// and the number of Free points.
struct Score {
    open: usize,
    pieces: i64,
    twice_genus: i64,
    free: usize,
}

impl Score {
    fn of(mesh: &PeelMesh, n: usize) -> Self {
        Self::from_parts(mesh.tris, mesh.state, mesh.loops, n)
    }

    fn of_candidate(c: &Candidate, n: usize) -> Self {
        Self::from_parts(&c.tris, &c.state, &c.loops, n)
    }

    fn from_parts(tris: &[[u32; 3]], state: &[u8], loops: &[Vec<u32>], n: usize) -> Self {
        let (pieces, twice_genus) = euler(tris, loops.len(), n);
        Self {
            open: open_edges(loops),
            pieces,
            twice_genus,
            free: state.iter().filter(|&&s| s == FREE).count(),
        }
    }

    /// I20: fewer open edges, the same pieces (a bridge between two sheets closes
    /// their borders too; nothing split off), and neither a handle nor a Free point
    /// more.
    fn closes_more(&self, old: &Score) -> bool {
        self.open < old.open
            && self.pieces == old.pieces
            && self.twice_genus <= old.twice_genus
            && self.free <= old.free
    }

    /// I22: fewer handles, the same pieces, and neither an open edge nor a Free point
    /// more.
    fn fewer_handles(&self, old: &Score) -> bool {
        self.twice_genus < old.twice_genus
            && self.pieces == old.pieces
            && self.open <= old.open
            && self.free <= old.free
    }

    /// I21: fewer Free points, the same pieces, and neither a handle nor an open edge
    /// more.
    fn meshes_more(&self, old: &Score) -> bool {
        self.free < old.free
            && self.pieces == old.pieces
            && self.twice_genus <= old.twice_genus
            && self.open <= old.open
    }
}

/// Open boundary edges of the front loops.
fn open_edges(loops: &[Vec<u32>]) -> usize {
    loops.iter().map(Vec::len).sum()
}

/// The number of pieces c of `tris` (components by shared vertices) and twice their
/// summed genus with `loops` boundary loops, from the Euler characteristic:
/// 2g = 2c - b - (V - E + F).
fn euler(tris: &[[u32; 3]], loops: usize, n: usize) -> (i64, i64) {
    let mut uf = UnionFind::new(n);
    let mut used = vec![false; n];
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(3 * tris.len());
    for t in tris {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            used[a as usize] = true;
            edges.push((a.min(b), a.max(b)));
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let v = used.iter().filter(|&&u| u).count() as i64;
    let c = (0..n as u32)
        .filter(|&i| used[i as usize] && uf.find(i) == i)
        .count() as i64;
    let chi = v - edges.len() as i64 + tris.len() as i64;
    (c, 2 * c - loops as i64 - chi)
}

/// The points within `d` vertex steps of loop `l` over the faces of `tris` (the loop's
/// own vertices are step 0).
fn within_steps(tris: &[[u32; 3]], l: &[u32], d: usize, n: usize) -> Vec<bool> {
    let vf = VertexFaces::new(n, tris);
    let mut touched = vec![false; n];
    let mut ring: Vec<u32> = l.to_vec();
    for &v in &ring {
        touched[v as usize] = true;
    }
    for _ in 0..d {
        let mut next = Vec::new();
        for &v in &ring {
            for &f in vf.of(v) {
                for &w in &tris[f as usize] {
                    if !touched[w as usize] {
                        touched[w as usize] = true;
                        next.push(w);
                    }
                }
            }
        }
        ring = next;
    }
    touched
}

/// How a regrowth cuts and what it may take.
#[derive(Clone, Copy)]
struct CutRule {
    /// Rounds of widening a pinched cut (see [`simple_cut`]).
    widen: usize,
    /// Whether the points that were Free before the cut stay out of the regrowth (they
    /// were refused by the growth and the insertion once already; near a second sheet
    /// they are that sheet's border points).
    hold_free: bool,
}

/// I19: large regions; a pinched cut is not widened (it would reach further sheets).
const CUT_I19: CutRule = CutRule {
    widen: 0,
    hold_free: false,
};

/// I20: the cut around one loop.
const CUT_I20: CutRule = CutRule {
    widen: 8,
    hold_free: true,
};

/// The mesh without the faces touching `touched` (the cut widened at its pinches and
/// its points held as `rule` says), grown again from its border, and the number of
/// faces removed; `None` when the border is not a set of simple cycles.
fn candidate(
    g: &Regrow,
    mesh: &PeelMesh,
    touched: &[bool],
    rule: CutRule,
    release: &[u32],
    ctx: &RunCtx,
) -> Result<Option<(Candidate, usize)>, MethodError> {
    let n = g.pts.len();
    let Some((kept, fronts)) = simple_cut(mesh.tris, touched, rule.widen, n) else {
        return Ok(None);
    };
    let removed = mesh.tris.len() - kept.len();
    let mut hold: Vec<bool> = mesh
        .state
        .iter()
        .map(|&s| rule.hold_free && s == FREE)
        .collect();
    for &v in release {
        hold[v as usize] = false;
    }
    let held: Vec<u8> = mesh
        .state
        .iter()
        .zip(&hold)
        .map(|(&s, &h)| if h { REFUSED } else { s })
        .collect();
    let mut m = mesher_from_faces(g.pts, g.grid, g.cfg, g.refused0, &kept, &fronts, &held);
    let all: Vec<u32> = (0..m.e_a.len() as u32).collect();
    m.push_only(&all);
    m.grow(ctx)?;
    m.close_small_holes(g.close_max);
    let b = g.fill;
    m.fill_holes(b.max_edge, b.edge_rel, b.max_loop, b.dp);
    let loops = m.loops();
    for (s, &old) in m.state.iter_mut().zip(mesh.state.iter()) {
        if old == FREE && *s == REFUSED {
            *s = FREE;
        }
    }
    let mut c = Candidate {
        tris: std::mem::take(&mut m.tris),
        state: std::mem::take(&mut m.state),
        loops,
    };
    if let Some(bound) = g.insert {
        // Splits interior faces and edges only: the loops stay as they are. With
        // `hold_free`, only the points the cut freed are offered.
        let skip: Vec<bool> = (0..n).map(|v| g.refused0[v] || hold[v]).collect();
        insert_covered(g.pts, g.grid, &mut c.tris, &mut c.state, &skip, bound);
    }
    Ok(Some((c, removed)))
}

/// Puts the regrown mesh `c` in place of `mesh`.
fn accept(mesh: &mut PeelMesh, c: Candidate) {
    *mesh.tris = c.tris;
    *mesh.state = c.state;
    *mesh.loops = c.loops;
}

/// Faces kept by a cut and their border as front loops.
type Cut = (Vec<[u32; 3]>, Vec<Vec<u32>>);

/// The faces of `tris` without those touching `touched`, and their border as front
/// loops. Where the border pinches (a vertex starting two border edges: two holes
/// meeting at a point), the faces around the pinch are removed too, for at most
/// `widen` rounds; `None` when the border is still not a set of simple cycles.
pub(super) fn simple_cut(
    tris: &[[u32; 3]],
    touched: &[bool],
    widen: usize,
    n: usize,
) -> Option<Cut> {
    let mut touched = touched.to_vec();
    for _ in 0..=widen {
        let kept: Vec<[u32; 3]> = tris
            .iter()
            .filter(|t| !t.iter().any(|&v| touched[v as usize]))
            .copied()
            .collect();
        match border_next(&kept, n) {
            Ok(next) => return Some((kept, cycles(&next)?)),
            Err(pinches) => pinches.iter().for_each(|&v| touched[v as usize] = true),
        }
    }
    None
}

const NO: u32 = u32::MAX;

/// Per vertex, the end of the border edge it starts (a half-edge of `tris` without its
/// twin), or [`NO`]; `Err` with the vertices that start two border edges.
fn border_next(tris: &[[u32; 3]], n: usize) -> Result<Vec<u32>, Vec<u32>> {
    let vf = VertexFaces::new(n, tris);
    let twin = |u: u32, v: u32| half_edge_face(tris, &vf, v, u, |_| false).is_some();
    let mut next = vec![NO; n];
    let mut pinches = Vec::new();
    for t in tris {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            if !twin(u, v) {
                if next[u as usize] != NO {
                    pinches.push(u);
                }
                next[u as usize] = v;
            }
        }
    }
    if pinches.is_empty() {
        Ok(next)
    } else {
        Err(pinches)
    }
}

/// The cycles of the border map `next`, or `None` when a border edge ends where no
/// border edge starts.
fn cycles(next: &[u32]) -> Option<Vec<Vec<u32>>> {
    let mut seen = vec![false; next.len()];
    let mut loops = Vec::new();
    for s in 0..next.len() as u32 {
        if next[s as usize] == NO || seen[s as usize] {
            continue;
        }
        let mut l = Vec::new();
        let mut v = s;
        while !seen[v as usize] {
            seen[v as usize] = true;
            l.push(v);
            v = next[v as usize];
            if v == NO {
                return None;
            }
        }
        if v != s {
            return None;
        }
        loops.push(l);
    }
    Some(loops)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::priority_front::inside_out::tests::sphere;

    /// Whether every edge `a -> b` of every loop is a half-edge of exactly one face of
    /// `tris` (the face on the loop's mesh side).
    fn in_front_order(tris: &[[u32; 3]], loops: &[Vec<u32>]) -> bool {
        loops.iter().all(|l| {
            (0..l.len()).all(|i| {
                let (a, b) = (l[i], l[(i + 1) % l.len()]);
                tris.iter()
                    .filter(|t| (0..3).any(|j| t[j] == a && t[(j + 1) % 3] == b))
                    .count()
                    == 1
            })
        })
    }

    /// Cutting the faces that touch one ring of the sphere leaves two loops, the rings
    /// beside it, in front order.
    #[test]
    fn a_cut_around_a_ring_leaves_the_two_neighbouring_rings() {
        let (pts, tris) = sphere(6);
        let (n, k) = (pts.len(), 12u32);
        let touched: Vec<bool> = (0..n as u32)
            .map(|v| (2 + 2 * k..2 + 3 * k).contains(&v))
            .collect();
        let (kept, loops) = simple_cut(&tris, &touched, 0, n).expect("simple loops");
        assert_eq!(kept.len(), tris.len() - 4 * k as usize);
        assert_eq!(loops.len(), 2, "{loops:?}");
        for l in &loops {
            let mut ring: Vec<u32> = l.iter().map(|&v| (v - 2) / k).collect();
            ring.dedup();
            assert!(ring == [1] || ring == [3], "{l:?}");
            assert_eq!(l.len(), k as usize);
        }
        assert!(in_front_order(&kept, &loops));
        assert_eq!(
            simple_cut(&tris, &vec![false; n], 0, n).unwrap().1,
            Vec::<Vec<u32>>::new()
        );
    }

    /// Two triangles of the north pole's fan removed, not adjacent: the pole starts two
    /// border edges. The cut is widened by the pole's whole fan, which leaves the first
    /// ring as the one loop.
    #[test]
    fn a_pinched_cut_is_widened_to_a_simple_loop() {
        let (pts, tris) = sphere(6);
        let (n, k) = (pts.len(), 12);
        let pinched: Vec<[u32; 3]> = tris
            .iter()
            .enumerate()
            .filter(|(f, _)| *f != 0 && *f != 3 * 2 * 6)
            .map(|(_, t)| *t)
            .collect();
        assert_eq!(border_next(&pinched, n), Err(vec![0]));
        assert!(simple_cut(&pinched, &vec![false; n], 0, n).is_none());
        let (kept, loops) = simple_cut(&pinched, &vec![false; n], 1, n).expect("widened");
        assert_eq!(kept.len(), tris.len() - k);
        assert_eq!(loops.len(), 1);
        let mut l = loops[0].clone();
        l.sort_unstable();
        assert_eq!(l, (2..2 + k as u32).collect::<Vec<_>>());
        assert!(in_front_order(&kept, &loops));
    }

    /// A closed torus of `m x m` vertices, two triangles per cell.
    fn torus(m: u32) -> Vec<[u32; 3]> {
        let at = |i: u32, j: u32| (i % m) * m + j % m;
        let mut tris = Vec::new();
        for i in 0..m {
            for j in 0..m {
                tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        tris
    }

    /// The Euler count: 0 for the sphere, with or without a hole cut in it (the hole is
    /// a loop, not a handle), 2 for the torus, 4 for two tori, 2 for a torus with a hole;
    /// one piece each but two for the two tori.
    #[test]
    fn euler_counts_pieces_and_handles_not_holes() {
        let twice_genus = |t: &[[u32; 3]], b: usize, n: usize| euler(t, b, n).1;
        let (pts, tris) = sphere(6);
        let n = pts.len();
        assert_eq!(twice_genus(&tris, 0, n), 0);
        let holed: Vec<[u32; 3]> = tris[1..].to_vec();
        assert_eq!(twice_genus(&holed, 1, n), 0);
        let t = torus(6);
        assert_eq!(twice_genus(&t, 0, 36), 2);
        let two: Vec<[u32; 3]> = t
            .iter()
            .chain(&t.iter().map(|f| f.map(|v| v + 36)).collect::<Vec<_>>())
            .copied()
            .collect();
        assert_eq!(euler(&two, 0, 72), (2, 4));
        assert_eq!(euler(&t, 0, 36).0, 1);
        assert_eq!(twice_genus(&t[1..], 1, 36), 2);
    }
}
