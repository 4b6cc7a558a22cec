//! `reconbench gen` and `reconbench shapes`: ground-truth clouds and reference meshes.

use std::path::{Path, PathBuf};

use clap::Args;
use reconbench_geom::io::{self, Format};
use reconbench_synth::{
    DatasetSpec, Density, MeshShape, MeshShapeOptions, PerturbSpec, SamplerSpec, ScanSpec, Shape,
    ShapeSpec, from_spec, generate_for_shape, shapes,
};

use super::provenance::{self, Provenance, Source};
use super::{CliError, CliResult, print_json};

/// Arguments of `gen`.
#[derive(Debug, Args)]
pub struct GenArgs {
    /// Shape spec, e.g. `torus`, `torus:R=2,r=0.5`, `wedge:angle=60` (see `reconbench shapes`);
    /// give either a shape or --mesh-input.
    shape: Option<String>,
    /// A mesh file (ply, obj, off, stl, m) as the ground truth instead of a shape: sampled,
    /// scanned, or its own vertices with `--sampler vertices`.
    #[arg(long, value_name = "FILE")]
    mesh_input: Option<PathBuf>,
    /// With --mesh-input: an edge is a sharp feature when its face normals differ by at
    /// least this angle, degrees [default: 30].
    #[arg(long, allow_negative_numbers = true)]
    feature_angle_deg: Option<f64>,
    /// With --mesh-input: declare the ground truth closed or open (default: as measured,
    /// watertight or not).
    #[arg(long, value_name = "true|false")]
    closed: Option<bool>,
    /// Number of points.
    #[arg(long, conflicts_with = "spacing")]
    points: Option<usize>,
    /// Target spacing instead of a count (fraction of the unit bounding-box diagonal).
    #[arg(long)]
    spacing: Option<f64>,
    /// Sampler: uniform | blue-noise | grid[:nu=60,nv=60] | gradient | stripes | vertices
    /// (a mesh's own vertices; then no --points or --spacing).
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
    /// Output file (.ply keeps every attribute and records the provenance in its header;
    /// .xyz keeps positions and normals only).
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
    // Everything is checked before the shape is built or the mesh read.
    match (&a.shape, &a.mesh_input) {
        (Some(_), Some(_)) => {
            return Err(CliError::input(
                "give either a shape or --mesh-input, not both",
            ));
        }
        (None, None) => return Err(CliError::input("give a shape or --mesh-input FILE")),
        (Some(_), None) if a.feature_angle_deg.is_some() || a.closed.is_some() => {
            return Err(CliError::input(
                "--feature-angle-deg and --closed apply to --mesh-input only",
            ));
        }
        (None, Some(_)) if a.mesh => {
            return Err(CliError::input(
                "--mesh writes a shape's reference mesh; it needs a shape, not --mesh-input",
            ));
        }
        _ => {}
    }
    if a.mesh {
        let shape = from_spec(a.shape.as_deref().unwrap_or_default()).map_err(CliError::input)?;
        let mesh = shape.reference_mesh(a.resolution);
        return io::write_mesh(&a.output, &mesh).map_err(CliError::input);
    }
    let format = Format::from_path(&a.output).map_err(CliError::input)?;
    if !format.stores_clouds() {
        return Err(CliError::input(format!(
            "{}: format {format} cannot hold a point cloud; use .ply or .xyz",
            a.output.display()
        )));
    }
    let sampler = a.sampler.parse::<SamplerSpec>().map_err(CliError::input)?;
    let density = match (a.points, a.spacing) {
        (Some(n), _) => Density::Count(n),
        (None, Some(h)) => Density::Spacing(h),
        (None, None) => Density::Count(10_000),
    };
    let vertices = sampler == SamplerSpec::Vertices;
    if vertices && (a.points.is_some() || a.spacing.is_some()) {
        return Err(CliError::input(
            "--sampler vertices takes the mesh's own vertices; drop --points/--spacing",
        ));
    }
    let perturbations: Vec<PerturbSpec> = a
        .noise
        .iter()
        .map(|s| s.parse::<PerturbSpec>())
        .collect::<Result<_, _>>()
        .map_err(CliError::input)?;
    let scan = a
        .scan
        .as_deref()
        .map(str::parse::<ScanSpec>)
        .transpose()
        .map_err(CliError::input)?;

    let (shape, spec_shape, source): (Box<dyn Shape>, ShapeSpec, Source) =
        match (&a.shape, &a.mesh_input) {
            (Some(s), _) => {
                let spec = s.parse::<ShapeSpec>().map_err(CliError::input)?;
                let canonical = provenance::canonical_shape(s).map_err(CliError::input)?;
                let shape = spec.build().map_err(CliError::input)?;
                (shape, spec, Source::Shape { spec: canonical })
            }
            (None, Some(path)) => {
                let (shape, source) = mesh_shape(path, a.feature_angle_deg, a.closed)?;
                // `generate_for_shape` does not use `DatasetSpec::shape`: a placeholder.
                (Box::new(shape), ShapeSpec::named("sphere"), source)
            }
            (None, None) => unreachable!("checked above"),
        };
    let provenance = Provenance {
        source,
        sampler: scan.is_none().then(|| sampler.to_string()),
        points: match density {
            Density::Count(n) if scan.is_none() && !vertices => Some(n),
            _ => None,
        },
        spacing: match density {
            Density::Spacing(h) if scan.is_none() && !vertices => Some(h),
            _ => None,
        },
        perturbations: perturbations.iter().map(ToString::to_string).collect(),
        scan: scan.as_ref().map(ToString::to_string),
        seed: a.seed,
        version: env!("CARGO_PKG_VERSION").to_string(),
    };
    let spec = DatasetSpec {
        shape: spec_shape,
        sampler,
        density,
        perturbations,
        scan,
    };
    let gt = generate_for_shape(shape.as_ref(), &spec, a.seed).map_err(CliError::input)?;
    let cloud = if a.with_clean {
        gt.to_point_cloud_with_clean()
    } else {
        gt.to_point_cloud()
    }
    .map_err(CliError::failure)?;
    io::write_cloud_with_comments(&a.output, &cloud, &[provenance.comment()?])
        .map_err(CliError::input)
}

/// The mesh file as ground truth, and its provenance.
fn mesh_shape(
    path: &Path,
    feature_angle_deg: Option<f64>,
    closed: Option<bool>,
) -> Result<(MeshShape, Source), CliError> {
    let bytes = std::fs::read(path)
        .map_err(|e| CliError::input(format!("cannot read mesh {}: {e}", path.display())))?;
    let format = Format::from_path(path).map_err(CliError::input)?;
    let mesh = io::mesh_from_bytes(&bytes, format, path).map_err(CliError::input)?;
    let opts = MeshShapeOptions {
        feature_angle_deg: feature_angle_deg
            .unwrap_or(MeshShapeOptions::default().feature_angle_deg),
        closed,
    };
    let name = path
        .file_stem()
        .map_or_else(|| "mesh".into(), |s| s.to_string_lossy().into_owned());
    let file = path
        .file_name()
        .map_or_else(|| name.clone(), |s| s.to_string_lossy().into_owned());
    let shape = MeshShape::with_options(&name, mesh, opts)
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    let source = Source::Mesh {
        file,
        hash: io::content_hash(&bytes),
        feature_angle_deg: opts.feature_angle_deg,
        closed,
    };
    Ok((shape, source))
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
