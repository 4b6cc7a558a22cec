//! Software renders: a mesh coloured by per-vertex error, from three viewpoints, with a
//! fixed colour scale (viridis, clamped at `max`) and a legend bar. A small z-buffer
//! rasteriser (orthographic, Gouraud-interpolated error, two-sided Lambert shading); no
//! GPU, deterministic. Text is drawn with plotters on top of the pixel buffer using the
//! embedded DejaVu font.

use std::path::Path;

use glam::DVec3;
use plotters::prelude::*;

use crate::error::{HarnessError, Result};

/// What to render: a triangle mesh with one error value per vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderData {
    /// Vertex positions.
    pub vertices: Vec<DVec3>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
    /// One error value per vertex (same unit as the scale's `max`).
    pub values: Vec<f64>,
    /// Legend title, e.g. `distance to surface / diag`.
    pub title: String,
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
            rgb: vec![255; (width * height * 3) as usize],
        }
    }

    fn put(&mut self, x: u32, y: u32, c: [u8; 3]) {
        let i = ((y * self.width + x) * 3) as usize;
        self.rgb[i..i + 3].copy_from_slice(&c);
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

fn rotation(az_deg: f64, el_deg: f64) -> [DVec3; 3] {
    let (sa, ca) = az_deg.to_radians().sin_cos();
    let (se, ce) = el_deg.to_radians().sin_cos();
    // Rows of Rx(el) * Ry(az).
    let ry = [DVec3::new(ca, 0.0, sa), DVec3::Y, DVec3::new(-sa, 0.0, ca)];
    let rx = [DVec3::X, DVec3::new(0.0, ce, -se), DVec3::new(0.0, se, ce)];
    let col = |j: usize| DVec3::new(ry[0][j], ry[1][j], ry[2][j]);
    [
        DVec3::new(rx[0].dot(col(0)), rx[0].dot(col(1)), rx[0].dot(col(2))),
        DVec3::new(rx[1].dot(col(0)), rx[1].dot(col(1)), rx[1].dot(col(2))),
        DVec3::new(rx[2].dot(col(0)), rx[2].dot(col(1)), rx[2].dot(col(2))),
    ]
}

/// Rasterises one view into `img` at horizontal offset `x0` (a `size` x `size` square).
fn rasterise(img: &mut Image, x0: u32, size: u32, data: &RenderData, rot: [DVec3; 3], max: f64) {
    let (lo, hi) = data.vertices.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return;
    }
    let c = (lo + hi) * 0.5;
    let r = ((hi - lo).length() * 0.5).max(1e-12);
    let s = size as f64;
    let proj: Vec<DVec3> = data
        .vertices
        .iter()
        .map(|&v| {
            let p = v - c;
            let q = DVec3::new(rot[0].dot(p), rot[1].dot(p), rot[2].dot(p));
            DVec3::new((q.x / r * 0.47 + 0.5) * s, (0.5 - q.y / r * 0.47) * s, q.z)
        })
        .collect();
    let light = DVec3::new(0.3, 0.4, 1.0).normalize();
    let mut zbuf = vec![f64::NEG_INFINITY; (size * size) as usize];
    for f in &data.faces {
        let [a, b, cc] = f.map(|i| i as usize);
        if a >= proj.len() || b >= proj.len() || cc >= proj.len() {
            continue;
        }
        let (pa, pb, pc) = (proj[a], proj[b], proj[cc]);
        // Shading from the face normal in view space (two-sided).
        let n3 = (data.vertices[b] - data.vertices[a]).cross(data.vertices[cc] - data.vertices[a]);
        let nv = DVec3::new(rot[0].dot(n3), rot[1].dot(n3), rot[2].dot(n3)).normalize_or_zero();
        let shade = 0.35 + 0.65 * nv.dot(light).abs();
        let area = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x);
        if area.abs() < 1e-12 {
            continue;
        }
        let xmin = pa.x.min(pb.x).min(pc.x).floor().max(0.0) as u32;
        let xmax = (pa.x.max(pb.x).max(pc.x).ceil() as i64).min(size as i64 - 1);
        let ymin = pa.y.min(pb.y).min(pc.y).floor().max(0.0) as u32;
        let ymax = (pa.y.max(pb.y).max(pc.y).ceil() as i64).min(size as i64 - 1);
        if xmax < 0 || ymax < 0 {
            continue;
        }
        let (va, vb, vc) = (data.values[a], data.values[b], data.values[cc]);
        for y in ymin..=ymax as u32 {
            for x in xmin..=xmax as u32 {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let w0 = ((pb.x - px) * (pc.y - py) - (pb.y - py) * (pc.x - px)) / area;
                let w1 = ((pc.x - px) * (pa.y - py) - (pc.y - py) * (pa.x - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9 {
                    continue;
                }
                let z = w0 * pa.z + w1 * pb.z + w2 * pc.z;
                let zi = (y * size + x) as usize;
                if z <= zbuf[zi] {
                    continue;
                }
                zbuf[zi] = z;
                let v = w0 * va + w1 * vb + w2 * vc;
                let col = viridis(v / max);
                img.put(
                    x0 + x,
                    y,
                    col.map(|ch| (ch * shade).round().clamp(0.0, 255.0) as u8),
                );
            }
        }
    }
}

/// Width of the legend panel.
const LEGEND_W: u32 = 150;

/// The three viewpoints `(name, azimuth, elevation)` in degrees.
pub const VIEWS: [(&str, f64, f64); 3] = [
    ("front", 20.0, 20.0),
    ("side", 110.0, 20.0),
    ("top", 20.0, 80.0),
];

/// Renders `data` from the three [`VIEWS`]
/// side by side, `size` pixels high each, with a legend for the scale `[0, max]`.
pub fn render_error_views(data: &RenderData, max: f64, size: u32) -> Result<Image> {
    if data.values.len() != data.vertices.len() {
        return Err(HarnessError::failure(format!(
            "render: {} values for {} vertices",
            data.values.len(),
            data.vertices.len()
        )));
    }
    crate::plots::register_fonts();
    let width = 3 * size + LEGEND_W;
    let mut img = Image::new(width, size);
    for (i, (_, az, el)) in VIEWS.into_iter().enumerate() {
        rasterise(&mut img, i as u32 * size, size, data, rotation(az, el), max);
    }
    // Legend bar pixels.
    let (bx, by0, by1) = (3 * size + 16, size / 8, size - size / 8);
    for y in by0..by1 {
        let t = 1.0 - (y - by0) as f64 / (by1 - by0).max(1) as f64;
        let c = viridis(t).map(|ch| ch.round() as u8);
        for x in bx..bx + 18 {
            img.put(x, y, c);
        }
    }
    // Text with plotters on the same buffer.
    {
        let root = BitMapBackend::with_buffer(&mut img.rgb, (width, size)).into_drawing_area();
        let font = ("sans-serif", 13).into_font().color(&BLACK);
        let draw = |text: String, x: u32, y: u32| {
            root.draw(&Text::new(text, (x as i32, y as i32), font.clone()))
                .map_err(|e| HarnessError::failure(format!("render text: {e}")))
        };
        draw(
            format!(">= {}", fmt_tick(max)),
            bx + 22,
            by0.saturating_sub(6),
        )?;
        draw(fmt_tick(max / 2.0), bx + 22, (by0 + by1) / 2 - 6)?;
        draw("0".into(), bx + 22, by1 - 8)?;
        draw(data.title.clone(), 3 * size + 4, 2)?;
        for (i, (name, _, _)) in VIEWS.into_iter().enumerate() {
            draw(name.to_string(), i as u32 * size + 4, 2)?;
        }
        root.present()
            .map_err(|e| HarnessError::failure(format!("render text: {e}")))?;
    }
    Ok(img)
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if (1e-3..1e3).contains(&v.abs()) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> RenderData {
        let vertices = vec![
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-1.0, -1.0, 1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(1.0, -1.0, -1.0),
        ];
        RenderData {
            values: vec![0.0, 0.005, 0.01, 0.02],
            vertices,
            faces: vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
            title: "error / diag".into(),
        }
    }

    #[test]
    fn render_has_requested_size_and_colours() {
        let img = render_error_views(&tetra(), 0.01, 64).unwrap();
        assert_eq!((img.width, img.height), (3 * 64 + LEGEND_W, 64));
        // Some pixels are not white: the mesh was drawn in each view.
        for v in 0..3 {
            let drawn = (0..64u32)
                .flat_map(|y| (0..64u32).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let i = ((y * img.width + v * 64 + x) * 3) as usize;
                    img.rgb[i..i + 3] != [255, 255, 255]
                })
                .count();
            assert!(drawn > 100, "view {v}: {drawn}");
        }
        let png = img.to_png().unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        assert_eq!(
            (dec.info().width, dec.info().height),
            (img.width, img.height)
        );
    }

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), [68.0, 1.0, 84.0]);
        assert_eq!(viridis(2.0), [253.0, 231.0, 37.0]);
    }
}
