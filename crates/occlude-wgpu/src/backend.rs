//! [`WgpuBackend`]: the [`Backend`] interface on a real GPU.
//!
//! Draws and queries are recorded on the CPU and submitted as one render pass
//! when a query result is asked for (as an OpenGL driver flushes on
//! `glGetQueryObject`) or the frame ends. Each submission's query results
//! are resolved into a buffer and mapped with `map_async`: "is it
//! available?" polls the device without blocking, "give me the result"
//! waits, and that wait is the frame's wait time (CHC paper, section 3).

use crate::context::GpuContext;
use crate::queries::{encode_resolve, read_values, PassTimer, QueryPool, Readback, QUERIES_PER_SET};
use crate::readback::Mapping;
use crate::scene_buffers::GpuScene;
use crate::target::RenderTarget;
use occlude_core::query_box::{query_boxes, QUERY_DEPTH_BIAS};
use occlude_core::{Aabb, Backend, Camera, FrameStats, OracleView, QueryHandle, RenderState, Scene, StateTracker};
use std::ops::Range;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Background of the colour image.
const CLEAR_COLOR: wgpu::Color = wgpu::Color { r: 0.62, g: 0.74, b: 0.86, a: 1.0 };

/// Bytes of one query box in the box buffer (min and max as `vec4`s).
const BOX_BYTES: u64 = 32;

/// A recorded command, waiting for the next submission.
#[derive(Clone, Debug)]
enum Op {
    /// Draw one instance.
    Draw(u32),
    /// Occlusion query `slot` over boxes of the box buffer.
    BoxQuery { slot: u32, boxes: Range<u32> },
    /// Occlusion query `slot` over an instance drawn with depth test equal.
    EqualQuery { slot: u32, instance: u32 },
}

/// Where a query's answer is.
#[derive(Clone, Copy, Debug)]
enum QueryState {
    /// Recorded, not yet submitted; `slot` is its place in the frame's query sets.
    Recorded { slot: u32 },
    /// Submitted with batch `batch`, at position `index` of its values.
    InFlight { batch: usize, index: usize },
    /// Read back.
    Ready(u64),
}

/// The queries of one submission, read back together.
struct Batch {
    readback: Option<Readback>,
    mapping: Mapping,
    bytes: u64,
    values: Vec<u64>,
}

/// Which pipeline a pass has bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Bound {
    Draw,
    Query,
    Oracle,
}

/// One method's view of a [`GpuScene`]: its own render target, camera,
/// query boxes and queries.
pub struct WgpuBackend<'s> {
    scene: &'s Scene,
    gpu: Arc<GpuScene>,
    target: RenderTarget,
    camera_buffer: wgpu::Buffer,
    box_buffer: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    pool: QueryPool,
    timer: Option<PassTimer>,
    camera: Option<Camera>,
    ops: Vec<Op>,
    boxes: Vec<[f32; 8]>,
    /// Query set of the recorded queries, if any are recorded.
    recorded_set: Option<u32>,
    next_slot: u32,
    queries: Vec<QueryState>,
    batches: Vec<Batch>,
    cleared: bool,
    state: StateTracker,
    stats: FrameStats,
    drawn: Vec<bool>,
    frame_start: Instant,
    wait: Duration,
}

impl<'s> WgpuBackend<'s> {
    /// A backend rendering `scene` (already uploaded as `gpu`) at `width` x
    /// `height` pixels.
    pub fn new(gpu: Arc<GpuScene>, scene: &'s Scene, width: u32, height: u32) -> Self {
        let ctx = Arc::clone(&gpu.ctx);
        let camera_buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: 80,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let box_buffer = box_buffer(&ctx, 256);
        let frame_group = frame_group(&gpu, &camera_buffer, &box_buffer);
        Self {
            scene,
            target: RenderTarget::new(&ctx, width, height),
            camera_buffer,
            box_buffer,
            frame_group,
            pool: QueryPool::default(),
            timer: PassTimer::new(&ctx),
            gpu,
            camera: None,
            ops: Vec::new(),
            boxes: Vec::new(),
            recorded_set: None,
            next_slot: 0,
            queries: Vec::new(),
            batches: Vec::new(),
            cleared: false,
            state: StateTracker::default(),
            stats: FrameStats::default(),
            drawn: vec![false; scene.instances.len()],
            frame_start: Instant::now(),
            wait: Duration::ZERO,
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

    /// Pixels of the image: what a query that cannot be answered reports, so
    /// that a failure never hides geometry.
    fn all_pixels(&self) -> u64 {
        u64::from(self.target.width) * u64::from(self.target.height)
    }

    /// Starts recording a frame (or an oracle pass) seen by `camera`.
    fn start(&mut self, camera: &Camera) {
        self.settle();
        self.camera = Some(*camera);
        let mut uniform = [0f32; 20];
        uniform[..16].copy_from_slice(&camera.view_projection().to_cols_array());
        uniform[16] = QUERY_DEPTH_BIAS;
        self.gpu.ctx.queue.write_buffer(&self.camera_buffer, 0, bytemuck::cast_slice(&uniform));
        self.cleared = false;
        self.next_slot = 0;
        self.queries.clear();
    }

    /// Records a query op, submitting first when its slot starts a new query
    /// set (a render pass has one set).
    fn record_query(&mut self, make: impl FnOnce(u32) -> Op) -> QueryHandle {
        let slot = self.next_slot;
        self.next_slot += 1;
        let set = slot / QUERIES_PER_SET;
        if self.recorded_set.is_some_and(|s| s != set) {
            self.flush();
        }
        self.recorded_set = Some(set);
        self.ops.push(make(slot));
        self.queries.push(QueryState::Recorded { slot });
        QueryHandle(self.queries.len() as u32 - 1)
    }

    /// Submits everything recorded as one render pass, its queries resolved
    /// and mapped for reading. A frame that recorded nothing still gets a
    /// pass, which clears its target.
    fn flush(&mut self) {
        if self.ops.is_empty() && self.cleared {
            return;
        }
        self.upload_boxes();
        let gpu = Arc::clone(&self.gpu);
        let ctx = &gpu.ctx;
        let set_index = self.recorded_set.take();
        let set = set_index.map(|k| self.pool.set(ctx, k as usize).clone());
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let load_color = if self.cleared { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(CLEAR_COLOR) };
            let load_depth = if self.cleared { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(1.0) };
            let timestamp_writes = self.timer.as_mut().and_then(PassTimer::next_pass);
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
            encode_ops(&mut pass, &gpu, self.scene, &self.frame_group, &self.ops);
        }
        self.cleared = true;
        let slots = self.ops.iter().filter_map(|op| match op {
            Op::BoxQuery { slot, .. } | Op::EqualQuery { slot, .. } => Some(*slot),
            Op::Draw(_) => None,
        });
        let (first, count) = match slots.clone().min() {
            Some(first) => (first, slots.count() as u32),
            None => (0, 0),
        };
        let readback = (count > 0).then(|| self.pool.readback(ctx));
        let bytes = match (&readback, &set) {
            (Some(r), Some(set)) => encode_resolve(&mut encoder, set, first % QUERIES_PER_SET, count, r),
            _ => 0,
        };
        ctx.queue.submit([encoder.finish()]);
        self.ops.clear();
        self.boxes.clear();
        if let Some(readback) = readback {
            let batch = self.batches.len();
            let mapping = Mapping::start(&readback.staging, bytes);
            self.batches.push(Batch { readback: Some(readback), mapping, bytes, values: Vec::new() });
            for q in &mut self.queries {
                if let QueryState::Recorded { slot } = *q {
                    *q = QueryState::InFlight { batch, index: (slot - first) as usize };
                }
            }
        }
    }

    /// Writes the recorded query boxes to the box buffer, growing it (and the
    /// bind group that names it) when they do not fit.
    fn upload_boxes(&mut self) {
        if self.boxes.is_empty() {
            return;
        }
        let bytes = self.boxes.len() as u64 * BOX_BYTES;
        if bytes > self.box_buffer.size() {
            self.box_buffer = box_buffer(self.ctx(), bytes.next_power_of_two());
            self.frame_group = frame_group(&self.gpu, &self.camera_buffer, &self.box_buffer);
        }
        self.gpu.ctx.queue.write_buffer(&self.box_buffer, 0, bytemuck::cast_slice(&self.boxes));
    }

    /// Reads a finished batch's values and frees its read-back buffers.
    fn collect(&mut self, batch: usize) {
        let Some(readback) = self.batches[batch].readback.take() else { return };
        let values = read_values(&readback, self.batches[batch].bytes);
        self.pool.recycle(readback);
        self.batches[batch].values = values.unwrap_or_else(|e| {
            self.gpu.ctx.fail(e);
            Vec::new()
        });
    }

    /// The query's value once its batch is read; `block` waits for it.
    fn poll_query(&mut self, query: QueryHandle, block: bool) -> Option<u64> {
        if matches!(self.queries[query.0 as usize], QueryState::Recorded { .. }) {
            self.flush();
        }
        let (batch, index) = match self.queries[query.0 as usize] {
            QueryState::Ready(v) => return Some(v),
            QueryState::InFlight { batch, index } => (batch, index),
            QueryState::Recorded { .. } => unreachable!("flushed above"),
        };
        if self.batches[batch].readback.is_some() {
            let mapping = self.batches[batch].mapping.clone();
            if block {
                let start = Instant::now();
                let waited = mapping.wait(self.ctx());
                self.wait += start.elapsed();
                if waited.is_err() {
                    return Some(self.all_pixels());
                }
            } else if !mapping.is_done(self.ctx()) {
                return None;
            }
            self.collect(batch);
        }
        let value = self.batches[batch].values.get(index).copied().unwrap_or_else(|| self.all_pixels());
        self.queries[query.0 as usize] = QueryState::Ready(value);
        Some(value)
    }

    /// Submits what is recorded and waits until the GPU is idle and every
    /// read-back has been collected, so the next frame starts clean.
    fn settle(&mut self) {
        self.flush();
        for batch in 0..self.batches.len() {
            if self.batches[batch].readback.is_some() {
                let mapping = self.batches[batch].mapping.clone();
                if mapping.wait(self.ctx()).is_ok() {
                    self.collect(batch);
                } else if let Some(r) = self.batches[batch].readback.take() {
                    self.pool.recycle(r);
                }
            }
        }
        self.batches.clear();
    }
}

/// The frame bind group over `camera`, the scene's transforms and `boxes`.
fn frame_group(gpu: &GpuScene, camera: &wgpu::Buffer, boxes: &wgpu::Buffer) -> wgpu::BindGroup {
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

fn box_buffer(ctx: &GpuContext, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("query boxes"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Encodes the recorded ops into `pass`, binding pipelines, index buffers
/// and material groups only when they change.
fn encode_ops(pass: &mut wgpu::RenderPass<'_>, gpu: &GpuScene, scene: &Scene, frame: &wgpu::BindGroup, ops: &[Op]) {
    pass.set_bind_group(0, frame, &[]);
    pass.set_vertex_buffer(0, gpu.vertices.slice(..));
    let mut bound: Option<Bound> = None;
    let mut material: Option<u32> = None;
    let mut bind = |pass: &mut wgpu::RenderPass<'_>, want: Bound| {
        if bound != Some(want) {
            let (pipeline, indices) = match want {
                Bound::Draw => (&gpu.pipelines.draw, &gpu.indices),
                Bound::Query => (&gpu.pipelines.query, &gpu.box_indices),
                Bound::Oracle => (&gpu.pipelines.oracle, &gpu.indices),
            };
            pass.set_pipeline(pipeline);
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            bound = Some(want);
        }
    };
    for op in ops {
        match op {
            Op::Draw(i) | Op::EqualQuery { instance: i, .. } => {
                let want = if matches!(op, Op::Draw(_)) { Bound::Draw } else { Bound::Oracle };
                bind(pass, want);
                let group = gpu.instance_material[*i as usize];
                if material != Some(group) {
                    pass.set_bind_group(1, &gpu.material_groups[group as usize], &[]);
                    material = Some(group);
                }
                let mesh = gpu.meshes[scene.instances[*i as usize].mesh as usize];
                if let Op::EqualQuery { slot, .. } = op {
                    pass.begin_occlusion_query(slot % QUERIES_PER_SET);
                }
                pass.draw_indexed(mesh.first_index..mesh.first_index + mesh.index_count, mesh.base_vertex, *i..*i + 1);
                if matches!(op, Op::EqualQuery { .. }) {
                    pass.end_occlusion_query();
                }
            }
            Op::BoxQuery { slot, boxes } => {
                bind(pass, Bound::Query);
                if material.is_none() {
                    // The query pipeline's layout includes the material group.
                    pass.set_bind_group(1, &gpu.material_groups[0], &[]);
                    material = Some(0);
                }
                pass.begin_occlusion_query(slot % QUERIES_PER_SET);
                pass.draw_indexed(0..36, 0, boxes.clone());
                pass.end_occlusion_query();
            }
        }
    }
}

impl Backend for WgpuBackend<'_> {
    fn begin_frame(&mut self, camera: &Camera) {
        self.start(camera);
        self.state = StateTracker::default();
        self.stats = FrameStats::default();
        self.drawn.fill(false);
        self.wait = Duration::ZERO;
        self.frame_start = Instant::now();
    }

    fn draw(&mut self, instances: &[u32]) {
        for &i in instances {
            let inst = &self.scene.instances[i as usize];
            if self.state.switch(RenderState::Material(inst.material)) {
                self.stats.state_changes += 1;
            }
            self.stats.draw_calls += 1;
            self.stats.triangles += self.scene.meshes[inst.mesh as usize].triangle_count() as u64;
            if !std::mem::replace(&mut self.drawn[i as usize], true) {
                self.stats.visible_objects += 1;
            }
            self.ops.push(Op::Draw(i));
        }
    }

    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
        let camera = self.camera.expect("issue_query outside a frame");
        if self.state.switch(RenderState::Query) {
            self.stats.state_changes += 1;
        }
        self.stats.queries += 1;
        self.stats.query_boxes += boxes.len() as u64;
        let Some(padded) = query_boxes(&camera, boxes) else {
            self.queries.push(QueryState::Ready(self.all_pixels()));
            return QueryHandle(self.queries.len() as u32 - 1);
        };
        let handle = self.record_query(|slot| Op::BoxQuery { slot, boxes: 0..0 });
        let first = self.boxes.len() as u32;
        self.boxes.extend(padded.iter().map(|b| {
            let (lo, hi) = (b.min, b.max);
            [lo.x, lo.y, lo.z, 0.0, hi.x, hi.y, hi.z, 0.0]
        }));
        if let Some(Op::BoxQuery { boxes, .. }) = self.ops.last_mut() {
            *boxes = first..self.boxes.len() as u32;
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
        self.stats.traversal_steps += nodes;
    }

    fn end_frame(&mut self) -> FrameStats {
        self.flush();
        let cpu_end = self.frame_start.elapsed();
        self.settle();
        let _ = self.ctx().device.poll(wgpu::PollType::wait_indefinitely());
        let frame = self.frame_start.elapsed();
        let gpu = Arc::clone(&self.gpu);
        let gpu_ms = match self.timer.as_mut().map(|t| t.finish(&gpu.ctx)) {
            Some(Ok(ms)) => ms,
            Some(Err(e)) => {
                gpu.ctx.fail(e);
                0.0
            }
            None => 0.0,
        };
        let mut s = self.stats;
        s.frame_ms = frame.as_secs_f64() * 1e3;
        s.cpu_ms = cpu_end.saturating_sub(self.wait).as_secs_f64() * 1e3;
        s.wait_ms = self.wait.as_secs_f64() * 1e3;
        s.gpu_ms = gpu_ms;
        s.wall_ms = s.frame_ms;
        self.camera = None;
        s
    }

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

    fn failure(&self) -> Option<String> {
        self.ctx().failure()
    }
}
