//! The point sets of the `hc-it` tests, bench and probe (`crates/recon/tests/hc_it.rs`,
//! `crates/recon/benches/hc_it.rs`, `tools/src/bin/hcit_run.rs`): one definition, so the
//! golden face hashes of the tests and the probe's hashes refer to the same points.

use std::f64::consts::PI;

use glam::DVec3;
use reconbench_synth::{DatasetSpec, Density};

/// A jittered m x m grid (deterministic, irrational offsets) over `[0, 1]^2` lifted by
/// `f`.
pub fn jittered_sheet(m: usize, f: impl Fn(f64, f64) -> f64) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(m * m);
    for i in 0..m {
        for j in 0..m {
            let jx = ((i * 7 + j * 13) as f64 * 0.618_034).fract() - 0.5;
            let jy = ((i * 11 + j * 5) as f64 * 0.414_214).fract() - 0.5;
            let x = (i as f64 + 0.5 + 0.3 * jx) / m as f64;
            let y = (j as f64 + 0.5 + 0.3 * jy) / m as f64;
            out.push(DVec3::new(x, y, f(x, y)));
        }
    }
    out
}

/// The wavy height of the sheets: `0.1 sin(3 x) y`.
pub fn wavy(x: f64, y: f64) -> f64 {
    0.1 * (3.0 * x).sin() * y
}

/// The bench's sheet of about `n` points: [`jittered_sheet`] with m = round(sqrt(n)) and
/// the [`wavy`] height.
pub fn wavy_sheet(n: usize) -> Vec<DVec3> {
    jittered_sheet((n as f64).sqrt().round() as usize, wavy)
}

/// `n` golden-spiral samples of the unit sphere.
pub fn golden_spiral_sphere(n: usize) -> Vec<DVec3> {
    let ga = PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            let phi = ga * i as f64;
            DVec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect()
}

/// The issue-24 noisy height field: the points of `reconbench gen height-field --points
/// n --sampler grid --noise ma-uniform:level=0.3 --seed 1`.
pub fn noisy_height_field(n: usize) -> Vec<DVec3> {
    let spec = DatasetSpec {
        shape: "height-field".parse().expect("shape"),
        sampler: "grid".parse().expect("sampler"),
        density: Density::Count(n),
        perturbations: vec!["ma-uniform:level=0.3".parse().expect("noise")],
        scan: None,
    };
    reconbench_synth::generate(&spec, 1)
        .expect("height field")
        .positions
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheets_and_spheres_have_their_sizes_and_lie_on_their_surfaces() {
        let s = wavy_sheet(100);
        assert_eq!(s.len(), 100);
        assert!(s.iter().all(|p| (p.z - wavy(p.x, p.y)).abs() == 0.0));
        assert!(
            s.iter()
                .all(|p| (0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y))
        );
        let g = golden_spiral_sphere(50);
        assert_eq!(g.len(), 50);
        assert!(g.iter().all(|p| (p.length() - 1.0).abs() < 1e-12));
    }
}
