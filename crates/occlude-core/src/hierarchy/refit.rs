//! Keeping a hierarchy up to date while its instances move
//! ([`crate::motion`]).
//!
//! A refit recomputes the boxes of the leaves holding changed instances and
//! of their ancestors, bottom up; node ids and leaf contents stay, so every
//! method's per-node state from the last frame still means the same nodes
//! (CHC paper, section 4.4: the scene graph's own hierarchy is what makes
//! dynamic scenes cheap). Refits let boxes grow apart from the tree's
//! split decisions; [`Hierarchy::update`] measures the tree's SAH cost
//! after each refit and rebuilds when it exceeds the cost right after the
//! last build by [`UpdatePolicy::max_cost_ratio`]. A rebuild makes a new
//! tree (a new [`Version::build`]): methods then start their per-node
//! state afresh.
//!
//! A kD-tree's cells cannot move: a refit turns the leaves it touches into
//! unions of their instances' whole boxes (no longer clipped to the cell),
//! which stays conservative and loosens the tree until the next rebuild.

use super::{Hierarchy, Node, NodeId};
use crate::geometry::Aabb;
use crate::scene::Scene;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Builds made in this process, so that every tree gets a
/// [`Version::build`] of its own.
static BUILDS: AtomicU64 = AtomicU64::new(0);

/// The next build number.
pub(super) fn next_build() -> u64 {
    BUILDS.fetch_add(1, Ordering::Relaxed) + 1
}

/// Which tree, and which of its refits, a method last saw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Version {
    /// Unique per build in the process: another build means other node ids.
    pub build: u64,
    /// Refits of that build so far.
    pub refit: u64,
}

/// What the last refit changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Changes {
    /// Nodes whose box changed, in no particular order.
    pub nodes: Vec<NodeId>,
    /// Instances that moved, hid or showed, sorted.
    pub instances: Vec<u32>,
}

/// What changed in a hierarchy since a [`Version`] a method saw
/// ([`Hierarchy::since`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Since<'a> {
    /// Nothing: same tree, same boxes.
    Unchanged,
    /// Same tree (node ids keep their meaning), boxes refitted: those in
    /// the given [`Changes`], or any box when `None` (more than one refit
    /// since).
    Refit(Option<&'a Changes>),
    /// Another tree, or none seen yet: per-node state starts afresh.
    New,
}

/// When [`Hierarchy::update`] rebuilds rather than refits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UpdatePolicy {
    /// Rebuild when the refitted tree's SAH cost ([`Hierarchy::sah_cost`])
    /// exceeds the cost right after its build by this factor.
    pub max_cost_ratio: f32,
}

impl Default for UpdatePolicy {
    /// A rebuild once refits have made the tree 3 times as costly to
    /// traverse as when built. A rebuild costs its build and the methods'
    /// coherence; measured on the city with every object moving and on
    /// `traffic`, rebuilding at 1.5 made every occlusion method 5-27 %
    /// slower than at 3, and never rebuilding made CHC++ on `traffic` 12 %
    /// slower (`docs/benchmarks.md`, "Hierarchy upkeep").
    fn default() -> Self {
        Self { max_cost_ratio: 3.0 }
    }
}

/// What [`Hierarchy::update`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Upkeep {
    /// Instances changed this frame.
    pub instances: usize,
    /// Nodes whose box changed (all of them after a rebuild).
    pub nodes: usize,
    /// Nodes the refit recomputed (those of the changed instances' leaves
    /// and their ancestors): its work, for a cost model.
    pub visited: usize,
    /// Whether the tree was rebuilt.
    pub rebuilt: bool,
    /// Wall time of the refit and the rebuild.
    pub time: Duration,
}

/// Per instance, the leaves that hold it (one in a BVH, one or more in a
/// kD-tree), as offsets into one array.
#[derive(Clone, Debug, Default)]
pub(super) struct LeavesOf {
    offsets: Vec<u32>,
    leaves: Vec<NodeId>,
}

impl LeavesOf {
    fn new(h: &Hierarchy, instances: usize) -> Self {
        let mut offsets = vec![0u32; instances + 1];
        for &i in &h.items {
            offsets[i as usize + 1] += 1;
        }
        for k in 0..instances {
            offsets[k + 1] += offsets[k];
        }
        let mut fill = offsets.clone();
        let mut leaves = vec![0; h.items.len()];
        for (id, n) in h.nodes.iter().enumerate() {
            for &i in &h.items[n.first as usize..(n.first + n.count) as usize] {
                leaves[fill[i as usize] as usize] = id as NodeId;
                fill[i as usize] += 1;
            }
        }
        Self { offsets, leaves }
    }

    fn of(&self, instance: u32) -> &[NodeId] {
        let i = instance as usize;
        &self.leaves[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// A node's term of the SAH cost's sum: its area, times its instance count
/// for a leaf.
pub(super) fn weighted_area(n: &Node) -> f64 {
    if n.is_leaf() {
        area(&n.bounds) * f64::from(n.count)
    } else {
        area(&n.bounds)
    }
}

/// Surface area of a box, 0 for an empty one.
fn area(b: &Aabb) -> f64 {
    if b.is_empty() {
        0.0
    } else {
        f64::from(b.surface_area())
    }
}

impl Hierarchy {
    /// The tree and refit this hierarchy is at.
    pub fn version(&self) -> Version {
        self.version
    }

    /// What changed since a method saw `seen` (`None`: it saw nothing yet).
    pub fn since(&self, seen: Option<Version>) -> Since<'_> {
        match seen {
            Some(v) if v.build == self.version.build && v.refit == self.version.refit => Since::Unchanged,
            Some(v) if v.build == self.version.build && v.refit + 1 == self.version.refit => {
                Since::Refit(Some(&self.changes))
            }
            Some(v) if v.build == self.version.build && v.refit < self.version.refit => Since::Refit(None),
            _ => Since::New,
        }
    }

    /// The SAH cost of the tree: each interior node's surface area plus
    /// each leaf's area times its instance count, over the root's area
    /// (traversal and intersection costs 1). Empty nodes cost nothing.
    pub fn sah_cost(&self) -> f64 {
        let root = area(self.bounds(self.root()));
        if root == 0.0 {
            return 0.0;
        }
        self.area_sum / root
    }

    /// Refits the boxes of the leaves holding `changed` instances of
    /// `scene` and of their ancestors, bottom up (module documentation);
    /// records what changed for [`Self::since`] and returns how many nodes
    /// it recomputed. `scene` is the one the tree was built over, after
    /// [`Scene::apply`].
    pub fn refit(&mut self, scene: &Scene, changed: &[u32]) -> usize {
        if self.leaves_of.offsets.len() != scene.instances.len() + 1 {
            self.leaves_of = LeavesOf::new(self, scene.instances.len());
        }
        let mut dirty = Vec::new();
        for &i in changed {
            for &leaf in self.leaves_of.of(i) {
                let mut n = leaf;
                while !std::mem::replace(&mut self.dirty[n as usize], true) {
                    dirty.push(n);
                    match self.parent(n) {
                        Some(p) => n = p,
                        None => break,
                    }
                }
            }
        }
        // Children have higher ids than their parent: refit in decreasing id
        // order and every child is done before its parent. Many dirty nodes
        // are found by a scan of the flags, cheaper than sorting them.
        let visited = dirty.len();
        if visited > self.nodes.len() / 16 {
            dirty.clear();
            dirty.extend((0..self.nodes.len() as NodeId).rev().filter(|&n| self.dirty[n as usize]));
        } else {
            dirty.sort_unstable_by(|a, b| b.cmp(a));
        }
        self.changes.nodes.clear();
        for &n in &dirty {
            self.dirty[n as usize] = false;
            let bounds = if self.is_leaf(n) {
                self.instances(n)
                    .iter()
                    .fold(Aabb::EMPTY, |b, &i| b.union(&scene.instances[i as usize].culling_bounds()))
            } else {
                let [l, r] = self.node(n).children;
                self.bounds(l).union(self.bounds(r))
            };
            let node = &mut self.nodes[n as usize];
            if node.bounds != bounds {
                self.area_sum -= weighted_area(node);
                node.bounds = bounds;
                self.area_sum += weighted_area(node);
                self.changes.nodes.push(n);
            }
        }
        self.changes.instances.clear();
        self.changes.instances.extend_from_slice(changed);
        self.version.refit += 1;
        visited
    }

    /// Brings the tree up to date with `scene` after `changed` instances
    /// changed: a refit, then a rebuild if `policy` finds the refitted tree
    /// too costly, or at once if the scene's instance count is no longer
    /// the tree's.
    pub fn update(&mut self, scene: &Scene, changed: &[u32], policy: UpdatePolicy) -> Upkeep {
        let start = Instant::now();
        let mut upkeep = Upkeep { instances: changed.len(), ..Upkeep::default() };
        if self.instance_count != scene.instances.len() {
            *self = Hierarchy::build(scene, self.kind, self.options);
            upkeep.rebuilt = true;
        } else if !changed.is_empty() {
            upkeep.visited = self.refit(scene, changed);
            upkeep.nodes = self.changes.nodes.len();
            if self.sah_cost() > self.built_cost * f64::from(policy.max_cost_ratio) {
                *self = Hierarchy::build(scene, self.kind, self.options);
                upkeep.rebuilt = true;
            }
        }
        if upkeep.rebuilt {
            upkeep.nodes = self.node_count();
        }
        upkeep.time = start.elapsed();
        upkeep
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::scattered;
    use super::super::{BuildOptions, HierarchyKind};
    use super::*;
    use crate::motion::InstanceChange;
    use glam::{Mat4, Vec3};

    /// Every node box equals the union of what it holds (a fresh refit of
    /// the whole tree would change nothing) and holds its children.
    fn assert_tight_and_nested(scene: &Scene, h: &Hierarchy) {
        for (id, n) in h.nodes.iter().enumerate() {
            let expected = if n.is_leaf() {
                h.instances(id as NodeId)
                    .iter()
                    .fold(Aabb::EMPTY, |b, &i| b.union(&scene.instances[i as usize].culling_bounds()))
            } else {
                h.bounds(n.children[0]).union(h.bounds(n.children[1]))
            };
            assert_eq!(n.bounds, expected, "node {id}");
        }
    }

    fn moves(scene: &Scene, every: usize, by: Vec3) -> Vec<InstanceChange> {
        (0..scene.instances.len())
            .step_by(every)
            .map(|i| InstanceChange::Move {
                instance: i as u32,
                transform: Mat4::from_translation(by) * scene.instances[i].transform,
            })
            .collect()
    }

    /// The SAH cost kept up to date by refits is the cost summed afresh.
    #[test]
    fn the_cost_kept_by_refits_is_the_cost_summed_afresh() {
        let mut scene = scattered(400);
        let mut h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
        for step in 1..=5 {
            let changed = scene.apply(&moves(&scene, 3, Vec3::new(7.0 * step as f32, 1.0, -2.0))).unwrap();
            h.refit(&scene, &changed);
            let root = area(h.bounds(h.root()));
            let afresh = h.nodes.iter().map(weighted_area).sum::<f64>() / root;
            assert!((h.sah_cost() - afresh).abs() <= 1e-9 * afresh, "step {step}: {} against {afresh}", h.sah_cost());
            assert!(h.sah_cost() > 1.0);
        }
    }

    #[test]
    fn refit_keeps_ids_and_makes_boxes_exact_again() {
        let mut scene = scattered(400);
        let mut h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
        let (before, items) = (h.version(), h.items.clone());
        let mut changes = moves(&scene, 7, Vec3::new(30.0, -4.0, 2.0));
        changes.push(InstanceChange::Hide(3));
        let changed = scene.apply(&changes).unwrap();
        h.refit(&scene, &changed);
        assert_tight_and_nested(&scene, &h);
        assert_eq!(h.items, items, "leaf contents kept");
        assert_eq!(h.version(), Version { build: before.build, refit: 1 });
        match h.since(Some(before)) {
            Since::Refit(Some(c)) => {
                assert_eq!(c.instances, changed);
                assert!(c.nodes.contains(&0), "the root moved with its contents");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(h.since(Some(h.version())), Since::Unchanged);
        assert_eq!(h.since(None), Since::New);
        h.refit(&scene, &[]);
        assert_eq!(h.since(Some(before)), Since::Refit(None), "two refits since: any box");
        // One instance of many: few dirty nodes, refitted in sorted order
        // rather than found by a scan.
        let one = [InstanceChange::Move { instance: 5, transform: Mat4::from_translation(Vec3::splat(60.0)) }];
        let changed = scene.apply(&one).unwrap();
        let visited = h.refit(&scene, &changed);
        assert!(visited > 0 && visited <= h.node_count() / 16, "{visited} of {} nodes", h.node_count());
        assert_tight_and_nested(&scene, &h);
    }

    #[test]
    fn kd_tree_refit_stays_conservative() {
        let mut scene = scattered(300);
        let mut h = Hierarchy::build(&scene, HierarchyKind::KdTree, BuildOptions::default());
        let changed = scene.apply(&moves(&scene, 3, Vec3::new(-20.0, 9.0, 0.0))).unwrap();
        h.refit(&scene, &changed);
        for (id, n) in h.nodes.iter().enumerate() {
            if n.is_leaf() {
                for &i in h.instances(id as NodeId) {
                    if changed.binary_search(&i).is_ok() {
                        let b = scene.instances[i as usize].bounds;
                        assert_eq!(b.union(&n.bounds), n.bounds, "leaf {id} misses moved instance {i}");
                    }
                }
            } else {
                for &c in h.children(id as NodeId) {
                    assert_eq!(h.bounds(c).union(&n.bounds), n.bounds);
                }
            }
        }
    }

    #[test]
    fn update_rebuilds_when_refits_degrade_the_tree() {
        let mut scene = scattered(500);
        let mut h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
        let first = h.version();
        // A small move keeps the tree.
        let changed = scene.apply(&moves(&scene, 50, Vec3::new(0.5, 0.0, 0.0))).unwrap();
        let upkeep = h.update(&scene, &changed, UpdatePolicy::default());
        assert!(!upkeep.rebuilt && upkeep.instances == changed.len() && upkeep.nodes > 0);
        assert_eq!(h.version().build, first.build);
        // Scattering half the instances far apart degrades it: a new tree.
        let mut scatter = Vec::new();
        for i in (0..500).step_by(2) {
            let far = Vec3::new((i % 7) as f32 * 300.0, (i % 5) as f32 * 300.0, 0.0);
            scatter.push(InstanceChange::Move {
                instance: i as u32,
                transform: Mat4::from_translation(far) * scene.instances[i].transform,
            });
        }
        let changed = scene.apply(&scatter).unwrap();
        let cost_refitted = {
            let mut r = h.clone();
            r.refit(&scene, &changed);
            r.sah_cost()
        };
        let upkeep = h.update(&scene, &changed, UpdatePolicy::default());
        assert!(upkeep.rebuilt, "refitted cost {cost_refitted} kept");
        assert_ne!(h.version().build, first.build);
        assert_eq!(h.since(Some(first)), Since::New);
        assert!(h.sah_cost() < cost_refitted);
        assert_tight_and_nested(&scene, &h);
    }
}
