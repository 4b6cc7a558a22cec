//! Regrowth of a damaged area, and IMPL-CHOICE I20 (not in the paper; issue 20;
//! `regrow_loops_depth`): the loops still open after the fills, grown again from a
//! wider border.
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
//! The removal and regrowth is shared with IMPL-CHOICE I19 (`inside_out.rs`), which
//! applies it to whole regions grown inside out.

use std::collections::HashSet;

use glam::DVec3;
use reconbench_geom::method::{MethodError, RunCtx};

use super::complete::{CoverBound, VertexFaces, insert_covered};
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
    mesh: PeelMesh,
    touched: &[bool],
    ctx: &RunCtx,
) -> Result<usize, MethodError> {
    let Some((c, removed)) = candidate(g, &mesh, touched, CUT_I19, ctx)? else {
        return Ok(0);
    };
    if open_edges(&c.loops) >= open_edges(mesh.loops) {
        return Ok(0);
    }
    accept(mesh, c);
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
    let n = g.pts.len();
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
        let before = Score::of(&mesh, n);
        for d in 1..=max_depth {
            let touched = within_steps(mesh.tris, &l, d, n);
            let Some((c, _)) = candidate(g, &mesh, &touched, CUT_I20, ctx)? else {
                continue;
            };
            if Score::of_candidate(&c, n).better_than(&before) {
                accept(mesh.reborrow(), c);
                kept += 1;
                break;
            }
        }
    }
    Ok(kept)
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

    /// Fewer open edges, no two pieces joined (a bridge between two sheets closes
    /// their borders too), and neither a handle nor a Free point more.
    fn better_than(&self, old: &Score) -> bool {
        self.open < old.open
            && self.pieces >= old.pieces
            && self.twice_genus <= old.twice_genus
            && self.free <= old.free
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
    ctx: &RunCtx,
) -> Result<Option<(Candidate, usize)>, MethodError> {
    let n = g.pts.len();
    let Some((kept, fronts)) = simple_cut(mesh.tris, touched, rule.widen, n) else {
        return Ok(None);
    };
    let removed = mesh.tris.len() - kept.len();
    let held: Vec<u8> = mesh
        .state
        .iter()
        .map(|&s| {
            if rule.hold_free && s == FREE {
                REFUSED
            } else {
                s
            }
        })
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
        let skip: Vec<bool> = (0..n)
            .map(|v| g.refused0[v] || (rule.hold_free && mesh.state[v] == FREE))
            .collect();
        insert_covered(g.pts, g.grid, &mut c.tris, &mut c.state, &skip, bound);
    }
    Ok(Some((c, removed)))
}

fn accept(mesh: PeelMesh, c: Candidate) {
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
