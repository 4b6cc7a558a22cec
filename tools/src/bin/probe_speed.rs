//! Diagnostic probe (not part of the API): single-thread cost of the clustering step on
//! real neighbourhoods (a 3000-point torus, k = 20, sigma 0.1 and 0.6), old and new
//! paths interleaved in one process so the ratio is robust to machine load:
//! (a) full matrix with the `atan2` small-angle branch + cut (the previous version),
//! (b) full matrix with the series `asin` branch + cut, (c) `count_big` (components).
//!
//! `cargo run --release -p reconbench-tools --bin probe_speed`

use std::time::Instant;

use glam::DVec3;
use reconbench_features::AverageLinkage;
use reconbench_geom::spatial::PointIndex;

fn old_distance(a: DVec3, b: DVec3) -> f64 {
    let c = a.dot(b).abs();
    if c < 0.99 {
        c.acos()
    } else {
        a.cross(b).length().atan2(c)
    }
}

fn main() {
    let n = 3000;
    let mut pts = Vec::new();
    let mut s = 1u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    while pts.len() < n {
        let (u, v, w) = (
            rnd() * std::f64::consts::TAU,
            rnd() * std::f64::consts::TAU,
            rnd(),
        );
        if w * 3.0 <= 2.0 + v.cos() {
            let r = 2.0 + v.cos();
            pts.push(DVec3::new(r * u.cos(), r * u.sin(), v.sin()));
        }
    }
    let boxed = std::env::args().any(|a| a == "box");
    let k = if boxed { 16 } else { 20 };
    if boxed {
        // Random unit-box surface points within 0.03 of an edge (the clustered ones).
        pts.clear();
        while pts.len() < 30000 {
            let (f, u, v) = ((rnd() * 6.0) as usize, rnd(), rnd());
            let w = if f >= 3 { 1.0 } else { 0.0 };
            pts.push(match f % 3 {
                0 => DVec3::new(w, u, v),
                1 => DVec3::new(u, w, v),
                _ => DVec3::new(u, v, w),
            });
        }
    }
    let near_edge = |p: DVec3| {
        let d = |x: f64| x.min(1.0 - x);
        let mut e = [d(p.x), d(p.y), d(p.z)];
        e.sort_by(f64::total_cmp);
        e[1] < 0.01
    };
    let table = PointIndex::new(&pts).unwrap().knn_all(k, true).unwrap();
    let chosen: Vec<usize> = (0..pts.len())
        .filter(|&i| !boxed || near_edge(pts[i]))
        .take(n)
        .collect();
    let n = chosen.len();
    let sets: Vec<Vec<DVec3>> = chosen
        .iter()
        .map(|&i| {
            let nb: Vec<DVec3> = table
                .indices(i)
                .iter()
                .map(|&j| pts[j as usize] - pts[i])
                .collect();
            let mut l = Vec::new();
            for a in 0..nb.len() {
                for b in a + 1..nb.len() {
                    let c = nb[a].cross(nb[b]);
                    if c.length() > 1e-6 * nb[a].length() * nb[b].length() {
                        l.push(c.normalize());
                    }
                }
            }
            l
        })
        .collect();
    let mut ws = AverageLinkage::new();
    for sigma in [0.1, 0.6] {
        let min_size = if boxed { 12 } else { 19 };
        let (mut ta, mut tb, mut tc) = (0.0, 0.0, 0.0);
        let mut agree = true;
        for _rep in 0..3 {
            // (a) old distance: fill a matrix the way `load` does, then time a cut via
            // `load` (to keep the API) is impossible, so time the old matrix fill alone
            // and add the cut time measured in (b).
            let t = Instant::now();
            let mut sink = 0.0;
            for l in &sets {
                for i in 0..l.len() {
                    for j in i + 1..l.len() {
                        sink += old_distance(l[i], l[j]);
                    }
                }
            }
            ta += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let mut sink2 = 0.0;
            for l in &sets {
                for i in 0..l.len() {
                    for j in i + 1..l.len() {
                        sink2 += reconbench_features::line_distance(l[i], l[j]);
                    }
                }
            }
            let fill_new = t.elapsed().as_secs_f64();
            assert!((sink - sink2).abs() < 1e-9 * sink.abs().max(1.0));
            let t = Instant::now();
            let mut big_b = Vec::new();
            for l in &sets {
                ws.load(l);
                big_b.push(
                    ws.cut(sigma)
                        .iter()
                        .filter(|&&s| s as usize >= min_size)
                        .count(),
                );
            }
            let full = t.elapsed().as_secs_f64();
            tb += full;
            ta += full - fill_new;
            let t = Instant::now();
            let big_c: Vec<usize> = sets
                .iter()
                .map(|l| ws.count_big(l, sigma, min_size))
                .collect();
            tc += t.elapsed().as_secs_f64();
            agree &= big_b == big_c;
        }
        println!(
            "sigma {sigma}: {n} neighbourhoods (L ~ {}), per neighbourhood: old matrix + cut {:.1} us, series asin + cut {:.1} us, count_big {:.1} us; ratios old/new {:.2}, old/count_big {:.2}; identical counts {agree}",
            sets[0].len(),
            1e6 * ta / (3.0 * n as f64),
            1e6 * tb / (3.0 * n as f64),
            1e6 * tc / (3.0 * n as f64),
            ta / tb,
            ta / tc
        );
    }
}
