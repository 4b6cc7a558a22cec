//! Timing of one construction: `cargo run --release -p reconbench-tools --bin
//! dt_bench -- <kind> <n> [--validate]` with kind in uniform, torus, sphere, isphere,
//! grid, cubegrid, intcube, cubegrid2; `--queries` times the facet/incidence/Gabriel
//! queries.

use std::time::Instant;

use reconbench_delaunay::Delaunay;
use reconbench_testkit::points as samples;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = args.get(1).map_or("uniform", String::as_str);
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let validate = args.iter().any(|a| a == "--validate");
    let pts = match kind {
        "uniform" => samples::uniform_cube(n, 2),
        "torus" => samples::torus_surface(n, 1),
        "sphere" => samples::sphere(n, 3),
        "isphere" => samples::integer_sphere(n as i64),
        "grid" => samples::grid(n, 1.0),
        "cubegrid" => samples::cube_surface_grid(n),
        // n random points with integer coordinates in 0..20: duplicates and
        // degeneracies everywhere.
        "intcube" => samples::uniform_cube(n, 4)
            .iter()
            .map(|p| (*p * 20.0).floor())
            .collect(),
        // Cube-surface grid with spacing 1/n plus all its points again, shuffled by the
        // BRIO order: duplicates on degenerate input.
        "cubegrid2" => {
            let mut p = samples::cube_surface_grid(n);
            p.extend(samples::cube_surface_grid(n));
            p
        }
        _ => panic!("unknown kind {kind}"),
    };
    let t = Instant::now();
    let c0 = cpu_seconds();
    let dt = Delaunay::new(&pts).expect("triangulation");
    let el = t.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - c0;
    println!(
        "{kind} {} points: {el:.3} s wall, {cpu:.2} s CPU of the calling thread",
        pts.len()
    );
    println!("{}", dt.stats());
    if args.iter().any(|a| a == "--queries") {
        let t = Instant::now();
        let nf = dt.facets().len();
        let t_f = t.elapsed().as_secs_f64();
        let _ = dt.facets_of_vertex(0);
        let t_vf = t.elapsed().as_secs_f64();
        let _ = dt.edges_of_vertex(0);
        let t_ve = t.elapsed().as_secs_f64();
        let g = dt.gabriel_flags().iter().filter(|&&b| b).count();
        let t_g = t.elapsed().as_secs_f64();
        println!(
            "queries: facets {nf} in {t_f:.3} s, +vertex->facets {:.3} s, +edges {:.3} s, \
             +gabriel ({g} Gabriel) {:.3} s",
            t_vf - t_f,
            t_ve - t_vf,
            t_g - t_ve
        );
    }
    if validate {
        let t = Instant::now();
        dt.validate().expect("valid");
        println!("valid ({:.2} s)", t.elapsed().as_secs_f64());
    }
}

/// User + system CPU time of the calling thread (Linux; 0 elsewhere), to compare runs on
/// a loaded machine.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/thread-self/stat") else {
        return 0.0;
    };
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok()).unwrap_or(0.0);
    // Fields 14 and 15 of stat (utime, stime) are at 11 and 12 after the ')'.
    (ticks(11) + ticks(12)) / 100.0
}
