//! Front-to-back order over hierarchy nodes: a priority queue keyed on the
//! distance from the eye to each node's box, as the CHC paper's traversal uses
//! for hierarchies other than the kD-tree (section 4.4), or to the box's
//! nearest corner, as the occupancy-map paper sorts (section 4.2).

use crate::geometry::Aabb;
use crate::hierarchy::NodeId;
use glam::Vec3;
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    distance: f32,
    node: NodeId,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.distance.total_cmp(&other.distance).then(self.node.cmp(&other.node))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// What a node's distance from the eye is measured to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SortKey {
    /// The nearest point of its box: 0 for a box around the eye, so that
    /// box comes first.
    #[default]
    NearestPoint,
    /// The nearest of its box's eight corners (the occupancy-map paper's
    /// key): a large box around the eye may come after small boxes beyond.
    NearestCorner,
}

impl SortKey {
    /// The squared distance from `eye` to `b` under this key.
    pub fn distance_squared(self, b: &Aabb, eye: Vec3) -> f32 {
        match self {
            SortKey::NearestPoint => b.distance_squared(eye),
            SortKey::NearestCorner => b.corners().iter().map(|c| c.distance_squared(eye)).fold(f32::INFINITY, f32::min),
        }
    }
}

/// Nodes popped nearest first (ties broken by node id, so the order is
/// deterministic).
#[derive(Debug, Default)]
pub struct FrontToBack {
    heap: BinaryHeap<Reverse<Entry>>,
    key: SortKey,
}

impl FrontToBack {
    /// An empty queue, nearest point first.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty queue ordered by `key`.
    pub fn by(key: SortKey) -> Self {
        Self { heap: BinaryHeap::new(), key }
    }

    /// Adds `node` whose box lies `distance_squared` from the eye.
    pub fn push(&mut self, node: NodeId, distance_squared: f32) {
        self.heap.push(Reverse(Entry { distance: distance_squared, node }));
    }

    /// Adds `node` of `hierarchy`, measured from `eye`.
    pub fn push_node(&mut self, hierarchy: &crate::hierarchy::Hierarchy, node: NodeId, eye: Vec3) {
        self.push(node, self.key.distance_squared(hierarchy.bounds(node), eye));
    }

    /// The nearest node, removed.
    pub fn pop(&mut self) -> Option<NodeId> {
        self.heap.pop().map(|Reverse(e)| e.node)
    }

    /// True when no node is waiting.
    pub fn is_empty(&self) -> bool {
        self.heap.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A large box around the eye and a small one beyond it: the nearest
    /// point puts the large box first (distance 0), the nearest corner the
    /// small one (the large box's corners are far).
    #[test]
    fn the_two_keys_order_a_box_around_the_eye_differently() {
        let eye = Vec3::ZERO;
        let around = Aabb::new(Vec3::splat(-10.0), Vec3::splat(10.0));
        let beyond = Aabb::new(Vec3::new(2.0, -0.5, -0.5), Vec3::new(3.0, 0.5, 0.5));
        assert_eq!(SortKey::NearestPoint.distance_squared(&around, eye), 0.0);
        assert_eq!(SortKey::NearestCorner.distance_squared(&around, eye), 300.0);
        assert_eq!(SortKey::NearestCorner.distance_squared(&beyond, eye), 4.5);
        for (key, first) in [(SortKey::NearestPoint, 0), (SortKey::NearestCorner, 1)] {
            let mut queue = FrontToBack::by(key);
            queue.push(0, key.distance_squared(&around, eye));
            queue.push(1, key.distance_squared(&beyond, eye));
            assert_eq!(queue.pop(), Some(first), "{key:?}");
        }
    }
}
