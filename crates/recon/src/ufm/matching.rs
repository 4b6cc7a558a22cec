//! Matching indices and classes (spec 000 §1.0.4, Table 3.1), umbrella states, and the
//! stop rules of the UFM loop (ASSUMPTION A-07).

use std::collections::VecDeque;

/// Absolute matching index `M_f = #{i : f ∈ U_{v_i}}` of a facet from the membership of
/// its three corners.
pub fn absolute_index(member: [bool; 3]) -> u8 {
    member.iter().map(|&b| b as u8).sum()
}

/// Relative matching index `M_f(v) = (M_f, [f ∈ U_v])` as the removal class used for
/// sorting (first removed first): `(0)→0, (1,0)→1, (1,1)→2, (2,0)→3, (2,1)→4, (3)→5`.
///
/// `m` must be consistent with `member` (`m = 0` implies not a member, `m = 3` implies a
/// member); inconsistent pairs are clamped to the nearest legal class.
pub fn class(m: u8, member: bool) -> u8 {
    match (m, member) {
        (0, _) => 0,
        (1, false) => 1,
        (1, true) => 2,
        (2, false) => 3,
        (2, true) => 4,
        _ => 5,
    }
}

/// The relative index as the thesis writes it: `"(0)"`, `"(1,0)"`, ..., `"(3)"`.
pub fn relative_label(m: u8, member: bool) -> &'static str {
    ["(0)", "(1,0)", "(1,1)", "(2,0)", "(2,1)", "(3)"][class(m, member) as usize]
}

/// State of one umbrella (Fig. 5.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UmbrellaState {
    /// No facet has `M_f = 3`.
    VoidMatched,
    /// Some but not all facets have `M_f = 3`.
    PartiallyMatched,
    /// All facets have `M_f = 3` (grade `G_v = 1`).
    FullyMatched,
}

/// The state of an umbrella from the matching indices of its facets.
pub fn umbrella_state(m_of_facets: impl Iterator<Item = u8>) -> UmbrellaState {
    let (mut any, mut all, mut n) = (false, true, 0usize);
    for m in m_of_facets {
        n += 1;
        any |= m == 3;
        all &= m == 3;
    }
    match (any, all && n > 0) {
        (_, true) => UmbrellaState::FullyMatched,
        (true, false) => UmbrellaState::PartiallyMatched,
        _ => UmbrellaState::VoidMatched,
    }
}

/// Which A-07 stop rule ended the loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopRule {
    /// (i) every umbrella fully matched (μ = 100 %).
    Converged,
    /// (ii) the umbrella set equals the previous iteration's (fixed point).
    FixedPoint,
    /// (ii) the umbrella set equals one of the 2nd to 4th previous iterations (limit
    /// cycle of the synchronous update).
    LimitCycle,
    /// (iii) the best μ has not improved for `patience` iterations.
    Patience,
    /// (iv) `max_iter` iterations done.
    MaxIter,
}

impl StopRule {
    /// Kebab-case name for diagnostics.
    pub fn name(self) -> &'static str {
        match self {
            StopRule::Converged => "converged",
            StopRule::FixedPoint => "fixed-point",
            StopRule::LimitCycle => "limit-cycle",
            StopRule::Patience => "patience",
            StopRule::MaxIter => "max-iter",
        }
    }
}

/// How many previous umbrella sets the limit-cycle test compares with (A-07 (ii)).
pub const CYCLE_MEMORY: usize = 4;

/// The history the A-07 stop rules look at.
#[derive(Debug, Default, Clone)]
pub struct StopHistory {
    /// Matching fraction after each iteration (index = iteration, 0 = initial umbrellas).
    pub trace: Vec<f64>,
    best: f64,
    since_best: usize,
    /// The last [`CYCLE_MEMORY`] umbrella sets, newest first.
    previous: VecDeque<Vec<bool>>,
}

impl StopHistory {
    /// Records μ and the umbrella set of the iteration just finished and returns the
    /// rule that stops the loop, if any (first hit wins, in the spec's order).
    /// `iteration` is the number of update iterations done so far.
    pub fn record(
        &mut self,
        mu: f64,
        state: &[bool],
        iteration: usize,
        patience: usize,
        max_iter: usize,
    ) -> Option<StopRule> {
        self.trace.push(mu);
        if mu >= 1.0 {
            return Some(StopRule::Converged);
        }
        if let Some(k) = self.previous.iter().position(|p| p.as_slice() == state) {
            return Some(if k == 0 {
                StopRule::FixedPoint
            } else {
                StopRule::LimitCycle
            });
        }
        if self.trace.len() == 1 || mu > self.best {
            self.best = mu;
            self.since_best = 0;
        } else {
            self.since_best += 1;
        }
        if self.since_best >= patience {
            return Some(StopRule::Patience);
        }
        if iteration >= max_iter {
            return Some(StopRule::MaxIter);
        }
        if self.previous.len() == CYCLE_MEMORY {
            let mut old = self.previous.pop_back().expect("non-empty");
            old.clear();
            old.extend_from_slice(state);
            self.previous.push_front(old);
        } else {
            self.previous.push_front(state.to_vec());
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table 3.1: every membership pattern of the three corners gives the published
    /// absolute and relative indices.
    #[test]
    fn table_3_1_all_patterns() {
        // (memberships, M_f, relative labels per corner) exactly as in Table 3.1.
        let rows: [([bool; 3], u8, [&str; 3]); 8] = [
            ([true, true, true], 3, ["(3)", "(3)", "(3)"]),
            ([true, true, false], 2, ["(2,1)", "(2,1)", "(2,0)"]),
            ([false, true, true], 2, ["(2,0)", "(2,1)", "(2,1)"]),
            ([true, false, true], 2, ["(2,1)", "(2,0)", "(2,1)"]),
            ([true, false, false], 1, ["(1,1)", "(1,0)", "(1,0)"]),
            ([false, true, false], 1, ["(1,0)", "(1,1)", "(1,0)"]),
            ([false, false, true], 1, ["(1,0)", "(1,0)", "(1,1)"]),
            ([false, false, false], 0, ["(0)", "(0)", "(0)"]),
        ];
        for (mem, m, labels) in rows {
            assert_eq!(absolute_index(mem), m);
            for k in 0..3 {
                assert_eq!(relative_label(m, mem[k]), labels[k], "{mem:?}");
            }
        }
        // Removal order (0), (1,0), (1,1), (2,0), (2,1), (3).
        let seq = [
            (0, false),
            (1, false),
            (1, true),
            (2, false),
            (2, true),
            (3, true),
        ];
        for w in seq.windows(2) {
            assert!(class(w[0].0, w[0].1) < class(w[1].0, w[1].1));
        }
    }

    /// Fig. 4.1 worked example: U_v1 = {f1..f6}, U_v2 = {f6..f9}, U_v3 = {f5, f6, f9,
    /// f10, f11} give M_f6 = 3, M_f5 = M_f9 = 2, all others 1; U(f̄)_v1 = {f6} and
    /// DT(U)_v1 = {f1..f7} (f7 contains v1 and v2 and lies only in U_v2).
    #[test]
    fn fig_4_1_worked_example() {
        // Vertices v1 = 1, v2 = 2, v3 = 3; others >= 10. f[i] = facet f_{i+1}.
        let f: [[u32; 3]; 11] = [
            [1, 10, 11],
            [1, 11, 12],
            [1, 12, 13],
            [1, 13, 14],
            [1, 3, 14],
            [1, 2, 3],
            [1, 2, 15],
            [2, 15, 16],
            [2, 3, 16],
            [3, 16, 17],
            [3, 14, 17],
        ];
        let umbrella = |w: u32| -> &'static [usize] {
            match w {
                1 => &[0, 1, 2, 3, 4, 5],
                2 => &[5, 6, 7, 8],
                3 => &[4, 5, 8, 9, 10],
                _ => &[],
            }
        };
        let m: Vec<u8> = (0..11)
            .map(|i| absolute_index(f[i].map(|w| umbrella(w).contains(&i))))
            .collect();
        assert_eq!(m, vec![1, 1, 1, 1, 2, 3, 1, 1, 2, 1, 1]);
        let ubar: Vec<usize> = umbrella(1).iter().copied().filter(|&i| m[i] == 3).collect();
        assert_eq!(ubar, vec![5]);
        let dt_u: Vec<usize> = (0..11)
            .filter(|&i| f[i].contains(&1) && m[i] >= 1)
            .collect();
        assert_eq!(dt_u, (0..7).collect::<Vec<_>>());
        // v1 sees f7 as (1,0), f5 as (2,1), f6 as (3).
        assert_eq!(relative_label(m[6], umbrella(1).contains(&6)), "(1,0)");
        assert_eq!(relative_label(m[4], true), "(2,1)");
        assert_eq!(relative_label(m[5], true), "(3)");
    }

    #[test]
    fn umbrella_states() {
        assert_eq!(
            umbrella_state([3, 3, 3].into_iter()),
            UmbrellaState::FullyMatched
        );
        assert_eq!(
            umbrella_state([3, 1, 3].into_iter()),
            UmbrellaState::PartiallyMatched
        );
        assert_eq!(
            umbrella_state([2, 1, 1].into_iter()),
            UmbrellaState::VoidMatched
        );
        assert_eq!(
            umbrella_state(std::iter::empty()),
            UmbrellaState::VoidMatched
        );
    }

    #[test]
    fn stop_rules_fire_in_order() {
        let mut h = StopHistory::default();
        let a = vec![true, false];
        let b = vec![false, true];
        assert_eq!(h.record(0.5, &a, 0, 20, 200), None);
        assert_eq!(h.record(0.6, &b, 1, 20, 200), None);
        // Back to a: limit cycle of length 2.
        assert_eq!(h.record(0.5, &a, 2, 20, 200), Some(StopRule::LimitCycle));
        let mut h = StopHistory::default();
        assert_eq!(h.record(0.5, &a, 0, 20, 200), None);
        assert_eq!(h.record(0.5, &a, 1, 20, 200), Some(StopRule::FixedPoint));
        let mut h = StopHistory::default();
        assert_eq!(h.record(1.0, &a, 0, 20, 200), Some(StopRule::Converged));
        // Patience: no gain for 2 iterations (distinct states).
        let mut h = StopHistory::default();
        let s = |i: usize| (0..8).map(|j| j == i).collect::<Vec<bool>>();
        assert_eq!(h.record(0.5, &s(0), 0, 2, 200), None);
        assert_eq!(h.record(0.4, &s(1), 1, 2, 200), None);
        assert_eq!(h.record(0.5, &s(2), 2, 2, 200), Some(StopRule::Patience));
        // Max iterations.
        let mut h = StopHistory::default();
        assert_eq!(h.record(0.5, &s(0), 0, 20, 1), None);
        assert_eq!(h.record(0.6, &s(1), 1, 20, 1), Some(StopRule::MaxIter));
        assert_eq!(h.trace, vec![0.5, 0.6]);
    }
}
