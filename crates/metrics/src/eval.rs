//! Entry points the CLI and the harness wrap: one call per command.
//!
//! * `reconbench eval --mesh m.ply --reference R` → [`eval_mesh`]
//! * `reconbench eval-normals --cloud c.ply --reference R` → [`eval_cloud_normals`]
//! * `reconbench eval-features --cloud c.ply --reference R` → [`eval_cloud_features`]
//!
//! Each returns a [`Report`]: `to_json()` for `--json`, `to_row()` for tables.

use reconbench_geom::{PointCloud, TriMesh};
use serde::{Deserialize, Serialize};

use crate::cost::CostReport;
use crate::distance::{DistanceEval, DistanceOptions, eval_distance};
use crate::error::Result;
use crate::features::{
    CleanPositions, FeatureEval, FeatureOptions, MeshFeatureEval, clean_positions,
    detected_from_cloud, eval_features, eval_mesh_features,
};
use crate::quality::{QualityEval, QualityOptions, eval_quality};
use crate::reference::Reference;
use crate::report::{Entries, Report, put, serialize_as_entries};
use crate::topology::{GroundTruthTopology, TopologyEval, TopologyOptions, eval_topology};
use reconbench_geom::method::PhaseTimer;

pub use crate::normals::{NormalGroundTruth, eval_cloud_normals};

/// Options of [`eval_mesh`].
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct MeshEvalOptions {
    /// Distance sampling and sides.
    pub distance: DistanceOptions,
    /// Self-intersection switch.
    pub topology: TopologyOptions,
    /// Edge-length target.
    pub quality: QualityOptions,
    /// Feature angle and radius of the mesh feature recovery (computed when the
    /// reference has counted feature curves). `radius` defaults to the mesh's mean edge
    /// length.
    pub features: FeatureOptions,
    /// Skip the mesh feature recovery.
    pub skip_features: bool,
}

impl MeshEvalOptions {
    /// Checks the options that bound the work (the distance sample counts), so an
    /// experiment file asking for 1e11 samples is refused when it loads.
    pub fn validate(&self) -> Result<()> {
        self.distance.validate()
    }
}

/// Everything [`eval_mesh`] measures.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshEval {
    /// Reference description (shape name or `mesh(F faces)`).
    pub reference: String,
    /// Geometry.
    pub distance: DistanceEval,
    /// Topology against the reference's genus and components.
    pub topology: TopologyEval,
    /// Triangle quality.
    pub quality: QualityEval,
    /// Mesh feature recovery (None when skipped).
    pub features: Option<MeshFeatureEval>,
    /// Wall time per phase of this evaluation.
    pub cost: CostReport,
}

impl Report for MeshEval {
    fn entries(&self) -> Entries {
        let mut e = Entries::new();
        put(&mut e, "reference", self.reference.clone());
        e.extend(self.distance.entries());
        e.extend(self.topology.entries());
        e.extend(self.quality.entries());
        if let Some(f) = &self.features {
            e.extend(f.entries());
        }
        e.extend(
            self.cost
                .entries()
                .into_iter()
                .map(|(k, v)| (format!("eval_{k}"), v)),
        );
        e
    }
}
serialize_as_entries!(MeshEval);

/// Geometry, topology, quality (and feature recovery when the reference has sharp
/// features) of a reconstructed mesh against the ground truth.
pub fn eval_mesh(
    mesh: &TriMesh,
    reference: &Reference,
    opts: &MeshEvalOptions,
) -> Result<MeshEval> {
    let mut timer = PhaseTimer::default();
    let distance = timer.time("distance", || {
        eval_distance(mesh, reference, &opts.distance)
    })?;
    let topology = timer.time("topology", || {
        eval_topology(
            mesh,
            Some(GroundTruthTopology::of(reference)),
            &opts.topology,
        )
    });
    let quality = timer.time("quality", || eval_quality(mesh, &opts.quality));
    let features = if opts.skip_features {
        None
    } else {
        let curves = reference.feature_curves(opts.features.feature_angle_deg);
        Some(timer.time("features", || {
            eval_mesh_features(mesh, reference, &curves, None, &opts.features)
        })?)
    };
    Ok(MeshEval {
        reference: reference.name(),
        distance,
        topology,
        quality,
        features,
        cost: CostReport::from_run_timer(&timer),
    })
}

/// Feature-labelling metrics of a cloud whose label channel (`opts.label_channel`,
/// default `feature`) marks detected points, against the reference's feature curves.
pub fn eval_cloud_features(
    cloud: &PointCloud,
    reference: &Reference,
    clean: CleanPositions,
    opts: &FeatureOptions,
) -> Result<FeatureEval> {
    let detected = detected_from_cloud(cloud, &opts.label_channel)?;
    let clean = clean_positions(cloud, clean)?;
    let curves = reference.feature_curves(opts.feature_angle_deg);
    eval_features(
        cloud.positions(),
        &clean,
        &detected,
        &curves,
        reference.diagonal(),
        opts,
    )
}
