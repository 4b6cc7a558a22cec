//! Union-find for the SM / NC hierarchy (ASSUMPTION H1).

/// Union-find with union by size and path halving; sizes are kept at the roots.
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    /// `n` singletons.
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    /// Root of `x`.
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let g = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = g;
            x = g;
        }
        x
    }

    /// Unites the sets of `a` and `b`; returns the new root.
    pub fn union(&mut self, a: u32, b: u32) -> u32 {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return ra;
        }
        if self.size[ra as usize] < self.size[rb as usize] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb as usize] = ra;
        self.size[ra as usize] += self.size[rb as usize];
        ra
    }

    /// Size of the set whose root is `root`.
    pub fn size(&self, root: u32) -> u32 {
        self.size[root as usize]
    }

    /// Removes one member from the count of the set rooted at `root` (a detached point
    /// stays linked but no longer counts; see the extra case of §3.3.2).
    pub fn shrink(&mut self, root: u32) {
        self.size[root as usize] -= 1;
    }
}
