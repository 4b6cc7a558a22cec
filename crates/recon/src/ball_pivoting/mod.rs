//! `ball-pivoting`: the Ball-Pivoting Algorithm of Bernardini, Mittleman, Rushmeier,
//! Silva and Taubin (IEEE TVCG 5(4), 1999), the interpolating baseline of seed 001's
//! Table 2 and of the field (spec `shared/spec/001_priority_driven.md` §6,
//! `000_ma_thesis.md` §3.3).
//!
//! A ball of radius ρ resting on three points with no point inside it gives a seed
//! triangle; the ball then pivots about each front edge, keeping contact with the
//! edge's two end points, until it touches another point, which makes a new triangle
//! (its free edges join the front, edges that close against the front are glued).
//! Point normals orient the triangles and reject inconsistent ones. As in Open3D and
//! MeshLab, several radii run in increasing order: each new pass re-activates the
//! boundary edges whose ball of the new radius is empty, pivots them, and seeds the
//! points still unused.
//!
//! Output: the input points as vertices (duplicates and unused points unreferenced and
//! refused), consistently oriented triangles, and diagnostics: triangles per radius,
//! boundary edges and loops, unused points, pivot failures by cause. Needs oriented
//! normals. See `docs/methods/ball_pivoting.md`.
//!
//! Files: [`params`], `input` (checks and deduplication, shared with `poisson`),
//! `geometry` (ball centres, pivot contacts), `grid` (neighbour rows), `nearest` (each
//! point's nearest other point, for the spacing), `mesher` (front, seeds, pivoting).

mod geometry;
mod grid;
pub(crate) mod input;
mod mesher;
mod nearest;
pub mod params;

use reconbench_geom::cloud::WORKING_SCALE_BITS;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, MethodError, Needs, ParamDoc, Reconstruction, Reconstructor,
    RunCtx,
};
use reconbench_geom::{PointCloud, TriMesh};

pub use params::{BallPivotingParams, PARAM_DOCS};

use crate::diag::num;
use crate::scale::times_pow2;
use mesher::{Mesher, count_loops};

/// Registry name.
pub const NAME: &str = "ball-pivoting";

/// The `ball-pivoting` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct BallPivoting {
    /// Parameters.
    pub params: BallPivotingParams,
}

impl BallPivoting {
    /// A reconstructor with validated parameters.
    pub fn new(params: BallPivotingParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl Describe for BallPivoting {
    const NAME: &'static str = NAME;
    const SOURCE: &'static str = "baseline (Bernardini et al. 1999; seed 001 Table 2)";
    const SUMMARY: &'static str =
        "ball pivoting: an interpolating front grown by a rolling ball, several radii";
    const NEEDS: Needs = Needs::OrientedNormals;
    type Params = BallPivotingParams;
    const PARAMS: &'static [ParamDoc] = PARAM_DOCS;

    fn from_params(params: BallPivotingParams) -> Result<Self, MethodError> {
        Self::new(params)
    }
}

impl Reconstructor for BallPivoting {
    fn name(&self) -> &str {
        NAME
    }

    /// Runs at the exact working scale (`crate::scale`): pivoting tests only ratios of
    /// lengths, so a cloud multiplied by a power of two gives the same faces; explicit
    /// `radii` are moved with the cloud and the length diagnostics moved back.
    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        self.params.validate()?;
        crate::scale::reconstruct_at_scale(NAME, cloud, WORKING_SCALE_BITS, |cloud, s| {
            self.pivot(cloud, s, ctx)
        })
    }
}

impl BallPivoting {
    /// The algorithm on `cloud`, the input multiplied by `2^s`.
    fn pivot(
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
        let radii: Vec<f64> = if p.radii.is_empty() {
            p.radii_spacing.iter().map(|k| k * prep.spacing).collect()
        } else {
            p.radii.iter().map(|&r| times_pow2(r, s)).collect()
        };
        // A radius that under- or overflows next to the (moved) cloud is absurd for it.
        if let Some(i) = radii.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
            let (name, given) = if p.radii.is_empty() {
                ("radii_spacing", p.radii_spacing[i])
            } else {
                ("radii", p.radii[i])
            };
            return Err(MethodError::InvalidParameter {
                name: name.into(),
                message: format!(
                    "{given:e} gives a ball radius of {:e} in working units (cloud multiplied \
                     by 2^{s}), not a finite positive double",
                    radii[i]
                ),
            });
        }
        // The mesher works on the points in grid-cell order (neighbours close in memory);
        // every decision that depends on the index order uses the working index
        // (`perm`), so the mesh is the same as in input order. The grid of the first
        // radius gives that order and, permuted, is the first pass's grid.
        let grid0 = grid::CellGrid::new(&prep.pos, 2.0 * radii[0]);
        let perm = grid0.items().to_vec();
        let mut first_grid = Some(grid0.into_permuted());
        let pos: Vec<_> = perm.iter().map(|&i| prep.pos[i as usize]).collect();
        let nrm: Vec<_> = perm.iter().map(|&i| prep.nrm[i as usize]).collect();
        let mut m = Mesher::new(&pos, &nrm, &perm);
        let mut per_radius = Vec::with_capacity(radii.len());
        let mut stop: Option<MethodError> = None;
        let target = 2.0 * prep.pos.len() as f64;
        {
            let _g = ctx.phase_guard("pivot");
            let mut poll = |tris: usize| match ctx.checkpoint() {
                Ok(()) => {
                    ctx.progress((tris as f64 / target).min(0.99));
                    true
                }
                Err(e) => {
                    stop = Some(e);
                    false
                }
            };
            'radii: for (r, &rho) in radii.iter().enumerate() {
                let active: Vec<u32> = if r == 0 {
                    (0..prep.pos.len() as u32).collect()
                } else {
                    m.active_points()
                };
                m.begin_pass(rho, &active, if r == 0 { first_grid.take() } else { None });
                let before = m.tris.len();
                if r > 0 {
                    m.reactivate();
                }
                m.expand(&mut poll);
                let mut cursor = 0;
                while m.find_seed(&mut cursor) {
                    m.expand(&mut poll);
                    if !poll(m.tris.len()) {
                        break 'radii;
                    }
                }
                per_radius.push((m.tris.len() - before) as f64);
            }
        }
        if let Some(e) = stop {
            return Err(e);
        }

        let boundary: Vec<(u32, u32)> = m
            .boundary_edges()
            .into_iter()
            .map(|(a, b)| (perm[a as usize], perm[b as usize]))
            .collect();
        let loops = count_loops(prep.pos.len(), &boundary);
        let faces: Vec<[u32; 3]> = m
            .tris
            .iter()
            .map(|t| t.map(|v| prep.ids[perm[v as usize] as usize]))
            .collect();
        let mut referenced = vec![false; cloud.len()];
        for f in &faces {
            for &v in f {
                referenced[v as usize] = true;
            }
        }
        let refused: Vec<u32> = (0..cloud.len() as u32)
            .filter(|&i| !referenced[i as usize])
            .collect();
        let unused = (0..prep.pos.len()).filter(|&i| !m.is_used(i)).count();

        let mut d = Diagnostics::new();
        num(&mut d, "spacing", times_pow2(prep.spacing, -s));
        d.insert(
            "radii".into(),
            Diagnostic::Series(radii.iter().map(|&r| times_pow2(r, -s)).collect()),
        );
        d.insert(
            "triangles_per_radius".into(),
            Diagnostic::Series(per_radius),
        );
        num(&mut d, "boundary_edges", boundary.len() as f64);
        num(&mut d, "boundary_loops", loops as f64);
        num(&mut d, "unused_points", unused as f64);
        num(&mut d, "duplicates", prep.duplicates as f64);
        num(&mut d, "zero_normals", prep.zero_normals as f64);
        num(&mut d, "flipped_share", prep.flipped_share);
        let c = m.counts;
        num(&mut d, "seeds", c.seeds as f64);
        num(&mut d, "glued", c.glued as f64);
        num(&mut d, "reactivated", c.reactivated as f64);
        num(&mut d, "pivot_no_hit", c.no_hit as f64);
        num(&mut d, "pivot_inner_hit", c.inner_hit as f64);
        num(&mut d, "pivot_edge_conflict", c.edge_conflict as f64);
        num(&mut d, "pivot_normal_conflict", c.normal_conflict as f64);

        let mesh = TriMesh::new(cloud.positions().to_vec(), faces)?;
        Ok(Reconstruction {
            mesh,
            refused,
            diagnostics: d,
        })
    }
}
