//! Plots with plotters, as PNG and SVG, with the DejaVu font embedded (no system font
//! is needed; [`register_fonts`] registers it under `sans-serif`).
//!
//! * metric vs perturbation level: one line per method, a band for mean ± std over seeds;
//! * log-log time vs input size with the fitted slope of each method;
//! * box plots of per-point errors (box = quartiles, whiskers = min and 95th percentile,
//!   averaged over seeds).

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

/// One line of a [`LinePlot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y, y_low, y_high)`; the band spans `y_low..y_high`.
    pub points: Vec<(f64, f64, f64, f64)>,
}

/// A line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Title.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// Lines.
    pub series: Vec<Series>,
    /// Log-log axes.
    pub log: bool,
}

/// A box plot.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxPlot {
    /// Title.
    pub title: String,
    /// Y axis label.
    pub y_label: String,
    /// `(category, distribution)`.
    pub boxes: Vec<(String, Dist)>,
}

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

fn draw_lines<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &LinePlot) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let all: Vec<&(f64, f64, f64, f64)> = p.series.iter().flat_map(|s| &s.points).collect();
    let xs = all.iter().map(|q| q.0);
    let x0 = xs.clone().fold(f64::INFINITY, f64::min);
    let x1 = xs.fold(f64::NEG_INFINITY, f64::max);
    let y0 = all
        .iter()
        .map(|q| q.2.min(q.1))
        .fold(f64::INFINITY, f64::min);
    let y1 = all
        .iter()
        .map(|q| q.3.max(q.1))
        .fold(f64::NEG_INFINITY, f64::max);
    if all.is_empty() || !x0.is_finite() || !y0.is_finite() {
        root.draw(&Text::new(
            "no data",
            (20, 20),
            ("sans-serif", 16).into_font(),
        ))
        .map_err(err)?;
        return root.present().map_err(err);
    }
    let (x0, x1) = padded(x0, x1, p.log);
    let (y0, y1) = padded(y0, y1, p.log);
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(&p.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75);
    macro_rules! body {
        ($chart:ident) => {{
            $chart
                .configure_mesh()
                .x_desc(p.x_label.as_str())
                .y_desc(p.y_label.as_str())
                .x_label_formatter(&|v| crate::tables::fmt_num(*v))
                .y_label_formatter(&|v| crate::tables::fmt_num(*v))
                .label_style(("sans-serif", 13))
                .axis_desc_style(("sans-serif", 15))
                .draw()
                .map_err(err)?;
            for (i, s) in p.series.iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                let mut pts = s.points.clone();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
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
                    .map_err(err)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                    });
                $chart
                    .draw_series(
                        pts.iter()
                            .map(|q| Circle::new((q.0, q.1), 3, color.filled())),
                    )
                    .map_err(err)?;
            }
            $chart
                .configure_series_labels()
                .label_font(("sans-serif", 13))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperLeft)
                .draw()
                .map_err(err)?;
        }};
    }
    if p.log {
        let mut chart = builder
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(err)?;
        body!(chart);
    } else {
        let mut chart = builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?;
        body!(chart);
    }
    root.present().map_err(err)
}

fn draw_boxes<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &BoxPlot) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let n = p.boxes.len().max(1);
    let y0 = p
        .boxes
        .iter()
        .map(|b| b.1.min)
        .fold(f64::INFINITY, f64::min);
    let y1 = p
        .boxes
        .iter()
        .map(|b| b.1.p95.max(b.1.q3))
        .fold(f64::NEG_INFINITY, f64::max);
    let (y0, y1) = if y0.is_finite() {
        padded(y0.min(0.0), y1, false)
    } else {
        (0.0, 1.0)
    };
    let labels: Vec<String> = p.boxes.iter().map(|b| b.0.clone()).collect();
    let mut chart = ChartBuilder::on(root)
        .caption(&p.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(60)
        .y_label_area_size(75)
        .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&|x: &f64| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_desc(p.y_label.as_str())
        .y_label_formatter(&|v| crate::tables::fmt_num(*v))
        .label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(err)?;
    for (i, (_, d)) in p.boxes.iter().enumerate() {
        let x = i as f64;
        let color = Palette99::pick(i).to_rgba();
        let w = 0.3;
        chart
            .draw_series([
                Rectangle::new([(x - w, d.q1), (x + w, d.q3)], color.mix(0.35).filled()),
                Rectangle::new([(x - w, d.q1), (x + w, d.q3)], color.stroke_width(2)),
            ])
            .map_err(err)?;
        chart
            .draw_series([
                PathElement::new(
                    vec![(x - w, d.median), (x + w, d.median)],
                    BLACK.stroke_width(2),
                ),
                PathElement::new(vec![(x, d.q3), (x, d.p95)], BLACK.stroke_width(1)),
                PathElement::new(vec![(x, d.q1), (x, d.min)], BLACK.stroke_width(1)),
                PathElement::new(
                    vec![(x - w / 2.0, d.p95), (x + w / 2.0, d.p95)],
                    BLACK.stroke_width(1),
                ),
                PathElement::new(
                    vec![(x - w / 2.0, d.min), (x + w / 2.0, d.min)],
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
                points: vec![(0.0, 1.0, 0.5, 1.5), (0.01, 2.0, 1.5, 2.5)],
            }],
            log: false,
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
            boxes: vec![("a".into(), Dist::of("x", &[1.0, 2.0, 3.0, 4.0]).unwrap())],
        });
        write(&boxes, &dir.path().join("b"), (300, 200)).unwrap();
    }
}
