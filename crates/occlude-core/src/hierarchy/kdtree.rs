//! SAH kD-tree over instance boxes, the hierarchy of the CHC paper (section
//! 6.1, after MacDonald and Booth's surface-area heuristic).
//!
//! Split planes are chosen among evenly spaced candidates in each cell. An
//! instance that crosses the plane is referenced by both children, so a leaf's
//! box is its cell clipped to the boxes of the instances it references: every
//! point of such an instance inside the cell lies in that box, which keeps
//! queries conservative. Methods draw each instance at most once per frame.

use super::{BuildOptions, NodeId, TreeBuilder, NO_NODE, SAH_BINS};
use crate::geometry::Aabb;

/// Builds the kD-tree of `boxes` into `out` (root first).
pub(crate) fn build(boxes: &[Aabb], options: BuildOptions, out: &mut TreeBuilder) {
    let ids: Vec<u32> = (0..boxes.len() as u32).collect();
    let cell = boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(x));
    Builder { boxes, options }.node(ids, cell, NO_NODE, 0, out);
}

struct Builder<'a> {
    boxes: &'a [Aabb],
    options: BuildOptions,
}

/// A candidate split: plane `axis = at`.
struct Split {
    axis: usize,
    at: f32,
}

impl Builder<'_> {
    fn node(&self, ids: Vec<u32>, cell: Aabb, parent: NodeId, depth: u32, out: &mut TreeBuilder) -> NodeId {
        let content = ids.iter().fold(Aabb::EMPTY, |b, &i| b.union(&self.boxes[i as usize]));
        let id = out.push(content.intersection(&cell), parent, depth);
        let split = if ids.len() <= self.options.leaf_size || depth >= self.options.max_depth {
            None
        } else {
            self.best_split(&ids, &cell)
        };
        let Some(Split { axis, at }) = split else {
            out.make_leaf(id, &ids);
            return id;
        };
        let (mut left, mut right) = (Vec::new(), Vec::new());
        for &i in &ids {
            let b = &self.boxes[i as usize];
            if b.min[axis] <= at {
                left.push(i);
            }
            if b.max[axis] > at {
                right.push(i);
            }
        }
        drop(ids);
        let (mut lcell, mut rcell) = (cell, cell);
        lcell.max[axis] = at;
        rcell.min[axis] = at;
        let l = self.node(left, lcell, id, depth + 1, out);
        let r = self.node(right, rcell, id, depth + 1, out);
        out.set_children(id, [l, r]);
        id
    }

    /// The plane with the lowest SAH cost, if splitting beats a leaf.
    fn best_split(&self, ids: &[u32], cell: &Aabb) -> Option<Split> {
        let extent = cell.extent();
        let area = cell.surface_area();
        let n = ids.len();
        let leaf_cost = n as f32;
        let mut best: Option<(f32, Split)> = None;
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            // Histograms of where boxes start and end along the axis.
            let bin_of = |x: f32| {
                let t = (x - cell.min[axis]) / extent[axis] * SAH_BINS as f32;
                (t.max(0.0) as usize).min(SAH_BINS - 1)
            };
            let plane = |k: usize| cell.min[axis] + extent[axis] * k as f32 / SAH_BINS as f32;
            let mut starts = [0usize; SAH_BINS];
            let mut ends = [0usize; SAH_BINS];
            for &i in ids {
                let b = &self.boxes[i as usize];
                starts[bin_of(b.min[axis])] += 1;
                ends[bin_of(b.max[axis])] += 1;
            }
            let (mut started, mut ended) = (0usize, 0usize);
            for k in 1..SAH_BINS {
                started += starts[k - 1];
                ended += ends[k - 1];
                // Binned estimate: boxes starting before the plane go left,
                // boxes not ended before it go right.
                let (nl, nr) = (started, n - ended);
                if nl == n && nr == n {
                    continue;
                }
                let at = plane(k);
                let (mut lc, mut rc) = (*cell, *cell);
                lc.max[axis] = at;
                rc.min[axis] = at;
                let cost = 1.0 + (lc.surface_area() * nl as f32 + rc.surface_area() * nr as f32) / area;
                if cost < leaf_cost && best.as_ref().is_none_or(|(c, _)| cost < *c) {
                    best = Some((cost, Split { axis, at }));
                }
            }
        }
        let split = best?.1;
        // The exact partition must shrink both sides, or the tree never ends.
        let left = ids.iter().filter(|&&i| self.boxes[i as usize].min[split.axis] <= split.at).count();
        let right = ids.iter().filter(|&&i| self.boxes[i as usize].max[split.axis] > split.at).count();
        (left < n || right < n).then_some(split)
    }
}
