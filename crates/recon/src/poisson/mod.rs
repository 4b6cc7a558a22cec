//! `poisson`: screened Poisson surface reconstruction (Kazhdan & Hoppe 2013, ACM TOG
//! 32(3)), our own solver; with `screening = 0` the unscreened equation of Kazhdan,
//! Bolitho & Hoppe (2006). The field's usual approximating peer (spec
//! `shared/spec/000_ma_thesis.md` §3.4, `001_priority_driven.md` §6).
//!
//! The indicator `chi` minimises `∫ |V - ∇chi|^2 + alpha (Area / sum w) sum_p w_p
//! chi(p)^2` on a regular grid of `2^depth` cells per side over the padded cubic
//! bounding box (`screened.rs`): `V` is the oriented normals spread with a quadratic
//! B-spline and weighted by the area each sample stands for (from its 8 nearest
//! neighbours, so the field is density-adaptive), the screening term pins `chi` to 0 at
//! the samples. Geometric multigrid solves the normal equations (`multigrid.rs`), the
//! level set at the mean of `chi` over the samples is extracted by marching tetrahedra
//! (`extract.rs`). Optionally, vertices in thinly sampled regions (the caps Poisson puts
//! over holes) are trimmed by a density quantile, as Open3D users do.
//!
//! Our own solver is the justified exception to "prefer crates": `poisson_reconstruction`
//! 0.4 (screened) was measured unfit and `threecrate-reconstruction` is unscreened and
//! closed (`docs/methods/poisson.md`).
//!
//! The output is approximating: its vertices are new points, so the mesh carries the
//! `interpolating = 0` diagnostic and the evaluator reports no vertex counts, Delta F or
//! refused points for it. Every stage is deterministic and independent of the thread
//! count.

mod extract;
mod multigrid;
pub mod params;
mod screened;

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::method::{
    Describe, Diagnostics, INTERPOLATING_DIAGNOSTIC, MethodError, Needs, ParamDoc, Reconstruction,
    Reconstructor, RunCtx,
};
use reconbench_geom::spatial::knn_self_table;
use reconbench_geom::{PointCloud, TriMesh};

pub use params::{PARAM_DOCS, PoissonParams, VertexFit};

use crate::ball_pivoting::input;
use crate::diag::num;
use crate::scale::times_pow2;
use screened::{Level, Samples};

/// Registry name.
pub const NAME: &str = "poisson";

/// The `poisson` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct Poisson {
    /// Parameters.
    pub params: PoissonParams,
}

impl Poisson {
    /// A reconstructor with validated parameters.
    pub fn new(params: PoissonParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl Describe for Poisson {
    const NAME: &'static str = NAME;
    const SOURCE: &'static str = "baseline (screened Poisson, Kazhdan & Hoppe 2013; own solver)";
    const SUMMARY: &'static str =
        "screened Poisson: a watertight approximating level set of the indicator function";
    const NEEDS: Needs = Needs::OrientedNormals;
    type Params = PoissonParams;
    const PARAMS: &'static [ParamDoc] = PARAM_DOCS;

    fn from_params(params: PoissonParams) -> Result<Self, MethodError> {
        Self::new(params)
    }
}

impl Reconstructor for Poisson {
    fn name(&self) -> &str {
        NAME
    }

    /// Runs at the working scale (`crate::scale`): everything is computed in grid cells,
    /// so only the bounding box and the output positions carry the cloud's units.
    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        self.params.validate()?;
        crate::scale::reconstruct_at_scale(NAME, cloud, SCALE_BITS, |cloud, s| {
            self.solve(cloud, s, ctx)
        })
    }
}

/// Clouds whose largest |coordinate| lies in `[2^-64, 2^64]` run unscaled (squared
/// distances stay far from `f64`'s limits); outside, the cloud is multiplied by a power
/// of two into `[1/2, 1)`.
const SCALE_BITS: i32 = 64;

/// Neighbours whose farthest distance gives each sample's area, `pi r_k^2 / k`.
const AREA_NEIGHBOURS: usize = 8;

/// Coarsest multigrid level: `2^2` cells per side.
const COARSEST_DEPTH: usize = 2;

/// The regular grid: `cells` cells per side from `origin`, side `cell`.
#[derive(Debug, Clone, Copy)]
struct Grid {
    cells: usize,
    origin: DVec3,
    cell: f64,
}

impl Grid {
    /// The cube of side `scale` times the bounding cube's (at least enough for two
    /// cells of padding on every side, which the normal kernel needs), centred on the
    /// points' bounding box.
    fn new(pos: &[DVec3], depth: usize, scale: f64) -> Self {
        let (lo, hi) = pos.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let extent = (hi - lo).max_element();
        let cells = 1usize << depth;
        let side = (scale * extent).max(extent / (1.0 - 4.5 / cells as f64));
        Self {
            cells,
            origin: 0.5 * (lo + hi) - DVec3::splat(0.5 * side),
            cell: side / cells as f64,
        }
    }

    fn to_grid(self, p: DVec3) -> DVec3 {
        (p - self.origin) / self.cell
    }
}

/// Whether every point lies in one plane (relative tolerance 1e-12 of the extent):
/// the plane through the first point, the point farthest from it and the point
/// farthest from that line.
fn coplanar(pos: &[DVec3]) -> bool {
    let p0 = pos[0];
    let far = |key: &dyn Fn(DVec3) -> f64| {
        pos.iter()
            .copied()
            .max_by(|a, b| key(*a).total_cmp(&key(*b)))
            .unwrap_or(p0)
    };
    let p1 = far(&|p| p.distance_squared(p0));
    let u = (p1 - p0).normalize_or_zero();
    let p2 = far(&|p| (p - p0).reject_from_normalized(u).length_squared());
    let nrm = u.cross(p2 - p0).normalize_or_zero();
    let tol = 1e-12 * p1.distance(p0);
    nrm == DVec3::ZERO || pos.iter().all(|&p| (p - p0).dot(nrm).abs() <= tol)
}

impl Poisson {
    /// The reconstruction on `cloud`, the input multiplied by `2^s`.
    fn solve(
        &self,
        cloud: &PointCloud,
        s: i32,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        let p = &self.params;
        let prep = ctx.phase("prepare", || {
            input::prepare(cloud, NAME, p.max_flipped_share)
        })?;
        ctx.checkpoint()?;
        // Points with a zero normal carry no gradient information: left out.
        let keep: Vec<usize> = (0..prep.pos.len())
            .filter(|&i| prep.nrm[i] != DVec3::ZERO)
            .collect();
        let pos: Vec<DVec3> = keep.iter().map(|&i| prep.pos[i]).collect();
        let nrm: Vec<DVec3> = keep.iter().map(|&i| prep.nrm[i]).collect();
        if pos.len() < 4 {
            return Err(MethodError::InvalidInput(format!(
                "{NAME}: needs at least 4 distinct points with non-zero normals, got {}",
                pos.len()
            )));
        }
        if coplanar(&pos) {
            return Err(MethodError::InvalidInput(format!(
                "{NAME}: all {} points lie in one plane; Poisson reconstructs the boundary \
                 of a solid",
                pos.len()
            )));
        }
        let grid = Grid::new(&pos, p.depth, p.scale);
        let g: Vec<DVec3> = pos.par_iter().map(|&q| grid.to_grid(q)).collect();
        // ASSUMPTION P-01 (density-adaptive kernel): each sample stands for the area
        // pi r_8^2 / 8 of its 8-nearest-neighbour disc (in cells^2); the paper weights by
        // an inverse density estimated from the splatted samples. Uniform point weights
        // w = 1, so Area / sum w is the mean of these areas.
        let area = ctx.phase("area", || sample_areas(&g))?;
        let mean_area = area.iter().sum::<f64>() / area.len() as f64;
        // ASSUMPTION P-02 (screening scale): the paper's weight alpha Area / sum w is for
        // the unit cube; PoissonRecon multiplies it by 2^depth so that the balance of the
        // two terms does not change with the resolution. In cell units that is
        // alpha * mean area (cells^2).
        let beta = (p.screening * mean_area) as f32;
        let mut levels = ctx.phase("system", || {
            let mut levels: Vec<Level> = (COARSEST_DEPTH..=p.depth)
                .map(|l| {
                    let shift = (p.depth - l) as u32;
                    let samples = Samples::new(&g, shift, 1 << l);
                    Level::new(1 << l, (1u32 << shift) as f32, beta, samples)
                })
                .collect();
            if let Some(top) = levels.last_mut() {
                top.b = screened::divergence_rhs(grid.cells, &g, &nrm, &area);
                // IMPL-CHOICE P-04 (the normal field in the B-spline basis): PoissonRecon
                // splats each normal onto B-spline coefficients with the quadratic
                // B-spline weights and represents V as the sum of those coefficients
                // times the quadratic B-splines; V at our edge midpoints is then our
                // point-sampled splat filtered by the B-spline's values at the integers,
                // (1/8, 3/4, 1/8) per axis. The filter commutes with the divergence, so
                // it is applied to b. `field_smoothing = 0` is the point-sampled kernel
                // alone (the behaviour before; the surface is noisier at the cell scale).
                screened::smooth(&mut top.b, top.n, p.field_smoothing);
            }
            levels
        });
        ctx.checkpoint()?;
        let stats = ctx.phase("solve", || {
            multigrid::solve(
                &mut levels,
                p.max_cycles,
                p.tolerance,
                p.sweeps,
                &mut || ctx.checkpoint(),
            )
        })?;
        let Some(top) = levels.pop() else {
            return Err(MethodError::Failed(format!("{NAME}: no grid level")));
        };
        drop(levels);
        // The level set through the samples: the mean of chi at them (both papers).
        let iso = {
            let vals: Vec<f64> = top
                .samples
                .cell
                .par_iter()
                .zip(&top.samples.frac)
                .map(|(c, f)| f64::from(screened::interp(&top.x, top.n, *c, *f)))
                .collect();
            (vals.iter().sum::<f64>() / vals.len() as f64) as f32
        };
        let field = extract::Field {
            x: &top.x,
            n: top.n,
            iso,
            origin: grid.origin,
            cell: grid.cell,
            fit: p.vertex_fit,
        };
        let (mut vertices, mut faces) =
            ctx.phase("extract", || extract::marching_tetrahedra(&field));
        drop(top);
        if faces.is_empty() {
            return Err(MethodError::InvalidInput(format!(
                "{NAME}: the iso-surface is empty (depth {}, {} points)",
                p.depth,
                pos.len()
            )));
        }
        let mut d = Diagnostics::new();
        if p.trim_quantile > 0.0 {
            let removed = ctx.phase("trim", || {
                extract::trim(
                    &mut vertices,
                    &mut faces,
                    &prep.pos,
                    p.trim_radius_cells * grid.cell,
                    p.trim_quantile,
                )
            })?;
            num(&mut d, "trimmed_vertices", removed as f64);
        }
        num(&mut d, INTERPOLATING_DIAGNOSTIC, 0.0);
        num(&mut d, "cell_size", times_pow2(grid.cell, -s));
        num(&mut d, "spacing", times_pow2(prep.spacing, -s));
        num(&mut d, "v_cycles", stats.cycles as f64);
        num(&mut d, "relative_residual", stats.relative_residual);
        num(&mut d, "screening_weight", f64::from(beta));
        num(&mut d, "duplicates", prep.duplicates as f64);
        num(&mut d, "zero_normals", prep.zero_normals as f64);
        num(&mut d, "flipped_share", prep.flipped_share);
        let mesh = TriMesh::new(vertices, faces)?;
        Ok(Reconstruction {
            mesh,
            refused: Vec::new(),
            diagnostics: d,
        })
    }
}

/// Area each sample stands for, `pi r_k^2 / k` with `r_k` the distance to its k-th
/// nearest neighbour (grid units, so cells^2).
fn sample_areas(g: &[DVec3]) -> Result<Vec<f64>, MethodError> {
    let k = AREA_NEIGHBOURS.min(g.len() - 1);
    let knn = knn_self_table(g, k, true)?;
    Ok((0..g.len())
        .map(|i| std::f64::consts::PI * knn.dist2(i)[knn.k - 1] / knn.k as f64)
        .collect())
}
