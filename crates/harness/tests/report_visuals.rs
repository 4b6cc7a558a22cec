//! What a reader sees in a report's plots (issue 26), asserted on the SVG output: label
//! boxes do not overlap, the legend does not cover data, a non-negative metric's band
//! stays above 0, tick labels share one format and a method keeps its colour.

use reconbench_harness::plots::{
    BoxEntry, BoxPlot, LABEL_FONT, LinePlot, Plot, Series, method_colour, text_width, write,
};
use reconbench_harness::store::Dist;

/// A `<text>` element: anchor point, anchor kind, font size and content.
#[derive(Debug)]
struct SvgText {
    x: f64,
    y: f64,
    anchor: String,
    size: f64,
    text: String,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(tag[i..j].to_string())
}

fn texts(svg: &str) -> Vec<SvgText> {
    svg.split("<text")
        .skip(1)
        .filter_map(|chunk| {
            let close = chunk.find('>')?;
            let tag = &chunk[..close];
            let end = chunk.find("</text>")?;
            Some(SvgText {
                x: attr(tag, "x")?.parse().ok()?,
                y: attr(tag, "y")?.parse().ok()?,
                anchor: attr(tag, "text-anchor").unwrap_or_else(|| "start".into()),
                // plotters writes the pixel size it was given over 1.24; the bound uses
                // the larger pixel size.
                size: attr(tag, "font-size")
                    .and_then(|s| s.trim_end_matches("px").parse::<f64>().ok())
                    .map_or(LABEL_FONT as f64, |s| s * 1.24),
                text: chunk[close + 1..end].trim().to_string(),
            })
        })
        .collect()
}

/// An upper bound of the box a text covers: its estimated width beside the anchor and
/// one font size above and below the anchor line (whatever the baseline shift).
fn text_box(t: &SvgText) -> [f64; 4] {
    let w = text_width(&t.text, t.size.round() as u32) as f64;
    let (x0, x1) = match t.anchor.as_str() {
        "end" => (t.x - w, t.x),
        "middle" => (t.x - w / 2.0, t.x + w / 2.0),
        _ => (t.x, t.x + w),
    };
    [x0, t.y - 0.5 * t.size, x1, t.y + 1.0 * t.size]
}

fn overlap(a: [f64; 4], b: [f64; 4]) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

fn inside(p: (f64, f64), b: [f64; 4]) -> bool {
    p.0 >= b[0] && p.0 <= b[2] && p.1 >= b[1] && p.1 <= b[3]
}

/// The points of every `<polygon>` / `<polyline>` element.
fn poly_points(svg: &str, tag: &str) -> Vec<Vec<(f64, f64)>> {
    svg.split(&format!("<{tag}"))
        .skip(1)
        .filter_map(|chunk| attr(&chunk[..chunk.find('>')?], "points"))
        .map(|pts| {
            pts.split_whitespace()
                .filter_map(|p| {
                    let (x, y) = p.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect()
        })
        .collect()
}

fn circles(svg: &str) -> Vec<(f64, f64)> {
    svg.split("<circle")
        .skip(1)
        .filter_map(|c| {
            let tag = &c[..c.find('>')?];
            Some((
                attr(tag, "cx")?.parse().ok()?,
                attr(tag, "cy")?.parse().ok()?,
            ))
        })
        .collect()
}

fn render_svg(plot: &Plot, size: (u32, u32)) -> String {
    let dir = tempfile::tempdir().unwrap();
    let (_, svg) = write(plot, &dir.path().join("p"), size).unwrap();
    std::fs::read_to_string(svg).unwrap()
}

const METHODS: [&str; 6] = [
    "priority-front",
    "ufm",
    "ball-pivoting (jet normals)",
    "tight-cocone",
    "poisson (gt-normals, depth 6)",
    "reference-mesh",
];

fn dist(scale: f64) -> Dist {
    let v: Vec<f64> = (0..50).map(|i| scale * (i as f64 / 49.0)).collect();
    Dist::of("surface distance (diag)", &v).unwrap()
}

#[test]
fn eighteen_box_labels_do_not_overlap() {
    let boxes: Vec<BoxEntry> = METHODS
        .iter()
        .flat_map(|m| {
            ["clean", "noise=0.0025", "noise=0.005"]
                .into_iter()
                .enumerate()
                .map(move |(i, p)| BoxEntry {
                    label: format!("{m} @ {p}"),
                    colour_key: m.to_string(),
                    dist: dist(0.001 * (i + 1) as f64),
                })
        })
        .collect();
    assert_eq!(boxes.len(), 18);
    let svg = render_svg(
        &Plot::Boxes(BoxPlot {
            title: "sphere: per-point surface distance".into(),
            y_label: "surface distance (fraction of diagonal)".into(),
            boxes: boxes.clone(),
        }),
        (800, 500),
    );
    let labels: Vec<SvgText> = texts(&svg)
        .into_iter()
        .filter(|t| t.text.contains(" @ "))
        .collect();
    assert_eq!(labels.len(), 18, "every box is labelled once");
    for (i, a) in labels.iter().enumerate() {
        assert!(
            text_box(a)[0] >= 0.0,
            "label {} cut at the left edge",
            a.text
        );
        for b in &labels[i + 1..] {
            assert!(
                !overlap(text_box(a), text_box(b)),
                "{} overlaps {}",
                a.text,
                b.text
            );
        }
    }
    // Every method's box is drawn in that method's colour.
    for m in METHODS {
        let c = method_colour(m);
        let hex = format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
        assert!(svg.to_uppercase().contains(&hex), "{m}: {hex}");
    }
}

fn line_plot(non_negative: bool) -> LinePlot {
    let series = METHODS
        .iter()
        .enumerate()
        .map(|(i, m)| Series {
            name: m.to_string(),
            colour_key: m.to_string(),
            // Spread 10x the mean: mean - std is far below 0.
            points: [0.0, 0.0025, 0.005]
                .iter()
                .map(|&x| {
                    let y = 0.001 * (i + 1) as f64 + x;
                    (x, y, y - 10.0 * y, y + 10.0 * y)
                })
                .collect(),
        })
        .collect();
    LinePlot {
        title: "sphere: hausdorff".into(),
        x_label: "noise (fraction of diagonal)".into(),
        y_label: "hausdorff (fraction of diagonal)".into(),
        series,
        log: false,
        non_negative,
    }
}

/// The legend entries' boxes (the swatch left of each text included).
fn legend_boxes(svg: &str) -> Vec<[f64; 4]> {
    texts(svg)
        .iter()
        .filter(|t| METHODS.contains(&t.text.as_str()))
        .map(|t| {
            let mut b = text_box(t);
            b[0] -= 30.0;
            b
        })
        .collect()
}

#[test]
fn legend_does_not_cover_the_data() {
    let svg = render_svg(&Plot::Lines(line_plot(true)), (800, 500));
    let legend = legend_boxes(&svg);
    assert_eq!(legend.len(), METHODS.len(), "one legend entry per series");
    let dots = circles(&svg);
    assert_eq!(dots.len(), 3 * METHODS.len());
    let lines: Vec<(f64, f64)> = poly_points(&svg, "polyline")
        .into_iter()
        .flatten()
        .collect();
    let bands: Vec<(f64, f64)> = poly_points(&svg, "polygon").into_iter().flatten().collect();
    assert!(!bands.is_empty());
    let data_right = dots
        .iter()
        .chain(&bands)
        .map(|p| p.0)
        .fold(f64::NEG_INFINITY, f64::max);
    for b in &legend {
        assert!(
            b[0] > data_right,
            "legend {b:?} starts left of data at x = {data_right}"
        );
        for p in dots.iter().chain(&bands) {
            assert!(!inside(*p, *b), "data point {p:?} under the legend {b:?}");
        }
        // Line vertices of the data (not the legend's own swatches) stay clear too.
        assert!(
            lines
                .iter()
                .filter(|p| p.0 < data_right + 1.0)
                .all(|p| !inside(*p, *b))
        );
    }
}

/// The y pixel of the y-axis tick labelled 0 (the rightmost texts left of the data).
fn zero_tick_y(svg: &str) -> Option<f64> {
    texts(svg)
        .into_iter()
        .filter(|t| t.anchor == "end")
        .find(|t| t.text.parse::<f64>().is_ok_and(|v| v == 0.0))
        .map(|t| t.y)
}

#[test]
fn band_of_a_non_negative_metric_stops_at_zero() {
    let svg = render_svg(&Plot::Lines(line_plot(true)), (800, 500));
    let zero = zero_tick_y(&svg).expect("the axis starts at a 0 tick");
    let lowest = poly_points(&svg, "polygon")
        .into_iter()
        .flatten()
        .map(|p| p.1)
        .fold(f64::NEG_INFINITY, f64::max);
    // SVG y grows downwards; the tick label is centred on its tick within a few pixels.
    assert!(
        lowest <= zero + LABEL_FONT as f64,
        "band reaches y = {lowest}, 0 at {zero}"
    );
    // The same data as a signed metric goes below 0 (the test can fail).
    let svg = render_svg(&Plot::Lines(line_plot(false)), (800, 500));
    let lowest = poly_points(&svg, "polygon")
        .into_iter()
        .flatten()
        .map(|p| p.1)
        .fold(f64::NEG_INFINITY, f64::max);
    let zero = zero_tick_y(&svg).unwrap_or(f64::INFINITY);
    assert!(lowest > zero + LABEL_FONT as f64, "{lowest} {zero}");
}

#[test]
fn tick_labels_of_an_axis_share_one_format() {
    let svg = render_svg(&Plot::Lines(line_plot(true)), (800, 500));
    let ticks: Vec<String> = texts(&svg)
        .into_iter()
        .filter(|t| t.anchor == "end" && t.text.parse::<f64>().is_ok())
        .map(|t| t.text)
        .collect();
    assert!(ticks.len() >= 3, "{ticks:?}");
    let decimals = |s: &str| s.split_once('.').map_or(0, |(_, d)| d.len());
    let sci = |s: &str| s.contains('e');
    assert!(
        ticks
            .iter()
            .all(|t| decimals(t) == decimals(&ticks[0]) && sci(t) == sci(&ticks[0])),
        "{ticks:?}"
    );
}

#[test]
fn a_method_has_one_colour_whatever_the_other_methods() {
    let a = method_colour("jet");
    assert_eq!(a, method_colour("jet"));
    let hex = |m: &str| {
        let c = method_colour(m);
        format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
    };
    // The same method in two plots with different company and order.
    let mut p = line_plot(true);
    let first = render_svg(&Plot::Lines(p.clone()), (800, 500)).to_uppercase();
    p.series.reverse();
    p.series.truncate(2);
    let second = render_svg(&Plot::Lines(p.clone()), (800, 500)).to_uppercase();
    for s in &p.series {
        assert!(first.contains(&hex(&s.colour_key)) && second.contains(&hex(&s.colour_key)));
    }
}
