//! Statistics over seeds: for every configuration (a cell without its seed index), the
//! mean, sample standard deviation and 95 % confidence interval (Student t) of each
//! metric over the seeds that finished ok.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;
use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::experiment::{DataSpec, Labels};
use crate::registry::MethodKind;
use crate::store::{Dist, Row, Status};

/// Mean, spread and confidence interval of one metric.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    /// Number of values.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one value).
    pub std: f64,
    /// Half-width of the 95 % confidence interval of the mean (NaN for one value).
    pub ci95: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

impl Stat {
    /// Statistics of `v` (`None` when empty).
    pub fn of(v: &[f64]) -> Option<Self> {
        if v.is_empty() {
            return None;
        }
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        // Identical values can leave rounding residue in the sum; call it 0.
        let std = if std <= 1e-12 * mean.abs() { 0.0 } else { std };
        let ci95 = if n > 1 {
            StudentsT::new(0.0, 1.0, (n - 1) as f64)
                .map(|t| t.inverse_cdf(0.975) * std / (n as f64).sqrt())
                .unwrap_or(f64::NAN)
        } else {
            f64::NAN
        };
        Some(Self {
            n,
            mean,
            std,
            ci95,
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        })
    }
}

/// One configuration, aggregated over its seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Group {
    /// Configuration key.
    pub config: String,
    /// Smallest grid index of its cells (for ordering).
    pub index: usize,
    /// Labels.
    pub labels: Labels,
    /// Method name.
    pub method: String,
    /// Method kind.
    pub kind: MethodKind,
    /// Resolved parameters.
    pub params: Value,
    /// Input data spec.
    pub data: DataSpec,
    /// Cells (seeds) in the group.
    pub cells: usize,
    /// Cells that finished ok.
    pub ok: usize,
    /// Metric statistics over the ok cells.
    pub metrics: BTreeMap<String, Stat>,
    /// Cost statistics (`method_s`, `wall_s`, `peak_rss_mib`).
    pub cost: BTreeMap<String, Stat>,
    /// Per-point error distribution, quartiles averaged over the ok seeds.
    pub dist: Option<Dist>,
}

impl Group {
    /// `dataset / perturbation / method`.
    pub fn label(&self) -> String {
        format!(
            "{} / {} / {}",
            self.labels.dataset, self.labels.perturb, self.labels.method
        )
    }
}

/// Groups rows by configuration, in grid order.
pub fn aggregate(rows: &[Row]) -> Vec<Group> {
    let mut by: BTreeMap<&str, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        by.entry(r.config.as_str()).or_default().push(r);
    }
    let mut groups: Vec<Group> = by
        .into_values()
        .map(|rs| {
            let first = rs[0];
            let ok: Vec<&&Row> = rs.iter().filter(|r| r.status == Status::Ok).collect();
            let mut values: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
            for r in &ok {
                for (k, v) in &r.metrics {
                    values.entry(k).or_default().push(*v);
                }
            }
            let metrics = values
                .into_iter()
                .filter_map(|(k, v)| Stat::of(&v).map(|s| (k.to_string(), s)))
                .collect();
            let mut cost = BTreeMap::new();
            for (name, f) in [
                ("method_s", (|r: &Row| r.cost.method_s) as fn(&Row) -> f64),
                ("wall_s", |r| r.cost.wall_s),
                ("peak_rss_mib", |r| r.cost.peak_rss_mib),
            ] {
                let v: Vec<f64> = ok.iter().map(|r| f(r)).collect();
                if let Some(s) = Stat::of(&v) {
                    cost.insert(name.to_string(), s);
                }
            }
            // The methods' own timings (`cost.timings`), for `[[expect]] metric = "cost.NAME"`.
            let mut timings: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
            for r in &ok {
                for (k, v) in &r.cost.timings {
                    timings.entry(k).or_default().push(*v);
                }
            }
            for (k, v) in timings {
                if let Some(s) = Stat::of(&v) {
                    cost.entry(k.to_string()).or_insert(s);
                }
            }
            let dists: Vec<&Dist> = ok.iter().filter_map(|r| r.dist.as_ref()).collect();
            let dist = (!dists.is_empty()).then(|| {
                let m = |f: fn(&Dist) -> f64| {
                    dists.iter().map(|d| f(d)).sum::<f64>() / dists.len() as f64
                };
                Dist {
                    what: dists[0].what.clone(),
                    n: dists.iter().map(|d| d.n).sum(),
                    min: m(|d| d.min),
                    q1: m(|d| d.q1),
                    median: m(|d| d.median),
                    q3: m(|d| d.q3),
                    p95: m(|d| d.p95),
                    max: m(|d| d.max),
                    mean: m(|d| d.mean),
                }
            });
            Group {
                config: first.config.clone(),
                index: rs.iter().map(|r| r.index).min().unwrap_or(0),
                labels: first.labels.clone(),
                method: first.spec.method.clone(),
                kind: first.spec.kind,
                params: first.spec.params.clone(),
                data: first.spec.data.clone(),
                cells: rs.len(),
                ok: ok.len(),
                metrics,
                cost,
                dist,
            }
        })
        .collect();
    groups.sort_by_key(|g| g.index);
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stat_matches_hand_values() {
        let s = Stat::of(&[1.0, 2.0, 3.0]).unwrap();
        assert_eq!(s.mean, 2.0);
        assert!((s.std - 1.0).abs() < 1e-12);
        // t_{0.975, 2} = 4.302653
        assert!(
            (s.ci95 - 4.302_652_729_7 / 3f64.sqrt()).abs() < 1e-6,
            "{}",
            s.ci95
        );
        let one = Stat::of(&[5.0]).unwrap();
        assert_eq!((one.std, one.n), (0.0, 1));
        assert!(one.ci95.is_nan());
        assert!(Stat::of(&[]).is_none());
    }
}
