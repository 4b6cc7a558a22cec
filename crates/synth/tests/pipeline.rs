//! Samplers, perturbations, scanner and the dataset glue.

use glam::DVec3;
use reconbench_geom::{PointIndex, io};
use reconbench_synth::perturb::parse_list;
use reconbench_synth::shapes::{MeshShape, from_spec};
use reconbench_synth::{
    DatasetSpec, Density, PerturbSpec, SamplerSpec, ScanSpec, ShapeSpec, generate,
    generate_for_shape,
};

fn spec(shape: &str, n: usize, sampler: &str, noise: &str) -> DatasetSpec {
    DatasetSpec {
        shape: shape.parse().unwrap(),
        sampler: sampler.parse().unwrap(),
        density: Density::Count(n),
        perturbations: parse_list(noise).unwrap(),
        scan: None,
    }
}

#[test]
fn gaussian_noise_std_is_reproduced_on_100k_points() {
    for (noise, sigma, along_normal) in [
        ("gaussian:sigma=0.005", 0.005, false),
        ("normal-gaussian:sigma=0.01", 0.01, true),
        ("gaussian:sigma=0.002,rel=radius", 0.001, false),
    ] {
        let gt = generate(&spec("sphere", 100_000, "uniform", noise), 1).unwrap();
        let d: Vec<DVec3> = gt
            .positions
            .iter()
            .zip(&gt.clean_positions)
            .map(|(p, c)| *p - *c)
            .collect();
        let (var, k) = if along_normal {
            let v: f64 = d
                .iter()
                .zip(&gt.normals)
                .map(|(x, n)| x.dot(*n).powi(2))
                .sum::<f64>();
            (v / d.len() as f64, 1.0)
        } else {
            (
                d.iter().map(|x| x.length_squared()).sum::<f64>() / (3 * d.len()) as f64,
                3.0,
            )
        };
        let std = var.sqrt();
        assert!(
            (std / sigma - 1.0).abs() < 0.02,
            "{noise}: std {std} vs {sigma} ({k})"
        );
    }
}

#[test]
fn ball_and_ma_uniform_noise_have_the_right_magnitude() {
    let gt = generate(&spec("torus", 20_000, "uniform", "ball:radius=0.01"), 2).unwrap();
    let r: Vec<f64> = gt
        .positions
        .iter()
        .zip(&gt.clean_positions)
        .map(|(p, c)| (*p - *c).length())
        .collect();
    assert!(r.iter().all(|&x| x <= 0.01 + 1e-15));
    // E|x| for a uniform ball of radius R is 3R/4.
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    assert!((mean / 0.0075 - 1.0).abs() < 0.02, "{mean}");

    let gt = generate(&spec("torus", 10_000, "uniform", "ma-uniform:level=0.2"), 3).unwrap();
    let idx = PointIndex::new(&gt.clean_positions).unwrap();
    let t = idx.knn_all(10, true).unwrap();
    for i in (0..gt.len()).step_by(97) {
        let s = t.dist2(i).iter().map(|d| d.sqrt()).sum::<f64>() / 10.0;
        let d = gt.positions[i] - gt.clean_positions[i];
        assert!(d.abs().max_element() <= 0.2 * s + 1e-15);
    }
}

#[test]
fn outliers_decimation_duplicates_keep_ground_truth_consistent() {
    let gt = generate(
        &spec("box", 10_000, "uniform", "decimate:keep=0.5;duplicate:fraction=0.02;outliers:fraction=0.1;holes:count=3,radius=0.05"),
        4,
    )
    .unwrap();
    let n_out = gt.is_outlier.iter().filter(|&&o| o).count();
    assert_eq!(n_out, 510);
    for i in 0..gt.len() {
        if gt.is_outlier[i] {
            assert_eq!(gt.source_ids[i], u32::MAX);
            assert_eq!(gt.normals[i], DVec3::ZERO);
        } else {
            assert!(gt.source_ids[i] < 10_000);
            assert_eq!(gt.positions[i], gt.clean_positions[i]);
        }
    }
    let c = gt.to_point_cloud().unwrap();
    assert_eq!(c.len(), gt.len());
    assert!(c.channel("is_outlier").is_some() && c.channel("feature_distance").is_some());
    let holes_only = generate(
        &spec("box", 10_000, "uniform", "holes:count=3,radius=0.05"),
        4,
    )
    .unwrap();
    assert!(holes_only.len() < 10_000 && holes_only.len() > 9_000);
}

#[test]
fn same_seed_gives_identical_bytes() {
    let s = spec(
        "torus",
        3_000,
        "blue-noise",
        "gaussian:sigma=0.003;outliers:fraction=0.05;misalign:angle=1,shift=0.01",
    );
    let dir = tempfile::tempdir().unwrap();
    let write = |seed: u64, name: &str| {
        let path = dir.path().join(name);
        io::write_cloud(
            &path,
            &generate(&s, seed).unwrap().to_point_cloud().unwrap(),
        )
        .unwrap();
        std::fs::read(path).unwrap()
    };
    let a = write(42, "a.ply");
    assert_eq!(a, write(42, "b.ply"));
    assert_ne!(a, write(43, "c.ply"));
    // Also through a scan, whose rays run in parallel.
    let mut sc = spec("cone", 0, "uniform", "gaussian:sigma=0.001");
    sc.scan = Some("views=3,res=24,noise=0.001,misalign=0.5".parse().unwrap());
    assert_eq!(generate(&sc, 7).unwrap(), generate(&sc, 7).unwrap());
}

#[test]
fn blue_noise_is_more_regular_than_uniform() {
    let nn = |sampler: &str| {
        let gt = generate(&spec("sphere", 4_000, sampler, ""), 5).unwrap();
        let idx = PointIndex::new(&gt.positions).unwrap();
        let t = idx.knn_all(1, true).unwrap();
        let d: Vec<f64> = (0..gt.len()).map(|i| t.dist2(i)[0].sqrt()).collect();
        (
            d.iter().cloned().fold(f64::INFINITY, f64::min),
            d.iter().sum::<f64>() / d.len() as f64,
            gt.len(),
        )
    };
    let (umin, umean, _) = nn("uniform");
    let (bmin, bmean, n) = nn("blue-noise");
    assert_eq!(n, 4_000);
    assert!(bmin > 5.0 * umin, "{bmin} vs {umin}");
    assert!(bmean > 1.3 * umean, "{bmean} vs {umean}");
    assert!(bmin > 0.5 * bmean, "{bmin} {bmean}");
}

#[test]
fn density_variants_are_denser_where_requested() {
    let gt = generate(&spec("box", 20_000, "gradient:min=0.1,axis=0", ""), 6).unwrap();
    let hi = gt.positions.iter().filter(|p| p.x > 0.0).count();
    assert!(hi as f64 > 1.5 * (gt.len() - hi) as f64, "{hi}");
    let gt = generate(
        &spec("box", 20_000, "stripes:count=4,min=0.2,axis=2", ""),
        6,
    )
    .unwrap();
    assert_eq!(gt.len(), 20_000);
    let grid = generate(&spec("torus", 3_600, "grid", ""), 0).unwrap();
    assert_eq!(grid.len(), 3_600);
    let cube = generate(&spec("box", 866, "grid", ""), 0).unwrap();
    assert_eq!(cube.len(), 866);
    let sp = DatasetSpec {
        density: Density::Spacing(0.02),
        ..spec("sphere", 0, "uniform", "")
    };
    let n = generate(&sp, 0).unwrap().len();
    let expect = from_spec("sphere").unwrap().area() / 0.0004;
    assert!((n as f64 - expect).abs() <= 1.0);
}

#[test]
fn specs_parse_print_and_serialise() {
    for s in [
        "gaussian:sigma=0.005,rel=diagonal",
        "ball:radius=0.01,rel=radius",
        "ma-uniform:level=0.1,k=10",
        "outliers:fraction=0.1,inflate=0.1",
        "copies:fraction=0.003,min=0.01,max=0.1",
        "decimate:keep=0.5",
        "holes:count=5,radius=0.05,rel=diagonal",
        "duplicate:fraction=0.02",
        "misalign:groups=4,angle=1,shift=0.01,rel=diagonal",
    ] {
        let p: PerturbSpec = s.parse().unwrap();
        assert_eq!(p.to_string(), s);
        assert_eq!(p.to_string().parse::<PerturbSpec>().unwrap(), p);
    }
    for s in [
        "uniform",
        "blue-noise:oversample=5",
        "grid:nu=60,nv=60",
        "gradient:min=0.1,axis=0",
        "stripes:count=5,min=0.1,axis=0",
    ] {
        let p: SamplerSpec = s.parse().unwrap();
        assert_eq!(p.to_string(), s);
    }
    let e = "gauss:sigma=1"
        .parse::<PerturbSpec>()
        .unwrap_err()
        .to_string();
    assert!(e.contains("gaussian") && e.contains("ma-uniform"), "{e}");
    let e = "gaussian:sigma=1,foo=2"
        .parse::<PerturbSpec>()
        .unwrap_err()
        .to_string();
    assert!(e.contains("sigma"), "{e}");
    let sc: ScanSpec = "views=3,res=64".parse().unwrap();
    assert_eq!(sc.to_string().parse::<ScanSpec>().unwrap(), sc);
    let ds = DatasetSpec::uniform(ShapeSpec::named("torus"), 100);
    let _ = format!("{ds:?}");
}

#[test]
fn scanner_sees_the_front_and_respects_occlusion() {
    let sphere = from_spec("sphere").unwrap();
    let sc = ScanSpec {
        viewpoints: Some(vec![[0.0, 0.0, 2.0]]),
        resolution: 64,
        fov_deg: 20.0,
        grazing_deg: 85.0,
        ..Default::default()
    };
    let gt = reconbench_synth::scanner::scan(sphere.as_ref(), &sc, 1).unwrap();
    assert!(gt.len() > 1000);
    for i in 0..gt.len() {
        let p = gt.positions[i];
        assert!(p.z > 0.0, "occluded back side seen at {p}");
        assert!(sphere.distance(p) < 1e-11);
        let to_cam = (DVec3::new(0.0, 0.0, 2.0) - p).normalize();
        assert!((gt.view_dirs.as_ref().unwrap()[i] - to_cam).length() < 1e-9);
        assert!(gt.normals[i].dot(to_cam) > 85f64.to_radians().cos() - 1e-12);
    }
    // Range noise is along the ray.
    let noisy = reconbench_synth::scanner::scan(
        sphere.as_ref(),
        &ScanSpec {
            noise: 0.001,
            ..sc.clone()
        },
        1,
    )
    .unwrap();
    for i in 0..noisy.len() {
        let d = noisy.positions[i] - noisy.clean_positions[i];
        assert!(d.cross(noisy.view_dirs.as_ref().unwrap()[i]).length() < 1e-12);
    }
}

#[test]
fn scanner_works_on_every_shape_and_on_meshes() {
    for d in reconbench_synth::shapes::definitions() {
        let mut s = spec(d.name, 0, "uniform", "");
        s.scan = Some("views=4,res=20".parse().unwrap());
        let gt = generate(&s, 9).unwrap();
        let built = from_spec(d.name).unwrap();
        // A blend shape's scan is of its part (without the designed tube).
        let shape = built.scanned_part().unwrap_or(built.as_ref());
        assert!(gt.len() > 50, "{}: {}", d.name, gt.len());
        for p in &gt.positions {
            assert!(
                shape.distance(*p) < 1e-10,
                "{}: {}",
                d.name,
                shape.distance(*p)
            );
        }
        // Every view sees a closed shape; an open sheet (the thin twisted blade) can be
        // edge-on to one of the four views.
        let views = gt.scan_ids.as_ref().unwrap().iter().max().copied();
        if shape.info().closed {
            assert_eq!(views, Some(3), "{}: every view sees the shape", d.name);
        } else {
            assert!(views >= Some(2), "{}: {views:?}", d.name);
        }
    }
    let torus = from_spec("torus").unwrap();
    let mesh = MeshShape::new("torus-mesh", torus.reference_mesh(48)).unwrap();
    let mut s = spec("torus", 0, "uniform", "");
    s.scan = Some("views=4,res=32".parse().unwrap());
    let gt = generate_for_shape(&mesh, &s, 1).unwrap();
    assert!(gt.len() > 500);
    for p in &gt.positions {
        assert!(torus.distance(*p) < 5e-3);
    }
    use reconbench_synth::Shape;
    assert_eq!(mesh.genus(), 1);
    assert!(mesh.is_inside(DVec3::new(torus.aabb().max.x * 0.8, 0.0, 0.0)));
    assert!(!mesh.is_inside(DVec3::ZERO));
}
