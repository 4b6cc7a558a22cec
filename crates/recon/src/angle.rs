//! Angle helpers shared by the reconstructors.

/// The diamond angle of the direction `(c, s)` in `[0, 4)`: monotone in `atan2(s, c)`
/// taken in `[0, 2π)` (0 along `+c`, 1 along `+s`, 2 along `−c`), invariant under
/// positive scaling, and 0 for the zero vector. Orders directions like the true angle
/// without a transcendental call.
#[inline]
pub(crate) fn pseudo_angle(c: f64, s: f64) -> f64 {
    let (ac, as_) = (c.abs(), s.abs());
    let sum = ac + as_;
    if sum == 0.0 {
        return 0.0;
    }
    let t = as_ / sum;
    match (c >= 0.0, s >= 0.0) {
        (true, true) => t,
        (false, true) => 2.0 - t,
        (false, false) => 2.0 + t,
        (true, false) => 4.0 - t,
    }
}
