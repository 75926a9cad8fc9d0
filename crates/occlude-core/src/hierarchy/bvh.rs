//! Binned surface-area-heuristic BVH over instance boxes (Wald, "On fast
//! construction of SAH-based bounding volume hierarchies", 2007): centroids are
//! binned along each axis and the split with the lowest SAH cost is taken.

use super::{BuildOptions, NodeId, TreeBuilder, NO_NODE, SAH_BINS};
use crate::geometry::Aabb;
use glam::Vec3;

/// Builds the BVH of `boxes` into `out` (root first).
pub(crate) fn build(boxes: &[Aabb], options: BuildOptions, out: &mut TreeBuilder) {
    let centers: Vec<Vec3> = boxes.iter().map(Aabb::center).collect();
    let mut ids: Vec<u32> = (0..boxes.len() as u32).collect();
    let builder = Builder { boxes, centers: &centers, options };
    builder.node(&mut ids, NO_NODE, 0, out);
}

struct Builder<'a> {
    boxes: &'a [Aabb],
    centers: &'a [Vec3],
    options: BuildOptions,
}

impl Builder<'_> {
    fn node(&self, ids: &mut [u32], parent: NodeId, depth: u32, out: &mut TreeBuilder) -> NodeId {
        let bounds = ids.iter().fold(Aabb::EMPTY, |b, &i| b.union(&self.boxes[i as usize]));
        let id = out.push(bounds, parent, depth);
        if ids.len() <= self.options.leaf_size || depth >= self.options.max_depth {
            out.make_leaf(id, ids);
            return id;
        }
        let mid = self.partition(ids);
        let (left, right) = ids.split_at_mut(mid);
        let l = self.node(left, id, depth + 1, out);
        let r = self.node(right, id, depth + 1, out);
        out.set_children(id, [l, r]);
        id
    }

    /// Reorders `ids` into two non-empty halves by the best SAH bin split and
    /// returns the size of the first; falls back to a median split where the
    /// centroids do not separate.
    fn partition(&self, ids: &mut [u32]) -> usize {
        let cb = Aabb::from_points(ids.iter().map(|&i| &self.centers[i as usize]));
        let extent = cb.extent();
        let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin)
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let bin_of = |i: u32| self.bin(self.centers[i as usize][axis], cb.min[axis], extent[axis]);
            let mut bins = [(Aabb::EMPTY, 0usize); SAH_BINS];
            for &i in ids.iter() {
                let b = &mut bins[bin_of(i)];
                b.0 = b.0.union(&self.boxes[i as usize]);
                b.1 += 1;
            }
            // Sweep from the right to get suffix areas, then from the left.
            let mut right_cost = [0.0f32; SAH_BINS];
            let (mut acc, mut count) = (Aabb::EMPTY, 0usize);
            for k in (1..SAH_BINS).rev() {
                acc = acc.union(&bins[k].0);
                count += bins[k].1;
                right_cost[k] = acc.surface_area() * count as f32;
            }
            let (mut acc, mut count) = (Aabb::EMPTY, 0usize);
            for k in 0..SAH_BINS - 1 {
                acc = acc.union(&bins[k].0);
                count += bins[k].1;
                if count == 0 || count == ids.len() {
                    continue;
                }
                let cost = acc.surface_area() * count as f32 + right_cost[k + 1];
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, k));
                }
            }
        }
        match best {
            Some((_, axis, k)) => {
                let mut mid = 0;
                for j in 0..ids.len() {
                    if self.bin(self.centers[ids[j] as usize][axis], cb.min[axis], extent[axis]) <= k {
                        ids.swap(mid, j);
                        mid += 1;
                    }
                }
                mid
            }
            None => ids.len() / 2,
        }
    }

    fn bin(&self, c: f32, min: f32, extent: f32) -> usize {
        (((c - min) / extent * SAH_BINS as f32) as usize).min(SAH_BINS - 1)
    }
}
