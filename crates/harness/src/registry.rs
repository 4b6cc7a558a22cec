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

use std::sync::OnceLock;

use serde::Serialize;
use serde_json::Value;

pub use crate::entry::{
    Built, GroundTruth, MakeCustom, MethodEntry, MethodEnv, MethodKind, Needs, ParamDoc, Unit,
    custom, features, filter, normals, parse_params, reconstruct,
};
use crate::error::{HarnessError, Result};

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
    // External programs (a command template per experiment entry).
    v.extend(crate::methods::external::entries());
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
            // External methods have no default command: they are built with a trivial one.
            let params = if e.name.starts_with("external") {
                serde_json::json!({ "command": "true" })
            } else {
                e.defaults()
            };
            let built = e
                .build(&params, &MethodEnv::default())
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
