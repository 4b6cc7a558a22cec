//! `reconbench info` and `reconbench convert`.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use reconbench_geom::io::{self, Format, Loaded, PlyEncoding, WriteOptions};
use reconbench_geom::spatial::mean_spacing;
use reconbench_geom::topology::{TopologyReport, analyze};
use reconbench_geom::{Aabb, PointCloud};
use serde::Serialize;

use super::{CliError, CliResult, print_json};

/// Arguments of `info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Mesh or point cloud file (ply, obj, off, stl, xyz, pts).
    file: PathBuf,
    /// Read the file as this format whatever its extension.
    #[arg(long)]
    format: Option<Format>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Arguments of `convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input file.
    input: PathBuf,
    /// Output file; its extension picks the format.
    output: PathBuf,
    /// Encoding of PLY output.
    #[arg(long, value_enum, default_value_t = PlyEnc::BinaryLittleEndian)]
    ply_encoding: PlyEnc,
    /// Write STL as ascii instead of binary.
    #[arg(long)]
    stl_ascii: bool,
}

/// PLY encodings as CLI values.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum PlyEnc {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

/// What `info` reports about a point cloud.
#[derive(Debug, Serialize)]
struct CloudInfo {
    kind: &'static str,
    points: usize,
    has_normals: bool,
    has_colors: bool,
    has_source_ids: bool,
    channels: Vec<String>,
    bbox_min: [f64; 3],
    bbox_max: [f64; 3],
    bbox_diagonal: f64,
    /// Mean distance to the nearest distinct neighbour.
    mean_spacing: Option<f64>,
}

/// What `info` reports about a mesh: the stable summary keys (documented in
/// docs/METRICS.md), then the full topology report (per component, per loop).
#[derive(Debug, Serialize)]
struct MeshInfo {
    kind: &'static str,
    vertices: usize,
    faces: usize,
    edges: usize,
    euler: i64,
    components: usize,
    genus: Option<u32>,
    watertight: bool,
    orientable: bool,
    boundary_edges: usize,
    /// Number of boundary loops (their details are in `topology.boundary_loops`).
    boundary_loops: usize,
    non_manifold_edges: usize,
    non_manifold_vertices: usize,
    bbox_min: [f64; 3],
    bbox_max: [f64; 3],
    bbox_diagonal: f64,
    area: f64,
    topology: TopologyReport,
}

fn cloud_info(c: &PointCloud) -> CloudInfo {
    let b = c.aabb();
    CloudInfo {
        kind: "point_cloud",
        points: c.len(),
        has_normals: c.normals().is_some(),
        has_colors: c.colors().is_some(),
        has_source_ids: c.source_ids().is_some(),
        channels: c.channels().keys().cloned().collect(),
        bbox_min: box_min(&b),
        bbox_max: box_max(&b),
        bbox_diagonal: b.diagonal(),
        mean_spacing: mean_spacing(c.positions(), 1).ok(),
    }
}

fn box_min(b: &Aabb) -> [f64; 3] {
    if b.is_empty() {
        [0.0; 3]
    } else {
        b.min.to_array()
    }
}

fn box_max(b: &Aabb) -> [f64; 3] {
    if b.is_empty() {
        [0.0; 3]
    } else {
        b.max.to_array()
    }
}

/// `reconbench info`.
pub fn info(a: InfoArgs) -> CliResult {
    let loaded = match a.format {
        Some(f) => io::read_any_as(&a.file, f),
        None => io::read_any(&a.file),
    }
    .map_err(CliError::input)?;
    match loaded {
        Loaded::Cloud(c) => {
            let i = cloud_info(&c);
            if a.json {
                return print_json(&i);
            }
            println!("{}: point cloud", a.file.display());
            println!("  points        {}", i.points);
            println!("  normals       {}", yes_no(i.has_normals));
            println!("  colours       {}", yes_no(i.has_colors));
            println!("  source ids    {}", yes_no(i.has_source_ids));
            println!(
                "  channels      {}",
                if i.channels.is_empty() {
                    "-".into()
                } else {
                    i.channels.join(", ")
                }
            );
            println!("  bbox diagonal {:.6}", i.bbox_diagonal);
            if let Some(s) = i.mean_spacing {
                println!("  mean spacing  {s:.6e}");
            }
        }
        Loaded::Mesh(m) => {
            let b = m.aabb();
            let t = analyze(&m);
            let i = MeshInfo {
                kind: "mesh",
                vertices: t.vertices,
                faces: t.faces,
                edges: t.edges,
                euler: t.euler,
                components: t.components,
                genus: t.genus,
                watertight: t.watertight,
                orientable: t.orientable,
                boundary_edges: t.boundary_edges,
                boundary_loops: t.n_boundary_loops(),
                non_manifold_edges: t.non_manifold_edges,
                non_manifold_vertices: t.non_manifold_vertices,
                bbox_min: box_min(&b),
                bbox_max: box_max(&b),
                bbox_diagonal: b.diagonal(),
                area: m.area(),
                topology: t,
            };
            if a.json {
                return print_json(&i);
            }
            let t = &i.topology;
            println!("{}: triangle mesh", a.file.display());
            println!("  vertices              {}", t.vertices);
            println!("  faces                 {}", t.faces);
            println!("  edges                 {}", t.edges);
            println!("  euler characteristic  {}", t.euler);
            println!("  components            {}", t.components);
            println!(
                "  genus                 {}",
                t.genus
                    .map_or("undefined (non-manifold or non-orientable)".into(), |g| g
                        .to_string())
            );
            println!("  watertight            {}", yes_no(t.watertight));
            println!("  orientable            {}", yes_no(t.orientable));
            println!(
                "  consistently oriented {}",
                yes_no(t.consistently_oriented)
            );
            println!(
                "  boundary edges/loops  {} / {}",
                t.boundary_edges,
                t.boundary_loops.len()
            );
            println!("  non-manifold edges    {}", t.non_manifold_edges);
            println!("  non-manifold vertices {}", t.non_manifold_vertices);
            println!("  degenerate faces      {}", t.degenerate_faces);
            println!("  duplicate faces       {}", t.duplicate_faces);
            println!("  unreferenced vertices {}", t.unreferenced_vertices);
            println!("  area                  {:.6e}", i.area);
            println!("  bbox diagonal         {:.6}", i.bbox_diagonal);
        }
    }
    Ok(())
}

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

/// `reconbench convert`.
pub fn convert(a: ConvertArgs) -> CliResult {
    let options = WriteOptions {
        ply_encoding: match a.ply_encoding {
            PlyEnc::Ascii => PlyEncoding::Ascii,
            PlyEnc::BinaryLittleEndian => PlyEncoding::BinaryLittleEndian,
            PlyEnc::BinaryBigEndian => PlyEncoding::BinaryBigEndian,
        },
        stl_binary: !a.stl_ascii,
    };
    let out_format = Format::from_path(&a.output).map_err(CliError::input)?;
    match io::read_any(&a.input).map_err(CliError::input)? {
        Loaded::Mesh(m) => io::write_mesh_with(&a.output, &m, out_format, &options),
        Loaded::Cloud(c) => io::write_cloud_with(&a.output, &c, out_format, &options),
    }
    .map_err(CliError::input)?;
    Ok(())
}
