//! Indexed triangle meshes (geometry only; adjacency lives in [`crate::topology`]).

use glam::DVec3;

use crate::aabb::Aabb;
use crate::error::{GeomError, Result, check_finite, check_len};

/// An indexed triangle mesh: vertex positions and `[u32; 3]` faces.
///
/// Construction guarantees finite vertices and in-range face indices. Nothing else is
/// assumed: meshes may be non-manifold, have degenerate or duplicate faces and
/// unreferenced vertices, because reconbench must be able to diagnose such output.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    vertices: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
    vertex_normals: Option<Vec<DVec3>>,
    vertex_colors: Option<Vec<[u8; 3]>>,
}

impl TriMesh {
    /// A mesh from vertices and faces; fails on a non-finite vertex or an out-of-range
    /// face index (naming the face), or on more than `u32::MAX` vertices.
    pub fn new(vertices: Vec<DVec3>, faces: Vec<[u32; 3]>) -> Result<Self> {
        check_finite("vertex", &vertices)?;
        if vertices.len() > u32::MAX as usize {
            return Err(GeomError::InvalidInput(format!(
                "{} vertices exceed the u32 index range",
                vertices.len()
            )));
        }
        let n = vertices.len();
        for (fi, f) in faces.iter().enumerate() {
            if let Some(&v) = f.iter().find(|&&v| v as usize >= n) {
                return Err(GeomError::FaceIndexOutOfRange {
                    face: fi,
                    vertex: v as u64,
                    n_vertices: n,
                });
            }
        }
        Ok(Self {
            vertices,
            faces,
            vertex_normals: None,
            vertex_colors: None,
        })
    }

    /// Attaches per-vertex normals.
    pub fn with_vertex_normals(mut self, normals: Vec<DVec3>) -> Result<Self> {
        self.set_vertex_normals(Some(normals))?;
        Ok(self)
    }

    /// Replaces (or removes) the per-vertex normals.
    pub fn set_vertex_normals(&mut self, normals: Option<Vec<DVec3>>) -> Result<()> {
        if let Some(n) = &normals {
            check_len("vertex normals", n.len(), self.vertices.len(), "vertex")?;
            check_finite("normal", n)?;
        }
        self.vertex_normals = normals;
        Ok(())
    }

    /// Replaces (or removes) the per-vertex colours.
    pub fn set_vertex_colors(&mut self, colors: Option<Vec<[u8; 3]>>) -> Result<()> {
        if let Some(c) = &colors {
            check_len("vertex colors", c.len(), self.vertices.len(), "vertex")?;
        }
        self.vertex_colors = colors;
        Ok(())
    }

    /// Vertex positions.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// Faces as vertex-index triples.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Per-vertex normals, if any.
    pub fn vertex_normals(&self) -> Option<&[DVec3]> {
        self.vertex_normals.as_deref()
    }

    /// Per-vertex colours, if any.
    pub fn vertex_colors(&self) -> Option<&[[u8; 3]]> {
        self.vertex_colors.as_deref()
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// The three corner positions of face `f`.
    pub fn triangle(&self, f: usize) -> [DVec3; 3] {
        self.faces[f].map(|v| self.vertices[v as usize])
    }

    /// Non-normalised face normal (cross product; its length is twice the area).
    pub fn face_cross(&self, f: usize) -> DVec3 {
        let [a, b, c] = self.triangle(f);
        (b - a).cross(c - a)
    }

    /// Unit face normal following the right-hand rule, or zero for a degenerate face.
    pub fn face_normal(&self, f: usize) -> DVec3 {
        self.face_cross(f).normalize_or_zero()
    }

    /// Area of face `f`.
    pub fn face_area(&self, f: usize) -> f64 {
        0.5 * self.face_cross(f).length()
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.n_faces()).map(|f| self.face_area(f)).sum()
    }

    /// Bounding box of the vertices (including unreferenced ones).
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }

    /// Angle-weighted vertex normals (Thürmer & Wüthrich), the convention METRICS.md uses
    /// for comparing mesh normals with ground truth. Isolated vertices get zero.
    pub fn angle_weighted_normals(&self) -> Vec<DVec3> {
        let mut acc = vec![DVec3::ZERO; self.vertices.len()];
        for f in 0..self.faces.len() {
            let n = self.face_normal(f);
            if n == DVec3::ZERO {
                continue;
            }
            let idx = self.faces[f];
            let p = self.triangle(f);
            for k in 0..3 {
                let e1 = p[(k + 1) % 3] - p[k];
                let e2 = p[(k + 2) % 3] - p[k];
                acc[idx[k] as usize] += e1.angle_between(e2) * n;
            }
        }
        acc.into_iter().map(DVec3::normalize_or_zero).collect()
    }

    /// Area-weighted vertex normals: the sum of the cross products of the incident faces
    /// (each is twice the face area times its unit normal), normalised. This is seed 000's
    /// "type-2" reference normal of a mesh vertex. Isolated vertices get zero.
    pub fn area_weighted_normals(&self) -> Vec<DVec3> {
        let mut acc = vec![DVec3::ZERO; self.vertices.len()];
        for (f, idx) in self.faces.iter().enumerate() {
            let c = self.face_cross(f);
            for &v in idx {
                acc[v as usize] += c;
            }
        }
        acc.into_iter().map(DVec3::normalize_or_zero).collect()
    }

    /// Flips the orientation of the faces whose flag is set.
    pub fn flip_faces(&mut self, flip: &[bool]) {
        for (f, &fl) in self.faces.iter_mut().zip(flip) {
            if fl {
                f.swap(1, 2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> TriMesh {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        TriMesh::new(v, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]).unwrap()
    }

    #[test]
    fn out_of_range_face_names_face_and_vertex() {
        let err = TriMesh::new(vec![DVec3::ZERO; 3], vec![[0, 1, 2], [0, 1, 7]]).unwrap_err();
        assert!(matches!(
            err,
            GeomError::FaceIndexOutOfRange {
                face: 1,
                vertex: 7,
                n_vertices: 3
            }
        ));
    }

    #[test]
    fn infinite_vertex_is_rejected() {
        assert!(TriMesh::new(vec![DVec3::new(f64::INFINITY, 0.0, 0.0)], vec![]).is_err());
    }

    #[test]
    fn tetra_area_and_outward_normals() {
        let m = tetra();
        let expect = 1.5 + 3f64.sqrt() / 2.0;
        assert!((m.area() - expect).abs() < 1e-12);
        let c = DVec3::splat(0.25);
        for f in 0..4 {
            let [a, _, _] = m.triangle(f);
            assert!(m.face_normal(f).dot(a - c) > 0.0, "face {f} points inwards");
        }
        let n = m.angle_weighted_normals();
        assert!(n[0].dot(-DVec3::ONE) > 0.0);
    }
}
