//! `ioc`'s late test in a [`GpuCuller`](super::GpuCuller): the walk of
//! [`occlude_core::methods::ioc`] (IOC poster, section 2, Figure 2) down a
//! BVH over the renderer's boxes, level by level, recorded into the frame.
//! Each level's node boxes are box-tested against the renderer's depth
//! ([`BoxTests`]); `cs_expand_flags` marks the instances of the visible
//! leaves and `cs_expand_list` lists the children of the visible nodes for
//! the next level; at the bottom level every instance below a visible node
//! is marked. The tables and the start list are [`IocWalk`]'s, the ones
//! `ioc` uploads on the wgpu backend; the shaders are `cull.wgsl`'s.

use super::box_tests::{BoxTest, BoxTests, TestInputs};
use super::passes::Tally;
use super::{Attachments, FrameTarget};
use crate::context::GpuContext;
use crate::culling::{bind_group, box_set_buffer, storage_init, write_boxes, TableBuffers};
use crate::pipelines::compute_pipeline;
use occlude_core::methods::ioc::IocWalk;
use occlude_core::{Aabb, Hierarchy, NodeId};

/// One level of the walk: its box test and, above the bottom, its
/// expansions.
struct Level {
    test: BoxTest,
    /// Above the bottom: the group marking the visible leaves' instances in
    /// instance flag buffer 0 or 1, and the next level's list with the group
    /// listing the visible nodes' children into it.
    below: Option<([wgpu::BindGroup; 2], wgpu::Buffer, wgpu::BindGroup)>,
}

/// The device side of `ioc`'s walk of one hierarchy, made once.
pub(super) struct NodeLevels {
    expand_flags: wgpu::ComputePipeline,
    expand_list: wgpu::ComputePipeline,
    /// Per node, whether its box passed this frame's test.
    node_flags: wgpu::Buffer,
    /// Per node, its box (a box set): rewritten after a refit.
    node_boxes: wgpu::Buffer,
    /// Nodes: the threads of each expansion.
    nodes: u32,
    levels: Vec<Level>,
    /// The bottom level's groups marking every instance below its visible
    /// nodes in instance flag buffer 0 or 1.
    bottom: [wgpu::BindGroup; 2],
}

/// What the walk binds besides its own buffers.
pub(super) struct WalkInputs<'a> {
    /// `Cull` of `cull.wgsl`.
    pub cull_camera: &'a wgpu::Buffer,
    /// The instance flags, by parity: the walk sets `instance_flags[p]`.
    pub instance_flags: &'a [wgpu::Buffer; 2],
    /// The statistics `cs_test_boxes` counts into.
    pub stats: &'a wgpu::Buffer,
}

impl NodeLevels {
    /// The walk `walk` of `h` on the device, its box tests run by `tests`;
    /// `cull` is the culling module (`crate::culling::cull_module`).
    pub fn new(
        ctx: &GpuContext,
        cull: &wgpu::ShaderModule,
        tests: &BoxTests,
        h: &Hierarchy,
        walk: &IocWalk,
        inputs: WalkInputs<'_>,
    ) -> Self {
        let device = &ctx.device;
        let expand_flags = compute_pipeline(device, cull, "cs_expand_flags");
        let expand_list = compute_pipeline(device, cull, "cs_expand_list");
        let nodes = h.node_count() as u32;
        let boxes: Vec<Aabb> = h.nodes.iter().map(|n| n.bounds).collect();
        let node_boxes = box_set_buffer(ctx, &boxes);
        let node_flags =
            storage_init(ctx, "node visibility", &vec![0; 4 * nodes as usize], wgpu::BufferUsages::COPY_DST);
        let list = |ids: &[u32]| {
            let mut words = vec![ids.len() as u32, nodes];
            words.extend(ids);
            words.resize(2 + nodes as usize, 0);
            storage_init(ctx, "node level", bytemuck::cast_slice(&words), wgpu::BufferUsages::COPY_DST)
        };
        let start = list(&walk.start);
        let scratch = [list(&[]), list(&[])];
        let children = TableBuffers::new(ctx, &walk.children.ranges, &walk.children.items);
        let leaves = TableBuffers::new(ctx, &walk.leaf_instances.ranges, &walk.leaf_instances.items);
        let subtrees = TableBuffers::new(ctx, &walk.subtree_instances.ranges, &walk.subtree_instances.items);
        let flags_layout = expand_flags.get_bind_group_layout(0);
        // Groups marking the instances of `table` for the visible nodes of
        // `src`, in instance flag buffer 0 or 1.
        let mark = |src: &wgpu::Buffer, table: &TableBuffers| {
            [0, 1].map(|p| {
                let entries = [
                    (2, src),
                    (6, &node_flags),
                    (3, &inputs.instance_flags[p]),
                    (9, &table.ranges),
                    (10, &table.items),
                ];
                bind_group(ctx, "ioc marks", &flags_layout, &entries)
            })
        };
        let count = walk.depths.1 - walk.depths.0 + 1;
        let mut levels = Vec::with_capacity(count as usize);
        // The list level i tests: the start list, then the scratch lists in
        // turn.
        let mut src = &start;
        for i in 0..count {
            let test_inputs = TestInputs {
                cull_camera: inputs.cull_camera,
                boxes: &node_boxes,
                ids: (src, nodes),
                flags: &node_flags,
                stats: inputs.stats,
            };
            let test = tests.test(ctx, test_inputs);
            let below = (i + 1 < count).then(|| {
                let next = &scratch[i as usize % 2];
                let entries = [(2, src), (6, &node_flags), (8, next), (9, &children.ranges), (10, &children.items)];
                let list_group = bind_group(ctx, "ioc children", &expand_list.get_bind_group_layout(0), &entries);
                (mark(src, &leaves), next.clone(), list_group)
            });
            levels.push(Level { test, below });
            if i + 1 < count {
                src = &scratch[i as usize % 2];
            }
        }
        let bottom = mark(src, &subtrees);
        Self { expand_flags, expand_list, node_flags, node_boxes, nodes, levels, bottom }
    }

    /// Rewrites the boxes of `nodes` from `h`, refitted since the walk was
    /// made (same tree, new boxes).
    pub fn update_boxes(&self, queue: &wgpu::Queue, h: &Hierarchy, nodes: &[NodeId]) {
        let boxes: Vec<(u32, Aabb)> = nodes.iter().map(|&n| (n, *h.bounds(n))).collect();
        write_boxes(queue, &self.node_boxes, &boxes);
    }

    /// Records the walk against the depth of `target` as everything
    /// recorded before leaves it, setting instance flag buffer `now` (which
    /// it does not clear); its passes counted in `tally`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        tally: &Tally,
        tests: &BoxTests,
        target: &FrameTarget<'_>,
        attachments: &Attachments,
        now: usize,
    ) {
        encoder.clear_buffer(&self.node_flags, 0, None);
        for level in &self.levels {
            tests.encode(encoder, tally, target, attachments, &level.test);
            let Some((marks, next, children)) = &level.below else { continue };
            encoder.clear_buffer(next, 0, Some(4));
            let mut pass = tally.compute_pass(encoder);
            pass.dispatch(&self.expand_flags, &marks[now], self.nodes);
            pass.dispatch(&self.expand_list, children, self.nodes);
        }
        tally.compute_pass(encoder).dispatch(&self.expand_flags, &self.bottom[now], self.nodes);
    }
}
