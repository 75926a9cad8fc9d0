//! [`WgpuBackend`]: the [`Backend`] interface on a real GPU.
//!
//! Draws and queries are recorded on the CPU and submitted together when a
//! query result or a list's length is asked for (as an OpenGL driver flushes
//! on `glGetQueryObject`) or the frame ends. Consecutive draws and queries
//! share a render pass; the GPU-resident culling commands ([`GpuCulling`],
//! module `culling`) put their compute passes between render passes, so that
//! everything runs in the order recorded. Each submission's query results
//! are resolved into a buffer and mapped with `map_async`: "is it
//! available?" polls the device without blocking, "give me the result"
//! waits, and that wait is the frame's wait time (CHC paper, section 3).
//!
//! wgpu promises an occlusion query's count only as zero or not zero
//! (Vulkan without the precise flag); lavapipe counts exactly. Only `chc`
//! with `nvp` above 0, an approximate method, reads more than that.
//! [`QueryMode::Hib`] counts exactly on any adapter that runs GPU-resident
//! culling.

use crate::context::GpuContext;
use crate::culling::{CullOp, Culling, CullingScene};
use crate::item_buffer::ItemPass;
use crate::queries::{encode_resolve, GpuTimes, PassKind, PassTimer, QUERIES_PER_SET};
use crate::query_book::{Pending, QueryBook};
use crate::query_boxes::{camera_buffer, write_camera, BoxRows, BOX_INDEX_COUNT};
use crate::scene_buffers::GpuScene;
use crate::target::RenderTarget;
use occlude_core::query_box::{query_boxes, QUERY_DEPTH_BIAS};
use occlude_core::{
    Aabb, Backend, BoxSet, Camera, ExpandInto, Flags, FrameCounter, FrameStats, GpuCulling, GpuCullingUnsupported,
    IdList, Instruments, ItemCounts, ItemLayout, ItemRange, OracleView, Pyramid, QueryHandle, QueryMode, RangeTable,
    RenderState, Scene,
};
use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;

/// Background of the colour image.
const CLEAR_COLOR: wgpu::Color = wgpu::Color { r: 0.62, g: 0.74, b: 0.86, a: 1.0 };

/// A recorded command, waiting for the next submission.
#[derive(Clone, Debug)]
enum Op {
    /// Draw one instance.
    Draw(u32),
    /// Occlusion query `slot` over boxes of the box buffer.
    BoxQuery { slot: u32, boxes: Range<u32> },
    /// Occlusion query `slot` over an instance drawn with depth test equal.
    EqualQuery { slot: u32, instance: u32 },
    /// Counted query `slot` ([`QueryMode::Hib`]) over boxes of the box
    /// buffer: no occlusion query, its fragments count themselves.
    CountedQuery { slot: u32, boxes: Range<u32> },
    /// A GPU-resident culling command: a compute pass, and for box tests and
    /// list draws a draw in the render pass after it.
    Cull(CullOp),
}

impl Op {
    /// Whether the op draws in a render pass.
    fn renders(&self) -> bool {
        match self {
            Op::Cull(op) => op.draws(),
            _ => true,
        }
    }

    /// The pipeline its draw needs (for ops that render).
    fn pipeline(&self) -> Bound {
        match self {
            Op::Draw(_) => Bound::Draw,
            Op::BoxQuery { .. } => Bound::Query,
            Op::EqualQuery { .. } => Bound::Oracle,
            Op::CountedQuery { .. } => Bound::Counted,
            Op::Cull(CullOp::TestBoxes { .. }) => Bound::BoxTest,
            // List draws; the other culling ops draw nothing.
            Op::Cull(_) => Bound::ListDraw,
        }
    }

    /// What its draw does, for the frame's GPU times.
    fn pass_kind(&self) -> PassKind {
        match self.pipeline() {
            Bound::Draw | Bound::ListDraw => PassKind::Render,
            Bound::Query | Bound::Oracle | Bound::BoxTest | Bound::Counted => PassKind::Cull,
        }
    }
}

/// A part of a submission: a render pass over the draws of a range of ops,
/// or the compute work of one culling op.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Segment {
    Render(Range<usize>),
    Compute(usize),
}

/// The passes that run `ops` in order: consecutive draws share a render
/// pass, each culling op's compute pass comes before its draw. With `clear`,
/// the first segment is a render pass (which clears the target), empty if
/// need be.
fn segments(ops: &[Op], clear: bool) -> Vec<Segment> {
    let mut out = Vec::new();
    if clear && ops.first().is_none_or(|op| matches!(op, Op::Cull(_))) {
        out.push(Segment::Render(0..0));
    }
    for (k, op) in ops.iter().enumerate() {
        if matches!(op, Op::Cull(_)) {
            out.push(Segment::Compute(k));
        }
        if op.renders() {
            match out.last_mut() {
                Some(Segment::Render(r)) if r.end == k => r.end = k + 1,
                _ => out.push(Segment::Render(k..k + 1)),
            }
        }
    }
    out
}

/// What a render pass over `ops` does: all draws, all tests, or a mix.
fn pass_kind(ops: &[Op]) -> PassKind {
    let mut kinds = ops.iter().map(Op::pass_kind);
    match kinds.next() {
        Some(first) if kinds.all(|k| k == first) => first,
        _ => PassKind::Other,
    }
}

/// Which pipeline a pass has bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Bound {
    Draw,
    Query,
    Oracle,
    BoxTest,
    ListDraw,
    Counted,
}

impl Bound {
    /// Whether the pipeline's group 1 is a material's group.
    fn material_group(self) -> bool {
        matches!(self, Bound::Draw | Bound::Query | Bound::Oracle)
    }
}

/// One method's view of a [`GpuScene`]: its own render target, camera,
/// query boxes and queries, and its own copy of the scene's instances
/// (meshes shared), updated by [`Backend::update_instances`].
pub struct WgpuBackend {
    scene: Scene,
    gpu: Arc<GpuScene>,
    target: RenderTarget,
    camera_buffer: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    timer: Option<PassTimer>,
    camera: Option<Camera>,
    ops: Vec<Op>,
    boxes: BoxRows,
    book: QueryBook,
    cleared: bool,
    count: FrameCounter,
    frame_start: Instant,
    /// GPU-resident culling's resources, made by the first `create_*`.
    pub(crate) culling: Option<Culling>,
    /// The item buffer's pipelines and image, made by the first item pass.
    item_pass: Option<ItemPass>,
    query_mode: QueryMode,
    /// Counted queries' resources, made when [`QueryMode::Hib`] is chosen.
    counted: Option<CountedQueries>,
}

/// What counted queries ([`QueryMode::Hib`]) draw with: the pipeline, and
/// per query slot of a set a 64-bit count (two words, low first) that the
/// boxes' passing fragments add to, cleared before each submission and
/// copied to its read-back where hardware queries are resolved.
struct CountedQueries {
    scene: Arc<CullingScene>,
    buffer: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl WgpuBackend {
    /// A backend rendering `scene` (already uploaded as `gpu`) at `width` x
    /// `height` pixels.
    pub fn new(gpu: Arc<GpuScene>, scene: &Scene, width: u32, height: u32) -> Self {
        let ctx = Arc::clone(&gpu.ctx);
        let camera_buffer = camera_buffer(&ctx.device);
        let boxes = BoxRows::new(&ctx.device);
        let frame_group = frame_group(&gpu, &camera_buffer, &boxes.buffer);
        Self {
            scene: scene.clone(),
            target: RenderTarget::new(&ctx, width, height),
            camera_buffer,
            frame_group,
            timer: PassTimer::new(&ctx),
            gpu,
            camera: None,
            ops: Vec::new(),
            boxes,
            book: QueryBook::default(),
            cleared: false,
            count: FrameCounter::new(scene.instances.len()),
            frame_start: Instant::now(),
            culling: None,
            item_pass: None,
            query_mode: QueryMode::Hardware,
            counted: None,
        }
    }

    fn ctx(&self) -> &GpuContext {
        &self.gpu.ctx
    }

    /// The colour image of the last frame (format [`crate::COLOR_FORMAT`],
    /// the backend's size), for a viewer to draw to a window or to draw over
    /// after `end_frame`; the next frame clears it.
    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.target.color_view
    }

    /// The colour image of the last frame as RGBA8 rows, row 0 at the top,
    /// after everything submitted so far (blocking; outside the frame's
    /// clock): a screenshot.
    pub fn color_image(&mut self) -> Result<Vec<u8>, String> {
        self.settle();
        self.target.read_color(&self.gpu.ctx)
    }

    /// Width and height of the render target in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.target.width, self.target.height)
    }

    /// Answers occlusion queries in `mode` from now on. [`QueryMode::Hib`]
    /// counts each submission's queries in its render pass, every box
    /// fragment that passes the depth test adding one to its query's count
    /// with an atomic (early depth test forced), the counts read back as
    /// hardware queries' are: the same exact counts where the adapter's
    /// occlusion queries are exact, and exact where they are not. It needs
    /// what GPU-resident culling needs, and is refused otherwise.
    pub fn set_query_mode(&mut self, mode: QueryMode) -> Result<(), GpuCullingUnsupported> {
        if mode == QueryMode::Hib && self.counted.is_none() {
            self.ctx().gpu_culling_support()?;
            let scene = self.gpu.culling(&self.scene);
            let buffer = self.ctx().device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("query counts"),
                size: u64::from(QUERIES_PER_SET) * 8,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = scene.counts_group(self.ctx(), &buffer);
            self.counted = Some(CountedQueries { scene, buffer, group });
        }
        self.query_mode = mode;
        Ok(())
    }

    /// Item pass of the hierarchical item buffer (module `item_buffer`),
    /// outside any frame's clock: draws `layout`'s instances from `camera`
    /// (each object's with one instanced draw) and counts every slot's,
    /// object's and tile's visible pixels on the GPU. Its depth image
    /// replaces the backend's, as after an oracle pass. Needs compute
    /// shaders: an adapter that cannot run GPU-resident culling is refused;
    /// a failed read-back fails the backend and answers zero counts.
    pub fn item_buffer(&mut self, camera: &Camera, layout: &ItemLayout) -> Result<ItemCounts, GpuCullingUnsupported> {
        self.ctx().gpu_culling_support()?;
        self.start(camera);
        let gpu = Arc::clone(&self.gpu);
        let pass = self.item_pass.get_or_insert_with(|| ItemPass::new(&gpu, &self.target));
        let counts = pass.run(&gpu, &self.target, &self.camera_buffer, layout).unwrap_or_else(|e| {
            gpu.ctx.fail(e);
            ItemCounts::reduce(layout, vec![0; layout.bins()])
        });
        // The target holds the item pass's depth: nothing clears it before
        // it is read.
        self.cleared = true;
        self.camera = None;
        Ok(counts)
    }

    /// Pixels of the image: what a query that cannot be answered reports, so
    /// that a failure never hides geometry.
    fn all_pixels(&self) -> u64 {
        u64::from(self.target.width) * u64::from(self.target.height)
    }

    /// Starts recording a frame (or an oracle pass) seen by `camera`.
    fn start(&mut self, camera: &Camera) {
        self.settle();
        self.camera = Some(*camera);
        write_camera(&self.gpu.ctx.queue, &self.camera_buffer, &camera.view_projection(), QUERY_DEPTH_BIAS);
        if let Some(culling) = &self.culling {
            culling.set_camera(camera);
        }
        self.cleared = false;
        self.book.start_frame();
    }

    /// Records a query op, submitting first when its slot starts a new query
    /// set (a render pass has one set).
    fn record_query(&mut self, make: impl FnOnce(u32) -> Op) -> QueryHandle {
        if self.book.starts_new_set() {
            self.flush();
        }
        let (handle, slot) = self.book.record();
        self.ops.push(make(slot));
        handle
    }

    /// Submits everything recorded (render passes, and compute passes of
    /// culling between them), its queries resolved and mapped for reading. A
    /// frame that recorded nothing still gets a pass, which clears its
    /// target.
    fn flush(&mut self) {
        if self.ops.is_empty() && self.cleared {
            return;
        }
        self.upload_boxes();
        let gpu = Arc::clone(&self.gpu);
        let ctx = &gpu.ctx;
        let pending = self.book.take_pending();
        let set = pending.map(|p| self.book.set(ctx, p.set).clone());
        let ops = std::mem::take(&mut self.ops);
        let Pending { first, count, .. } = pending.unwrap_or(Pending { set: 0, first: 0, count: 0 });
        let counted = self.counted.as_ref().filter(|_| ops.iter().any(|op| matches!(op, Op::CountedQuery { .. })));
        let counted_bytes = (u64::from(first) * 8, u64::from(count) * 8);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        if let Some(c) = counted {
            encoder.clear_buffer(&c.buffer, counted_bytes.0, Some(counted_bytes.1));
        }
        for segment in segments(&ops, !self.cleared) {
            let range = match segment {
                Segment::Compute(k) => {
                    if let (Op::Cull(op), Some(culling)) = (&ops[k], self.culling.as_mut()) {
                        culling.encode_compute(&mut encoder, op, self.timer.as_mut());
                    }
                    continue;
                }
                Segment::Render(range) => range,
            };
            let load_color = if self.cleared { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(CLEAR_COLOR) };
            let load_depth = if self.cleared { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(1.0) };
            let kind = pass_kind(&ops[range.clone()]);
            let timestamp_writes = self.timer.as_mut().and_then(|t| t.render_pass(kind));
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("frame"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.target.color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: load_color, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.target.depth_view,
                    depth_ops: Some(wgpu::Operations { load: load_depth, store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes,
                occlusion_query_set: set.as_ref(),
                multiview_mask: None,
            });
            let frame = Encoding {
                gpu: &gpu,
                scene: &self.scene,
                frame: &self.frame_group,
                culling: self.culling.as_ref(),
                counted: self.counted.as_ref(),
            };
            encode_ops(&mut pass, &frame, &ops[range]);
            self.cleared = true;
        }
        let readback = (count > 0).then(|| self.book.readback(ctx));
        let bytes = match (&readback, &set, counted) {
            (Some(r), _, Some(c)) => {
                encoder.copy_buffer_to_buffer(&c.buffer, counted_bytes.0, &r.staging, 0, counted_bytes.1);
                counted_bytes.1
            }
            (Some(r), Some(set), None) => encode_resolve(&mut encoder, set, first, count, r),
            _ => 0,
        };
        ctx.queue.submit([encoder.finish()]);
        self.ops = ops;
        self.ops.clear();
        self.boxes.clear();
        if let Some(readback) = readback {
            self.book.submitted(readback, bytes);
        }
    }

    /// Writes the recorded query boxes to the box buffer, growing it (and the
    /// bind group that names it) when they do not fit.
    fn upload_boxes(&mut self) {
        let ctx = &self.gpu.ctx;
        if self.boxes.upload(&ctx.device, &ctx.queue) {
            self.frame_group = frame_group(&self.gpu, &self.camera_buffer, &self.boxes.buffer);
        }
    }

    /// The query's value once its batch is read; `block` waits for it.
    fn poll_query(&mut self, query: QueryHandle, block: bool) -> Option<u64> {
        if self.book.is_recorded(query) {
            self.flush();
        }
        let unknown = self.all_pixels();
        self.book.poll(&self.gpu.ctx, query, block, unknown)
    }

    /// Adds what the frame's box tests and list draws did, counted on the
    /// GPU, to its statistics: boxes rasterized, draw calls, triangles, and
    /// the instances that no CPU draw drew too.
    fn add_cull_stats(&mut self) {
        let Some(culling) = self.culling.as_mut() else { return };
        match culling.take_stats() {
            Ok(Some(counted)) => {
                self.count.stats.query_boxes += counted.boxes;
                self.count.stats.draw_calls += counted.draws;
                self.count.stats.indirect_draw_calls += counted.draws;
                self.count.stats.triangles += counted.triangles;
                let drawn = &counted.drawn;
                let new = (0..self.scene.instances.len())
                    .filter(|&i| !self.count.was_drawn(i) && drawn[i / 32] >> (i % 32) & 1 != 0);
                self.count.stats.visible_objects += new.count() as u64;
            }
            Ok(None) => {}
            Err(e) => self.gpu.ctx.fail(e),
        }
    }

    /// GPU-resident culling's resources, made on first use.
    fn culling(&mut self) -> &mut Culling {
        let (gpu, scene, camera_buffer, camera) = (&self.gpu, &self.scene, &self.camera_buffer, self.camera);
        let depth = &self.target.depth;
        self.culling.get_or_insert_with(|| {
            let culling = Culling::new(gpu, scene, camera_buffer, depth);
            if let Some(camera) = &camera {
                culling.set_camera(camera);
            }
            culling
        })
    }

    /// Records a culling command (one dispatch).
    fn record_cull(&mut self, op: CullOp) {
        self.count.stats.dispatches += 1;
        self.ops.push(Op::Cull(op));
    }

    /// Records a culling command that ends in an indirect draw in `state`
    /// (box tests, list draws), whose counts are read after the frame.
    fn record_indirect(&mut self, op: CullOp, state: RenderState) {
        self.count.indirect_draw(state);
        self.culling().note_counted();
        self.record_cull(op);
    }

    /// Submits what is recorded and waits until the GPU is idle and every
    /// read-back has been collected, so the next frame starts clean.
    fn settle(&mut self) {
        self.flush();
        self.book.settle(&self.gpu.ctx);
    }
}

/// The frame bind group over `camera`, the scene's transforms and `boxes`.
pub(crate) fn frame_group(gpu: &GpuScene, camera: &wgpu::Buffer, boxes: &wgpu::Buffer) -> wgpu::BindGroup {
    gpu.ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("frame"),
        layout: &gpu.pipelines.frame_layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: camera.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: gpu.transforms.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: boxes.as_entire_binding() },
        ],
    })
}

/// What a render pass draws with.
struct Encoding<'a> {
    gpu: &'a GpuScene,
    scene: &'a Scene,
    /// Group 0 of instance draws and queries.
    frame: &'a wgpu::BindGroup,
    culling: Option<&'a Culling>,
    counted: Option<&'a CountedQueries>,
}

/// Encodes the draws of `ops` into `pass`, binding pipelines, index buffers
/// and groups only when they change.
fn encode_ops(pass: &mut wgpu::RenderPass<'_>, enc: &Encoding<'_>, ops: &[Op]) {
    let gpu = enc.gpu;
    pass.set_vertex_buffer(0, gpu.vertices.slice(..));
    let mut bound: Option<Bound> = None;
    let mut frame_bound = false;
    let mut material: Option<u32> = None;
    for op in ops {
        let want = op.pipeline();
        if bound != Some(want) {
            let (pipeline, indices) = match (want, enc.culling) {
                (Bound::Draw, _) => (&gpu.pipelines.draw, &gpu.indices),
                (Bound::Query, _) => (&gpu.pipelines.query, &gpu.box_indices),
                (Bound::Oracle, _) => (&gpu.pipelines.oracle, &gpu.indices),
                (Bound::BoxTest, Some(c)) => (c.scene().test_pipeline(), &gpu.box_indices),
                (Bound::ListDraw, Some(c)) => (c.scene().list_pipeline(), &gpu.indices),
                // Culling ops are recorded only once culling exists.
                (Bound::BoxTest | Bound::ListDraw, None) => continue,
                (Bound::Counted, _) => match enc.counted {
                    Some(c) => (c.scene.count_pipeline(), &gpu.box_indices),
                    // Counted queries are recorded only once their resources exist.
                    None => continue,
                },
            };
            pass.set_pipeline(pipeline);
            if let (Bound::Counted, Some(c)) = (want, enc.counted) {
                pass.set_bind_group(1, &c.group, &[]);
            }
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            if !want.material_group() || bound.is_some_and(|b| !b.material_group()) {
                material = None;
            }
            bound = Some(want);
        }
        if want != Bound::BoxTest && !frame_bound {
            pass.set_bind_group(0, enc.frame, &[]);
            frame_bound = true;
        }
        match op {
            Op::Draw(i) | Op::EqualQuery { instance: i, .. } => {
                let group = gpu.instance_material[*i as usize];
                if material != Some(group) {
                    pass.set_bind_group(1, &gpu.material_groups[group as usize], &[]);
                    material = Some(group);
                }
                let mesh = gpu.meshes[enc.scene.instances[*i as usize].mesh as usize];
                if let Op::EqualQuery { slot, .. } = op {
                    pass.begin_occlusion_query(slot % QUERIES_PER_SET);
                }
                pass.draw_indexed(mesh.first_index..mesh.first_index + mesh.index_count, mesh.base_vertex, *i..*i + 1);
                if matches!(op, Op::EqualQuery { .. }) {
                    pass.end_occlusion_query();
                }
            }
            Op::CountedQuery { boxes, .. } => pass.draw_indexed(0..BOX_INDEX_COUNT, 0, boxes.clone()),
            Op::BoxQuery { slot, boxes } => {
                if material.is_none() {
                    // The query pipeline's layout includes the material group.
                    pass.set_bind_group(1, &gpu.material_groups[0], &[]);
                    material = Some(0);
                }
                pass.begin_occlusion_query(slot % QUERIES_PER_SET);
                pass.draw_indexed(0..BOX_INDEX_COUNT, 0, boxes.clone());
                pass.end_occlusion_query();
            }
            Op::Cull(op) => {
                if let Some(culling) = enc.culling {
                    culling.encode_draw(pass, op);
                }
                // Box tests bind their own group 0 (the raster list's boxes).
                frame_bound &= want != Bound::BoxTest;
            }
        }
    }
}

impl Backend for WgpuBackend {
    fn begin_frame(&mut self, camera: &Camera) {
        self.start(camera);
        self.count.begin_frame();
        self.frame_start = Instant::now();
    }

    fn update_instances(&mut self, scene: &Scene, changed: &[u32]) {
        self.scene.copy_instances(scene, changed);
        self.gpu.write_transforms(&self.scene, changed);
    }

    fn draw(&mut self, instances: &[u32]) {
        for &i in instances {
            let inst = &self.scene.instances[i as usize];
            if !inst.enabled {
                continue;
            }
            self.count.set_state(RenderState::Material(inst.material));
            self.count.draw(i, self.scene.instance_triangles(i as usize));
            self.ops.push(Op::Draw(i));
        }
    }

    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
        let camera = self.camera.expect("issue_query outside a frame");
        self.count.query(boxes.len());
        let Some(padded) = query_boxes(&camera, boxes) else {
            return self.book.answered(self.all_pixels());
        };
        let counted = self.query_mode == QueryMode::Hib;
        let handle = self.record_query(|slot| {
            if counted {
                Op::CountedQuery { slot, boxes: 0..0 }
            } else {
                Op::BoxQuery { slot, boxes: 0..0 }
            }
        });
        // A counted query's boxes carry its slot in the set, the count
        // their fragments add to.
        let id = match self.ops.last() {
            Some(Op::CountedQuery { slot, .. }) => f32::from_bits(slot % QUERIES_PER_SET),
            _ => 0.0,
        };
        let rows = self.boxes.push(&padded, id);
        if let Some(Op::BoxQuery { boxes, .. } | Op::CountedQuery { boxes, .. }) = self.ops.last_mut() {
            *boxes = rows;
        }
        handle
    }

    fn is_available(&mut self, query: QueryHandle) -> bool {
        self.poll_query(query, false).is_some()
    }

    fn result(&mut self, query: QueryHandle) -> u64 {
        self.poll_query(query, true).unwrap_or_else(|| self.all_pixels())
    }

    fn traverse(&mut self, nodes: u64) {
        self.count.traverse(nodes);
    }

    fn resolution(&self) -> (u32, u32) {
        self.size()
    }

    fn end_frame(&mut self) -> FrameStats {
        self.flush();
        let cpu_end = self.frame_start.elapsed();
        self.settle();
        let _ = self.ctx().device.poll(wgpu::PollType::wait_indefinitely());
        let frame = self.frame_start.elapsed();
        let gpu = Arc::clone(&self.gpu);
        let times = match self.timer.as_mut().map(|t| t.finish(&gpu.ctx)) {
            Some(Ok(times)) => times,
            Some(Err(e)) => {
                gpu.ctx.fail(e);
                GpuTimes::default()
            }
            None => GpuTimes::default(),
        };
        self.add_cull_stats();
        let mut s = self.count.stats;
        s.frame_ms = frame.as_secs_f64() * 1e3;
        s.cpu_ms = cpu_end.saturating_sub(self.book.wait).as_secs_f64() * 1e3;
        s.wait_ms = self.book.wait.as_secs_f64() * 1e3;
        s.gpu_ms = times.total;
        s.cull_ms = times.cull;
        s.render_ms = times.render;
        s.pyramid_ms = times.pyramid;
        s.late_ms = times.late;
        s.wall_ms = s.frame_ms;
        self.camera = None;
        s
    }

    fn failure(&self) -> Option<String> {
        self.ctx().failure()
    }

    fn gpu_culling(&mut self) -> Result<&mut dyn GpuCulling, GpuCullingUnsupported> {
        self.ctx().gpu_culling_support()?;
        Ok(self)
    }

    fn instruments(&mut self) -> Option<&mut dyn Instruments> {
        Some(self)
    }
}

impl Instruments for WgpuBackend {
    fn depth_image(&mut self, out: &mut Vec<f32>) {
        self.settle();
        let gpu = Arc::clone(&self.gpu);
        if let Err(e) = self.target.read_depth(&gpu.ctx, out) {
            gpu.ctx.fail(e);
            out.clear();
            out.resize(self.all_pixels() as usize, f32::NAN);
        }
    }

    fn oracle(&mut self, camera: &Camera, candidates: &[u32]) -> OracleView {
        self.start(camera);
        self.ops.extend(candidates.iter().map(|&i| Op::Draw(i)));
        let handles: Vec<QueryHandle> =
            candidates.iter().map(|&instance| self.record_query(|slot| Op::EqualQuery { slot, instance })).collect();
        let pixels = handles.into_iter().map(|h| self.result(h)).collect();
        let mut depth = Vec::new();
        self.depth_image(&mut depth);
        self.camera = None;
        OracleView::new(candidates, pixels, depth, self.target.width, self.target.height)
    }
}

/// Resources are made at once (outside frames, as the trait asks); commands
/// are recorded as ops and run at the next submission, in order with the
/// draws and queries around them.
impl GpuCulling for WgpuBackend {
    fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet {
        self.culling().create_boxes(boxes)
    }

    fn update_boxes(&mut self, boxes: BoxSet, changed: &[(u32, Aabb)]) {
        self.culling().update_boxes(boxes, changed);
    }

    fn release_all(&mut self) {
        self.culling().release_all();
    }

    fn create_flags(&mut self, len: u32) -> Flags {
        self.culling().create_flags(len)
    }

    fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList {
        self.culling().create_list(capacity, ids)
    }

    fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable {
        self.culling().create_table(ranges, items)
    }

    fn clear_flags(&mut self, flags: Flags) {
        self.record_cull(CullOp::ClearFlags(flags));
    }

    fn write_flags(&mut self, flags: Flags, set: &[bool]) {
        // Submitted first, the work recorded so far runs before the write.
        self.flush();
        self.culling().write_flags(flags, set);
    }

    fn copy_flags(&mut self, src: Flags, dst: Flags) {
        self.record_cull(CullOp::CopyFlags { src, dst });
    }

    fn test_boxes(&mut self, boxes: BoxSet, ids: IdList, flags: Flags) {
        self.record_indirect(CullOp::TestBoxes { boxes, ids, flags }, RenderState::Query);
    }

    fn expand(&mut self, src: IdList, filter: Flags, table: RangeTable, into: ExpandInto) {
        // One dispatch cannot read a buffer and write it too.
        assert!(into != ExpandInto::List(src), "expand cannot replace the list it reads (use a second list)");
        assert!(into != ExpandInto::Flags(filter), "expand cannot set the flags it filters by (use a second buffer)");
        self.record_cull(CullOp::Expand { src, filter, table, into });
    }

    fn drop_outside_frustum(&mut self, boxes: BoxSet, flags: Flags) {
        self.record_cull(CullOp::DropOutside { boxes, flags });
    }

    fn compact(&mut self, flags: Flags, unless: Option<Flags>, dst: IdList) {
        self.record_cull(CullOp::Compact { flags, unless, dst });
    }

    fn pyramid_support(&mut self) -> Result<(), GpuCullingUnsupported> {
        self.ctx().gpu_culling_support()
    }

    fn create_pyramid(&mut self) -> Pyramid {
        self.culling().create_pyramid()
    }

    /// One op whose compute pass holds a dispatch per level past level 0.
    fn build_pyramid(&mut self, pyramid: Pyramid) {
        self.count.stats.dispatches += self.culling().reductions(pyramid);
        self.ops.push(Op::Cull(CullOp::BuildPyramid(pyramid)));
    }

    fn test_boxes_pyramid(&mut self, boxes: BoxSet, ids: IdList, pyramid: Pyramid, reach: u32, flags: Flags) {
        self.culling().note_counted();
        self.record_cull(CullOp::TestPyramid { boxes, ids, pyramid, reach, flags });
    }

    fn draw_list(&mut self, list: IdList) {
        self.record_indirect(CullOp::DrawList(list), RenderState::Indirect);
    }

    fn read_count(&mut self, list: IdList) -> u32 {
        self.read_back(|c| c.read_count(list))
    }

    fn read_list(&mut self, list: IdList) -> Vec<u32> {
        self.read_back(|c| c.read_list(list))
    }

    fn read_flags(&mut self, flags: Flags) -> Vec<bool> {
        self.read_back(|c| c.read_flags(flags))
    }
}

impl WgpuBackend {
    /// Runs everything recorded, then `read` (a blocking read-back of the
    /// culling resources): the time is wait time, the call a read-back. A
    /// failed read-back fails the backend and answers the default.
    fn read_back<T: Default>(&mut self, read: impl FnOnce(&Culling) -> Result<T, String>) -> T {
        self.count.stats.readbacks += 1;
        self.flush();
        let start = Instant::now();
        let value = read(self.culling());
        self.book.wait += start.elapsed();
        value.unwrap_or_else(|e| {
            self.gpu.ctx.fail(e);
            T::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn culling_ops_split_render_passes_in_order() {
        let list = IdList(0);
        let test = Op::Cull(CullOp::TestBoxes { boxes: BoxSet(0), ids: list, flags: Flags(0) });
        let compact = Op::Cull(CullOp::Compact { flags: Flags(0), unless: None, dst: list });
        let draw_list = Op::Cull(CullOp::DrawList(list));
        let ops = [Op::Draw(0), test, compact, draw_list, Op::Draw(1)];
        use Segment::{Compute, Render};
        assert_eq!(
            segments(&ops, true),
            [Render(0..1), Compute(1), Render(1..2), Compute(2), Compute(3), Render(3..5)]
        );
        // A frame starting with culling work clears its target first.
        assert_eq!(segments(&ops[2..], true), [Render(0..0), Compute(0), Compute(1), Render(1..3)]);
        assert_eq!(segments(&ops[2..], false), [Compute(0), Compute(1), Render(1..3)]);
        assert_eq!(segments(&[], true), [Render(0..0)]);
        assert_eq!(pass_kind(&ops[3..]), PassKind::Render);
        assert_eq!(pass_kind(&ops[1..2]), PassKind::Cull);
        assert_eq!(pass_kind(&ops), PassKind::Other);
        assert_eq!(pass_kind(&[]), PassKind::Other);
    }
}
