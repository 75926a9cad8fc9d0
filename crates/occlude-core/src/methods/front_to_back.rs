//! Front-to-back order over hierarchy nodes: a priority queue keyed on the
//! distance from the eye to each node's box, as the CHC paper's traversal uses
//! for hierarchies other than the kD-tree (section 4.4).

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

/// Nodes popped nearest first (ties broken by node id, so the order is
/// deterministic).
#[derive(Debug, Default)]
pub struct FrontToBack {
    heap: BinaryHeap<Reverse<Entry>>,
}

impl FrontToBack {
    /// An empty queue.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `node` whose box lies `distance_squared` from the eye.
    pub fn push(&mut self, node: NodeId, distance_squared: f32) {
        self.heap.push(Reverse(Entry { distance: distance_squared, node }));
    }

    /// Adds `node` of `hierarchy`, measured from `eye`.
    pub fn push_node(&mut self, hierarchy: &crate::hierarchy::Hierarchy, node: NodeId, eye: Vec3) {
        self.push(node, hierarchy.bounds(node).distance_squared(eye));
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
