//! Geometric multigrid for the screened Poisson system: V-cycles over the grid levels
//! `2^2 .. 2^depth` cells per side, eight-colour Gauss-Seidel smoothing, full-weighting
//! restriction and trilinear prolongation (its transpose), the coarse operators
//! rediscretised with the Galerkin weights of [`Level`].

use rayon::prelude::*;
use reconbench_geom::method::MethodError;

use super::screened::Level;

/// Gauss-Seidel sweeps on the coarsest level (5^3 nodes: cheap, and enough to solve it).
const COARSEST_SWEEPS: usize = 30;

/// Outcome of [`solve`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct SolveStats {
    /// V-cycles run on the finest level (the full-multigrid start counts as one).
    pub cycles: usize,
    /// Final relative residual `|b - A x| / |b|` on the finest level.
    pub relative_residual: f64,
}

/// 1D prolongation weights of fine node `f` from coarse nodes: `(coarse, weight)`
/// pairs (one for even `f`, two for odd).
#[inline]
fn parents(f: usize) -> ([usize; 2], [f32; 2], usize) {
    if f.is_multiple_of(2) {
        ([f / 2, 0], [1.0, 0.0], 1)
    } else {
        ([f / 2, f / 2 + 1], [0.5, 0.5], 2)
    }
}

/// `coarse.b = P^T fine.r` (full weighting, unnormalised: `P^T` is the adjoint of the
/// trilinear prolongation, as the Galerkin weights of [`Level`] assume).
fn restrict(fine: &Level, coarse: &mut Level) {
    let (nf, nc) = (fine.n, coarse.n);
    let r = &fine.r;
    coarse
        .b
        .par_chunks_mut(nc * nc)
        .enumerate()
        .for_each(|(kc, plane)| {
            for jc in 0..nc {
                for ic in 0..nc {
                    let mut s = 0.0f32;
                    for dz in -1i64..=1 {
                        let kf = 2 * kc as i64 + dz;
                        if kf < 0 || kf >= nf as i64 {
                            continue;
                        }
                        let wz = if dz == 0 { 1.0 } else { 0.5 };
                        for dy in -1i64..=1 {
                            let jf = 2 * jc as i64 + dy;
                            if jf < 0 || jf >= nf as i64 {
                                continue;
                            }
                            let wy = if dy == 0 { 1.0 } else { 0.5 };
                            let row = (kf as usize * nf + jf as usize) * nf;
                            for dx in -1i64..=1 {
                                let i_f = 2 * ic as i64 + dx;
                                if i_f < 0 || i_f >= nf as i64 {
                                    continue;
                                }
                                let wx = if dx == 0 { 1.0 } else { 0.5 };
                                s += wx * wy * wz * r[row + i_f as usize];
                            }
                        }
                    }
                    plane[jc * nc + ic] = s;
                }
            }
        });
}

/// `fine.x += P coarse.x` (trilinear interpolation of the coarse correction).
fn prolong_add(coarse: &Level, fine: &mut Level) {
    let (nf, nc) = (fine.n, coarse.n);
    let e = &coarse.x;
    fine.x
        .par_chunks_mut(nf * nf)
        .enumerate()
        .for_each(|(kf, plane)| {
            let (pz, wz, cz) = parents(kf);
            for jf in 0..nf {
                let (py, wy, cy) = parents(jf);
                for i_f in 0..nf {
                    let (px, wx, cx) = parents(i_f);
                    let mut s = 0.0f32;
                    for a in 0..cz {
                        for b in 0..cy {
                            let row = (pz[a] * nc + py[b]) * nc;
                            for c in 0..cx {
                                s += wz[a] * wy[b] * wx[c] * e[row + px[c]];
                            }
                        }
                    }
                    plane[jf * nf + i_f] += s;
                }
            }
        });
}

/// One V-cycle on `levels[..=top]` (`levels[0]` coarsest), from the current `x` of
/// `levels[top]`; coarser levels start from zero.
fn v_cycle(levels: &mut [Level], top: usize, sweeps: usize) {
    if top == 0 {
        for _ in 0..COARSEST_SWEEPS {
            levels[0].sweep();
        }
        return;
    }
    for _ in 0..sweeps {
        levels[top].sweep();
    }
    levels[top].residual();
    let (lower, upper) = levels.split_at_mut(top);
    let (fine, coarse) = (&mut upper[0], &mut lower[top - 1]);
    restrict(fine, coarse);
    coarse.x.par_iter_mut().for_each(|v| *v = 0.0);
    v_cycle(lower, top - 1, sweeps);
    let (lower, upper) = levels.split_at_mut(top);
    prolong_add(&lower[top - 1], &mut upper[0]);
    for _ in 0..sweeps {
        levels[top].sweep();
    }
}

/// Full multigrid start: the right-hand side restricted down the hierarchy, the
/// coarsest level solved, then on each finer level the prolongated coarse solution
/// improved by one V-cycle; the finest level ends close to the solution, so few
/// V-cycles remain.
fn full_multigrid(levels: &mut [Level], sweeps: usize) {
    let top = levels.len() - 1;
    for l in (1..=top).rev() {
        let (lower, upper) = levels.split_at_mut(l);
        let fine = &mut upper[0];
        std::mem::swap(&mut fine.r, &mut fine.b);
        restrict(fine, &mut lower[l - 1]);
        std::mem::swap(&mut fine.r, &mut fine.b);
    }
    v_cycle(levels, 0, sweeps);
    for l in 1..=top {
        let (lower, upper) = levels.split_at_mut(l);
        upper[0].x.par_iter_mut().for_each(|v| *v = 0.0);
        prolong_add(&lower[l - 1], &mut upper[0]);
        v_cycle(&mut levels[..=l], l, sweeps);
    }
}

/// V-cycles on the finest level until the relative residual is below `tolerance` or
/// `max_cycles` ran; `checkpoint` is called between cycles (time limits).
pub(crate) fn solve(
    levels: &mut [Level],
    max_cycles: usize,
    tolerance: f64,
    sweeps: usize,
    checkpoint: &mut dyn FnMut() -> Result<(), MethodError>,
) -> Result<SolveStats, MethodError> {
    let top = levels.len() - 1;
    let bnorm = levels[top]
        .b
        .par_chunks(1 << 16)
        .map(|c| c.iter().map(|&v| f64::from(v) * f64::from(v)).sum::<f64>())
        .collect::<Vec<f64>>()
        .iter()
        .sum::<f64>()
        .sqrt();
    if bnorm == 0.0 {
        return Ok(SolveStats {
            cycles: 0,
            relative_residual: 0.0,
        });
    }
    let mut stats = SolveStats {
        cycles: 0,
        relative_residual: 1.0,
    };
    full_multigrid(levels, sweeps);
    stats.cycles = 1;
    stats.relative_residual = levels[top].residual().sqrt() / bnorm;
    checkpoint()?;
    while stats.cycles < max_cycles && stats.relative_residual >= tolerance {
        v_cycle(levels, top, sweeps);
        stats.cycles += 1;
        stats.relative_residual = levels[top].residual().sqrt() / bnorm;
        checkpoint()?;
    }
    Ok(stats)
}
