//! Parameters of `priority-front` (spec 001 §2 and the ASSUMPTION register §4.10).

use reconbench_geom::method::{Describe, MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// How many points the density estimate ρ samples (ASSUMPTION A1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum RhoSample {
    /// `s = min(N, max(100, ceil(0.05 N)))`: "100 points or up to 5 %" (the default).
    #[default]
    Max100Or5Percent,
    /// `s = min(N, 100)`: the other reading of the paper's sentence.
    Fixed100,
}

/// What `d(t)` in the score term `(R - d)/R` measures (ASSUMPTION A11).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ScoreDistance {
    /// Distance to the edge midpoint `o` (the paper's Step 1 wording; default).
    #[default]
    Midpoint,
    /// Distance to the edge segment `ab` (the paper's Eq. 7 wording).
    Segment,
}

/// Parameters of [`super::PriorityFront`]. Lengths are in units of the estimated mean
/// nearest-neighbour distance ρ unless said otherwise; angles are in degrees. Defaults
/// are the paper's (spec 001 §2) and the spec's ASSUMPTION choices.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PriorityFrontParams {
    /// Search-radius multiplier k: the candidate ball has radius R = k·ρ (paper: 4).
    pub k: f64,
    /// Upper bound α_max on every triangle angle, degrees (paper: 120).
    pub alpha_max_deg: f64,
    /// Upper bound β_max on the normal change across the front edge, degrees (paper: 90).
    pub beta_max_deg: f64,
    /// Weight w1 of cos β in the candidate score C (paper: 1; raise for noisy data).
    pub w1: f64,
    /// Weight w2 of cos γ (isosceles-ness) in the score (paper: 1).
    pub w2: f64,
    /// Weight w3 of the proximity term (R - d)/R in the score (paper: 1).
    pub w3: f64,
    /// Number m of random patches tried for a seed (paper: 5..10; ASSUMPTION A4: 8).
    pub seed_patches: usize,
    /// Nearest Free neighbours of a patch centre, = fan triangles n (paper: 10..15;
    /// ASSUMPTION A5/A6: 12).
    pub patch_neighbours: usize,
    /// ρ sample-size rule (ASSUMPTION A1).
    pub rho_sample: RhoSample,
    /// Hash-grid cell edge in units of R (ASSUMPTION A2: 1). Performance only: results do
    /// not depend on it.
    pub grid_cell: f64,
    /// What d(t) in the score measures (ASSUMPTION A11).
    pub score_distance: ScoreDistance,
    /// Also apply Rule 1 to the apex angle at t (ASSUMPTION A12). Default **false**, a
    /// documented deviation from the spec's `true`: with the apex rule, Free points close
    /// to a front edge are skipped and then covered by the next triangle, so about 3x
    /// more clean points end up refused (6k torus: 4.5 % vs 1.3 %; see
    /// docs/methods/priority_front.md). `true` = the spec's reading.
    pub apex_angle_rule: bool,
    /// Orient the seed triangle's normal away from the cloud centroid (ASSUMPTION A9;
    /// default true). When false the seed keeps the fan orientation of its patch.
    pub seed_outward: bool,
    /// Orient whole pieces rather than seed triangles (IMPL-CHOICE I16, not in the
    /// paper; default true, a deviation for issue 20): before the two-thread stitch each
    /// slab piece takes the orientation of the facing front of the slabs before it, and
    /// every output piece whose signed volume seen from the centroid is negative is
    /// reversed. A9 alone orients one seed triangle, which is wrong when it lands in a
    /// concave region. false = A9 only.
    pub seed_orient_front: bool,
    /// Allow link-prev, the mirror of the paper's link (ASSUMPTION A16; default true).
    pub link_prev: bool,
    /// Try the mirror repair when glue's second triangle fails (ASSUMPTION A17; default
    /// true). When false a failing glue rejects the candidate at once.
    pub glue_mirror: bool,
    /// Radius, in units of R, of the neighbourhood whose front edges the 2-D crossing test
    /// checks (spec §4.4 Step 4: 2).
    pub cross_radius: f64,
    /// Optional strictness flag of spec §4.4 (not in the paper): reject t when another
    /// Free point projects strictly inside the 2-D triangle (a, t, b). Default **true**, a
    /// deviation from the spec's false (issue 20): a Free point under a triangle can never
    /// be meshed without a fold, and on non-uniform real vertex sets such covered points
    /// were where the front later folded over the mesh (self-intersections, false
    /// handles); see docs/methods/priority_front.md, "Real data".
    pub reject_free_inside: bool,
    /// With `reject_free_inside`: only Free points within this height, in units of ρ, of
    /// the plane of (a, t, b) block it (IMPL-CHOICE I12, not in the spec; default 0.5;
    /// 1000 = every Free point, the spec's flag). Points well off the triangle's plane
    /// (outliers, the other sheet of a thin part) then do not block it.
    pub free_inside_height: f64,
    /// With `reject_free_inside`: Free points within this share of the triangle's
    /// longest edge of its plane block it too, when that is more than
    /// `free_inside_height` ρ (IMPL-CHOICE I12; default 0.25; 0 = the absolute bound
    /// alone). Long triangles on a curved surface rise farther above the points they
    /// cover.
    pub free_inside_rel: f64,
    /// IMPL-CHOICE I13 (issue 20, not in the paper or the spec; default false): reject t
    /// when an interior mesh vertex (accepted, no front edge) within R of the edge
    /// midpoint lies near the plane of (a, t, b) (the I12 height bound) and inside it in
    /// 2-D: the triangle would lie on top of the mesh already made (a second layer, a
    /// fold), which the crossing test cannot see because there is no front edge in the
    /// interior. Off by default: it removes most false handles on the real vertex sets
    /// but leaves a hole on the blue-noise fandisk-like shape (li_variety), see
    /// docs/methods/priority_front.md, "Real data". false = the paper.
    pub interior_inside_check: bool,
    /// Reject a candidate triangle (and a glue's repair triangle) that intersects a mesh
    /// triangle sharing none of its vertices (IMPL-CHOICE I14, not in the paper; exact
    /// predicates, the self-intersection metric's test): the 2-D crossing and inside
    /// tests see one projection plane, so a front that reaches another sheet across a
    /// thin part or a notch can cut through the mesh there. false = the paper; default
    /// true (a deviation, issue 20).
    pub self_intersection_check: bool,
    /// Reject a candidate when a front vertex near the edge projects strictly inside the
    /// 2-D triangle (a, t, b) (IMPL-CHOICE I6, not in the paper; default true): the
    /// triangle would fold over the front, which the edge-crossing test misses when a
    /// whole piece of front lies inside it. Such folds leave holes that cannot close.
    pub front_inside_check: bool,
    /// Waive Rule 1 for FILL, whose 3-edge hole has only one possible triangle
    /// (IMPL-CHOICE I3, not in the paper; default true). False = the paper's rule.
    pub fill_any_angle: bool,
    /// Require the new edges to leave a, b (and a front point t) inside their free
    /// sector in the projection plane (IMPL-CHOICE I4, not in the paper; default true).
    pub sector_check: bool,
    /// Extra passes over the live front once the heap is empty (IMPL-CHOICE I2, not in
    /// the paper, whose edges that fail once stay boundary forever; default 4). 0 = the
    /// paper's behaviour.
    pub revisit_passes: u32,
    /// Largest elevation, degrees, of a *Free* candidate t above the mesh's tangent plane
    /// at the edge midpoint (the plane normal is the sum of the fan normals of a and b):
    /// `asin(|(t - o) . n_v| / |t - o|)` (IMPL-CHOICE I5, not in the paper; default 30).
    /// Front points (link / glue / fill) are exempt. The paper's Rule 2 compares with the
    /// one adjacent triangle only, so chains of tilted triangles grow into outlier clouds;
    /// this robust reading of §4.4 keeps off-surface points out. 90 disables it.
    pub free_elevation_max_deg: f64,
    /// Largest height, in units of ρ, of a *Free* candidate above the same tangent plane
    /// (IMPL-CHOICE I5, with the elevation bound; default 0.5). Bounds how far off the
    /// surface a single accepted point can lie when it is the only candidate left.
    /// 1000 disables it.
    pub free_height_max: f64,
    /// Largest angle, degrees, between the fan normal of a *front* candidate t (link /
    /// glue; FILL is exempt) and the fan normal at the popped edge (IMPL-CHOICE I10,
    /// not in the paper; default 150). The two sheets of a thin part are meshed with
    /// opposite orientations; the paper's Rule 2 compares the new triangle with the one
    /// triangle across the edge only, so a link or glue to the other sheet's front
    /// passes it (the triangle stands at about 90° to both) and bridges the sheets.
    /// 180 = off (the paper).
    pub front_normal_max_deg: f64,
    /// Neighbours of the support test of IMPL-CHOICE I8 (not in the paper; default
    /// 12): a Free candidate above the I5 height cap (but within the elevation bound) is
    /// still accepted when all its this many nearest other points lie within R and a
    /// plane through it holds at least `support_share` of them within
    /// `support_tolerance ρ`. Points just across a crease pass (the face they lie on is
    /// behind them); outliers do not. 0 = off (the I5 cap alone).
    pub support_neighbours: usize,
    /// Plane tolerance of IMPL-CHOICE I8, in units of ρ (default 0.25).
    pub support_tolerance: f64,
    /// Share of the neighbours the I8 support plane must hold (default 0.5).
    pub support_share: f64,
    /// IMPL-CHOICE I11 (not in the paper; default true): a Free candidate let in by the
    /// I8 support test must lie on a plane that meets the tangent plane at the edge
    /// midpoint o within the candidate's distance from o, as the far face of a crease
    /// does. The other sheet of a thin part (parallel to this one, within R) fails, and
    /// is no longer bridged. false = I8 alone.
    pub support_crease: bool,
    /// Slab stitch (threads > 1): grow each Free band from the even-numbered slab's
    /// front first, then all fronts (default true); false = all fronts at once.
    pub stitch_one_sided: bool,
    /// Slab stitch (threads > 1): zip pairs of parallel front loops left along a cut
    /// (IMPL-CHOICE I9; default true).
    pub stitch_zip: bool,
    /// Search radius of the I8 neighbours, in units of R (default 2; all
    /// `support_neighbours` must lie within it, so an outlier in the volume fails).
    pub support_radius: f64,
    /// Close leftover front loops of at most this many vertices (all edges shorter than
    /// 2R) by ear clipping with LINK / FILL after growth (IMPL-CHOICE I7, not in the
    /// paper, which leaves them to an external hole filler; default 10). 0 = off (the
    /// paper). Larger loops stay and are reported as holes / boundaries.
    pub close_holes_max: usize,
    /// Surface completion, holes (IMPL-CHOICE I15, a deviation; issue 20): after
    /// growth, every loop that ear clipping closes whole with new edges at most this
    /// many R long (no fold over 150 degrees, no crossing) is closed; wider holes are
    /// kept untouched. 0 = off (the paper). Default 1.
    pub fill_holes_max_edge: f64,
    /// I15: where the loop's own longest edge times this exceeds `fill_holes_max_edge`
    /// R, that is the bound on new edges instead (sparse regions of CAD vertex sets,
    /// whose edges exceed R; default 1.5).
    pub fill_holes_edge_rel: f64,
    /// Loops of more vertices than this are not tried by the I15 hole fill (cost
    /// bound; default 4096).
    pub fill_holes_max_loop: usize,
    /// I15: a loop that greedy ear clipping cannot close is triangulated by dynamic
    /// programming instead (the least-folded triangulation over all that use only the
    /// loop's vertices, under the same bounds; loops of at most 400 vertices). false =
    /// ears only. Default true.
    pub fill_holes_dp: bool,
    /// IMPL-CHOICE I17: a loop the I15 fillers cannot close is enlarged by removing the
    /// faces within 1, 2, ... up to this many edge steps of it, and the enlarged loop
    /// is filled; where that fails too, the faces are put back. 0 = off. Default 2.
    pub fill_holes_peel: usize,
    /// IMPL-CHOICE I18: after growth, a piece (component) of at most this many vertices
    /// whose vertices all lie within R of the larger pieces is taken apart and its
    /// points freed for the completion (restart seeds grow such pieces over finished
    /// mesh). 0 = off (the paper). Default 20.
    pub stray_piece_max: usize,
    /// IMPL-CHOICE I19: when loops are left open after growth, regions of at least this
    /// many faces that point into the solid (ray parity against their piece's
    /// majority) are removed with the faces touching them and their area is grown
    /// again from the new border; kept only when fewer boundary edges remain. 0 = off
    /// (the paper). Default 20.
    pub inside_out_min_faces: usize,
    /// IMPL-CHOICE I20: a loop still open after the fills is grown again after the
    /// faces within d vertex steps of it are removed, for d = 1 up to this depth; a
    /// regrowth is kept only when it leaves fewer open boundary edges, no more handles
    /// and no more unmeshed points. 0 = off (the paper). Default 3.
    pub regrow_loops_depth: usize,
    /// IMPL-CHOICE I21: a point left unmeshed within R of the mesh (at most 64 per run,
    /// nearest first) is offered to a regrowth of the faces within d vertex steps of
    /// the meshed points near it, for d = 0 up to this depth minus one; kept only when
    /// fewer points stay unmeshed, with the same pieces and no handle or open edge
    /// more. 0 = off (the paper). Default 5.
    pub regrow_points_depth: usize,
    /// IMPL-CHOICE I22: when the mesh has handles, the faces within d vertex steps of
    /// the ends of its sheet-crossing edges (edges along the cloud's local plane normal
    /// at both ends) are grown again, for d = 0 up to this depth minus one; kept only
    /// with fewer handles, the same pieces and no open edge or unmeshed point more.
    /// 0 = off (the paper). Default 4.
    pub regrow_handles_depth: usize,
    /// Surface completion, points (IMPL-CHOICE I15): every point left unmeshed that
    /// lies on its meshed neighbours' surface and projects into a triangle within the
    /// I12 height bound of it (a covered point; further above a chamfer for a crease
    /// vertex) is inserted there. false = the paper (such points are refused). Default
    /// true.
    pub insert_covered: bool,
    /// I15: a covered point is inserted only when it lies within max(`insert_height`
    /// rho, `insert_rel` x their RMS residual) of the least-squares plane of its 12
    /// nearest neighbours; others stay refused as noise (default 0.1).
    pub insert_height: f64,
    /// I15: relative part of that bound, in RMS residuals of the neighbours (default 3).
    pub insert_rel: f64,
    /// I15: a point off that plane passes when it lies on the least-squares quadric of
    /// the same neighbours within the same bound (by the fit's residual standard error):
    /// surface points on curved patches, whose plane residual is mostly curvature.
    /// false = the plane test alone. Default true.
    pub insert_quadric: bool,
    /// Multi-seed restart while Free point patches remain (spec M8; default true).
    pub restart: bool,
    /// Minimum size of a Free point patch (R-graph component) that triggers a restart
    /// (ASSUMPTION A10: 10).
    pub restart_min_points: usize,
    /// Cap of the restart radius in units of the original R₀ (ASSUMPTION A10: 2).
    pub restart_radius_cap: f64,
    /// Restart seeds must have a patch flatness score `1 - |mean normal|²` at most this
    /// (IMPL-CHOICE I1, not in the paper; default 0.2) and all their patch neighbours
    /// within the restart radius. Keeps restarts out of outlier clouds. The first seed is
    /// exempt. Set to 1 to disable the flatness part.
    pub restart_max_flatness: f64,
    /// Upper bound on the number of seeds (first + restarts); 0 = no bound.
    pub max_seeds: usize,
    /// Force the first seed patch centre to this input point index (spec §4.2 "seed
    /// override"); `None` = automatic.
    pub seed_point: Option<u32>,
    /// Worker threads for the slab-parallel growth (paper §3.7.1, Table 3). 1 = the
    /// sequential algorithm. Output is deterministic for a fixed thread count.
    pub threads: usize,
}

impl Default for PriorityFrontParams {
    fn default() -> Self {
        Self {
            k: 4.0,
            alpha_max_deg: 120.0,
            beta_max_deg: 90.0,
            w1: 1.0,
            w2: 1.0,
            w3: 1.0,
            seed_patches: 8,
            patch_neighbours: 12,
            rho_sample: RhoSample::default(),
            grid_cell: 1.0,
            score_distance: ScoreDistance::default(),
            apex_angle_rule: false,
            seed_outward: true,
            // DEVIATION (issue 20): IMPL-CHOICE I16; A9 alone left restarted and slab
            // pieces inverted on the golf club, mechpart and bunny
            // (docs/methods/priority_front.md).
            seed_orient_front: true,
            link_prev: true,
            glue_mirror: true,
            cross_radius: 2.0,
            // DEVIATION (issue 20): the spec's default is false; on real vertex sets
            // covered Free points were where the front folded over the mesh
            // (docs/methods/priority_front.md, "Deviation: reject_free_inside").
            reject_free_inside: true,
            free_inside_height: 0.5,
            free_inside_rel: 0.25,
            interior_inside_check: false,
            // DEVIATION (issue 20): IMPL-CHOICE I14 on by default; without it the real
            // vertex sets fold over the mesh (mechpart genus 6-16 instead of 3).
            self_intersection_check: true,
            front_inside_check: true,
            fill_any_angle: true,
            sector_check: true,
            revisit_passes: 4,
            free_elevation_max_deg: 30.0,
            free_height_max: 0.5,
            front_normal_max_deg: 150.0,
            support_neighbours: 12,
            support_tolerance: 0.25,
            support_share: 0.5,
            support_crease: true,
            support_radius: 2.0,
            stitch_one_sided: true,
            stitch_zip: true,
            close_holes_max: 10,
            // DEVIATION (issue 20): surface completion, IMPL-CHOICE I15.
            fill_holes_max_edge: 1.0,
            fill_holes_edge_rel: 1.5,
            fill_holes_max_loop: 4096,
            fill_holes_dp: true,
            fill_holes_peel: 2,
            insert_covered: true,
            insert_height: 0.1,
            insert_rel: 3.0,
            insert_quadric: true,
            stray_piece_max: 20,
            inside_out_min_faces: 20,
            regrow_loops_depth: 3,
            regrow_points_depth: 5,
            regrow_handles_depth: 4,
            restart: true,
            restart_min_points: 10,
            restart_radius_cap: 2.0,
            restart_max_flatness: 0.2,
            max_seeds: 0,
            seed_point: None,
            threads: 1,
        }
    }
}

fn bad(name: &str, message: impl Into<String>) -> MethodError {
    MethodError::InvalidParameter {
        name: name.to_string(),
        message: message.into(),
    }
}

impl PriorityFrontParams {
    /// Checks ranges; returns the first offending parameter.
    pub fn validate(&self) -> Result<(), MethodError> {
        let finite_pos = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(name, format!("must be finite and > 0, got {v}")))
            }
        };
        finite_pos("k", self.k)?;
        finite_pos("grid_cell", self.grid_cell)?;
        finite_pos("cross_radius", self.cross_radius)?;
        finite_pos("restart_radius_cap", self.restart_radius_cap)?;
        if self.k > 1000.0 {
            return Err(bad("k", format!("must be <= 1000, got {}", self.k)));
        }
        if !(self.grid_cell >= 0.125 && self.grid_cell <= 8.0) {
            return Err(bad("grid_cell", "must be in [0.125, 8]"));
        }
        if !(self.alpha_max_deg > 60.0 && self.alpha_max_deg <= 180.0) {
            return Err(bad(
                "alpha_max_deg",
                format!("must be in (60, 180], got {}", self.alpha_max_deg),
            ));
        }
        if !(self.beta_max_deg > 0.0 && self.beta_max_deg <= 180.0) {
            return Err(bad(
                "beta_max_deg",
                format!("must be in (0, 180], got {}", self.beta_max_deg),
            ));
        }
        for (n, w) in [("w1", self.w1), ("w2", self.w2), ("w3", self.w3)] {
            if !(w.is_finite() && w >= 0.0) {
                return Err(bad(n, format!("must be finite and >= 0, got {w}")));
            }
        }
        if self.seed_patches == 0 || self.seed_patches > 10_000 {
            return Err(bad("seed_patches", "must be in 1..=10000"));
        }
        if self.patch_neighbours < 2 || self.patch_neighbours > 1000 {
            return Err(bad("patch_neighbours", "must be in 2..=1000"));
        }
        if self.restart_min_points < 3 {
            return Err(bad("restart_min_points", "must be >= 3"));
        }
        if !(0.0..=1.0).contains(&self.restart_max_flatness) {
            return Err(bad("restart_max_flatness", "must be in [0, 1]"));
        }
        if !(self.free_elevation_max_deg > 0.0 && self.free_elevation_max_deg <= 90.0) {
            return Err(bad(
                "free_elevation_max_deg",
                format!("must be in (0, 90], got {}", self.free_elevation_max_deg),
            ));
        }
        if !(self.free_height_max > 0.0 && self.free_height_max <= 1000.0) {
            return Err(bad(
                "free_height_max",
                format!("must be in (0, 1000], got {}", self.free_height_max),
            ));
        }
        if !(self.front_normal_max_deg > 0.0 && self.front_normal_max_deg <= 180.0) {
            return Err(bad(
                "front_normal_max_deg",
                format!("must be in (0, 180], got {}", self.front_normal_max_deg),
            ));
        }
        if !(self.free_inside_height > 0.0 && self.free_inside_height <= 1000.0) {
            return Err(bad(
                "free_inside_height",
                format!("must be in (0, 1000], got {}", self.free_inside_height),
            ));
        }
        if !(0.0..=10.0).contains(&self.free_inside_rel) {
            return Err(bad(
                "free_inside_rel",
                format!("must be in [0, 10], got {}", self.free_inside_rel),
            ));
        }
        if self.support_neighbours > 1000 {
            return Err(bad("support_neighbours", "must be <= 1000"));
        }
        if !(self.support_tolerance >= 0.0 && self.support_tolerance <= 1000.0) {
            return Err(bad(
                "support_tolerance",
                format!("must be in [0, 1000], got {}", self.support_tolerance),
            ));
        }
        if !(self.support_radius > 0.0 && self.support_radius <= 100.0) {
            return Err(bad(
                "support_radius",
                format!("must be in (0, 100], got {}", self.support_radius),
            ));
        }
        if !(self.support_share > 0.0 && self.support_share <= 1.0) {
            return Err(bad(
                "support_share",
                format!("must be in (0, 1], got {}", self.support_share),
            ));
        }
        if self.stray_piece_max > 1_000_000 {
            return Err(bad(
                "stray_piece_max",
                format!("must be at most 1000000, got {}", self.stray_piece_max),
            ));
        }
        if self.inside_out_min_faces > 1_000_000_000 {
            return Err(bad(
                "inside_out_min_faces",
                format!("must be at most 1e9, got {}", self.inside_out_min_faces),
            ));
        }
        for (name, depth) in [
            ("regrow_loops_depth", self.regrow_loops_depth),
            ("regrow_points_depth", self.regrow_points_depth),
            ("regrow_handles_depth", self.regrow_handles_depth),
        ] {
            if depth > 8 {
                return Err(bad(name, format!("must be at most 8, got {depth}")));
            }
        }
        if self.close_holes_max > 1_000_000 {
            return Err(bad("close_holes_max", "must be <= 1000000"));
        }
        if !(self.fill_holes_max_edge >= 0.0 && self.fill_holes_max_edge <= 100.0) {
            return Err(bad(
                "fill_holes_max_edge",
                format!(
                    "must be in [0, 100] (units of R), got {}",
                    self.fill_holes_max_edge
                ),
            ));
        }
        if !(self.fill_holes_edge_rel >= 0.0 && self.fill_holes_edge_rel <= 100.0) {
            return Err(bad(
                "fill_holes_edge_rel",
                format!("must be in [0, 100], got {}", self.fill_holes_edge_rel),
            ));
        }
        if !(self.insert_height >= 0.0 && self.insert_height <= 1000.0) {
            return Err(bad(
                "insert_height",
                format!("must be in [0, 1000] (rho), got {}", self.insert_height),
            ));
        }
        if !(self.insert_rel >= 0.0 && self.insert_rel <= 1000.0) {
            return Err(bad(
                "insert_rel",
                format!("must be in [0, 1000], got {}", self.insert_rel),
            ));
        }
        if self.fill_holes_peel > 8 {
            return Err(bad("fill_holes_peel", "must be <= 8"));
        }
        if self.fill_holes_max_loop > 1_000_000 {
            return Err(bad("fill_holes_max_loop", "must be <= 1000000"));
        }
        if self.revisit_passes > 1000 {
            return Err(bad("revisit_passes", "must be <= 1000"));
        }
        if self.threads == 0 || self.threads > 256 {
            return Err(bad("threads", "must be in 1..=256"));
        }
        Ok(())
    }
}

/// Docs of every parameter of [`PriorityFrontParams`], in `list` order.
pub const PARAM_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "k",
        Unit::Spacing,
        "candidate ball radius R = k * rho (paper: 4)",
    ),
    ParamDoc::new(
        "free_inside_rel",
        Unit::None,
        "I12: Free points within this share of the triangle's longest edge of its plane block it too (0.25)",
    ),
    ParamDoc::new(
        "alpha_max_deg",
        Unit::Deg,
        "upper bound on every triangle angle (paper: 120)",
    ),
    ParamDoc::new(
        "beta_max_deg",
        Unit::Deg,
        "upper bound on the normal change across the front edge (paper: 90)",
    ),
    ParamDoc::new("w1", Unit::None, "score weight of cos(beta) (paper: 1)"),
    ParamDoc::new("w2", Unit::None, "score weight of cos(gamma) (paper: 1)"),
    ParamDoc::new("w3", Unit::None, "score weight of (R - d)/R (paper: 1)"),
    ParamDoc::new(
        "seed_patches",
        Unit::Count,
        "random patches tried for a seed, m (A4: 8)",
    ),
    ParamDoc::new(
        "patch_neighbours",
        Unit::Count,
        "neighbours / fan triangles per patch, n (A5/A6: 12)",
    ),
    ParamDoc::new(
        "rho_sample",
        Unit::Choice,
        "rho sample rule: max100-or5-percent (A1) or fixed100",
    ),
    ParamDoc::new(
        "grid_cell",
        Unit::None,
        "hash-grid cell edge in units of R (A2: 1; speed only)",
    ),
    ParamDoc::new(
        "score_distance",
        Unit::Choice,
        "d(t) of the score: midpoint (A11) or segment",
    ),
    ParamDoc::new(
        "apex_angle_rule",
        Unit::Flag,
        "apply alpha_max to the apex angle too (A12; default false, spec: true)",
    ),
    ParamDoc::new(
        "seed_outward",
        Unit::Flag,
        "orient the seed away from the centroid (A9)",
    ),
    ParamDoc::new(
        "seed_orient_front",
        Unit::Flag,
        "I16: orient slab pieces by the facing front before the stitch and every output piece outward (true; false = A9 only)",
    ),
    ParamDoc::new(
        "link_prev",
        Unit::Flag,
        "allow the mirrored link operation (A16)",
    ),
    ParamDoc::new(
        "glue_mirror",
        Unit::Flag,
        "try the mirrored glue repair (A17)",
    ),
    ParamDoc::new(
        "cross_radius",
        Unit::None,
        "front edges within this many R are crossing-tested (spec: 2)",
    ),
    ParamDoc::new(
        "reject_free_inside",
        Unit::Flag,
        "reject t when a Free point lies inside (a,t,b) in 2-D (true; spec: false; issue 20)",
    ),
    ParamDoc::new(
        "free_inside_height",
        Unit::Spacing,
        "I12: with reject_free_inside, only Free points this close to the triangle's plane block it, in rho (0.5; 1000 = all)",
    ),
    ParamDoc::new(
        "self_intersection_check",
        Unit::Flag,
        "I14: reject t when (a,t,b) would intersect a mesh triangle sharing no vertex with it (true; false = paper)",
    ),
    ParamDoc::new(
        "interior_inside_check",
        Unit::Flag,
        "I13: reject t when an interior mesh vertex lies inside (a,t,b) in 2-D near its plane (false; issue 20)",
    ),
    ParamDoc::new(
        "front_inside_check",
        Unit::Flag,
        "reject t when a front vertex lies inside (a,t,b) in 2-D (I6; true)",
    ),
    ParamDoc::new(
        "fill_any_angle",
        Unit::Flag,
        "waive Rule 1 for FILL of a 3-edge hole (I3; true)",
    ),
    ParamDoc::new(
        "sector_check",
        Unit::Flag,
        "new edges must lie in the free sector of their end vertices (I4; true)",
    ),
    ParamDoc::new(
        "revisit_passes",
        Unit::Count,
        "passes over the live front after the heap empties (I2: 4; 0 = paper)",
    ),
    ParamDoc::new(
        "free_elevation_max_deg",
        Unit::Deg,
        "max elevation of a Free candidate above the fan tangent plane (I5: 30; 90 = off)",
    ),
    ParamDoc::new(
        "free_height_max",
        Unit::Spacing,
        "max height of a Free candidate above the fan tangent plane, in rho (I5: 0.5)",
    ),
    ParamDoc::new(
        "front_normal_max_deg",
        Unit::Deg,
        "I10: max angle between the fan normals of a front candidate and of the edge (150; 180 = off)",
    ),
    ParamDoc::new(
        "support_neighbours",
        Unit::Count,
        "I8: neighbours of the support plane that lets a Free point above the I5 cap in (12; 0 = off)",
    ),
    ParamDoc::new(
        "support_tolerance",
        Unit::Spacing,
        "I8: distance tolerance of the support plane, in rho (0.25)",
    ),
    ParamDoc::new(
        "stitch_one_sided",
        Unit::Flag,
        "threads > 1: sweep each slab band from one side first (true)",
    ),
    ParamDoc::new(
        "stitch_zip",
        Unit::Flag,
        "threads > 1: zip pairs of parallel front loops left along a slab cut (I9: true)",
    ),
    ParamDoc::new(
        "support_radius",
        Unit::None,
        "I8: neighbour search radius in units of R (2)",
    ),
    ParamDoc::new(
        "support_share",
        Unit::None,
        "I8: share of the neighbours the support plane must hold (0.5)",
    ),
    ParamDoc::new(
        "support_crease",
        Unit::Flag,
        "I11: an I8-supported point must lie on a plane meeting the edge's tangent plane near it (true)",
    ),
    ParamDoc::new(
        "close_holes_max",
        Unit::Count,
        "ear-clip leftover loops of at most this many vertices (I7: 10; 0 = paper)",
    ),
    ParamDoc::new(
        "fill_holes_max_edge",
        Unit::None,
        "I15: close loops that ear clipping closes whole with new edges <= this x R (1; 0 = paper)",
    ),
    ParamDoc::new(
        "fill_holes_edge_rel",
        Unit::None,
        "I15: or this x the loop's longest edge where larger (sparse regions; 1.5)",
    ),
    ParamDoc::new(
        "fill_holes_max_loop",
        Unit::Count,
        "I15: loops with more vertices are not tried (4096)",
    ),
    ParamDoc::new(
        "fill_holes_dp",
        Unit::Flag,
        "I15: loops the ears cannot close are triangulated by dynamic programming, least largest fold (true; false = ears only)",
    ),
    ParamDoc::new(
        "fill_holes_peel",
        Unit::Count,
        "I17: loops the fillers cannot close are retried with up to this many rings of rim faces removed, which are put back on failure (2; 0 = off)",
    ),
    ParamDoc::new(
        "insert_covered",
        Unit::Flag,
        "I15: insert unmeshed points covered by a triangle into it (true; false = paper)",
    ),
    ParamDoc::new(
        "insert_height",
        Unit::Spacing,
        "I15: insert a covered point only within this height of its neighbours' plane, in rho (0.1)",
    ),
    ParamDoc::new(
        "insert_rel",
        Unit::None,
        "I15: ... or within this many RMS residuals of the neighbours from that plane (3)",
    ),
    ParamDoc::new(
        "stray_piece_max",
        Unit::Count,
        "I18: free the points of pieces of at most this many vertices lying within R of larger pieces (20)",
    ),
    ParamDoc::new(
        "inside_out_min_faces",
        Unit::Count,
        "I19: regrow regions of at least this many faces that point into the solid, when loops are open (20; 0 = off)",
    ),
    ParamDoc::new(
        "regrow_loops_depth",
        Unit::Count,
        "I20: regrow each loop left open by the fills without the faces within 1 to this many vertex steps of it (3; 0 = off)",
    ),
    ParamDoc::new(
        "regrow_handles_depth",
        Unit::Count,
        "I22: with handles in the mesh, regrow the faces within 0 to this many minus one vertex steps of its sheet-crossing edges (4; 0 = off)",
    ),
    ParamDoc::new(
        "regrow_points_depth",
        Unit::Count,
        "I21: offer each unmeshed point within R of the mesh to a regrowth of the faces within 0 to this many minus one vertex steps of its meshed neighbours (5; 0 = off)",
    ),
    ParamDoc::new(
        "insert_quadric",
        Unit::Flag,
        "I15: a point off that plane may lie on the neighbours' quadric instead (true)",
    ),
    ParamDoc::new(
        "restart",
        Unit::Flag,
        "re-seed while Free point patches remain (M8)",
    ),
    ParamDoc::new(
        "restart_min_points",
        Unit::Count,
        "minimum Free patch size that triggers a restart (A10: 10)",
    ),
    ParamDoc::new(
        "restart_radius_cap",
        Unit::None,
        "restart radius cap in units of R0 (A10: 2)",
    ),
    ParamDoc::new(
        "restart_max_flatness",
        Unit::None,
        "max patch flatness score of restart seeds (I1: 0.2)",
    ),
    ParamDoc::new(
        "max_seeds",
        Unit::Count,
        "bound on the number of seeds, 0 = none",
    ),
    ParamDoc::new(
        "seed_point",
        Unit::Count,
        "force the first seed patch centre (point index)",
    ),
    ParamDoc::new(
        "threads",
        Unit::Count,
        "slab-parallel growth threads (1 = sequential)",
    ),
];

impl Describe for super::PriorityFront {
    const NAME: &'static str = super::NAME;
    const SOURCE: &'static str = "seed 001 §4";
    const SUMMARY: &'static str = "priority-driven advancing front (Li, Han & Wee); deviations in docs/methods/priority_front.md";
    type Params = PriorityFrontParams;
    const PARAMS: &'static [ParamDoc] = PARAM_DOCS;

    fn from_params(params: PriorityFrontParams) -> Result<Self, MethodError> {
        Self::new(params)
    }
}
