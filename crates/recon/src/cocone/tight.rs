//! Tight Cocone's marking and peeling (Dey & Goswami 2003): label every Delaunay
//! tetrahedron inside or outside starting from the infinite ones, and output the
//! triangles between the two labels, a watertight surface by construction.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use rayon::prelude::*;
use reconbench_delaunay::{Delaunay, INFINITE, NO_TET};

use super::poles::{OUT_FACE, Poles, apex};

/// Which initial-surface triangles the marking treats as certain surface triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SurfaceRule {
    /// A triangle of the umbrella of at least one good sample.
    OneGood,
    /// A triangle all of whose vertices are good samples.
    AllGood,
}

/// Counts of the marking.
#[derive(Debug, Clone, Copy, Default)]
pub struct MarkStats {
    /// Samples whose initial-surface triangles form one closed disc.
    pub good: usize,
    /// Tetrahedra labelled inside.
    pub inside: usize,
    /// Crossings weighed by the circumball intersection angle (near poor samples).
    pub ball_tests: usize,
}

/// Samples whose triangles in `surface` (Delaunay vertex triples) form exactly one
/// closed fan: every incident edge is used twice and the link is one cycle.
pub fn good_samples(nv: usize, surface: &[[u32; 3]]) -> Vec<bool> {
    let mut off = vec![0u32; nv + 1];
    for t in surface {
        for &v in t {
            off[v as usize + 1] += 1;
        }
    }
    for i in 0..nv {
        off[i + 1] += off[i];
    }
    let mut fill = off.clone();
    let mut link = vec![[0u32; 2]; off[nv] as usize];
    for t in surface {
        for k in 0..3 {
            let v = t[k] as usize;
            link[fill[v] as usize] = [t[(k + 1) % 3], t[(k + 2) % 3]];
            fill[v] += 1;
        }
    }
    (0..nv)
        .into_par_iter()
        .map(|v| {
            let l = &link[off[v] as usize..off[v + 1] as usize];
            if l.len() < 3 {
                return false;
            }
            // Oriented link edges a→b: a closed disc is one cycle through distinct
            // successors.
            let next = |a: u32| l.iter().filter(move |e| e[0] == a).map(|e| e[1]);
            if l.iter().any(|e| next(e[0]).count() != 1) {
                return false;
            }
            let start = l[0][0];
            let mut cur = start;
            for step in 1..=l.len() {
                let Some(n) = next(cur).next() else {
                    return false;
                };
                cur = n;
                if cur == start {
                    return step == l.len();
                }
            }
            false
        })
        .collect()
}

#[derive(PartialEq)]
struct Item {
    prio: f64,
    tet: u32,
    inside: bool,
}

impl Eq for Item {}

impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        self.prio
            .total_cmp(&o.prio)
            .then_with(|| o.tet.cmp(&self.tet))
    }
}

impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Cosine of the angle at which the circumspheres of tetrahedron `t` and its neighbour
/// across face `i` meet: near 1 when they intersect deeply (same side of the surface),
/// near −1 when they barely overlap (the face separates them). For a hull face the outer
/// ball is the half-space beyond the hull plane.
fn ball_cos(dt: &Delaunay, poles: &Poles, t: u32, i: usize) -> f64 {
    let (c0, r0) = (poles.centres[t as usize], poles.radii[t as usize]);
    if !(c0.is_finite() && r0 > 0.0) {
        return 1.0;
    }
    let n = dt.tet_neighbors(t)[i];
    if n as usize >= dt.n_tets() {
        let p = dt.vertices();
        let tv = dt.tet_vertices(t);
        let [a, b, c] = OUT_FACE[i].map(|k| p[tv[k] as usize]);
        let nrm = (b - a).cross(c - a).normalize_or_zero();
        return ((c0 - a).dot(nrm) / r0).clamp(-1.0, 1.0);
    }
    let (c1, r1) = (poles.centres[n as usize], poles.radii[n as usize]);
    if !(c1.is_finite() && r1 > 0.0) {
        return 1.0;
    }
    ((r0 * r0 + r1 * r1 - c0.distance_squared(c1)) / (2.0 * r0 * r1)).clamp(-1.0, 1.0)
}

/// Flags the two sides (`4·t + i`, face `i` of tetrahedron `t`) of every listed facet.
fn face_flags(dt: &Delaunay, facets: &[u32]) -> Vec<bool> {
    let mut out = vec![false; 4 * dt.n_tets()];
    for &f in facets {
        let facet = dt.facets()[f as usize];
        for &t in &facet.tets {
            if t == NO_TET {
                continue;
            }
            let tv = dt.tet_vertices(t);
            let a = apex(tv, facet.v);
            let i = tv.iter().position(|&v| v == a).expect("apex");
            out[4 * t as usize + i] = true;
        }
    }
    out
}

/// What crossing a face into the neighbour does to the label (the two low bits of a
/// [`face_classes`] entry): a surface triangle flips it.
const FLIP: u32 = 0;
/// Crossed freely: no poor vertex, the label is kept.
const KEEP: u32 = 1;
/// Near a poor sample: the circumball angle decides.
const BALL: u32 = 2;
/// The neighbour is a ghost (always outside): never entered.
const GHOST: u32 = 3;

/// For every face `4·t + i` (ghosts included), the neighbour across it and the crossing
/// rule, packed as `neighbour << 2 | rule` (the triangulation keeps tetrahedron ids below
/// 2^30 for the same packing). Computed in parallel before the sequential walk, so the
/// walk reads one flat array in place of the tetrahedra, their vertices and the
/// vertices' good flags.
fn face_classes(dt: &Delaunay, surface: &[bool], good: &[bool]) -> Vec<u32> {
    let nt = dt.n_tets();
    let mut cls = vec![GHOST; 4 * dt.n_all_tets()];
    cls.par_chunks_mut(4)
        .enumerate()
        .with_min_len(4096)
        .for_each(|(t, c)| {
            let t = t as u32;
            for (i, &n) in dt.tet_neighbors(t).iter().enumerate() {
                if n as usize >= nt {
                    continue;
                }
                // The shared face seen from the finite side (n, face j) when t is a ghost.
                let (ft, fi) = if (t as usize) < nt {
                    (t, i)
                } else {
                    (n, dt.mirror_face(t, i))
                };
                let tv = dt.tet_vertices(ft);
                let rule = if surface[4 * ft as usize + fi] {
                    FLIP
                } else if OUT_FACE[fi].iter().all(|&k| good[tv[k] as usize]) {
                    KEEP
                } else {
                    BALL
                };
                c[i] = (n << 2) | rule;
            }
        });
    cls
}

/// Labels every tetrahedron inside (`true`) or outside; ghosts are outside.
///
/// Crossing a facet from a labelled tetrahedron: a surface triangle flips the label; a
/// facet with no poor vertex keeps it (it is "crossed freely"); near poor samples the
/// circumball angle decides (ASSUMPTION K-05). Decisions are taken most certain first
/// (ASSUMPTION K-06), the two certain rules before any circumball decision.
pub fn label(
    dt: &Delaunay,
    poles: &Poles,
    surface_facets: &[u32],
    good: &[bool],
    stats: &mut MarkStats,
) -> Vec<bool> {
    let nt = dt.n_tets();
    let nall = dt.n_all_tets();
    let cls = face_classes(dt, &face_flags(dt, surface_facets), good);
    // 0 unknown, 1 outside, 2 inside.
    let mut label = vec![0u8; nall];
    // The certain crossings (priority above every circumball decision) wait on a stack,
    // the circumball decisions in a max-heap on |cos|.
    let mut certain: Vec<(u32, bool)> = Vec::new();
    let mut heap = BinaryHeap::new();
    let push = |t: u32,
                inside: bool,
                label: &[u8],
                certain: &mut Vec<(u32, bool)>,
                heap: &mut BinaryHeap<Item>,
                stats: &mut MarkStats| {
        let row = &cls[4 * t as usize..4 * t as usize + 4];
        for (i, &c) in row.iter().enumerate() {
            let (n, k) = (c >> 2, c & 3);
            if k == GHOST || label[n as usize] != 0 {
                continue;
            }
            match k {
                FLIP => certain.push((n, !inside)),
                KEEP => certain.push((n, inside)),
                _ => {
                    debug_assert_eq!(k, BALL);
                    let (ft, fi) = if (t as usize) < nt {
                        (t, i)
                    } else {
                        (n, dt.mirror_face(t, i))
                    };
                    let c = ball_cos(dt, poles, ft, fi);
                    stats.ball_tests += 1;
                    heap.push(Item {
                        prio: c.abs(),
                        tet: n,
                        inside: inside != (c < 0.0),
                    });
                }
            }
        }
    };
    for l in &mut label[nt..nall] {
        *l = 1;
    }
    for t in nt..nall {
        push(t as u32, false, &label, &mut certain, &mut heap, stats);
    }
    loop {
        let (tet, inside) = if let Some(x) = certain.pop() {
            x
        } else if let Some(Item { tet, inside, .. }) = heap.pop() {
            (tet, inside)
        } else {
            break;
        };
        if label[tet as usize] != 0 {
            continue;
        }
        label[tet as usize] = if inside { 2 } else { 1 };
        push(tet, inside, &label, &mut certain, &mut heap, stats);
    }
    let inside: Vec<bool> = label.iter().map(|&l| l == 2).collect();
    stats.inside = inside.iter().filter(|&&x| x).count();
    inside
}

/// The oriented triangles (Delaunay ids) between inside and outside tetrahedra, normals
/// pointing out of the inside.
pub fn interface(dt: &Delaunay, inside: &[bool]) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for t in 0..dt.n_tets() as u32 {
        if !inside[t as usize] {
            continue;
        }
        let tv = dt.tet_vertices(t);
        for (i, &n) in dt.tet_neighbors(t).iter().enumerate() {
            if !inside[n as usize] {
                out.push(OUT_FACE[i].map(|k| tv[k]));
            }
        }
    }
    debug_assert!(out.iter().all(|t| !t.contains(&INFINITE)));
    out
}
