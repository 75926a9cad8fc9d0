//! Spatial hierarchies over scene instances.
//!
//! Both builders — a binned-SAH bounding volume hierarchy ([`bvh`]) and a
//! kD-tree with SAH splits ([`kdtree`], the structure of the CHC paper,
//! section 6.1) — produce the same binary [`Hierarchy`], so every culling
//! method is written once against it. Node boxes are always conservative: they
//! hold every point of geometry that the node's leaves can draw inside the node.

pub mod bvh;
pub mod kdtree;
mod refit;

pub use refit::{Changes, Since, UpdatePolicy, Upkeep, Version};

use crate::geometry::Aabb;
use crate::scene::Scene;
use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant};

/// Index of a node in [`Hierarchy::nodes`].
pub type NodeId = u32;

/// Marks "no node" in [`Node::children`] and [`Node::parent`].
pub const NO_NODE: NodeId = NodeId::MAX;

/// One node of a binary hierarchy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Conservative box of what the node's subtree draws inside it.
    pub bounds: Aabb,
    /// Two children, or `[NO_NODE; 2]` for a leaf.
    pub children: [NodeId; 2],
    /// Parent, `NO_NODE` for the root.
    pub parent: NodeId,
    /// First index into [`Hierarchy::items`] of a leaf's instances.
    pub first: u32,
    /// Number of a leaf's instances (0 for interior nodes).
    pub count: u32,
    /// Distance from the root.
    pub depth: u32,
}

impl Node {
    /// True for nodes without children.
    pub fn is_leaf(&self) -> bool {
        self.children[0] == NO_NODE
    }
}

/// Which builder made a hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HierarchyKind {
    /// Binned-SAH bounding volume hierarchy over instance boxes.
    Bvh,
    /// SAH kD-tree; an instance crossing a split plane is referenced by both sides.
    KdTree,
}

impl fmt::Display for HierarchyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            HierarchyKind::Bvh => "bvh",
            HierarchyKind::KdTree => "kdtree",
        })
    }
}

impl FromStr for HierarchyKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "bvh" => Ok(HierarchyKind::Bvh),
            "kdtree" | "kd" => Ok(HierarchyKind::KdTree),
            _ => Err(format!("unknown hierarchy '{s}': expected 'bvh' or 'kdtree'")),
        }
    }
}

/// A binary hierarchy over the instances of one scene.
#[derive(Clone, Debug)]
pub struct Hierarchy {
    /// Nodes; the root is node 0.
    pub nodes: Vec<Node>,
    /// Leaf instance lists, each leaf a contiguous range.
    pub items: Vec<u32>,
    /// The builder used.
    pub kind: HierarchyKind,
    /// Wall time the build took.
    pub build_time: Duration,
    /// The options it was built with (a rebuild uses them again).
    options: BuildOptions,
    /// Instances of the scene it was built over.
    instance_count: usize,
    /// Its SAH cost right after the build ([`Hierarchy::sah_cost`]).
    built_cost: f64,
    /// The weighted node areas [`Hierarchy::sah_cost`] sums, kept up to
    /// date by refits so that checking the cost costs what the refit does.
    area_sum: f64,
    version: Version,
    /// What the last refit changed.
    changes: Changes,
    /// Per instance, its leaves (built on the first refit).
    leaves_of: refit::LeavesOf,
    /// Per node, scratch of a refit.
    dirty: Vec<bool>,
}

/// Options shared by both builders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// A node with at most this many instances becomes a leaf.
    pub leaf_size: usize,
    /// Deepest level a node may have (guards kD-trees against endless splits).
    pub max_depth: u32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self { leaf_size: 4, max_depth: 48 }
    }
}

impl Hierarchy {
    /// Builds a hierarchy of `kind` over all instances of `scene`. Hidden
    /// instances are placed where they are and lie in no node box
    /// ([`crate::Instance::culling_bounds`]).
    pub fn build(scene: &Scene, kind: HierarchyKind, options: BuildOptions) -> Hierarchy {
        let start = Instant::now();
        let boxes: Vec<Aabb> = scene.instances.iter().map(|i| i.bounds).collect();
        let mut builder = TreeBuilder::default();
        match kind {
            HierarchyKind::Bvh => bvh::build(&boxes, options, &mut builder),
            HierarchyKind::KdTree => kdtree::build(&boxes, options, &mut builder),
        }
        let nodes = builder.nodes.len();
        let mut h = Hierarchy {
            nodes: builder.nodes,
            items: builder.items,
            kind,
            build_time: Duration::ZERO,
            options,
            instance_count: scene.instances.len(),
            built_cost: 0.0,
            area_sum: 0.0,
            version: Version { build: refit::next_build(), refit: 0 },
            changes: Changes::default(),
            leaves_of: Default::default(),
            dirty: vec![false; nodes],
        };
        let hidden: Vec<u32> =
            (0..scene.instances.len() as u32).filter(|&i| !scene.instances[i as usize].enabled).collect();
        if !hidden.is_empty() {
            h.refit(scene, &hidden);
            h.version.refit = 0;
            h.changes = Changes::default();
        }
        h.area_sum = h.nodes.iter().map(refit::weighted_area).sum();
        h.built_cost = h.sah_cost();
        h.build_time = start.elapsed();
        h
    }

    /// The root node.
    pub fn root(&self) -> NodeId {
        0
    }

    /// The node `id`.
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id as usize]
    }

    /// Conservative box of node `id`.
    pub fn bounds(&self, id: NodeId) -> &Aabb {
        &self.nodes[id as usize].bounds
    }

    /// True when `id` is a leaf.
    pub fn is_leaf(&self, id: NodeId) -> bool {
        self.node(id).is_leaf()
    }

    /// The children of `id` (empty for a leaf).
    pub fn children(&self, id: NodeId) -> &[NodeId] {
        let n = self.node(id);
        if n.is_leaf() {
            &[]
        } else {
            &n.children
        }
    }

    /// The parent of `id`, `None` for the root.
    pub fn parent(&self, id: NodeId) -> Option<NodeId> {
        let p = self.node(id).parent;
        (p != NO_NODE).then_some(p)
    }

    /// Instances a leaf draws (empty for interior nodes).
    pub fn instances(&self, id: NodeId) -> &[u32] {
        let n = self.node(id);
        &self.items[n.first as usize..(n.first + n.count) as usize]
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of leaves.
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }

    /// Depth of the deepest node.
    pub fn max_depth(&self) -> u32 {
        self.nodes.iter().map(|n| n.depth).max().unwrap_or(0)
    }
}

/// Collects nodes in build order; shared by both builders.
#[derive(Default)]
pub(crate) struct TreeBuilder {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

impl TreeBuilder {
    /// Appends a node with no children yet and returns its id.
    pub(crate) fn push(&mut self, bounds: Aabb, parent: NodeId, depth: u32) -> NodeId {
        self.nodes.push(Node { bounds, children: [NO_NODE; 2], parent, first: 0, count: 0, depth });
        (self.nodes.len() - 1) as NodeId
    }

    /// Makes `id` a leaf drawing `items`.
    pub(crate) fn make_leaf(&mut self, id: NodeId, items: &[u32]) {
        let n = &mut self.nodes[id as usize];
        n.first = self.items.len() as u32;
        n.count = items.len() as u32;
        self.items.extend_from_slice(items);
    }

    /// Links two children under `id`.
    pub(crate) fn set_children(&mut self, id: NodeId, children: [NodeId; 2]) {
        self.nodes[id as usize].children = children;
    }
}

/// Number of SAH bins per axis, shared by both builders.
pub(crate) const SAH_BINS: usize = 16;

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Vec3};

    /// A scene of `n` unit boxes scattered deterministically.
    pub(crate) fn scattered(n: usize) -> Scene {
        let mut s = Scene::new("scatter");
        let m =
            s.add_mesh(crate::scene::Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE], vec![0, 1, 2, 1, 3, 2]));
        let mut x = 12345u64;
        for _ in 0..n {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let p = Vec3::new((x >> 40) as f32 % 97.0, (x >> 20) as f32 % 13.0, (x >> 8) as f32 % 89.0);
            s.add_instance(
                m,
                Mat4::from_scale_rotation_translation(Vec3::splat(1.0 + (x % 5) as f32), glam::Quat::IDENTITY, p),
                0,
            );
        }
        s
    }

    fn check_invariants(scene: &Scene, h: &Hierarchy, leaf_size: usize) {
        let mut seen = vec![false; scene.instances.len()];
        for (id, n) in h.nodes.iter().enumerate() {
            if n.is_leaf() {
                for &i in h.instances(id as NodeId) {
                    seen[i as usize] = true;
                    // The leaf box holds the instance where it lies inside the node.
                    let inside = scene.instances[i as usize].bounds.intersection(&n.bounds);
                    assert!(!inside.is_empty(), "leaf {id} box misses its instance {i}");
                }
                assert!(
                    n.count as usize <= leaf_size
                        || n.depth >= BuildOptions::default().max_depth
                        || h.kind == HierarchyKind::KdTree
                );
            } else {
                for &c in h.children(id as NodeId) {
                    let child = h.node(c);
                    assert_eq!(child.parent, id as NodeId);
                    assert_eq!(child.bounds.union(&n.bounds), n.bounds, "child box outside parent");
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "an instance is in no leaf");
    }

    #[test]
    fn both_builders_cover_every_instance_with_nested_boxes() {
        let scene = scattered(500);
        for kind in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let h = Hierarchy::build(&scene, kind, BuildOptions::default());
            check_invariants(&scene, &h, 4);
            assert!(h.leaf_count() > 500 / 8, "{kind}: too few leaves: {}", h.leaf_count());
        }
    }

    #[test]
    fn bvh_references_each_instance_once() {
        let scene = scattered(300);
        let h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
        let mut items = h.items.clone();
        items.sort_unstable();
        assert_eq!(items, (0..300).collect::<Vec<u32>>());
    }

    #[test]
    fn single_instance_is_a_leaf_root() {
        let scene = scattered(1);
        for kind in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let h = Hierarchy::build(&scene, kind, BuildOptions::default());
            assert_eq!(h.node_count(), 1);
            assert_eq!(h.instances(0), &[0]);
        }
    }

    #[test]
    fn identical_boxes_still_terminate() {
        let mut scene = scattered(1);
        let inst = scene.instances[0].clone();
        scene.instances = vec![inst; 100];
        for kind in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let h = Hierarchy::build(&scene, kind, BuildOptions::default());
            check_invariants(&scene, &h, 100);
        }
    }
}
