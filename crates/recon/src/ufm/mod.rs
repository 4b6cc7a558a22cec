//! `ufm`: Umbrella Facet Matching, the watertight Delaunay reconstruction of Ji Ma's
//! thesis (2011), chapter 3 (spec `shared/spec/000_ma_thesis.md` §1.1).
//!
//! Every input point keeps a candidate umbrella (a closed fan of Delaunay triangles
//! around it). A triangle is *matched* when the umbrellas of its three corners all
//! contain it. Umbrellas start from the Gabriel triangles (size priority, large removed
//! first) and are rebuilt synchronously from all Delaunay triangles at the point with a
//! three-level priority (absolute matching index, relative matching index, size) until
//! every umbrella is fully matched or a stop rule fires. The output — all matched
//! facets — is always edge-manifold; at 100 % matching it is a closed 2-manifold whose
//! vertices are exactly the input points.
//!
//! Files: [`params`], [`umbrella`] (BuildUmbrella on the link graph), [`matching`]
//! (Table 3.1 classes, umbrella states, A-07 stop rules), [`complex`] (the CSR complex
//! and its per-triangle attributes), [`engine`] (iterations), [`facet_fit`] (the normal
//! fits shared by Algorithms B and C), [`normals`] (`ufm-mesh`, Algorithm B of chapter
//! 4), [`nvc`] (Algorithm C of chapter 5: Normal Vector Cone filtering, the `nvc`
//! option, off by default). Dependencies run one way: `complex` <- `facet_fit` <- `nvc`
//! <- `engine` <- `normals`.
//! See `docs/methods/ufm.md`.

pub mod closure;
pub mod complex;
pub mod engine;
pub mod facet_fit;
pub mod geometry;
pub mod matching;
pub mod normals;
pub mod nvc;
pub mod params;
pub mod umbrella;

use std::time::Instant;

use crate::diag::num;
use glam::DVec3;
use reconbench_delaunay::{Delaunay, DelaunayError};
use reconbench_geom::method::{
    Diagnostic, Diagnostics, MethodError, Reconstruction, Reconstructor, RunCtx,
};
use reconbench_geom::topology::{MeshTopology, analyze_with, orient_consistently};
use reconbench_geom::{PointCloud, TriMesh};

pub use engine::{Complex, Counters, UfmState};
pub use matching::StopRule;
pub use normals::{UfmMesh, UfmMeshParams};
pub use params::{
    Init, Mode, Nvc, NvcLevel, NvcStart, OutputSet, PARAM_DOCS, SizeOrder, UfmParams, Update,
};

/// Registry name.
pub const NAME: &str = "ufm";

/// The `ufm` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct Ufm {
    /// Parameters.
    pub params: UfmParams,
}

impl Ufm {
    /// A reconstructor with validated parameters.
    pub fn new(params: UfmParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

/// Step 1: the Delaunay triangulation (ASSUMPTION A-01: exact duplicates merged by the
/// triangulation) and the triangle attributes. Phases `delaunay` and `attributes`.
pub fn build_complex(
    points: &[DVec3],
    params: &UfmParams,
    ctx: &mut RunCtx,
) -> Result<Complex, MethodError> {
    let dt = ctx.phase("delaunay", || {
        let dt = Delaunay::new(points).map_err(|e| match e {
            DelaunayError::NonFinite { index } => {
                MethodError::InvalidInput(format!("ufm: point {index} has a non-finite coordinate"))
            }
            e => MethodError::InvalidInput(format!("ufm: {e}")),
        })?;
        // Triangle extraction and DT_v belong to the thesis's "DT" time.
        dt.facets();
        dt.facets_of_vertex(0);
        Ok::<_, MethodError>(dt)
    })?;
    ctx.checkpoint()?;
    ctx.phase("attributes", || Complex::new(dt, params.size_order))
}

/// Steps 1–3 on raw points: the final UFM state (phases `delaunay`, `attributes`,
/// `init`, `iterate`).
pub fn run_ufm(
    points: &[DVec3],
    params: &UfmParams,
    ctx: &mut RunCtx,
) -> Result<UfmState, MethodError> {
    params.validate()?;
    let cx = build_complex(points, params, ctx)?;
    ctx.checkpoint()?;
    let st = engine::run(cx, params, ctx)?;
    ctx.record_phase("init", st.init_s);
    ctx.record_phase("iterate", st.iterate_s);
    Ok(st)
}

/// The output facets (ASSUMPTION A-11), as Delaunay vertex triples.
pub fn output_facets(st: &UfmState, output: OutputSet) -> Vec<u32> {
    let facets = st.cx.facets();
    match output {
        // ASSUMPTION A-11 (default): F_out = {t : M_t = 3}.
        OutputSet::MatchedFacets => (0..facets.len() as u32)
            .filter(|&f| st.m[f as usize] == 3)
            .collect(),
        // Literal alternative: the facets of the fully matched umbrellas.
        OutputSet::FullUmbrellas => {
            let g = engine::grades(&st.cx, &st.inu, &st.m);
            (0..facets.len() as u32)
                .filter(|&f| {
                    st.m[f as usize] == 3 && facets[f as usize].v.iter().any(|&v| g[v as usize])
                })
                .collect()
        }
    }
}

/// Orients every component consistently (BFS over manifold edges) and outward (positive
/// signed volume about the component's first vertex; meaningful for closed components).
fn orient_outward(mesh: &mut TriMesh) -> Result<(), MethodError> {
    orient_consistently(mesh)?;
    let topo = MeshTopology::new(mesh);
    let (nc, comp) = topo.face_components();
    let mut origin = vec![None::<DVec3>; nc];
    let mut vol = vec![0.0f64; nc];
    for (f, face) in mesh.faces().iter().enumerate() {
        let c = comp[f];
        if c as usize >= nc {
            continue;
        }
        let [a, b, d] = face.map(|x| mesh.vertices()[x as usize]);
        let o = *origin[c as usize].get_or_insert(a);
        vol[c as usize] += (a - o).dot((b - o).cross(d - o));
    }
    let flip: Vec<bool> = (0..mesh.n_faces())
        .map(|f| (comp[f] as usize) < nc && vol[comp[f] as usize] < 0.0)
        .collect();
    mesh.flip_faces(&flip);
    Ok(())
}

/// One-line record of the ASSUMPTION switches in force.
fn assumption_flags(p: &UfmParams) -> String {
    format!(
        "A-01=exact-dedup A-02=facet-id A-03=open-ball A-04=skip+rebuild A-05=max-min-key \
         A-06={:?} A-07=converged/fixed/cycle{}/patience:{}/max:{} A-08=freeze:{} \
         A-09=lock:{} A-11={:?} mode={:?} init={:?} update={:?} escapes={} max_fold={} close={} reorder={} \
         nvc={:?} C-01=consistent-dihedral C-02=min(factor:{}*mean,alpha_gen:{}) \
         C-03=adjacent-shadow-pair C-04=flat:facet-average C-05={:?} \
         C-06={:?} C-07=full-unfiltered R={}",
        p.size_order,
        matching::CYCLE_MEMORY,
        p.patience,
        p.max_iter,
        p.freeze_full,
        p.lock_matched,
        p.output,
        p.mode,
        p.init,
        p.update,
        p.escapes,
        p.max_fold,
        p.close_max_turn,
        p.reorder,
        p.nvc,
        p.nvc_flat_factor,
        p.nvc_angle,
        p.nvc_level,
        p.nvc_start,
        p.nvc_range
    )
}

impl Reconstructor for Ufm {
    fn name(&self) -> &str {
        NAME
    }

    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        let p = &self.params;
        p.validate()?;
        let original = cloud.positions();
        let scaled = cloud.at_working_scale();
        let input = crate::scale::working(cloud, &scaled).positions();
        let n = input.len();
        if n >= u32::MAX as usize {
            return Err(MethodError::InvalidInput(format!(
                "{n} points exceed u32 range"
            )));
        }
        let t_start = Instant::now();
        // Memory locality (`reorder`): run on the points in Morton order, so that
        // vertex ids, facet ids and every per-vertex array follow space; `perm[k]` is
        // the input index of the k-th point. Ties of the Morton code keep input order,
        // so the first of exact duplicates stays the representative.
        let perm: Option<Vec<u32>> = p
            .reorder
            .then(|| reconbench_geom::spatial::morton_order(input));
        let permuted: Vec<DVec3>;
        let run_pts = match &perm {
            Some(perm) => {
                permuted = perm.iter().map(|&i| input[i as usize]).collect();
                &permuted[..]
            }
            None => input,
        };
        let to_input = |k: u32| perm.as_ref().map_or(k, |p| p[k as usize]);
        let st = run_ufm(run_pts, p, ctx)?;
        let dt_s = ctx.phase_seconds("delaunay");
        let t_out = Instant::now();
        let dt = &st.cx.dt;
        let nv = dt.n_vertices();
        let facets = st.cx.facets();
        let mut out = output_facets(&st, p.output);
        let mut closure = closure::ClosureStats::default();
        let mut filled: Vec<[u32; 3]> = Vec::new();
        let mut closure_s = 0.0;
        let closing = p.mode == Mode::Closed && p.close_max_turn > 0.0;
        if closing {
            let t = Instant::now();
            (out, filled, closure) =
                closure::close(&st.cx, dt.vertices(), &out, p.close_max_turn.to_radians());
            closure_s = t.elapsed().as_secs_f64();
            ctx.record_phase("closure", closure_s);
        }
        let faces: Vec<[u32; 3]> = out
            .iter()
            .map(|&f| {
                facets[f as usize]
                    .v
                    .map(|v| to_input(dt.input_of_vertex(v)))
            })
            .chain(
                filled
                    .iter()
                    .map(|t| t.map(|v| to_input(dt.input_of_vertex(v)))),
            )
            .collect();
        // Every input point is a vertex (interpolation); exact duplicates are
        // unreferenced and listed as refused.
        let mut refused: Vec<u32> = (0..n as u32)
            .filter(|&k| dt.input_of_vertex(dt.vertex_of_input(k as usize)) != k)
            .map(to_input)
            .collect();
        refused.sort_unstable();
        let mut mesh = TriMesh::new(input.to_vec(), faces)?;
        orient_outward(&mut mesh)?;
        let topo = MeshTopology::new(&mesh);
        let rep = analyze_with(&mesh, &topo);
        let output_s = t_out.elapsed().as_secs_f64() - closure_s;
        ctx.record_phase("output", output_s);

        let mut d = Diagnostics::new();
        let matched = st.trace.last().copied().unwrap_or(0.0);
        num(&mut d, "matching", 100.0 * matched);
        d.insert(
            "matching_trace".into(),
            Diagnostic::Series(st.trace.iter().map(|x| 100.0 * x).collect()),
        );
        num(&mut d, "iterations", st.iterations as f64);
        d.insert("stop_rule".into(), Diagnostic::Text(st.stop.name().into()));
        let g = engine::grades(&st.cx, &st.inu, &st.m);
        num(
            &mut d,
            "unmatched_points",
            g.iter().filter(|&&x| !x).count() as f64,
        );
        num(&mut d, "vertices", nv as f64);
        num(&mut d, "triangles", out.len() as f64);
        if let Some(genus) = p.genus {
            let df = (2 * nv as i64 + 4 * (genus as i64 - 1) - out.len() as i64).unsigned_abs();
            num(&mut d, "delta_f", df as f64);
        }
        num(&mut d, "duplicates", refused.len() as f64);
        num(&mut d, "delaunay_triangles", facets.len() as f64);
        num(
            &mut d,
            "gabriel_triangles",
            st.cx.gabriel.iter().filter(|&&x| x).count() as f64,
        );
        let c = st.counters;
        num(&mut d, "init_fallbacks", c.init_fallbacks as f64);
        num(&mut d, "lock_fallbacks", c.lock_fallbacks as f64);
        num(&mut d, "skipped_cascades", c.skipped_cascades as f64);
        num(&mut d, "dropped_cycles", c.dropped_cycles as f64);
        num(&mut d, "build_failures", c.build_failures as f64);
        num(&mut d, "fold_repairs", c.fold_repairs as f64);
        num(&mut d, "escapes_used", st.escapes as f64);
        if closing {
            num(&mut d, "closure_added", closure.added as f64);
            num(&mut d, "closure_unpinched", closure.unpinched_faces as f64);
            num(&mut d, "closure_untwisted", closure.untwisted_faces as f64);
            num(&mut d, "closure_bubbles", closure.bubble_faces as f64);
            num(
                &mut d,
                "closure_inserted_points",
                closure.inserted_points as f64,
            );
            num(&mut d, "closure_filled_holes", closure.filled_holes as f64);
            num(
                &mut d,
                "closure_fill_triangles",
                closure.fill_triangles as f64,
            );
        }
        if p.nvc != Nvc::Off {
            // Algorithm C (summed over the iterations with filtering).
            num(&mut d, "nvc_points", st.nvc.filtered as f64);
            num(&mut d, "nvc_flat_points", st.nvc.flat as f64);
            num(&mut d, "nvc_triangles", st.nvc.members as f64);
            if let Some(it) = st.nvc_from {
                num(&mut d, "nvc_from_iteration", it as f64);
            }
            if st.nvc.last_alpha_flat.is_finite() {
                num(
                    &mut d,
                    "nvc_alpha_flat_deg",
                    st.nvc.last_alpha_flat.to_degrees(),
                );
            }
        }
        crate::diag::topology(&mut d, &rep);
        num(&mut d, "dt_s", dt_s);
        num(&mut d, "ufm_s", t_start.elapsed().as_secs_f64() - dt_s);
        d.insert("assumptions".into(), Diagnostic::Text(assumption_flags(p)));
        crate::scale::check_not_collapsed(NAME, &mesh, input)?;
        if scaled.is_some() {
            mesh = crate::scale::on_input_points(mesh, original)?;
        }
        Ok(Reconstruction {
            mesh,
            refused,
            diagnostics: d,
        })
    }
}
