//! Input checks shared by the reconstructors that need oriented normals
//! (`ball-pivoting`, `poisson`): normals present, enough distinct points, not all on a
//! line, normals consistently oriented; plus the deduplicated working set and its mean
//! nearest-neighbour spacing.

use std::collections::HashSet;
use std::hash::{Hash, Hasher};

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::MethodError;

use super::nearest::nearest_others;

/// The deduplicated, checked input.
#[derive(Debug)]
pub(crate) struct Prepared {
    /// Input index of each distinct position (its first occurrence), increasing.
    pub ids: Vec<u32>,
    /// Distinct positions.
    pub pos: Vec<DVec3>,
    /// Unit normals of the distinct positions (zero where the input normal is zero).
    pub nrm: Vec<DVec3>,
    /// Input points that repeat an earlier position exactly.
    pub duplicates: usize,
    /// Distinct points whose normal is zero (the estimator could not decide).
    pub zero_normals: usize,
    /// Mean distance from a distinct point to its nearest other distinct point.
    pub spacing: f64,
    /// Share of distinct points whose nearest neighbour's normal points the other way.
    pub flipped_share: f64,
}

/// The bit pattern of a position (with `-0` read as `0`), as a hash key: equal exactly
/// when the positions are, hashed as one mixed `u64` (cheaper than the 24 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Bits([u64; 3]);

impl Bits {
    #[inline]
    fn of(p: DVec3) -> Self {
        Bits((p + DVec3::ZERO).to_array().map(f64::to_bits))
    }
}

impl Hash for Bits {
    #[inline]
    fn hash<H: Hasher>(&self, state: &mut H) {
        let [x, y, z] = self.0;
        state.write_u64(
            x ^ y.rotate_left(21).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ z.rotate_left(42).wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
        );
    }
}

fn invalid(name: &str, what: String) -> MethodError {
    MethodError::InvalidInput(format!("{name}: {what}"))
}

/// Checks `cloud` for a method `name` that needs oriented normals and returns the
/// deduplicated working set. Refuses: no normals, fewer than 3 distinct positions,
/// all points on one line, every normal zero, and normals whose nearest-neighbour
/// flip share exceeds `max_flipped_share` (unoriented normals flip about half).
pub(crate) fn prepare(
    cloud: &PointCloud,
    name: &str,
    max_flipped_share: f64,
) -> Result<Prepared, MethodError> {
    let n = cloud.len();
    let Some(normals) = cloud.normals() else {
        return Err(invalid(
            name,
            format!(
                "needs oriented normals but the cloud has none: put an oriented normal \
                 estimator before it (steps = [\"jet\", \"{name}\"] or [\"gt-normals\", \"{name}\"])"
            ),
        ));
    };
    if n < 3 {
        return Err(invalid(name, format!("needs at least 3 points, got {n}")));
    }
    // Exact duplicates (bit patterns, -0 == 0): the first occurrence represents them.
    // One pass in input order with a hash set of the bit patterns gives the first
    // occurrences already in increasing order (a sort by pattern cost several times
    // more on 100k points).
    let pts = cloud.positions();
    let mut seen: HashSet<Bits, foldhash::fast::FixedState> =
        HashSet::with_capacity_and_hasher(n, Default::default());
    let ids: Vec<u32> = (0..n as u32)
        .filter(|&i| seen.insert(Bits::of(pts[i as usize])))
        .collect();
    drop(seen);
    let duplicates = n - ids.len();
    if ids.len() < 3 {
        return Err(invalid(
            name,
            format!(
                "needs at least 3 distinct points, got {} ({duplicates} exact duplicates)",
                ids.len()
            ),
        ));
    }
    let pos: Vec<DVec3> = ids.iter().map(|&i| pts[i as usize]).collect();
    if collinear(&pos) {
        return Err(invalid(
            name,
            format!("all {} distinct points lie on one line", pos.len()),
        ));
    }
    let nrm: Vec<DVec3> = ids
        .iter()
        .map(|&i| normals[i as usize].normalize_or_zero())
        .collect();
    let zero_normals = nrm.iter().filter(|v| **v == DVec3::ZERO).count();
    if zero_normals == nrm.len() {
        return Err(invalid(name, "every normal is zero".into()));
    }
    // The nearest other point of each (as `knn_self_table(&pos, 1, true)`, from a grid);
    // the distances summed in point order.
    let nn = nearest_others(&pos)?;
    let spacing = nn.iter().map(|&(_, d2)| d2.sqrt()).sum::<f64>() / pos.len() as f64;
    let flipped = (0..pos.len())
        .filter(|&i| nrm[i].dot(nrm[nn[i].0 as usize]) < 0.0)
        .count();
    let flipped_share = flipped as f64 / pos.len() as f64;
    if flipped_share > max_flipped_share {
        return Err(invalid(
            name,
            format!(
                "the normals look unoriented: {:.1}% of the points have a nearest neighbour \
                 whose normal points the other way (at most {:.1}% allowed, \
                 max_flipped_share); orient them first (an estimator with orient_k > 0, \
                 or gt-normals)",
                100.0 * flipped_share,
                100.0 * max_flipped_share
            ),
        ));
    }
    Ok(Prepared {
        ids,
        pos,
        nrm,
        duplicates,
        zero_normals,
        spacing,
        flipped_share,
    })
}

/// Whether every point lies on the line through the first point and the point farthest
/// from it (relative tolerance 1e-12 of that distance).
fn collinear(pos: &[DVec3]) -> bool {
    let p0 = pos[0];
    let far = pos
        .iter()
        .copied()
        .max_by(|a, b| a.distance_squared(p0).total_cmp(&b.distance_squared(p0)))
        .unwrap_or(p0);
    let d = far - p0;
    let len = d.length();
    if len == 0.0 {
        return true;
    }
    let u = d / len;
    pos.iter().all(|&p| {
        let v = p - p0;
        (v - u * v.dot(u)).length() <= 1e-12 * len
    })
}
