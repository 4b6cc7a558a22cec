//! The crate's marching-cubes buffers as a canonical mesh, and density trimming.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::method::MethodError;
use reconbench_geom::spatial::PointIndex;
use threecrate_core::TriangleMesh;

fn bits(p: DVec3) -> [u64; 3] {
    (p + DVec3::ZERO).to_array().map(f64::to_bits)
}

/// The crate's mesh with vertices sorted by position (exactly equal positions welded) and faces rotated to
/// start at their lowest index (orientation kept) and sorted; faces that collapse when
/// welding are dropped. The result does not depend on the order the crate emitted.
pub(crate) fn canonical(mesh: &TriangleMesh) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let raw: Vec<DVec3> = mesh
        .vertices
        .iter()
        .map(|p| DVec3::new(f64::from(p.x), f64::from(p.y), f64::from(p.z)))
        .collect();
    let mut order: Vec<u32> = (0..raw.len() as u32).collect();
    order.par_sort_unstable_by_key(|&i| bits(raw[i as usize]));
    let mut remap = vec![0u32; raw.len()];
    let mut vertices: Vec<DVec3> = Vec::with_capacity(raw.len());
    for (j, &i) in order.iter().enumerate() {
        let p = raw[i as usize];
        if j == 0 || bits(raw[order[j - 1] as usize]) != bits(p) {
            vertices.push(p);
        }
        remap[i as usize] = vertices.len() as u32 - 1;
    }
    let mut faces: Vec<[u32; 3]> = mesh
        .faces
        .iter()
        .map(|t| t.map(|v| remap[v]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .map(|t| {
            let r = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
        })
        .collect();
    faces.par_sort_unstable();
    (vertices, faces)
}

/// Removes the share `quantile` of the vertices with the fewest input points within
/// `radius` (Open3D's `densities < quantile(densities, q)` idiom, made exact: ties, such
/// as the many zero counts of a surface closed over a hole, go by vertex index), the
/// faces using them, and the vertices left unused; compacts the rest. Returns the number of vertices removed.
pub(crate) fn trim(
    vertices: &mut Vec<DVec3>,
    faces: &mut Vec<[u32; 3]>,
    input: &[DVec3],
    radius: f64,
    quantile: f64,
) -> Result<usize, MethodError> {
    let index = PointIndex::new(input)?;
    let table = index.radius_batch(vertices, radius)?;
    let counts: Vec<usize> = (0..vertices.len())
        .map(|i| table.offsets[i + 1] - table.offsets[i])
        .collect();
    // The floor(q n) vertices of lowest count go, ties to the lower index.
    let mut order: Vec<u32> = (0..vertices.len() as u32).collect();
    order.sort_unstable_by_key(|&i| (counts[i as usize], i));
    let cut = (quantile * vertices.len() as f64).floor() as usize;
    let mut keep = vec![true; vertices.len()];
    for &i in &order[..cut] {
        keep[i as usize] = false;
    }
    let mut remap = vec![u32::MAX; vertices.len()];
    let mut kept = Vec::with_capacity(vertices.len());
    faces.retain(|f| f.iter().all(|&v| keep[v as usize]));
    let mut used = vec![false; vertices.len()];
    for f in faces.iter() {
        for &v in f {
            used[v as usize] = true;
        }
    }
    for (i, &p) in vertices.iter().enumerate() {
        if used[i] {
            remap[i] = kept.len() as u32;
            kept.push(p);
        }
    }
    for f in faces.iter_mut() {
        *f = f.map(|v| remap[v as usize]);
    }
    let removed = vertices.len() - kept.len();
    *vertices = kept;
    Ok(removed)
}
