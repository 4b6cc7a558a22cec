//! Mesh-edge adjacency of the *front* vertices (the edge map of spec §3.3).
//!
//! A triangle may only be added when it does not give an edge a third face (ASSUMPTION
//! A13). Every edge a new triangle could create joins two front vertices, and a vertex
//! never gets a new edge once it has left the front; so it suffices to keep the full
//! neighbour list of each *front* vertex. Lists live in fixed-size blocks from a
//! recycled pool: memory is O(front size) and the hot loop does not allocate once the
//! pool has grown to the largest front.

use super::grid::NONE;

const K: usize = 8;

/// Neighbour lists of front vertices in pooled blocks of `K` entries.
#[derive(Debug, Clone)]
pub(crate) struct Adjacency {
    head: Vec<u32>,
    pool: Vec<[u32; K]>,
    len: Vec<u8>,
    next: Vec<u32>,
    free: Vec<u32>,
}

impl Adjacency {
    /// Empty lists for `n` points.
    pub fn new(n: usize) -> Self {
        Self {
            head: vec![NONE; n],
            pool: Vec::new(),
            len: Vec::new(),
            next: Vec::new(),
            free: Vec::new(),
        }
    }

    fn alloc(&mut self) -> u32 {
        if let Some(b) = self.free.pop() {
            self.len[b as usize] = 0;
            self.next[b as usize] = NONE;
            b
        } else {
            self.pool.push([NONE; K]);
            self.len.push(0);
            self.next.push(NONE);
            (self.pool.len() - 1) as u32
        }
    }

    fn push_one(&mut self, u: u32, v: u32) {
        let mut b = self.head[u as usize];
        if b == NONE {
            b = self.alloc();
            self.head[u as usize] = b;
        }
        loop {
            let l = self.len[b as usize] as usize;
            if l < K {
                self.pool[b as usize][l] = v;
                self.len[b as usize] += 1;
                return;
            }
            let nb = self.next[b as usize];
            if nb == NONE {
                let nb = self.alloc();
                self.next[b as usize] = nb;
                b = nb;
            } else {
                b = nb;
            }
        }
    }

    /// Records the undirected edge `{u, v}` (the caller ensures it is new).
    pub fn add(&mut self, u: u32, v: u32) {
        self.push_one(u, v);
        self.push_one(v, u);
    }

    /// True when `{u, v}` is a mesh edge (`u` must be a front vertex).
    #[inline]
    pub fn has(&self, u: u32, v: u32) -> bool {
        let mut b = self.head[u as usize];
        while b != NONE {
            let l = self.len[b as usize] as usize;
            if self.pool[b as usize][..l].contains(&v) {
                return true;
            }
            b = self.next[b as usize];
        }
        false
    }

    /// Number of mesh neighbours of front vertex `u`.
    pub fn degree(&self, u: u32) -> usize {
        let mut b = self.head[u as usize];
        let mut d = 0;
        while b != NONE {
            d += self.len[b as usize] as usize;
            b = self.next[b as usize];
        }
        d
    }

    /// Frees the list of `u` (it left the front).
    pub fn release(&mut self, u: u32) {
        let mut b = self.head[u as usize];
        while b != NONE {
            self.free.push(b);
            b = self.next[b as usize];
        }
        self.head[u as usize] = NONE;
    }
}
