//! Regression tracking: baselines (per-configuration metric means) and comparison of a
//! current run against one.
//!
//! A baseline stores, for every configuration, the mean of each metric over its ok
//! seeds and the ok count. `compare` reports each metric that moved by more than its
//! tolerance as improved or regressed (direction from [`higher_is_better`]), a
//! configuration missing from the current run or with fewer ok seeds as a regression,
//! and new configurations as information. Costs (time, memory) are not in baselines:
//! they are only comparable on one machine.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::aggregate::Group;
use crate::error::{HarnessError, Result};
use crate::metric_spec::higher_is_better;

/// A tolerance: relative, absolute, or both (a change within either is no change).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tol {
    /// Relative tolerance (fraction of the baseline's magnitude).
    pub rel: Option<f64>,
    /// Absolute tolerance.
    pub abs: Option<f64>,
}

impl Tol {
    /// Parses `rel:0.05`, `abs:0.001` or `rel:0.05,abs:1e-6`.
    pub fn parse(s: &str) -> Result<Self> {
        let mut t = Tol {
            rel: None,
            abs: None,
        };
        for part in s.split(',') {
            let (k, v) = part.trim().split_once(':').ok_or_else(|| {
                HarnessError::input(format!("tolerance '{s}': expected rel:X or abs:X"))
            })?;
            let v: f64 = v
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    HarnessError::input(format!("tolerance '{s}': '{v}' is not a number >= 0"))
                })?;
            match k.trim() {
                "rel" => t.rel = Some(v),
                "abs" => t.abs = Some(v),
                other => {
                    return Err(HarnessError::input(format!(
                        "tolerance '{s}': unknown kind '{other}'; valid: rel, abs"
                    )));
                }
            }
        }
        Ok(t)
    }

    /// Whether `current` is within tolerance of `reference`.
    pub fn within(&self, reference: f64, current: f64) -> bool {
        let d = (current - reference).abs();
        if d == 0.0 {
            return true;
        }
        self.abs.is_some_and(|a| d <= a) || self.rel.is_some_and(|r| d <= r * reference.abs())
    }
}

impl std::fmt::Display for Tol {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut parts = Vec::new();
        if let Some(r) = self.rel {
            parts.push(format!("rel:{r}"));
        }
        if let Some(a) = self.abs {
            parts.push(format!("abs:{a}"));
        }
        f.write_str(&parts.join(","))
    }
}

/// Default tolerance: 1 % relative or 1e-9 absolute.
pub const DEFAULT_TOL: Tol = Tol {
    rel: Some(0.01),
    abs: Some(1e-9),
};

/// Tolerances per metric: exact names, `prefix*` patterns or `*`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tolerances {
    rules: Vec<(String, Tol)>,
}

impl Tolerances {
    /// Parses `metric=rel:0.05` entries (`--tol`).
    pub fn parse(entries: &[String]) -> Result<Self> {
        let mut rules = Vec::new();
        for e in entries {
            let (m, t) = e.split_once('=').ok_or_else(|| {
                HarnessError::input(format!(
                    "--tol '{e}': expected metric=rel:X or metric=abs:X"
                ))
            })?;
            rules.push((m.trim().to_string(), Tol::parse(t)?));
        }
        Ok(Self { rules })
    }

    /// Tolerance of `metric`: the last matching rule, else [`DEFAULT_TOL`].
    pub fn of(&self, metric: &str) -> Tol {
        self.rules
            .iter()
            .rev()
            .find(|(p, _)| match p.strip_suffix('*') {
                Some(prefix) => metric.starts_with(prefix),
                None => p == metric,
            })
            .map_or(DEFAULT_TOL, |(_, t)| *t)
    }
}

/// One configuration in a baseline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BaselineEntry {
    /// Configuration key.
    pub config: String,
    /// `dataset / perturbation / method`.
    pub label: String,
    /// Seeds in the configuration.
    pub cells: usize,
    /// Seeds that finished ok.
    pub ok: usize,
    /// Metric means over the ok seeds.
    pub metrics: BTreeMap<String, f64>,
}

/// A saved baseline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Baseline {
    /// Experiment name.
    pub experiment: String,
    /// Harness version that produced it (keys change with it).
    pub harness_version: String,
    /// Git commit of the run, when known.
    pub git_commit: String,
    /// Configurations.
    pub configs: Vec<BaselineEntry>,
}

impl Baseline {
    /// A baseline from aggregated groups.
    pub fn from_groups(experiment: &str, git_commit: &str, groups: &[Group]) -> Self {
        Self {
            experiment: experiment.to_string(),
            harness_version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: git_commit.to_string(),
            configs: groups
                .iter()
                .map(|g| BaselineEntry {
                    config: g.config.clone(),
                    label: g.label(),
                    cells: g.cells,
                    ok: g.ok,
                    metrics: g.metrics.iter().map(|(k, s)| (k.clone(), s.mean)).collect(),
                })
                .collect(),
        }
    }

    /// Reads a baseline file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::error::read_to_string(path)?;
        serde_json::from_str(&text)
            .map_err(|e| HarnessError::input(format!("{}: not a baseline: {e}", path.display())))
    }

    /// Writes it (pretty JSON, stable order).
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut text =
            serde_json::to_string_pretty(self).map_err(|e| HarnessError::failure(e.to_string()))?;
        text.push('\n');
        crate::error::write_atomic(path, text.as_bytes())
    }
}

/// A metric that moved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Change {
    /// Configuration label.
    pub label: String,
    /// Metric.
    pub metric: String,
    /// Baseline value.
    pub baseline: f64,
    /// Current value.
    pub current: f64,
    /// Tolerance applied.
    pub tol: String,
}

/// Result of a comparison.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Metrics better than the baseline beyond tolerance.
    pub improved: Vec<Change>,
    /// Metrics worse than the baseline beyond tolerance.
    pub regressed: Vec<Change>,
    /// Configurations of the baseline missing from the current run, or with fewer ok seeds.
    pub lost: Vec<String>,
    /// Configurations only in the current run.
    pub new: Vec<String>,
    /// Configurations whose key changed (a parameter renamed, a default added) but whose
    /// label matched exactly one configuration on each side; they were compared.
    #[serde(default)]
    pub rekeyed: Vec<String>,
    /// Metric values compared.
    pub compared: usize,
}

impl Comparison {
    /// True when anything regressed.
    pub fn has_regressions(&self) -> bool {
        !self.regressed.is_empty() || !self.lost.is_empty()
    }
}

fn label_counts(side: &[BaselineEntry]) -> BTreeMap<&str, usize> {
    let mut n: BTreeMap<&str, usize> = BTreeMap::new();
    for c in side {
        *n.entry(c.label.as_str()).or_default() += 1;
    }
    n
}

/// Compares `current` against `baseline`.
pub fn compare(baseline: &Baseline, current: &Baseline, tols: &Tolerances) -> Comparison {
    let cur: BTreeMap<&str, &BaselineEntry> = current
        .configs
        .iter()
        .map(|c| (c.config.as_str(), c))
        .collect();
    let base: BTreeMap<&str, &BaselineEntry> = baseline
        .configs
        .iter()
        .map(|c| (c.config.as_str(), c))
        .collect();
    // Labels that name exactly one configuration on each side, for re-keyed matches.
    let (bn, cn) = (
        label_counts(&baseline.configs),
        label_counts(&current.configs),
    );
    let by_label: BTreeMap<&str, &BaselineEntry> = current
        .configs
        .iter()
        .filter(|c| !base.contains_key(c.config.as_str()) && cn[c.label.as_str()] == 1)
        .map(|c| (c.label.as_str(), c))
        .collect();
    let mut matched_by_label = std::collections::BTreeSet::new();
    let mut out = Comparison::default();
    for b in &baseline.configs {
        let c = match cur.get(b.config.as_str()) {
            Some(c) => *c,
            None => match by_label.get(b.label.as_str()) {
                Some(c) if bn[b.label.as_str()] == 1 => {
                    out.rekeyed.push(b.label.clone());
                    matched_by_label.insert(c.config.as_str());
                    *c
                }
                _ => {
                    out.lost.push(format!("{} (missing)", b.label));
                    continue;
                }
            },
        };
        if c.ok < b.ok {
            out.lost.push(format!(
                "{} ({} of {} seeds ok, baseline {})",
                b.label, c.ok, c.cells, b.ok
            ));
        }
        for (m, &bv) in &b.metrics {
            let Some(&cv) = c.metrics.get(m) else {
                out.lost.push(format!("{}: metric {m} missing", b.label));
                continue;
            };
            out.compared += 1;
            let tol = tols.of(m);
            if tol.within(bv, cv) {
                continue;
            }
            let better = if higher_is_better(m) {
                cv > bv
            } else {
                cv < bv
            };
            let ch = Change {
                label: b.label.clone(),
                metric: m.clone(),
                baseline: bv,
                current: cv,
                tol: tol.to_string(),
            };
            if better {
                out.improved.push(ch);
            } else {
                out.regressed.push(ch);
            }
        }
    }
    for c in &current.configs {
        if !base.contains_key(c.config.as_str()) && !matched_by_label.contains(c.config.as_str()) {
            out.new.push(c.label.clone());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rekeyed_configuration_is_matched_by_its_unique_label() {
        let base = bl(1.0, 3);
        let mut cur = bl(2.0, 3);
        cur.configs[0].config = "c2".into();
        let c = compare(&base, &cur, &Tolerances::default());
        assert_eq!(c.rekeyed, ["d / p / m"]);
        assert!(c.lost.is_empty() && c.new.is_empty(), "{c:?}");
        assert_eq!(c.compared, base.configs[0].metrics.len());
        // Two current configurations with that label: no guess, lost and new.
        let mut two = cur.clone();
        let mut other = two.configs[0].clone();
        other.config = "c3".into();
        two.configs.push(other);
        let c = compare(&base, &two, &Tolerances::default());
        assert!(c.rekeyed.is_empty());
        assert_eq!((c.lost.len(), c.new.len()), (1, 2));
    }

    fn bl(v: f64, ok: usize) -> Baseline {
        Baseline {
            experiment: "e".into(),
            harness_version: "0".into(),
            git_commit: "x".into(),
            configs: vec![BaselineEntry {
                config: "c1".into(),
                label: "d / p / m".into(),
                cells: 3,
                ok,
                metrics: [
                    ("chamfer_l1".to_string(), v),
                    ("fscore_0.01".to_string(), 1.0 - v),
                ]
                .into(),
            }],
        }
    }

    #[test]
    fn regressions_respect_direction_and_tolerance() {
        let t = Tolerances::parse(&["chamfer_l1=rel:0.05".into()]).unwrap();
        assert!(!compare(&bl(0.1, 3), &bl(0.104, 3), &t).has_regressions());
        let worse = compare(&bl(0.1, 3), &bl(0.2, 3), &t);
        assert_eq!(worse.regressed.len(), 2, "{worse:?}");
        let better = compare(&bl(0.2, 3), &bl(0.1, 3), &t);
        assert_eq!((better.improved.len(), better.regressed.len()), (2, 0));
        let lost = compare(&bl(0.1, 3), &bl(0.1, 2), &t);
        assert!(lost.has_regressions());
        assert!(Tol::parse("rel:x").is_err());
        assert_eq!(
            Tolerances::parse(&["chamfer*=abs:1".into()])
                .unwrap()
                .of("chamfer_l1")
                .abs,
            Some(1.0)
        );
    }
}
