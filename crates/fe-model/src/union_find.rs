//! Disjoint sets, shared by the assembly (tied DOFs share an equation) and
//! the kinematic check (beam-connected nodes form a body), in a file of
//! their own so that neither imports the other.

/// Disjoint sets of `0..n` whose representative is the smallest member
/// (in `assembly`: equations follow node order; in `kinematics`: bodies).
pub(crate) struct UnionFind(Vec<usize>);

impl UnionFind {
    pub(crate) fn new(n: usize) -> Self {
        UnionFind((0..n).collect())
    }
    pub(crate) fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    pub(crate) fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            // keep the smaller index as root: equations follow node order
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi] = lo;
        }
    }
}
