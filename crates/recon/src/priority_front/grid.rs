//! Static uniform grid over the points (the paper's hash grid, spec §3.2) and a dynamic
//! index of front vertices.
//!
//! The points are reordered by cell so that every cell is a contiguous index range (CSR):
//! ball queries then read memory sequentially. Cells are addressed densely when the box
//! holds few enough cells, otherwise through a hash map of the occupied cells.

use std::collections::HashMap;
use std::ops::Range;

use glam::DVec3;

/// "No element" marker for u32 links.
pub(crate) const NONE: u32 = u32::MAX;

/// Largest per-axis cell count (coordinates are packed in 21 bits for hashing).
const MAX_DIM: i64 = (1 << 21) - 2;

/// `x.floor()` without the library call (the baseline x86-64 target has no rounding
/// instruction, so `f64::floor` is an out-of-line function; the grid queries call it six
/// times per scan). Exact for every `f64`: values of magnitude >= 2^52 (and infinities,
/// NaN) are returned unchanged, as they are integral already.
#[inline]
pub(crate) fn floor(x: f64) -> f64 {
    if x.is_nan() || x.abs() >= 4_503_599_627_370_496.0 {
        return x;
    }
    let t = x as i64 as f64;
    // `t == x` returns `x` itself, which keeps the sign of -0.0.
    if t > x {
        t - 1.0
    } else if t == x {
        x
    } else {
        t
    }
}

/// Cell geometry shared by [`Grid`] and [`FrontIndex`].
#[derive(Debug, Clone)]
pub(crate) struct Lattice {
    origin: DVec3,
    h: f64,
    inv_h: f64,
    dims: [i64; 3],
}

impl Lattice {
    /// A lattice of cell edge about `h` over the box `[lo, hi]`; `h` is enlarged when the
    /// box would need more than `MAX_DIM` cells along an axis.
    pub fn new(lo: DVec3, hi: DVec3, h: f64) -> Self {
        let ext = (hi - lo).max(DVec3::ZERO);
        let mut h = if h.is_finite() && h > 0.0 {
            h
        } else {
            ext.max_element().max(1.0)
        };
        let longest = ext.max_element();
        if longest / h > MAX_DIM as f64 {
            h = longest / MAX_DIM as f64 * 1.000_001;
        }
        let d = |e: f64| ((e / h).floor() as i64 + 1).clamp(1, MAX_DIM);
        Self {
            origin: lo,
            h,
            inv_h: 1.0 / h,
            dims: [d(ext.x), d(ext.y), d(ext.z)],
        }
    }

    /// Cell edge.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Number of cells of the box.
    pub fn n_cells(&self) -> u128 {
        self.dims.iter().map(|&d| d as u128).product()
    }

    #[inline]
    fn coord(&self, x: f64, axis: usize) -> i64 {
        let c = floor((x - self.origin[axis]) * self.inv_h);
        // NaN-free by construction (finite inputs); clamp keeps far query points sane.
        (c.clamp(-1.0, (self.dims[axis]) as f64) as i64).clamp(0, self.dims[axis] - 1)
    }

    /// Cell coordinates of `p` (clamped into the box).
    #[inline]
    pub fn coords(&self, p: DVec3) -> [i64; 3] {
        [self.coord(p.x, 0), self.coord(p.y, 1), self.coord(p.z, 2)]
    }

    /// Inclusive coordinate ranges of the cells meeting the cube `[o - r, o + r]`, or
    /// `None` when the cube misses the box.
    #[inline]
    pub fn cube(&self, o: DVec3, r: f64) -> Option<[[i64; 2]; 3]> {
        // The same ranges as clamping `floor` of the scaled ends into `0..dims`, without
        // the floors: `floor(t) < 0 <=> t < 0`, `floor(t) > d - 1 <=> t >= d` and
        // `floor(t) >= d - 1 <=> t >= d - 1` for integral `d`, and a cast truncates,
        // which is `floor` for the non-negative `t` left. Finite `o` and `r` only.
        debug_assert!(o.is_finite() && r.is_finite());
        let mut out = [[0i64; 2]; 3];
        for a in 0..3 {
            let lo = (o[a] - r - self.origin[a]) * self.inv_h;
            let hi = (o[a] + r - self.origin[a]) * self.inv_h;
            let top = (self.dims[a] - 1) as f64;
            if hi < 0.0 || lo >= top + 1.0 {
                return None;
            }
            let l = if lo < 0.0 { 0 } else { lo as i64 };
            let h = if hi >= top {
                self.dims[a] - 1
            } else {
                hi as i64
            };
            out[a] = [l, h];
        }
        Some(out)
    }

    #[inline]
    fn linear(&self, c: [i64; 3]) -> u64 {
        (c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])) as u64
    }

    #[inline]
    fn key(c: [i64; 3]) -> u64 {
        (c[0] as u64) | ((c[1] as u64) << 21) | ((c[2] as u64) << 42)
    }
}

/// Cell addressing: dense linear index or hash of occupied cells.
#[derive(Debug, Clone)]
enum Addr {
    Dense,
    Sparse(HashMap<u64, u32>),
}

/// The static point grid. Point `i` of the grid is point `order[i]` of the input.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    pub lat: Lattice,
    addr: Addr,
    /// CSR: cell `c` holds grid points `starts[c]..starts[c + 1]`.
    starts: Vec<u32>,
}

impl Grid {
    /// Builds the grid with cell edge `h` over `pts`; returns it with the permutation
    /// `order` (grid index -> input index). Dense addressing is used up to
    /// `8 n + 65536` cells.
    pub fn build(pts: &[DVec3], h: f64) -> (Grid, Vec<u32>) {
        let (lo, hi) = bounds(pts);
        let lat = Lattice::new(lo, hi, h);
        let n = pts.len();
        let dense = lat.n_cells() <= (8 * n as u128 + 65_536);
        if dense {
            let nc = lat.n_cells() as usize;
            let cells: Vec<u32> = pts
                .iter()
                .map(|&p| lat.linear(lat.coords(p)) as u32)
                .collect();
            let mut starts = vec![0u32; nc + 1];
            for &c in &cells {
                starts[c as usize + 1] += 1;
            }
            for c in 0..nc {
                starts[c + 1] += starts[c];
            }
            let mut fill = starts.clone();
            let mut order = vec![0u32; n];
            for (i, &c) in cells.iter().enumerate() {
                let slot = fill[c as usize] as usize;
                fill[c as usize] += 1;
                order[slot] = i as u32;
            }
            (
                Grid {
                    lat,
                    addr: Addr::Dense,
                    starts,
                },
                order,
            )
        } else {
            let mut keyed: Vec<(u64, u32)> = pts
                .iter()
                .enumerate()
                .map(|(i, &p)| (Lattice::key(lat.coords(p)), i as u32))
                .collect();
            keyed.sort_unstable();
            let mut map = HashMap::new();
            let mut starts = Vec::new();
            let mut order = Vec::with_capacity(n);
            let mut prev = u64::MAX;
            for (slot, &(k, i)) in keyed.iter().enumerate() {
                if k != prev {
                    map.insert(k, starts.len() as u32);
                    starts.push(slot as u32);
                    prev = k;
                }
                order.push(i);
            }
            starts.push(n as u32);
            (
                Grid {
                    lat,
                    addr: Addr::Sparse(map),
                    starts,
                },
                order,
            )
        }
    }

    /// Number of addressable cells.
    pub fn n_cells(&self) -> usize {
        self.starts.len() - 1
    }

    /// Grid points of cell `c`.
    #[inline]
    pub fn range(&self, c: u32) -> Range<usize> {
        self.starts[c as usize] as usize..self.starts[c as usize + 1] as usize
    }

    #[inline]
    fn cell_at(&self, c: [i64; 3]) -> Option<u32> {
        match &self.addr {
            Addr::Dense => Some(self.lat.linear(c) as u32),
            Addr::Sparse(m) => m.get(&Lattice::key(c)).copied(),
        }
    }

    /// Calls `f` with every non-empty cell meeting the cube `[o - r, o + r]`.
    #[inline]
    pub fn for_cells(&self, o: DVec3, r: f64, mut f: impl FnMut(Range<usize>)) {
        let Some(q) = self.lat.cube(o, r) else {
            return;
        };
        for z in q[2][0]..=q[2][1] {
            for y in q[1][0]..=q[1][1] {
                match &self.addr {
                    Addr::Dense => {
                        // Cells of one row are contiguous: one CSR span.
                        let c0 = self.lat.linear([q[0][0], y, z]) as usize;
                        let c1 = self.lat.linear([q[0][1], y, z]) as usize;
                        let s = self.starts[c0] as usize;
                        let e = self.starts[c1 + 1] as usize;
                        if s < e {
                            f(s..e);
                        }
                    }
                    Addr::Sparse(_) => {
                        for x in q[0][0]..=q[0][1] {
                            if let Some(c) = self.cell_at([x, y, z]) {
                                f(self.range(c));
                            }
                        }
                    }
                }
            }
        }
    }

    /// Calls `f` with the cells of the cube shell of Chebyshev radius `level` around the
    /// cell of `o` (level 0 = that cell). Returns false when the cube of radius
    /// `level - 1` already covered the whole box (nothing left to visit).
    pub fn for_shell(&self, o: DVec3, level: i64, mut f: impl FnMut(Range<usize>)) -> bool {
        let c = self.lat.coords(o);
        let d = self.lat.dims;
        let l = level;
        if l > 0 && (0..3).all(|a| c[a] - (l - 1) <= 0 && c[a] + (l - 1) >= d[a] - 1) {
            return false;
        }
        for z in (c[2] - l).max(0)..=(c[2] + l).min(d[2] - 1) {
            for y in (c[1] - l).max(0)..=(c[1] + l).min(d[1] - 1) {
                let full_row = (z - c[2]).abs() == l || (y - c[1]).abs() == l;
                if full_row {
                    for x in (c[0] - l).max(0)..=(c[0] + l).min(d[0] - 1) {
                        if let Some(cell) = self.cell_at([x, y, z]) {
                            f(self.range(cell));
                        }
                    }
                } else {
                    for x in [c[0] - l, c[0] + l] {
                        if x >= 0
                            && x < d[0]
                            && let Some(cell) = self.cell_at([x, y, z])
                        {
                            f(self.range(cell));
                        }
                    }
                }
            }
        }
        true
    }

    /// Distance from `o` to the outside of the cube of cells of Chebyshev radius `level`
    /// around `o`'s cell: every point closer than this lies in shells `0..=level`.
    pub fn covered(&self, o: DVec3, level: i64) -> f64 {
        let c = self.lat.coords(o);
        let mut m = f64::INFINITY;
        for a in 0..3 {
            let lo = self.lat.origin[a] + (c[a] - level) as f64 * self.lat.h;
            let hi = self.lat.origin[a] + (c[a] + level + 1) as f64 * self.lat.h;
            m = m.min(o[a] - lo).min(hi - o[a]);
        }
        m.max(0.0)
    }
}

/// Axis-aligned bounds of `pts` (a unit box at the origin for an empty slice).
pub(crate) fn bounds(pts: &[DVec3]) -> (DVec3, DVec3) {
    if pts.is_empty() {
        return (DVec3::ZERO, DVec3::ONE);
    }
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &p in pts {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (lo, hi)
}

/// Entries per chunk of the front index.
const CHUNK: usize = 16;

/// A fixed-size block of front-index entries (point id and position, structure of
/// arrays so that a scan reads the positions sequentially).
#[derive(Debug, Clone)]
struct Chunk {
    pos: [DVec3; CHUNK],
    ids: [u32; CHUNK],
    len: u32,
    /// Next (full) chunk of the same bucket.
    next: u32,
}

/// Front vertices bucketed by a coarser lattice (cell edge `2 h`). Each bucket is a
/// list of fixed-size chunks from a recycled pool that stores the points' ids *and
/// positions*: a scan reads each chunk's positions sequentially instead of chasing a
/// linked list through the point array (the gather step's dominant cost). Only the
/// bucket's head chunk is partly filled; a removal moves the head chunk's last entry
/// into the freed place. O(1) insert and remove, no allocation once the pool has grown
/// to the largest front. The order of a bucket's entries is not stable; callers treat
/// a scan as a set.
#[derive(Debug, Clone)]
pub(crate) struct FrontIndex {
    lat: Lattice,
    dense: bool,
    /// Head chunk of each bucket (dense addressing by linear cell).
    heads: Vec<u32>,
    /// Head chunk of each occupied bucket (sparse addressing by packed cell key).
    sparse: HashMap<u64, u32>,
    pool: Vec<Chunk>,
    free: Vec<u32>,
    /// Per point: its bucket (`u64::MAX` when not listed), chunk and place in it.
    bucket: Vec<u64>,
    chunk: Vec<u32>,
    place: Vec<u8>,
}

impl FrontIndex {
    /// An empty index for `n` points over the box of `grid`.
    pub fn new(grid: &Grid, n: usize, cell: f64) -> Self {
        let lo = grid.lat.origin;
        let hi = lo
            + DVec3::new(
                grid.lat.dims[0] as f64,
                grid.lat.dims[1] as f64,
                grid.lat.dims[2] as f64,
            ) * grid.lat.h;
        let lat = Lattice::new(lo, hi, cell);
        let dense = lat.n_cells() <= (2 * n as u128 + 65_536);
        let heads = if dense {
            vec![NONE; lat.n_cells() as usize]
        } else {
            Vec::new()
        };
        Self {
            lat,
            dense,
            heads,
            sparse: HashMap::new(),
            pool: Vec::new(),
            free: Vec::new(),
            bucket: vec![u64::MAX; n],
            chunk: vec![NONE; n],
            place: vec![0; n],
        }
    }

    #[inline]
    fn bucket_of(&self, c: [i64; 3]) -> u64 {
        if self.dense {
            self.lat.linear(c)
        } else {
            Lattice::key(c)
        }
    }

    #[inline]
    fn head(&self, b: u64) -> u32 {
        if self.dense {
            self.heads[b as usize]
        } else {
            self.sparse.get(&b).copied().unwrap_or(NONE)
        }
    }

    #[inline]
    fn set_head(&mut self, b: u64, c: u32) {
        if self.dense {
            self.heads[b as usize] = c;
        } else if c == NONE {
            self.sparse.remove(&b);
        } else {
            self.sparse.insert(b, c);
        }
    }

    /// A fresh chunk whose successor is `next`.
    fn alloc(&mut self, next: u32) -> u32 {
        if let Some(c) = self.free.pop() {
            let k = &mut self.pool[c as usize];
            k.len = 0;
            k.next = next;
            c
        } else {
            self.pool.push(Chunk {
                pos: [DVec3::ZERO; CHUNK],
                ids: [NONE; CHUNK],
                len: 0,
                next,
            });
            (self.pool.len() - 1) as u32
        }
    }

    /// Lists point `i` at position `p` (no-op when already listed).
    pub fn insert(&mut self, i: u32, p: DVec3) {
        if self.bucket[i as usize] != u64::MAX {
            return;
        }
        let b = self.bucket_of(self.lat.coords(p));
        let mut h = self.head(b);
        if h == NONE || self.pool[h as usize].len as usize == CHUNK {
            h = self.alloc(h);
            self.set_head(b, h);
        }
        let k = &mut self.pool[h as usize];
        let l = k.len as usize;
        k.pos[l] = p;
        k.ids[l] = i;
        k.len += 1;
        self.bucket[i as usize] = b;
        self.chunk[i as usize] = h;
        self.place[i as usize] = l as u8;
    }

    /// Unlists point `i` (no-op when not listed).
    pub fn remove(&mut self, i: u32) {
        let b = self.bucket[i as usize];
        if b == u64::MAX {
            return;
        }
        let (c, l) = (self.chunk[i as usize], self.place[i as usize] as usize);
        let h = self.head(b);
        // Move the head chunk's last entry into the freed place.
        let hk = &mut self.pool[h as usize];
        hk.len -= 1;
        let last = hk.len as usize;
        let (lp, li) = (hk.pos[last], hk.ids[last]);
        let emptied = hk.len == 0;
        let after = hk.next;
        if li != i {
            let k = &mut self.pool[c as usize];
            k.pos[l] = lp;
            k.ids[l] = li;
            self.chunk[li as usize] = c;
            self.place[li as usize] = l as u8;
        }
        if emptied {
            self.free.push(h);
            self.set_head(b, after);
        }
        self.bucket[i as usize] = u64::MAX;
        self.chunk[i as usize] = NONE;
    }

    /// Collects into `out` (cleared) the chunks holding the listed points of the buckets
    /// meeting the cube `[o - r, o + r]`; [`FrontIndex::chunk`] reads them. Lets the
    /// caller scan them in a plain loop over locals (no closure captures).
    #[inline(never)]
    pub fn chunks_near(&self, o: DVec3, r: f64, out: &mut Vec<u32>) {
        out.clear();
        let Some(q) = self.lat.cube(o, r) else {
            return;
        };
        for z in q[2][0]..=q[2][1] {
            for y in q[1][0]..=q[1][1] {
                if self.dense {
                    // The buckets of one row are contiguous in `heads`.
                    let b0 = self.lat.linear([q[0][0], y, z]) as usize;
                    let b1 = b0 + (q[0][1] - q[0][0]) as usize;
                    for &h in &self.heads[b0..=b1] {
                        let mut c = h;
                        while c != NONE {
                            out.push(c);
                            c = self.pool[c as usize].next;
                        }
                    }
                } else {
                    for x in q[0][0]..=q[0][1] {
                        let mut c = self.head(Lattice::key([x, y, z]));
                        while c != NONE {
                            out.push(c);
                            c = self.pool[c as usize].next;
                        }
                    }
                }
            }
        }
    }

    /// The ids and positions of the listed points of chunk `c` (from
    /// [`FrontIndex::chunks_near`]).
    #[inline]
    pub fn chunk(&self, c: u32) -> (&[u32], &[DVec3]) {
        let k = &self.pool[c as usize];
        let l = k.len as usize;
        (&k.ids[..l], &k.pos[..l])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Random inserts / removes; every ball query must return exactly the listed points
    /// within the radius (after the caller's distance filter), each once, with their
    /// positions. `cell` small enough forces the sparse (hashed) addressing.
    fn churn(cell_factor: f64, expect_dense: bool) {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let pts: Vec<DVec3> = (0..3000)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random::<f64>() * 0.1))
            .collect();
        let (grid, _) = Grid::build(&pts, 0.05);
        let mut fi = FrontIndex::new(&grid, pts.len(), cell_factor * grid.lat.h());
        assert_eq!(fi.dense, expect_dense);
        let mut listed = vec![false; pts.len()];
        for step in 0..20_000 {
            let i = rng.random_range(0..pts.len());
            if rng.random::<f64>() < 0.6 {
                fi.insert(i as u32, pts[i]);
                listed[i] = true;
            } else {
                fi.remove(i as u32);
                listed[i] = false;
            }
            if step % 97 == 0 {
                let o = DVec3::new(rng.random(), rng.random(), 0.05);
                let r = 0.1;
                let mut got = Vec::new();
                let mut chunks = Vec::new();
                fi.chunks_near(o, r, &mut chunks);
                for &c in &chunks {
                    let (ids, pos) = fi.chunk(c);
                    for (&v, &p) in ids.iter().zip(pos) {
                        assert_eq!(p, pts[v as usize]);
                        assert!(listed[v as usize]);
                        if (p - o).length() <= r {
                            got.push(v);
                        }
                    }
                }
                got.sort_unstable();
                let want: Vec<u32> = (0..pts.len() as u32)
                    .filter(|&v| listed[v as usize] && (pts[v as usize] - o).length() <= r)
                    .collect();
                assert_eq!(got, want);
            }
        }
    }

    #[test]
    fn front_index_matches_brute_force_dense() {
        churn(2.0, true);
    }

    #[test]
    fn front_index_matches_brute_force_sparse() {
        churn(0.2, false);
    }

    #[test]
    fn fast_floor_is_exact() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999_999,
            -2.000_001,
            1e15 + 0.5,
            -1e15 - 0.5,
            4.5e15,
            -4.5e15,
            1e300,
            -1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
        ] {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x}");
        }
        assert!(floor(f64::NAN).is_nan());
        assert_eq!(floor(f64::INFINITY), f64::INFINITY);
        assert_eq!(floor(f64::NEG_INFINITY), f64::NEG_INFINITY);
    }
}
