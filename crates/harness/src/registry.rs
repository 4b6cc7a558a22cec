//! The method registry: every normal estimator, feature detector, filter and
//! reconstructor by a stable kebab-case name, with typed parameters (serde defaults,
//! documented units).
//!
//! A method describes itself once, beside its code, by implementing
//! [`reconbench_geom::method::Describe`] (name, source, summary, parameter docs with
//! units, input needs, validating constructor); its registry entry is then one line in
//! [`crate::methods::algorithms`]:
//!
//! ```ignore
//! reconstruct::<BallPivoting>(),
//! ```
//!
//! `Params` types derive `Deserialize` with `#[serde(default, deny_unknown_fields)]` and
//! `Default`, so unknown keys are errors listing the valid ones and `list` can show the
//! defaults. The oracles and test-only methods, which need the cell's ground truth or
//! misbehave on purpose, use [`custom`] instead.

use std::sync::{Arc, OnceLock};

use glam::DVec3;
use reconbench_geom::method::{
    Describe, FeatureDetector, Filter, MethodError, NormalEstimator, Reconstructor,
};
pub use reconbench_geom::method::{Needs, ParamDoc, Unit};
use reconbench_synth::Shape;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{HarnessError, Result};

/// What a method produces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MethodKind {
    /// A [`NormalEstimator`].
    Normals,
    /// A [`FeatureDetector`].
    Features,
    /// A [`Filter`] (cloud in, cloud out).
    Filter,
    /// A [`Reconstructor`].
    Reconstruct,
}

impl MethodKind {
    /// Stable lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            MethodKind::Normals => "normals",
            MethodKind::Features => "features",
            MethodKind::Filter => "filter",
            MethodKind::Reconstruct => "reconstruct",
        }
    }
}

impl std::fmt::Display for MethodKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Ground truth a cell can hand to oracle methods.
///
/// Honesty rule: only methods registered with `needs_ground_truth = true` (the oracles,
/// shown as such in `list`) ever receive it; every other method gets `None` and sees
/// only the input positions.
#[derive(Debug, Clone, Default)]
pub struct GroundTruth {
    /// The analytic shape the cloud was sampled from.
    pub shape: Option<Arc<dyn Shape>>,
    /// Per input point: the clean surface normal at the sample it came from.
    pub normals: Option<Vec<DVec3>>,
    /// Per input point: distance of its clean position to the nearest sharp feature, as
    /// `reconbench-synth` computes it, absolute (synthetic shapes have unit diagonal);
    /// infinite for outliers and shapes without features.
    pub feature_distance: Option<Vec<f64>>,
}

/// What a constructor receives besides its parameters.
#[derive(Debug, Clone, Default)]
pub struct MethodEnv {
    /// Ground truth, for oracles only (see [`GroundTruth`]).
    pub ground_truth: Option<Arc<GroundTruth>>,
}

/// A constructed method.
#[derive(Debug)]
pub enum Built {
    /// A normal estimator.
    Normals(Box<dyn NormalEstimator>),
    /// A feature detector.
    Features(Box<dyn FeatureDetector>),
    /// A filter.
    Filter(Box<dyn Filter>),
    /// A reconstructor.
    Reconstruct(Box<dyn Reconstructor>),
}

/// Constructor of a [`custom`] entry from its typed parameters and the cell's
/// environment.
pub type MakeCustom<P> = fn(P, &MethodEnv) -> Result<Built, MethodError>;

type BuildFn = Arc<dyn Fn(&Value, &MethodEnv) -> Result<Built, MethodError> + Send + Sync>;
type DefaultsFn = Arc<dyn Fn() -> Value + Send + Sync>;
type CanonFn = Arc<dyn Fn(&Value) -> Result<Value, MethodError> + Send + Sync>;

/// One registered method.
#[derive(Clone)]
pub struct MethodEntry {
    /// Stable kebab-case name.
    pub name: &'static str,
    /// What it produces.
    pub kind: MethodKind,
    /// Seed section it implements (e.g. `"seed 001 §3.2"`), or `"oracle"`, `"debug"`.
    pub seed: &'static str,
    /// One-line summary.
    pub summary: &'static str,
    /// Parameter docs.
    pub params: &'static [ParamDoc],
    /// What its input cloud must carry.
    pub needs: Needs,
    /// Whether it receives ground truth (oracles only).
    pub needs_ground_truth: bool,
    /// Hidden from `list` unless `--all` (test-only `debug-*` methods).
    pub hidden: bool,
    defaults: DefaultsFn,
    canon: CanonFn,
    build: BuildFn,
}

impl std::fmt::Debug for MethodEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MethodEntry")
            .field("name", &self.name)
            .field("kind", &self.kind)
            .field("seed", &self.seed)
            .finish_non_exhaustive()
    }
}

impl MethodEntry {
    /// Default parameters as a JSON object.
    pub fn defaults(&self) -> Value {
        (self.defaults)()
    }

    /// `params` (a JSON object; `null` means none) parsed into the typed `Params`
    /// (defaults filled in, old parameter names accepted) and written back under the
    /// canonical names. The result is what goes into cell keys.
    pub fn resolve_params(&self, params: &Value) -> Result<Value> {
        let defaults = self.defaults();
        match (params, &defaults) {
            (Value::Null, _) | (Value::Object(_), Value::Object(_)) => {}
            (Value::Object(p), _) => {
                if let Some(k) = p.keys().next() {
                    return Err(HarnessError::input(format!(
                        "method '{}' has no parameters (got '{k}')",
                        self.name
                    )));
                }
            }
            (other, _) => {
                return Err(HarnessError::input(format!(
                    "method '{}': parameters must be a table, got {other}",
                    self.name
                )));
            }
        }
        let out = (self.canon)(params)
            .map_err(|e| HarnessError::input(format!("method '{}': {e}", self.name)))?;
        // Validate by building once without ground truth when the method allows it; the
        // parse step alone is what matters (oracles fail later without ground truth).
        (self.build)(&out, &MethodEnv::default())
            .map(drop)
            .or_else(|e| match e {
                MethodError::InvalidParameter { .. } => Err(e),
                _ => Ok(()),
            })
            .map_err(|e| HarnessError::input(format!("method '{}': {e}", self.name)))?;
        Ok(out)
    }

    /// Builds the method from resolved parameters.
    pub fn build(&self, params: &Value, env: &MethodEnv) -> Result<Built, MethodError> {
        let env = if self.needs_ground_truth {
            env.clone()
        } else {
            MethodEnv::default()
        };
        (self.build)(params, &env)
    }
}

/// Parses `params` into the typed `P`, turning serde's message (which lists the valid
/// keys of an unknown one) into [`MethodError::InvalidParameter`].
pub fn parse_params<P: DeserializeOwned>(params: &Value) -> Result<P, MethodError> {
    let v = if params.is_null() {
        Value::Object(Default::default())
    } else {
        params.clone()
    };
    serde_json::from_value(v).map_err(|e| MethodError::InvalidParameter {
        name: "params".into(),
        message: e.to_string(),
    })
}

fn defaults_of<P: Serialize + Default>() -> DefaultsFn {
    Arc::new(|| serde_json::to_value(P::default()).unwrap_or(Value::Null))
}

fn canon_of<P: Serialize + DeserializeOwned + 'static>() -> CanonFn {
    Arc::new(|v| {
        let p: P = parse_params(v)?;
        serde_json::to_value(p).map_err(|e| MethodError::Failed(format!("parameters: {e}")))
    })
}

fn described<M: Describe + 'static>(kind: MethodKind, wrap: fn(M) -> Built) -> MethodEntry {
    MethodEntry {
        name: M::NAME,
        kind,
        seed: M::SOURCE,
        summary: M::SUMMARY,
        params: M::PARAMS,
        needs: M::NEEDS,
        needs_ground_truth: false,
        hidden: false,
        defaults: defaults_of::<M::Params>(),
        canon: canon_of::<M::Params>(),
        build: Arc::new(move |v, _env| Ok(wrap(M::from_params(parse_params(v)?)?))),
    }
}

/// The entry of a normal estimator.
pub fn normals<M: Describe + NormalEstimator + 'static>() -> MethodEntry {
    described::<M>(MethodKind::Normals, |m| Built::Normals(Box::new(m)))
}

/// The entry of a feature detector.
pub fn features<M: Describe + FeatureDetector + 'static>() -> MethodEntry {
    described::<M>(MethodKind::Features, |m| Built::Features(Box::new(m)))
}

/// The entry of a filter.
pub fn filter<M: Describe + Filter + 'static>() -> MethodEntry {
    described::<M>(MethodKind::Filter, |m| Built::Filter(Box::new(m)))
}

/// The entry of a reconstructor.
pub fn reconstruct<M: Describe + Reconstructor + 'static>() -> MethodEntry {
    described::<M>(MethodKind::Reconstruct, |m| Built::Reconstruct(Box::new(m)))
}

/// An entry whose constructor also sees the cell's environment (oracles, test-only
/// methods). `make` must return a method of `kind`.
pub fn custom<P>(
    kind: MethodKind,
    name: &'static str,
    seed: &'static str,
    summary: &'static str,
    params: &'static [ParamDoc],
    make: MakeCustom<P>,
) -> MethodEntry
where
    P: DeserializeOwned + Serialize + Default + 'static,
{
    MethodEntry {
        name,
        kind,
        seed,
        summary,
        params,
        needs: Needs::Positions,
        needs_ground_truth: false,
        hidden: false,
        defaults: defaults_of::<P>(),
        canon: canon_of::<P>(),
        build: Arc::new(move |v, env| make(parse_params(v)?, env)),
    }
}

impl MethodEntry {
    /// Marks an oracle: it receives ground truth.
    #[must_use]
    pub fn oracle(mut self) -> Self {
        self.needs_ground_truth = true;
        self
    }

    /// Declares what the input must carry (for [`custom`] entries).
    #[must_use]
    pub fn needing(mut self, needs: Needs) -> Self {
        self.needs = needs;
        self
    }

    /// Hides the entry from `list` (unless `--all`).
    #[must_use]
    pub fn hidden(mut self) -> Self {
        self.hidden = true;
        self
    }
}

/// All registered methods. One line per method.
fn entries() -> Vec<MethodEntry> {
    use crate::methods::{debug, oracle};
    let mut v = vec![
        // Oracles: calibrate the harness (metric floor, geometry floor).
        oracle::gt_normals(),
        oracle::gt_features(),
        oracle::reference_mesh(),
        // Test-only methods, hidden from `list` (see `list --all`).
        debug::panic(),
        debug::abort(),
        debug::hang(),
        debug::alloc(),
        debug::sleep(),
        debug::splats(),
    ];
    // Algorithm crates: one line each in methods/algorithms.rs.
    v.extend(crate::methods::algorithms::entries());
    v
}

/// The registry, built once.
pub fn registry() -> &'static [MethodEntry] {
    static REG: OnceLock<Vec<MethodEntry>> = OnceLock::new();
    REG.get_or_init(entries)
}

/// Looks a method up; the error lists the valid names.
pub fn find(name: &str) -> Result<&'static MethodEntry> {
    registry().iter().find(|e| e.name == name).ok_or_else(|| {
        let names: Vec<&str> = registry()
            .iter()
            .filter(|e| !e.hidden)
            .map(|e| e.name)
            .collect();
        HarnessError::input(format!(
            "unknown method '{name}'; registered methods: {}",
            names.join(", ")
        ))
    })
}

/// A parameter as `list` shows it.
#[derive(Debug, Clone, Serialize)]
pub struct ParamInfo {
    /// Name.
    pub name: String,
    /// Default value.
    pub default: Value,
    /// Unit.
    pub unit: String,
    /// Description.
    pub doc: String,
}

/// A method as `list` shows it.
#[derive(Debug, Clone, Serialize)]
pub struct MethodInfo {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: MethodKind,
    /// Seed section.
    pub seed: String,
    /// Summary.
    pub summary: String,
    /// Oracle (receives ground truth)?
    pub oracle: bool,
    /// What its input must carry.
    pub needs: Needs,
    /// Parameters with defaults.
    pub params: Vec<ParamInfo>,
}

/// Listing of the registry (hidden entries only with `all`).
pub fn list(all: bool) -> Vec<MethodInfo> {
    registry()
        .iter()
        .filter(|e| all || !e.hidden)
        .map(|e| {
            let defaults = e.defaults();
            MethodInfo {
                name: e.name.to_string(),
                kind: e.kind,
                seed: e.seed.to_string(),
                summary: e.summary.to_string(),
                oracle: e.needs_ground_truth,
                needs: e.needs,
                params: e
                    .params
                    .iter()
                    .map(|p| ParamInfo {
                        name: p.name.to_string(),
                        default: defaults.get(p.name).cloned().unwrap_or(Value::Null),
                        unit: p.unit.as_str().to_string(),
                        doc: p.doc.to_string(),
                    })
                    .collect(),
            }
        })
        .collect()
}

/// Parses `key=value` overrides (`--set`): the value is read as a TOML value when it
/// parses as one (`8`, `0.5`, `true`, `[1, 2]`, `"x"`), else taken as a bare string.
pub fn parse_overrides(sets: &[String]) -> Result<Value> {
    let mut map = serde_json::Map::new();
    for s in sets {
        let (k, v) = s
            .split_once('=')
            .ok_or_else(|| HarnessError::input(format!("--set '{s}': expected key=value")))?;
        let k = k.trim();
        if k.is_empty() {
            return Err(HarnessError::input(format!("--set '{s}': empty key")));
        }
        let value = toml_scalar(v.trim());
        map.insert(k.to_string(), value);
    }
    Ok(Value::Object(map))
}

fn toml_scalar(text: &str) -> Value {
    let doc = format!("v = {text}");
    match toml::from_str::<toml::Table>(&doc) {
        Ok(t) => t
            .get("v")
            .and_then(|v| serde_json::to_value(v).ok())
            .unwrap_or_else(|| Value::String(text.to_string())),
        Err(_) => Value::String(text.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn names_are_unique_kebab_case_and_documented() {
        let mut seen = std::collections::BTreeSet::new();
        for e in registry() {
            assert!(seen.insert(e.name), "duplicate {}", e.name);
            assert!(
                e.name
                    .chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'),
                "{}",
                e.name
            );
            let defaults = e.defaults();
            let keys: Vec<&String> = defaults
                .as_object()
                .map(|m| m.keys().collect())
                .unwrap_or_default();
            assert_eq!(keys.len(), e.params.len(), "{}: docs vs defaults", e.name);
            for p in e.params {
                assert!(
                    defaults.get(p.name).is_some(),
                    "{}: {} undocumented default",
                    e.name,
                    p.name
                );
            }
        }
    }

    #[test]
    fn every_entry_agrees_with_the_method_it_builds() {
        for e in registry() {
            let built = e
                .build(&e.defaults(), &MethodEnv::default())
                .unwrap_or_else(|err| panic!("{}: defaults do not build: {err}", e.name));
            let (kind, name) = match &built {
                Built::Normals(m) => (MethodKind::Normals, m.name().to_string()),
                Built::Features(m) => (MethodKind::Features, m.name().to_string()),
                Built::Filter(m) => (MethodKind::Filter, m.name().to_string()),
                Built::Reconstruct(m) => (MethodKind::Reconstruct, m.name().to_string()),
            };
            assert_eq!(kind, e.kind, "{}", e.name);
            assert_eq!(
                name, e.name,
                "registered name differs from the method's own"
            );
            assert!(!e.summary.is_empty() && !e.seed.is_empty(), "{}", e.name);
            for p in e.params {
                assert!(!p.doc.is_empty(), "{}.{}: empty doc", e.name, p.name);
            }
        }
    }

    #[test]
    fn angle_parameters_name_their_unit() {
        for e in registry() {
            for p in e.params {
                let named = if p.name.ends_with("_deg") {
                    Some(Unit::Deg)
                } else if p.name.ends_with("_rad") {
                    Some(Unit::Rad)
                } else {
                    None
                };
                if p.unit.is_angle() || named.is_some() {
                    assert_eq!(
                        named,
                        Some(p.unit),
                        "{}.{}: unit {:?}",
                        e.name,
                        p.name,
                        p.unit
                    );
                }
            }
        }
    }

    #[test]
    fn bad_parameters_fail_when_resolved() {
        for (name, key, bad) in [
            ("pf", "k", json!(1)),
            ("jet", "k", json!(2)),
            ("lvm-approx", "k", json!(65)),
            ("gauss-map", "sigma_rad", json!(-1.0)),
            ("priority-front", "threads", json!(0)),
        ] {
            let err = find(name)
                .unwrap()
                .resolve_params(&json!({ key: bad }))
                .unwrap_err()
                .to_string();
            assert!(err.contains(key), "{name}: {err}");
        }
        // Old angle names stay readable.
        let v = find("ufm")
            .unwrap()
            .resolve_params(&json!({"max_fold": 90}))
            .unwrap();
        assert_eq!(v["max_fold_deg"], json!(90.0));
    }

    #[test]
    fn unknown_names_and_keys_list_the_valid_ones() {
        let err = find("nope").unwrap_err().to_string();
        assert!(
            err.contains("gt-normals") && err.contains("reference-mesh"),
            "{err}"
        );
        assert!(!err.contains("debug-panic"), "{err}");
        let e = find("reference-mesh").unwrap();
        let err = e
            .resolve_params(&json!({"resolutoin": 3}))
            .unwrap_err()
            .to_string();
        assert!(err.contains("resolution"), "{err}");
        let ok = e.resolve_params(&json!({"resolution": 12})).unwrap();
        assert_eq!(ok["resolution"], json!(12));
    }

    #[test]
    fn overrides_parse_toml_values() {
        let v = parse_overrides(&[
            "k=8".into(),
            "r=0.5".into(),
            "s=torus:R=1".into(),
            "b=true".into(),
        ])
        .unwrap();
        assert_eq!(v, json!({"k": 8, "r": 0.5, "s": "torus:R=1", "b": true}));
        assert!(parse_overrides(&["novalue".into()]).is_err());
    }
}
