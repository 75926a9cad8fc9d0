//! Tight bounding volumes and virtual leaves (CHC++ paper, section 6).
//!
//! A node is queried with the boxes of its descendants down to `dmax` levels
//! instead of its own box, refining only while the children's total surface
//! area stays within `smax` times their parent's, so the query's fill cost
//! does not grow much. Interior nodes with few triangles become virtual
//! leaves: traversal stops there and renders their whole subtree.

use crate::geometry::Aabb;
use crate::hierarchy::{Hierarchy, NodeId};

/// The boxes to query for `node`: its descendants' boxes, refined while
/// depth < `dmax` and the children's summed area is at most `smax` times the
/// parent's. Empty children are dropped.
pub fn tight_boxes(h: &Hierarchy, node: NodeId, dmax: u32, smax: f32) -> Vec<Aabb> {
    let mut out = Vec::new();
    let mut stack = vec![(node, 0u32)];
    while let Some((n, depth)) = stack.pop() {
        let children = h.children(n);
        let area: f32 = children.iter().map(|&c| h.bounds(c).surface_area()).sum();
        if depth < dmax && !children.is_empty() && area <= smax * h.bounds(n).surface_area() {
            stack.extend(children.iter().filter(|&&c| !h.bounds(c).is_empty()).map(|&c| (c, depth + 1)));
        } else {
            out.push(*h.bounds(n));
        }
    }
    out
}

/// Marks the virtual leaves: real leaves, and the topmost interior nodes
/// whose subtree has fewer than `max_triangles` triangles (0 disables).
pub fn virtual_leaves(h: &Hierarchy, subtree_triangles: &[u64], max_triangles: u64) -> Vec<bool> {
    let mut is_leaf: Vec<bool> = (0..h.node_count() as NodeId).map(|n| h.is_leaf(n)).collect();
    if max_triangles == 0 {
        return is_leaf;
    }
    let mut stack = vec![h.root()];
    while let Some(n) = stack.pop() {
        if subtree_triangles[n as usize] < max_triangles {
            is_leaf[n as usize] = true;
        } else {
            stack.extend_from_slice(h.children(n));
        }
    }
    is_leaf
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hierarchy::{BuildOptions, HierarchyKind};
    use crate::scene::{Mesh, Scene};
    use glam::{Mat4, Vec3};

    fn row_of_boxes(n: usize) -> Scene {
        let mut s = Scene::new("row");
        let m = s.add_mesh(Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE], vec![0, 1, 2, 1, 3, 2]));
        for i in 0..n {
            s.add_instance(m, Mat4::from_translation(Vec3::new(i as f32 * 10.0, 0.0, 0.0)), 0);
        }
        s
    }

    #[test]
    fn tight_boxes_cover_the_node_content_and_are_smaller() {
        let scene = row_of_boxes(16);
        let h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions { leaf_size: 1, ..Default::default() });
        let boxes = tight_boxes(&h, h.root(), 3, 1.4);
        assert!(boxes.len() > 1);
        let area: f32 = boxes.iter().map(Aabb::surface_area).sum();
        assert!(area < h.bounds(h.root()).surface_area());
        for inst in &scene.instances {
            assert!(boxes.iter().any(|b| b.union(&inst.bounds) == *b), "instance box not covered");
        }
        assert_eq!(tight_boxes(&h, h.root(), 0, 1.4), vec![*h.bounds(h.root())]);
    }

    #[test]
    fn virtual_leaves_stop_at_small_subtrees() {
        let scene = row_of_boxes(16);
        let h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions { leaf_size: 1, ..Default::default() });
        let tris = crate::methods::subtree_triangles(&scene, &h);
        let plain = virtual_leaves(&h, &tris, 0);
        let coarse = virtual_leaves(&h, &tris, 9);
        assert_eq!(plain.iter().filter(|&&l| l).count(), 16);
        assert!(!coarse[h.root() as usize] && coarse.iter().filter(|&&l| l).count() > 16);
    }
}
