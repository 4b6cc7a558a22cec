//! Flat, stable key/value views of the reports: the JSON the CLI prints and the rows the
//! harness tabulates come from the same list, so their keys cannot drift apart.

use std::collections::BTreeMap;

use serde::Serialize;

/// One reported value.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// A flag (`true`/`false` in JSON; 1/0 in rows).
    Bool(bool),
    /// A count.
    Int(i64),
    /// A real number (NaN and infinities are written as JSON `null`, left out of rows).
    Num(f64),
    /// Text (left out of rows).
    Text(String),
    /// Not computed or undefined (JSON `null`, left out of rows).
    Null,
}

impl Value {
    /// The value as a table cell, if it is numeric.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
            Value::Int(i) => Some(*i as f64),
            Value::Num(x) if x.is_finite() => Some(*x),
            _ => None,
        }
    }
}

impl From<f64> for Value {
    fn from(x: f64) -> Self {
        Value::Num(x)
    }
}
impl From<bool> for Value {
    fn from(b: bool) -> Self {
        Value::Bool(b)
    }
}
impl From<usize> for Value {
    fn from(i: usize) -> Self {
        Value::from(i as u64)
    }
}
impl From<u64> for Value {
    fn from(i: u64) -> Self {
        i64::try_from(i).map_or(Value::Num(i as f64), Value::Int)
    }
}
impl From<u32> for Value {
    fn from(i: u32) -> Self {
        Value::Int(i as i64)
    }
}
impl From<i64> for Value {
    fn from(i: i64) -> Self {
        Value::Int(i)
    }
}
impl From<String> for Value {
    fn from(s: String) -> Self {
        Value::Text(s)
    }
}
impl<T: Into<Value>> From<Option<T>> for Value {
    fn from(o: Option<T>) -> Self {
        o.map_or(Value::Null, Into::into)
    }
}

/// Ordered `(key, value)` pairs of a report.
pub type Entries = Vec<(String, Value)>;

/// Appends `(key, value)`.
pub(crate) fn put(e: &mut Entries, key: impl Into<String>, v: impl Into<Value>) {
    e.push((key.into(), v.into()));
}

/// A report with stable, documented keys (see `docs/METRICS.md`).
pub trait Report {
    /// Every key of the report, in a fixed order.
    fn entries(&self) -> Entries;

    /// The numeric entries as a table row (booleans as 0/1; null, non-finite and text
    /// entries left out).
    fn to_row(&self) -> BTreeMap<String, f64> {
        self.entries()
            .into_iter()
            .filter_map(|(k, v)| v.as_f64().map(|x| (k, x)))
            .collect()
    }

    /// The report as a flat JSON object, keys in [`entries`](Self::entries) order.
    fn to_json(&self) -> serde_json::Value {
        let map: serde_json::Map<String, serde_json::Value> = self
            .entries()
            .into_iter()
            .map(|(k, v)| {
                let j = match v {
                    Value::Bool(b) => serde_json::Value::Bool(b),
                    Value::Int(i) => serde_json::Value::from(i),
                    Value::Num(x) => serde_json::Number::from_f64(x)
                        .map_or(serde_json::Value::Null, serde_json::Value::Number),
                    Value::Text(s) => serde_json::Value::String(s),
                    Value::Null => serde_json::Value::Null,
                };
                (k, j)
            })
            .collect();
        serde_json::Value::Object(map)
    }
}

/// Implements `serde::Serialize` as the flat map of [`Report::entries`].
macro_rules! serialize_as_entries {
    ($t:ty) => {
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                use serde::ser::SerializeMap;
                let e = $crate::report::Report::entries(self);
                let mut m = s.serialize_map(Some(e.len()))?;
                for (k, v) in &e {
                    match v {
                        $crate::report::Value::Num(x) if !x.is_finite() => {
                            m.serialize_entry(k, &Option::<f64>::None)?
                        }
                        _ => m.serialize_entry(k, v)?,
                    }
                }
                m.end()
            }
        }
    };
}
pub(crate) use serialize_as_entries;

/// Merges several reports into one flat list (later keys must not repeat earlier ones).
pub fn merge_entries(parts: &[&dyn Report]) -> Entries {
    parts.iter().flat_map(|p| p.entries()).collect()
}
