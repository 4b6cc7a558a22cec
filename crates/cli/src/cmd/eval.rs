//! `reconbench eval`, `eval-normals` and `eval-features`: metrics of one output against
//! ground truth (keys and formulas in docs/METRICS.md).

use std::path::PathBuf;

use clap::Args;
use reconbench_geom::io;
use reconbench_metrics::{
    CleanPositions, FeatureOptions, MeshEvalOptions, NormalGroundTruth, NormalOptions, Reference,
    Report, Value, eval_cloud_features, eval_cloud_normals, eval_mesh,
};

use super::{CliError, CliResult, provenance};

/// Arguments of `eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Reconstructed mesh.
    #[arg(long)]
    mesh: PathBuf,
    /// Ground truth: a shape spec (`torus`, `box`, ...) or a mesh file.
    #[arg(long)]
    reference: String,
    /// The cloud the mesh was reconstructed from: if `reconbench gen` recorded its
    /// provenance, it must match --reference.
    #[arg(long, value_name = "CLOUD")]
    input: Option<PathBuf>,
    /// Minimum number of area-uniform samples per side (default 100000; at least
    /// 10 x faces are taken).
    #[arg(long)]
    samples: Option<usize>,
    /// Sampling seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Also count self-intersecting face pairs.
    #[arg(long)]
    self_intersections: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Arguments of `eval-normals`.
#[derive(Debug, Args)]
pub struct EvalNormalsArgs {
    /// Cloud with estimated normals (nx ny nz).
    #[arg(long)]
    cloud: PathBuf,
    /// Ground truth: a shape spec or a mesh file (normal at the closest point), used
    /// when --gt-cloud is not given.
    #[arg(long)]
    reference: Option<String>,
    /// The cloud written by `reconbench gen`: GT normals at each point's source sample
    /// (its recorded provenance must match --reference when both are given).
    #[arg(long)]
    gt_cloud: Option<PathBuf>,
    /// Also report oriented errors and the flip rate.
    #[arg(long)]
    oriented: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Arguments of `eval-features`.
#[derive(Debug, Args)]
pub struct EvalFeaturesArgs {
    /// Cloud with a `feature` label channel (nonzero = detected).
    #[arg(long)]
    cloud: PathBuf,
    /// Ground truth: a shape spec (feature curves come from the shape).
    #[arg(long)]
    reference: String,
    /// The cloud written by `reconbench gen` (clean positions through source ids; its
    /// recorded provenance must match --reference); without it the cloud's
    /// clean_x/y/z channels, else its own positions, are used.
    #[arg(long)]
    gt_cloud: Option<PathBuf>,
    /// A curve counts when its normal deviation is at least this (degrees).
    #[arg(long, default_value_t = 20.0)]
    feature_angle: f64,
    /// Radius r as a multiple of the mean spacing.
    #[arg(long, default_value_t = 1.0)]
    radius_factor: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

fn print_report(r: &impl Report, json: bool) -> CliResult {
    if json {
        return super::print_json(&r.to_json());
    }
    let entries = r.entries();
    let text = |v: &Value| match v {
        Value::Bool(b) => b.to_string(),
        Value::Int(i) => i.to_string(),
        Value::Num(x) => super::num_text(*x),
        Value::Text(t) => t.clone(),
        Value::Null => "-".into(),
    };
    let abs_of = |k: &str| {
        let want = format!("{k}_abs");
        entries.iter().find(|(n, _)| *n == want).map(|(_, v)| v)
    };
    for (k, v) in &entries {
        match k.strip_suffix("_abs") {
            // Shown next to its relative value.
            Some(rel) if entries.iter().any(|(n, _)| n == rel) => continue,
            Some(_) => println!("{k:<28} {} (input units)", text(v)),
            None => match abs_of(k) {
                Some(a) => println!("{k:<28} {} x diagonal = {} (input units)", text(v), text(a)),
                None => println!("{k:<28} {}", text(v)),
            },
        }
    }
    Ok(())
}

/// An evaluation error (bad input, exit code 2) prefixed with the file it concerns.
fn on_file(path: &std::path::Path, e: impl std::fmt::Display) -> CliError {
    let shown = reconbench_geom::error::escape_control(&path.to_string_lossy()).into_owned();
    CliError::input(format!("{shown}: {e}"))
}

/// `reconbench eval`.
pub fn eval(a: EvalArgs) -> CliResult {
    if let Some(input) = &a.input {
        provenance::check(input, &a.reference)?;
    }
    let mesh = io::read_mesh(&a.mesh).map_err(CliError::input)?;
    let reference = Reference::from_arg(&a.reference).map_err(CliError::input)?;
    let mut opts = MeshEvalOptions::default();
    if let Some(n) = a.samples {
        opts.distance.min_samples = n;
    }
    opts.distance.seed = a.seed;
    opts.topology.self_intersections = a.self_intersections;
    let e = eval_mesh(&mesh, &reference, &opts).map_err(|e| on_file(&a.mesh, e))?;
    print_report(&e, a.json)
}

/// `reconbench eval-normals`.
pub fn eval_normals(a: EvalNormalsArgs) -> CliResult {
    if let (Some(g), Some(r)) = (&a.gt_cloud, &a.reference) {
        provenance::check(g, r)?;
    }
    let cloud = io::read_cloud(&a.cloud).map_err(CliError::input)?;
    let opts = NormalOptions {
        oriented: a.oriented,
    };
    let e = match (&a.gt_cloud, &a.reference) {
        (Some(g), _) => {
            let gt = io::read_cloud(g).map_err(CliError::input)?;
            eval_cloud_normals(&cloud, NormalGroundTruth::SourceSamples(&gt), &opts)
        }
        (None, Some(r)) => {
            let reference = Reference::from_arg(r).map_err(CliError::input)?;
            eval_cloud_normals(&cloud, NormalGroundTruth::ClosestPoint(&reference), &opts)
        }
        (None, None) => {
            return Err(CliError::input(
                "eval-normals needs --gt-cloud or --reference",
            ));
        }
    }
    .map_err(|e| on_file(&a.cloud, e))?;
    print_report(&e, a.json)
}

/// `reconbench eval-features`.
pub fn eval_features(a: EvalFeaturesArgs) -> CliResult {
    if let Some(g) = &a.gt_cloud {
        provenance::check(g, &a.reference)?;
    }
    let cloud = io::read_cloud(&a.cloud).map_err(CliError::input)?;
    let reference = Reference::from_arg(&a.reference).map_err(CliError::input)?;
    let gt = a
        .gt_cloud
        .as_ref()
        .map(io::read_cloud)
        .transpose()
        .map_err(CliError::input)?;
    let clean = match &gt {
        Some(g) => CleanPositions::SourceSamples(g),
        None if cloud.channel("clean_x").is_some() => CleanPositions::Channels,
        None => CleanPositions::Observed,
    };
    let opts = FeatureOptions {
        feature_angle_deg: a.feature_angle,
        radius_factor: a.radius_factor,
        ..FeatureOptions::default()
    };
    let e =
        eval_cloud_features(&cloud, &reference, clean, &opts).map_err(|e| on_file(&a.cloud, e))?;
    print_report(&e, a.json)
}
