//! Requests that would need more memory than a machine has are refused before anything
//! is allocated, with the estimate in the message (issue 28): sample counts, grid
//! sizes, and points added per input point by perturbations.

use reconbench_synth::sampler::MAX_SAMPLES;
use reconbench_synth::{Density, PerturbSpec, SamplerSpec, from_spec};

#[test]
fn a_grid_of_more_nodes_than_the_limit_is_refused_when_parsed() {
    let e = "grid:nu=1000000,nv=1000000"
        .parse::<SamplerSpec>()
        .unwrap_err()
        .to_string();
    assert!(e.contains("1000000 x 1000000 grid"), "{e}");
    assert!(e.contains("TB"), "{e}");
    let e = "grid:nu=20000"
        .parse::<SamplerSpec>()
        .unwrap_err()
        .to_string();
    assert!(e.contains("20000 x 20000"), "{e}");
    assert!("grid:nu=0".parse::<SamplerSpec>().is_err());
    // At the limit and below it is fine.
    assert!("grid:nu=10000,nv=10000".parse::<SamplerSpec>().is_ok());
    assert!("grid:nu=60,nv=60".parse::<SamplerSpec>().is_ok());
}

#[test]
fn a_point_count_above_the_limit_is_refused_with_its_memory() {
    let s = from_spec("sphere").unwrap();
    let s = s.as_ref();
    assert_eq!(Density::Count(1000).count(s).unwrap(), 1000);
    let e = Density::Count(1_000_000_000_000)
        .count(s)
        .unwrap_err()
        .to_string();
    assert!(e.contains("about 84 TB"), "{e}");
    assert!(Density::Count(MAX_SAMPLES + 1).count(s).is_err());
    // A spacing so fine that the count explodes is refused the same way.
    let e = Density::Spacing(1e-9).count(s).unwrap_err().to_string();
    assert!(e.contains("at most"), "{e}");
}

#[test]
fn perturbations_add_a_bounded_number_of_points_per_point() {
    for spec in [
        "duplicate:fraction=1e9",
        "outliers:fraction=1000",
        "copies:fraction=101",
    ] {
        let e = spec.parse::<PerturbSpec>().unwrap_err().to_string();
        assert!(e.contains("points added per input point"), "{spec}: {e}");
    }
    for spec in [
        "duplicate:fraction=2",
        "outliers:fraction=0.05",
        "copies:fraction=100",
    ] {
        assert!(spec.parse::<PerturbSpec>().is_ok(), "{spec}");
    }
}
