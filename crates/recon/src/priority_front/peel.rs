//! Peel and refill (IMPL-CHOICE I17, not in the paper; issue 20; `fill_holes_peel`).
//!
//! A loop that neither the ears nor the least-fold programme of I15 can close is most
//! often rimmed by folded faces: where two fronts met at a crease or across a sparsely
//! sampled band, the last faces of the growth lie over one another, so every triangle
//! that would close the loop folds back onto a rim face or crosses one (on the real
//! fandisk, rocker arm and golf club every such loop of 3-6 vertices is of this kind).
//! The remedy is the usual one of hole fillers: take the rim away and fill the larger,
//! cleaner loop. For depth d = 1, 2, ... the faces within d edge steps of such a loop
//! (its rim, then the faces across the rim's edges) are removed, when the remaining border is one simple loop that touches no other loop,
//! and the enlarged loop is given to the I15 fillers (same bounds, same crossing test).
//! A loop that is still open afterwards gets its faces back unchanged, so the pass never
//! leaves a hole larger than it found. Points left without a face by a successful refill
//! become Free again (the completion may insert them).

use glam::DVec3;

use super::complete::VertexFaces;
use super::grid::{Grid, NONE};
use super::mesher::{ACCEPTED, Cfg, FREE, Mesher, tri_normal};

/// The mesh being repaired: faces, point states and front loops (vertex cycles in front
/// order: front edge `l[i] -> l[i + 1]` has its face on the mesh side).
pub(super) struct PeelMesh<'a> {
    pub tris: &'a mut Vec<[u32; 3]>,
    pub state: &'a mut Vec<u8>,
    pub loops: &'a mut Vec<Vec<u32>>,
}

/// The fill bounds of IMPL-CHOICE I15 (see `Mesher::fill_holes`).
#[derive(Clone, Copy)]
pub(super) struct FillBounds {
    pub max_edge: f64,
    pub edge_rel: f64,
    pub max_loop: usize,
    pub dp: bool,
}

/// One loop's peel: the loop, the faces taken away and the enlarged loop.
struct Peel {
    old: usize,
    faces: Vec<u32>,
    grown: Vec<u32>,
}

/// Peels and refills the open loops of at most `b.max_loop` vertices, at depths 1 to
/// `depth`. Returns the number of loops closed.
pub(super) fn peel_refill(
    pts: &[DVec3],
    grid: &Grid,
    cfg: &Cfg,
    refused0: &[bool],
    mut mesh: PeelMesh,
    b: FillBounds,
    depth: usize,
) -> u64 {
    let mut closed = 0;
    for d in 1..=depth {
        if !mesh
            .loops
            .iter()
            .any(|l| (3..=b.max_loop).contains(&l.len()))
        {
            break;
        }
        let vf = VertexFaces::new(pts.len(), mesh.tris);
        let peels = plan_peels(mesh.tris, mesh.loops, &vf, b.max_loop, d, pts.len());
        if peels.is_empty() {
            continue;
        }
        closed += refill(pts, grid, cfg, refused0, &mut mesh, &peels, b);
    }
    closed
}

/// The peels at depth `d` of the loops that qualify, in loop order; a loop is skipped
/// when its peel would share a face or a vertex with another loop or peel, or leave a
/// border that is not one simple loop.
fn plan_peels(
    tris: &[[u32; 3]],
    loops: &[Vec<u32>],
    vf: &VertexFaces,
    max_loop: usize,
    d: usize,
    n: usize,
) -> Vec<Peel> {
    const NO: u32 = u32::MAX;
    let mut on_loop = vec![NO; n];
    for (i, l) in loops.iter().enumerate() {
        for &v in l {
            on_loop[v as usize] = i as u32;
        }
    }
    let mut in_peel = vec![false; tris.len()];
    let mut touched = vec![false; n];
    let mut peels = Vec::new();
    for (li, l) in loops.iter().enumerate() {
        if !(3..=max_loop).contains(&l.len()) {
            continue;
        }
        let faces = rings(tris, l, vf, d);
        // A face of an earlier peel has its vertices touched, so this also keeps the
        // peels' faces apart.
        let ok = faces.iter().all(|&f| {
            tris[f as usize].iter().all(|&v| {
                !touched[v as usize]
                    && (on_loop[v as usize] == NO || on_loop[v as usize] == li as u32)
            })
        });
        if !ok || faces.is_empty() {
            continue;
        }
        for &f in &faces {
            in_peel[f as usize] = true;
        }
        let grown = border(tris, vf, &faces, &in_peel);
        for &f in &faces {
            in_peel[f as usize] = false;
        }
        let Some(grown) = grown else { continue };
        for &f in &faces {
            for &v in &tris[f as usize] {
                touched[v as usize] = true;
            }
        }
        peels.push(Peel {
            old: li,
            faces,
            grown,
        });
    }
    peels
}

/// The faces within `d` edge steps of loop `l` (sorted): step 1 is the loop's rim,
/// the face on each loop edge; step k + 1 adds the faces across an edge of step k.
fn rings(tris: &[[u32; 3]], l: &[u32], vf: &VertexFaces, d: usize) -> Vec<u32> {
    let k = l.len();
    let mut faces: Vec<u32> = (0..k)
        .filter_map(|i| half_edge_face(tris, vf, l[i], l[(i + 1) % k], |_| false))
        .collect();
    faces.sort_unstable();
    faces.dedup();
    for _ in 1..d {
        let mut more = faces.clone();
        for &f in &faces {
            let t = tris[f as usize];
            for j in 0..3 {
                more.extend(half_edge_face(tris, vf, t[(j + 1) % 3], t[j], |_| false));
            }
        }
        more.sort_unstable();
        more.dedup();
        faces = more;
    }
    faces
}

/// The face with half-edge `u -> v`, among those not `removed`, if any.
pub(super) fn half_edge_face(
    tris: &[[u32; 3]],
    vf: &VertexFaces,
    u: u32,
    v: u32,
    removed: impl Fn(u32) -> bool,
) -> Option<u32> {
    vf.of(u).iter().copied().find(|&g| {
        let t = tris[g as usize];
        !removed(g) && (0..3).any(|j| t[j] == u && t[(j + 1) % 3] == v)
    })
}

/// The border left when the faces `faces` (flagged in `in_peel`) are removed, as one
/// vertex cycle in front order, or `None` when it is not one simple loop of at least
/// three vertices. A front edge runs along the half-edge of the face on its mesh side,
/// so against the half-edge of the peeled face across it.
fn border(
    tris: &[[u32; 3]],
    vf: &VertexFaces,
    faces: &[u32],
    in_peel: &[bool],
) -> Option<Vec<u32>> {
    let mut next: Vec<(u32, u32)> = Vec::new();
    for &f in faces {
        let t = tris[f as usize];
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            if half_edge_face(tris, vf, v, u, |g| in_peel[g as usize]).is_some() {
                next.push((v, u));
            }
        }
    }
    next.sort_unstable();
    if next.len() < 3 || next.windows(2).any(|w| w[0].0 == w[1].0) {
        return None;
    }
    let start = next[0].0;
    let mut cycle = vec![start];
    let mut v = next[0].1;
    while v != start {
        if cycle.len() >= next.len() {
            return None;
        }
        cycle.push(v);
        let i = next.binary_search_by_key(&v, |e| e.0).ok()?;
        v = next[i].1;
    }
    (cycle.len() == next.len()).then_some(cycle)
}

/// Removes the peeled faces, rebuilds a mesher on what is left and fills the enlarged
/// loops; a peel whose loop stays open gets its faces back. Returns the number of loops
/// closed.
fn refill(
    pts: &[DVec3],
    grid: &Grid,
    cfg: &Cfg,
    refused0: &[bool],
    mesh: &mut PeelMesh,
    peels: &[Peel],
    b: FillBounds,
) -> u64 {
    let mut gone = vec![false; mesh.tris.len()];
    let mut peeled = vec![false; mesh.loops.len()];
    for p in peels {
        peeled[p.old] = true;
        for &f in &p.faces {
            gone[f as usize] = true;
        }
    }
    let kept: Vec<[u32; 3]> = mesh
        .tris
        .iter()
        .zip(&gone)
        .filter(|(_, g)| !**g)
        .map(|(t, _)| *t)
        .collect();
    let fronts = mesh
        .loops
        .iter()
        .zip(&peeled)
        .filter(|(_, p)| !**p)
        .map(|(l, _)| l)
        .chain(peels.iter().map(|p| &p.grown));
    let mut m = mesher_from_faces(pts, grid, cfg, refused0, &kept, fronts, mesh.state);
    let todo: Vec<Vec<u32>> = peels.iter().map(|p| p.grown.clone()).collect();
    m.fill_loops(todo, b.max_edge, b.edge_rel, b.dp);
    let failed: Vec<&Peel> = peels
        .iter()
        .filter(|p| m.fout[p.grown[0] as usize] != NONE)
        .collect();
    let mut tris = std::mem::take(&mut m.tris);
    let mut state = std::mem::take(&mut m.state);
    let mut loops: Vec<Vec<u32>> = m
        .loops()
        .into_iter()
        .filter(|l| !failed.iter().any(|p| l.contains(&p.grown[0])))
        .collect();
    for p in &failed {
        for &f in &p.faces {
            let t = mesh.tris[f as usize];
            tris.push(t);
            for &v in &t {
                state[v as usize] = ACCEPTED;
            }
        }
        loops.push(mesh.loops[p.old].clone());
    }
    let closed = (peels.len() - failed.len()) as u64;
    *mesh.tris = tris;
    *mesh.state = state;
    *mesh.loops = loops;
    closed
}

/// A mesher over faces `kept` whose live front is `fronts` (vertex cycles in front
/// order). Points with a face are Accepted, points that had one in `state` and lost it
/// are Free, the others keep their `state`.
pub(super) fn mesher_from_faces<'g, 'l>(
    pts: &'g [DVec3],
    grid: &'g Grid,
    cfg: &Cfg,
    refused0: &[bool],
    kept: &[[u32; 3]],
    fronts: impl IntoIterator<Item = &'l Vec<u32>>,
    state: &[u8],
) -> Mesher<'g> {
    let n = pts.len();
    let vf = VertexFaces::new(n, kept);
    let mut edges = Vec::new();
    for l in fronts {
        let (base, k) = (edges.len(), l.len());
        for i in 0..k {
            let (a, c) = (l[i], l[(i + 1) % k]);
            // The face on the mesh side of front edge a -> c has half-edge a -> c.
            let nrm = half_edge_face(kept, &vf, a, c, |_| false).map_or(DVec3::ZERO, |f| {
                let t = kept[f as usize].map(|v| pts[v as usize]);
                tri_normal(t[0], t[1], t[2])
            });
            edges.push((a, c, (base + (i + 1) % k) as u32, nrm, 0.0));
        }
    }
    let mut has_face = vec![false; n];
    for &v in kept.iter().flatten() {
        has_face[v as usize] = true;
    }
    let accepted: Vec<u32> = (0..n as u32).filter(|&v| has_face[v as usize]).collect();
    let mut m = Mesher::new(pts, grid, cfg.clone(), refused0);
    m.import(kept, &accepted, &edges);
    for (v, s) in m.state.iter_mut().enumerate() {
        *s = match (has_face[v], state[v]) {
            (true, _) => ACCEPTED,
            (false, ACCEPTED) => FREE,
            (false, old) => old,
        };
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat `m x m` vertex grid, two counter-clockwise triangles per cell, without the
    /// cells listed in `holes` (cell index `y (m - 1) + x`).
    fn grid_mesh(m: u32, holes: &[u32]) -> Vec<[u32; 3]> {
        let mut tris = Vec::new();
        for y in 0..m - 1 {
            for x in 0..m - 1 {
                if holes.contains(&(y * (m - 1) + x)) {
                    continue;
                }
                let v = y * m + x;
                tris.push([v, v + 1, v + m + 1]);
                tris.push([v, v + m + 1, v + m]);
            }
        }
        tris
    }

    /// The front loop of a one-cell hole at cell (x, y): front edges run along the
    /// half-edges of the faces on their mesh side.
    fn hole_loop(m: u32, x: u32, y: u32) -> Vec<u32> {
        let v = y * m + x;
        vec![v + 1, v, v + m, v + m + 1]
    }

    fn has_half_edge(tris: &[[u32; 3]], skip: &[u32], u: u32, v: u32) -> bool {
        tris.iter().enumerate().any(|(f, t)| {
            !skip.contains(&(f as u32)) && (0..3).any(|j| t[j] == u && t[(j + 1) % 3] == v)
        })
    }

    /// The fixture's hole loop is in front order. The rim of a one-cell hole is its four
    /// edge neighbours; the border left without
    /// them is one simple cycle of 8 vertices whose every edge has its face on the mesh
    /// side, and depth 2 takes a larger rim with a longer border.
    #[test]
    fn peeling_a_hole_leaves_one_simple_front_ordered_border() {
        let m = 8;
        let hole = 3 * (m - 1) + 3;
        let tris = grid_mesh(m, &[hole]);
        let l = hole_loop(m, 3, 3);
        for i in 0..l.len() {
            assert!(has_half_edge(&tris, &[], l[i], l[(i + 1) % l.len()]));
        }
        let vf = VertexFaces::new((m * m) as usize, &tris);
        let mut last = 0;
        for d in 1..=2 {
            let faces = rings(&tris, &l, &vf, d);
            assert!(faces.len() > last, "depth {d}");
            last = faces.len();
            let mut in_peel = vec![false; tris.len()];
            for &f in &faces {
                in_peel[f as usize] = true;
            }
            let b = border(&tris, &vf, &faces, &in_peel).expect("a simple border");
            let mut uniq = b.clone();
            uniq.sort_unstable();
            uniq.dedup();
            assert_eq!(uniq.len(), b.len(), "depth {d}: {b:?}");
            if d == 1 {
                assert_eq!(faces.len(), 4);
                assert_eq!(b.len(), 8, "{b:?}");
            }
            for i in 0..b.len() {
                let (u, v) = (b[i], b[(i + 1) % b.len()]);
                assert!(has_half_edge(&tris, &faces, u, v), "depth {d}: {u} -> {v}");
            }
        }
    }

    /// Two holes one cell apart: the rim of the first touches the second's vertices, so
    /// it is not peeled (the pass never merges loops); the second, planned after it, is.
    #[test]
    fn a_peel_that_would_touch_another_loop_is_skipped() {
        let m = 8;
        let tris = grid_mesh(m, &[3 * (m - 1) + 2, 3 * (m - 1) + 4]);
        let loops = vec![hole_loop(m, 2, 3), hole_loop(m, 4, 3)];
        let vf = VertexFaces::new((m * m) as usize, &tris);
        let peels = plan_peels(&tris, &loops, &vf, 16, 1, (m * m) as usize);
        assert!(peels.is_empty(), "{}", peels.len());
        let far = grid_mesh(m, &[(m - 1) + 1, 5 * (m - 1) + 5]);
        let loops = vec![hole_loop(m, 1, 1), hole_loop(m, 5, 5)];
        let vf = VertexFaces::new((m * m) as usize, &far);
        let peels = plan_peels(&far, &loops, &vf, 16, 1, (m * m) as usize);
        assert_eq!(peels.len(), 2);
        assert!(
            peels
                .iter()
                .all(|p| p.faces.len() == 4 && p.grown.len() == 8)
        );
    }
}
