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

use super::params::VertexFit;

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
    /// How a vertex is placed on its grid edge.
    pub fit: VertexFit,
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
    /// the crossing by up to a tenth of a cell. The root is taken on the tricubic
    /// (Lagrange) interpolant of the 4x4x4 nodes around the cell holding the edge,
    /// restricted to the edge, by bisection: on an axis edge that is the cubic through
    /// the four nodes on the edge's line; on a face or body diagonal of a Kuhn
    /// tetrahedron it still uses nodes one cell apart, where a cubic through the nodes
    /// on the diagonal's own line (`sqrt 2` or `sqrt 3` cells apart) misses a step a few
    /// cells wide by several times more (`docs/methods/poisson.md`, Figures). Linear
    /// where the stencil leaves the grid.
    fn crossing(&self, a: [usize; 3], d: [usize; 3]) -> f64 {
        let val = |c: [usize; 3]| f64::from(self.x[self.id(c)]) - f64::from(self.iso);
        let p1 = val(a);
        let p2 = val([a[0] + d[0], a[1] + d[1], a[2] + d[2]]);
        let linear = if p1 == p2 { 0.5 } else { p1 / (p1 - p2) };
        if p1 == 0.0 || (p1 > 0.0) == (p2 > 0.0) {
            return linear;
        }
        let axes: Vec<usize> = (0..3).filter(|&k| d[k] == 1).collect();
        if axes.iter().any(|&k| a[k] < 1 || a[k] + 2 >= self.n) {
            return linear;
        }
        // IMPL-CHOICE (vertex placement, `vertex_fit`): tricubic by default; the cubic
        // on the edge's own line (the behaviour before) and the linear fit are kept.
        match self.fit {
            VertexFit::Linear => return linear,
            VertexFit::EdgeCubic => {
                let on_line =
                    |m: i64| val([0, 1, 2].map(|k| (a[k] as i64 + m * d[k] as i64) as usize));
                let (p0, p3) = (on_line(-1), on_line(2));
                let f = |t: f64| {
                    let l = lagrange(t);
                    l[0] * p0 + l[1] * p1 + l[2] * p2 + l[3] * p3
                };
                return bisect(&f, p1);
            }
            VertexFit::Tricubic => {}
        }
        // The 4^m stencil values (m varying axes), first varying axis fastest.
        let m = axes.len();
        let mut vals = [0f64; 64];
        for (s, v) in vals.iter_mut().enumerate().take(1 << (2 * m)) {
            let mut c = a;
            for (q, &k) in axes.iter().enumerate() {
                c[k] = a[k] + ((s >> (2 * q)) & 3) - 1;
            }
            *v = val(c);
        }
        let f = |t: f64| {
            let l = lagrange(t);
            let mut acc = [0f64; 16];
            let rows = 1 << (2 * (m - 1));
            for (r, out) in acc.iter_mut().enumerate().take(rows) {
                let v = &vals[4 * r..4 * r + 4];
                *out = l[0] * v[0] + l[1] * v[1] + l[2] * v[2] + l[3] * v[3];
            }
            match m {
                1 => acc[0],
                2 => l[0] * acc[0] + l[1] * acc[1] + l[2] * acc[2] + l[3] * acc[3],
                _ => {
                    let mut s = 0.0;
                    for (z, lz) in l.iter().enumerate() {
                        let b = &acc[4 * z..4 * z + 4];
                        s += lz * (l[0] * b[0] + l[1] * b[1] + l[2] * b[2] + l[3] * b[3]);
                    }
                    s
                }
            }
        };
        bisect(&f, p1)
    }
}

/// The cubic Lagrange basis on the nodes `-1, 0, 1, 2` at `t`.
#[inline]
fn lagrange(t: f64) -> [f64; 4] {
    [
        -t * (t - 1.0) * (t - 2.0) / 6.0,
        (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
        -(t + 1.0) * t * (t - 2.0) / 2.0,
        (t + 1.0) * t * (t - 1.0) / 6.0,
    ]
}

/// A root of `f` in `[0, 1]` by bisection, `f(0) = f0` and `f(1)` of opposite signs.
fn bisect(f: &dyn Fn(f64) -> f64, f0: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if (f(mid) > 0.0) == (f0 > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
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
