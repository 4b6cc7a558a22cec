//! What a registered method is: its kind, documented parameters, input needs and a
//! constructor from JSON parameters, plus the ground truth only oracles receive. Built
//! from a method's own [`Describe`] impl ([`normals`], [`features`], [`filter`],
//! [`reconstruct`]) or, for oracles and test-only methods, from a closure ([`custom`]).
//! The list of registered methods is [`mod@crate::registry`].

use std::sync::Arc;

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
