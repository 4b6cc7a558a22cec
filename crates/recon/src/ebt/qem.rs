//! `qem-simplified`: seed 004's suggested comparison at an equal vertex budget (spec §5
//! and §6 item 5, not in the paper): mesh the *full* cloud with another seed's
//! reconstructor, then simplify the mesh by quadric-error edge collapses (Garland &
//! Heckbert 1997, through meshoptimizer's simplifier, crate `meshopt`) to `target`
//! vertices, e.g. EBT's |Q|. Collapses keep a subset of the original vertices, so the
//! result interpolates input points like EBT's mesh does.
//!
//! The simplifier takes a triangle budget; the vertex budget is met by bisection on it
//! (the number of referenced vertices grows with the triangle budget). Positions are
//! handed over in `f32`, centred and divided by the bounding-box diagonal (so no scale
//! overflows); the output mesh uses the original `f64` points, compacted to the
//! referenced ones.

use glam::DVec3;
use meshopt::SimplifyOptions;
use reconbench_geom::method::{
    Describe, Diagnostic, MethodError, ParamDoc, Reconstruction, Reconstructor, RunCtx, Unit,
};
use reconbench_geom::{Aabb, PointCloud, TriMesh};
use serde::{Deserialize, Serialize};

use crate::priority_front::{PriorityFront, PriorityFrontParams};
use crate::ufm::{Ufm, UfmParams};

/// Bisection steps on the triangle budget (2^24 triangles covered).
const BISECT_STEPS: usize = 24;

/// The reconstructor that meshes the full cloud.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FullMesher {
    /// `priority-front` (seed 001) with its defaults.
    PriorityFront,
    /// `ufm` (seed 000) with its defaults (closed mode: a sheet gets closed).
    Ufm,
}

/// Parameters of `qem-simplified`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QemParams {
    /// Reconstructor of the full cloud.
    pub mesher: FullMesher,
    /// Vertex budget of the simplified mesh.
    pub target: usize,
}

impl Default for QemParams {
    fn default() -> Self {
        Self {
            mesher: FullMesher::PriorityFront,
            target: 5000,
        }
    }
}

const QEM_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "mesher",
        Unit::Choice,
        "reconstructor of the full cloud: priority-front | ufm",
    ),
    ParamDoc::new(
        "target",
        Unit::Count,
        "vertex budget of the simplified mesh (e.g. EBT's |Q|)",
    ),
];

/// The `qem-simplified` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct QemSimplified {
    /// Parameters.
    pub params: QemParams,
}

impl Describe for QemSimplified {
    const NAME: &'static str = "qem-simplified";
    const SOURCE: &'static str = "baseline (seed 004 §5: full-resolution mesh + QEM)";
    const SUMMARY: &'static str =
        "full cloud meshed (priority-front or ufm), then QEM edge collapses to `target` vertices";
    type Params = QemParams;
    const PARAMS: &'static [ParamDoc] = QEM_DOCS;

    fn from_params(params: QemParams) -> Result<Self, MethodError> {
        if params.target < 3 {
            return Err(MethodError::InvalidParameter {
                name: "target".into(),
                message: format!("must be at least 3, got {}", params.target),
            });
        }
        Ok(Self { params })
    }
}

/// Faces of `mesh` simplified by QEM to a triangle budget; also the referenced vertex
/// count.
fn simplify(pos: &[[f32; 3]], indices: &[u32], tris: usize) -> (Vec<u32>, usize, Vec<bool>) {
    let out = meshopt::simplify_decoder(
        indices,
        pos,
        3 * tris,
        f32::MAX,
        SimplifyOptions::None,
        None,
    );
    let mut used = vec![false; pos.len()];
    for &i in &out {
        used[i as usize] = true;
    }
    let n = used.iter().filter(|&&u| u).count();
    (out, n, used)
}

/// `mesh` simplified to the vertex count nearest `target` (ties to the smaller count);
/// the mesh itself when it has no more referenced vertices than that.
pub fn simplify_to(mesh: &TriMesh, target: usize) -> Result<TriMesh, MethodError> {
    let v = mesh.vertices();
    let bb = Aabb::from_points(v);
    let (c, d) = (bb.center(), bb.diagonal().max(f64::MIN_POSITIVE));
    let pos: Vec<[f32; 3]> = v
        .iter()
        .map(|p| ((*p - c) / d).as_vec3().to_array())
        .collect();
    let indices: Vec<u32> = mesh.faces().iter().flatten().copied().collect();
    let nf = mesh.n_faces();
    let (mut lo, mut hi) = (1usize, nf);
    let mut best: Option<(usize, Vec<u32>, Vec<bool>)> = None;
    for _ in 0..BISECT_STEPS {
        if lo > hi {
            break;
        }
        let mid = lo + (hi - lo) / 2;
        let (out, n, used) = simplify(&pos, &indices, mid);
        let gap = n.abs_diff(target);
        if best.as_ref().is_none_or(|b| gap < b.0) {
            best = Some((gap, out, used));
        }
        if n == target {
            break;
        }
        if n < target {
            lo = mid + 1;
        } else {
            hi = mid.saturating_sub(1);
        }
    }
    let Some((_, out, used)) = best else {
        return Ok(mesh.clone());
    };
    let mut map = vec![u32::MAX; v.len()];
    let mut verts: Vec<DVec3> = Vec::new();
    for (i, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        map[i] = verts.len() as u32;
        verts.push(v[i]);
    }
    let faces: Vec<[u32; 3]> = out
        .chunks_exact(3)
        .map(|t| [map[t[0] as usize], map[t[1] as usize], map[t[2] as usize]])
        .collect();
    Ok(TriMesh::new(verts, faces)?)
}

impl Reconstructor for QemSimplified {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        let full = match self.params.mesher {
            FullMesher::PriorityFront => {
                PriorityFront::new(PriorityFrontParams::default())?.reconstruct(cloud, ctx)?
            }
            FullMesher::Ufm => Ufm::new(UfmParams::default())?.reconstruct(cloud, ctx)?,
        };
        let (fv, ff) = (full.mesh.n_vertices(), full.mesh.n_faces());
        let mesh = ctx.phase("simplify", || simplify_to(&full.mesh, self.params.target))?;
        let mut diagnostics = full.diagnostics;
        let mut num = |k: &str, x: f64| {
            diagnostics.insert(k.to_string(), Diagnostic::Number(x));
        };
        num("full_vertices", fv as f64);
        num("full_faces", ff as f64);
        num("q_points", mesh.n_vertices() as f64);
        Ok(Reconstruction {
            mesh,
            refused: Vec::new(),
            diagnostics,
        })
    }
}
