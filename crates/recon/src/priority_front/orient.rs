//! IMPL-CHOICE I16, last step: each piece of the output faces outward.

use glam::DVec3;

use super::complete::VertexFaces;

/// Volumes below this share of a piece's area x reach are rounding noise.
const FLAT: f64 = 1e-9;

/// Orients every edge-connected piece of `faces` (IMPL-CHOICE I16, last step), largest
/// first. A piece whose rim faces the rim of a larger piece across a gap takes the
/// orientation that makes the two consistent (see [`FacingIndex`]; `radius` bounds the
/// gap); a piece that faces none (the largest, or one alone) is reversed when its
/// signed volume seen from `centre` (the sum of the tetrahedra `centre, a, b, c`) is
/// negative: A9's away-from-the-centroid rule for a whole piece rather than its seed
/// triangle, exact on a closed piece whatever the centre, and kept when the piece is
/// flat through the centre. (The volume alone misjudges an open piece that faces the
/// centre, such as the wall of a bore around it; the rim vote does not.) Returns the
/// number of reversed faces.
pub(crate) fn orient_pieces(
    pts: &[DVec3],
    faces: &mut [[u32; 3]],
    centre: DVec3,
    radius: f64,
) -> usize {
    let topo = FaceTopology::new(pts.len(), faces);
    let roots = topo.pieces(faces);
    let mut members: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for (f, &r) in roots.iter().enumerate() {
        members.entry(r).or_default().push(f as u32);
    }
    let mut order: Vec<(u32, Vec<u32>)> = members.into_iter().collect();
    order.sort_by(|x, y| y.1.len().cmp(&x.1.len()).then(x.0.cmp(&y.0)));
    let mut index = FacingIndex::new(radius);
    let mut reversed = 0;
    for (_, list) in &order {
        let rim: Vec<(u32, u32, DVec3)> = list
            .iter()
            .flat_map(|&f| topo.rim_edges(faces, f as usize))
            .map(|(a, b, c)| (a, b, face_normal(pts, [a, b, c])))
            .collect();
        let vote: i64 = rim
            .iter()
            .filter_map(|&(a, b, n)| index.vote(pts, a, b, n))
            .map(|ok| if ok { 1 } else { -1 })
            .sum();
        let flip = match vote {
            v if v < 0 => true,
            v if v > 0 => false,
            _ => inward(pts, faces, list, centre),
        };
        if flip {
            for &f in list {
                faces[f as usize].swap(1, 2);
            }
            reversed += list.len();
        }
        for (a, b, n) in rim {
            if flip {
                index.add(pts, b, a, -n);
            } else {
                index.add(pts, a, b, n);
            }
        }
    }
    reversed
}

/// Unit normal of triangle `t` (zero when degenerate).
fn face_normal(pts: &[DVec3], t: [u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|i| pts[i as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

/// Whether the piece `list` faces `centre` as a whole: negative signed volume beyond
/// the rounding noise of a flat piece through the centre.
fn inward(pts: &[DVec3], faces: &[[u32; 3]], list: &[u32], centre: DVec3) -> bool {
    let (mut volume, mut scale) = (0.0f64, 0.0f64);
    for &f in list {
        let [a, b, c] = faces[f as usize].map(|i| pts[i as usize] - centre);
        volume += a.dot(b.cross(c));
        let reach = a.length().max(b.length()).max(c.length());
        scale += (b - a).cross(c - a).length() * reach;
    }
    volume < -FLAT * scale
}

/// Front or rim edges `a -> b` (with their triangle's unit normal), bucketed for the
/// facing test of IMPL-CHOICE I16. Two pieces bounding consistently oriented meshes
/// across a gap have rims that run in opposite directions. An edge faces the nearest
/// indexed edge whose midpoint lies within `radius`, within 30° of the edge's triangle
/// plane, and with each edge on the other's free side (the side away from its own mesh,
/// which does not depend on how a piece is oriented; this leaves out an edge that
/// continues the other along one rim).
pub(crate) struct FacingIndex {
    radius: f64,
    edges: Vec<(u32, u32, DVec3)>,
    buckets: std::collections::HashMap<[i32; 3], Vec<u32>>,
}

impl FacingIndex {
    /// An empty index for gaps up to `radius`.
    pub(crate) fn new(radius: f64) -> Self {
        Self {
            radius,
            edges: Vec::new(),
            buckets: Default::default(),
        }
    }

    fn cell(&self, p: DVec3) -> [i32; 3] {
        (p / self.radius).floor().as_ivec3().to_array()
    }

    /// Adds edge `a -> b` whose triangle has unit normal `n`.
    pub(crate) fn add(&mut self, pts: &[DVec3], a: u32, b: u32, n: DVec3) {
        let c = self.cell(0.5 * (pts[a as usize] + pts[b as usize]));
        self.buckets
            .entry(c)
            .or_default()
            .push(self.edges.len() as u32);
        self.edges.push((a, b, n));
    }

    /// Whether edge `a -> b` (triangle normal `n`) runs consistently with the indexed
    /// edge it faces; `None` when it faces none.
    pub(crate) fn vote(&self, pts: &[DVec3], a: u32, b: u32, n: DVec3) -> Option<bool> {
        let mid = |a: u32, b: u32| 0.5 * (pts[a as usize] + pts[b as usize]);
        let mf = mid(a, b);
        let tf = pts[b as usize] - pts[a as usize];
        let c = self.cell(mf);
        let facing = |from: DVec3, t: DVec3, n: DVec3| {
            from.dot(t.cross(n).normalize_or_zero()) > FACING_MIN * from.length()
        };
        let mut best: Option<(f64, u32, bool)> = None;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(list) = self.buckets.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &k in list {
                        let (ea, eb, ne) = self.edges[k as usize];
                        let d = mid(ea, eb) - mf;
                        let off = d.dot(n).abs();
                        let along = d.reject_from(n).length();
                        if d.length() > self.radius || off > TAN_30 * along || along == 0.0 {
                            continue;
                        }
                        let te = pts[eb as usize] - pts[ea as usize];
                        if !facing(d, tf, n) || !facing(-d, te, ne) {
                            continue;
                        }
                        if best.is_none_or(|(bo, bk, _)| off < bo || (off == bo && k < bk)) {
                            best = Some((off, k, te.dot(tf) < 0.0));
                        }
                    }
                }
            }
        }
        best.map(|b| b.2)
    }
}

/// cos 60°: how far to the free side of an edge a facing edge must lie, as a share of
/// their distance.
const FACING_MIN: f64 = 0.5;

/// tan 30°: the largest elevation of a facing edge above an edge's triangle plane.
const TAN_30: f64 = 0.577_350_269_189_625_8;

/// The faces around each vertex, with the rim and piece queries of the last step.
struct FaceTopology(VertexFaces);

impl FaceTopology {
    fn new(n: usize, faces: &[[u32; 3]]) -> Self {
        Self(VertexFaces::new(n, faces))
    }

    fn row(&self, v: u32) -> &[u32] {
        self.0.of(v)
    }

    /// The edges `a -> b` of face `f` that no other face shares (its part of a rim),
    /// directed as in `f`, with the face's third corner `c`.
    fn rim_edges(&self, faces: &[[u32; 3]], f: usize) -> Vec<(u32, u32, u32)> {
        let t = faces[f];
        (0..3)
            .map(|k| (t[k], t[(k + 1) % 3], t[(k + 2) % 3]))
            .filter(|&(a, b, _)| {
                !self
                    .row(a)
                    .iter()
                    .any(|&g| g as usize != f && faces[g as usize].contains(&b))
            })
            .collect()
    }

    /// Per face: the smallest face index of its edge-connected piece (faces sharing an
    /// edge, whatever its direction; pieces touching at a vertex stay apart, so an
    /// inverted piece pinned to a good one at a vertex is judged alone).
    fn pieces(&self, faces: &[[u32; 3]]) -> Vec<u32> {
        let mut parent: Vec<u32> = (0..faces.len() as u32).collect();
        let find = |parent: &mut Vec<u32>, mut x: u32| {
            while parent[x as usize] != x {
                let g = parent[parent[x as usize] as usize];
                parent[x as usize] = g;
                x = g;
            }
            x
        };
        for (fi, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                for &g in self.row(a) {
                    if g != fi as u32 && faces[g as usize].contains(&b) {
                        let (r0, r) = (find(&mut parent, fi as u32), find(&mut parent, g));
                        if r != r0 {
                            parent[r.max(r0) as usize] = r.min(r0);
                        }
                    }
                }
            }
        }
        (0..faces.len() as u32)
            .map(|f| find(&mut parent, f))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's 12 faces, all outward (counter-clockwise seen from outside).
    fn cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let pts: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let faces = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (pts, faces)
    }

    #[test]
    fn an_inverted_closed_piece_is_reversed_and_an_outward_one_kept() {
        let (pts, faces) = cube();
        let centre = DVec3::splat(0.5);
        let mut out = faces.clone();
        assert_eq!(orient_pieces(&pts, &mut out, centre, 0.5), 0);
        assert_eq!(out, faces);
        let mut inv: Vec<[u32; 3]> = faces.iter().map(|f| [f[0], f[2], f[1]]).collect();
        // A closed piece: the sign does not depend on the centre.
        assert_eq!(
            orient_pieces(&pts, &mut inv, DVec3::new(7.0, -3.0, 2.0), 0.5),
            12
        );
        assert_eq!(inv, faces);
    }

    #[test]
    fn a_flat_piece_through_the_centre_is_kept_either_way() {
        let pts: Vec<DVec3> = (0..9)
            .map(|i| DVec3::new(0.1 * (i % 3) as f64, 0.3 * (i / 3) as f64 - 0.3, 0.0))
            .collect();
        let grid = [
            [0, 1, 4],
            [0, 4, 3],
            [1, 2, 5],
            [1, 5, 4],
            [3, 4, 7],
            [3, 7, 6],
        ];
        for faces in [
            grid.to_vec(),
            grid.iter().map(|f| [f[0], f[2], f[1]]).collect(),
        ] {
            let mut out = faces.clone();
            assert_eq!(
                orient_pieces(&pts, &mut out, DVec3::new(0.1, 0.0, 0.0), 0.5),
                0
            );
            assert_eq!(out, faces);
        }
    }

    #[test]
    fn pieces_touching_at_a_vertex_are_judged_separately() {
        // Two tetrahedra sharing vertex 0; the small one inverted.
        let pts = vec![
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(-0.1, 0.0, 0.0),
            DVec3::new(0.0, -0.1, 0.0),
            DVec3::new(0.0, 0.0, -0.1),
        ];
        let big = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let small_out = [[0, 4, 5], [0, 6, 4], [0, 5, 6], [4, 6, 5]];
        let mut faces: Vec<[u32; 3]> = big.to_vec();
        faces.extend(small_out.iter().map(|f| [f[0], f[2], f[1]]));
        let centre = DVec3::new(0.2, 0.2, 0.2);
        assert_eq!(orient_pieces(&pts, &mut faces, centre, 0.05), 4);
        assert_eq!(&faces[..4], &big[..]);
        assert_eq!(&faces[4..], &small_out[..]);
    }

    #[test]
    fn pieces_are_judged_separately() {
        let (pts, faces) = cube();
        // A second cube shifted by 3 in x, inverted.
        let mut all = pts.clone();
        all.extend(pts.iter().map(|p| *p + DVec3::new(3.0, 0.0, 0.0)));
        let mut out = faces.clone();
        out.extend(faces.iter().map(|f| [f[0] + 8, f[2] + 8, f[1] + 8]));
        assert_eq!(
            orient_pieces(&all, &mut out, DVec3::new(2.0, 0.5, 0.5), 0.5),
            12
        );
        assert!(
            out[12..]
                .iter()
                .zip(&faces)
                .all(|(a, b)| *a == b.map(|i| i + 8))
        );
        assert_eq!(&out[..12], &faces[..]);
    }
}
