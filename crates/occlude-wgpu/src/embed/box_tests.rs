//! Batched box tests against a renderer's depth texture, for the embedded
//! `roc` and `ioc` ([`GpuCuller`](super::GpuCuller); IOC poster, sections
//! 1-2; nvpro's `gl_occlusion_culling`, "raster" technique), as
//! [`GpuCulling::test_boxes`](occlude_core::GpuCulling::test_boxes) runs them
//! on the wgpu backend: `cs_test_boxes` of `cull.wgsl` applies the near and
//! frustum rules and appends the boxes to test to a raster list with its
//! indirect draw's instance count; one indirect draw of that list, with
//! `vs_query_box` of `shader.wgsl` and `fs_test_box` of
//! `cull_fragments.wgsl` (forced early depth test), rasterizes the boxes in
//! a pass holding the renderer's depth view alone, read-only, tested with
//! the renderer's compare function, each fragment that passes setting its
//! box's flag.

use super::backend::{write_query_camera, PassStart};
use super::passes::Tally;
use super::{Attachments, FrameTarget};
use crate::context::GpuContext;
use crate::culling::{bind_group, storage_init};
use crate::pipelines::{build_pipeline, compute_pipeline, Targets, Variant, QUERY};
use crate::query_boxes::{box_index_buffer, camera_buffer, BOX_BYTES, BOX_INDEX_COUNT};
use occlude_core::Camera;

/// The pipelines and scratch buffers of box tests on one renderer's
/// attachments, shared by every test of a frame (they run one after the
/// other in the queue).
pub(super) struct BoxTests {
    /// `cs_test_boxes`: the frustum and near rules, the raster list.
    append: wgpu::ComputePipeline,
    /// The boxes' draw: no colour target, depth test the renderer's, no
    /// depth writes, fragments setting flags.
    raster: wgpu::RenderPipeline,
    /// `Camera` of `shader.wgsl`: the renderer's clip matrix and the depth
    /// bias pulling boxes towards the eye.
    camera: wgpu::Buffer,
    box_indices: wgpu::Buffer,
    /// The boxes to draw (`Box` of `cull.wgsl`), room for the largest set.
    list: wgpu::Buffer,
    /// `DrawIndexedIndirectArgs` of the boxes' draw, its instance count the
    /// list's length.
    draw: wgpu::Buffer,
    /// Group 0 of the boxes' draw: the camera and the list.
    draw_group: wgpu::BindGroup,
}

/// One box test's bind groups: which boxes, named by which list, set which
/// flags.
pub(super) struct BoxTest {
    append: wgpu::BindGroup,
    /// Group 1 of the boxes' draw: the flags the fragments set.
    flags: wgpu::BindGroup,
    /// The id list's capacity: threads of the append dispatch.
    capacity: u32,
}

/// The buffers of `cull.wgsl` a box test binds besides the scratch ones.
pub(super) struct TestInputs<'a> {
    /// `Cull` of `cull.wgsl`: frustum planes and near region.
    pub cull_camera: &'a wgpu::Buffer,
    /// The box set.
    pub boxes: &'a wgpu::Buffer,
    /// The list of box slots to test, and its capacity.
    pub ids: (&'a wgpu::Buffer, u32),
    /// The flags set where a box may be visible.
    pub flags: &'a wgpu::Buffer,
    /// The statistics `cs_test_boxes` counts into.
    pub stats: &'a wgpu::Buffer,
}

impl BoxTests {
    /// Box tests drawn into `attachments`, for sets of up to `capacity`
    /// boxes. `cull` is `cull.wgsl` with `cull_fragments.wgsl` appended
    /// (`crate::culling::cull_module`), which needs the device's
    /// `SHADER_EARLY_DEPTH_TEST`.
    pub fn new(ctx: &GpuContext, attachments: &Attachments, cull: &wgpu::ShaderModule, capacity: u32) -> Self {
        let device = &ctx.device;
        let boxes_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("occlude query boxes"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../shader.wgsl").into()),
        });
        let targets = Targets { color: None, depth: attachments.depth, samples: attachments.samples };
        let variant = Variant {
            label: "embedded box tests",
            fragment_entry: "fs_test_box",
            fragment_module: Some(cull),
            compare: attachments.compare,
            ..QUERY
        };
        let raster = build_pipeline(device, None, &boxes_module, targets, variant);
        let camera = camera_buffer(device);
        let list = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raster boxes"),
            size: BOX_BYTES * u64::from(capacity.max(1)),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let indirect = wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST;
        let draw = storage_init(ctx, "box-test draw", bytemuck::cast_slice(&[BOX_INDEX_COUNT, 0, 0, 0, 0]), indirect);
        // Bindings as in shader.wgsl (the transforms, binding 1, are unused).
        let draw_group = bind_group(ctx, "box tests", &raster.get_bind_group_layout(0), &[(0, &camera), (2, &list)]);
        Self {
            append: compute_pipeline(device, cull, "cs_test_boxes"),
            raster,
            camera,
            box_indices: box_index_buffer(device),
            list,
            draw,
            draw_group,
        }
    }

    /// The bind groups of a test of `inputs`.
    pub fn test(&self, ctx: &GpuContext, inputs: TestInputs<'_>) -> BoxTest {
        let append = [
            (0, inputs.cull_camera),
            (1, inputs.boxes),
            (2, inputs.ids.0),
            (3, inputs.flags),
            (4, &self.list),
            (5, &self.draw),
            (13, inputs.stats),
        ];
        BoxTest {
            append: bind_group(ctx, "box-test list", &self.append.get_bind_group_layout(0), &append),
            flags: bind_group(ctx, "box-test flags", &self.raster.get_bind_group_layout(1), &[(0, inputs.flags)]),
            capacity: inputs.ids.1,
        }
    }

    /// Sets the frame's camera, as the renderer draws with it.
    pub fn set_camera(&self, queue: &wgpu::Queue, camera: &Camera, attachments: &Attachments) {
        write_query_camera(queue, &self.camera, camera, attachments);
    }

    /// Records `test` against the depth of `target` as everything recorded
    /// before leaves it: the append dispatch, then the boxes' draw in a
    /// pass of its own; both passes counted in `tally`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        tally: &Tally,
        target: &FrameTarget<'_>,
        attachments: &Attachments,
        test: &BoxTest,
    ) {
        // Zero the draw's instance count, which the append counts up.
        encoder.clear_buffer(&self.draw, 4, Some(4));
        tally.compute_pass(encoder).dispatch(&self.append, &test.append, test.capacity);
        let mut pass = tally.render_pass(encoder, target, attachments, PassStart::TestDepth);
        pass.set_pipeline(&self.raster);
        pass.set_bind_group(0, &self.draw_group, &[]);
        pass.set_bind_group(1, &test.flags, &[]);
        pass.set_index_buffer(self.box_indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed_indirect(&self.draw, 0);
    }
}
