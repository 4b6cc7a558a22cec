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
    /// Check the result exactly (every facet locally Delaunay, adjacency, Euler).
    #[arg(long)]
    validate: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// `reconbench delaunay`.
pub fn delaunay(a: DelaunayArgs) -> CliResult {
    let cloud = io::read_cloud(&a.cloud).map_err(CliError::input)?;
    let dt = Delaunay::new(cloud.positions())
        .map_err(|e| CliError::input(format!("{}: {e}", a.cloud.display())))?;
    if a.validate {
        dt.validate()
            .map_err(|e| CliError::failure(format!("validation failed: {e}")))?;
    }
    if a.json {
        print_json(dt.stats())
    } else {
        println!("{}", dt.stats());
        if a.validate {
            println!("validated: ok");
        }
        Ok(())
    }
}
