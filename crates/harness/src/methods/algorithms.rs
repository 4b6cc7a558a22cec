//! Registry entries of the algorithm crates: one line per method. Each method describes
//! itself (name, source, parameter docs, validation) beside its code through
//! [`reconbench_geom::method::Describe`].

use reconbench_features::{GaussMap, GaussMapAdaptive, PcaVariation};
use reconbench_filters::StatisticalOutliers;
use reconbench_filters::{Blend, Mls, MlsSharp};
use reconbench_filters::{EbtThinning, GridThinning, RandomThinning};
use reconbench_normals::{Jet, LvmApprox, PlaneFit, WeightedPlaneFit};
use reconbench_recon::Ebt;
use reconbench_recon::HcIt;
use reconbench_recon::{BallPivoting, Poisson};
use reconbench_recon::{Cocone, PriorityFront, TightCocone, Ufm, UfmMesh};

use crate::entry::{MethodEntry, features, filter, normals, reconstruct};

/// Every algorithm method, in `list` order.
pub fn entries() -> Vec<MethodEntry> {
    vec![
        normals::<PlaneFit>(),
        normals::<WeightedPlaneFit>(),
        normals::<Jet>(),
        normals::<LvmApprox>(),
        normals::<UfmMesh>(),
        features::<GaussMap>(),
        features::<GaussMapAdaptive>(),
        features::<PcaVariation>(),
        filter::<StatisticalOutliers>(),
        filter::<Mls>(),
        filter::<MlsSharp>(),
        filter::<Blend>(),
        filter::<EbtThinning>(),
        filter::<RandomThinning>(),
        filter::<GridThinning>(),
        reconstruct::<PriorityFront>(),
        reconstruct::<Ebt>(),
        reconstruct::<reconbench_recon::ebt::qem::QemSimplified>(),
        reconstruct::<HcIt>(),
        reconstruct::<Ufm>(),
        reconstruct::<Cocone>(),
        reconstruct::<TightCocone>(),
        reconstruct::<BallPivoting>(),
        reconstruct::<Poisson>(),
    ]
}
