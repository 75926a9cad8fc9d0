//! [`QueryBackend`]: the [`Backend`] interface over a renderer's own wgpu
//! device, depth buffer and draws, for the query-driven methods (CHC paper,
//! section 3: queries are issued into the command stream between draws and
//! read back later, without stalling until a result is needed).
//!
//! A frame is recorded as a list of ops (a run of the renderer's draws, or
//! one occlusion query over boxes) and submitted as one render pass when a
//! query's result is asked for, when the next query needs another query set,
//! or when the frame ends. The frame's first pass clears the renderer's
//! attachments; the passes after it load them.

use super::EmbedError;
use crate::context::GpuContext;
use crate::pipelines::{bind_group, build_pipeline, Targets, Variant, QUERY};
use crate::queries::{encode_resolve, QUERIES_PER_SET};
use crate::query_book::QueryBook;
use crate::query_boxes::{box_index_buffer, camera_buffer, write_camera, BoxRows, BOX_INDEX_COUNT};
use occlude_core::query_box::{query_boxes, QUERY_DEPTH_BIAS};
use occlude_core::{Aabb, Backend, Camera, FrameCounter, FrameStats, QueryHandle, RenderState, Scene};
use std::ops::Range;
use std::time::Instant;

/// The renderer's attachments and depth test, which occlude's query boxes
/// must match to be drawn in the renderer's passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Attachments {
    /// Format of the colour attachment the renderer draws into, or `None`
    /// for depth-only passes. Occlude's query pipeline writes no colour but
    /// must name the pass's colour format. One colour attachment at most.
    pub color: Option<wgpu::TextureFormat>,
    /// Format of the depth attachment (`Depth32Float`, `Depth24Plus`, a
    /// depth-stencil format: any with a depth aspect).
    pub depth: wgpu::TextureFormat,
    /// The renderer's depth test: `Less` or `LessEqual` (depth 0 nearest,
    /// cleared to 1), or `Greater` or `GreaterEqual` (reverse Z: depth 1
    /// nearest, cleared to 0). Query boxes are tested with the same
    /// function and drawn without depth or colour writes.
    pub compare: wgpu::CompareFunction,
    /// Samples per pixel of the colour and depth attachments: 1, or the
    /// MSAA count. Occlude's tests then count a pixel where any of its
    /// samples may be visible.
    pub samples: u32,
}

impl Attachments {
    /// Whether depth 1 is nearest (the depth test is `Greater` or
    /// `GreaterEqual`).
    pub fn reverse_z(&self) -> bool {
        matches!(self.compare, wgpu::CompareFunction::Greater | wgpu::CompareFunction::GreaterEqual)
    }

    /// The farthest depth, which the frame's first pass clears to.
    pub fn far_depth(&self) -> f32 {
        if self.reverse_z() {
            0.0
        } else {
            1.0
        }
    }

    /// Whether a culling method can test against this depth buffer.
    pub(super) fn check(&self) -> Result<(), EmbedError> {
        use wgpu::CompareFunction::{Greater, GreaterEqual, Less, LessEqual};
        if !self.depth.has_depth_aspect() {
            return Err(EmbedError::Attachments(format!("{:?} is not a depth format", self.depth)));
        }
        if !matches!(self.compare, Less | LessEqual | Greater | GreaterEqual) {
            return Err(EmbedError::Attachments(format!(
                "depth test {:?} does not order depths (use Less, LessEqual, Greater or GreaterEqual)",
                self.compare
            )));
        }
        if !self.samples.is_power_of_two() || self.samples > 32 {
            return Err(EmbedError::Attachments(format!("{} samples per pixel (use 1, 2, 4, 8 or 16)", self.samples)));
        }
        Ok(())
    }
}

/// The views one frame draws into, as the renderer made them: views of
/// whole 2D textures of the same size and sample count, in the formats of
/// its [`Attachments`] (a colour view may be the sRGB or linear twin of the
/// colour format). [`FrameTarget::new`] makes one with no resolve target,
/// drawing into the whole target.
#[derive(Clone, Copy, Debug)]
pub struct FrameTarget<'a> {
    /// The colour view, when [`Attachments::color`] names a format.
    pub color: Option<&'a wgpu::TextureView>,
    /// The colour the frame's first pass clears `color` to.
    pub clear_color: wgpu::Color,
    /// The depth view; the frame's first pass clears it to
    /// [`Attachments::far_depth`].
    pub depth: &'a wgpu::TextureView,
    /// With MSAA, the single-sample view each of occlude's passes resolves
    /// the colour into (its last pass leaves the frame's image there); or
    /// `None`, to resolve in a pass of your own.
    pub resolve: Option<&'a wgpu::TextureView>,
    /// The rectangle of the views the frame draws into, or `None` for the
    /// whole target. Its size is the frame's ([`Backend::resolution`]);
    /// your projection maps to it.
    pub viewport: Option<Viewport>,
}

/// A rectangle of pixels of a target: the viewport of a [`FrameTarget`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Viewport {
    /// The left column.
    pub x: u32,
    /// The top row.
    pub y: u32,
    /// Columns, at least 1.
    pub width: u32,
    /// Rows, at least 1.
    pub height: u32,
}

impl<'a> FrameTarget<'a> {
    /// The whole of `color` (if any) and `depth`, the colour cleared to
    /// `clear_color`, no resolve target.
    pub fn new(color: Option<&'a wgpu::TextureView>, clear_color: wgpu::Color, depth: &'a wgpu::TextureView) -> Self {
        Self { color, clear_color, depth, resolve: None, viewport: None }
    }

    /// The rectangle drawn into: the viewport, or the whole depth texture.
    pub(super) fn area(&self) -> Viewport {
        let texture = self.depth.texture();
        self.viewport.unwrap_or(Viewport { x: 0, y: 0, width: texture.width(), height: texture.height() })
    }

    /// Width and height of the rectangle drawn into, in pixels.
    pub(super) fn size(&self) -> (u32, u32) {
        let area = self.area();
        (area.width, area.height)
    }

    /// Whether the views are what `attachments` says and of one size, so
    /// that occlude's passes on them are valid.
    pub(super) fn check(&self, attachments: &Attachments) -> Result<(), EmbedError> {
        let depth = self.depth.texture();
        let wrong = |what: String| Err(EmbedError::Attachments(what));
        if depth.format() != attachments.depth {
            return wrong(format!("the depth view is {:?}, not {:?}", depth.format(), attachments.depth));
        }
        let color = self.color.map(|v| v.texture());
        let same = |a: wgpu::TextureFormat, b: wgpu::TextureFormat| a.remove_srgb_suffix() == b.remove_srgb_suffix();
        match (color, attachments.color) {
            (None, None) => {}
            (Some(c), Some(format)) if same(c.format(), format) => {
                if c.size() != depth.size() || c.sample_count() != depth.sample_count() {
                    return wrong(format!(
                        "the colour view ({:?}, {} samples) is not the depth view's size ({:?}) and samples ({})",
                        c.size(),
                        c.sample_count(),
                        depth.size(),
                        depth.sample_count()
                    ));
                }
            }
            (c, format) => {
                return wrong(format!("the colour view is {:?}, not {:?}", c.map(|c| c.format()), format));
            }
        }
        if depth.sample_count() != attachments.samples || depth.dimension() != wgpu::TextureDimension::D2 {
            return wrong(format!(
                "the depth view is not of a 2D texture of {} samples (it has {})",
                attachments.samples,
                depth.sample_count()
            ));
        }
        if let Some(resolve) = self.resolve.map(|v| v.texture()) {
            let fits = color.is_some_and(|c| same(c.format(), resolve.format()))
                && resolve.size() == depth.size()
                && resolve.sample_count() == 1
                && attachments.samples > 1;
            if !fits {
                return wrong(format!(
                    "the resolve view ({:?}, {:?}, {} samples) is not a single-sample twin of a multisampled colour view",
                    resolve.format(),
                    resolve.size(),
                    resolve.sample_count()
                ));
            }
        }
        let area = self.area();
        let inside = area.width > 0
            && area.height > 0
            && u64::from(area.x) + u64::from(area.width) <= u64::from(depth.width())
            && u64::from(area.y) + u64::from(area.height) <= u64::from(depth.height());
        if !inside {
            return wrong(format!("the viewport {area:?} is empty or leaves the {:?} target", depth.size()));
        }
        Ok(())
    }
}

/// A recorded command, waiting for the next submission.
#[derive(Clone, Debug)]
enum Op {
    /// The renderer's draw callback over these entries of the draw list.
    Draw(Range<usize>),
    /// Occlusion query `slot` over these rows of the box buffer.
    Query { slot: u32, boxes: Range<u32> },
}

/// The query-driven culling state kept from frame to frame on a renderer's
/// device: the query pipeline matching its [`Attachments`], query sets,
/// read-back buffers, the query boxes' buffer and the frame's counts.
/// [`QueryBackend::frame`] lends it, with a frame's views and the
/// renderer's draw callback, as the [`Backend`] a method renders one frame
/// on.
pub struct QueryBackend {
    ctx: GpuContext,
    attachments: Attachments,
    pipeline: wgpu::RenderPipeline,
    camera_buffer: wgpu::Buffer,
    box_indices: wgpu::Buffer,
    boxes: BoxRows,
    group: wgpu::BindGroup,
    book: QueryBook,
    /// Triangles of each instance, for the frame's statistics.
    triangles: Vec<u64>,
    /// Material of each instance: a switch between them is a state change.
    materials: Vec<u32>,
    ops: Vec<Op>,
    /// The instances of the recorded draws, in order.
    listed: Vec<u32>,
    camera: Option<Camera>,
    cleared: bool,
    count: FrameCounter,
    frame_start: Instant,
}

impl QueryBackend {
    /// Culling state on the renderer's `device` and `queue` (cloned: wgpu's
    /// handles are reference-counted, so the renderer keeps its own), for
    /// the instances of `scene` (their bounds, triangles and materials;
    /// [`Scene::from_bounds`] makes one from boxes alone), drawn into
    /// `attachments`. Attachments that no method can test against are an
    /// error.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        attachments: Attachments,
        scene: &Scene,
    ) -> Result<Self, EmbedError> {
        attachments.check()?;
        let ctx = GpuContext::from_device(device, queue);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("occlude query boxes"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../shader.wgsl").into()),
        });
        let targets = Targets { color: attachments.color, depth: attachments.depth, samples: attachments.samples };
        let variant = Variant { label: "embedded query boxes", compare: attachments.compare, ..QUERY };
        let pipeline = build_pipeline(device, None, &module, targets, variant);
        let camera_buffer = camera_buffer(device);
        let boxes = BoxRows::new(device);
        let group = query_group(device, &pipeline, &camera_buffer, &boxes.buffer);
        Ok(Self {
            attachments,
            pipeline,
            camera_buffer,
            box_indices: box_index_buffer(device),
            boxes,
            group,
            book: QueryBook::default(),
            triangles: (0..scene.instances.len()).map(|i| scene.instance_triangles(i)).collect(),
            materials: scene.instances.iter().map(|i| i.material).collect(),
            ops: Vec::new(),
            listed: Vec::new(),
            camera: None,
            cleared: false,
            count: FrameCounter::new(scene.instances.len()),
            frame_start: Instant::now(),
            ctx,
        })
    }

    /// Takes the triangle counts of the `changed` instances of `scene` (0
    /// while hidden) for the frames' statistics.
    pub fn update_instances(&mut self, scene: &Scene, changed: &[u32]) {
        for &i in changed {
            self.triangles[i as usize] = scene.instance_triangles(i as usize);
        }
    }

    /// The attachments the query pipeline was built for.
    pub fn attachments(&self) -> Attachments {
        self.attachments
    }

    /// The [`Backend`] of one frame: this state, drawing into `target`, the
    /// renderer's instances drawn by `draw`. `draw(pass, instances)` is
    /// called inside occlude's render passes with the instances to draw (in
    /// order, possibly several times a frame); it must set its own pipeline,
    /// bind groups and buffers each time, since occlude's query boxes are
    /// drawn in the same pass between calls, and begin no occlusion query
    /// of its own. Views that are not what the [`Attachments`] say are an
    /// error.
    pub fn frame<'a, F>(&'a mut self, target: FrameTarget<'a>, draw: F) -> Result<EmbeddedFrame<'a, F>, EmbedError>
    where
        F: FnMut(&mut wgpu::RenderPass<'_>, &[u32]),
    {
        target.check(&self.attachments)?;
        Ok(EmbeddedFrame { state: self, target, draw })
    }
}

/// How a render pass of a frame begins on the renderer's views.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum PassStart {
    /// Clears them (colour to its clear colour, depth to
    /// [`Attachments::far_depth`], stencil to 0): the frame's first pass.
    Clear,
    /// Loads them, to draw on.
    Load,
    /// The depth view alone, read-only (no colour attachment): box tests,
    /// which test against the depth and write neither depth nor colour.
    TestDepth,
}

/// Begins a render pass of a frame on the renderer's views in `target`,
/// as `start` says; its occlusion queries go to `queries`.
pub(super) fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &FrameTarget<'_>,
    attachments: &Attachments,
    start: PassStart,
    queries: Option<&wgpu::QuerySet>,
) -> wgpu::RenderPass<'e> {
    let (color_load, depth_load, stencil_load) = if start == PassStart::Clear {
        (wgpu::LoadOp::Clear(target.clear_color), wgpu::LoadOp::Clear(attachments.far_depth()), wgpu::LoadOp::Clear(0))
    } else {
        (wgpu::LoadOp::Load, wgpu::LoadOp::Load, wgpu::LoadOp::Load)
    };
    // Read-only aspects have no operations.
    let writes = start != PassStart::TestDepth;
    let stencil = (writes && attachments.depth.has_stencil_aspect())
        .then_some(wgpu::Operations { load: stencil_load, store: wgpu::StoreOp::Store });
    // Depth-only attachments: no colour slot at all, as a depth-only
    // pipeline (no fragment stage, no targets) expects; `[None]` would not
    // match it.
    let color = [target.color.filter(|_| writes).map(|view| wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: target.resolve,
        ops: wgpu::Operations { load: color_load, store: wgpu::StoreOp::Store },
    })];
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("occlude embedded frame"),
        color_attachments: if color[0].is_some() { &color } else { &[] },
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: target.depth,
            depth_ops: writes.then_some(wgpu::Operations { load: depth_load, store: wgpu::StoreOp::Store }),
            stencil_ops: stencil,
        }),
        timestamp_writes: None,
        occlusion_query_set: queries,
        multiview_mask: None,
    });
    if let Some(v) = target.viewport {
        pass.set_viewport(v.x as f32, v.y as f32, v.width as f32, v.height as f32, 0.0, 1.0);
    }
    pass
}

/// The bind group of the query pipeline: the camera and the boxes.
fn query_group(
    device: &wgpu::Device,
    pipeline: &wgpu::RenderPipeline,
    camera: &wgpu::Buffer,
    boxes: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let layout = pipeline.get_bind_group_layout(0);
    // Bindings as in shader.wgsl (the transforms, binding 1, are unused).
    bind_group(device, "embedded queries", &layout, &[(0, camera.as_entire_binding()), (2, boxes.as_entire_binding())])
}

/// Writes the query boxes' camera uniform (`Camera` of `shader.wgsl`) for
/// `camera` as the renderer draws with it: its own projection times view
/// (reverse Z as it is; for a look-at camera
/// [`Camera::view_projection`]), the boxes pulled towards the eye by
/// [`QUERY_DEPTH_BIAS`] in the attachments' depth order.
pub(super) fn write_query_camera(
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    camera: &Camera,
    attachments: &Attachments,
) {
    let clip = match camera.matrices {
        Some(m) => m.projection * m.view,
        None => camera.view_projection(),
    };
    let bias = if attachments.reverse_z() { -QUERY_DEPTH_BIAS } else { QUERY_DEPTH_BIAS };
    write_camera(queue, buffer, &clip, bias);
}

/// One frame of a [`QueryBackend`] in a renderer's views, with its draw
/// callback: the [`Backend`] that [`occlude_core::render_frame`] renders a
/// method's frame on. Made by [`QueryBackend::frame`].
pub struct EmbeddedFrame<'a, F> {
    state: &'a mut QueryBackend,
    target: FrameTarget<'a>,
    draw: F,
}

impl<F> EmbeddedFrame<'_, F>
where
    F: FnMut(&mut wgpu::RenderPass<'_>, &[u32]),
{
    /// Pixels of the image: what a query that cannot be answered reports,
    /// so that a failure never hides geometry.
    fn all_pixels(&self) -> u64 {
        let (width, height) = self.target.size();
        u64::from(width) * u64::from(height)
    }

    /// Submits everything recorded as one render pass (the frame's first
    /// clears the attachments), its queries resolved and mapped for
    /// reading. A frame that recorded nothing still gets a pass, which
    /// clears them.
    fn flush(&mut self) {
        let Self { state: s, target, draw } = self;
        if s.ops.is_empty() && s.cleared {
            return;
        }
        if s.boxes.upload(&s.ctx.device, &s.ctx.queue) {
            s.group = query_group(&s.ctx.device, &s.pipeline, &s.camera_buffer, &s.boxes.buffer);
        }
        let pending = s.book.take_pending();
        let set = pending.map(|p| s.book.set(&s.ctx, p.set).clone());
        let mut encoder = s.ctx.device.create_command_encoder(&Default::default());
        {
            let start = if s.cleared { PassStart::Load } else { PassStart::Clear };
            let mut pass = begin_pass(&mut encoder, target, &s.attachments, start, set.as_ref());
            // The query pipeline is bound again after each of the
            // renderer's draws, which bind their own.
            let mut bound = false;
            for op in &s.ops {
                match op {
                    Op::Draw(range) => {
                        draw(&mut pass, &s.listed[range.clone()]);
                        bound = false;
                    }
                    Op::Query { slot, boxes } => {
                        if !bound {
                            pass.set_pipeline(&s.pipeline);
                            pass.set_bind_group(0, &s.group, &[]);
                            pass.set_index_buffer(s.box_indices.slice(..), wgpu::IndexFormat::Uint32);
                            bound = true;
                        }
                        pass.begin_occlusion_query(slot % QUERIES_PER_SET);
                        pass.draw_indexed(0..BOX_INDEX_COUNT, 0, boxes.clone());
                        pass.end_occlusion_query();
                    }
                }
            }
        }
        s.cleared = true;
        let readback = pending.zip(set.as_ref()).map(|(p, set)| {
            let readback = s.book.readback(&s.ctx);
            let bytes = encode_resolve(&mut encoder, set, p.first, p.count, &readback);
            (readback, bytes)
        });
        s.ctx.queue.submit([encoder.finish()]);
        s.ops.clear();
        s.listed.clear();
        s.boxes.clear();
        if let Some((readback, bytes)) = readback {
            s.book.submitted(readback, bytes);
        }
    }

    /// The query's value once its submission is read (submitting it first
    /// if it is only recorded); `block` waits for it, and a wait that fails
    /// answers every pixel.
    fn answer(&mut self, query: QueryHandle, block: bool) -> Option<u64> {
        if self.state.book.is_recorded(query) {
            self.flush();
        }
        let unknown = self.all_pixels();
        self.state.book.poll(&self.state.ctx, query, block, unknown)
    }
}

impl<F> Backend for EmbeddedFrame<'_, F>
where
    F: FnMut(&mut wgpu::RenderPass<'_>, &[u32]),
{
    /// Starts the frame. A camera whose depth order is not the
    /// attachments' ([`Camera::from_matrices`]' `reverse_z` against
    /// [`Attachments::reverse_z`]) fails the backend ([`Backend::failure`]),
    /// and every query of the frame then counts as visible.
    fn begin_frame(&mut self, camera: &Camera) {
        let s = &mut *self.state;
        s.book.settle(&s.ctx);
        let reverse_z = camera.matrices.is_some_and(|m| m.reverse_z);
        if reverse_z != s.attachments.reverse_z() {
            s.ctx.fail(format!(
                "the camera's reverse_z is {reverse_z} but the depth test {:?} is {}",
                s.attachments.compare,
                if s.attachments.reverse_z() { "reverse Z" } else { "forward Z" }
            ));
        }
        write_query_camera(&s.ctx.queue, &s.camera_buffer, camera, &s.attachments);
        s.camera = Some(*camera);
        s.cleared = false;
        s.book.start_frame();
        s.count.begin_frame();
        s.frame_start = Instant::now();
    }

    fn draw(&mut self, instances: &[u32]) {
        let s = &mut *self.state;
        for &i in instances {
            s.count.set_state(RenderState::Material(s.materials[i as usize]));
            s.count.draw(i, s.triangles[i as usize]);
        }
        let start = s.listed.len();
        s.listed.extend_from_slice(instances);
        match s.ops.last_mut() {
            Some(Op::Draw(range)) if range.end == start => range.end = s.listed.len(),
            _ => s.ops.push(Op::Draw(start..s.listed.len())),
        }
    }

    fn traverse(&mut self, nodes: u64) {
        self.state.count.traverse(nodes);
    }

    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
        let camera = self.state.camera.expect("issue_query outside a frame");
        self.state.count.query(boxes.len());
        let padded = query_boxes(&camera, boxes).filter(|_| self.state.ctx.failure().is_none());
        let Some(padded) = padded else {
            let all = self.all_pixels();
            return self.state.book.answered(all);
        };
        if self.state.book.starts_new_set() {
            self.flush();
        }
        let s = &mut *self.state;
        let (handle, slot) = s.book.record();
        let rows = s.boxes.push(&padded, 0.0);
        s.ops.push(Op::Query { slot, boxes: rows });
        handle
    }

    fn is_available(&mut self, query: QueryHandle) -> bool {
        self.answer(query, false).is_some()
    }

    /// Waits for the query's submission to be read (a blocking poll of
    /// the renderer's device), counting the wait.
    fn result(&mut self, query: QueryHandle) -> u64 {
        let unknown = self.all_pixels();
        self.answer(query, true).unwrap_or(unknown)
    }

    fn resolution(&self) -> (u32, u32) {
        self.target.size()
    }

    /// Submits the rest of the frame and waits for the read-backs still in
    /// flight (not for the renderer's draws to finish). The statistics'
    /// GPU times are zero: the renderer's device may lack timestamps, and
    /// its passes are its own to time.
    fn end_frame(&mut self) -> FrameStats {
        self.flush();
        let s = &mut *self.state;
        let cpu_end = s.frame_start.elapsed();
        s.book.settle(&s.ctx);
        let mut stats = s.count.stats;
        stats.frame_ms = s.frame_start.elapsed().as_secs_f64() * 1e3;
        stats.cpu_ms = cpu_end.saturating_sub(s.book.wait).as_secs_f64() * 1e3;
        stats.wait_ms = s.book.wait.as_secs_f64() * 1e3;
        stats.wall_ms = stats.frame_ms;
        s.camera = None;
        stats
    }

    fn failure(&self) -> Option<String> {
        self.state.ctx.failure()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attachments_need_a_depth_format_and_an_ordering_test() {
        use wgpu::CompareFunction::{Always, Equal, GreaterEqual, Less};
        use wgpu::TextureFormat::{Depth24Plus, Depth24PlusStencil8, Depth32Float, Rgba8Unorm};
        let ok = |depth, compare| Attachments { color: None, depth, compare, samples: 1 }.check().is_ok();
        assert!(ok(Depth32Float, Less) && ok(Depth24Plus, GreaterEqual) && ok(Depth24PlusStencil8, Less));
        assert!(!ok(Rgba8Unorm, Less) && !ok(Depth32Float, Always) && !ok(Depth32Float, Equal));
        let reverse = Attachments { color: None, depth: Depth32Float, compare: GreaterEqual, samples: 1 };
        assert!(reverse.reverse_z() && reverse.far_depth() == 0.0);
        let forward = Attachments { compare: Less, ..reverse };
        assert!(!forward.reverse_z() && forward.far_depth() == 1.0);
    }
}
