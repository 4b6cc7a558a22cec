//! Stage 2 of EBT (paper §4.2-4.3, Appendix A): the maximum edge length Omega from the
//! tolerance and the curvature term, and the voxel bin size B from Omega.

use super::params::{BinRule, OmegaRule};

/// Omega for tolerance `eps` and curvature term `m_sum = M1 + 2 M2 + M3`; infinite when
/// `m_sum` is 0 (a plane: any edge interpolates it exactly).
pub fn omega(eps: f64, m_sum: f64, rule: OmegaRule) -> f64 {
    if m_sum.is_nan() || m_sum <= 0.0 {
        return f64::INFINITY;
    }
    match rule {
        // ASSUMPTION E7 (default): Eq. 13, from the sharpened bound (1/8) Omega^2 M.
        OmegaRule::Eq13 => 2.0 * (2.0 * eps / m_sum).sqrt(),
        // Eq. 11, from the cited bound (2/9) Omega^2 M.
        OmegaRule::Eq11 => 3.0 * (eps / (2.0 * m_sum)).sqrt(),
    }
}

/// The deviation bound of the rule's inequality (Eq. 12 or Eq. 7) for edge `omega`.
pub fn bound(omega: f64, m_sum: f64, rule: OmegaRule) -> f64 {
    match rule {
        OmegaRule::Eq13 => omega * omega * m_sum / 8.0,
        OmegaRule::Eq11 => 2.0 * omega * omega * m_sum / 9.0,
    }
}

/// Ratio Omega / B of a bin rule.
pub fn ratio(rule: BinRule) -> f64 {
    match rule {
        // ASSUMPTION E8 (default): Eq. 1, B = Omega / sqrt 2 (edge-adjacent bins); with
        // Eq. 13 this is exactly the printed B = 2 sqrt(eps / M), and Table 1's ratio.
        BinRule::Eq1 => std::f64::consts::SQRT_2,
        // Eq. 16, B = Omega / sqrt 3: corner-adjacent kept points stay within Omega.
        BinRule::Eq16 => 3f64.sqrt(),
    }
}

/// B from Omega.
pub fn bin_from_omega(omega: f64, rule: BinRule) -> f64 {
    omega / ratio(rule)
}

/// Omega from a forced B (the inverse of [`bin_from_omega`]).
pub fn omega_from_bin(b: f64, rule: BinRule) -> f64 {
    b * ratio(rule)
}
