//! The short string form of specs: `name` or `name:key=value,key=value`.
//!
//! Used by shapes (`torus:R=0.5,r=0.2`), samplers (`blue-noise:oversample=5`),
//! perturbations (`gaussian:sigma=0.005,rel=diagonal`) and scans
//! (`views=8,res=128`). Keys are case-sensitive (`R` and `r` differ for the torus).

use std::collections::BTreeMap;

use crate::error::{Result, SynthError};

/// A parsed `name:key=value,...` string; values are kept as text.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KvSpec {
    /// The name before the colon (may be empty for pure key lists).
    pub name: String,
    /// Key/value pairs in input order.
    pub params: Vec<(String, String)>,
}

/// Parses `name[:k=v,k=v]` (white space around tokens is ignored). With `name_required`
/// false, a string without a colon whose first token contains `=` is a pure key list.
pub fn parse_kv(what: &'static str, input: &str, name_required: bool) -> Result<KvSpec> {
    let err = |m: String| SynthError::Parse {
        what,
        input: input.to_string(),
        message: m,
    };
    let s = input.trim();
    let (name, rest) = match s.split_once(':') {
        Some((n, r)) => (n.trim().to_string(), r),
        None if !name_required && s.contains('=') => (String::new(), s),
        None => (s.to_string(), ""),
    };
    if name_required && name.is_empty() {
        return Err(err("missing name".into()));
    }
    let mut params = Vec::new();
    for tok in rest.split(',').map(str::trim).filter(|t| !t.is_empty()) {
        let (k, v) = tok
            .split_once('=')
            .ok_or_else(|| err(format!("'{tok}' is not key=value")))?;
        let (k, v) = (k.trim(), v.trim());
        if k.is_empty() || v.is_empty() {
            return Err(err(format!("'{tok}' has an empty key or value")));
        }
        if params.iter().any(|(pk, _)| pk == k) {
            return Err(err(format!("key '{k}' given twice")));
        }
        params.push((k.to_string(), v.to_string()));
    }
    Ok(KvSpec { name, params })
}

/// Parses a number, naming the owner and key on failure.
pub fn parse_f64(owner: &str, key: &str, v: &str) -> Result<f64> {
    let x: f64 = v
        .parse()
        .map_err(|_| SynthError::invalid(owner, key, format!("'{v}' is not a number")))?;
    if !x.is_finite() {
        return Err(SynthError::invalid(
            owner,
            key,
            format!("'{v}' is not finite"),
        ));
    }
    Ok(x)
}

/// Parses a non-negative integer.
pub fn parse_usize(owner: &str, key: &str, v: &str) -> Result<usize> {
    v.parse().map_err(|_| {
        SynthError::invalid(owner, key, format!("'{v}' is not a non-negative integer"))
    })
}

/// Formats a float so that it parses back to the same value (shortest round trip).
pub fn fmt_f64(x: f64) -> String {
    format!("{x}")
}

/// Formats `name:k=v,...` (just `name` without parameters).
pub fn format_kv<'a>(name: &str, params: impl IntoIterator<Item = (&'a str, String)>) -> String {
    let body: Vec<String> = params
        .into_iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    if body.is_empty() {
        name.to_string()
    } else if name.is_empty() {
        body.join(",")
    } else {
        format!("{name}:{}", body.join(","))
    }
}

/// Parameter table of one item: names with defaults; fills a map from a spec and rejects
/// unknown keys with the list of valid ones.
pub fn resolve_params(
    owner: &str,
    defaults: &[(&str, f64)],
    given: &BTreeMap<String, f64>,
) -> Result<BTreeMap<String, f64>> {
    let mut out: BTreeMap<String, f64> =
        defaults.iter().map(|&(k, v)| (k.to_string(), v)).collect();
    for (k, &v) in given {
        if !out.contains_key(k) {
            return Err(SynthError::UnknownParameter {
                owner: owner.to_string(),
                name: k.clone(),
                valid: list_defaults(defaults),
            });
        }
        if !v.is_finite() {
            return Err(SynthError::invalid(owner, k, format!("{v} is not finite")));
        }
        out.insert(k.clone(), v);
    }
    Ok(out)
}

/// `k=default, ...` or `(none)`.
pub fn list_defaults(defaults: &[(&str, f64)]) -> String {
    if defaults.is_empty() {
        "(none)".to_string()
    } else {
        defaults
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_names_and_pairs() {
        let s = parse_kv("shape", " torus : R=0.5, r=0.2 ", true).unwrap();
        assert_eq!(s.name, "torus");
        assert_eq!(
            s.params,
            vec![("R".into(), "0.5".into()), ("r".into(), "0.2".into())]
        );
        assert_eq!(parse_kv("shape", "sphere", true).unwrap().params, vec![]);
        assert!(parse_kv("shape", "torus:R", true).is_err());
        assert!(parse_kv("shape", "torus:R=1,R=2", true).is_err());
        let s = parse_kv("scan", "views=8,res=64", false).unwrap();
        assert_eq!(s.name, "");
        assert_eq!(s.params.len(), 2);
        assert_eq!(fmt_f64(0.1), "0.1");
        assert_eq!(format_kv("t", [("a", "1".to_string())]), "t:a=1");
    }
}
