//! Plots with plotters, as PNG and SVG, with the DejaVu font embedded (no system font
//! is needed; [`register_fonts`] registers it under `sans-serif`).
//!
//! * metric vs perturbation level: one line per method, a band for mean ± std over seeds;
//! * log-log time vs input size with the fitted slope of each method;
//! * box plots of per-point errors (box = quartiles, whiskers = min and 95th percentile,
//!   averaged over seeds), drawn horizontally with one labelled row per box.
//!
//! A method has one colour everywhere ([`method_colour`]), legends sit in a panel right
//! of the data, every tick label of an axis has one format ([`tick_format`]) and bands of
//! a non-negative metric stop at 0.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{HarnessError, Result};
use crate::store::Dist;

/// Registers the embedded DejaVu Sans as `sans-serif` (idempotent).
pub fn register_fonts() {
    static DONE: OnceLock<()> = OnceLock::new();
    DONE.get_or_init(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold());
    });
}

/// A fixed qualitative palette (Tableau 10, the dark half of Tableau 20b, then the
/// light half of Tableau 20): a method keeps its colour in every plot and every report,
/// see [`method_colour`].
const PALETTE: [RGBColor; 30] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(57, 59, 121),
    RGBColor(99, 121, 57),
    RGBColor(140, 109, 49),
    RGBColor(132, 60, 57),
    RGBColor(123, 65, 115),
    RGBColor(82, 84, 163),
    RGBColor(140, 162, 82),
    RGBColor(189, 158, 57),
    RGBColor(173, 73, 74),
    RGBColor(165, 81, 148),
    RGBColor(174, 199, 232),
    RGBColor(255, 187, 120),
    RGBColor(152, 223, 138),
    RGBColor(255, 152, 150),
    RGBColor(197, 176, 213),
    RGBColor(196, 156, 148),
    RGBColor(247, 182, 210),
    RGBColor(199, 199, 199),
    RGBColor(219, 219, 141),
    RGBColor(158, 218, 229),
];

/// The colour of a method label. A registered method's name gets the palette slot of its
/// place in the registry, so no two registered methods share a colour; any other label
/// (a pipeline, a custom label) an FNV-1a hash into the palette. Either way it depends
/// on the label alone, not on which other methods a report holds or their order.
pub fn method_colour(label: &str) -> RGBColor {
    let visible = crate::registry::registry().iter().filter(|e| !e.hidden);
    if let Some(i) = visible.map(|e| e.name).position(|n| n == label) {
        return PALETTE[i % PALETTE.len()];
    }
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in label.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    PALETTE[(h % PALETTE.len() as u64) as usize]
}

/// One line of a [`LinePlot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// The label its colour comes from (the method label, also for a series whose name
    /// adds the other swept keys), see [`method_colour`].
    pub colour_key: String,
    /// `(x, y, y_low, y_high)`; the band spans `y_low..y_high`.
    pub points: Vec<(f64, f64, f64, f64)>,
}

/// A line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Title.
    pub title: String,
    /// X axis label (with its unit).
    pub x_label: String,
    /// Y axis label (with its unit).
    pub y_label: String,
    /// Lines.
    pub series: Vec<Series>,
    /// Log-log axes.
    pub log: bool,
    /// The metric cannot be negative: bands are clipped at 0 and the axis starts at 0.
    pub non_negative: bool,
}

/// One box of a [`BoxPlot`].
#[derive(Debug, Clone, PartialEq)]
pub struct BoxEntry {
    /// Category label, written beside the box.
    pub label: String,
    /// The label its colour comes from (the method label), see [`method_colour`].
    pub colour_key: String,
    /// Distribution.
    pub dist: Dist,
}

/// A box plot, drawn horizontally: one row per box with its label on the left, so that
/// any number of labels of any length stay legible (the plot grows in height).
#[derive(Debug, Clone, PartialEq)]
pub struct BoxPlot {
    /// Title.
    pub title: String,
    /// Value axis label (with its unit).
    pub y_label: String,
    /// Boxes, top to bottom.
    pub boxes: Vec<BoxEntry>,
}

/// Font size of tick and legend labels, in pixels.
pub const LABEL_FONT: u32 = 13;
/// Ticks per axis (about): few enough that labels of 6 digits do not collide.
pub const TICKS: usize = 6;
/// Height in pixels of one box row of a [`BoxPlot`].
pub const BOX_ROW: u32 = 24;

fn err(e: impl std::fmt::Display) -> HarnessError {
    HarnessError::failure(format!("plot: {e}"))
}

/// Least-squares slope of `log10 y` against `log10 x` (positive values only).
pub fn loglog_slope(points: &[(f64, f64)]) -> Option<f64> {
    let v: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.log10(), y.log10()))
        .collect();
    if v.len() < 2 {
        return None;
    }
    let n = v.len() as f64;
    let mx = v.iter().map(|p| p.0).sum::<f64>() / n;
    let my = v.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = v.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = v.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

fn padded(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let lo = if lo > 0.0 { lo } else { 1e-9 };
        let hi = if hi > lo { hi } else { lo * 10.0 };
        (lo / 1.5, hi * 1.5)
    } else {
        let span = hi - lo;
        if !(span.is_finite()) || span <= 0.0 {
            let d = if lo.abs() > 0.0 { lo.abs() * 0.1 } else { 1.0 };
            (lo - d, hi + d)
        } else {
            (lo - 0.08 * span, hi + 0.08 * span)
        }
    }
}

/// The tick format of a linear axis over `lo..hi`: one format for every tick, fixed
/// decimals from the tick step (about [`TICKS`] ticks), or scientific with two digits when
/// the values are too small or large for that to stay short.
pub fn tick_format(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let big = lo.abs().max(hi.abs());
    let step = ((hi - lo) / TICKS as f64).abs();
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).max(0.0) as usize
    } else {
        2
    };
    let scientific = !(1e-3..1e5).contains(&big) && big != 0.0 || decimals > 5;
    move |v: &f64| {
        if scientific {
            format!("{v:.1e}")
        } else {
            // Rounding can leave "-0.000".
            let s = format!("{v:.decimals$}");
            if s.trim_start_matches('-')
                .chars()
                .all(|c| c == '0' || c == '.')
            {
                s.trim_start_matches('-').to_string()
            } else {
                s
            }
        }
    }
}

/// The tick format of a log axis: the value with two significant digits (`1.0e3`).
fn log_tick(v: &f64) -> String {
    format!("{v:.1e}")
}

/// Width in pixels of `text` at `font` pixels: an upper bound for DejaVu Sans (whose
/// widest common glyphs are about 0.62 em).
pub fn text_width(text: &str, font: u32) -> u32 {
    (text.chars().count() as f64 * font as f64 * 0.62).ceil() as u32
}

/// Width of the legend panel right of the data: the longest entry plus the swatch.
fn legend_width(names: &[&str]) -> u32 {
    names
        .iter()
        .map(|n| text_width(n, LABEL_FONT))
        .max()
        .unwrap_or(0)
        + 48
}

/// Draws the legend in its own panel (never over the data).
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBColor)],
    top: i32,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (w, _) = area.dim_in_pixel();
    let h = entries.len() as i32 * 20 + 10;
    area.draw(&Rectangle::new(
        [(4, top), (w as i32 - 4, top + h)],
        BLACK.stroke_width(1),
    ))
    .map_err(err)?;
    for (i, (name, c)) in entries.iter().enumerate() {
        let y = top + 15 + 20 * i as i32;
        area.draw(&PathElement::new(vec![(12, y), (32, y)], c.stroke_width(3)))
            .map_err(err)?;
        area.draw(&Text::new(
            name.clone(),
            (38, y - LABEL_FONT as i32 / 2 - 1),
            ("sans-serif", LABEL_FONT).into_font(),
        ))
        .map_err(err)?;
    }
    Ok(())
}

/// The y range of a line plot: the data and bands, padded; from 0 for a non-negative
/// metric (no padding below 0).
fn line_y_range(p: &LinePlot, all: &[&(f64, f64, f64, f64)]) -> (f64, f64) {
    let low = |q: &(f64, f64, f64, f64)| {
        let l = q.2.min(q.1);
        if p.non_negative { l.max(0.0) } else { l }
    };
    let y0 = all.iter().map(|q| low(q)).fold(f64::INFINITY, f64::min);
    let y1 = all
        .iter()
        .map(|q| q.3.max(q.1))
        .fold(f64::NEG_INFINITY, f64::max);
    let (a, b) = padded(y0, y1, p.log);
    if p.non_negative && !p.log {
        (a.max(0.0).min(y0), b)
    } else {
        (a, b)
    }
}

fn draw_lines<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &LinePlot) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let all: Vec<&(f64, f64, f64, f64)> = p.series.iter().flat_map(|s| &s.points).collect();
    let xs = all.iter().map(|q| q.0);
    let x0 = xs.clone().fold(f64::INFINITY, f64::min);
    let x1 = xs.fold(f64::NEG_INFINITY, f64::max);
    if all.is_empty() || !x0.is_finite() {
        root.draw(&Text::new(
            "no data",
            (20, 20),
            ("sans-serif", 16).into_font(),
        ))
        .map_err(err)?;
        return root.present().map_err(err);
    }
    let (x0, x1) = padded(x0, x1, p.log);
    let (y0, y1) = line_y_range(p, &all);
    let names: Vec<&str> = p.series.iter().map(|s| s.name.as_str()).collect();
    let (w, _) = root.dim_in_pixel();
    let lw = legend_width(&names).min(w / 2);
    let (left, right) = root.split_horizontally(w - lw);
    let mut builder = ChartBuilder::on(&left);
    builder
        .caption(&p.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(80);
    let xf = tick_format(x0, x1);
    let yf = tick_format(y0, y1);
    macro_rules! body {
        ($chart:ident, $xf:expr, $yf:expr) => {{
            $chart
                .configure_mesh()
                .x_desc(p.x_label.as_str())
                .y_desc(p.y_label.as_str())
                .x_labels(TICKS)
                .y_labels(TICKS)
                .x_label_formatter($xf)
                .y_label_formatter($yf)
                .label_style(("sans-serif", LABEL_FONT))
                .axis_desc_style(("sans-serif", 15))
                .draw()
                .map_err(err)?;
            for s in &p.series {
                let color = method_colour(&s.colour_key);
                let mut pts = s.points.clone();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                if p.non_negative {
                    for q in &mut pts {
                        q.2 = q.2.max(0.0);
                    }
                }
                if pts.iter().any(|q| q.3 > q.2) {
                    let mut poly: Vec<(f64, f64)> = pts.iter().map(|q| (q.0, q.3)).collect();
                    poly.extend(pts.iter().rev().map(|q| (q.0, q.2)));
                    $chart
                        .draw_series(std::iter::once(Polygon::new(
                            poly,
                            color.mix(0.18).filled(),
                        )))
                        .map_err(err)?;
                }
                $chart
                    .draw_series(LineSeries::new(
                        pts.iter().map(|q| (q.0, q.1)),
                        color.stroke_width(2),
                    ))
                    .map_err(err)?;
                $chart
                    .draw_series(
                        pts.iter()
                            .map(|q| Circle::new((q.0, q.1), 3, color.filled())),
                    )
                    .map_err(err)?;
            }
        }};
    }
    if p.log {
        let mut chart = builder
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(err)?;
        body!(chart, &log_tick, &log_tick);
    } else {
        let mut chart = builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?;
        body!(chart, &xf, &yf);
    }
    let entries: Vec<(String, RGBColor)> = p
        .series
        .iter()
        .map(|s| (s.name.clone(), method_colour(&s.colour_key)))
        .collect();
    draw_legend(&right, &entries, 40)?;
    root.present().map_err(err)
}

/// Pixel size of a box plot of `n` boxes at width `w`: at least `min_h` high, and high
/// enough for one [`BOX_ROW`] per box.
pub fn box_plot_size(n: usize, (w, min_h): (u32, u32)) -> (u32, u32) {
    (w, min_h.max(n as u32 * BOX_ROW + 110))
}

fn draw_boxes<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &BoxPlot) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let n = p.boxes.len().max(1);
    let x0 = p
        .boxes
        .iter()
        .map(|b| b.dist.min)
        .fold(f64::INFINITY, f64::min);
    let x1 = p
        .boxes
        .iter()
        .map(|b| b.dist.p95.max(b.dist.q3))
        .fold(f64::NEG_INFINITY, f64::max);
    let (x0, x1) = if x0.is_finite() {
        let (a, b) = padded(x0.min(0.0), x1, false);
        (if x0 >= 0.0 { 0.0 } else { a }, b)
    } else {
        (0.0, 1.0)
    };
    let labels: Vec<String> = p.boxes.iter().map(|b| b.label.clone()).collect();
    let label_w = labels
        .iter()
        .map(|l| text_width(l, LABEL_FONT))
        .max()
        .unwrap_or(40)
        + 16;
    let xf = tick_format(x0, x1);
    // Row i (from the top) is centred on y = n - 1 - i.
    let mut chart = ChartBuilder::on(root)
        .caption(&p.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(label_w)
        .build_cartesian_2d(x0..x1, -0.5f64..(n as f64 - 0.5))
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(n)
        .y_label_formatter(&|y: &f64| {
            let i = y.round();
            if (y - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < n {
                labels.get(n - 1 - i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .x_desc(p.y_label.as_str())
        .x_labels(TICKS)
        .x_label_formatter(&xf)
        .label_style(("sans-serif", LABEL_FONT))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(err)?;
    for (i, b) in p.boxes.iter().enumerate() {
        let (y, d) = ((n - 1 - i) as f64, &b.dist);
        let color = method_colour(&b.colour_key);
        let h = 0.32;
        chart
            .draw_series([
                Rectangle::new([(d.q1, y - h), (d.q3, y + h)], color.mix(0.45).filled()),
                Rectangle::new([(d.q1, y - h), (d.q3, y + h)], color.stroke_width(2)),
            ])
            .map_err(err)?;
        chart
            .draw_series([
                PathElement::new(
                    vec![(d.median, y - h), (d.median, y + h)],
                    BLACK.stroke_width(2),
                ),
                PathElement::new(vec![(d.q3, y), (d.p95, y)], BLACK.stroke_width(1)),
                PathElement::new(vec![(d.q1, y), (d.min, y)], BLACK.stroke_width(1)),
                PathElement::new(
                    vec![(d.p95, y - h / 2.0), (d.p95, y + h / 2.0)],
                    BLACK.stroke_width(1),
                ),
                PathElement::new(
                    vec![(d.min, y - h / 2.0), (d.min, y + h / 2.0)],
                    BLACK.stroke_width(1),
                ),
            ])
            .map_err(err)?;
    }
    root.present().map_err(err)
}

/// Which plot.
#[derive(Debug, Clone, PartialEq)]
pub enum Plot {
    /// Lines.
    Lines(LinePlot),
    /// Boxes.
    Boxes(BoxPlot),
}

/// Writes `plot` as `<stem>.png` and `<stem>.svg`; returns the two paths.
pub fn write(plot: &Plot, stem: &Path, size: (u32, u32)) -> Result<(PathBuf, PathBuf)> {
    register_fonts();
    if let Some(dir) = stem.parent() {
        crate::error::create_dir_all(dir)?;
    }
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let size = match plot {
        Plot::Boxes(b) => box_plot_size(b.boxes.len(), size),
        Plot::Lines(_) => size,
    };
    {
        let root = BitMapBackend::new(&png, size).into_drawing_area();
        match plot {
            Plot::Lines(p) => draw_lines(&root, p)?,
            Plot::Boxes(p) => draw_boxes(&root, p)?,
        }
    }
    {
        let root = SVGBackend::new(&svg, size).into_drawing_area();
        match plot {
            Plot::Lines(p) => draw_lines(&root, p)?,
            Plot::Boxes(p) => draw_boxes(&root, p)?,
        }
    }
    Ok((png, svg))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registered_methods_never_share_a_colour() {
        let names: Vec<&str> = crate::registry::registry()
            .iter()
            .filter(|e| !e.hidden)
            .map(|e| e.name)
            .collect();
        assert!(names.len() <= PALETTE.len(), "grow the palette");
        let colours: std::collections::HashSet<(u8, u8, u8)> = names
            .iter()
            .map(|n| {
                let c = method_colour(n);
                (c.0, c.1, c.2)
            })
            .collect();
        assert_eq!(colours.len(), names.len());
        assert_ne!(
            method_colour("priority-front").0,
            method_colour("tight-cocone").0
        );
    }

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [1e3, 1e4, 1e5]
            .iter()
            .map(|&x: &f64| (x, 2.0 * x.powf(1.5)))
            .collect();
        assert!((loglog_slope(&pts).unwrap() - 1.5).abs() < 1e-12);
        assert!(loglog_slope(&pts[..1]).is_none());
    }

    #[test]
    fn png_and_svg_are_written_at_the_requested_size() {
        let dir = tempfile::tempdir().unwrap();
        let plot = Plot::Lines(LinePlot {
            title: "normal_mean_deg vs noise".into(),
            x_label: "noise".into(),
            y_label: "deg".into(),
            series: vec![Series {
                name: "m".into(),
                colour_key: "m".into(),
                points: vec![(0.0, 1.0, 0.5, 1.5), (0.01, 2.0, 1.5, 2.5)],
            }],
            log: false,
            non_negative: true,
        });
        let (png, svg) = write(&plot, &dir.path().join("p"), (320, 200)).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(bytes))
            .read_info()
            .unwrap();
        assert_eq!((dec.info().width, dec.info().height), (320, 200));
        let s = std::fs::read_to_string(svg).unwrap();
        assert!(s.contains("<svg") && s.contains("noise"));
        let boxes = Plot::Boxes(BoxPlot {
            title: "b".into(),
            y_label: "deg".into(),
            boxes: vec![BoxEntry {
                label: "a".into(),
                colour_key: "a".into(),
                dist: Dist::of("x", &[1.0, 2.0, 3.0, 4.0]).unwrap(),
            }],
        });
        write(&boxes, &dir.path().join("b"), (300, 200)).unwrap();
    }
}
