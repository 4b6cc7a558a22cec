//! [`PointIndex`]: exact kNN and radius queries over a point set on kiddo's static
//! k-d tree, and [`mean_spacing`].

use std::num::NonZeroUsize;

use glam::DVec3;
use kiddo::ImmutableKdTree;
use kiddo::dist::SquaredEuclidean;
use rayon::prelude::*;

use super::checks::{check_k, check_query, check_radius};
use super::self_knn::knn_self_table;
use super::tables::{KnnTable, Neighbor, RadiusTable};
use crate::error::{GeomError, Result, check_finite};

type Tree = ImmutableKdTree<f64, 3>;

/// The conventional `k` of [`mean_spacing`]: distance to the nearest other point.
pub const DEFAULT_SPACING_K: usize = 1;
/// A static k-d tree over a point set, for exact kNN and radius queries.
///
/// Built on kiddo 6's `ImmutableKdTree` (the mutable tree loses points on regular grids
/// and duplicated sets; see CRATES.md). The index keeps its own copy of the points.
///
/// Results are sorted by (squared distance, index): when several points tie at the k-th
/// distance the lower indices are returned, which a plain kd-tree kNN does not guarantee.
/// This costs one extra neighbour per query and, only when a tie straddles the k-th
/// place (common on grids), one radius query.
pub struct PointIndex {
    tree: Tree,
    points: Vec<DVec3>,
}

impl std::fmt::Debug for PointIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PointIndex")
            .field("points", &self.points.len())
            .finish_non_exhaustive()
    }
}

/// Sorts by (distance, index).
fn sort_neighbors(v: &mut [Neighbor]) {
    v.sort_unstable_by(|a, b| a.dist2.total_cmp(&b.dist2).then(a.index.cmp(&b.index)));
}

impl PointIndex {
    /// Builds the index. Errors on an empty slice, a non-finite point (naming it) or more
    /// than `u32::MAX` points.
    pub fn new(points: &[DVec3]) -> Result<Self> {
        if points.is_empty() {
            return Err(GeomError::InvalidInput(
                "cannot build a point index over no points".to_string(),
            ));
        }
        if points.len() > u32::MAX as usize {
            return Err(GeomError::InvalidInput(format!(
                "{} points exceed the u32 index range",
                points.len()
            )));
        }
        check_finite("point", points)?;
        let arr: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        let tree = Tree::new_from_slice(&arr)
            .map_err(|e| GeomError::InvalidInput(format!("k-d tree construction failed: {e:?}")))?;
        Ok(Self {
            tree,
            points: points.to_vec(),
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Always false (an index has at least one point); for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The indexed points.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    fn neighbor(&self, p: DVec3, index: u32) -> Neighbor {
        Neighbor {
            index,
            dist2: (p - self.points[index as usize]).length_squared(),
        }
    }

    /// The `k` nearest points (k clamped to `len()`), appended to `out` sorted by
    /// (distance, index). `p` must be finite.
    fn knn_into(&self, p: DVec3, k: usize, out: &mut Vec<Neighbor>) {
        let n = self.points.len();
        let k = k.min(n);
        if k == 0 {
            return;
        }
        let Some(q) = NonZeroUsize::new((k + 1).min(n)) else {
            return;
        };
        let pa = p.to_array();
        let res = self
            .tree
            .query(&pa)
            .nearest_n::<SquaredEuclidean<f64>>(q)
            .execute();
        let start = out.len();
        out.extend(res.iter().map(|r| self.neighbor(p, r.item)));
        sort_neighbors(&mut out[start..]);
        if out.len() - start > k {
            let dk = out[start + k - 1].dist2;
            let dk1 = out[start + k].dist2;
            if dk1 <= dk {
                // A tie straddles the k-th place: fetch every point at distance <= dk so
                // the lowest indices win. (Use the tree's own distance for the radius so
                // no tied point is lost to rounding differences.)
                let kd = res
                    .iter()
                    .map(|r| r.distance)
                    .fold(f64::NEG_INFINITY, f64::max);
                out.truncate(start);
                let all = self
                    .tree
                    .query(&pa)
                    .within::<SquaredEuclidean<f64>>(kd)
                    .execute();
                out.extend(all.iter().map(|r| self.neighbor(p, r.item)));
                sort_neighbors(&mut out[start..]);
            }
            out.truncate(start + k);
        }
    }

    /// The `k` nearest points to `p`, sorted by (squared distance, index). `k` larger than
    /// the number of points is clamped; `k = 0` gives an empty list. Errors on a
    /// non-finite `p`.
    pub fn knn(&self, p: DVec3, k: usize) -> Result<Vec<Neighbor>> {
        check_query(p)?;
        let mut out = Vec::with_capacity(k.min(self.len()) + 1);
        self.knn_into(p, k, &mut out);
        Ok(out)
    }

    /// The nearest point to `p` (lowest index among equidistant ones).
    pub fn nearest(&self, p: DVec3) -> Result<Neighbor> {
        check_query(p)?;
        let mut out = Vec::with_capacity(2);
        self.knn_into(p, 1, &mut out);
        out.first().copied().ok_or_else(|| {
            GeomError::InvalidInput("nearest-neighbour query on an empty index".to_string())
        })
    }

    /// All points within distance `r` of `p` (inclusive, up to the rounding of `r * r`),
    /// sorted by (squared distance, index). Errors on a non-finite `p` or a negative or
    /// non-finite `r`.
    pub fn radius(&self, p: DVec3, r: f64) -> Result<Vec<Neighbor>> {
        check_query(p)?;
        check_radius(r)?;
        Ok(self.radius_unchecked(p, r))
    }

    fn radius_unchecked(&self, p: DVec3, r: f64) -> Vec<Neighbor> {
        let res = self
            .tree
            .query(&p.to_array())
            .within::<SquaredEuclidean<f64>>(r * r)
            .execute();
        let mut out: Vec<Neighbor> = res.iter().map(|r| self.neighbor(p, r.item)).collect();
        sort_neighbors(&mut out);
        out
    }

    /// kNN of every indexed point, in parallel (see [`knn_self_table`], which this calls:
    /// the rows come from a tree specialised for all-points queries, not from the kiddo
    /// tree of this index).
    ///
    /// With `exclude_self`, row `i` leaves out point `i` itself (but keeps exact duplicates
    /// of it, at distance 0), and `k` is clamped to `len() - 1`; otherwise to `len()`.
    /// Errors when `k == 0` or when the clamped `k` is 0 (a single point with
    /// `exclude_self`).
    pub fn knn_all(&self, k: usize, exclude_self: bool) -> Result<KnnTable> {
        knn_self_table(&self.points, k, exclude_self)
    }

    /// kNN of arbitrary query points, in parallel (`k` clamped to `len()`). Errors on
    /// `k == 0` or a non-finite query (naming it).
    pub fn knn_batch(&self, queries: &[DVec3], k: usize) -> Result<KnnTable> {
        check_k(k)?;
        check_finite("query point", queries)?;
        let keff = k.min(self.len());
        let mut indices = vec![0u32; queries.len() * keff];
        let mut dist2 = vec![0.0; queries.len() * keff];
        indices
            .par_chunks_mut(keff)
            .zip(dist2.par_chunks_mut(keff))
            .zip(queries.par_iter())
            .for_each_init(Vec::new, |buf, ((ri, rd), &p)| {
                buf.clear();
                self.knn_into(p, keff, buf);
                for (j, nb) in buf.iter().enumerate() {
                    ri[j] = nb.index;
                    rd[j] = nb.dist2;
                }
            });
        Ok(KnnTable {
            k: keff,
            indices,
            dist2,
        })
    }

    /// Nearest indexed point of every query, in parallel.
    pub fn nearest_batch(&self, queries: &[DVec3]) -> Result<Vec<Neighbor>> {
        check_finite("query point", queries)?;
        Ok(queries
            .par_iter()
            .map_init(Vec::new, |buf, &p| {
                buf.clear();
                self.knn_into(p, 1, buf);
                buf[0]
            })
            .collect())
    }

    /// Radius search for every query, in parallel, as a CSR table.
    pub fn radius_batch(&self, queries: &[DVec3], r: f64) -> Result<RadiusTable> {
        check_finite("query point", queries)?;
        check_radius(r)?;
        let rows: Vec<Vec<Neighbor>> = queries
            .par_iter()
            .map(|&p| self.radius_unchecked(p, r))
            .collect();
        let mut t = RadiusTable {
            offsets: Vec::with_capacity(rows.len() + 1),
            ..Default::default()
        };
        t.offsets.push(0);
        for row in rows {
            t.indices.extend(row.iter().map(|nb| nb.index));
            t.dist2.extend(row.iter().map(|nb| nb.dist2));
            t.offsets.push(t.indices.len());
        }
        Ok(t)
    }
}

/// Mean distance from each point to its `k` nearest other points, averaged over the
/// points ([`DEFAULT_SPACING_K`] = 1 is the usual "sampling spacing").
///
/// Exact duplicates are merged first (positions compared bit for bit, `-0.0 == 0.0`):
/// otherwise every duplicated point would contribute a spacing of 0 and a cloud with
/// doubled points would look twice as dense. The average is over distinct positions; `k`
/// is clamped to (distinct positions - 1).
///
/// Errors: `k == 0`, non-finite points, fewer than two distinct positions.
pub fn mean_spacing(points: &[DVec3], k: usize) -> Result<f64> {
    check_k(k)?;
    check_finite("point", points)?;
    let mut keys: Vec<[u64; 3]> = points
        .iter()
        .map(|p| (*p + DVec3::ZERO).to_array().map(f64::to_bits))
        .collect();
    keys.par_sort_unstable();
    keys.dedup();
    if keys.len() < 2 {
        return Err(GeomError::InvalidInput(format!(
            "mean spacing needs at least 2 distinct points, got {}",
            keys.len()
        )));
    }
    let unique: Vec<DVec3> = keys
        .iter()
        .map(|k| DVec3::from_array(k.map(f64::from_bits)))
        .collect();
    let table = knn_self_table(&unique, k, true)?;
    let per_point: Vec<f64> = (0..table.rows())
        .into_par_iter()
        .map(|i| table.dist2(i).iter().map(|d| d.sqrt()).sum::<f64>() / table.k as f64)
        .collect();
    // Sequential sum: a parallel float reduction would depend on the thread split.
    Ok(per_point.iter().sum::<f64>() / per_point.len() as f64)
}
