//! Unorganized point clouds with optional per-point attributes.

use std::collections::BTreeMap;

use glam::DVec3;

use crate::aabb::Aabb;
use crate::error::{GeomError, Result, check_finite, check_len};

/// A named per-point attribute: a real-valued scalar (curvature, feature distance, ...) or
/// an integer label (feature class, scan id, outlier flag, ...).
#[derive(Debug, Clone, PartialEq)]
pub enum Channel {
    /// Real values, written as PLY `double` (or the type they were read with, as f64).
    Scalar(Vec<f64>),
    /// Integer values, written as PLY `int`.
    Label(Vec<i64>),
}

impl Channel {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Channel::Scalar(v) => v.len(),
            Channel::Label(v) => v.len(),
        }
    }

    /// True when there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` as f64, whatever the channel kind.
    pub fn get_f64(&self, i: usize) -> f64 {
        match self {
            Channel::Scalar(v) => v[i],
            Channel::Label(v) => v[i] as f64,
        }
    }

    /// Keeps the values at `indices`, in that order.
    fn select(&self, indices: &[usize]) -> Channel {
        match self {
            Channel::Scalar(v) => Channel::Scalar(indices.iter().map(|&i| v[i]).collect()),
            Channel::Label(v) => Channel::Label(indices.iter().map(|&i| v[i]).collect()),
        }
    }
}

/// An unorganized point cloud.
///
/// Positions are always finite (checked on construction). Optional attributes, when
/// present, have exactly one value per point. `source_ids` link each point to the clean
/// ground-truth sample it was generated from (kept through perturbations and decimation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    positions: Vec<DVec3>,
    normals: Option<Vec<DVec3>>,
    colors: Option<Vec<[u8; 3]>>,
    source_ids: Option<Vec<u32>>,
    channels: BTreeMap<String, Channel>,
}

impl PointCloud {
    /// A cloud of `positions`; fails on the first NaN or infinite coordinate.
    pub fn new(positions: Vec<DVec3>) -> Result<Self> {
        check_finite("point", &positions)?;
        Ok(Self {
            positions,
            ..Self::default()
        })
    }

    /// Attaches normals (one per point, finite; not required to be unit length).
    pub fn with_normals(mut self, normals: Vec<DVec3>) -> Result<Self> {
        self.set_normals(Some(normals))?;
        Ok(self)
    }

    /// Replaces (or removes, with `None`) the normals.
    pub fn set_normals(&mut self, normals: Option<Vec<DVec3>>) -> Result<()> {
        if let Some(n) = &normals {
            check_len("normals", n.len(), self.len(), "point")?;
            check_finite("normal", n)?;
        }
        self.normals = normals;
        Ok(())
    }

    /// Replaces (or removes) the RGB colours.
    pub fn set_colors(&mut self, colors: Option<Vec<[u8; 3]>>) -> Result<()> {
        if let Some(c) = &colors {
            check_len("colors", c.len(), self.len(), "point")?;
        }
        self.colors = colors;
        Ok(())
    }

    /// Replaces (or removes) the source ids.
    pub fn set_source_ids(&mut self, ids: Option<Vec<u32>>) -> Result<()> {
        if let Some(s) = &ids {
            check_len("source ids", s.len(), self.len(), "point")?;
        }
        self.source_ids = ids;
        Ok(())
    }

    /// Adds or replaces the channel `name`. Names are PLY property names, so they must be
    /// non-empty and contain no white space.
    pub fn set_channel(&mut self, name: impl Into<String>, channel: Channel) -> Result<()> {
        let name = name.into();
        if name.is_empty() || name.chars().any(char::is_whitespace) {
            return Err(GeomError::InvalidParameter {
                name: "channel name",
                message: format!("'{name}' must be non-empty and contain no white space"),
            });
        }
        check_len(
            format!("channel '{name}'"),
            channel.len(),
            self.len(),
            "point",
        )?;
        if let Channel::Scalar(v) = &channel
            && let Some(i) = v.iter().position(|x| !x.is_finite())
        {
            return Err(GeomError::InvalidInput(format!(
                "channel '{name}' value {i} is not finite ({})",
                v[i]
            )));
        }
        self.channels.insert(name, channel);
        Ok(())
    }

    /// Removes a channel, returning it.
    pub fn remove_channel(&mut self, name: &str) -> Option<Channel> {
        self.channels.remove(name)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Point positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Normals, if any.
    pub fn normals(&self) -> Option<&[DVec3]> {
        self.normals.as_deref()
    }

    /// RGB colours, if any.
    pub fn colors(&self) -> Option<&[[u8; 3]]> {
        self.colors.as_deref()
    }

    /// Source ids, if any.
    pub fn source_ids(&self) -> Option<&[u32]> {
        self.source_ids.as_deref()
    }

    /// A named channel.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.get(name)
    }

    /// All channels, sorted by name.
    pub fn channels(&self) -> &BTreeMap<String, Channel> {
        &self.channels
    }

    /// Bounding box of the positions.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }

    /// Keeps the points at `indices` (in that order, repeats allowed) with all their
    /// attributes. Fails if an index is out of range.
    pub fn select(&self, indices: &[usize]) -> Result<Self> {
        if let Some(&bad) = indices.iter().find(|&&i| i >= self.len()) {
            return Err(GeomError::InvalidInput(format!(
                "selection index {bad} out of range for a cloud of {} points",
                self.len()
            )));
        }
        Ok(Self {
            positions: indices.iter().map(|&i| self.positions[i]).collect(),
            normals: self
                .normals
                .as_ref()
                .map(|n| indices.iter().map(|&i| n[i]).collect()),
            colors: self
                .colors
                .as_ref()
                .map(|c| indices.iter().map(|&i| c[i]).collect()),
            source_ids: self
                .source_ids
                .as_ref()
                .map(|s| indices.iter().map(|&i| s[i]).collect()),
            channels: self
                .channels
                .iter()
                .map(|(k, c)| (k.clone(), c.select(indices)))
                .collect(),
        })
    }

    /// Replaces the positions keeping every attribute (e.g. after adding noise).
    pub fn with_positions(mut self, positions: Vec<DVec3>) -> Result<Self> {
        check_len("positions", positions.len(), self.len(), "point")?;
        check_finite("point", &positions)?;
        self.positions = positions;
        Ok(self)
    }

    /// This cloud moved exactly to the working scale and the exponent `s` it was
    /// multiplied by (`2^s`), or `None` when it is already there (no copy): see
    /// [`working_scale_exponent`]. Normals, colours, ids and channels are kept (normals
    /// and labels are scale-free; callers map lengths back with `2^-s`).
    pub fn at_working_scale(&self) -> Option<(PointCloud, i32)> {
        let s = working_scale_exponent(&self.positions)?;
        let mut scaled = self.clone();
        scaled.positions = scale_pow2(&self.positions, s);
        Some((scaled, s))
    }
}

/// Floating-point methods run unscaled while the largest |coordinate| lies in
/// `[2^-WORKING_SCALE_BITS, 2^WORKING_SCALE_BITS]`: products of up to 8 coordinate
/// differences (squared distances, covariances, cross products, circumradii) then neither
/// overflow nor fall into the subnormal range for any spacing above `2^-50` of the
/// extent.
pub const WORKING_SCALE_BITS: i32 = 64;

/// True when all points lie on one line (or coincide), tested exactly in floating point
/// on the cross products (a non-zero cross product proves non-collinearity): only then
/// may a method return no faces or only zero-length normals on distinct points.
pub fn all_collinear(points: &[DVec3]) -> bool {
    let Some(&a) = points.first() else {
        return true;
    };
    let Some(&b) = points.iter().find(|&&p| p != a) else {
        return true;
    };
    points.iter().all(|&p| (b - a).cross(p - a) == DVec3::ZERO)
}

/// The power-of-two exponent `s` that brings the largest |coordinate| of `positions`
/// into `[1/2, 1)`, or `None` when it is already within `2^±WORKING_SCALE_BITS` (or
/// every coordinate is zero). Multiplying by `2^s` is exact unless coordinates more
/// than about 2^1000 times smaller than the largest drop below the subnormal grid
/// (then they lose low bits, a relative error below the cloud's own precision), and it
/// leaves every fraction of the bounding-box diagonal, every angle and every normal
/// unchanged: methods whose parameters are such fractions give the same result.
pub fn working_scale_exponent(positions: &[DVec3]) -> Option<i32> {
    working_scale_exponent_within(positions, WORKING_SCALE_BITS)
}

/// [`working_scale_exponent`] with its own range `2^±bits` (`bits` in `0..=64`): a
/// method with narrower arithmetic (an `f32` stage, say) moves every cloud whose largest
/// |coordinate| lies outside `[2^-bits, 2^bits]` into `[1/2, 1)`.
pub fn working_scale_exponent_within(positions: &[DVec3], bits: i32) -> Option<i32> {
    let bits = bits.clamp(0, WORKING_SCALE_BITS);
    let m = positions
        .iter()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let lim = 2f64.powi(bits);
    if m == 0.0 || (m >= 1.0 / lim && m <= lim) {
        return None;
    }
    let lim = 2f64.powi(WORKING_SCALE_BITS);
    // frexp: m = f · 2^e with f in [1/2, 1); subnormals are first lifted by 2^64.
    let (m, lift) = if m < f64::MIN_POSITIVE {
        (m * lim, WORKING_SCALE_BITS)
    } else {
        (m, 0)
    };
    let e = ((m.to_bits() >> 52) & 0x7ff) as i32 - 1022 - lift;
    Some(-e)
}

/// `positions` multiplied by `2^s` in two steps of at most `2^±1023` each (exact while
/// the results stay above the subnormal grid and below overflow).
pub fn scale_pow2(positions: &[DVec3], s: i32) -> Vec<DVec3> {
    let pow2 = |e: i32| f64::from_bits(((1023 + e.clamp(-1022, 1023)) as u64) << 52);
    let h = s / 2;
    let (f1, f2) = (pow2(h), pow2(s - h));
    positions.iter().map(|&p| p * f1 * f2).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn working_scale_is_an_exact_power_of_two_move() {
        let unit = vec![DVec3::new(0.3, -0.9, 0.1), DVec3::new(1e-20, 0.5, 0.0)];
        assert_eq!(working_scale_exponent(&unit), None);
        assert_eq!(working_scale_exponent(&[DVec3::ZERO]), None);
        let tiny = f64::from_bits(1);
        for f in [1e-300, 1e-160, 1e-60, 1e80, 1e200, 1e300, tiny * 3e6] {
            let pts: Vec<DVec3> = unit.iter().map(|&p| p * f).collect();
            let s = working_scale_exponent(&pts).expect("outside the working range");
            let q = scale_pow2(&pts, s);
            let m = q.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
            assert!((0.5..1.0).contains(&m), "{f:e}: max {m}");
            // The largest coordinates come back bit for bit.
            assert_eq!(scale_pow2(&q, -s)[0].y, pts[0].y, "{f:e}");
            let cloud = PointCloud::new(pts.clone()).unwrap();
            let (c, s2) = cloud.at_working_scale().unwrap();
            assert_eq!((c.positions(), s2), (&q[..], s));
        }
    }

    #[test]
    fn a_narrower_working_range_moves_more_clouds() {
        let pts = |f: f64| vec![DVec3::new(0.75 * f, -0.1 * f, 0.0)];
        assert_eq!(working_scale_exponent_within(&pts(1.0), 32), None);
        assert_eq!(working_scale_exponent_within(&pts(2f64.powi(31)), 32), None);
        // 0.75 * 2^40 lies outside 2^32: moved into [1/2, 1) by 2^-40.
        assert_eq!(
            working_scale_exponent_within(&pts(2f64.powi(40)), 32),
            Some(-40)
        );
        assert_eq!(working_scale_exponent(&pts(2f64.powi(40))), None);
        assert_eq!(
            working_scale_exponent_within(&pts(2f64.powi(-40)), 32),
            Some(40)
        );
        // 0 bits: everything outside [1, 1] moves, and the range never exceeds 2^±64.
        assert_eq!(working_scale_exponent_within(&pts(1.0), 0), Some(0));
        assert_eq!(
            working_scale_exponent_within(&pts(2f64.powi(70)), 99),
            working_scale_exponent(&pts(2f64.powi(70)))
        );
    }

    #[test]
    fn nan_position_is_rejected_with_its_index() {
        let err = PointCloud::new(vec![DVec3::ZERO, DVec3::new(0.0, f64::NAN, 0.0)]).unwrap_err();
        assert!(
            matches!(err, GeomError::NonFinite { index: 1, .. }),
            "{err}"
        );
    }

    #[test]
    fn attribute_lengths_are_checked() {
        let c = PointCloud::new(vec![DVec3::ZERO; 3]).unwrap();
        assert!(c.clone().with_normals(vec![DVec3::Z; 2]).is_err());
        let mut c = c;
        assert!(
            c.set_channel("bad name", Channel::Label(vec![0; 3]))
                .is_err()
        );
        assert!(c.set_channel("ok", Channel::Label(vec![0; 2])).is_err());
        assert!(
            c.set_channel("ok", Channel::Scalar(vec![0.0, f64::NAN, 1.0]))
                .is_err()
        );
        c.set_channel("ok", Channel::Label(vec![1, 2, 3])).unwrap();
        assert_eq!(c.channel("ok").unwrap().get_f64(2), 3.0);
    }

    #[test]
    fn select_keeps_attributes_aligned() {
        let mut c = PointCloud::new((0..4).map(|i| DVec3::splat(i as f64)).collect())
            .unwrap()
            .with_normals(vec![DVec3::X, DVec3::Y, DVec3::Z, -DVec3::X])
            .unwrap();
        c.set_source_ids(Some(vec![10, 11, 12, 13])).unwrap();
        c.set_channel("s", Channel::Scalar(vec![0.5, 1.5, 2.5, 3.5]))
            .unwrap();
        let s = c.select(&[3, 1]).unwrap();
        assert_eq!(s.positions(), &[DVec3::splat(3.0), DVec3::splat(1.0)]);
        assert_eq!(s.normals().unwrap(), &[-DVec3::X, DVec3::Y]);
        assert_eq!(s.source_ids().unwrap(), &[13, 11]);
        assert_eq!(s.channel("s"), Some(&Channel::Scalar(vec![3.5, 1.5])));
        assert!(c.select(&[4]).is_err());
    }
}
