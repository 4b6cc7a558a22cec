//! Robust 3D Delaunay tetrahedralization in pure Rust.
//!
//! * **Algorithm**: incremental Bowyer–Watson insertion. Points are inserted in a Biased
//!   Randomized Insertion Order whose rounds are sorted along a Hilbert curve; each point
//!   is located by a visibility walk from the last created tetrahedron, its conflict
//!   region (cavity) is found by a breadth-first search, and the cavity is replaced by
//!   the cone from the new point to its boundary. Tetrahedra are stored in flat `u32`
//!   arrays (4 vertices and 4 neighbours each, freed slots are reused); the convex hull
//!   is closed by "ghost" tetrahedra incident to an infinite vertex.
//! * **Robustness**: `orient3d` and `insphere` are evaluated with a semi-static floating
//!   point filter and fall back to exact arithmetic: fixed-size integers when the
//!   coordinates are small integers after a common power-of-two scaling (grids, integer
//!   spheres), Shewchuk's adaptive exact predicates (`robust`) otherwise.
//!   Exact ties (co-spherical, co-planar input) are broken by a symbolic perturbation of
//!   the lifting map ordered by insertion rank (as in Geogram), so grids, points exactly
//!   on a sphere or on the faces of a cube give the Delaunay triangulation of the
//!   perturbed set: a valid triangulation whose every tetrahedron has non-zero volume.
//!   Walks are bounded (with an exhaustive fallback that is never expected to run).
//! * **Duplicates** (bit-identical points) are merged; see [`Delaunay::vertex_of_input`]
//!   and [`Delaunay::duplicates`]. Vertices are numbered in the order of their first
//!   occurrence in the input, so without duplicates vertex `i` is input point `i`.
//!
//! ```
//! use glam::DVec3;
//! use reconbench_delaunay::Delaunay;
//!
//! let pts = [
//!     DVec3::new(0.0, 0.0, 0.0),
//!     DVec3::new(1.0, 0.0, 0.0),
//!     DVec3::new(0.0, 1.0, 0.0),
//!     DVec3::new(0.0, 0.0, 1.0),
//!     DVec3::new(1.2, 1.2, 1.2),
//! ];
//! let dt = Delaunay::new(&pts).unwrap();
//! dt.validate().unwrap();
//! assert_eq!(dt.n_tets(), 2);
//! assert_eq!(dt.facets().len(), 7);
//! ```

mod build;
mod exact;
mod exact_int;
mod point;
mod predicates;
mod queries;
mod scale;
mod sort;
mod validate;

use std::fmt;
use std::sync::OnceLock;
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use build::{Builder, FREE, INF, Tet};
use point::P3;
use predicates::orient3d;

pub use queries::Facet;

/// The infinite vertex, as it appears in [`Delaunay::tet_vertices`] of infinite tetrahedra.
pub const INFINITE: u32 = u32::MAX;

/// "No tetrahedron": the second incident tetrahedron of a convex-hull facet.
pub const NO_TET: u32 = u32::MAX;

/// Largest supported number of input points (about 7 tetrahedra per point must fit in
/// 30-bit tetrahedron ids).
pub const MAX_POINTS: usize = 120_000_000;

/// Why a triangulation could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DelaunayError {
    /// Fewer than 4 distinct points.
    #[error("too few points: {distinct} distinct, a tetrahedralization needs at least 4")]
    TooFewPoints {
        /// Number of distinct points (counted up to 4).
        distinct: usize,
    },
    /// All points lie on one line.
    #[error("all points are collinear")]
    AllCollinear,
    /// All points lie in one plane.
    #[error("all points are coplanar")]
    AllCoplanar,
    /// More than [`MAX_POINTS`] points, or a triangulation with more than 2^30
    /// tetrahedron slots (tetrahedron ids must fit in 30 bits).
    #[error("too many points: {count} (at most {MAX_POINTS})")]
    TooManyPoints {
        /// Number of input points.
        count: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("point {index} has a non-finite coordinate")]
    NonFinite {
        /// Input index of the first offending point.
        index: usize,
    },
    /// The coordinates' binary span (from the lowest set bit of the finest non-zero
    /// coordinate to the magnitude of the largest) is wider than [`MAX_SPAN_BITS`], so no
    /// exact power-of-two rescaling brings them into the range where the exact
    /// predicates cannot underflow or overflow.
    #[error(
        "coordinates span {bits} bits (from 2^{lowest} to 2^{highest}), more than the \
         {MAX_SPAN_BITS} the exact predicates can hold after rescaling"
    )]
    SpanTooWide {
        /// `highest - lowest`.
        bits: i32,
        /// Exponent of the lowest set bit over the non-zero coordinates.
        lowest: i32,
        /// Smallest `e` with every `|coordinate| < 2^e`.
        highest: i32,
    },
}

/// Widest binary span of the coordinates (lowest set bit of the finest non-zero
/// coordinate to the magnitude of the largest) that the construction accepts: any cloud
/// within it is rescaled exactly by a power of two into the predicates' safe window
/// (see `docs/methods/delaunay.md`, Scale). Clouds of ordinary doubles span 53 bits plus
/// the binary orders of magnitude between their largest and smallest non-zero coordinate.
pub const MAX_SPAN_BITS: i32 = scale::MAX_SPAN_BITS;

/// Construction options.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DelaunayOptions {
    /// Seed of the randomized insertion order (and of the walk's face order).
    pub seed: u64,
    /// Insert in BRIO/Hilbert order (`true`, the default) or in input order.
    pub spatial_sort: bool,
}

impl Default for DelaunayOptions {
    fn default() -> Self {
        DelaunayOptions {
            seed: 0x0DE1_A0A9,
            spatial_sort: true,
        }
    }
}

/// Counts and phase timings of one construction (serializable, printable).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DelaunayStats {
    /// Input points.
    pub input_points: usize,
    /// Distinct points (vertices).
    pub vertices: usize,
    /// Finite tetrahedra.
    pub tets: usize,
    /// Finite triangles (each once), hull facets included.
    pub facets: usize,
    /// Convex-hull facets.
    pub hull_facets: usize,
    /// Input points merged into an earlier identical point.
    pub duplicates_merged: usize,
    /// Walks that exceeded the step bound and fell back to a scan (expected 0).
    pub walk_fallbacks: usize,
    /// Tetrahedra crossed by the point-location walks, in total.
    pub walk_steps: u64,
    /// Conflict (in-sphere) tests made while growing cavities, in total.
    pub conflict_tests: u64,
    /// Seconds spent on spatial sorting (BRIO + Hilbert).
    pub sort_s: f64,
    /// Seconds spent inserting points.
    pub insert_s: f64,
    /// Seconds spent renumbering vertices and tetrahedra after the insertion.
    pub finalize_s: f64,
    /// Seconds for the whole construction (validation of input, sort, insertion,
    /// renumbering).
    pub total_s: f64,
}

impl fmt::Display for DelaunayStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "input points       {}", self.input_points)?;
        writeln!(f, "vertices           {}", self.vertices)?;
        writeln!(f, "tetrahedra         {}", self.tets)?;
        writeln!(f, "facets             {}", self.facets)?;
        writeln!(f, "hull facets        {}", self.hull_facets)?;
        writeln!(f, "duplicates merged  {}", self.duplicates_merged)?;
        if self.walk_fallbacks > 0 {
            writeln!(f, "walk fallbacks     {}", self.walk_fallbacks)?;
        }
        let per = |x: u64| x as f64 / self.input_points.max(1) as f64;
        writeln!(
            f,
            "per point          {:.1} walk steps, {:.1} conflict tests",
            per(self.walk_steps),
            per(self.conflict_tests)
        )?;
        writeln!(f, "sort               {:.3} s", self.sort_s)?;
        writeln!(f, "insert             {:.3} s", self.insert_s)?;
        writeln!(f, "finalize           {:.3} s", self.finalize_s)?;
        write!(f, "total              {:.3} s", self.total_s)
    }
}

/// Compressed sparse rows: the items of row `r` are `items[offsets[r]..offsets[r + 1]]`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Csr {
    pub(crate) offsets: Vec<u32>,
    pub(crate) items: Vec<u32>,
}

impl Csr {
    fn row(&self, r: usize) -> &[u32] {
        &self.items[self.offsets[r] as usize..self.offsets[r + 1] as usize]
    }
}

/// A 3D Delaunay tetrahedralization with adjacency.
///
/// Tetrahedra `0..n_tets()` are finite, `n_tets()..n_all_tets()` are infinite ("ghost")
/// tetrahedra that have [`INFINITE`] as one vertex and a convex-hull facet opposite it.
/// Finite tetrahedra are positively oriented: `(v1 − v0) · ((v2 − v0) × (v3 − v0)) > 0`
/// exactly. Neighbour `i` of a tetrahedron is across the face opposite vertex `i`.
#[derive(Clone)]
pub struct Delaunay {
    points: Vec<DVec3>,
    /// The vertices multiplied by the construction's power of two (see `scale.rs`), which
    /// every predicate reads; empty when the factor is 1 (then `points` serve).
    scaled: Vec<P3>,
    /// Symbolic perturbation rank of each vertex (its insertion index).
    rank: Vec<u32>,
    vertex_of_input: Vec<u32>,
    input_of_vertex: Vec<u32>,
    duplicates: Vec<(u32, u32)>,
    tets: Vec<Tet>,
    n_finite: usize,
    stats: DelaunayStats,
    facets: OnceLock<Vec<Facet>>,
    vertex_facets: OnceLock<Csr>,
    vertex_edges: OnceLock<Csr>,
}

impl fmt::Debug for Delaunay {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Delaunay")
            .field("vertices", &self.points.len())
            .field("tets", &self.n_finite)
            .field("all_tets", &self.n_all_tets())
            .field("duplicates", &self.duplicates.len())
            .finish()
    }
}

impl Delaunay {
    /// Delaunay tetrahedralization of `points` with default options.
    pub fn new(points: &[DVec3]) -> Result<Self, DelaunayError> {
        Self::with_options(points, &DelaunayOptions::default())
    }

    /// Delaunay tetrahedralization of `points`.
    pub fn with_options(points: &[DVec3], opts: &DelaunayOptions) -> Result<Self, DelaunayError> {
        let t0 = Instant::now();
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(DelaunayError::NonFinite { index });
        }
        if points.len() > MAX_POINTS {
            return Err(DelaunayError::TooManyPoints {
                count: points.len(),
            });
        }
        let n = points.len();
        let s = scale::scale_exponent(points)?;
        let input: Vec<P3> = scale::scaled(points, s);
        let order: Vec<u32> = if opts.spatial_sort {
            sort::brio_order(&input, opts.seed)
        } else {
            (0..n as u32).collect()
        };
        let sort_s = t0.elapsed().as_secs_f64();

        let init = initial_simplex(&input, &order)?;
        let t1 = Instant::now();
        // Insertion sequence: the initial simplex first, then the rest in sorted order.
        let mut ins: Vec<u32> = Vec::with_capacity(n);
        ins.extend(init.iter().map(|&k| order[k]));
        ins.extend(
            order
                .iter()
                .enumerate()
                .filter(|(k, _)| !init.contains(k))
                .map(|(_, &i)| i),
        );
        drop(order);
        let pts: Vec<P3> = ins.iter().map(|&i| input[i as usize]).collect();
        let mut b = Builder::new(pts, opts.seed);
        let mut dup_of = vec![u32::MAX; n];
        for k in 4..n as u32 {
            if let Some(x) = b.insert(k) {
                dup_of[k as usize] = x;
            }
            if b.overflow {
                return Err(DelaunayError::TooManyPoints { count: n });
            }
        }
        let insert_s = t1.elapsed().as_secs_f64();

        let t2 = Instant::now();
        let mut dt = Self::finalize(points, &ins, &dup_of, b);
        if s != 0 {
            dt.scaled = dt
                .input_of_vertex
                .iter()
                .map(|&i| input[i as usize])
                .collect();
        }
        dt.stats.sort_s = sort_s;
        dt.stats.insert_s = insert_s;
        dt.stats.finalize_s = t2.elapsed().as_secs_f64();
        dt.stats.total_s = t0.elapsed().as_secs_f64();
        Ok(dt)
    }

    /// Renumber vertices into input order and tetrahedra into finite-then-ghost order.
    fn finalize(points: &[DVec3], ins: &[u32], dup_of: &[u32], b: Builder) -> Self {
        let n = ins.len();
        // Representative input index of each internal vertex: smallest of its group.
        let mut rep: Vec<u32> = ins.to_vec();
        for k in 0..n {
            let d = dup_of[k];
            if d != u32::MAX {
                rep[d as usize] = rep[d as usize].min(ins[k]);
            }
        }
        let mut internal_of_input = vec![0u32; n];
        for (k, &i) in ins.iter().enumerate() {
            internal_of_input[i as usize] = k as u32;
        }
        let mut pub_of_internal = vec![u32::MAX; n];
        let mut input_of_vertex = Vec::new();
        let mut rank = Vec::new();
        for i in 0..n as u32 {
            let k = internal_of_input[i as usize];
            let kk = if dup_of[k as usize] != u32::MAX {
                dup_of[k as usize]
            } else {
                k
            };
            if rep[kk as usize] == i {
                pub_of_internal[kk as usize] = input_of_vertex.len() as u32;
                input_of_vertex.push(i);
                rank.push(kk);
            }
        }
        let mut vertex_of_input = vec![0u32; n];
        let mut duplicates = Vec::new();
        for i in 0..n as u32 {
            let k = internal_of_input[i as usize] as usize;
            let kk = if dup_of[k] != u32::MAX {
                dup_of[k] as usize
            } else {
                k
            };
            let v = pub_of_internal[kk];
            vertex_of_input[i as usize] = v;
            if input_of_vertex[v as usize] != i {
                duplicates.push((i, v));
            }
        }
        let pts: Vec<DVec3> = input_of_vertex
            .iter()
            .map(|&i| points[i as usize])
            .collect();

        // Tetrahedra: finite first, then ghosts, free slots dropped. Tetrahedra already
        // in the right region keep their slot; the others fill the holes, and the
        // permutation is applied in place.
        let mut tets = b.tets;
        let slots = tets.len();
        let kind: Vec<u8> = tets
            .par_iter()
            .map(|t| {
                if t.v[0] == FREE {
                    2
                } else if t.v.contains(&INF) {
                    1
                } else {
                    0
                }
            })
            .collect();
        let mut count = [0usize; 3];
        for &k in &kind {
            count[k as usize] += 1;
        }
        let start = [0, count[0], count[0] + count[1]];
        let mut new_id = vec![u32::MAX; slots];
        let mut holes: [Vec<u32>; 3] = Default::default();
        for (s, &k) in kind.iter().enumerate() {
            let region = if s < start[1] {
                0
            } else if s < start[2] {
                1
            } else {
                2
            };
            if region == k as usize {
                new_id[s] = s as u32;
            } else {
                holes[region].push(s as u32);
            }
        }
        let mut next = [0usize; 3];
        for (s, &k) in kind.iter().enumerate() {
            if new_id[s] == u32::MAX {
                let k = k as usize;
                new_id[s] = holes[k][next[k]];
                next[k] += 1;
            }
        }
        drop(holes);
        let mut dest = new_id.clone();
        for s in 0..slots {
            while dest[s] as usize != s {
                let d = dest[s] as usize;
                tets.swap(s, d);
                dest.swap(s, d);
            }
        }
        drop(dest);
        let n_finite = count[0] as u32;
        let n_all = count[0] + count[1];
        tets.truncate(n_all);
        tets.par_iter_mut().for_each(|tet| {
            tet.v = tet.v.map(|x| {
                if x == INF {
                    INF
                } else {
                    pub_of_internal[x as usize]
                }
            });
            tet.n = tet.n.map(|c| 4 * new_id[(c >> 2) as usize] + (c & 3));
        });
        let n_ghost = n_all - n_finite as usize;
        let stats = DelaunayStats {
            input_points: n,
            vertices: pts.len(),
            tets: n_finite as usize,
            facets: (4 * n_finite as usize + n_ghost) / 2,
            hull_facets: n_ghost,
            duplicates_merged: duplicates.len(),
            walk_fallbacks: b.walk_fallbacks,
            walk_steps: b.walk_steps,
            conflict_tests: b.conflict_tests,
            sort_s: 0.0,
            insert_s: 0.0,
            finalize_s: 0.0,
            total_s: 0.0,
        };
        Delaunay {
            points: pts,
            scaled: Vec::new(),
            rank,
            vertex_of_input,
            input_of_vertex,
            duplicates,
            tets,
            n_finite: n_finite as usize,
            stats,
            facets: OnceLock::new(),
            vertex_facets: OnceLock::new(),
            vertex_edges: OnceLock::new(),
        }
    }

    /// Number of vertices (distinct input points).
    #[inline]
    pub fn n_vertices(&self) -> usize {
        self.points.len()
    }

    /// Position of vertex `v`.
    #[inline]
    pub fn vertex(&self, v: u32) -> DVec3 {
        self.points[v as usize]
    }

    /// Positions of all vertices, indexed by vertex id.
    #[inline]
    pub fn vertices(&self) -> &[DVec3] {
        &self.points
    }

    /// Vertex that input point `i` became (duplicates map to their first occurrence).
    pub fn vertex_of_input(&self, i: usize) -> u32 {
        self.vertex_of_input[i]
    }

    /// The whole input → vertex map.
    pub fn vertex_of_input_map(&self) -> &[u32] {
        &self.vertex_of_input
    }

    /// Input index of vertex `v` (the first occurrence of its position).
    #[inline]
    pub fn input_of_vertex(&self, v: u32) -> u32 {
        self.input_of_vertex[v as usize]
    }

    /// Merged duplicates as `(input index, vertex)`, by increasing input index. The first
    /// occurrence of each position is the vertex itself and is not listed.
    pub fn duplicates(&self) -> &[(u32, u32)] {
        &self.duplicates
    }

    /// Number of finite tetrahedra.
    #[inline]
    pub fn n_tets(&self) -> usize {
        self.n_finite
    }

    /// Number of tetrahedra including the infinite ones (one per hull facet).
    #[inline]
    pub fn n_all_tets(&self) -> usize {
        self.tets.len()
    }

    /// Whether `t` is an infinite tetrahedron (`t >= n_tets()`).
    #[inline]
    pub fn is_infinite(&self, t: u32) -> bool {
        t as usize >= self.n_finite
    }

    /// Vertices of tetrahedron `t` ([`INFINITE`] for the infinite vertex).
    #[inline]
    pub fn tet_vertices(&self, t: u32) -> [u32; 4] {
        self.tets[t as usize].v
    }

    /// Neighbours of tetrahedron `t`; neighbour `i` shares the face opposite vertex `i`.
    #[inline]
    pub fn tet_neighbors(&self, t: u32) -> [u32; 4] {
        self.tets[t as usize].n.map(|c| c >> 2)
    }

    /// Index of the face of neighbour `tet_neighbors(t)[i]` that is face `i` of `t`.
    #[inline]
    pub fn mirror_face(&self, t: u32, i: usize) -> usize {
        (self.tets[t as usize].n[i] & 3) as usize
    }

    /// Vertices of the finite tetrahedra `0..n_tets()`, in order.
    pub fn tets(&self) -> impl ExactSizeIterator<Item = [u32; 4]> + '_ {
        self.tets[..self.n_finite].iter().map(|t| t.v)
    }

    /// Counts and timings of the construction.
    pub fn stats(&self) -> &DelaunayStats {
        &self.stats
    }

    /// Coordinates of vertex `v` as the predicates see them (rescaled exactly).
    #[inline]
    pub(crate) fn p(&self, v: u32) -> &P3 {
        match self.scaled.get(v as usize) {
            Some(q) => q,
            None => self.points[v as usize].as_ref(),
        }
    }
}

/// Positions in `order` of four affinely independent points, or the reason there are none.
fn initial_simplex(input: &[P3], order: &[u32]) -> Result<[usize; 4], DelaunayError> {
    let p = |k: usize| &input[order[k] as usize];
    let n = order.len();
    let fail = |collinear: bool| -> DelaunayError {
        let mut reps: Vec<&P3> = Vec::new();
        for q in input {
            if reps.len() >= 4 {
                break;
            }
            if !reps.contains(&q) {
                reps.push(q);
            }
        }
        if reps.len() < 4 {
            DelaunayError::TooFewPoints {
                distinct: reps.len(),
            }
        } else if collinear {
            DelaunayError::AllCollinear
        } else {
            DelaunayError::AllCoplanar
        }
    };
    if n == 0 {
        return Err(fail(true));
    }
    let i0 = 0;
    let Some(i1) = (1..n).find(|&k| p(k) != p(i0)) else {
        return Err(fail(true));
    };
    let Some(i2) = (i1 + 1..n).find(|&k| !collinear(p(i0), p(i1), p(k))) else {
        return Err(fail(true));
    };
    let Some(i3) = (i2 + 1..n).find(|&k| orient3d(p(i0), p(i1), p(i2), p(k)) != 0) else {
        return Err(fail(false));
    };
    Ok([i0, i1, i2, i3])
}

/// Exact collinearity: all three coordinate-plane projections are collinear.
fn collinear(a: &P3, b: &P3, c: &P3) -> bool {
    let o = |x: usize, y: usize| {
        robust::orient2d(
            robust::Coord { x: a[x], y: a[y] },
            robust::Coord { x: b[x], y: b[y] },
            robust::Coord { x: c[x], y: c[y] },
        )
    };
    o(0, 1) == 0.0 && o(1, 2) == 0.0 && o(2, 0) == 0.0
}
