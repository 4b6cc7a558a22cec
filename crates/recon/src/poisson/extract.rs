//! The iso-surface of the solved indicator by marching tetrahedra, and density
//! trimming.
//!
//! Marching tetrahedra on the Kuhn (Freudenthal) split of every cell into six
//! tetrahedra around its main diagonal: the piecewise-linear level set of a grid
//! function is a closed 2-manifold by construction (no ambiguous cases, unlike
//! marching cubes without its disambiguation tables), at the cost of about twice the
//! triangles of marching cubes. Vertices sit on grid edges (keyed by edge, so shared
//! between cells); faces are oriented from the inside (`chi > iso`) to the outside.
//! Both passes run per grid plane in parallel and are concatenated in plane order, so
//! the mesh does not depend on the thread count.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::method::MethodError;
use reconbench_geom::spatial::PointIndex;

/// The six monotone paths from a cell's corner `(0, 0, 0)` to `(1, 1, 1)`: the axis
/// order of each Kuhn tetrahedron.
const PATHS: [[usize; 3]; 6] = [
    [0, 1, 2],
    [0, 2, 1],
    [1, 0, 2],
    [1, 2, 0],
    [2, 0, 1],
    [2, 1, 0],
];

/// The grid function the surface is extracted from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Field<'a> {
    /// Values at the nodes, `(k * n + j) * n + i`.
    pub x: &'a [f32],
    /// Nodes per side.
    pub n: usize,
    /// Level.
    pub iso: f32,
    /// Position of node `(0, 0, 0)`.
    pub origin: DVec3,
    /// Cell side.
    pub cell: f64,
}

impl Field<'_> {
    fn id(&self, c: [usize; 3]) -> usize {
        (c[2] * self.n + c[1]) * self.n + c[0]
    }

    /// Inside: above the level and not on the grid boundary (which closes the surface).
    fn inside(&self, c: [usize; 3]) -> bool {
        let last = self.n - 1;
        c.iter().all(|&v| v > 0 && v < last) && self.x[self.id(c)] > self.iso
    }

    /// Vertex key of the edge from `lo` along the 0/1 offsets `d`.
    fn key(&self, lo: [usize; 3], d: [usize; 3]) -> u64 {
        self.id(lo) as u64 * 8 + (d[0] + 2 * d[1] + 4 * d[2]) as u64
    }
}

impl Field<'_> {
    /// Where `chi - iso` changes sign on the edge from node `a` along `d`, as a
    /// fraction of the edge. The indicator is a smoothed step a few cells wide, far
    /// from linear across an edge, so linear interpolation of the two end values misses
    /// the crossing by up to a tenth of a cell; the cubic through the four nodes
    /// `a - d, a, a + d, a + 2d` on the edge's line (Lagrange) follows the step, and its
    /// root in the bracket is found by bisection. Linear where the line leaves the grid
    /// or the cubic does not change sign in the bracket.
    fn crossing(&self, a: [usize; 3], d: [usize; 3]) -> f64 {
        let at = |m: i64| -> Option<f64> {
            let c = [0, 1, 2].map(|k| a[k] as i64 + m * d[k] as i64);
            if c.iter().any(|&v| v < 0 || v >= self.n as i64) {
                return None;
            }
            let c = c.map(|v| v as usize);
            Some(f64::from(self.x[self.id(c)]) - f64::from(self.iso))
        };
        let (Some(p1), Some(p2)) = (at(0), at(1)) else {
            return 0.5;
        };
        let linear = if p1 == p2 { 0.5 } else { p1 / (p1 - p2) };
        let (Some(p0), Some(p3)) = (at(-1), at(2)) else {
            return linear;
        };
        // Lagrange cubic through t = -1, 0, 1, 2.
        let cubic = |t: f64| {
            -p0 * t * (t - 1.0) * (t - 2.0) / 6.0 + p1 * (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0
                - p2 * (t + 1.0) * t * (t - 2.0) / 2.0
                + p3 * (t + 1.0) * t * (t - 1.0) / 6.0
        };
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let flo = cubic(lo);
        if flo == 0.0 || (flo > 0.0) == (cubic(hi) > 0.0) {
            return linear;
        }
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if (cubic(mid) > 0.0) == (flo > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

/// Crossing edges of the nodes of one plane: sorted keys and vertex positions.
type PlaneVertices = (Vec<u64>, Vec<DVec3>);

fn plane_vertices(f: &Field, k: usize) -> PlaneVertices {
    let n = f.n;
    let (mut keys, mut pos) = (Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..n {
            let a = [i, j, k];
            let ina = f.inside(a);
            for code in 1..8usize {
                let d = [code & 1, (code >> 1) & 1, (code >> 2) & 1];
                let b = [i + d[0], j + d[1], k + d[2]];
                if b.iter().any(|&v| v >= n) || f.inside(b) == ina {
                    continue;
                }
                // Kept off the nodes so that no face collapses to a point.
                let t = f.crossing(a, d).clamp(1e-3, 1.0 - 1e-3);
                let p = DVec3::new(i as f64, j as f64, k as f64)
                    + t * DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64);
                keys.push(f.key(a, d));
                pos.push(f.origin + f.cell * p);
            }
        }
    }
    (keys, pos)
}

/// Orients triangle `t` (vertex ids, with the grid-space midpoints `m` of their edges)
/// so that its normal points along `out`.
fn oriented(t: [u32; 3], m: [DVec3; 3], out: DVec3) -> [u32; 3] {
    if (m[1] - m[0]).cross(m[2] - m[0]).dot(out) >= 0.0 {
        t
    } else {
        [t[0], t[2], t[1]]
    }
}

/// Triangles of one Kuhn tetrahedron with corners `c` (grid coordinates, monotone).
fn tetrahedron(
    f: &Field,
    c: [[usize; 3]; 4],
    lookup: &dyn Fn(u64) -> u32,
    faces: &mut Vec<[u32; 3]>,
) {
    let inside = c.map(|v| f.inside(v));
    let count = inside.iter().filter(|&&b| b).count();
    if count == 0 || count == 4 {
        return;
    }
    let g = |v: [usize; 3]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
    // Edge (u, v) of the tetrahedron: its vertex id and grid-space midpoint.
    let edge = |u: usize, v: usize| -> (u32, DVec3) {
        let (lo, hi) = if u < v { (c[u], c[v]) } else { (c[v], c[u]) };
        let d = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        (lookup(f.key(lo, d)), 0.5 * (g(lo) + g(hi)))
    };
    let ins: Vec<usize> = (0..4).filter(|&m| inside[m]).collect();
    let outs: Vec<usize> = (0..4).filter(|&m| !inside[m]).collect();
    let centre = |s: &[usize]| s.iter().map(|&m| g(c[m])).sum::<DVec3>() / s.len() as f64;
    let out = centre(&outs) - centre(&ins);
    if count == 2 {
        let (a, b, cc, d) = (ins[0], ins[1], outs[0], outs[1]);
        let q = [edge(a, cc), edge(a, d), edge(b, d), edge(b, cc)];
        for t in [[0, 1, 2], [0, 2, 3]] {
            faces.push(oriented(t.map(|m| q[m].0), t.map(|m| q[m].1), out));
        }
    } else {
        let (lone, rest) = if count == 1 {
            (ins[0], &outs)
        } else {
            (outs[0], &ins)
        };
        let e = [
            edge(lone, rest[0]),
            edge(lone, rest[1]),
            edge(lone, rest[2]),
        ];
        faces.push(oriented(e.map(|v| v.0), e.map(|v| v.1), out));
    }
}

/// The closed, oriented level set `{chi = iso}` of `f`.
pub(crate) fn marching_tetrahedra(f: &Field) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let n = f.n;
    let planes: Vec<PlaneVertices> = (0..n)
        .into_par_iter()
        .map(|k| plane_vertices(f, k))
        .collect();
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0usize);
    for p in &planes {
        offsets.push(offsets.last().copied().unwrap_or(0) + p.0.len());
    }
    let lookup = |key: u64| -> u32 {
        let k = (key / 8) as usize / (n * n);
        let at = planes[k].0.binary_search(&key).unwrap_or(0);
        (offsets[k] + at) as u32
    };
    let faces: Vec<[u32; 3]> = (0..n - 1)
        .into_par_iter()
        .map(|k| {
            let mut out = Vec::new();
            for j in 0..n - 1 {
                for i in 0..n - 1 {
                    let corner = |o: usize| [i + (o & 1), j + ((o >> 1) & 1), k + (o >> 2)];
                    let first = f.inside(corner(0));
                    if (1..8).all(|o| f.inside(corner(o)) == first) {
                        continue;
                    }
                    for path in PATHS {
                        let mut c = [[i, j, k]; 4];
                        for m in 1..4 {
                            c[m] = c[m - 1];
                            c[m][path[m - 1]] += 1;
                        }
                        tetrahedron(f, c, &lookup, &mut out);
                    }
                }
            }
            out
        })
        .collect::<Vec<Vec<[u32; 3]>>>()
        .concat();
    let vertices: Vec<DVec3> = planes.into_iter().flat_map(|p| p.1).collect();
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
