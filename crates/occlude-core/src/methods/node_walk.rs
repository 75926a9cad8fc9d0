//! A top-down walk of the hierarchy on [`GpuCulling`], level by level,
//! shared by `ioc` (IOC poster, section 2: node boxes tested against the
//! occluders' depth) and `hiz.granularity=node` (node boxes tested against
//! the depth pyramid).
//!
//! Each level is one batch: the level's node boxes are tested, the
//! instances of the visible leaves are marked, and the children of the
//! visible interior nodes make the next level's list. A hidden node ends
//! the descent into its subtree. Everything stays on the device: three
//! dispatches a level (test, leaves, children), no read-back; a level's
//! list length is read on the device by the next dispatch.

use crate::gpu_culling::{BoxSet, ExpandInto, Flags, GpuCulling, IdList, ItemRange, RangeTable, TableData};
use crate::hierarchy::{Hierarchy, NodeId};

/// A box test of a level: the boxes of `BoxSet` named by `IdList`, setting
/// `Flags` where visible.
pub(crate) type NodeTest<'a> = &'a mut dyn FnMut(&mut dyn GpuCulling, BoxSet, IdList, Flags);

/// The device resources of a level-by-level walk of one hierarchy.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NodeWalk {
    /// Every node's box.
    pub(crate) boxes: BoxSet,
    /// Per node, whether its box passed this frame's test.
    pub(crate) visible: Flags,
    /// The lists of the levels below the start, used in turn.
    levels: [IdList; 2],
    /// Per node, its children (none for a leaf).
    children: RangeTable,
    /// Per node, the instances of a leaf (none for an interior node).
    pub(crate) leaf_instances: RangeTable,
}

impl NodeWalk {
    /// Uploads `h`'s node boxes and its children and leaf tables.
    pub(crate) fn new(gpu: &mut dyn GpuCulling, h: &Hierarchy) -> Self {
        let (children, leaf_instances) = walk_tables(h);
        let boxes: Vec<_> = h.nodes.iter().map(|n| n.bounds).collect();
        let nodes = h.node_count() as u32;
        Self {
            boxes: gpu.create_boxes(&boxes),
            visible: gpu.create_flags(nodes),
            levels: [gpu.create_list(nodes, &[]), gpu.create_list(nodes, &[])],
            children: gpu.create_table(&children.ranges, &children.items),
            leaf_instances: gpu.create_table(&leaf_instances.ranges, &leaf_instances.items),
        }
    }

    /// Clears the node flags, then tests `levels` levels (at least 1) from
    /// the list `start` with `test`: on every level but the last, sets in
    /// `instances` the instances of the visible leaves and descends into
    /// the children of the visible nodes. Returns the last level's list,
    /// tested (its flags in [`Self::visible`]) and not yet expanded, for the
    /// caller to gather what lies below its visible nodes.
    pub(crate) fn walk(
        &self,
        gpu: &mut dyn GpuCulling,
        start: IdList,
        levels: u32,
        test: NodeTest<'_>,
        instances: Flags,
    ) -> IdList {
        gpu.clear_flags(self.visible);
        let mut level = start;
        for i in 0..levels {
            test(gpu, self.boxes, level, self.visible);
            if i + 1 == levels {
                break;
            }
            gpu.expand(level, self.visible, self.leaf_instances, ExpandInto::Flags(instances));
            let next = self.levels[i as usize % 2];
            gpu.expand(level, self.visible, self.children, ExpandInto::List(next));
            level = next;
        }
        level
    }
}

/// The walk's tables of `h`: per node its children (none for a leaf), and
/// per node a leaf's instances (none for an interior node).
pub(crate) fn walk_tables(h: &Hierarchy) -> (TableData, TableData) {
    let n = h.node_count();
    let mut children = TableData { ranges: vec![ItemRange::default(); n], items: Vec::with_capacity(n) };
    let mut leaves = TableData { ranges: vec![ItemRange::default(); n], items: h.items.clone() };
    for id in 0..n as NodeId {
        let node = h.node(id);
        if node.is_leaf() {
            leaves.ranges[id as usize] = ItemRange { first: node.first, count: node.count };
        } else {
            children.ranges[id as usize] = ItemRange { first: children.items.len() as u32, count: 2 };
            children.items.extend_from_slice(h.children(id));
        }
    }
    (children, leaves)
}
