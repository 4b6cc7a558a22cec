//! The UFM loop (spec 000 §1.1.4–1.1.5): per-triangle attributes, initial umbrellas,
//! synchronous (or Gauss–Seidel) updates by facet matching, stop rules.
//!
//! State layout: the Delaunay triangles around every vertex are kept as one CSR array
//! (`off`, `items`, items increasing per vertex); umbrella membership is one `bool` per
//! CSR slot (`inu`), so each vertex writes only its own slot range and the parallel
//! update is deterministic. `slot[f]` gives the three slots of facet `f` (in the order
//! of its sorted vertex triple), so `M_f` is the sum of three flags.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::method::{MethodError, RunCtx};

pub use super::complex::{Complex, circum_diameter};
use super::complex::{LEVEL_SHIFT, RANK_SHIFT, blocks};
use super::matching::{StopHistory, StopRule, absolute_index, class};
use super::nvc::{NvcCfg, NvcStats, nvc_flags};
use super::params::{Init, NvcLevel, NvcStart, UfmParams, Update};
use super::umbrella::LinkGraph;

/// Counters of one run (summed over vertices and iterations).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Vertices whose Gabriel cluster held no umbrella (Step 2.4 fallback to `DT_v`).
    pub init_fallbacks: u64,
    /// Rebuilds repeated without locks because the locked result was invalid.
    pub lock_fallbacks: u64,
    /// Pocket removals skipped because their cascade would orphan a locked facet.
    pub skipped_cascades: u64,
    /// Disjoint cycles dropped by the A-05 rule.
    pub dropped_cycles: u64,
    /// Builds that failed even on all of `DT_v` without locks (expected 0; the vertex
    /// keeps its previous umbrella).
    pub build_failures: u64,
    /// Fold repairs: rebuilds after demoting the most folded facet (deviation,
    /// `max_fold`).
    pub fold_repairs: u64,
}

impl std::ops::Add for Counters {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            init_fallbacks: self.init_fallbacks + o.init_fallbacks,
            lock_fallbacks: self.lock_fallbacks + o.lock_fallbacks,
            skipped_cascades: self.skipped_cascades + o.skipped_cascades,
            dropped_cycles: self.dropped_cycles + o.dropped_cycles,
            build_failures: self.build_failures + o.build_failures,
            fold_repairs: self.fold_repairs + o.fold_repairs,
        }
    }
}

/// Per-thread scratch of a vertex rebuild.
#[derive(Debug, Default, Clone)]
pub struct Scratch {
    /// The link graph.
    pub g: LinkGraph,
    keys: Vec<u64>,
    order: Vec<u32>,
    sub: Vec<u32>,
    // Fold repair buffers.
    cyc: Vec<u32>,
    ring: Vec<u32>,
    ang: Vec<f64>,
    demoted: Vec<u32>,
    order2: Vec<u32>,
}

/// Most fold repairs per rebuild.
const MAX_FOLD_REPAIRS: usize = 3;

/// The local facet of the current umbrella (`s.g.alive`) to demote because the
/// umbrella folds back by more than `bound` radians at one of its ribs: the facet with
/// the largest sum of over-bound fold angles at its two ribs, skipping facets already
/// demoted; ties (the two facets of a single fold) go to the facet that comes first in
/// the removal `order` (worse class, then larger), so the choice does not depend on
/// vertex or facet numbering. `None` when the umbrella does not fold.
fn most_folded(s: &mut Scratch, pts: &[DVec3], v: u32, bound: f64, order: &[u32]) -> Option<u32> {
    let Scratch {
        g,
        cyc,
        ring,
        ang,
        demoted,
        ..
    } = s;
    g.cycle(|i| g.alive[i], cyc, ring);
    super::geometry::fold_angles(pts, v, ring, ang);
    let k = cyc.len();
    if k == 0 || ang.iter().all(|&a| a <= bound) {
        return None;
    }
    let pos = |f: u32| order.iter().position(|&x| x == f).unwrap_or(usize::MAX);
    // ang[j] is at the rib between facets j and j + 1.
    let over = |a: f64| if a > bound { a } else { 0.0 };
    (0..k)
        .filter(|&j| !demoted.contains(&cyc[j]))
        .map(|j| (over(ang[(j + k - 1) % k]) + over(ang[j]), cyc[j]))
        .filter(|&(sc, _)| sc > 0.0)
        .max_by(|a, b| a.0.total_cmp(&b.0).then(pos(b.1).cmp(&pos(a.1))))
        .map(|(_, f)| f)
}

/// BuildUmbrella with the optional lock (and the line-12 fallback without it), then
/// the fold repair when `bound > 0`: while the umbrella folds back, its most folded
/// facet is moved to the front of the queue and unlocked, and the cluster rebuilt.
fn build_checked(
    s: &mut Scratch,
    pts: &[DVec3],
    v: u32,
    locked: Option<&(dyn Fn(usize) -> bool + '_)>,
    bound: f64,
    c: &mut Counters,
) -> Result<super::umbrella::BuildInfo, super::umbrella::BuildFail> {
    let order = std::mem::take(&mut s.order);
    let mut res = s.g.build(|_| true, &order, locked);
    if res.is_err() && locked.is_some() {
        // Line 12: rebuild once without protection.
        c.lock_fallbacks += 1;
        res = s.g.build(|_| true, &order, None);
    }
    s.demoted.clear();
    if bound > 0.0 && res.is_ok() {
        for _ in 0..MAX_FOLD_REPAIRS {
            let Some(f) = most_folded(s, pts, v, bound, &order) else {
                break;
            };
            s.demoted.push(f);
            c.fold_repairs += 1;
            let Scratch {
                g, demoted, order2, ..
            } = &mut *s;
            order2.clear();
            order2.extend_from_slice(demoted);
            order2.extend(order.iter().filter(|x| !demoted.contains(x)));
            let lk = |i: usize| locked.is_some_and(|l| l(i)) && !demoted.contains(&(i as u32));
            let mut r = g.build(
                |_| true,
                order2,
                locked.map(|_| &lk as &dyn Fn(usize) -> bool),
            );
            if r.is_err() && locked.is_some() {
                c.lock_fallbacks += 1;
                r = g.build(|_| true, order2, None);
            }
            if r.is_err() {
                // Keep the last valid umbrella (rebuild it).
                res = g.build(|_| true, &order, None);
                break;
            }
            res = r;
        }
    }
    s.order = order;
    res
}

/// Which queue a rebuild uses.
enum Mode<'a> {
    /// Step 2: initial umbrella.
    Init {
        start: Init,
        /// Fold bound in radians (0 = no fold repair).
        fold: f64,
    },
    /// Step 3: update from the current state.
    Update {
        m: &'a [u8],
        inu: &'a [bool],
        lock: bool,
        /// Stagnation escape (non-faithful extension): ignore the membership bit, so
        /// the middle level collapses and ties of `M_f` go to the global size order.
        ignore_member: bool,
        /// Fold bound in radians (0 = no fold repair).
        fold: f64,
        /// Algorithm C: the `NVC_v` flags (one per CSR slot), `None` = chapter 3's key.
        nvc: Option<&'a [bool]>,
        /// Where NVC membership sits in the key (`nvc_level`).
        nvc_level: NvcLevel,
    },
}

/// Sorts the local facets of `DT_v` by `key(i)` into `s.order`.
fn sort_order(s: &mut Scratch, n: usize, key: impl Fn(usize) -> u64) {
    s.keys.clear();
    s.keys.extend((0..n).map(|i| key(i) | i as u64));
    s.keys.sort_unstable();
    s.order.clear();
    s.order.extend(
        s.keys
            .iter()
            .map(|&k| (k & ((1u64 << RANK_SHIFT) - 1)) as u32),
    );
}

/// Removal level of a triangle in the update key (first removed first). Without NVC
/// filtering (`nvc = None`) it is the Table 3.1 class `class(m, member)` (0..=5).
/// With NVC filtering (Algorithm C, Fig. 5.5's four-level inheritance) the top level
/// is the tier: ASSUMPTION C-05: tier 0 = unmatched and not in `NVC_v` (removed
/// first), tier 1 = unmatched and in `NVC_v` (kept preferentially), tier 2 = matched
/// (`M_f = 3`, kept last as in chapter 3, so NVC never outranks a matched facet);
/// inside a tier the class, then size. Encoded as `5 · tier + class` (0..=10).
/// `level = BelowClass` (ablation, `nvc_level = below-class`): NVC membership only
/// ranks inside a class, between the class and the size (`2 · class + [t ∈ NVC_v]`).
pub fn update_level(m: u8, member: bool, nvc: Option<bool>, level: NvcLevel) -> u8 {
    let cl = class(m, member);
    match (nvc, level) {
        (None, _) => cl,
        (Some(_), _) if m >= 3 => 10,
        (Some(x), NvcLevel::Top) => 5 * x as u8 + cl,
        (Some(x), NvcLevel::BelowClass) => 2 * cl + x as u8,
    }
}

/// Rebuilds the umbrella of `v` into `out` (one flag per local facet of `DT_v`).
fn rebuild_vertex(
    cx: &Complex,
    v: usize,
    s: &mut Scratch,
    mode: &Mode,
    out: &mut [bool],
) -> Counters {
    let mut c = Counters::default();
    let row = cx.row(v);
    let base = cx.off[v] as usize;
    let n = row.len();
    let pts = cx.dt.vertices();
    match *mode {
        Mode::Init { start, fold } => {
            // Step 2.1 / 2.3: start from GT_v. The link graph is built over GT_v only
            // (the same graph as DT_v restricted to C, without the isolated rest).
            if start == Init::Gabriel {
                s.sub.clear();
                s.sub
                    .extend((0..n as u32).filter(|&i| cx.gabriel[row[i as usize] as usize]));
                let facets = cx.facets();
                let sub = std::mem::take(&mut s.sub);
                s.g.prepare(
                    v as u32,
                    sub.iter().map(|&i| facets[row[i as usize] as usize].v),
                );
                // Step 2.2: key (-diam, id), largest first.
                sort_order(s, sub.len(), |j| {
                    (cx.rank_init[row[sub[j] as usize] as usize] as u64) << RANK_SHIFT
                });
                let res = build_checked(s, pts, v as u32, None, fold, &mut c);
                if let Ok(i) = res {
                    c.dropped_cycles += i.dropped_cycles as u64;
                    out.fill(false);
                    for (j, &i) in sub.iter().enumerate() {
                        out[i as usize] = s.g.alive[j];
                    }
                    s.sub = sub;
                    return c;
                }
                s.sub = sub;
                // Step 2.4: fall back to all Delaunay triangles.
                c.init_fallbacks += 1;
            }
            cx.prepare(v, &mut s.g);
            sort_order(s, n, |i| {
                (cx.rank_init[row[i] as usize] as u64) << RANK_SHIFT
            });
            match build_checked(s, pts, v as u32, None, fold, &mut c) {
                Ok(i) => c.dropped_cycles += i.dropped_cycles as u64,
                Err(_) => {
                    c.build_failures += 1;
                    out.fill(false);
                    return c;
                }
            }
        }
        Mode::Update {
            m,
            inu,
            lock,
            ignore_member,
            fold,
            nvc,
            nvc_level,
        } => {
            cx.prepare(v, &mut s.g);
            // Line 9: key_v(t) = (class_v(t), size rank, id); with NVC filtering
            // ASSUMPTION C-05: (tier(t), class_v(t), size rank, id) with matched facets
            // in the last tier, see `update_level`.
            sort_order(s, n, |i| {
                let f = row[i] as usize;
                let member = ignore_member || inu[base + i];
                let lvl = update_level(m[f], member, nvc.map(|x| x[base + i]), nvc_level) as u64;
                (lvl << LEVEL_SHIFT) | ((cx.rank_update[f] as u64) << RANK_SHIFT)
            });
            // Line 10 (ASSUMPTION A-09): lock the (3) facets.
            let any_locked = lock && row.iter().any(|&f| m[f as usize] == 3);
            let locked = |i: usize| m[row[i] as usize] == 3;
            let lk: Option<&dyn Fn(usize) -> bool> = if any_locked { Some(&locked) } else { None };
            match build_checked(s, pts, v as u32, lk, fold, &mut c) {
                Ok(i) => {
                    c.dropped_cycles += i.dropped_cycles as u64;
                    c.skipped_cascades += i.skipped_cascades as u64;
                }
                Err(_) => {
                    c.build_failures += 1;
                    out.copy_from_slice(&inu[base..base + n]);
                    return c;
                }
            }
        }
    }
    out.copy_from_slice(&s.g.alive[..n]);
    c
}

/// Whether the current umbrella of `v` (membership flags `inu`) folds back by more
/// than `bound` radians at some rib (see [`super::geometry`]).
pub fn umbrella_folds(cx: &Complex, inu: &[bool], v: usize, bound: f64) -> bool {
    let base = cx.off[v] as usize;
    let facets = cx.facets();
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(16);
    for (i, &f) in cx.row(v).iter().enumerate() {
        if inu[base + i] {
            let t = facets[f as usize].v;
            let o: Vec<u32> = t.iter().copied().filter(|&x| x as usize != v).collect();
            pairs.push((o[0], o[1]));
        }
    }
    let mut ring = Vec::with_capacity(16);
    if !super::geometry::ring_from_pairs(&pairs, &mut ring) {
        return false;
    }
    let mut buf = Vec::with_capacity(16);
    super::geometry::max_fold(cx.dt.vertices(), v as u32, &ring, &mut buf) > bound
}

/// `M_t` for every facet from the membership flags (Step 3.1).
pub fn matching_indices(cx: &Complex, inu: &[bool], m: &mut Vec<u8>) {
    m.clear();
    m.par_extend(
        cx.slot
            .par_iter()
            .map(|s| absolute_index(s.map(|x| inu[x as usize]))),
    );
}

/// Whether the umbrella of `v` is fully matched (`G_v = 1`).
pub fn fully_matched(cx: &Complex, inu: &[bool], m: &[u8], v: usize) -> bool {
    let base = cx.off[v] as usize;
    let mut any = false;
    for (i, &f) in cx.row(v).iter().enumerate() {
        if inu[base + i] {
            any = true;
            if m[f as usize] != 3 {
                return false;
            }
        }
    }
    any
}

/// Grades `G_v` of all vertices.
pub fn grades(cx: &Complex, inu: &[bool], m: &[u8]) -> Vec<bool> {
    let mut g = Vec::new();
    grades_into(cx, inu, m, &mut g);
    g
}

/// Grades `G_v` of all vertices into `g` (reused buffer).
pub fn grades_into(cx: &Complex, inu: &[bool], m: &[u8], g: &mut Vec<bool>) {
    g.clear();
    g.par_extend(
        (0..cx.n_vertices())
            .into_par_iter()
            .map(|v| fully_matched(cx, inu, m, v)),
    );
}

/// Runs `mode` for every vertex in parallel into `out` (deterministic: each vertex
/// writes its own slots; counters are summed).
fn rebuild_all(
    cx: &Complex,
    out: &mut [bool],
    mode: &Mode,
    skip: Option<&(dyn Fn(usize) -> bool + Sync)>,
    old: Option<&[bool]>,
) -> Counters {
    let mode_ref = mode;
    blocks(cx, out, 256)
        .into_par_iter()
        .map_init(Scratch::default, |s, (v0, v1, chunk)| {
            let mut c = Counters::default();
            let start = cx.off[v0] as usize;
            for v in v0..v1 {
                let a = cx.off[v] as usize - start;
                let b = cx.off[v + 1] as usize - start;
                if let (Some(sk), Some(old)) = (skip, old)
                    && sk(v)
                {
                    chunk[a..b].copy_from_slice(&old[a + start..b + start]);
                    continue;
                }
                c = c + rebuild_vertex(cx, v, s, mode_ref, &mut chunk[a..b]);
            }
            c
        })
        .reduce(Counters::default, |a, b| a + b)
}

/// Result of the UFM loop.
#[derive(Debug)]
pub struct UfmState {
    /// The complex.
    pub cx: Complex,
    /// Membership flags of the final umbrellas (one per CSR slot).
    pub inu: Vec<bool>,
    /// Matching indices of the final umbrellas.
    pub m: Vec<u8>,
    /// Matching fraction after each iteration (0 = initial umbrellas).
    pub trace: Vec<f64>,
    /// Update iterations done.
    pub iterations: usize,
    /// The stop rule that fired.
    pub stop: StopRule,
    /// Counters.
    pub counters: Counters,
    /// Stagnation escapes used (non-faithful extension).
    pub escapes: usize,
    /// Algorithm C counters (zero when `nvc = off`).
    pub nvc: NvcStats,
    /// Iteration at which NVC filtering started (`None`: never).
    pub nvc_from: Option<usize>,
    /// Seconds of Step 2 (initial umbrellas).
    pub init_s: f64,
    /// Seconds of Step 3 (iterations).
    pub iterate_s: f64,
}

/// Steps 2–3: initial umbrellas, then updates until a stop rule fires.
pub fn run(cx: Complex, p: &UfmParams, ctx: &RunCtx) -> Result<UfmState, MethodError> {
    let t0 = std::time::Instant::now();
    let nslots = cx.items.len();
    let mut inu = vec![false; nslots];
    let mut counters = rebuild_all(
        &cx,
        &mut inu,
        &Mode::Init {
            start: p.init,
            fold: p.max_fold.to_radians(),
        },
        None,
        None,
    );
    let init_s = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let mut m = Vec::new();
    let mut history = StopHistory::default();
    let mut next = vec![false; nslots];
    let mut it = 0usize;
    let mut escapes = 0usize;
    // Algorithm C: the NVC flags (one per CSR slot) and whether filtering is active.
    let nvc_cfg = NvcCfg::from_params(p);
    let mut nvc_slots = if nvc_cfg.is_some() {
        vec![false; nslots]
    } else {
        Vec::new()
    };
    let mut nvc_on = nvc_cfg.is_some() && p.nvc_start == NvcStart::First;
    let mut nvc_from = None;
    let mut nvc_stats = NvcStats {
        last_alpha_flat: f64::NAN,
        ..Default::default()
    };
    let mut g = Vec::new();
    let stop = loop {
        // Step 3.1 and the stop test (3.5, A-07).
        matching_indices(&cx, &inu, &mut m);
        grades_into(&cx, &inu, &m, &mut g);
        let mu = g.iter().filter(|&&x| x).count() as f64 / cx.n_vertices().max(1) as f64;
        let mut escape = false;
        if let Some(rule) = history.record(mu, &inu, it, p.patience, p.max_iter) {
            let stuck = matches!(rule, StopRule::FixedPoint | StopRule::LimitCycle);
            if stuck && nvc_cfg.is_some() && !nvc_on {
                // ASSUMPTION C-06 (ablation `nvc_start = stagnation`): NVC filtering
                // starts when the plain loop stagnates, instead of stopping.
                nvc_on = true;
            } else if stuck && escapes < p.escapes {
                // Non-faithful extension: on a fixed point or limit cycle, run one
                // update with the membership level switched off instead of stopping.
                escapes += 1;
                escape = true;
            } else {
                break rule;
            }
        }
        // Algorithm C, lines 5-11: θ̄, α_flat and NVC_v of every G_v = 0 point, from
        // the state at the start of the iteration (synchronous).
        let nvc = match (&nvc_cfg, nvc_on) {
            (Some(cfg), true) => {
                // ASSUMPTION C-06 (default): from the first update iteration on.
                nvc_from.get_or_insert(it);
                nvc_stats = nvc_stats + nvc_flags(&cx, &inu, &m, &g, cfg, &mut nvc_slots);
                Some(&nvc_slots[..])
            }
            _ => None,
        };
        ctx.checkpoint()?;
        ctx.progress(it as f64 / p.max_iter.max(1) as f64);
        // Steps 3.2–3.4.
        it += 1;
        match p.update {
            Update::Jacobi => {
                let mode = Mode::Update {
                    m: &m,
                    inu: &inu,
                    lock: p.lock_matched,
                    ignore_member: escape,
                    fold: p.max_fold.to_radians(),
                    nvc,
                    nvc_level: p.nvc_level,
                };
                // A-08, and with the fold repair: a folded umbrella is not frozen.
                let bound = p.max_fold.to_radians();
                let frozen =
                    |v: usize| g[v] && (bound <= 0.0 || !umbrella_folds(&cx, &inu, v, bound));
                let skip: Option<&(dyn Fn(usize) -> bool + Sync)> =
                    if p.freeze_full { Some(&frozen) } else { None };
                counters = counters + rebuild_all(&cx, &mut next, &mode, skip, Some(&inu));
                // Line 13: synchronous update.
                std::mem::swap(&mut inu, &mut next);
            }
            Update::GaussSeidel => {
                counters = counters + gauss_seidel_sweep(&cx, &mut inu, &mut m, p, escape, nvc);
            }
        }
    };
    let trace = history.trace.clone();
    Ok(UfmState {
        cx,
        inu,
        m,
        trace,
        iterations: it,
        stop,
        counters,
        escapes,
        nvc: nvc_stats,
        nvc_from,
        init_s,
        iterate_s: t1.elapsed().as_secs_f64(),
    })
}

/// One sequential sweep: each vertex in index order is rebuilt from the current state
/// and the matching indices of its triangles are updated at once.
fn gauss_seidel_sweep(
    cx: &Complex,
    inu: &mut [bool],
    m: &mut [u8],
    p: &UfmParams,
    ignore_member: bool,
    nvc: Option<&[bool]>,
) -> Counters {
    let mut s = Scratch::default();
    let mut out = Vec::new();
    let mut c = Counters::default();
    let bound = p.max_fold.to_radians();
    for v in 0..cx.n_vertices() {
        if p.freeze_full
            && fully_matched(cx, inu, m, v)
            && (bound <= 0.0 || !umbrella_folds(cx, inu, v, bound))
        {
            continue;
        }
        let row = cx.row(v);
        let base = cx.off[v] as usize;
        out.clear();
        out.resize(row.len(), false);
        let mode = Mode::Update {
            m,
            inu,
            lock: p.lock_matched,
            ignore_member,
            fold: bound,
            nvc,
            nvc_level: p.nvc_level,
        };
        c = c + rebuild_vertex(cx, v, &mut s, &mode, &mut out);
        for (i, &f) in row.iter().enumerate() {
            let old = inu[base + i];
            if old != out[i] {
                inu[base + i] = out[i];
                if out[i] {
                    m[f as usize] += 1;
                } else {
                    m[f as usize] -= 1;
                }
            }
        }
    }
    c
}

/// Rebuilds the umbrella of one vertex from a given state (for tests of ).
pub fn rebuild_one(cx: &Complex, v: usize, inu: &[bool], m: &[u8], lock: bool) -> Vec<bool> {
    let mut s = Scratch::default();
    let mut out = vec![false; cx.row(v).len()];
    let mode = Mode::Update {
        m,
        inu,
        lock,
        ignore_member: false,
        fold: 0.0,
        nvc: None,
        nvc_level: NvcLevel::Top,
    };
    rebuild_vertex(cx, v, &mut s, &mode, &mut out);
    out
}
