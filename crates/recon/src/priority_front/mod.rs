//! `priority-front`: Li, Han & Wee, "On Surface Reconstruction: A Priority Driven
//! Approach", CAD 41(9), 2009 (spec `shared/spec/001_priority_driven.md`).
//!
//! An interpolating advancing-front mesher. From a seed triangle in the flattest of a few
//! random patches, front edges are popped from a min-heap keyed by the bend cost
//! T = 1 - cos(normal change) (flat regions first). For each edge the Free and front
//! points within R = kρ of its midpoint are filtered by the angle bound α_max = 120° and
//! the normal-change bound β_max = 90°, ranked by the score
//! C = w1 cos β + w2 cos γ + w3 (R - d)/R, and validated by a 2-D crossing test; the
//! winner is joined, filled, linked or glued into the front. Restarts seed the Free
//! patches left; points never used are refused as noise. By default (deviations, issue
//! 20) candidates that would cross the mesh are refused (I14), and after growth the
//! holes that close under the length bound are closed and the covered points inserted
//! (I15).
//!
//! Output: a consistently oriented manifold mesh whose vertices are the input points
//! (refused points are unreferenced vertices), the refused indices, and diagnostics
//! (holes as boundary loops, operation counts, timings). See
//! `docs/methods/priority_front.md`.
//!
//! Files: [`params`] (parameters), `grid` (hash grid, front-vertex index), `density`
//! (ρ, duplicates, exact neighbour search), `seed` (§4.2), `mesher` (state and the four
//! operations), `triangulate` (§4.4 and the main loop), `cross` (2-D crossing test),
//! `adjacency` (edge map of front vertices), `run` (restarts), `parallel` (slabs),
//! `holes` (I7 small loops, I9 zip), `complete` (I15 surface completion).

mod adjacency;
mod complete;
mod cross;
mod density;
mod fill_dp;
mod grid;
mod holes;
mod inside_out;
mod mesher;
mod orient;
mod parallel;
pub mod params;
mod peel;
mod regrow;
mod run;
mod seed;
mod strays;
mod triangulate;

use std::time::Instant;

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::cloud::WORKING_SCALE_BITS;
use reconbench_geom::method::{
    Diagnostic, Diagnostics, MethodError, Reconstruction, Reconstructor, RunCtx,
};
use reconbench_geom::{PointCloud, TriMesh};

pub use params::{PARAM_DOCS, PriorityFrontParams, RhoSample, ScoreDistance};

use crate::diag::num;
use crate::scale::times_pow2;
use density::{duplicates, mean_nn, search_grid};
use grid::Grid;
use mesher::{Cfg, FREE, Mesher, REFUSED, Stats};
use run::DomainCfg;

/// Registry name.
pub const NAME: &str = "priority-front";

/// The `priority-front` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct PriorityFront {
    /// Parameters.
    pub params: PriorityFrontParams,
}

impl PriorityFront {
    /// A reconstructor with validated parameters.
    pub fn new(params: PriorityFrontParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

/// Records `name` as a phase that started at `t0` (for phases that need `ctx` inside).
fn end_phase(ctx: &mut RunCtx, name: &str, t0: Instant) {
    ctx.record_phase(name, t0.elapsed().as_secs_f64());
}

/// The whole-run result before conversion to input indices.
struct Grown {
    tris: Vec<[u32; 3]>,
    state: Vec<u8>,
    loops: Vec<Vec<u32>>,
    stats: Stats,
}

impl Grown {
    /// The faces, point states and loops, for the repairs that rebuild them.
    fn mesh(&mut self) -> peel::PeelMesh<'_> {
        peel::PeelMesh {
            tris: &mut self.tris,
            state: &mut self.state,
            loops: &mut self.loops,
        }
    }
}

impl Reconstructor for PriorityFront {
    fn name(&self) -> &str {
        NAME
    }

    /// Runs on the exact power-of-two working-scale copy of the cloud (every parameter
    /// is relative to ρ or R), so coordinates near 1e±160 or 1e308 neither overflow nor
    /// underflow; the length diagnostics are given back in the cloud's units.
    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        self.params.validate()?;
        crate::scale::reconstruct_at_scale(NAME, cloud, WORKING_SCALE_BITS, |c, s| {
            let mut r = self.reconstruct_unscaled(c, ctx)?;
            if s != 0 {
                for key in ["rho", "radius", "boundary_loop_centroids"] {
                    match r.diagnostics.get_mut(key) {
                        Some(Diagnostic::Number(x)) => *x = times_pow2(*x, -s),
                        Some(Diagnostic::Series(v)) => {
                            v.iter_mut().for_each(|x| *x = times_pow2(*x, -s))
                        }
                        _ => {}
                    }
                }
            }
            Ok(r)
        })
    }
}

impl PriorityFront {
    /// The method on `cloud` as given (see [`Reconstructor::reconstruct`]).
    fn reconstruct_unscaled(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        let p = &self.params;
        p.validate()?;
        let n = cloud.len();
        check_input(p, n)?;
        let t_start = Instant::now();
        let input = cloud.positions();
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
        let mut diag = Diagnostics::new();

        // P1-P3: duplicates, rho, R.
        let (dup, rho) = density_phase(input, p, &mut rng, ctx);
        let n_dup = dup.iter().filter(|&&d| d).count();
        num(&mut diag, "duplicates", n_dup as f64);
        let Some(rho) = rho.filter(|_| n - n_dup >= 3) else {
            // ρ undefined on 3 or more distinct points that span a plane: the squared
            // distances over- or underflowed (coordinates near 1e±160); an empty mesh
            // would be a silent failure.
            if n - n_dup >= 3 && spans_plane(input, &dup) {
                return Err(MethodError::InvalidInput(format!(
                    "priority-front: the point spacing is not representable at this \
                     coordinate scale ({}); rescale the input",
                    scale_text(input)
                )));
            }
            // Fewer than 3 distinct points: nothing to mesh; every point is refused.
            diag.insert(
                "note".into(),
                Diagnostic::Text("fewer than 3 distinct points: empty mesh".into()),
            );
            return finish(
                input,
                Vec::new(),
                (0..n as u32).collect(),
                diag,
                t_start,
                0.0,
            );
        };
        let r0 = p.k * rho;
        num(&mut diag, "rho", rho);
        num(&mut diag, "radius", r0);

        // P4: the hash grid, cell h = grid_cell * R (ASSUMPTION A2: h = R).
        let lay = grid_phase(input, &dup, r0 * p.grid_cell, ctx);
        let cfg = mesher_cfg(p, r0, rho);
        let dcfg = DomainCfg {
            params: p,
            r0,
            centroid: lay.centroid,
            first_centre: p.seed_point.map(|s| lay.inv[s as usize]),
            seeds_before: 0,
        };

        // M0-M8.
        let t_grow = Instant::now();
        let mut grown = if p.threads <= 1 {
            grow_serial(&lay, cfg.clone(), &dcfg, &mut rng, ctx, t_grow)?
        } else {
            let mut outs = grow_slabs_phase(&lay, &cfg, &dcfg, ctx, t_grow)?;
            stitch_phase(&lay, cfg.clone(), &dcfg, &mut outs, &mut rng, ctx)?
        };
        let grow_secs = t_grow.elapsed().as_secs_f64();
        let regrown = inside_out_phase(&mut grown, &lay, &cfg, p, ctx)?;
        num(&mut diag, "inside_out_faces", regrown as f64);
        let strays = ctx.phase("strays", || {
            strays::dissolve_stray_pieces(
                &lay.pts,
                &mut grown.tris,
                &mut grown.state,
                &mut grown.loops,
                p.stray_piece_max,
                r0,
            )
        });
        num(&mut diag, "stray_pieces", strays as f64);
        let peeled = peel_phase(&mut grown, &lay, &cfg, p, ctx);
        num(&mut diag, "holes_peeled", peeled as f64);
        let inserted = insert_phase(&mut grown, &lay, p, rho, ctx);
        num(&mut diag, "inserted_points", inserted as f64);
        // I20-I22: loops, unmeshed points and false handles grown again.
        let insert = p.insert_covered.then(|| cover_bound(p, rho));
        let g = regrow_ctx(&lay, &cfg, p, insert);
        let open = !grown.loops.is_empty() && p.regrow_loops_depth > 0;
        let kept = regrow_step(ctx, "regrow_loops", open, |c| {
            regrow::regrow_open_loops(&g, grown.mesh(), p.regrow_loops_depth, c)
        })?;
        num(&mut diag, "loops_regrown", kept as f64);
        let free = grown.state.contains(&FREE) && p.regrow_points_depth > 0;
        let kept = regrow_step(ctx, "regrow_points", free, |c| {
            regrow::regrow_free_points(&g, grown.mesh(), p.regrow_points_depth, c)
        })?;
        num(&mut diag, "points_regrown", kept as f64);
        let kept = regrow_step(ctx, "regrow_handles", p.regrow_handles_depth > 0, |c| {
            regrow::regrow_handles(&g, grown.mesh(), p.regrow_handles_depth, c).map(u64::from)
        })?;
        num(&mut diag, "handles_regrown", kept as f64);

        // M9: Free points become Refused; map back to input indices.
        let (mut faces, refused) = output_phase(&grown, &lay.order, n, ctx);
        if p.seed_outward && p.seed_orient_front {
            let radius = SLAB_ORIENT_RADIUS * r0;
            let reversed = orient::orient_pieces(input, &mut faces, lay.centroid, radius);
            num(&mut diag, "reversed_faces", reversed as f64);
        }
        if faces.is_empty() && spans_plane(input, &dup) {
            return Err(MethodError::Failed(format!(
                "priority-front made no triangle on {} distinct points that span a plane \
                 (rho {rho:e}, R {r0:e}; coordinate scale {}): the geometric tests \
                 under- or overflow at this scale; rescale the input",
                n - n_dup,
                scale_text(input)
            )));
        }
        record_stats(&mut diag, &grown, &lay.pts, p);
        num(
            &mut diag,
            "grow_triangles_per_second",
            faces.len() as f64 / grow_secs.max(1e-9),
        );
        diag.insert("assumptions".into(), Diagnostic::Text(assumption_flags(p)));
        finish(input, faces, refused, diag, t_start, grow_secs)
    }
}

/// True when the points not flagged in `dup` do not all lie on one line, decided on
/// coordinates divided by the largest magnitude (so no product over- or underflows at
/// any finite scale): some point's offset from the first is not parallel, to a relative
/// 1e-9, to the offset of the point farthest from it.
fn spans_plane(input: &[DVec3], dup: &[bool]) -> bool {
    let m = input
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0f64, f64::max);
    if !(m.is_finite() && m > 0.0) {
        return false;
    }
    let q: Vec<DVec3> = input
        .iter()
        .zip(dup)
        .filter(|(_, d)| !**d)
        .map(|(p, _)| *p / m)
        .collect();
    let Some(&p0) = q.first() else {
        return false;
    };
    let far = q
        .iter()
        .map(|&p| p - p0)
        .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))
        .unwrap_or(DVec3::ZERO);
    let lf = far.length();
    lf > 0.0
        && q.iter().any(|&p| {
            let d = p - p0;
            far.cross(d).length() > 1e-9 * lf * d.length()
        })
}

/// The input's largest coordinate magnitude and bounding-box extent, for error messages.
fn scale_text(input: &[DVec3]) -> String {
    let m = input
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0f64, f64::max);
    let (lo, hi) = input.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    format!(
        "largest |coordinate| {m:e}, box extent {:e}",
        (hi - lo).max_element()
    )
}

/// Rejects inputs the mesher cannot index: fewer than 3 points, more than the `u32`
/// range, or a `seed_point` outside the cloud.
fn check_input(p: &PriorityFrontParams, n: usize) -> Result<(), MethodError> {
    if n < 3 {
        return Err(MethodError::InvalidInput(format!(
            "priority-front needs at least 3 points, got {n}"
        )));
    }
    if n >= u32::MAX as usize {
        return Err(MethodError::InvalidInput(format!(
            "{n} points exceed u32 range"
        )));
    }
    if let Some(s) = p.seed_point
        && s as usize >= n
    {
        return Err(MethodError::InvalidParameter {
            name: "seed_point".into(),
            message: format!("index {s} out of range for {n} points"),
        });
    }
    Ok(())
}

/// P1-P3 (timed as `density`): the duplicate flag of every input point and ρ, the mean
/// nearest-neighbour distance over the distinct points (`None` when it is undefined).
fn density_phase(
    input: &[DVec3],
    p: &PriorityFrontParams,
    rng: &mut ChaCha8Rng,
    ctx: &mut RunCtx,
) -> (Vec<bool>, Option<f64>) {
    ctx.phase("density", || {
        let (g0, ord0) = search_grid(input);
        let dup = duplicates(&g0, &ord0, input);
        let p0: Vec<DVec3> = ord0.iter().map(|&i| input[i as usize]).collect();
        let dup0: Vec<bool> = ord0.iter().map(|&i| dup[i as usize]).collect();
        let eligible = |i: usize| !dup0[i];
        let rho = mean_nn(&g0, &p0, &eligible, p.rho_sample, rng);
        (dup, rho)
    })
}

/// The points in hash-grid order with the grid and their starting state.
struct Layout {
    grid: Grid,
    /// Input index of every point in grid order.
    order: Vec<u32>,
    /// The points in grid order.
    pts: Vec<DVec3>,
    /// Grid-order index of every input point.
    inv: Vec<u32>,
    /// Per point in grid order: a duplicate, refused from the start.
    refused0: Vec<bool>,
    /// Centroid of the points not refused.
    centroid: DVec3,
}

/// P4: the hash grid of cell `h` (timed as `grid`), then the grid-order views of the
/// input and the centroid of the distinct points.
fn grid_phase(input: &[DVec3], dup: &[bool], h: f64, ctx: &mut RunCtx) -> Layout {
    let (grid, order, pts) = ctx.phase("grid", || {
        let (grid, order) = Grid::build(input, h);
        let pts: Vec<DVec3> = order.iter().map(|&i| input[i as usize]).collect();
        (grid, order, pts)
    });
    let mut inv = vec![0u32; input.len()];
    for (g, &i) in order.iter().enumerate() {
        inv[i as usize] = g as u32;
    }
    let refused0: Vec<bool> = order.iter().map(|&i| dup[i as usize]).collect();
    let centroid = {
        let (s, c) = pts
            .iter()
            .zip(&refused0)
            .filter(|(_, d)| !**d)
            .fold((DVec3::ZERO, 0usize), |(s, c), (q, _)| (s + *q, c + 1));
        s / c.max(1) as f64
    };
    Layout {
        grid,
        order,
        pts,
        inv,
        refused0,
        centroid,
    }
}

/// The mesher configuration for radius `r0` and spacing `rho`.
fn mesher_cfg(p: &PriorityFrontParams, r0: f64, rho: f64) -> Cfg {
    Cfg {
        r: r0,
        cos_alpha: p.alpha_max_deg.to_radians().cos(),
        cos_beta: p.beta_max_deg.to_radians().cos(),
        w: [p.w1, p.w2, p.w3],
        seg_dist: p.score_distance == ScoreDistance::Segment,
        apex_rule: p.apex_angle_rule,
        link_prev: p.link_prev,
        glue_mirror: p.glue_mirror,
        cross_factor: p.cross_radius,
        reject_free_inside: p.reject_free_inside,
        free_inside_h: p.free_inside_height * rho,
        free_inside_rel: p.free_inside_rel,
        interior_inside: p.interior_inside_check,
        self_check: p.self_intersection_check,
        front_inside_check: p.front_inside_check,
        fill_any_angle: p.fill_any_angle,
        sector_check: p.sector_check,
        revisit_passes: p.revisit_passes,
        sin_elev: if p.free_elevation_max_deg >= 90.0 {
            1.0
        } else {
            p.free_elevation_max_deg.to_radians().sin()
        },
        height_r: p.free_height_max / p.k,
        cos_front: if p.front_normal_max_deg >= 180.0 {
            -2.0
        } else {
            p.front_normal_max_deg.to_radians().cos()
        },
        support_k: p.support_neighbours,
        support_tol: p.support_tolerance * rho,
        support_radius: p.support_radius,
        support_share: p.support_share,
        support_crease: p.support_crease,
    }
}

/// Takes the result out of a finished mesher.
fn take_grown(m: &mut Mesher) -> Grown {
    Grown {
        loops: m.loops(),
        tris: std::mem::take(&mut m.tris),
        state: std::mem::take(&mut m.state),
        stats: m.stats.clone(),
    }
}

/// M0-M8 on one thread: seeds, growth and restarts over the whole cloud, then small
/// holes closed; timed as `grow` from `t_grow`.
fn grow_serial(
    lay: &Layout,
    cfg: Cfg,
    dcfg: &DomainCfg,
    rng: &mut ChaCha8Rng,
    ctx: &mut RunCtx,
    t_grow: Instant,
) -> Result<Grown, MethodError> {
    let p = dcfg.params;
    let mut m = Mesher::new(&lay.pts, &lay.grid, cfg, &lay.refused0);
    m.run_domain(dcfg, rng, ctx)?;
    m.stats.holes_closed = m.close_small_holes(p.close_holes_max);
    m.stats.holes_filled = fill_phase(&mut m, p);
    end_phase(ctx, "grow", t_grow);
    Ok(take_grown(&mut m))
}

/// M0-M8 in parallel slabs, timed as `grow` from `t_grow`.
fn grow_slabs_phase(
    lay: &Layout,
    cfg: &Cfg,
    dcfg: &DomainCfg,
    ctx: &mut RunCtx,
    t_grow: Instant,
) -> Result<Vec<parallel::SlabOut>, MethodError> {
    let p = dcfg.params;
    let outs = parallel::grow_slabs(
        &lay.pts,
        &lay.refused0,
        lay.grid.lat.h(),
        cfg,
        dcfg,
        p.threads,
        ctx.seed,
        ctx,
    )?;
    end_phase(ctx, "grow", t_grow);
    Ok(outs)
}

/// Radius, in R, within which a piece's front or rim edge looks for the facing edge of
/// another piece (IMPL-CHOICE I16): the Free band between two slabs is 2 R wide.
const SLAB_ORIENT_RADIUS: f64 = 4.0;

/// Joins the slab meshes into one mesher (timed as `stitch`): imports them, sweeps the
/// bands and every front, restarts over the whole cloud for what the slabs left, then
/// closes small holes (and zips parallel loops with `stitch_zip`).
fn stitch_phase(
    lay: &Layout,
    cfg: Cfg,
    dcfg: &DomainCfg,
    outs: &mut [parallel::SlabOut],
    rng: &mut ChaCha8Rng,
    ctx: &mut RunCtx,
) -> Result<Grown, MethodError> {
    let p = dcfg.params;
    let t_st = Instant::now();
    if p.seed_orient_front {
        parallel::orient_slab_pieces(&lay.pts, outs, SLAB_ORIENT_RADIUS * cfg.r);
    }
    let mut m = Mesher::new(&lay.pts, &lay.grid, cfg, &lay.refused0);
    parallel::stitch_import(&mut m, outs, p.stitch_one_sided);
    // One-sided sweep of the bands (no revisits yet), then every front.
    let passes = m.cfg.revisit_passes;
    m.cfg.revisit_passes = 0;
    m.grow(ctx)?;
    m.cfg.revisit_passes = passes;
    m.repush_all();
    m.grow(ctx)?;
    // Restarts over the whole cloud for what the slabs left.
    m.restarts(dcfg, rng, ctx)?;
    m.stats.holes_closed = m.close_small_holes(p.close_holes_max);
    if p.stitch_zip {
        m.stats.holes_closed += m.zip_parallel_loops();
    }
    m.stats.holes_filled = fill_phase(&mut m, p);
    end_phase(ctx, "stitch", t_st);
    Ok(take_grown(&mut m))
}

/// IMPL-CHOICE I15, holes: the loops that close whole under `fill_holes_max_edge` R.
fn fill_phase(m: &mut Mesher, p: &PriorityFrontParams) -> u64 {
    let max_edge = p.fill_holes_max_edge * m.cfg.r;
    m.fill_holes(
        max_edge,
        p.fill_holes_edge_rel,
        p.fill_holes_max_loop,
        p.fill_holes_dp,
    )
}

/// IMPL-CHOICE I19 (timed as `inside_out`): regions grown inside out are removed and
/// grown again. Returns how many faces were removed.
fn inside_out_phase(
    grown: &mut Grown,
    lay: &Layout,
    cfg: &Cfg,
    p: &PriorityFrontParams,
    ctx: &mut RunCtx,
) -> Result<usize, MethodError> {
    let t0 = Instant::now();
    let removed = inside_out::regrow_inside_out(
        &regrow_ctx(lay, cfg, p, None),
        grown.mesh(),
        p.inside_out_min_faces,
        ctx,
    )?;
    end_phase(ctx, "inside_out", t0);
    Ok(removed)
}

/// A regrowth step of IMPL-CHOICE I20-I22, timed as phase `name` when `run`; returns
/// what `step` counts.
fn regrow_step(
    ctx: &mut RunCtx,
    name: &str,
    run: bool,
    step: impl FnOnce(&RunCtx) -> Result<u64, MethodError>,
) -> Result<u64, MethodError> {
    if !run {
        return Ok(0);
    }
    let t0 = Instant::now();
    let n = step(ctx)?;
    end_phase(ctx, name, t0);
    Ok(n)
}

/// The growth context of the regrowths of I19 to I22.
fn regrow_ctx<'a>(
    lay: &'a Layout,
    cfg: &'a Cfg,
    p: &PriorityFrontParams,
    insert: Option<complete::CoverBound>,
) -> regrow::Regrow<'a> {
    regrow::Regrow {
        pts: &lay.pts,
        grid: &lay.grid,
        cfg,
        refused0: &lay.refused0,
        close_max: p.close_holes_max,
        fill: fill_bounds(p, cfg),
        insert,
    }
}

/// The IMPL-CHOICE I15 fill bounds at radius `cfg.r`.
fn fill_bounds(p: &PriorityFrontParams, cfg: &Cfg) -> peel::FillBounds {
    peel::FillBounds {
        max_edge: p.fill_holes_max_edge * cfg.r,
        edge_rel: p.fill_holes_edge_rel,
        max_loop: p.fill_holes_max_loop,
        dp: p.fill_holes_dp,
    }
}

/// IMPL-CHOICE I17 (timed as `peel`): the loops left open by the fill, retried with
/// their rim faces removed. Returns how many were closed.
fn peel_phase(
    grown: &mut Grown,
    lay: &Layout,
    cfg: &Cfg,
    p: &PriorityFrontParams,
    ctx: &mut RunCtx,
) -> u64 {
    if p.fill_holes_peel == 0 || p.fill_holes_max_edge <= 0.0 {
        return 0;
    }
    ctx.phase("peel", || {
        peel::peel_refill(
            &lay.pts,
            &lay.grid,
            cfg,
            &lay.refused0,
            grown.mesh(),
            fill_bounds(p, cfg),
            p.fill_holes_peel,
        )
    })
}

/// IMPL-CHOICE I15, points (timed as `complete`): the unmeshed points covered by a
/// triangle are inserted into it. Returns how many.
fn insert_phase(
    grown: &mut Grown,
    lay: &Layout,
    p: &PriorityFrontParams,
    rho: f64,
    ctx: &mut RunCtx,
) -> usize {
    if !p.insert_covered {
        return 0;
    }
    ctx.phase("complete", || {
        complete::insert_covered(
            &lay.pts,
            &lay.grid,
            &mut grown.tris,
            &mut grown.state,
            &lay.refused0,
            cover_bound(p, rho),
        )
    })
}

/// The bounds of the IMPL-CHOICE I15 point insertion.
fn cover_bound(p: &PriorityFrontParams, rho: f64) -> complete::CoverBound {
    complete::CoverBound {
        h_abs: p.free_inside_height * rho,
        h_rel: p.free_inside_rel,
        radius: p.k * rho,
        plane_radius: 2.5 * rho,
        plane_abs: p.insert_height * rho,
        plane_rel: p.insert_rel,
        quadric: p.insert_quadric,
    }
}

/// M9 (timed as `output`): the faces in input indices and the sorted input indices of
/// the points left Free or Refused.
fn output_phase(
    grown: &Grown,
    order: &[u32],
    n: usize,
    ctx: &mut RunCtx,
) -> (Vec<[u32; 3]>, Vec<u32>) {
    ctx.phase("output", || {
        let faces: Vec<[u32; 3]> = grown
            .tris
            .iter()
            .map(|t| t.map(|g| order[g as usize]))
            .collect();
        let mut refused: Vec<u32> = (0..n)
            .filter(|&g| grown.state[g] == FREE || grown.state[g] == REFUSED)
            .map(|g| order[g])
            .collect();
        refused.sort_unstable();
        (faces, refused)
    })
}

/// The operation counts and boundary loops of the run (`pts` in grid order).
fn record_stats(diag: &mut Diagnostics, grown: &Grown, pts: &[DVec3], p: &PriorityFrontParams) {
    let s = &grown.stats;
    num(diag, "seeds", s.seeds as f64);
    num(diag, "front_edges_processed", s.pops as f64);
    num(diag, "boundary_pops", s.boundary_pops as f64);
    num(diag, "joins", s.joins as f64);
    num(diag, "fills", s.fills as f64);
    num(diag, "links", (s.link_next + s.link_prev) as f64);
    num(diag, "link_next", s.link_next as f64);
    num(diag, "link_prev", s.link_prev as f64);
    num(diag, "glues", (s.glues + s.glue_mirrors) as f64);
    num(diag, "glue_mirrors", s.glue_mirrors as f64);
    num(diag, "glue_rejects", s.glue_rejects as f64);
    num(diag, "cross_rejects", s.cross_rejects as f64);
    num(diag, "threads", p.threads as f64);
    num(diag, "fail_rules", s.fail_rules as f64);
    num(diag, "sector_rejects", s.sector_rejects as f64);
    num(diag, "interior_rejects", s.interior_rejects as f64);
    num(diag, "self_rejects", s.self_rejects as f64);
    num(diag, "boundary_loops", grown.loops.len() as f64);
    num(diag, "holes_closed", s.holes_closed as f64);
    num(diag, "holes_filled", s.holes_filled as f64);
    diag.insert(
        "boundary_loop_sizes".into(),
        Diagnostic::Series(grown.loops.iter().map(|l| l.len() as f64).collect()),
    );
    let mut cents = Vec::with_capacity(grown.loops.len() * 3);
    for l in &grown.loops {
        let c = l.iter().map(|&v| pts[v as usize]).sum::<DVec3>() / l.len().max(1) as f64;
        cents.extend([c.x, c.y, c.z]);
    }
    diag.insert("boundary_loop_centroids".into(), Diagnostic::Series(cents));
}

/// A one-line record of every ASSUMPTION flag in force (spec §7 item 9).
fn assumption_flags(p: &PriorityFrontParams) -> String {
    format!(
        "A1={:?} A2=h:{}R A4=m:{} A5/A6=n:{} A9=outward:{} I16=orient_front:{} A11={:?} A12={} A16={} A17=mirror:{} \
         A10=min:{},cap:{} I1=flat<={} I5=elev<={}deg,h<={}rho I10=front_normal<={}deg I8=support:k{},share{},tol{}rho,r{}R I11=support_crease:{} cross={}R free_inside={},h<=max({}rho,{}edge) I13=interior_inside:{} I14=self_check:{} I6=front_inside:{} I7=close<={} I9=stitch_zip:{} I15=fill<=max({}R,{}edge),loop<={},dp:{} I17=peel:{} I18=strays<={} I19=inside_out>={} I20=regrow_loops<={} I21=regrow_points<={} I22=regrow_handles<={} insert:{},plane_h<=max({}rho,{}rms),quadric:{} threads={}",
        p.rho_sample,
        p.grid_cell,
        p.seed_patches,
        p.patch_neighbours,
        p.seed_outward,
        p.seed_orient_front,
        p.score_distance,
        p.apex_angle_rule,
        p.link_prev,
        p.glue_mirror,
        p.restart_min_points,
        p.restart_radius_cap,
        p.restart_max_flatness,
        p.free_elevation_max_deg,
        p.free_height_max,
        p.front_normal_max_deg,
        p.support_neighbours,
        p.support_share,
        p.support_tolerance,
        p.support_radius,
        p.support_crease,
        p.cross_radius,
        p.reject_free_inside,
        p.free_inside_height,
        p.free_inside_rel,
        p.interior_inside_check,
        p.self_intersection_check,
        p.front_inside_check,
        p.close_holes_max,
        p.stitch_zip,
        p.fill_holes_max_edge,
        p.fill_holes_edge_rel,
        p.fill_holes_max_loop,
        p.fill_holes_dp,
        p.fill_holes_peel,
        p.stray_piece_max,
        p.inside_out_min_faces,
        p.regrow_loops_depth,
        p.regrow_points_depth,
        p.regrow_handles_depth,
        p.insert_covered,
        p.insert_height,
        p.insert_rel,
        p.insert_quadric,
        p.threads
    )
}

/// Builds the mesh (all input points as vertices) and the final diagnostics.
fn finish(
    input: &[DVec3],
    faces: Vec<[u32; 3]>,
    refused: Vec<u32>,
    mut diag: Diagnostics,
    t_start: Instant,
    _grow_secs: f64,
) -> Result<Reconstruction, MethodError> {
    let nf = faces.len();
    let mesh = TriMesh::new(input.to_vec(), faces)?;
    let secs = t_start.elapsed().as_secs_f64();
    num(&mut diag, "triangles", nf as f64);
    num(&mut diag, "refused_points", refused.len() as f64);
    num(&mut diag, "seconds", secs);
    num(
        &mut diag,
        "triangles_per_second",
        nf as f64 / secs.max(1e-9),
    );
    Ok(Reconstruction {
        mesh,
        refused,
        diagnostics: diag,
    })
}
