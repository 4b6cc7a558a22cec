//! Scale robustness shared by the reconstructors: run at the exact working scale, hand
//! back a mesh on the input's own points, and refuse a result that collapsed to nothing.
//!
//! A reconstructor whose parameters are fractions of the diagonal, multiples of the
//! spacing, angles or counts gives the same faces on a cloud multiplied by a power of
//! two, so it can run on the copy [`PointCloud::at_working_scale`] makes (largest
//! |coordinate| in `[1/2, 1)` when it is outside `2^±64`), where no squared distance,
//! circumradius or volume overflows or underflows, and then put the input's points back
//! under the faces ([`on_input_points`]).

use glam::DVec3;
use reconbench_geom::cloud::{WORKING_SCALE_BITS, scale_pow2, working_scale_exponent_within};
use reconbench_geom::method::{MethodError, Reconstruction};
use reconbench_geom::{PointCloud, TriMesh};

/// The cloud to run on: the working-scale copy when one was made, else the input.
pub fn working<'a>(cloud: &'a PointCloud, scaled: &'a Option<(PointCloud, i32)>) -> &'a PointCloud {
    scaled.as_ref().map_or(cloud, |(c, _)| c)
}

/// `mesh` (built on the working-scale copy of `input`, same vertex order) with the input
/// points, bit for bit, as its vertices; vertex normals are kept (scale-free).
pub fn on_input_points(mesh: TriMesh, input: &[DVec3]) -> Result<TriMesh, MethodError> {
    if mesh.n_vertices() != input.len() {
        return Err(MethodError::Failed(format!(
            "mesh of {} vertices cannot take the {} input points back",
            mesh.n_vertices(),
            input.len()
        )));
    }
    let normals = mesh.vertex_normals().map(<[DVec3]>::to_vec);
    let out = TriMesh::new(input.to_vec(), mesh.faces().to_vec())?;
    Ok(match normals {
        Some(n) => out.with_vertex_normals(n)?,
        None => out,
    })
}

/// Runs `f` on the working-scale copy of `cloud` (or on `cloud` itself when it is
/// already in range), refuses an empty result on non-collinear points, and multiplies
/// the mesh vertices back by `2^-s` (exact, so vertices that are input points come back
/// bit for bit whenever the forward move was exact: always, unless coordinates more than
/// about 2^1000 below the largest lost low bits).
pub fn reconstruct_at_working_scale(
    name: &str,
    cloud: &PointCloud,
    f: impl FnOnce(&PointCloud) -> Result<Reconstruction, MethodError>,
) -> Result<Reconstruction, MethodError> {
    reconstruct_at_scale(name, cloud, WORKING_SCALE_BITS, |c, _| f(c))
}

/// [`reconstruct_at_working_scale`] for a method whose arithmetic needs the narrower
/// range `2^±bits` (an `f32` stage) or whose parameters or diagnostics carry lengths in
/// the cloud's units: `f` also gets the exponent `s` the cloud was multiplied by (`2^s`,
/// 0 when it ran unscaled), to scale such lengths in ([`times_pow2`]`(x, s)`) and its
/// length diagnostics back out (`times_pow2(x, -s)`).
pub fn reconstruct_at_scale(
    name: &str,
    cloud: &PointCloud,
    bits: i32,
    f: impl FnOnce(&PointCloud, i32) -> Result<Reconstruction, MethodError>,
) -> Result<Reconstruction, MethodError> {
    let scaled = match working_scale_exponent_within(cloud.positions(), bits) {
        Some(s) => {
            let c = cloud
                .clone()
                .with_positions(scale_pow2(cloud.positions(), s))?;
            Some((c, s))
        }
        None => None,
    };
    let work = working(cloud, &scaled);
    let s = scaled.as_ref().map_or(0, |(_, s)| *s);
    let mut r = f(work, s)?;
    check_not_collapsed(name, &r.mesh, work.positions())?;
    if let Some((_, s)) = scaled {
        let normals = r.mesh.vertex_normals().map(<[DVec3]>::to_vec);
        let v = scale_pow2(r.mesh.vertices(), -s);
        let mesh = TriMesh::new(v, r.mesh.faces().to_vec())?;
        r.mesh = match normals {
            Some(n) => mesh.with_vertex_normals(n)?,
            None => mesh,
        };
    }
    Ok(r)
}

/// `x · 2^s`, exact while the result stays a normal double (two steps, so any `s` the
/// working scale produces is fine).
pub fn times_pow2(x: f64, s: i32) -> f64 {
    scale_pow2(&[DVec3::splat(x)], s)[0].x
}

/// Fails when `mesh` has no face although `points` hold three non-collinear points: a
/// reconstruction that collapsed to nothing is an error, not an empty success, and an
/// input error ([`MethodError::InvalidInput`]: the method cannot handle this cloud).
pub fn check_not_collapsed(
    name: &str,
    mesh: &TriMesh,
    points: &[DVec3],
) -> Result<(), MethodError> {
    if mesh.n_faces() > 0 || reconbench_geom::cloud::all_collinear(points) {
        return Ok(());
    }
    // An input error (exit code 2): the method cannot reconstruct this cloud.
    Err(MethodError::InvalidInput(format!(
        "{name}: no face on {} points that are not collinear",
        points.len()
    )))
}

/// Fails when every normal is zero-length although `points` are not collinear.
pub fn check_normals_not_collapsed(
    name: &str,
    normals: &[DVec3],
    points: &[DVec3],
) -> Result<(), MethodError> {
    if normals.iter().any(|n| *n != DVec3::ZERO) || reconbench_geom::cloud::all_collinear(points) {
        return Ok(());
    }
    Err(MethodError::InvalidInput(format!(
        "{name}: every one of the {} normals is zero-length although the points are not \
         collinear",
        normals.len()
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collapse_is_an_error_only_on_a_spread_cloud() {
        let empty = TriMesh::new(vec![DVec3::ZERO; 3], Vec::new()).unwrap();
        let line = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert!(check_not_collapsed("m", &empty, &line).is_ok());
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let err = check_not_collapsed("m", &empty, &tri).unwrap_err();
        assert!(err.to_string().contains("no face on 3 points"), "{err}");
        let one = TriMesh::new(tri.to_vec(), vec![[0, 1, 2]]).unwrap();
        assert!(check_not_collapsed("m", &one, &tri).is_ok());
    }

    #[test]
    fn input_points_come_back_bit_for_bit() {
        let input = vec![
            DVec3::new(1e300, 0.0, 0.0),
            DVec3::new(0.0, 3e300, 0.0),
            DVec3::Z * 1e300,
        ];
        let cloud = PointCloud::new(input.clone()).unwrap();
        let scaled = cloud.at_working_scale();
        let work = working(&cloud, &scaled);
        assert!(work.positions()[1].y < 1.0);
        let mesh = TriMesh::new(work.positions().to_vec(), vec![[0, 1, 2]]).unwrap();
        let back = on_input_points(mesh, &input).unwrap();
        assert_eq!(back.vertices(), &input[..]);
        assert_eq!(back.faces(), &[[0, 1, 2]]);
    }
}
