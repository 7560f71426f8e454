//! Union–find over `0..n`, for the output blocks of a predictor's columns and
//! the components of interacting sign arguments.

/// Disjoint sets of `0..n`: each set is named by its root.
pub(super) struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    /// `n` singletons.
    pub(super) fn new(n: usize) -> UnionFind {
        UnionFind {
            parent: (0..n).collect(),
        }
    }
    /// The root of `x`'s set (with path compression).
    pub(super) fn find(&mut self, x: usize) -> usize {
        let mut r = x;
        while self.parent[r] != r {
            r = self.parent[r];
        }
        let mut y = x;
        while self.parent[y] != r {
            let next = self.parent[y];
            self.parent[y] = r;
            y = next;
        }
        r
    }
    /// Joins the sets of `a` and `b`; the root of `a`'s set stays the root.
    pub(super) fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[rb] = ra;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::UnionFind;

    #[test]
    fn the_first_root_stays() {
        let mut u = UnionFind::new(5);
        u.union(3, 1);
        u.union(1, 4);
        assert_eq!(u.find(4), 3);
        assert_eq!(u.find(1), 3);
        assert_ne!(u.find(0), 3);
        u.union(0, 4);
        assert_eq!(u.find(3), 0);
    }
}
