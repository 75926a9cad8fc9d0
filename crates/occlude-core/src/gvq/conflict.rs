//! The conflict graph and its colouring (section 3.1.1): one vertex per
//! query object, an edge where two objects' screen rectangles overlap, and
//! the paper's adaptation of Chaitin-Briggs register allocation to give
//! each vertex a colour channel no neighbour has.

use super::rect::PixelRect;

/// Objects whose screen rectangles overlap, as adjacency lists. Objects
/// without a rectangle (off screen) have no edges.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ConflictGraph {
    adjacency: Vec<Vec<u32>>,
}

/// The outcome of [`ConflictGraph::colour`]: per object its channel, or
/// `None` for a conflict object (one that could not be placed whole).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Colouring {
    /// Per object, the channel it is rendered in as a whole.
    pub colours: Vec<Option<u32>>,
}

impl Colouring {
    /// The conflict objects, in increasing order.
    pub fn conflicts(&self) -> Vec<u32> {
        (0..self.colours.len() as u32).filter(|&v| self.colours[v as usize].is_none()).collect()
    }
}

impl ConflictGraph {
    /// The graph of `rects` (the overlap test: every pair, `O(n^2)`).
    pub fn new(rects: &[Option<PixelRect>]) -> Self {
        let mut adjacency = vec![Vec::new(); rects.len()];
        for (i, a) in rects.iter().enumerate() {
            let Some(a) = a else { continue };
            for (j, b) in rects.iter().enumerate().skip(i + 1) {
                if b.is_some_and(|b| a.intersect(&b).is_some()) {
                    adjacency[i].push(j as u32);
                    adjacency[j].push(i as u32);
                }
            }
        }
        Self { adjacency }
    }

    /// Number of vertices (objects).
    pub fn len(&self) -> usize {
        self.adjacency.len()
    }

    /// True when the graph has no vertex.
    pub fn is_empty(&self) -> bool {
        self.adjacency.is_empty()
    }

    /// The objects `v` conflicts with.
    pub fn neighbours(&self, v: u32) -> &[u32] {
        &self.adjacency[v as usize]
    }

    /// Colours the graph with `channels` colours (1 to 32) as the paper
    /// does: decomposition removes, one at a time, a vertex with the fewest
    /// edges left (the lowest index on ties) and stacks it; reconstruction
    /// pops the stack, reinserting each vertex with the lowest channel none
    /// of its reinserted neighbours has. A vertex left with no channel is a
    /// conflict object and is not reinserted, so it constrains no one.
    ///
    /// # Panics
    /// If `channels` is 0 or above 32.
    pub fn colour(&self, channels: u32) -> Colouring {
        assert!((1..=32).contains(&channels), "{channels} channels: 1 to 32 supported");
        let n = self.len();
        let mut degree: Vec<usize> = self.adjacency.iter().map(Vec::len).collect();
        let mut removed = vec![false; n];
        let mut stack = Vec::with_capacity(n);
        for _ in 0..n {
            let v = (0..n).filter(|&v| !removed[v]).min_by_key(|&v| degree[v]).expect("a vertex is left");
            removed[v] = true;
            stack.push(v);
            for &w in &self.adjacency[v] {
                degree[w as usize] -= usize::from(!removed[w as usize]);
            }
        }
        let all = if channels == 32 { u32::MAX } else { (1 << channels) - 1 };
        let mut colours: Vec<Option<u32>> = vec![None; n];
        while let Some(v) = stack.pop() {
            let used = self.adjacency[v].iter().filter_map(|&w| colours[w as usize]).fold(0u32, |m, c| m | 1 << c);
            let free = all & !used;
            colours[v] = (free != 0).then(|| free.trailing_zeros());
        }
        Colouring { colours }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gvq::rect::tests::rect_strategy;
    use proptest::prelude::*;

    #[test]
    fn overlapping_rectangles_are_neighbours_and_touching_ones_are_not() {
        let rects = [
            Some(PixelRect::new(0, 0, 4, 4)),
            Some(PixelRect::new(3, 3, 6, 6)),
            Some(PixelRect::new(4, 0, 8, 3)),
            None,
        ];
        let g = ConflictGraph::new(&rects);
        assert_eq!(g.neighbours(0), &[1]);
        assert_eq!(g.neighbours(1), &[0]);
        assert!(g.neighbours(2).is_empty() && g.neighbours(3).is_empty());
    }

    #[test]
    fn a_clique_one_larger_than_the_channels_leaves_one_conflict() {
        let rects = vec![Some(PixelRect::new(0, 0, 10, 10)); 5];
        let c = ConflictGraph::new(&rects).colour(4);
        assert_eq!(c.conflicts().len(), 1);
        let mut placed: Vec<u32> = c.colours.iter().flatten().copied().collect();
        placed.sort_unstable();
        assert_eq!(placed, vec![0, 1, 2, 3]);
        assert!(ConflictGraph::new(&rects).colour(8).conflicts().is_empty());
    }

    #[test]
    fn a_star_is_coloured_with_two_channels_and_no_conflict() {
        // The centre is decomposed last, so it is reinserted first.
        let mut rects = vec![Some(PixelRect::new(0, 0, 100, 2))];
        rects.extend((0..10).map(|k| Some(PixelRect::new(k * 10, 1, k * 10 + 5, 5))));
        let c = ConflictGraph::new(&rects).colour(2);
        assert!(c.conflicts().is_empty());
        assert!(c.colours[1..].iter().all(|&k| k != c.colours[0]));
    }

    proptest! {
        #[test]
        fn no_two_conflicting_objects_share_a_colour(
            rects in prop::collection::vec(rect_strategy(), 0..40),
            channels in 1u32..9,
        ) {
            let g = ConflictGraph::new(&rects);
            let c = g.colour(channels);
            for v in 0..g.len() as u32 {
                let Some(cv) = c.colours[v as usize] else { continue };
                prop_assert!(cv < channels);
                for &w in g.neighbours(v) {
                    prop_assert_ne!(Some(cv), c.colours[w as usize]);
                }
            }
            // Off-screen objects have no neighbours and always get a colour.
            for (v, r) in rects.iter().enumerate() {
                if r.is_none() {
                    prop_assert!(c.colours[v].is_some());
                }
            }
        }
    }
}
