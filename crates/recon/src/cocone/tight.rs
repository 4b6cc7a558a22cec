//! Tight Cocone's marking and peeling (Dey & Goswami 2003): label every Delaunay
//! tetrahedron inside or outside starting from the infinite ones, and output the
//! triangles between the two labels, a watertight surface by construction.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use reconbench_delaunay::{Delaunay, INFINITE, NO_TET};

use super::poles::{OUT_FACE, Poles, apex, outward_normal};

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

/// Cosine of the angle at which the circumspheres of the two tetrahedra of facet `f`
/// meet: near 1 when they intersect deeply (same side of the surface), near −1 when they
/// barely overlap (the facet separates them). For a hull facet the outer ball is the
/// half-space beyond the hull plane.
fn ball_cos(dt: &Delaunay, poles: &Poles, f: u32) -> f64 {
    let facet = dt.facets()[f as usize];
    let (c0, r0) = (
        poles.centres[facet.tets[0] as usize],
        poles.radii[facet.tets[0] as usize],
    );
    if !(c0.is_finite() && r0 > 0.0) {
        return 1.0;
    }
    if facet.tets[1] == NO_TET {
        let p = dt.vertices();
        let n = outward_normal(p, facet.v, apex(dt.tet_vertices(facet.tets[0]), facet.v));
        return ((c0 - p[facet.v[0] as usize]).dot(n) / r0).clamp(-1.0, 1.0);
    }
    let (c1, r1) = (
        poles.centres[facet.tets[1] as usize],
        poles.radii[facet.tets[1] as usize],
    );
    if !(c1.is_finite() && r1 > 0.0) {
        return 1.0;
    }
    ((r0 * r0 + r1 * r1 - c0.distance_squared(c1)) / (2.0 * r0 * r1)).clamp(-1.0, 1.0)
}

/// Facet id of every face of every finite tetrahedron (`4·t + i` is the face opposite
/// vertex `i`).
fn face_facets(dt: &Delaunay) -> Vec<u32> {
    let mut out = vec![u32::MAX; 4 * dt.n_tets()];
    for (f, facet) in dt.facets().iter().enumerate() {
        for &t in &facet.tets {
            if t == NO_TET {
                continue;
            }
            let tv = dt.tet_vertices(t);
            let a = apex(tv, facet.v);
            let i = tv.iter().position(|&v| v == a).expect("apex");
            out[4 * t as usize + i] = f as u32;
        }
    }
    out
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
    surface_facets: &[bool],
    good: &[bool],
    stats: &mut MarkStats,
) -> Vec<bool> {
    let nt = dt.n_tets();
    let nall = dt.n_all_tets();
    let ff = face_facets(dt);
    // 0 unknown, 1 outside, 2 inside.
    let mut label = vec![0u8; nall];
    let mut heap = BinaryHeap::new();
    let push = |heap: &mut BinaryHeap<Item>, t: u32, inside: bool, stats: &mut MarkStats| {
        for (i, &n) in dt.tet_neighbors(t).iter().enumerate() {
            if (n as usize) >= nt {
                continue;
            }
            // The facet between t and n, seen from the finite side when t is a ghost.
            let f = if (t as usize) < nt {
                ff[4 * t as usize + i]
            } else {
                ff[4 * n as usize + dt.mirror_face(t, i)]
            };
            let v = dt.facets()[f as usize].v;
            let poor = v.iter().any(|&x| !good[x as usize]);
            let (prio, flip) = if surface_facets[f as usize] {
                (2.0, true)
            } else if !poor {
                (2.0, false)
            } else {
                let c = ball_cos(dt, poles, f);
                stats.ball_tests += 1;
                (c.abs(), c < 0.0)
            };
            heap.push(Item {
                prio,
                tet: n,
                inside: inside != flip,
            });
        }
    };
    for t in nt..nall {
        label[t] = 1;
    }
    for t in nt..nall {
        push(&mut heap, t as u32, false, stats);
    }
    while let Some(Item { tet, inside, .. }) = heap.pop() {
        if label[tet as usize] != 0 {
            continue;
        }
        label[tet as usize] = if inside { 2 } else { 1 };
        push(&mut heap, tet, inside, stats);
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
