//! Renders one `priority-front` run on an issue-20 real set beside the reference mesh, to
//! look at its holes, extra pieces and reversed faces (`docs/methods/priority_front.md`,
//! "Real data").
//!
//! `cargo run --release -p reconbench-tools --bin pf_render -- SET THREADS SEED OUT.png
//! [X Y Z RADIUS]`: SET is a name in `datasets/real/` or a `.ply` mesh; with a centre and
//! a radius only faces whose centroid lies within the ball are drawn (both panels).
//! Output faces are coloured 1 (yellow) when they point against the reference normals,
//! 0 otherwise; boundary edges, non-manifold and self-intersecting faces get the
//! renderer's defect colours. Every boundary loop is printed with its centroid and
//! radius, so that a crop can be chosen. `RECON_PARAMS` as in `pf_real_table`.

use glam::DVec3;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_geom::{PointCloud, TriMesh};
use reconbench_harness::render::{Panel, RenderData, Scale, render_comparison};
use reconbench_recon::{PriorityFront, PriorityFrontParams};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 4 && args.len() != 8 {
        eprintln!("usage: pf_render SET THREADS SEED OUT.png [X Y Z RADIUS]");
        std::process::exit(2);
    }
    let path = if args[0].ends_with(".ply") {
        args[0].clone()
    } else {
        format!("datasets/real/{}.ply", args[0])
    };
    let num = |s: &str| -> f64 { s.parse().unwrap_or_else(|_| panic!("not a number: {s}")) };
    let threads = num(&args[1]) as usize;
    let seed = num(&args[2]) as u64;
    let crop = (args.len() == 8).then(|| {
        (
            DVec3::new(num(&args[4]), num(&args[5]), num(&args[6])),
            num(&args[7]),
        )
    });

    let reference = reconbench_geom::io::read_mesh(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let cloud = PointCloud::new(reference.vertices().to_vec()).expect("finite points");
    let mut params = match std::env::var("RECON_PARAMS") {
        Ok(j) => serde_json::from_str(&j).expect("RECON_PARAMS must be a JSON params object"),
        Err(_) => PriorityFrontParams::default(),
    };
    params.threads = threads;
    let rec = PriorityFront::new(params)
        .expect("valid params")
        .reconstruct(&cloud, &mut RunCtx::new(seed))
        .expect("reconstruction");
    print_loops(&rec.mesh);

    let truth = vertex_normals(&reference);
    let v = rec.mesh.vertices();
    let reversed: Vec<f64> = rec
        .mesh
        .faces()
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| v[i as usize]);
            let sum: DVec3 = f.iter().map(|&i| truth[i as usize]).sum();
            f64::from(u8::from((b - a).cross(c - a).dot(sum) < 0.0))
        })
        .collect();
    let (out, out_vals) = cropped(&rec.mesh, &reversed, crop);
    let (refm, ref_vals) = cropped(&reference, &vec![0.0; reference.n_faces()], crop);
    let out_data = RenderData::from_mesh(&out, &[], &out_vals).expect("render data");
    let ref_data = RenderData::from_mesh(&refm, &[], &ref_vals).expect("render data");
    let lines = [format!("{} faces", out.n_faces())];
    let ref_lines = [format!("{} faces", refm.n_faces())];
    let panels = [
        Panel {
            title: "priority-front",
            lines: &lines,
            data: Some(&out_data),
        },
        Panel {
            title: "reference",
            lines: &ref_lines,
            data: Some(&ref_data),
        },
    ];
    let img = render_comparison(
        &format!("{} t{threads} s{seed}", args[0]),
        &panels,
        &Scale::fixed(1.0),
        420,
    )
    .expect("render");
    img.image
        .save_png(std::path::Path::new(&args[3]))
        .expect("write png");
}

/// The faces whose centroid lies in the crop ball (all without a crop), re-indexed.
fn cropped(mesh: &TriMesh, values: &[f64], crop: Option<(DVec3, f64)>) -> (TriMesh, Vec<f64>) {
    let v = mesh.vertices();
    let mut map = vec![u32::MAX; v.len()];
    let (mut verts, mut faces, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for (f, &val) in mesh.faces().iter().zip(values) {
        let c = f.iter().map(|&i| v[i as usize]).sum::<DVec3>() / 3.0;
        if crop.is_some_and(|(p, r)| c.distance(p) > r) {
            continue;
        }
        faces.push(f.map(|i| {
            if map[i as usize] == u32::MAX {
                map[i as usize] = verts.len() as u32;
                verts.push(v[i as usize]);
            }
            map[i as usize]
        }));
        vals.push(val);
    }
    (TriMesh::new(verts, faces).expect("valid crop"), vals)
}

/// Every boundary loop of `mesh` with its edge count, centroid and radius (largest
/// distance of a loop vertex from the centroid).
fn print_loops(mesh: &TriMesh) {
    let v = mesh.vertices();
    let mut count = std::collections::HashMap::<(u32, u32), (u32, u32, u32)>::new();
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let e = count.entry((a.min(b), a.max(b))).or_insert((0, a, b));
            e.0 += 1;
        }
    }
    let mut next = std::collections::HashMap::<u32, u32>::new();
    for &(c, a, b) in count.values() {
        if c == 1 {
            next.insert(b, a);
        }
    }
    let mut seen = std::collections::HashSet::new();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut pts = Vec::new();
        let mut cur = s;
        while seen.insert(cur) {
            pts.push(v[cur as usize]);
            match next.get(&cur) {
                Some(&n) => cur = n,
                None => break,
            }
        }
        let c = pts.iter().sum::<DVec3>() / pts.len() as f64;
        let r = pts.iter().map(|p| p.distance(c)).fold(0.0, f64::max);
        println!(
            "loop {} edges centroid {:.4} {:.4} {:.4} radius {r:.4}",
            pts.len(),
            c.x,
            c.y,
            c.z
        );
    }
}

/// Area-weighted vertex normals of the reference mesh.
fn vertex_normals(mesh: &TriMesh) -> Vec<DVec3> {
    let v = mesh.vertices();
    let mut n = vec![DVec3::ZERO; v.len()];
    for f in mesh.faces() {
        let [a, b, c] = f.map(|i| v[i as usize]);
        let fn_ = (b - a).cross(c - a);
        for &i in f {
            n[i as usize] += fn_;
        }
    }
    n
}
