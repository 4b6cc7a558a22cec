//! Refused-point classification: how well a method's list of refused (unused, "noise")
//! input points matches the outliers the generator added (seed 001 §4.4, spec §7 item 4).
//!
//! The generator knows which input points are outliers; the method reports the indices
//! it refused. Outliers are the positive class:
//! * `refused_outlier_recall` = |refused ∩ outliers| / |outliers| (null without outliers);
//! * `refused_precision` = |refused ∩ outliers| / |refused| (null when nothing is refused);
//! * `clean_refused_share` = |refused \ outliers| / |clean points| (null without clean
//!   points).

use crate::error::{MetricsError, Result};
use crate::report::{Entries, Report, put};

/// Refused points against the known outliers.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RefusedEval {
    /// Input points.
    pub points: usize,
    /// Added outliers among them.
    pub outliers: usize,
    /// Distinct refused indices.
    pub refused: usize,
    /// Refused indices that are outliers.
    pub refused_outliers: usize,
    /// Share of the outliers that were refused.
    pub refused_outlier_recall: Option<f64>,
    /// Share of the refused points that are outliers.
    pub refused_precision: Option<f64>,
    /// Share of the clean points that were refused.
    pub clean_refused_share: Option<f64>,
}

/// Evaluates the refused indices `refused` against the per-point outlier flags.
/// Duplicate indices count once; an index out of range is an error.
pub fn eval_refused(refused: &[u32], is_outlier: &[bool]) -> Result<RefusedEval> {
    let n = is_outlier.len();
    let mut seen = vec![false; n];
    let (mut r, mut ro) = (0usize, 0usize);
    for &i in refused {
        let i = i as usize;
        if i >= n {
            return Err(MetricsError::InvalidInput(format!(
                "refused index {i} out of range for {n} points"
            )));
        }
        if !seen[i] {
            seen[i] = true;
            r += 1;
            ro += usize::from(is_outlier[i]);
        }
    }
    let outliers = is_outlier.iter().filter(|&&o| o).count();
    let clean = n - outliers;
    let share = |a: usize, b: usize| (b > 0).then(|| a as f64 / b as f64);
    Ok(RefusedEval {
        points: n,
        outliers,
        refused: r,
        refused_outliers: ro,
        refused_outlier_recall: share(ro, outliers),
        refused_precision: share(ro, r),
        clean_refused_share: share(r - ro, clean),
    })
}

impl Report for RefusedEval {
    fn entries(&self) -> Entries {
        let mut e = Entries::new();
        put(&mut e, "outliers", self.outliers);
        put(&mut e, "refused", self.refused);
        put(&mut e, "refused_outliers", self.refused_outliers);
        put(
            &mut e,
            "refused_outlier_recall",
            self.refused_outlier_recall,
        );
        put(&mut e, "refused_precision", self.refused_precision);
        put(&mut e, "clean_refused_share", self.clean_refused_share);
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_counts() {
        // 10 points, outliers 6..10; refused {1, 6, 7, 7, 8}.
        let out: Vec<bool> = (0..10).map(|i| i >= 6).collect();
        let e = eval_refused(&[1, 6, 7, 7, 8], &out).unwrap();
        assert_eq!((e.outliers, e.refused, e.refused_outliers), (4, 4, 3));
        assert_eq!(e.refused_outlier_recall, Some(0.75));
        assert_eq!(e.refused_precision, Some(0.75));
        assert_eq!(e.clean_refused_share, Some(1.0 / 6.0));
    }

    #[test]
    fn undefined_shares_are_null_and_bad_index_is_an_error() {
        let e = eval_refused(&[], &[false, false]).unwrap();
        assert_eq!(e.refused_outlier_recall, None);
        assert_eq!(e.refused_precision, None);
        assert_eq!(e.clean_refused_share, Some(0.0));
        assert!(eval_refused(&[2], &[false, true]).is_err());
        let e = eval_refused(&[0], &[true]).unwrap();
        assert_eq!(e.clean_refused_share, None);
        assert_eq!(e.refused_outlier_recall, Some(1.0));
    }
}
