//! Renders (issue 26): one colour scale shared by every panel of a report, boundary
//! edges drawn in their colour on open meshes only, self-intersecting faces marked, one
//! panel per method, and the render data surviving a file round trip.

use reconbench_geom::{DVec3, TriMesh};
use reconbench_harness::render::{
    BOUNDARY_COLOUR, DEFECT_COLOUR, Panel, RenderData, Scale, render_comparison,
};

const VIEW: u32 = 96;

/// A closed octahedron (no boundary, no self-intersection).
fn octahedron() -> TriMesh {
    let v = vec![
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::Z,
        -DVec3::Z,
    ];
    let f = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    TriMesh::new(v, f).unwrap()
}

/// The octahedron without its top four faces: an open cup with a square rim.
fn open_cup() -> TriMesh {
    let m = octahedron();
    TriMesh::new(m.vertices().to_vec(), m.faces()[4..].to_vec()).unwrap()
}

/// Two triangles crossing each other (not sharing a vertex), and two apart.
fn crossing(apart: bool) -> TriMesh {
    let shift = if apart { 3.0 } else { 0.0 };
    let v = vec![
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(1.0, 0.0, -1.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(shift, -1.0, -0.5),
        DVec3::new(shift, 1.0, -0.5),
        DVec3::new(shift, 0.0, 1.5),
    ];
    TriMesh::new(v, vec![[0, 1, 2], [3, 4, 5]]).unwrap()
}

fn constant(mesh: &TriMesh, d: f64) -> RenderData {
    RenderData::from_mesh(mesh, &vec![d; mesh.n_vertices()], &vec![d; mesh.n_faces()]).unwrap()
}

fn count(
    img: &reconbench_harness::render::Image,
    x0: u32,
    y0: u32,
    w: u32,
    h: u32,
    c: [u8; 3],
) -> usize {
    (y0..y0 + h)
        .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
        .filter(|&(x, y)| img.pixel(x, y) == c)
        .count()
}

fn not_white(img: &reconbench_harness::render::Image, x0: u32, y0: u32, w: u32, h: u32) -> usize {
    (y0..y0 + h)
        .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
        .filter(|&(x, y)| img.pixel(x, y) != [255, 255, 255])
        .count()
}

/// The first column's views carry their names (front, side, top) in the top-left corner.
fn under_view_name(x: u32, y: u32) -> bool {
    x < 50 && y % VIEW < 18
}

#[test]
fn one_scale_for_all_panels_so_equal_distances_get_equal_colours() {
    // Same geometry, one mesh at distance 0.002 everywhere, one at 0.008: on a shared
    // scale the first is darker than the second, and each pixel of the first equals
    // what the second would show at 0.002.
    let m = octahedron();
    let (low, high) = (constant(&m, 0.002), constant(&m, 0.008));
    let scale = Scale::robust(&[&low, &high]);
    assert!(scale.max >= 0.008 && scale.max < 0.02, "{scale:?}");
    let lines = vec![String::new()];
    let panels = [
        Panel {
            title: "low",
            lines: &lines,
            data: Some(&low),
        },
        Panel {
            title: "high",
            lines: &lines,
            data: Some(&high),
        },
        Panel {
            title: "low again",
            lines: &lines,
            data: Some(&low),
        },
    ];
    let cmp = render_comparison("t", &panels, &scale, VIEW).unwrap();
    let (a, b, c) = (cmp.panels[0], cmp.panels[1], cmp.panels[2]);
    let mut differ = 0;
    let mut inside = 0;
    for y in 0..3 * VIEW {
        for x in 0..VIEW {
            let pa = cmp.image.pixel(a.x + x, a.y + y);
            let pb = cmp.image.pixel(b.x + x, b.y + y);
            let pc = cmp.image.pixel(c.x + x, c.y + y);
            if under_view_name(x, y) {
                continue;
            }
            // The same mesh in two panels: the same pixels (one framing, one scale).
            assert_eq!(pa, pc, "pixel {x},{y}");
            if pa != [255, 255, 255] {
                inside += 1;
                differ += usize::from(pa != pb);
            }
        }
    }
    assert!(inside > 1000, "{inside}");
    assert!(differ * 10 > inside * 9, "{differ} of {inside}");
    // The colour a distance gets does not depend on the panel: rendering the low mesh
    // alone on the same scale gives the same pixels.
    let alone = render_comparison("t", &panels[..1], &scale, VIEW).unwrap();
    let r = alone.panels[0];
    for y in (0..3 * VIEW).step_by(7) {
        for x in (0..VIEW).step_by(5) {
            assert_eq!(
                alone.image.pixel(r.x + x, r.y + y),
                cmp.image.pixel(a.x + x, a.y + y)
            );
        }
    }
    // The scale is the report's: with only the low mesh it tops out lower, and the
    // same mesh is drawn brighter.
    let own = Scale::robust(&[&low]);
    assert!(own.max < scale.max, "{own:?} vs {scale:?}");
    assert_ne!(own.colour(0.002), scale.colour(0.002));
}

#[test]
fn the_scale_is_robust_to_one_stray_mesh_part() {
    // 99 % of a mesh's values at 0.001 and 1 % at 1.0: the 95th percentile ignores the
    // stray part.
    let m = octahedron();
    let mut d = constant(&m, 0.001);
    d.face_values = vec![0.001; 8];
    d.vertex_values = vec![0.001; 6];
    let mut stray = d.clone();
    stray.face_values[0] = 1.0;
    let s = Scale::robust(&[&d, &d, &d, &d, &d, &d, &d, &d, &d, &d, &d, &d, &d, &stray]);
    assert!(s.max < 0.01, "{s:?}");
    // Ticks are round and the top covers the percentile.
    let t = s.ticks();
    assert_eq!(t[0], 0.0);
    assert!((t.last().unwrap() - s.max).abs() < 1e-12);
    assert!(s.max >= s.percentile_95.unwrap());
}

#[test]
fn boundary_edges_are_drawn_on_an_open_mesh_and_not_on_a_closed_one() {
    let open = constant(&open_cup(), 0.001);
    let closed = constant(&octahedron(), 0.001);
    assert_eq!(open.boundary_edges.len(), 4);
    assert!(closed.boundary_edges.is_empty());
    let scale = Scale::fixed(0.01);
    let lines = vec![];
    for (d, want) in [(&open, true), (&closed, false)] {
        let cmp = render_comparison(
            "t",
            &[Panel {
                title: "m",
                lines: &lines,
                data: Some(d),
            }],
            &scale,
            VIEW,
        )
        .unwrap();
        let r = cmp.panels[0];
        let red = count(&cmp.image, r.x, r.y, VIEW, 3 * VIEW, BOUNDARY_COLOUR);
        assert_eq!(red > 30, want, "boundary pixels {red}");
        assert_eq!(
            count(&cmp.image, r.x, r.y, VIEW, 3 * VIEW, DEFECT_COLOUR),
            0
        );
    }
}

#[test]
fn self_intersecting_faces_show_the_marking_colour() {
    let cross = constant(&crossing(false), 0.001);
    let apart = constant(&crossing(true), 0.001);
    assert_eq!(cross.self_intersecting_faces(), 2);
    assert_eq!(apart.self_intersecting_faces(), 0);
    let scale = Scale::fixed(0.01);
    let lines = vec![];
    for (d, want) in [(&cross, true), (&apart, false)] {
        let cmp = render_comparison(
            "t",
            &[Panel {
                title: "m",
                lines: &lines,
                data: Some(d),
            }],
            &scale,
            VIEW,
        )
        .unwrap();
        let r = cmp.panels[0];
        let marked = count(&cmp.image, r.x, r.y, VIEW, 3 * VIEW, DEFECT_COLOUR);
        assert_eq!(marked > 100, want, "marked pixels {marked}");
    }
}

#[test]
fn non_manifold_faces_are_flagged() {
    // Three triangles on one edge.
    let v = vec![
        DVec3::ZERO,
        DVec3::Z,
        DVec3::X,
        DVec3::Y,
        DVec3::new(-1.0, -1.0, 0.0),
    ];
    let m = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    let d = constant(&m, 0.0);
    assert_eq!(d.non_manifold_faces(), 3);
    assert_eq!(constant(&octahedron(), 0.0).non_manifold_faces(), 0);
}

#[test]
fn one_panel_per_method_side_by_side() {
    let m = octahedron();
    let datas: Vec<RenderData> = (1..=5).map(|i| constant(&m, 0.001 * i as f64)).collect();
    let lines = vec!["Hausdorff 0.001".to_string()];
    let names = ["a", "b", "c", "d", "e"];
    let mut panels: Vec<Panel<'_>> = datas
        .iter()
        .zip(names)
        .map(|(d, n)| Panel {
            title: n,
            lines: &lines,
            data: Some(d),
        })
        .collect();
    // A method whose cell failed keeps its column, empty.
    panels.push(Panel {
        title: "failed",
        lines: &lines,
        data: None,
    });
    let refs: Vec<&RenderData> = datas.iter().collect();
    let cmp = render_comparison("t", &panels, &Scale::robust(&refs), VIEW).unwrap();
    assert_eq!(cmp.panels.len(), 6);
    for w in cmp.panels.windows(2) {
        assert_eq!(w[0].y, w[1].y, "one row");
        assert!(w[1].x >= w[0].x + VIEW, "side by side, not overlapping");
    }
    let last = cmp.panels[5];
    assert!(last.x + VIEW <= cmp.image.width);
    for (i, r) in cmp.panels.iter().enumerate() {
        // Mesh pixels in each of the three views of a drawn panel; none in the failed one
        // (its view area holds only the grey "no mesh" text).
        for k in 0..3 {
            let n = not_white(&cmp.image, r.x, r.y + k * VIEW, VIEW, VIEW);
            if i < 5 {
                assert!(n > 500, "panel {i} view {k}: {n}");
            } else {
                assert!(n < 400, "panel {i} view {k}: {n}");
            }
        }
    }
    // More than eight methods wrap into a second row.
    let many: Vec<Panel<'_>> = (0..10).map(|i| panels[i % 5]).collect();
    let cmp = render_comparison("t", &many, &Scale::fixed(0.01), VIEW).unwrap();
    assert_eq!(cmp.panels.len(), 10);
    assert!(cmp.panels[9].y > cmp.panels[0].y);
    // An image too large to allocate sensibly is refused with the option to change.
    let e = render_comparison("t", &many, &Scale::fixed(0.01), 4096)
        .unwrap_err()
        .to_string();
    assert!(e.contains("too large") && e.contains("render_size"), "{e}");
}

#[test]
fn render_data_survives_a_file_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let d = constant(&open_cup(), 0.003);
    let p = dir.path().join("renders/x.rbr");
    d.save(&p).unwrap();
    assert_eq!(RenderData::load(&p).unwrap(), d);
    std::fs::write(&p, b"not render data").unwrap();
    let e = RenderData::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("x.rbr") && e.contains("not a render data file"),
        "{e}"
    );
}

/// Rows of a small experiment (two reconstruction methods, two noise levels, two seeds)
/// marked ok, with the render path `render` gives each cell at seed 0.
fn report_rows(
    render: impl Fn(&reconbench_harness::experiment::Cell) -> Option<String>,
) -> (
    reconbench_harness::experiment::Experiment,
    Vec<reconbench_harness::store::Row>,
) {
    use reconbench_harness::store::{Row, Status};
    let exp = reconbench_harness::experiment::Experiment::parse(
        r#"
        seeds = 2
        [[datasets]]
        shape = "sphere"
        points = 200
        [[perturbations]]
        noise = [0.0, 0.01]
        [[methods]]
        name = "reference-mesh"
        params = { resolution = [8, 16] }
        [report]
        plots = false
        tables = []
        render_size = 64
        "#,
        "renders",
    )
    .unwrap();
    let rows = exp
        .cells
        .iter()
        .map(|c| {
            let mut r = Row::failed(c, Status::Ok, "");
            r.error = None;
            r.metrics.insert("hausdorff".into(), 0.01);
            if c.spec.seed_index == 0 {
                r.render = render(c);
            }
            r
        })
        .collect();
    (exp, rows)
}

#[test]
fn the_report_draws_one_image_per_configuration_from_the_stored_data() {
    let dir = tempfile::tempdir().unwrap();
    let open = constant(&open_cup(), 0.002);
    let (exp, rows) = report_rows(|c| {
        let rel = reconbench_harness::render::data_path(&c.key);
        open.save(&dir.path().join(&rel)).unwrap();
        Some(rel)
    });
    let out =
        reconbench_harness::report::write_report(dir.path(), &rows, Some(&exp), None).unwrap();
    // Two noise levels: two images, each with the two resolutions side by side.
    assert_eq!(out.renders.len(), 2, "{:?}", out.renders);
    for p in &out.renders {
        assert!(p.extension().is_some_and(|e| e == "png"), "{}", p.display());
        assert!(p.exists());
    }
    let md = std::fs::read_to_string(&out.report).unwrap();
    assert!(
        md.contains("## Renders") && md.contains("95th percentile"),
        "{md}"
    );
    assert!(!md.contains("Left out"), "{md}");
}

#[test]
fn old_or_missing_render_files_give_a_note_not_a_failure() {
    let dir = tempfile::tempdir().unwrap();
    // An older version's rows: a PNG per cell, no render data.
    let (exp, rows) = report_rows(|c| Some(format!("renders/{}.png", c.key)));
    let out =
        reconbench_harness::report::write_report(dir.path(), &rows, Some(&exp), None).unwrap();
    assert!(out.renders.is_empty());
    let md = std::fs::read_to_string(&out.report).unwrap();
    assert!(md.contains("older version"), "{md}");
    // Data files named but gone, or not render data: a note naming them.
    let (exp, rows) = report_rows(|c| Some(reconbench_harness::render::data_path(&c.key)));
    let first = rows[0].render.clone().unwrap();
    std::fs::create_dir_all(dir.path().join("renders")).unwrap();
    std::fs::write(dir.path().join(&first), b"garbage").unwrap();
    let out =
        reconbench_harness::report::write_report(dir.path(), &rows, Some(&exp), None).unwrap();
    assert!(out.renders.is_empty());
    let md = std::fs::read_to_string(&out.report).unwrap();
    assert!(
        md.contains("No render data") && md.contains("not a render data file"),
        "{md}"
    );
}
