//! Subcommand definitions and dispatch.

mod datasets;
mod delaunay;
mod eval;
mod harness;
mod info;
mod provenance;
mod synth;

use std::fmt::Display;

use clap::{Parser, Subcommand};

/// A failure with the exit code the process should return.
#[derive(Debug)]
pub struct CliError {
    /// One-line message for stderr.
    pub message: String,
    /// 2 for bad input, 128 + signal for a run stopped by a signal, 1 for anything else.
    pub code: u8,
}

impl CliError {
    /// Bad input: unreadable/malformed files, invalid parameters (exit code 2).
    pub fn input(e: impl Display) -> Self {
        Self {
            message: one_line(e),
            code: 2,
        }
    }

    /// Any other failure (exit code 1).
    pub fn failure(e: impl Display) -> Self {
        Self {
            message: one_line(e),
            code: 1,
        }
    }
}

/// A number for people: integers as integers, 4 significant digits in plain decimal
/// between 1e-4 and 1e7, e-notation outside, `0` for -0.
pub fn num_text(x: f64) -> String {
    if !x.is_finite() {
        return x.to_string();
    }
    let a = x.abs();
    if a == 0.0 {
        return "0".into();
    }
    if x.fract() == 0.0 && a < 1e15 {
        return format!("{x:.0}");
    }
    if (1e-4..1e7).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        return format!("{x:.decimals$}");
    }
    format!("{x:.3e}")
}

/// Collapses a possibly multi-line message into one line.
fn one_line(e: impl Display) -> String {
    e.to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// Result type of the subcommands.
pub type CliResult = Result<(), CliError>;

/// reconbench: reproducible benchmarks for surface reconstruction from point clouds.
#[derive(Debug, Parser)]
#[command(name = "reconbench", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Print counts and the topology report of a mesh or point cloud file.
    #[command(after_help = "Example:\n  reconbench info datasets/real/rocker-arm.ply --json")]
    Info(info::InfoArgs),
    /// Convert between PLY, OBJ, OFF, STL and XYZ/PTS (chosen by extension).
    #[command(
        after_help = "Example:\n  reconbench convert datasets/real/fandisk.ply fandisk.obj\n  reconbench convert fandisk.obj fandisk-ascii.ply --ply-encoding ascii"
    )]
    Convert(info::ConvertArgs),
    /// Generate a ground-truth cloud (positions, GT normals, feature distance, source
    /// ids; its provenance in the PLY header) from a built-in shape or a mesh file, or a
    /// shape's reference mesh.
    #[command(
        after_help = "Examples:\n  reconbench gen torus --points 10000 --noise gaussian:sigma=0.002 --seed 1 -o torus.ply\n  reconbench gen double-torus --mesh --resolution 96 -o ref.ply\n  reconbench gen --mesh-input datasets/real/3holes.ply --sampler vertices -o 3holes-pts.ply"
    )]
    Gen(synth::GenArgs),
    /// List the built-in shapes with genus and sharp-feature summary.
    #[command(after_help = "Example:\n  reconbench shapes --json")]
    Shapes(synth::ShapesArgs),
    /// List the vendored real data sets (datasets/real/) with topology, licence and source.
    #[command(after_help = "Example:\n  reconbench datasets --json")]
    Datasets(datasets::DatasetsArgs),
    /// Build the 3D Delaunay tetrahedralization of a cloud and print its statistics.
    #[command(after_help = "Example:\n  reconbench delaunay torus.ply --json")]
    Delaunay(delaunay::DelaunayArgs),
    /// Distances, topology and quality of a reconstructed mesh against ground truth.
    #[command(
        after_help = "Example:\n  reconbench eval --mesh out.ply --reference torus --input torus.ply --json"
    )]
    Eval(eval::EvalArgs),
    /// Normal errors of a cloud's normals against ground truth.
    #[command(
        after_help = "Example:\n  reconbench eval-normals --cloud est.ply --gt-cloud torus.ply --oriented --json"
    )]
    EvalNormals(eval::EvalNormalsArgs),
    /// Sharp-feature precision/recall/F1 of a labelled cloud against a shape's curves.
    #[command(
        after_help = "Example:\n  reconbench eval-features --cloud labels.ply --reference box --gt-cloud box.ply --json"
    )]
    EvalFeatures(eval::EvalFeaturesArgs),
    /// Experiment harness verbs (run, list, reconstruct, normals, features, ...).
    #[command(flatten)]
    Harness(harness::HarnessCommand),
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> CliResult {
    match cli.command {
        Command::Info(a) => info::info(a),
        Command::Convert(a) => info::convert(a),
        Command::Gen(a) => synth::gen_cmd(a),
        Command::Shapes(a) => synth::shapes_cmd(a),
        Command::Datasets(a) => datasets::datasets(a),
        Command::Delaunay(a) => delaunay::delaunay(a),
        Command::Eval(a) => eval::eval(a),
        Command::EvalNormals(a) => eval::eval_normals(a),
        Command::EvalFeatures(a) => eval::eval_features(a),
        Command::Harness(c) => harness::run(c),
    }
}

/// Prints `value` as pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> CliResult {
    let s = serde_json::to_string_pretty(value).map_err(CliError::failure)?;
    println!("{s}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::num_text;

    #[test]
    fn numbers_read_as_people_write_them() {
        for (x, want) in [
            (0.0, "0"),
            (-0.0, "0"),
            (3000.0, "3000"),
            (0.004567958, "0.004568"),
            (98.4, "98.40"),
            (0.0005261692, "0.0005262"),
            (1234567.8, "1234568"),
            (12345678.9, "1.235e7"),
            (5e-9, "5.000e-9"),
            (2.5, "2.500"),
        ] {
            assert_eq!(num_text(x), want, "{x}");
        }
    }
}
