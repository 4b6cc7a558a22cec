//! One growth domain: first seed, main loop, multi-seed restarts (spec §4.3 M0-M8, §4.6).

use glam::DVec3;
use rand::RngExt;
use rand::seq::index;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::method::{MethodError, RunCtx};

use super::density::mean_nn;
use super::grid::NONE;
use super::mesher::{FREE, Mesher};
use super::params::PriorityFrontParams;
use super::seed::SeedCfg;

/// Settings of a domain run.
#[derive(Debug, Clone)]
pub(crate) struct DomainCfg<'p> {
    pub params: &'p PriorityFrontParams,
    /// Original radius R₀.
    pub r0: f64,
    /// Cloud centroid (A9).
    pub centroid: DVec3,
    /// Forced first patch centre (grid index of this domain).
    pub first_centre: Option<u32>,
    /// Seeds already used elsewhere (counts against `max_seeds`).
    pub seeds_before: u64,
}

/// `m` distinct random picks from `pool` (all of it when smaller), sorted.
fn pick(rng: &mut ChaCha8Rng, pool: &[u32], m: usize) -> Vec<u32> {
    if pool.len() <= m {
        return pool.to_vec();
    }
    let mut v: Vec<u32> = index::sample(rng, pool.len(), m)
        .into_iter()
        .map(|k| pool[k])
        .collect();
    v.sort_unstable();
    v
}

impl Mesher<'_> {
    /// Free points in R-graph components of at least `min` points (ASSUMPTION A10).
    pub fn patch_points(&self, r: f64, min: usize) -> Vec<u32> {
        let n = self.pts.len();
        let mut comp = vec![NONE; n];
        let mut out = Vec::new();
        let mut stack = Vec::new();
        let mut members = Vec::new();
        let r2 = r * r;
        for s in 0..n {
            if self.state[s] != FREE || comp[s] != NONE {
                continue;
            }
            comp[s] = s as u32;
            stack.push(s as u32);
            members.clear();
            while let Some(i) = stack.pop() {
                members.push(i);
                let p = self.pts[i as usize];
                let (pts, state) = (self.pts, &self.state);
                let comp = &mut comp;
                let stack = &mut stack;
                self.grid.for_cells(p, r, |range| {
                    for j in range {
                        if state[j] == FREE
                            && comp[j] == NONE
                            && (pts[j] - p).length_squared() <= r2
                        {
                            comp[j] = s as u32;
                            stack.push(j as u32);
                        }
                    }
                });
            }
            if members.len() >= min {
                out.extend_from_slice(&members);
            }
        }
        out.sort_unstable();
        out
    }

    fn seeds_left(&self, cfg: &DomainCfg) -> bool {
        cfg.params.max_seeds == 0
            || cfg.seeds_before + self.stats.seeds < cfg.params.max_seeds as u64
    }

    /// M0-M8 on this domain: the first seed, growth, then restarts while Free patches
    /// remain. Does not refuse points (M9 is the caller's).
    pub fn run_domain(
        &mut self,
        cfg: &DomainCfg,
        rng: &mut ChaCha8Rng,
        ctx: &RunCtx,
    ) -> Result<(), MethodError> {
        let p = cfg.params;
        let outward = p.seed_outward.then_some(cfg.centroid);
        // First seed (S1-S7): m random Free centres (or the forced one); a few extra
        // draws when none of them yields a valid triangle.
        let free: Vec<u32> = (0..self.pts.len() as u32)
            .filter(|&i| self.state[i as usize] == FREE)
            .collect();
        if free.len() < 3 || !self.seeds_left(cfg) {
            return Ok(());
        }
        let first = SeedCfg {
            n_nb: p.patch_neighbours,
            rmax: f64::INFINITY,
            max_flatness: f64::INFINITY,
            full_patch: false,
            outward_from: outward,
        };
        let mut seed = None;
        if let Some(c) = cfg.first_centre {
            seed = self.find_seed(&[c], &first);
        }
        for _ in 0..4 {
            if seed.is_some() {
                break;
            }
            // ASSUMPTION A4: m = seed_patches random patches.
            let centres = pick(rng, &free, p.seed_patches);
            seed = self.find_seed(&centres, &first);
        }
        let Some(s) = seed else {
            return Ok(());
        };
        self.add_seed(s);
        self.grow(ctx)?;
        self.restarts(cfg, rng, ctx)
    }

    /// M8: restarts while Free patches remain (no-op when `restart` is off).
    pub fn restarts(
        &mut self,
        cfg: &DomainCfg,
        rng: &mut ChaCha8Rng,
        ctx: &RunCtx,
    ) -> Result<(), MethodError> {
        let p = cfg.params;
        if !p.restart {
            return Ok(());
        }
        let outward = p.seed_outward.then_some(cfg.centroid);
        // M8 / ASSUMPTION A10: restart while Free R-graph components of >= 10 points
        // exist and a seed can be built; rho is recomputed on the Free points and R is
        // capped at restart_radius_cap * R0.
        let mut failures = 0;
        while self.seeds_left(cfg) {
            ctx.checkpoint()?;
            let state = &self.state;
            let eligible = |i: usize| state[i] == FREE;
            let Some(rho_f) = mean_nn(self.grid, self.pts, &eligible, p.rho_sample, rng) else {
                break;
            };
            let r = (p.k * rho_f).min(p.restart_radius_cap * cfg.r0);
            let pool = self.patch_points(r, p.restart_min_points);
            if pool.is_empty() {
                break;
            }
            let centres = pick(rng, &pool, p.seed_patches);
            let sc = SeedCfg {
                n_nb: p.patch_neighbours,
                rmax: r,
                max_flatness: p.restart_max_flatness,
                full_patch: true,
                outward_from: outward,
            };
            let old_r = self.cfg.r;
            self.cfg.r = r;
            // IMPL-CHOICE I14: a restart seed through the mesh counts as not found.
            let found = self.find_seed(&centres, &sc);
            match found.filter(|&s| !self.crosses_mesh(s)) {
                Some(s) => {
                    failures = 0;
                    self.add_seed(s);
                    self.grow(ctx)?;
                }
                None => {
                    self.cfg.r = old_r;
                    failures += 1;
                    // A random draw may miss the one good patch: retry a few times.
                    if failures >= 3 {
                        break;
                    }
                    let _: u32 = rng.random();
                }
            }
        }
        Ok(())
    }
}
