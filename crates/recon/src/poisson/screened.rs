//! The screened Poisson system of Kazhdan & Hoppe (2013) on a regular grid.
//!
//! The unknown is the indicator `chi` at the nodes of a grid of `cells` cells per side;
//! all lengths are in grid cells. Discretised energy (in grid units):
//!
//! `E(chi) = sum_edges (chi_head - chi_tail - V_edge)^2 + beta * sum_p chi(p)^2`
//!
//! with `V` the splatted normal field sampled at the edge midpoints (a staggered grid,
//! so that the gradient and its adjoint, the divergence, pair exactly and the first
//! term is the 7-point Laplacian), and `chi(p)` the trilinear interpolation at sample
//! `p`. Its normal equations are `(L + beta B^T B) chi = b` with `b = -div V`.
//! `beta = alpha * Area / sum w` in cell units is the paper's screening weight (the
//! unit-cube weight times `2^depth`, see `docs/methods/poisson.md`).
//!
//! The smoother is Gauss-Seidel in eight colours (the parity of each coordinate): two
//! nodes of one colour share no grid edge and no cell, so neither the Laplacian nor the
//! screening term couples them, and a colour pass is exact Gauss-Seidel whatever the
//! thread split (the result is bit-identical for any number of threads).

use glam::DVec3;
use rayon::prelude::*;

/// Levels with fewer nodes per side run their passes on the calling thread.
const PARALLEL_SIDE: usize = 40;

/// Samples of one level: the cell each lies in and its position inside it.
#[derive(Debug, Default)]
pub(crate) struct Samples {
    /// Cell `(i, j, k)` of each sample, clamped to the grid.
    pub cell: Vec<[u32; 3]>,
    /// Position inside the cell, each coordinate in `[0, 1]`.
    pub frac: Vec<[f32; 3]>,
}

impl Samples {
    /// The samples `g` (finest-grid coordinates) on a level `shift` levels coarser,
    /// with `cells` cells per side.
    pub fn new(g: &[DVec3], shift: u32, cells: usize) -> Self {
        let s = f64::from(1u32 << shift);
        let (cell, frac) = g
            .par_iter()
            .map(|&p| {
                let q = p / s;
                let mut c = [0u32; 3];
                let mut f = [0f32; 3];
                for a in 0..3 {
                    let ci = (q[a].floor().max(0.0) as usize).min(cells - 1);
                    c[a] = ci as u32;
                    f[a] = (q[a] - ci as f64).clamp(0.0, 1.0) as f32;
                }
                (c, f)
            })
            .unzip();
        Self { cell, frac }
    }
}

/// One level of the multigrid hierarchy: its operator `lap * L + beta * B^T B`, the
/// unknowns, right-hand side and scratch arrays (flat, node `(i, j, k)` at
/// `(k * n + j) * n + i`).
#[derive(Debug)]
pub(crate) struct Level {
    /// Nodes per side (`cells + 1`).
    pub n: usize,
    /// Weight of the Laplacian: `2^(depth - level)`, the Galerkin coarsening of the
    /// finest grid's edge energy (each coarsening halves the cell-unit energy of a
    /// smooth function twice over: `2^3` volume over `2^2` gradient).
    pub lap: f32,
    /// Screening weight (the same on every level: trilinear prolongation reproduces
    /// coarse trilinear functions exactly, so `B_c = B_f P` and the term is Galerkin).
    pub beta: f32,
    /// The samples at this level's resolution.
    pub samples: Samples,
    /// The cells holding samples, sorted (`beta * B^T B` restricted to each is an 8x8
    /// block over its corners; applying the blocks costs one pass over the occupied
    /// cells instead of one over the samples).
    pub cells: Vec<[u32; 3]>,
    /// `beta * sum_p phi_a(p) phi_b(p)` for the corners `a, b` (offsets `a & 1`,
    /// `(a >> 1) & 1`, `a >> 2`) of each cell in `cells`.
    pub blocks: Vec<[f32; 64]>,
    /// Diagonal of `beta * B^T B`.
    pub sdiag: Vec<f32>,
    /// Unknowns.
    pub x: Vec<f32>,
    /// Right-hand side.
    pub b: Vec<f32>,
    /// Residual (scratch).
    pub r: Vec<f32>,
    /// Scatter accumulator of the screening term (kept zero between uses).
    pub acc: Vec<f32>,
}

/// Trilinear weight of the corner with offsets `o` (0 or 1 per axis).
#[inline]
fn corner_weight(f: [f32; 3], o: [usize; 3]) -> f32 {
    let w = |a: usize| if o[a] == 1 { f[a] } else { 1.0 - f[a] };
    w(0) * w(1) * w(2)
}

/// Node index of corner `a` (offsets `a & 1`, `(a >> 1) & 1`, `a >> 2`) of cell `c`.
#[inline]
fn corner_id(n: usize, c: [u32; 3], a: usize) -> usize {
    ((c[2] as usize + (a >> 2)) * n + c[1] as usize + ((a >> 1) & 1)) * n + c[0] as usize + (a & 1)
}

/// The occupied cells (sorted by `(k, j, i)`) and their 8x8 screening blocks
/// `beta * sum_p phi_a(p) phi_b(p)`, summed in sample order within a cell.
fn screening_blocks(samples: &Samples, beta: f32) -> (Vec<[u32; 3]>, Vec<[f32; 64]>) {
    let key = |c: [u32; 3]| (c[2], c[1], c[0]);
    let mut order: Vec<u32> = (0..samples.cell.len() as u32).collect();
    order.par_sort_by_key(|&i| (key(samples.cell[i as usize]), i));
    let mut cells: Vec<[u32; 3]> = Vec::new();
    let mut blocks: Vec<[f32; 64]> = Vec::new();
    for &i in &order {
        let (c, f) = (samples.cell[i as usize], samples.frac[i as usize]);
        if cells.last() != Some(&c) {
            cells.push(c);
            blocks.push([0.0; 64]);
        }
        let phi: [f32; 8] =
            std::array::from_fn(|a| corner_weight(f, [a & 1, (a >> 1) & 1, a >> 2]));
        if let Some(m) = blocks.last_mut() {
            for a in 0..8 {
                for b in 0..8 {
                    m[a * 8 + b] += beta * phi[a] * phi[b];
                }
            }
        }
    }
    (cells, blocks)
}

/// Trilinear interpolation of `x` (nodes per side `n`) in cell `c` at `f`.
#[inline]
pub(crate) fn interp(x: &[f32], n: usize, c: [u32; 3], f: [f32; 3]) -> f32 {
    let base = (c[2] as usize * n + c[1] as usize) * n + c[0] as usize;
    let mut v = 0.0;
    for oz in 0..2 {
        for oy in 0..2 {
            for ox in 0..2 {
                let id = base + (oz * n + oy) * n + ox;
                v += corner_weight(f, [ox, oy, oz]) * x[id];
            }
        }
    }
    v
}

impl Level {
    /// A level with `cells` cells per side, zero unknowns and right-hand side.
    pub fn new(cells: usize, lap: f32, beta: f32, samples: Samples) -> Self {
        let n = cells + 1;
        let len = n * n * n;
        let (occupied, blocks) = if beta > 0.0 {
            screening_blocks(&samples, beta)
        } else {
            (Vec::new(), Vec::new())
        };
        let mut sdiag = vec![0f32; len];
        for (c, m) in occupied.iter().zip(&blocks) {
            for a in 0..8 {
                sdiag[corner_id(n, *c, a)] += m[a * 8 + a];
            }
        }
        Self {
            n,
            lap,
            beta,
            samples,
            cells: occupied,
            blocks,
            sdiag,
            x: vec![0.0; len],
            b: vec![0.0; len],
            r: vec![0.0; len],
            acc: vec![0.0; len],
        }
    }

    /// Sum of the neighbours' values and the neighbour count of node `(i, j)` in plane
    /// `cur` (with the planes below and above, if any).
    #[inline]
    fn neighbours(
        &self,
        cur: &[f32],
        below: Option<&[f32]>,
        above: Option<&[f32]>,
        i: usize,
        j: usize,
    ) -> (f32, f32) {
        let n = self.n;
        let l = j * n + i;
        let (mut s, mut deg) = (0.0f32, 0.0f32);
        if i > 0 {
            s += cur[l - 1];
            deg += 1.0;
        }
        if i + 1 < n {
            s += cur[l + 1];
            deg += 1.0;
        }
        if j > 0 {
            s += cur[l - n];
            deg += 1.0;
        }
        if j + 1 < n {
            s += cur[l + n];
            deg += 1.0;
        }
        if let Some(p) = below {
            s += p[l];
            deg += 1.0;
        }
        if let Some(p) = above {
            s += p[l];
            deg += 1.0;
        }
        (s, deg)
    }

    /// Adds, for colour `col`, the off-diagonal part of `beta B^T B` times `x` to the
    /// accumulator at the one corner of each occupied cell in that colour. Serial over
    /// the cells in a fixed order, so the sums do not depend on threads.
    fn scatter_offdiagonal(&mut self, col: [usize; 3]) {
        let n = self.n;
        for (c, m) in self.cells.iter().zip(&self.blocks) {
            let o = [0, 1, 2].map(|a| (col[a] ^ (c[a] as usize & 1)) & 1);
            let a = o[0] + 2 * o[1] + 4 * o[2];
            let mut v = 0.0f32;
            for b in (0..8).filter(|&b| b != a) {
                v += m[a * 8 + b] * self.x[corner_id(n, *c, b)];
            }
            self.acc[corner_id(n, *c, a)] += v;
        }
    }

    /// One Gauss-Seidel pass over the nodes of colour `col` (parity per axis).
    fn colour_pass(&mut self, col: [usize; 3]) {
        if self.beta > 0.0 {
            self.scatter_offdiagonal(col);
        }
        let n = self.n;
        let plane = n * n;
        let mut x = std::mem::take(&mut self.x);
        let mut acc = std::mem::take(&mut self.acc);
        {
            let mut mine: Vec<(usize, &mut [f32])> = Vec::with_capacity(n / 2 + 1);
            let mut others: Vec<Option<&[f32]>> = Vec::with_capacity(n);
            for (k, p) in x.chunks_mut(plane).enumerate() {
                if k % 2 == col[2] {
                    mine.push((k, p));
                    others.push(None);
                } else {
                    let shared: &[f32] = p;
                    others.push(Some(shared));
                }
            }
            let accs: Vec<&mut [f32]> = acc
                .chunks_mut(plane)
                .enumerate()
                .filter(|(k, _)| k % 2 == col[2])
                .map(|(_, p)| p)
                .collect();
            let this = &*self;
            let update = |((k, cur), acc): ((usize, &mut [f32]), &mut [f32])| {
                let below = if k > 0 { others[k - 1] } else { None };
                let above = others.get(k + 1).copied().flatten();
                let g0 = k * plane;
                for j in (col[1]..n).step_by(2) {
                    for i in (col[0]..n).step_by(2) {
                        let l = j * n + i;
                        let (s, deg) = this.neighbours(cur, below, above, i, j);
                        let a = acc[l];
                        acc[l] = 0.0;
                        cur[l] = (this.b[g0 + l] + this.lap * s - a)
                            / (this.lap * deg + this.sdiag[g0 + l]);
                    }
                }
            };
            // Small levels run on this thread: dispatching them costs more than they do.
            if this.n < PARALLEL_SIDE {
                mine.into_iter().zip(accs).for_each(update);
            } else {
                mine.into_par_iter().zip(accs).for_each(update);
            }
        }
        self.x = x;
        self.acc = acc;
    }

    /// One symmetric-order-free Gauss-Seidel sweep: the eight colours in a fixed order.
    pub fn sweep(&mut self) {
        for c in 0..8 {
            self.colour_pass([c & 1, (c >> 1) & 1, (c >> 2) & 1]);
        }
    }

    /// `r = b - A x`; returns `|r|^2` (per-plane sums added in plane order).
    pub fn residual(&mut self) -> f64 {
        let n = self.n;
        let plane = n * n;
        for (c, m) in self.cells.iter().zip(&self.blocks) {
            let xs: [f32; 8] = std::array::from_fn(|b| self.x[corner_id(n, *c, b)]);
            for a in 0..8 {
                let v: f32 = (0..8).map(|b| m[a * 8 + b] * xs[b]).sum();
                self.acc[corner_id(n, *c, a)] += v;
            }
        }
        let mut r = std::mem::take(&mut self.r);
        let mut acc = std::mem::take(&mut self.acc);
        let this = &*self;
        let plane_residual = |(k, (rp, ap)): (usize, (&mut [f32], &mut [f32]))| {
            let g0 = k * plane;
            let cur = &this.x[g0..g0 + plane];
            let below = (k > 0).then(|| &this.x[g0 - plane..g0]);
            let above = (k + 1 < n).then(|| &this.x[g0 + plane..g0 + 2 * plane]);
            let mut sum = 0.0f64;
            for j in 0..n {
                for i in 0..n {
                    let l = j * n + i;
                    let (s, deg) = this.neighbours(cur, below, above, i, j);
                    let v = this.b[g0 + l] - this.lap * (deg * cur[l] - s) - ap[l];
                    ap[l] = 0.0;
                    rp[l] = v;
                    sum += f64::from(v) * f64::from(v);
                }
            }
            sum
        };
        let sums: Vec<f64> = if n < PARALLEL_SIDE {
            r.chunks_mut(plane)
                .zip(acc.chunks_mut(plane))
                .enumerate()
                .map(plane_residual)
                .collect()
        } else {
            r.par_chunks_mut(plane)
                .zip(acc.par_chunks_mut(plane))
                .enumerate()
                .map(plane_residual)
                .collect()
        };
        self.r = r;
        self.acc = acc;
        sums.iter().sum()
    }
}

/// Quadratic B-spline weights of the three nodes around `x` (grid units): nodes
/// `m - 1, m, m + 1` with `m = round(x)`.
#[inline]
fn bspline2(x: f64) -> (i64, [f64; 3]) {
    let m = x.round();
    let t = x - m;
    (
        m as i64,
        [
            0.5 * (0.5 - t) * (0.5 - t),
            0.75 - t * t,
            0.5 * (0.5 + t) * (0.5 + t),
        ],
    )
}

/// The right-hand side `b = -div V` on a grid of `cells` cells per side: each sample
/// `g` (grid coordinates) carries the vector `-area * normal` (the indicator grows
/// inwards), spread over the edge midpoints of axis `a` (the staggered grid, offset
/// half a cell along `a`) with a quadratic B-spline (PoissonRecon's normal kernel,
/// three cells wide); an edge value `v` adds `v` to its head node and `-v` to its tail
/// node. Serial in sample order (deterministic). The samples lie at least two cells
/// inside the grid, so every touched edge exists.
pub(crate) fn divergence_rhs(cells: usize, g: &[DVec3], nrm: &[DVec3], area: &[f64]) -> Vec<f32> {
    let n = cells + 1;
    let mut b = vec![0f32; n * n * n];
    let last = cells as i64 - 1;
    for ((&p, &nv), &ar) in g.iter().zip(nrm).zip(area) {
        for a in 0..3 {
            let v = -ar * nv[a];
            if v == 0.0 {
                continue;
            }
            // Edge midpoints of axis a sit at integer + 1/2 along a.
            let mut q = p;
            q[a] -= 0.5;
            let (mx, wx) = bspline2(q.x);
            let (my, wy) = bspline2(q.y);
            let (mz, wz) = bspline2(q.z);
            for (dz, wzv) in wz.iter().enumerate() {
                for (dy, wyv) in wy.iter().enumerate() {
                    for (dx, wxv) in wx.iter().enumerate() {
                        let e = [mx + dx as i64 - 1, my + dy as i64 - 1, mz + dz as i64 - 1];
                        let lim = |b: usize| if b == a { last } else { cells as i64 };
                        if (0..3).any(|b| e[b] < 0 || e[b] > lim(b)) {
                            continue;
                        }
                        let tail = (e[2] as usize * n + e[1] as usize) * n + e[0] as usize;
                        let stride = [1, n, n * n][a];
                        let w = (v * wxv * wyv * wzv) as f32;
                        b[tail + stride] += w;
                        b[tail] -= w;
                    }
                }
            }
        }
    }
    b
}

/// Filters the grid function `x` (nodes per side `n`) with `(w, 1 - 2w, w)` along each
/// axis in turn, the values beyond the grid taken as zero (so the sum is kept when the
/// boundary nodes are zero, as they are for the right-hand side: the samples lie at
/// least two cells inside). `w = 1/8` is the quadratic B-spline at the integers (see
/// `field_smoothing`); `w = 0` leaves `x` unchanged. Each output node depends only on
/// the input, so the result does not depend on the thread split.
pub(crate) fn smooth(x: &mut [f32], n: usize, w: f64) {
    if w == 0.0 {
        return;
    }
    let (w, c) = (w as f32, (1.0 - 2.0 * w) as f32);
    let plane = n * n;
    for axis in 0..3 {
        let stride = [1, n, plane][axis];
        let src = x.to_vec();
        x.par_chunks_mut(plane).enumerate().for_each(|(k, out)| {
            let g0 = k * plane;
            for j in 0..n {
                for i in 0..n {
                    let l = j * n + i;
                    let id = g0 + l;
                    let co = [i, j, k][axis];
                    let lo = if co > 0 { src[id - stride] } else { 0.0 };
                    let hi = if co + 1 < n { src[id + stride] } else { 0.0 };
                    out[l] = c * src[id] + w * (lo + hi);
                }
            }
        });
    }
}
