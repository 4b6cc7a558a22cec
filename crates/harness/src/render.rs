//! Software renders of reconstructions that show where they are wrong.
//!
//! A worker stores what a render needs ([`RenderData`]: the mesh in `f32`, the distance
//! to the true surface at every vertex and face centre, the boundary edges and the faces
//! that are self-intersecting or on a non-manifold edge) in a small binary file next to
//! the results ([`RenderData::save`]); the report reads every such file of a report,
//! picks one colour scale for all of them ([`Scale::robust`]) and draws one image per
//! configuration with the methods side by side ([`render_comparison`]), so the same
//! distance has the same colour in every panel and a reader sees what differs.
//!
//! Drawing: a small z-buffer rasteriser (orthographic, two-sided Lambert shading, no GPU,
//! deterministic) colours each pixel by the distance interpolated over the face (its
//! three vertices and its centre, see [`RenderData::face_values`]) on viridis, clamped at
//! the scale's top. Faces that intersect another face or sit on an edge shared by more
//! than two faces are filled with [`DEFECT_COLOUR`]; boundary edges are drawn on top in
//! [`BOUNDARY_COLOUR`] where they are not hidden by a nearer surface. Text (labels, the
//! colour bar's numbers) is drawn with plotters on the same pixels using the embedded
//! DejaVu font, so no system font is needed.

use std::path::Path;

use glam::DVec3;
use plotters::prelude::*;
use reconbench_geom::TriMesh;
use reconbench_geom::topology::MeshTopology;

use crate::error::{HarnessError, Result};

/// Face flag: the face intersects a face it is not adjacent to.
pub const FLAG_SELF_INTERSECTING: u8 = 1;
/// Face flag: one of the face's edges is shared by three or more faces.
pub const FLAG_NON_MANIFOLD: u8 = 2;

/// Colour of boundary edges (an edge of only one face): a hole or an open rim.
pub const BOUNDARY_COLOUR: [u8; 3] = [230, 0, 0];
/// Colour of self-intersecting and non-manifold faces (drawn flat, unshaded, so that it
/// is never confused with a shaded viridis colour).
pub const DEFECT_COLOUR: [u8; 3] = [255, 0, 255];
/// Colour of a face whose distance is unknown (data without ground truth).
pub const NO_VALUE_COLOUR: [u8; 3] = [190, 190, 190];

/// Everything a render of one reconstruction needs, as stored by the worker.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RenderData {
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles (indices into `vertices`).
    pub faces: Vec<[u32; 3]>,
    /// Distance to the true surface at each vertex, as a fraction of the bounding-box
    /// diagonal (NaN when unknown).
    pub vertex_values: Vec<f32>,
    /// Distance at each face's centroid (NaN when unknown). The vertices of an
    /// interpolating mesh are input points, so their distances are the input noise; a
    /// triangle that spans a concavity is far from the surface only inside, which the
    /// centre value shows.
    pub face_values: Vec<f32>,
    /// Per face, [`FLAG_SELF_INTERSECTING`] and [`FLAG_NON_MANIFOLD`] bits.
    pub face_flags: Vec<u8>,
    /// Edges with exactly one face.
    pub boundary_edges: Vec<[u32; 2]>,
}

/// Where the render data of the cell with `key` lives, relative to the results
/// directory (the path recorded in its row's `render`).
pub fn data_path(key: &str) -> String {
    format!("renders/{key}.rbr")
}

/// Copies the render data file `rel` of a results directory `from` into `to` (for
/// `merge`); nothing to do when both are the same directory. A missing source file is
/// reported as a warning, not an error: the report then shows that panel empty.
pub fn copy_data(from: &Path, to: &Path, rel: &str) -> Option<String> {
    let (src, dst) = (from.join(rel), to.join(rel));
    if src == dst || !rel.ends_with(".rbr") {
        return None;
    }
    if let (Ok(a), Ok(b)) = (src.canonicalize(), dst.canonicalize())
        && a == b
    {
        return None;
    }
    match std::fs::read(&src) {
        Ok(bytes) => crate::error::write_atomic(&dst, &bytes)
            .err()
            .map(|e| format!("render data not copied: {e}")),
        Err(e) => Some(format!("{}: render data not copied: {e}", src.display())),
    }
}

/// Magic bytes and version of the render data file.
const MAGIC: &[u8; 8] = b"RBRENDR1";

impl RenderData {
    /// Builds the render data of `mesh`: its topology (boundary and non-manifold edges)
    /// from geom's [`MeshTopology`] and its self-intersecting face pairs from
    /// [`reconbench_metrics::topology::self_intersecting_pairs`] (the counts in the
    /// result row come from the same code). `vertex_values` and `face_values` are the
    /// distances (fraction of the diagonal) at the vertices and face centroids; empty
    /// slices mean unknown.
    pub fn from_mesh(mesh: &TriMesh, vertex_values: &[f64], face_values: &[f64]) -> Result<Self> {
        let (nv, nf) = (mesh.n_vertices(), mesh.n_faces());
        let values = |v: &[f64], n: usize, what: &str| -> Result<Vec<f32>> {
            match v.len() {
                0 => Ok(vec![f32::NAN; n]),
                m if m == n => Ok(v.iter().map(|&x| x as f32).collect()),
                m => Err(HarnessError::failure(format!(
                    "render data: {m} {what} values for {n} {what}s"
                ))),
            }
        };
        let vertex_values = values(vertex_values, nv, "vertex")?;
        let face_values = values(face_values, nf, "face")?;
        let topo = MeshTopology::new(mesh);
        let mut face_flags = vec![0u8; nf];
        let mut boundary_edges = Vec::new();
        for e in 0..topo.n_edges() {
            match topo.edge_valence(e) {
                1 => boundary_edges.push(topo.edges()[e]),
                2 => {}
                _ => {
                    for &f in topo.edge_faces(e) {
                        face_flags[f as usize] |= FLAG_NON_MANIFOLD;
                    }
                }
            }
        }
        for (f, g) in reconbench_metrics::topology::self_intersecting_pairs(mesh) {
            face_flags[f as usize] |= FLAG_SELF_INTERSECTING;
            face_flags[g as usize] |= FLAG_SELF_INTERSECTING;
        }
        Ok(Self {
            vertices: mesh
                .vertices()
                .iter()
                .map(|v| v.as_vec3().to_array())
                .collect(),
            faces: mesh.faces().to_vec(),
            vertex_values,
            face_values,
            face_flags,
            boundary_edges,
        })
    }

    /// Faces flagged self-intersecting.
    pub fn self_intersecting_faces(&self) -> usize {
        self.face_flags
            .iter()
            .filter(|&&f| f & FLAG_SELF_INTERSECTING != 0)
            .count()
    }

    /// Faces flagged non-manifold.
    pub fn non_manifold_faces(&self) -> usize {
        self.face_flags
            .iter()
            .filter(|&&f| f & FLAG_NON_MANIFOLD != 0)
            .count()
    }

    /// The little-endian binary form: magic `RBRENDR1`, vertex, face and boundary-edge
    /// counts (`u32` each), then positions (`3 f32`), vertex values (`f32`), faces
    /// (`3 u32`), face values (`f32`), face flags (`u8`) and boundary edges (`2 u32`).
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let (nv, nf, nb) = (
            self.vertices.len(),
            self.faces.len(),
            self.boundary_edges.len(),
        );
        if self.vertex_values.len() != nv
            || self.face_values.len() != nf
            || self.face_flags.len() != nf
        {
            return Err(HarnessError::failure(
                "render data: value or flag counts differ from the vertex and face counts",
            ));
        }
        let count = |n: usize| {
            u32::try_from(n).map_err(|_| HarnessError::failure("render data: too large"))
        };
        let mut out = Vec::with_capacity(20 + nv * 16 + nf * 17 + nb * 8);
        out.extend_from_slice(MAGIC);
        for n in [nv, nf, nb] {
            out.extend_from_slice(&count(n)?.to_le_bytes());
        }
        for v in &self.vertices {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        for x in &self.vertex_values {
            out.extend_from_slice(&x.to_le_bytes());
        }
        for f in &self.faces {
            for i in f {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
        for x in &self.face_values {
            out.extend_from_slice(&x.to_le_bytes());
        }
        out.extend_from_slice(&self.face_flags);
        for e in &self.boundary_edges {
            for i in e {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
        Ok(out)
    }

    /// Parses [`to_bytes`](Self::to_bytes) output. A truncated or foreign file, or an
    /// index out of range, is an error naming what is wrong.
    pub fn from_bytes(b: &[u8]) -> Result<Self> {
        let bad = |m: String| HarnessError::input(format!("render data: {m}"));
        if b.len() < 20 || &b[..8] != MAGIC {
            return Err(bad("not a render data file (no RBRENDR1 header)".into()));
        }
        let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
        let (nv, nf, nb) = (u32_at(8) as u64, u32_at(12) as u64, u32_at(16) as u64);
        let want = 20 + nv * 16 + nf * 17 + nb * 8;
        if b.len() as u64 != want {
            return Err(bad(format!(
                "{} bytes, but {nv} vertices, {nf} faces and {nb} boundary edges need {want}",
                b.len()
            )));
        }
        let (nv, nf, nb) = (nv as usize, nf as usize, nb as usize);
        let mut o = 20;
        let mut f32s = |n: usize| {
            let v: Vec<f32> = (0..n)
                .map(|i| {
                    f32::from_le_bytes(b[o + 4 * i..o + 4 * i + 4].try_into().unwrap_or([0; 4]))
                })
                .collect();
            o += 4 * n;
            v
        };
        let pos = f32s(3 * nv);
        let vertex_values = f32s(nv);
        let idx: Vec<u32> = (0..3 * nf).map(|i| u32_at(o + 4 * i)).collect();
        o += 12 * nf;
        let face_values: Vec<f32> = (0..nf).map(|i| f32::from_bits(u32_at(o + 4 * i))).collect();
        o += 4 * nf;
        let face_flags = b[o..o + nf].to_vec();
        o += nf;
        let be: Vec<u32> = (0..2 * nb).map(|i| u32_at(o + 4 * i)).collect();
        if let Some(i) = idx.iter().chain(&be).find(|&&i| i as usize >= nv) {
            return Err(bad(format!(
                "vertex index {i} out of range ({nv} vertices)"
            )));
        }
        if let Some(f) = face_flags.iter().find(|&&f| f > 3) {
            return Err(bad(format!("unknown face flag {f}")));
        }
        Ok(Self {
            vertices: pos.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            faces: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            vertex_values,
            face_values,
            face_flags,
            boundary_edges: be.chunks_exact(2).map(|c| [c[0], c[1]]).collect(),
        })
    }

    /// Writes the binary form to `path` (atomically).
    pub fn save(&self, path: &Path) -> Result<()> {
        crate::error::write_atomic(path, &self.to_bytes()?)
    }

    /// Reads a file written by [`save`](Self::save).
    pub fn load(path: &Path) -> Result<Self> {
        let b = std::fs::read(path).map_err(|e| HarnessError::io(path, e))?;
        Self::from_bytes(&b).map_err(|e| HarnessError::input(format!("{}: {e}", path.display())))
    }

    /// The distances a colour scale should cover: the vertices some face uses and every
    /// face centre (finite values only).
    fn scale_values(&self) -> Vec<f32> {
        let mut used = vec![false; self.vertices.len()];
        for f in &self.faces {
            for &i in f {
                if let Some(u) = used.get_mut(i as usize) {
                    *u = true;
                }
            }
        }
        self.vertex_values
            .iter()
            .zip(&used)
            .filter(|(_, u)| **u)
            .map(|(v, _)| *v)
            .chain(self.face_values.iter().copied())
            .filter(|v| v.is_finite())
            .collect()
    }
}

/// The colour scale of a report's renders: `[0, max]`, ticks every `step`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// Top of the scale (distances above it get the top colour), fraction of the
    /// diagonal.
    pub max: f64,
    /// Distance between two ticks of the colour bar.
    pub step: f64,
    /// The 95th percentile the scale was rounded up from (None for a fixed scale).
    pub percentile_95: Option<f64>,
}

impl Scale {
    /// A fixed scale `[0, max]` (the experiment's `report.render_max`).
    pub fn fixed(max: f64) -> Self {
        let step = nice_step(max / 5.0);
        Self {
            max,
            step,
            percentile_95: None,
        }
    }

    /// The scale of a set of meshes: the 95th percentile of their distances pooled with
    /// every mesh weighted equally (a mesh with many triangles does not outvote one with
    /// few; vertex and face-centre distances of a mesh together), rounded up to a
    /// multiple of a 1, 2 or 5 x 10^k step with at most six steps. A percentile rather
    /// than the maximum, so that one broken mesh (or one stray triangle) does not push
    /// every other mesh into the bottom colour; what lies above saturates, and the
    /// panels' Hausdorff labels give the maxima. No finite distance at all gives a scale
    /// of 0.001.
    pub fn robust(meshes: &[&RenderData]) -> Self {
        let mut pooled: Vec<(f32, f64)> = Vec::new();
        for m in meshes {
            let v = m.scale_values();
            let w = 1.0 / v.len().max(1) as f64;
            pooled.extend(v.into_iter().map(|x| (x, w)));
        }
        pooled.sort_by(|a, b| a.0.total_cmp(&b.0));
        let total: f64 = pooled.iter().map(|p| p.1).sum();
        let mut acc = 0.0;
        let mut p95 = None;
        for (x, w) in &pooled {
            acc += w;
            if acc >= 0.95 * total {
                p95 = Some(f64::from(*x));
                break;
            }
        }
        let top = p95
            .filter(|&p| p > 0.0)
            .or_else(|| pooled.last().map(|p| f64::from(p.0)).filter(|&m| m > 0.0))
            .unwrap_or(1e-3);
        let mut step = nice_step(top / 6.0);
        while (top / step).ceil() > 6.0 {
            step = nice_step(step * 1.01);
        }
        Self {
            max: (top / step).ceil().max(1.0) * step,
            step,
            percentile_95: p95,
        }
    }

    /// The tick values `0, step, 2 step, ..` up to `max`.
    pub fn ticks(&self) -> Vec<f64> {
        let n = (self.max / self.step + 1e-9).floor() as usize;
        (0..=n).map(|i| i as f64 * self.step).collect()
    }

    /// A distance written with as many decimals as the scale's step needs.
    pub fn label(&self, v: f64) -> String {
        fmt_tick(v, self.step)
    }

    /// The (unshaded) colour of a distance.
    pub fn colour(&self, d: f64) -> [u8; 3] {
        if d.is_nan() {
            return NO_VALUE_COLOUR;
        }
        viridis(d / self.max).map(|c| c.round().clamp(0.0, 255.0) as u8)
    }
}

/// The smallest `1, 2, 5 x 10^k` that is `>= x` (for `x > 0`).
fn nice_step(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1e-3;
    }
    let e = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * e)
        .find(|&s| s >= x * (1.0 - 1e-12))
        .unwrap_or(10.0 * e)
}

/// An RGB image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGB bytes.
    pub rgb: Vec<u8>,
}

impl Image {
    /// A white image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            rgb: vec![255; (width as usize) * (height as usize) * 3],
        }
    }

    /// The colour at `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = ((y as usize) * (self.width as usize) + x as usize) * 3;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    fn put(&mut self, x: u32, y: u32, c: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = ((y as usize) * (self.width as usize) + x as usize) * 3;
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Encodes as PNG.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc
                .write_header()
                .map_err(|e| HarnessError::failure(format!("png: {e}")))?;
            w.write_image_data(&self.rgb)
                .map_err(|e| HarnessError::failure(format!("png: {e}")))?;
        }
        Ok(out)
    }

    /// Writes a PNG file.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        crate::error::write_atomic(path, &self.to_png()?)
    }
}

/// Viridis, 9 control points (matplotlib's table, sampled).
const VIRIDIS: [[f64; 3]; 9] = [
    [68.0, 1.0, 84.0],
    [71.0, 44.0, 122.0],
    [59.0, 81.0, 139.0],
    [44.0, 113.0, 142.0],
    [33.0, 144.0, 141.0],
    [39.0, 173.0, 129.0],
    [92.0, 200.0, 99.0],
    [170.0, 220.0, 50.0],
    [253.0, 231.0, 37.0],
];

/// Colour of `t` in `[0, 1]` (clamped) on the viridis map.
pub fn viridis(t: f64) -> [f64; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ]
}

/// The rows of the view rotation of a camera seen from azimuth `az_deg` (about the z
/// axis, 0 = from -y) and elevation `el_deg` (above the xy plane), with z up on the
/// screen: screen right, screen up, and the direction towards the camera (view depth:
/// larger is nearer).
fn rotation(az_deg: f64, el_deg: f64) -> [DVec3; 3] {
    let (sa, ca) = az_deg.to_radians().sin_cos();
    let (se, ce) = el_deg.to_radians().sin_cos();
    let towards = DVec3::new(sa * ce, -ca * ce, se);
    let right = DVec3::new(ca, sa, 0.0);
    let up = towards.cross(right);
    [right, up, towards]
}

/// The three viewpoints `(name, azimuth, elevation)` in degrees, z up (the axis of the
/// synthetic surfaces of revolution): from the front (-y) and a little to the right and
/// above, from the side (+x), and from above.
pub const VIEWS: [(&str, f64, f64); 3] = [
    ("front", 25.0, 20.0),
    ("side", 105.0, 20.0),
    ("top", 25.0, 80.0),
];

/// What every panel of one image is framed by: a centre and a radius, shared so that
/// the methods' meshes appear at one scale and position.
#[derive(Debug, Clone, Copy)]
struct Frame {
    centre: DVec3,
    radius: f64,
}

impl Frame {
    /// Centred on the bounding box of the vertices the faces of `meshes` use, with the
    /// radius of the smallest ball around that centre holding them all (so that no
    /// rotation leaves the view, and a round shape fills it).
    fn of(meshes: &[&RenderData]) -> Option<Self> {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for m in meshes {
            for f in &m.faces {
                for &i in f.iter().filter(|&&i| (i as usize) < m.vertices.len()) {
                    let v = pos(m, i as usize);
                    if v.is_finite() {
                        lo = lo.min(v);
                        hi = hi.max(v);
                    }
                }
            }
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let centre = (lo + hi) * 0.5;
        let mut r2: f64 = 0.0;
        for m in meshes {
            for f in &m.faces {
                for &i in f.iter().filter(|&&i| (i as usize) < m.vertices.len()) {
                    let v = pos(m, i as usize);
                    if v.is_finite() {
                        r2 = r2.max(v.distance_squared(centre));
                    }
                }
            }
        }
        Some(Self {
            centre,
            radius: r2.sqrt().max(1e-12),
        })
    }
}

fn pos(m: &RenderData, i: usize) -> DVec3 {
    let v = m.vertices[i];
    DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))
}

/// One view: its pixels and depth buffer (larger = nearer).
struct View {
    size: u32,
    rgb: Vec<[u8; 3]>,
    z: Vec<f64>,
}

impl View {
    fn put_marker(&mut self, x: f64, y: f64, z: f64, eps: f64, c: [u8; 3]) {
        let (cx, cy) = (x.floor() as i64, y.floor() as i64);
        for (dx, dy) in [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (px, py) = (cx + dx, cy + dy);
            if px < 0 || py < 0 || px >= self.size as i64 || py >= self.size as i64 {
                continue;
            }
            let i = (py as usize) * (self.size as usize) + px as usize;
            if z >= self.z[i] - eps {
                self.rgb[i] = c;
            }
        }
    }

    /// Draws the segment `a`-`b` (projected) where no nearer surface hides it.
    fn segment(&mut self, a: DVec3, b: DVec3, eps: f64, c: [u8; 3]) {
        let steps = ((b - a).truncate().length() * 2.0).ceil().clamp(1.0, 1e5) as usize;
        for s in 0..=steps {
            let p = a.lerp(b, s as f64 / steps as f64);
            self.put_marker(p.x, p.y, p.z, eps, c);
        }
    }
}

/// Rasterises one view of `data`.
fn rasterise(data: &RenderData, frame: Frame, rot: [DVec3; 3], size: u32, scale: &Scale) -> View {
    let n = (size as usize) * (size as usize);
    let mut view = View {
        size,
        rgb: vec![[255, 255, 255]; n],
        z: vec![f64::NEG_INFINITY; n],
    };
    let s = size as f64;
    let proj: Vec<DVec3> = (0..data.vertices.len())
        .map(|i| {
            let p = pos(data, i) - frame.centre;
            let q = DVec3::new(rot[0].dot(p), rot[1].dot(p), rot[2].dot(p));
            DVec3::new(
                (q.x / frame.radius * 0.47 + 0.5) * s,
                (0.5 - q.y / frame.radius * 0.47) * s,
                q.z,
            )
        })
        .collect();
    let light = DVec3::new(0.3, 0.4, 1.0).normalize();
    let nv = proj.len();
    let value = |i: usize| f64::from(data.vertex_values[i]);
    for (fi, f) in data.faces.iter().enumerate() {
        let [a, b, c] = f.map(|i| i as usize);
        if a >= nv || b >= nv || c >= nv {
            continue;
        }
        let (pa, pb, pc) = (proj[a], proj[b], proj[c]);
        if !(pa.is_finite() && pb.is_finite() && pc.is_finite()) {
            continue;
        }
        let n3 = (pos(data, b) - pos(data, a)).cross(pos(data, c) - pos(data, a));
        let nvw = DVec3::new(rot[0].dot(n3), rot[1].dot(n3), rot[2].dot(n3)).normalize_or_zero();
        let shade = 0.35 + 0.65 * nvw.dot(light).abs();
        let area = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x);
        if area.abs() < 1e-12 {
            continue;
        }
        let xmin = pa.x.min(pb.x).min(pc.x).floor().max(0.0) as i64;
        let xmax = (pa.x.max(pb.x).max(pc.x).ceil() as i64).min(size as i64 - 1);
        let ymin = pa.y.min(pb.y).min(pc.y).floor().max(0.0) as i64;
        let ymax = (pa.y.max(pb.y).max(pc.y).ceil() as i64).min(size as i64 - 1);
        let defect = data.face_flags.get(fi).copied().unwrap_or(0) != 0;
        let (va, vb, vc) = (value(a), value(b), value(c));
        let vf = data.face_values.get(fi).map_or(f64::NAN, |&x| f64::from(x));
        for y in ymin..=ymax {
            for x in xmin..=xmax {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let w0 = ((pb.x - px) * (pc.y - py) - (pb.y - py) * (pc.x - px)) / area;
                let w1 = ((pc.x - px) * (pa.y - py) - (pc.y - py) * (pa.x - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9 {
                    continue;
                }
                let z = w0 * pa.z + w1 * pb.z + w2 * pc.z;
                let zi = (y as usize) * (size as usize) + x as usize;
                if z <= view.z[zi] {
                    continue;
                }
                view.z[zi] = z;
                view.rgb[zi] = if defect {
                    DEFECT_COLOUR
                } else {
                    // Piecewise linear over the three sub-triangles the centre makes: the
                    // corners' values at the corners, the centre's at the centre.
                    let m = w0.min(w1).min(w2);
                    let v = if vf.is_finite() {
                        3.0 * m * vf + (w0 - m) * va + (w1 - m) * vb + (w2 - m) * vc
                    } else {
                        w0 * va + w1 * vb + w2 * vc
                    };
                    if v.is_nan() {
                        NO_VALUE_COLOUR.map(|ch| (f64::from(ch) * shade).round() as u8)
                    } else {
                        scale
                            .colour(v)
                            .map(|ch| (f64::from(ch) * shade).round().clamp(0.0, 255.0) as u8)
                    }
                };
            }
        }
    }
    let eps = 0.015 * frame.radius;
    // Outlines of defective faces first (so a defect of one pixel still shows), then
    // boundary edges on top.
    for (fi, f) in data.faces.iter().enumerate() {
        if data.face_flags.get(fi).copied().unwrap_or(0) == 0 || f.iter().any(|&i| i as usize >= nv)
        {
            continue;
        }
        let p = f.map(|i| proj[i as usize]);
        for k in 0..3 {
            view.segment(p[k], p[(k + 1) % 3], eps, DEFECT_COLOUR);
        }
    }
    for e in &data.boundary_edges {
        let (a, b) = (e[0] as usize, e[1] as usize);
        if a < nv && b < nv && proj[a].is_finite() && proj[b].is_finite() {
            view.segment(proj[a], proj[b], eps, BOUNDARY_COLOUR);
        }
    }
    view
}

/// One method's panel of a comparison image.
#[derive(Debug, Clone, Copy)]
pub struct Panel<'a> {
    /// Heading (the method label).
    pub title: &'a str,
    /// Lines under the heading (Hausdorff, defect counts).
    pub lines: &'a [String],
    /// The mesh; `None` draws the lines only (a failed cell, missing data).
    pub data: Option<&'a RenderData>,
}

/// Where a panel's views were drawn in a comparison image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PanelRect {
    /// Left edge of the views.
    pub x: u32,
    /// Top edge of the first view.
    pub y: u32,
    /// Side of each (square) view; the views are stacked, `front` at the top.
    pub size: u32,
}

/// A composed image and where each panel is.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// The image.
    pub image: Image,
    /// One entry per panel, in the order given.
    pub panels: Vec<PanelRect>,
}

const PAD: u32 = 8;
const TITLE_H: u32 = 26;
const LINE_H: u32 = 16;
const HEADER_LINES: u32 = 4;
const HEADER_H: u32 = HEADER_LINES * LINE_H + 6;
const LEGEND_W: u32 = 210;
const MIN_PANEL_W: u32 = 170;
/// At most this many panels in one row; more wrap into further rows.
const MAX_COLUMNS: usize = 8;

/// Draws `panels` side by side (wrapping after eight) under `title`, each as three views
/// stacked (front, side, top) under its heading lines, all on one colour `scale` and one
/// framing, with the colour bar and the defect colours explained on the right. `view` is
/// the side of each view in pixels.
pub fn render_comparison(
    title: &str,
    panels: &[Panel<'_>],
    scale: &Scale,
    view: u32,
) -> Result<Comparison> {
    if panels.is_empty() {
        return Err(HarnessError::failure("render: no panel to draw"));
    }
    if !(16..=4096).contains(&view) {
        return Err(HarnessError::input(format!(
            "render: view size {view} is outside 16..=4096"
        )));
    }
    crate::plots::register_fonts();
    let rows = panels.len().div_ceil(MAX_COLUMNS);
    let cols = panels.len().div_ceil(rows) as u32;
    let pw = view.max(MIN_PANEL_W);
    let band_h = HEADER_H + 3 * view + PAD;
    let bar_h = (3 * view * 3 / 5).clamp(100, 420);
    let legend_h = 2 * LINE_H + bar_h + 10 + 4 * LINE_H + 8;
    let width = PAD + cols * (pw + PAD) + LEGEND_W;
    let height = (TITLE_H + rows as u32 * band_h).max(TITLE_H + legend_h) + PAD;
    if u64::from(width) * u64::from(height) > 100_000_000 {
        return Err(HarnessError::input(format!(
            "render: an image of {width} x {height} pixels ({} panels of {view} pixels) is too large; lower report.render_size",
            panels.len()
        )));
    }
    let mut img = Image::new(width, height);
    let datas: Vec<&RenderData> = panels.iter().filter_map(|p| p.data).collect();
    let frame = Frame::of(&datas);
    let mut rects = Vec::new();
    for (i, p) in panels.iter().enumerate() {
        let (r, c) = ((i as u32) / cols, (i as u32) % cols);
        let x = PAD + c * (pw + PAD) + (pw - view) / 2;
        let y = TITLE_H + r * band_h + HEADER_H;
        rects.push(PanelRect { x, y, size: view });
        let (Some(d), Some(frame)) = (p.data, frame) else {
            continue;
        };
        for (k, (_, az, el)) in VIEWS.into_iter().enumerate() {
            let v = rasterise(d, frame, rotation(az, el), view, scale);
            let y0 = y + k as u32 * view;
            for (j, c) in v.rgb.iter().enumerate() {
                img.put(x + (j as u32 % view), y0 + j as u32 / view, *c);
            }
        }
    }
    // Colour bar pixels.
    let lx = PAD + cols * (pw + PAD) + 4;
    let bar_top = TITLE_H + 2 * LINE_H + 6;
    let bar_x = lx + 4;
    for y in 0..bar_h {
        let t = 1.0 - f64::from(y) / f64::from(bar_h - 1);
        let c = scale.colour(t * scale.max);
        for x in bar_x..bar_x + 18 {
            img.put(x, bar_top + y, c);
        }
    }
    let sw_y = bar_top + bar_h + 14;
    for y in 0..10 {
        for x in 0..18 {
            // A boundary-edge sample: a thick line; a defect sample: a filled box.
            if (4..7).contains(&y) {
                img.put(bar_x + x, sw_y + y, BOUNDARY_COLOUR);
            }
            img.put(bar_x + x, sw_y + 2 * LINE_H + y, DEFECT_COLOUR);
        }
    }
    let root = BitMapBackend::with_buffer(&mut img.rgb, (width, height)).into_drawing_area();
    let text_err = |e: DrawingAreaErrorKind<_>| HarnessError::failure(format!("render text: {e}"));
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    let bold = ("sans-serif", 13)
        .into_font()
        .style(FontStyle::Bold)
        .color(&BLACK);
    let grey = ("sans-serif", 12).into_font().color(&RGBColor(90, 90, 90));
    let big = ("sans-serif", 16)
        .into_font()
        .style(FontStyle::Bold)
        .color(&BLACK);
    let fit = |text: &str, style: &TextStyle, w: u32| -> String {
        let width_of = |t: &str| root.estimate_text_size(t, style).map_or(0, |s| s.0);
        if width_of(text) <= w {
            return text.to_string();
        }
        let chars: Vec<char> = text.chars().collect();
        for n in (1..chars.len()).rev() {
            let t: String = chars[..n].iter().collect::<String>() + "…";
            if width_of(&t) <= w {
                return t;
            }
        }
        "…".into()
    };
    let draw = |t: &str, x: u32, y: u32, style: &TextStyle| {
        root.draw(&Text::new(
            t.to_string(),
            (x as i32, y as i32),
            style.clone(),
        ))
        .map_err(text_err)
    };
    draw(&fit(title, &big, width - 2 * PAD), PAD, 5, &big)?;
    for (i, p) in panels.iter().enumerate() {
        let (r, c) = ((i as u32) / cols, (i as u32) % cols);
        let x = PAD + c * (pw + PAD);
        let y = TITLE_H + r * band_h;
        draw(&fit(p.title, &bold, pw), x, y, &bold)?;
        for (k, line) in p.lines.iter().take(HEADER_LINES as usize - 1).enumerate() {
            draw(&fit(line, &font, pw), x, y + (k as u32 + 1) * LINE_H, &font)?;
        }
        if p.data.is_none() {
            draw("no mesh to render", x, y + HEADER_H + view / 2, &grey)?;
        }
        if c == 0 {
            for (k, (name, _, _)) in VIEWS.into_iter().enumerate() {
                let vx = rects[i].x.saturating_sub(2).max(x);
                draw(name, vx, rects[i].y + k as u32 * view + 2, &grey)?;
            }
        }
    }
    draw("distance to the surface", lx, TITLE_H, &font)?;
    draw("(fraction of bbox diagonal)", lx, TITLE_H + LINE_H, &grey)?;
    for t in scale.ticks() {
        let y = bar_top + ((1.0 - t / scale.max) * f64::from(bar_h - 1)).round() as u32;
        let label = if (t - scale.max).abs() <= 1e-9 * scale.max {
            format!("≥ {}", fmt_tick(t, scale.step))
        } else {
            fmt_tick(t, scale.step)
        };
        root.draw(&PathElement::new(
            vec![
                ((bar_x + 18) as i32, y as i32),
                ((bar_x + 23) as i32, y as i32),
            ],
            BLACK,
        ))
        .map_err(text_err)?;
        draw(&label, bar_x + 27, y.saturating_sub(7), &font)?;
    }
    draw("boundary edge", bar_x + 24, sw_y - 2, &font)?;
    draw("(hole or open rim)", bar_x + 24, sw_y + LINE_H - 4, &grey)?;
    draw(
        "self-intersecting or",
        bar_x + 24,
        sw_y + 2 * LINE_H - 2,
        &font,
    )?;
    draw(
        "non-manifold face",
        bar_x + 24,
        sw_y + 3 * LINE_H - 4,
        &font,
    )?;
    root.present().map_err(text_err)?;
    drop(root);
    Ok(Comparison {
        image: img,
        panels: rects,
    })
}

/// A tick label with as many decimals as the step needs.
fn fmt_tick(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if step >= 1e-4 {
        let decimals = (-step.log10().floor()).max(0.0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.1e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps_and_ticks() {
        assert_eq!(nice_step(0.0007), 0.001);
        assert_eq!(nice_step(0.0013), 0.002);
        assert_eq!(nice_step(0.003), 0.005);
        assert_eq!(nice_step(0.006), 0.01);
        let s = Scale::fixed(0.01);
        assert_eq!(s.ticks().len(), 6);
        assert_eq!(fmt_tick(0.004, 0.002), "0.004");
        assert_eq!(fmt_tick(0.0025, 0.0005), "0.0025");
    }

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), [68.0, 1.0, 84.0]);
        assert_eq!(viridis(2.0), [253.0, 231.0, 37.0]);
    }

    #[test]
    fn bytes_round_trip_and_bad_files_are_errors() {
        let d = RenderData {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            faces: vec![[0, 1, 2]],
            vertex_values: vec![0.0, 0.5, f32::NAN],
            face_values: vec![0.25],
            face_flags: vec![FLAG_SELF_INTERSECTING],
            boundary_edges: vec![[0, 1], [1, 2], [0, 2]],
        };
        let b = d.to_bytes().unwrap();
        let back = RenderData::from_bytes(&b).unwrap();
        assert_eq!(back.faces, d.faces);
        assert_eq!(back.boundary_edges, d.boundary_edges);
        assert!(back.vertex_values[2].is_nan());
        assert_eq!(back.face_flags, d.face_flags);
        assert!(RenderData::from_bytes(&b[..b.len() - 1]).is_err());
        assert!(RenderData::from_bytes(b"PNG....").is_err());
        let mut bad = b.clone();
        // The first face index (after the 20-byte header, 36 bytes of positions and
        // 12 of vertex values) pointing past the vertices.
        bad[68] = 9;
        let e = RenderData::from_bytes(&bad).unwrap_err().to_string();
        assert!(e.contains("out of range"), "{e}");
    }
}
