//! `cocone` (Amenta, Choi, Dey & Leekha 2002) and `tight-cocone` (Dey & Goswami 2003):
//! the Delaunay baselines of seed 000 (Table 3.4, chapter 5) and seed 001 (Table 2).
//!
//! Both interpolate: every output vertex is an input point. `cocone` keeps the Delaunay
//! triangles whose dual Voronoi edges cross the cocones (thickened tangent planes, from
//! the poles) of their three vertices, prunes triangles at sharp edges and walks the
//! outer side of the rest; it leaves holes where the sampling is too thin for the
//! cocone test. `tight-cocone` takes that surface, marks the samples whose umbrella is a
//! closed disc as good, labels every tetrahedron inside or outside from the infinite
//! ones and outputs the triangles between the two labels: watertight by construction,
//! possibly with non-manifold edges where the labels pinch (the thesis's Casting Die).
//!
//! Files: [`poles`] (poles, the cocone test), [`extract`] (pruning and the walk),
//! [`tight`] (marking and peeling). See `docs/methods/cocone.md`.

pub mod extract;
pub mod poles;
pub mod repair;
pub mod tight;

use crate::diag::num;
use reconbench_delaunay::{Delaunay, DelaunayError};
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, MethodError, ParamDoc, Reconstruction, Reconstructor,
    RunCtx, Unit,
};
use reconbench_geom::topology::{MeshTopology, analyze_with};
use reconbench_geom::{PointCloud, TriMesh};
use serde::{Deserialize, Serialize};

pub use tight::SurfaceRule;

/// Parameters of `cocone`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CoconeParams {
    /// Half-angle of the cocone about the tangent plane (ACDL: π/8 = 22.5°).
    pub theta_deg: f64,
    /// An edge is sharp when two consecutive triangles around it leave a larger gap
    /// (ACDL: 3π/2 = 270°).
    pub sharp_deg: f64,
    /// Treat an edge with a single triangle as sharp (the paper's rule, for closed
    /// well-sampled surfaces); off by default so that holes stay local.
    pub prune_dangling: bool,
}

impl Default for CoconeParams {
    fn default() -> Self {
        Self {
            theta_deg: 22.5,
            sharp_deg: 270.0,
            prune_dangling: false,
        }
    }
}

/// Parameters of `tight-cocone`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TightCoconeParams {
    /// Half-angle of the cocone about the tangent plane (π/8 = 22.5°).
    pub theta_deg: f64,
    /// Sharp-edge gap of the initial surface's pruning (270°).
    pub sharp_deg: f64,
    /// Prune dangling edges in the initial surface (see `cocone`).
    pub prune_dangling: bool,
    /// Initial-surface triangles the marking trusts: `one-good` (of the umbrella of a
    /// good sample) or `all-good` (all three vertices good).
    pub surface: SurfaceRule,
    /// Relabel the smallest groups of tetrahedra at non-manifold edges and pinched
    /// vertices of the interface (rounds; 0 = the paper's output as it is).
    pub repair_rounds: usize,
    /// Relabel inside blobs and enclosed outside cavities with fewer tetrahedra than this
    /// share of the inside ones (0 = keep every pocket, the paper's output).
    pub pocket_share: f64,
}

impl Default for TightCoconeParams {
    fn default() -> Self {
        Self {
            theta_deg: 22.5,
            sharp_deg: 270.0,
            prune_dangling: false,
            surface: SurfaceRule::OneGood,
            repair_rounds: 8,
            pocket_share: 0.01,
        }
    }
}

fn check_angles(theta_deg: f64, sharp_deg: f64) -> Result<(), MethodError> {
    if !(theta_deg.is_finite() && theta_deg > 0.0 && theta_deg < 90.0) {
        return Err(MethodError::InvalidParameter {
            name: "theta_deg".into(),
            message: format!("must be in (0, 90) degrees, got {theta_deg}"),
        });
    }
    if !(sharp_deg.is_finite() && sharp_deg > 180.0 && sharp_deg <= 360.0) {
        return Err(MethodError::InvalidParameter {
            name: "sharp_deg".into(),
            message: format!("must be in (180, 360] degrees, got {sharp_deg}"),
        });
    }
    Ok(())
}

/// The `cocone` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct Cocone {
    /// Parameters.
    pub params: CoconeParams,
}

/// The `tight-cocone` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct TightCocone {
    /// Parameters.
    pub params: TightCoconeParams,
}

const COMMON_DOCS: [ParamDoc; 3] = [
    ParamDoc::new(
        "theta_deg",
        Unit::Deg,
        "cocone half-angle about the tangent plane (pi/8)",
    ),
    ParamDoc::new(
        "sharp_deg",
        Unit::Deg,
        "prune triangles at edges whose largest gap between consecutive triangles exceeds this (3pi/2)",
    ),
    ParamDoc::new(
        "prune_dangling",
        Unit::Flag,
        "an edge with one triangle is sharp too (the paper's rule for closed surfaces)",
    ),
];

impl Describe for Cocone {
    const NAME: &'static str = "cocone";
    const SOURCE: &'static str = "baseline (Amenta, Choi, Dey & Leekha 2002)";
    const SUMMARY: &'static str = "Delaunay triangles dual to Voronoi edges in the cocones of their vertices, pruned and walked";
    type Params = CoconeParams;
    const PARAMS: &'static [ParamDoc] = &COMMON_DOCS;

    fn from_params(params: CoconeParams) -> Result<Self, MethodError> {
        check_angles(params.theta_deg, params.sharp_deg)?;
        Ok(Self { params })
    }
}

impl Describe for TightCocone {
    const NAME: &'static str = "tight-cocone";
    const SOURCE: &'static str = "baseline (Dey & Goswami 2003)";
    const SUMMARY: &'static str =
        "watertight Cocone: tetrahedra labelled inside/outside by peeling, their interface";
    type Params = TightCoconeParams;
    const PARAMS: &'static [ParamDoc] = &[
        COMMON_DOCS[0],
        COMMON_DOCS[1],
        COMMON_DOCS[2],
        ParamDoc::new(
            "surface",
            Unit::Choice,
            "trusted initial triangles: one-good (umbrella of a good sample) or all-good",
        ),
        ParamDoc::new(
            "repair_rounds",
            Unit::Count,
            "rounds relabelling the smallest tetrahedron group at non-manifold spots (0 = literal)",
        ),
        ParamDoc::new(
            "pocket_share",
            Unit::Fraction,
            "relabel inside blobs / enclosed cavities below this share of the inside tetrahedra (0 = literal)",
        ),
    ];

    fn from_params(params: TightCoconeParams) -> Result<Self, MethodError> {
        check_angles(params.theta_deg, params.sharp_deg)?;
        if !(params.pocket_share.is_finite() && (0.0..1.0).contains(&params.pocket_share)) {
            return Err(MethodError::InvalidParameter {
                name: "pocket_share".into(),
                message: format!("must be in [0, 1), got {}", params.pocket_share),
            });
        }
        Ok(Self { params })
    }
}

/// The Delaunay tetrahedralization of the cloud, with input errors named.
fn triangulate(name: &str, cloud: &PointCloud, ctx: &RunCtx) -> Result<Delaunay, MethodError> {
    let input = cloud.positions();
    if input.len() >= u32::MAX as usize {
        return Err(MethodError::InvalidInput(format!(
            "{name}: {} points exceed the u32 range",
            input.len()
        )));
    }
    ctx.phase("delaunay", || {
        let dt = Delaunay::new(input).map_err(|e| match e {
            DelaunayError::NonFinite { index } => MethodError::InvalidInput(format!(
                "{name}: point {index} has a non-finite coordinate"
            )),
            e => MethodError::InvalidInput(format!("{name}: {e}")),
        })?;
        dt.facets();
        Ok(dt)
    })
}

/// The initial Cocone surface: oriented Delaunay triples with their facet ids.
fn cocone_surface(
    dt: &Delaunay,
    poles: &poles::Poles,
    theta_deg: f64,
    sharp_deg: f64,
    dangling: bool,
    ctx: &RunCtx,
    d: &mut Diagnostics,
) -> Result<Vec<(u32, [u32; 3])>, MethodError> {
    let flags = ctx.phase("cocone_test", || {
        poles::cocone_flags(dt, poles, theta_deg.to_radians())
    });
    ctx.checkpoint()?;
    let mut stats = extract::ExtractStats::default();
    let mut cx = ctx.phase("complex", || extract::Complex::new(dt, &flags));
    stats.candidates = cx.facet.len();
    // ASSUMPTION K-02: dangling edges are sharp only with `prune_dangling` (the paper's
    // closed-surface rule erodes a surface from any hole).
    stats.pruned = ctx.phase("prune", || cx.prune(sharp_deg.to_radians(), dangling));
    ctx.checkpoint()?;
    let tris = ctx.phase("walk", || cx.walk(&mut stats));
    num(d, "cocone_triangles", stats.candidates as f64);
    num(d, "pruned_triangles", stats.pruned as f64);
    num(d, "walk_components", stats.components as f64);
    num(d, "walk_conflicts", stats.walk_conflicts as f64);
    Ok(tris
        .into_iter()
        .map(|(j, t)| (cx.facet[j as usize], t))
        .collect())
}

/// Oriented Cocone triangles (Delaunay vertex ids) with their Delaunay facet ids.
type Surface = Vec<(u32, [u32; 3])>;

/// The steps both methods share: the Delaunay, the poles and the Cocone surface, with
/// the record of the shared ASSUMPTIONs in `d`.
fn delaunay_and_surface(
    name: &str,
    cloud: &PointCloud,
    (theta_deg, sharp_deg, dangling): (f64, f64, bool),
    ctx: &RunCtx,
    d: &mut Diagnostics,
) -> Result<(Delaunay, poles::Poles, Surface), MethodError> {
    check_angles(theta_deg, sharp_deg)?;
    let dt = triangulate(name, cloud, ctx)?;
    ctx.checkpoint()?;
    let poles = ctx.phase("poles", || poles::Poles::new(&dt));
    let tris = cocone_surface(&dt, &poles, theta_deg, sharp_deg, dangling, ctx, d)?;
    d.insert(
        "assumptions".into(),
        Diagnostic::Text(format!(
            "K-01=farthest-voronoi-vertex,hull:mean-normal K-02=dangling-sharp:{dangling} K-03=hull-seed K-04=exact-segment-cone"
        )),
    );
    Ok((dt, poles, tris))
}

/// The output mesh on the input points, with the topology diagnostics.
fn finish(
    cloud: &PointCloud,
    dt: &Delaunay,
    tris: &[[u32; 3]],
    mut d: Diagnostics,
    ctx: &RunCtx,
) -> Result<Reconstruction, MethodError> {
    let _g = ctx.phase_guard("output");
    let input = cloud.positions();
    let n = input.len();
    let faces: Vec<[u32; 3]> = tris
        .iter()
        .map(|t| t.map(|v| dt.input_of_vertex(v)))
        .collect();
    let mut used = vec![false; n];
    for f in &faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    // Exact duplicates are merged by the triangulation: refused, like `ufm`'s.
    let refused: Vec<u32> = (0..n as u32)
        .filter(|&k| dt.input_of_vertex(dt.vertex_of_input(k as usize)) != k)
        .collect();
    let mesh = TriMesh::new(input.to_vec(), faces)?;
    let topo = MeshTopology::new(&mesh);
    let rep = analyze_with(&mesh, &topo);
    num(&mut d, "vertices", dt.n_vertices() as f64);
    num(&mut d, "triangles", mesh.n_faces() as f64);
    num(
        &mut d,
        "unused_points",
        (used.iter().filter(|&&u| !u).count() - refused.len()) as f64,
    );
    num(&mut d, "duplicates", refused.len() as f64);
    num(&mut d, "delaunay_triangles", dt.facets().len() as f64);
    crate::diag::topology(&mut d, &rep);
    Ok(Reconstruction {
        mesh,
        refused,
        diagnostics: d,
    })
}

impl Reconstructor for Cocone {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        crate::scale::reconstruct_at_working_scale(Self::NAME, cloud, |cloud| {
            let p = &self.params;
            let mut d = Diagnostics::new();
            let (dt, _, tris) = delaunay_and_surface(
                Self::NAME,
                cloud,
                (p.theta_deg, p.sharp_deg, p.prune_dangling),
                ctx,
                &mut d,
            )?;
            let tris: Vec<[u32; 3]> = tris.into_iter().map(|(_, t)| t).collect();
            finish(cloud, &dt, &tris, d, ctx)
        })
    }
}

impl Reconstructor for TightCocone {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        crate::scale::reconstruct_at_working_scale(Self::NAME, cloud, |cloud| {
            let p = &self.params;
            let mut d = Diagnostics::new();
            let (dt, poles, initial) = delaunay_and_surface(
                Self::NAME,
                cloud,
                (p.theta_deg, p.sharp_deg, p.prune_dangling),
                ctx,
                &mut d,
            )?;
            ctx.checkpoint()?;
            let g = ctx.phase_guard("good_samples");
            let triples: Vec<[u32; 3]> = initial.iter().map(|&(_, t)| t).collect();
            let good = tight::good_samples(dt.n_vertices(), &triples);
            drop(g);
            let g = ctx.phase_guard("mark");
            // ASSUMPTION K-05: the trusted surface triangles.
            let surface: Vec<u32> = initial
                .iter()
                .filter(|(_, t)| match p.surface {
                    SurfaceRule::OneGood => t.iter().any(|&v| good[v as usize]),
                    SurfaceRule::AllGood => t.iter().all(|&v| good[v as usize]),
                })
                .map(|&(f, _)| f)
                .collect();
            let mut stats = tight::MarkStats {
                good: good.iter().filter(|&&g| g).count(),
                ..Default::default()
            };
            let mut inside = tight::label(&dt, &poles, &surface, &good, &mut stats);
            drop(g);
            // ASSUMPTION K-08 (deviation): small pockets are relabelled first.
            let pockets = ctx.phase("pockets", || {
                repair::drop_pockets(&dt, &mut inside, p.pocket_share)
            });
            // ASSUMPTION K-07 (deviation): then non-manifold spots.
            let (rep, tris) = ctx.phase("repair", || {
                repair::repair(&dt, &mut inside, p.repair_rounds)
            });
            num(&mut d, "pocket_tets", pockets as f64);
            num(&mut d, "repair_rounds", rep.rounds as f64);
            num(&mut d, "repair_flipped_tets", rep.flipped as f64);
            num(&mut d, "initial_triangles", initial.len() as f64);
            num(&mut d, "good_samples", stats.good as f64);
            num(
                &mut d,
                "poor_samples",
                (dt.n_vertices() - stats.good) as f64,
            );
            num(&mut d, "inside_tets", stats.inside as f64);
            num(&mut d, "ball_tests", stats.ball_tests as f64);
            if let Some(Diagnostic::Text(a)) = d.get_mut("assumptions") {
                a.push_str(&format!(
                    " K-05=surface:{:?} K-06=certain-first,ball-angle K-07=repair:{} K-08=pockets:{}",
                    p.surface, p.repair_rounds, p.pocket_share
                ));
            }
            finish(cloud, &dt, &tris, d, ctx)
        })
    }
}
