//! IMPL-CHOICE I16, last step: each piece of the output faces outward.

use glam::DVec3;

/// Volumes below this share of a piece's area x reach are rounding noise.
const FLAT: f64 = 1e-9;

/// Reverses every vertex-connected piece of `faces` whose signed volume seen from
/// `centre` (the sum of the tetrahedra `centre, a, b, c`) is negative: A9's
/// away-from-the-centroid rule applied to a whole piece rather than to its seed
/// triangle, which can land in a concave region. On a closed piece the sign does not
/// depend on `centre`; on an open one it is the flux of the piece seen from it. A piece
/// that faces the centre as a whole (the inside of a hollow part seen from a point
/// outside it) would be reversed wrongly; such clouds need `seed_orient_front = false`.
/// A piece whose volume is within rounding of zero (a plane through the centre) is
/// kept. Returns the number of reversed faces.
pub(crate) fn outward_pieces(pts: &[DVec3], faces: &mut [[u32; 3]], centre: DVec3) -> usize {
    let mut parent: Vec<u32> = (0..pts.len() as u32).collect();
    let find = |parent: &mut Vec<u32>, mut x: u32| {
        while parent[x as usize] != x {
            let g = parent[parent[x as usize] as usize];
            parent[x as usize] = g;
            x = g;
        }
        x
    };
    for f in faces.iter() {
        for &v in &f[1..] {
            let (r0, r) = (find(&mut parent, f[0]), find(&mut parent, v));
            if r != r0 {
                parent[r.max(r0) as usize] = r.min(r0);
            }
        }
    }
    let mut volume = vec![0.0f64; pts.len()];
    // Per piece: the sum of |2 area| x the piece's reach from the centre, the scale of
    // the rounding noise the volume of a flat piece seen from its own plane carries.
    let mut scale = vec![0.0f64; pts.len()];
    let roots: Vec<u32> = faces.iter().map(|f| find(&mut parent, f[0])).collect();
    for (f, &r) in faces.iter().zip(&roots) {
        let [a, b, c] = f.map(|i| pts[i as usize] - centre);
        volume[r as usize] += a.dot(b.cross(c));
        let reach = a.length().max(b.length()).max(c.length());
        scale[r as usize] += (b - a).cross(c - a).length() * reach;
    }
    let mut reversed = 0;
    for (f, &r) in faces.iter_mut().zip(&roots) {
        // A piece flat in a plane through the centre has no outward side: kept.
        if volume[r as usize] < -FLAT * scale[r as usize] {
            f.swap(1, 2);
            reversed += 1;
        }
    }
    reversed
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
        assert_eq!(outward_pieces(&pts, &mut out, centre), 0);
        assert_eq!(out, faces);
        let mut inv: Vec<[u32; 3]> = faces.iter().map(|f| [f[0], f[2], f[1]]).collect();
        // A closed piece: the sign does not depend on the centre.
        assert_eq!(
            outward_pieces(&pts, &mut inv, DVec3::new(7.0, -3.0, 2.0)),
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
            assert_eq!(outward_pieces(&pts, &mut out, DVec3::new(0.1, 0.0, 0.0)), 0);
            assert_eq!(out, faces);
        }
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
            outward_pieces(&all, &mut out, DVec3::new(2.0, 0.5, 0.5)),
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
