//! `reconbench delaunay`: 3D Delaunay tetrahedralization statistics of a cloud.

use std::path::PathBuf;

use clap::Args;
use reconbench_delaunay::Delaunay;
use reconbench_geom::io;

use super::{CliError, CliResult, print_json};

/// Arguments of `delaunay`.
#[derive(Debug, Args)]
pub struct DelaunayArgs {
    /// Point cloud (or mesh: its vertices are used).
    cloud: PathBuf,
    /// Check the result exactly (every facet locally Delaunay, adjacency, Euler) also
    /// above 200,000 points (it is the default up to that size).
    #[arg(long, conflicts_with = "no_validate")]
    validate: bool,
    /// Skip the exact check that runs by default on up to 200,000 points.
    #[arg(long)]
    no_validate: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Largest input validated by default (validation is exact and parallel, a few seconds
/// per million points): a wrong triangulation must not be reported with normal-looking
/// statistics.
const VALIDATE_DEFAULT_MAX: usize = 200_000;

/// `reconbench delaunay`.
pub fn delaunay(a: DelaunayArgs) -> CliResult {
    let cloud = io::read_cloud(&a.cloud).map_err(CliError::input)?;
    let dt = Delaunay::new(cloud.positions())
        .map_err(|e| CliError::input(format!("{}: {e}", a.cloud.display())))?;
    let validate = a.validate || (!a.no_validate && cloud.len() <= VALIDATE_DEFAULT_MAX);
    if validate {
        dt.validate().map_err(|e| {
            CliError::failure(format!("{}: validation failed: {e}", a.cloud.display()))
        })?;
    }
    if a.json {
        print_json(dt.stats())
    } else {
        println!("{}", dt.stats());
        if validate {
            println!("validated: ok");
        }
        Ok(())
    }
}
