use glam::DVec3;
use reconbench_synth::shapes::{definitions, from_spec};
#[test]
fn probe() {
    let s = from_spec("double-torus").unwrap();
    let q = DVec3::new(0.0, 0.0, -0.04834);
    let c = s.closest_point(q);
    println!("scale {} q {:?} -> {:?}", s.scale(), q / s.scale(), c);
    for d in definitions() {
        let s = from_spec(d.name).unwrap();
        let m = s.reference_mesh(48);
        let mut worst = (0.0f64, DVec3::ZERO);
        for &v in m.vertices() {
            let e = s.distance(v);
            if e > worst.0 {
                worst = (e, v);
            }
        }
        println!(
            "{:16} worst vertex dist {:e} at {:?} (natural {:?})",
            d.name,
            worst.0,
            worst.1,
            worst.1 / s.scale()
        );
    }
}
