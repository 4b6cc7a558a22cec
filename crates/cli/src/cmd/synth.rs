//! `reconbench gen` and `reconbench shapes`: ground-truth clouds and reference meshes.

use std::path::PathBuf;

use clap::Args;
use reconbench_geom::io;
use reconbench_synth::{
    DatasetSpec, Density, PerturbSpec, SamplerSpec, ScanSpec, ShapeSpec, from_spec, generate,
    shapes,
};

use super::{CliError, CliResult, print_json};

/// Arguments of `gen`.
#[derive(Debug, Args)]
pub struct GenArgs {
    /// Shape spec, e.g. `torus`, `torus:R=2,r=0.5`, `wedge:angle=60` (see `reconbench shapes`).
    shape: String,
    /// Number of points.
    #[arg(long, conflicts_with = "spacing")]
    points: Option<usize>,
    /// Target spacing instead of a count (fraction of the unit bounding-box diagonal).
    #[arg(long)]
    spacing: Option<f64>,
    /// Sampler: uniform | blue-noise | grid[:nu=60,nv=60] | gradient | stripes.
    #[arg(long, default_value = "uniform")]
    sampler: String,
    /// Perturbation, repeatable and applied in order, e.g. `gaussian:sigma=0.005`,
    /// `outliers:fraction=0.1`, `ma-uniform:level=0.1`.
    #[arg(long = "noise")]
    noise: Vec<String>,
    /// Virtual range scan instead of surface sampling, e.g. `views=8,res=128,noise=0.001`.
    #[arg(long)]
    scan: Option<String>,
    /// Random seed (same seed, same bytes).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Write the shape's reference mesh instead of a cloud.
    #[arg(long)]
    mesh: bool,
    /// Reference-mesh resolution (segments along the longest direction; minimum 48 for
    /// composite shapes).
    #[arg(long, default_value_t = 64)]
    resolution: usize,
    /// Also write the clean positions as channels clean_x/clean_y/clean_z.
    #[arg(long)]
    with_clean: bool,
    /// Output file (.ply keeps every attribute; .xyz keeps positions and normals).
    #[arg(short, long)]
    output: PathBuf,
}

/// Arguments of `shapes`.
#[derive(Debug, Args)]
pub struct ShapesArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

/// `reconbench gen`.
pub fn gen_cmd(a: GenArgs) -> CliResult {
    if a.mesh {
        let shape = from_spec(&a.shape).map_err(CliError::input)?;
        let mesh = shape.reference_mesh(a.resolution);
        return io::write_mesh(&a.output, &mesh).map_err(CliError::input);
    }
    let density = match (a.points, a.spacing) {
        (Some(n), _) => Density::Count(n),
        (None, Some(h)) => Density::Spacing(h),
        (None, None) => Density::Count(10_000),
    };
    let spec = DatasetSpec {
        shape: a.shape.parse::<ShapeSpec>().map_err(CliError::input)?,
        sampler: a.sampler.parse::<SamplerSpec>().map_err(CliError::input)?,
        density,
        perturbations: a
            .noise
            .iter()
            .map(|s| s.parse::<PerturbSpec>())
            .collect::<Result<_, _>>()
            .map_err(CliError::input)?,
        scan: a
            .scan
            .as_deref()
            .map(str::parse::<ScanSpec>)
            .transpose()
            .map_err(CliError::input)?,
    };
    let gt = generate(&spec, a.seed).map_err(CliError::input)?;
    let cloud = if a.with_clean {
        gt.to_point_cloud_with_clean()
    } else {
        gt.to_point_cloud()
    }
    .map_err(CliError::failure)?;
    io::write_cloud(&a.output, &cloud).map_err(CliError::input)
}

/// `reconbench shapes`.
pub fn shapes_cmd(a: ShapesArgs) -> CliResult {
    let rows = shapes::listing();
    if a.json {
        return print_json(&rows);
    }
    println!(
        "{:<16} {:>5} {:>6} {:>8} {:>8} {:>7}  description",
        "shape", "genus", "closed", "curves", "corners", "area"
    );
    for r in rows {
        println!(
            "{:<16} {:>5} {:>6} {:>8} {:>8} {:>7.4}  {}",
            r.info.name,
            r.info.genus,
            if r.info.closed { "yes" } else { "no" },
            r.info.feature_curves,
            r.info.corners,
            r.info.area,
            r.summary
        );
    }
    Ok(())
}
