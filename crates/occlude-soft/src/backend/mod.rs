//! [`SoftBackend`]: the [`Backend`] interface on the exact CPU rasterizer and
//! the simulated GPU clock.
//!
//! Commands are recorded with the CPU time they were issued at and rasterized
//! lazily, in order, when a result is needed (a query check, the end of the
//! frame). The GPU time line is then replayed: each command starts at
//! max(issued, GPU free) and costs its fixed part plus its fragments. Pixel
//! counts are always exact; only the times are modelled. The GPU-resident
//! culling commands ([`occlude_core::GpuCulling`], in `culling.rs`) run
//! the same way: their compute steps on the CPU, their box tests and draws on
//! the rasterizer, their costs on the GPU time line.
//!
//! Query pixel counts are exact in both [`QueryMode`]s; the mode changes what
//! they cost. `Hardware`: per query `cpu_query_us`, `gpu_query_box_us` per
//! box, the result readable `query_latency_us` after its query ends. `Hib`
//! (the queries between two submissions counted as one batch in one pass,
//! as the wgpu backend does): per query `GpuModel::hib_query_us`
//! (`cpu_hib_query_us` where measured, else `cpu_query_us`), per box `gpu_box_us`
//! (a box of an instanced draw, no query around it), per passing fragment
//! `gpu_box_fragment_ns` on top of the depth test (the counting atomic); per
//! batch `cpu_dispatch_us` on the CPU and `GpuModel::hib_batch_gpu_us` on
//! the GPU (its pass and the clearing of its counts: `gpu_hib_batch_us`
//! where measured, else `gpu_draw_call_us` + `gpu_dispatch_us`); every
//! result of the batch readable `readback_us` after the batch's last box.
//!
//! Draws are recorded until `FLUSH_TRIANGLES` (2^20) triangles wait (outside a
//! `Hib` batch) and then rasterized, so that a frame drawing tens of millions
//! of triangles (view-frustum culling of the million-instance `swarm`) holds
//! a bounded number of them: commands run in order either way, so images,
//! counts and the replayed time line are the same. For the same reason the
//! recorded commands are rasterized ahead of that, every `RASTER_TRIANGLES`
//! (2^16) triangles, their counts kept until the time line is replayed at the
//! flush: the triangles are then still in the caches when the rasterizer sets
//! them up.

mod culling;
mod item_buffer;
mod oracle;
mod replay;
mod shared_setup;

pub use replay::DrawReplay;
pub use shared_setup::SharedSetup;

use crate::clock::SimClock;
use crate::gpu_model::GpuModel;
use crate::raster::{Command, CommandKind, CommandResult, DepthBuffer, DepthTest, Prepared, Rasterizer};
use glam::{Mat4, Vec4};
use occlude_core::host_culling::HostResources;
use occlude_core::query_box::{query_boxes, BOX_TRIANGLES, QUERY_DEPTH_BIAS};
use occlude_core::{
    Aabb, Backend, Camera, CostModel, CpuCullingWork, FrameCounter, FrameStats, GpuCulling, GpuCullingUnsupported,
    Instruments, OracleView, QueryHandle, QueryMode, RenderState, Scene,
};
use replay::Role;
use shared_setup::FrameSetup;
use std::sync::Arc;
use std::time::Instant;

/// Recorded triangles (48 bytes each in clip space) past which a draw
/// rasterizes what is recorded first (module documentation).
const FLUSH_TRIANGLES: usize = 1 << 20;

/// Recorded triangles past which a draw rasterizes the commands recorded so
/// far, keeping their counts for the flush (module documentation): 3 MiB in
/// clip space, still in the caches when the rasterizer sets them up.
const RASTER_TRIANGLES: usize = 1 << 16;

/// Triangles per rasterizer call of the oracle pass: 3 MiB in clip space, so
/// that they are still in the caches when the rasterizer sets them up
/// (`FLUSH_TRIANGLES`' 48 MiB are not).
/// The oracle's image and counts do not depend on it, and it has no time
/// line to replay.
const ORACLE_PART: usize = 1 << 16;

/// Triangles per rasterizer call of the oracle pass when they come set up
/// from a [`SharedSetup`] table: nothing is set up in the call, so fewer,
/// larger calls rebuild the pass's depth pyramid less often. 2^18 took the
/// fewest instructions per frame of the power plant's `--paper chc` (2^14:
/// 6.71 billion, 2^16: 5.71, 2^18: 5.57, 2^20: 5.84) and 10 % fewer than
/// 2^16 on the teapots, 6 % more on the city, whose whole view takes one or
/// two calls.
const ORACLE_PREPARED_PART: usize = 1 << 18;

/// A recorded command's place on the simulated GPU time line.
#[derive(Clone, Copy, Debug)]
struct GpuOp {
    issued_us: f64,
    fixed_us: f64,
    fragment_ns: f64,
    /// Cost of each fragment that passes the depth test, on top of
    /// `fragment_ns` (a batched box test's fragment shader).
    passed_ns: f64,
    query: Option<u32>,
    /// Occlusion-test work (`FrameStats::cull_ms`) rather than drawing
    /// (`render_ms`).
    cull: bool,
}

/// What is known about an issued query.
#[derive(Clone, Copy, Debug)]
struct QueryState {
    /// Still waiting to be rasterized.
    pending: bool,
    /// Treated as visible without rasterizing (a box touches the near region).
    forced_visible: bool,
    /// Counted in a batch ([`QueryMode::Hib`]): readable when the batch is.
    batched: bool,
    available_at_us: f64,
    pixels: u64,
}

/// Adds `us` of GPU time to the frame's occlusion-test or drawing time.
fn charge_gpu_time(stats: &mut FrameStats, cull: bool, us: f64) {
    if cull {
        stats.cull_ms += us * 1e-3;
    } else {
        stats.render_ms += us * 1e-3;
    }
}

/// Software backend over one scene: its own copy of the scene's instances
/// (meshes shared), updated by [`Backend::update_instances`].
pub struct SoftBackend {
    scene: Scene,
    model: GpuModel,
    depth: DepthBuffer,
    rasterizer: Rasterizer,
    camera: Option<Camera>,
    view_projection: Mat4,
    clock: SimClock,
    count: FrameCounter,
    pending_state_us: f64,
    /// The triangles of the commands not yet rasterized.
    triangles: Vec<[Vec4; 3]>,
    clip_scratch: Vec<Vec4>,
    /// The commands recorded since the last flush; the first `rasterized.len()`
    /// have been rasterized (their triangle ranges are spent).
    commands: Vec<Command>,
    /// The counts of the commands rasterized ahead of the flush, in order.
    rasterized: Vec<CommandResult>,
    /// Per recorded command, the instance and triangle count of a draw
    /// set up in [`Self::frame_setup`] rather than in `triangles`.
    sources: Vec<Option<(u32, usize)>>,
    /// Input triangles of the commands in `sources` not yet rasterized.
    prepared_pending: usize,
    /// The set-ups shared with other backends, if any
    /// ([`Self::share_setup`]), and this frame's table of them.
    shared_setup: Option<SharedSetup>,
    frame_setup: Option<Arc<FrameSetup>>,
    /// Triangles recorded since the last flush, rasterized or not.
    recorded: usize,
    /// Recorded triangles past which a draw rasterizes ahead of the flush:
    /// `RASTER_TRIANGLES`, or fewer in tests.
    raster_triangles: usize,
    /// Recorded triangles past which a draw flushes first:
    /// `FLUSH_TRIANGLES`, or fewer in tests.
    flush_triangles: usize,
    ops: Vec<GpuOp>,
    queries: Vec<QueryState>,
    frame_start: Instant,
    device: HostResources,
    query_mode: QueryMode,
    /// Whether a [`QueryMode::Hib`] batch has been started since the last
    /// submission (its fixed costs charged).
    batch_open: bool,
    /// The simulated GPU busy time when the frame's first depth-pyramid
    /// build ended, µs (`None` before it): where `FrameStats::late_ms`
    /// starts.
    late_from_us: Option<f64>,
    /// Whether draws are counted here or taken from another backend's
    /// frame (`replay.rs`).
    replay: Role,
}

impl SoftBackend {
    /// A backend drawing `scene` at `width` x `height` pixels with the costs
    /// of `model`.
    pub fn new(scene: &Scene, width: u32, height: u32, model: GpuModel) -> Self {
        Self {
            scene: scene.clone(),
            model,
            depth: DepthBuffer::new(width, height),
            rasterizer: Rasterizer::new(),
            camera: None,
            view_projection: Mat4::IDENTITY,
            clock: SimClock::default(),
            count: FrameCounter::new(scene.instances.len()),
            pending_state_us: 0.0,
            triangles: Vec::new(),
            clip_scratch: Vec::new(),
            commands: Vec::new(),
            rasterized: Vec::new(),
            sources: Vec::new(),
            prepared_pending: 0,
            shared_setup: None,
            frame_setup: None,
            recorded: 0,
            raster_triangles: RASTER_TRIANGLES,
            flush_triangles: FLUSH_TRIANGLES,
            ops: Vec::new(),
            queries: Vec::new(),
            frame_start: Instant::now(),
            device: HostResources::default(),
            query_mode: QueryMode::Hardware,
            batch_open: false,
            late_from_us: None,
            replay: Role::Own,
        }
    }

    /// Answers occlusion queries in `mode` from now on: the same exact
    /// counts, at the costs of that mode (module documentation).
    pub fn set_query_mode(&mut self, mode: QueryMode) {
        self.query_mode = mode;
    }

    /// Sets up its draws' triangles in `shared`, with the other backends
    /// given a clone of it, from the next frame on: each instance once per
    /// camera for all of them ([`SharedSetup`]). Changes no image, count or
    /// time; for backends of one scene rendering the same frames side by
    /// side (the table knows instances by index, not by scene).
    pub fn share_setup(&mut self, shared: SharedSetup) {
        self.shared_setup = Some(shared);
    }

    /// The cost model in use.
    pub fn model(&self) -> &GpuModel {
        &self.model
    }

    /// Replaces the depth buffer's contents with `depth` (`width * height`
    /// values, row by row from the top) after everything recorded so far
    /// has run: tests of depth-based culling (the depth pyramid) start from
    /// depth images of their own. Costs nothing on the clock.
    ///
    /// # Panics
    /// If `depth` has not the buffer's size.
    pub fn write_depth(&mut self, depth: &[f32]) {
        self.flush();
        let width = self.depth.width();
        assert_eq!(depth.len(), width as usize * self.depth.height() as usize, "a depth image of another size");
        for (i, &d) in depth.iter().enumerate() {
            self.depth.set(i as u32 % width, i as u32 / width, d);
        }
    }

    /// Charges a render-state change's costs when `changed` (what
    /// [`FrameCounter`] answered).
    fn charge_state_change(&mut self, changed: bool) {
        if changed {
            self.clock.cpu_work(self.model.cpu_state_change_us);
            self.pending_state_us += self.model.gpu_state_change_us;
        }
    }

    /// Appends the clip-space triangles of instance `i`.
    fn push_instance_triangles(&mut self, i: u32) {
        self.scene.push_clip_triangles(i, &self.view_projection, &mut self.clip_scratch, &mut self.triangles);
    }

    /// Appends the 12 outward, counter-clockwise triangles of a box in clip
    /// space, pulled towards the eye by [`QUERY_DEPTH_BIAS`].
    fn push_box_triangles(&mut self, b: &Aabb) {
        let c = b.corners().map(|p| {
            let v = self.view_projection * p.extend(1.0);
            Vec4::new(v.x, v.y, v.z - QUERY_DEPTH_BIAS * v.w, v.w)
        });
        self.triangles.extend(BOX_TRIANGLES.iter().map(|t| t.map(|i| c[i as usize])));
    }

    /// Records one raster command and its GPU time-line entry.
    fn record(&mut self, kind: CommandKind, first_triangle: usize, cull_back: bool, mut op: GpuOp) {
        op.fixed_us += std::mem::take(&mut self.pending_state_us);
        self.commands.push(Command { kind, triangles: first_triangle as u32..self.triangles.len() as u32, cull_back });
        self.sources.push(None);
        self.recorded += self.triangles.len() - first_triangle;
        self.ops.push(op);
    }

    /// Rasterizes the commands recorded and not yet rasterized, keeping their
    /// counts for the flush, whose time line they do not change.
    fn rasterize_recorded(&mut self) {
        let done = self.rasterized.len();
        let pending = &self.commands[done..];
        let results = match self.replay.taken(pending.len()) {
            Some(replayed) => replayed,
            None => {
                let prepared: Vec<Option<&Prepared>> = match &self.frame_setup {
                    Some(setup) => {
                        let instances: Vec<u32> = self.sources[done..].iter().flatten().map(|&(i, _)| i).collect();
                        let mut set_up = setup.prepare(&self.scene, &instances, &self.rasterizer).into_iter();
                        self.sources[done..]
                            .iter()
                            .map(|s| s.map(|_| set_up.next().expect("one set-up per such draw")))
                            .collect()
                    }
                    None => Vec::new(),
                };
                self.rasterizer.execute_prepared(&mut self.depth, &self.triangles, pending, &prepared)
            }
        };
        self.rasterized.extend(results);
        self.triangles.clear();
        self.prepared_pending = 0;
    }

    /// Rasterizes everything recorded and replays the GPU time line.
    fn flush(&mut self) {
        self.run_recorded();
    }

    /// [`Self::flush`], returning each command's counts.
    fn run_recorded(&mut self) -> Vec<CommandResult> {
        if self.commands.is_empty() {
            return Vec::new();
        }
        self.rasterize_recorded();
        let results = std::mem::take(&mut self.rasterized);
        let (mut batch, mut batch_end) = (Vec::new(), 0.0);
        // CPU time the replayed submissions blocked (a bounded driver
        // queue): every command recorded after a blocked one was issued
        // that much later.
        let mut blocked = 0.0;
        for ((op, r), (command, source)) in self.ops.iter().zip(&results).zip(self.commands.iter().zip(&self.sources)) {
            let cost_us = op.fixed_us + (r.fragments as f64 * op.fragment_ns + r.passed as f64 * op.passed_ns) * 1e-3;
            let submitted = self.clock.gpu_command(op.issued_us + blocked, cost_us);
            blocked += submitted.blocked;
            let end = submitted.end;
            charge_gpu_time(&mut self.count.stats, op.cull, cost_us);
            match op.query {
                Some(handle) => {
                    let q = &mut self.queries[handle as usize];
                    q.pending = false;
                    q.available_at_us = end + self.model.query_latency_us;
                    if q.batched {
                        batch.push(handle);
                        batch_end = end;
                    }
                    q.pixels = if q.forced_visible {
                        u64::from(self.depth.width()) * u64::from(self.depth.height())
                    } else {
                        r.passed
                    };
                }
                None if !op.cull => {
                    self.count.stats.fragments += r.fragments;
                    self.replay.keep(*r, source.map_or(command.triangles.len(), |(_, n)| n));
                }
                // A batched box test: its caller reads the counts.
                None => {}
            }
        }
        for handle in batch {
            self.queries[handle as usize].available_at_us = batch_end + self.model.readback_us;
        }
        self.batch_open = false;
        self.recorded = 0;
        self.commands.clear();
        self.sources.clear();
        self.ops.clear();
        results
    }

    /// Draws instance `i` as one draw costing `fixed_us` of GPU time before
    /// its triangles and fragments; counts it.
    fn draw_instance(&mut self, i: u32, fixed_us: f64) {
        if self.recorded >= self.flush_triangles && !self.batch_open {
            self.flush();
        } else if self.triangles.len() + self.prepared_pending >= self.raster_triangles {
            self.rasterize_recorded();
        }
        let triangles = self.scene.instance_triangles(i as usize);
        self.count.draw(i, triangles);
        let first = self.triangles.len();
        let mut source = None;
        match (self.replay.next_draw(), &self.frame_setup) {
            // No triangles to rasterize, but counted towards the flush as
            // the recording backend's were.
            (Some(recorded), _) => self.recorded += recorded,
            // Set up (or found set up) when rasterized.
            (None, Some(_)) => {
                let n = self.scene.meshes[self.scene.instances[i as usize].mesh as usize].triangle_count();
                self.prepared_pending += n;
                self.recorded += n;
                source = Some((i, n));
            }
            (None, None) => self.push_instance_triangles(i),
        }
        let op = GpuOp {
            issued_us: self.clock.cpu,
            fixed_us: self.model.draw_us(fixed_us, triangles),
            fragment_ns: self.model.gpu_fragment_ns,
            passed_ns: 0.0,
            query: None,
            cull: false,
        };
        self.record(CommandKind::Draw, first, false, op);
        *self.sources.last_mut().expect("the draw just recorded") = source;
    }

    fn query_state(&mut self, query: QueryHandle) -> QueryState {
        if self.queries[query.0 as usize].pending {
            self.flush();
        }
        let q = self.queries[query.0 as usize];
        // Submissions recorded after the query may yet block the CPU (a
        // bounded driver queue) past the time its result is readable: replay
        // them before the CPU clock is compared with it.
        if q.available_at_us > self.clock.cpu && self.clock.queue_is_bounded() {
            self.flush();
        }
        q
    }
}

impl Backend for SoftBackend {
    fn begin_frame(&mut self, camera: &Camera) {
        self.camera = Some(*camera);
        self.view_projection = camera.view_projection();
        self.depth.clear();
        self.clock = SimClock::new(self.model.driver_queue_us);
        self.count.begin_frame();
        self.pending_state_us = 0.0;
        self.queries.clear();
        self.batch_open = false;
        self.late_from_us = None;
        self.replay.begin_frame();
        let (width, height) = (self.depth.width(), self.depth.height());
        let (instances, revision) = (self.scene.instances.len(), self.scene.revision());
        self.frame_setup =
            self.shared_setup.as_ref().map(|s| s.frame(self.view_projection, width, height, instances, revision));
        self.frame_start = Instant::now();
    }

    fn update_instances(&mut self, scene: &Scene, changed: &[u32]) {
        self.scene.copy_instances(scene, changed);
    }

    fn draw(&mut self, instances: &[u32]) {
        for &i in instances {
            if !self.scene.instances[i as usize].enabled {
                continue;
            }
            let changed = self.count.set_state(RenderState::Material(self.scene.instances[i as usize].material));
            self.charge_state_change(changed);
            self.clock.cpu_work(self.model.cpu_draw_call_us);
            self.draw_instance(i, self.model.gpu_draw_call_us);
        }
    }

    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
        let camera = self.camera.expect("issue_query outside a frame");
        assert!(!self.replay.replays(), "a backend replaying another's draws answers no query");
        let changed = self.count.query(boxes.len());
        self.charge_state_change(changed);
        self.clock.cpu_work(match self.query_mode {
            QueryMode::Hardware => self.model.cpu_query_us,
            QueryMode::Hib => self.model.hib_query_us(),
        });
        let handle = self.queries.len() as u32;
        let padded = query_boxes(&camera, boxes);
        let forced_visible = padded.is_none();
        let first = self.triangles.len();
        for b in padded.iter().flatten() {
            self.push_box_triangles(b);
        }
        let batched = self.query_mode == QueryMode::Hib;
        self.queries.push(QueryState { pending: true, forced_visible, batched, available_at_us: 0.0, pixels: 0 });
        let m = &self.model;
        let (mut fixed_us, passed_ns) = match self.query_mode {
            QueryMode::Hardware => (m.gpu_query_box_us * boxes.len() as f64, 0.0),
            QueryMode::Hib => (m.gpu_box_us * boxes.len() as f64, m.gpu_box_fragment_ns),
        };
        if batched && !std::mem::replace(&mut self.batch_open, true) {
            fixed_us += m.hib_batch_gpu_us();
            self.clock.cpu_work(self.model.cpu_dispatch_us);
        }
        let op = GpuOp {
            issued_us: self.clock.cpu,
            fixed_us,
            fragment_ns: self.model.gpu_query_fragment_ns,
            passed_ns,
            query: Some(handle),
            cull: true,
        };
        self.record(CommandKind::Query(DepthTest::Less), first, true, op);
        QueryHandle(handle)
    }

    fn is_available(&mut self, query: QueryHandle) -> bool {
        self.clock.cpu_work(self.model.cpu_query_poll_us);
        self.query_state(query).available_at_us <= self.clock.cpu
    }

    fn result(&mut self, query: QueryHandle) -> u64 {
        let q = self.query_state(query);
        self.clock.wait_until(q.available_at_us);
        q.pixels
    }

    fn traverse(&mut self, nodes: u64) {
        self.count.traverse(nodes);
        self.clock.cpu_work(nodes as f64 * self.model.cpu_node_us);
    }

    fn resolution(&self) -> (u32, u32) {
        (self.depth.width(), self.depth.height())
    }

    fn cpu_culling(&mut self, work: CpuCullingWork) {
        let m = &self.model;
        let ns = work.triangles as f64 * m.cpu_moc_triangle_ns
            + work.tiles as f64 * m.cpu_moc_tile_ns
            + work.boxes as f64 * m.cpu_moc_box_ns
            + work.subtiles_read as f64 * m.cpu_moc_subtile_read_ns;
        self.clock.cpu_work(ns * 1e-3);
    }

    fn end_frame(&mut self) -> FrameStats {
        self.flush();
        self.replay.keep_image(&self.depth);
        let c = &self.clock;
        let mut s = self.count.stats;
        s.frame_ms = c.frame_end() * 1e-3;
        s.cpu_ms = c.cpu_busy() * 1e-3;
        s.gpu_ms = c.gpu_busy * 1e-3;
        s.wait_ms = c.wait * 1e-3;
        s.submit_wait_ms = c.submit_wait * 1e-3;
        s.late_ms = self.late_from_us.map_or(0.0, |from| (c.gpu_busy - from) * 1e-3);
        s.wall_ms = self.frame_start.elapsed().as_secs_f64() * 1e3;
        self.camera = None;
        s
    }

    fn gpu_culling(&mut self) -> Result<&mut dyn GpuCulling, GpuCullingUnsupported> {
        if self.replay.replays() {
            return Err(GpuCullingUnsupported("a backend replaying another's draws runs no culling commands".into()));
        }
        Ok(self)
    }

    fn instruments(&mut self) -> Option<&mut dyn Instruments> {
        Some(self)
    }

    fn cost_model(&self) -> Option<CostModel> {
        Some(self.model.cost_model())
    }
}

impl Instruments for SoftBackend {
    fn depth_image(&mut self, out: &mut Vec<f32>) {
        self.flush();
        if !self.replay.image(out) {
            self.depth.copy_to(out);
        }
    }

    fn oracle(&mut self, camera: &Camera, candidates: &[u32]) -> OracleView {
        let part = if self.shared_setup.is_some() { ORACLE_PREPARED_PART } else { ORACLE_PART };
        self.oracle_in_parts(camera, candidates, part, true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use occlude_core::{Keyframe, Mesh};

    /// Twelve overlapping quads one behind the other, and a smaller one
    /// hidden behind the first.
    fn quads() -> Scene {
        let mut scene = Scene::new("quads");
        let quad = Mesh::new(
            vec![
                Vec3::new(-0.5, -0.5, 0.0),
                Vec3::new(0.5, -0.5, 0.0),
                Vec3::new(0.5, 0.5, 0.0),
                Vec3::new(-0.5, 0.5, 0.0),
            ],
            vec![0, 1, 2, 0, 2, 3],
        );
        let mesh = scene.add_mesh(quad);
        for k in 0..12 {
            let at = Vec3::new(0.04 * k as f32, 0.03 * k as f32, -2.0 - 0.1 * k as f32);
            scene.add_instance(mesh, Mat4::from_translation(at), k % 3);
        }
        scene.add_instance(
            mesh,
            Mat4::from_translation(Vec3::new(0.0, 0.0, -2.05)) * Mat4::from_scale(Vec3::splat(0.5)),
            0,
        );
        scene
    }

    /// The driver-queue tests' camera, at the origin looking down -z at
    /// [`quads`], and a small box behind the quads (hidden).
    fn view_and_hidden_box() -> (Camera, Aabb) {
        let key = Keyframe { time: 0.0, position: Vec3::ZERO, target: -Vec3::Z, fov_y_deg: 60.0 };
        let camera = key.camera(4.0 / 3.0, 0.1, 100.0);
        (camera, Aabb::new(Vec3::new(-0.1, -0.1, -3.0), Vec3::new(0.1, 0.1, -2.9)))
    }

    /// What a frame of draws and queries with checks between them gave:
    /// its statistics (but wall time), whether the first query was
    /// available when checked, both counts and the image's bits.
    type Figures = (FrameStats, bool, [u64; 2], Vec<u32>);

    /// Renders [`quads`] through `camera` on `backend` in draws and
    /// queries (one of `hidden`) with checks between them.
    fn draws_and_queries(backend: &mut SoftBackend, camera: &Camera, hidden: Aabb) -> Figures {
        backend.begin_frame(camera);
        backend.draw(&[3, 1, 12]);
        let early = backend.issue_query(&[hidden]);
        backend.draw(&[0, 2, 4, 5]);
        let available = backend.is_available(early);
        let late = backend.issue_query(&[Aabb::new(Vec3::new(-0.2, -0.2, -2.3), Vec3::new(0.3, 0.3, -1.0))]);
        backend.draw(&[6, 7, 8, 9, 10, 11]);
        let pixels = [backend.result(early), backend.result(late)];
        let mut depth = Vec::new();
        backend.depth_image(&mut depth);
        let stats = FrameStats { wall_ms: 0.0, ..backend.end_frame() };
        (stats, available, pixels, depth.iter().map(|d| d.to_bits()).collect())
    }

    /// Rasterizing ahead of the flush (after every draw, every few, never)
    /// gives the same image, query counts and frame statistics, bit for bit,
    /// in a frame of draws and queries with a bounded driver queue (so that
    /// submissions block and move the CPU clock) and checks between them.
    #[test]
    fn rasterizing_ahead_of_the_flush_changes_no_figure() {
        let scene = quads();
        let (camera, hidden) = view_and_hidden_box();
        let model = GpuModel { gpu_draw_call_us: 40.0, driver_queue_us: 60.0, ..GpuModel::modern() };
        let frame = |raster_triangles: usize| {
            let mut backend = SoftBackend::new(&scene, 97, 71, model.clone());
            backend.raster_triangles = raster_triangles;
            draws_and_queries(&mut backend, &camera, hidden)
        };
        let never = frame(usize::MAX);
        assert!(never.2[1] > 0 && never.0.submit_wait_ms > 0.0, "{never:?}");
        for raster_triangles in [1, 2, 5, 13] {
            assert_eq!(frame(raster_triangles), never, "ahead every {raster_triangles} triangles");
        }
    }

    /// Backends sharing their set-up give, bit for bit, the figures of a
    /// backend setting up for itself: the first of a camera setting every
    /// instance up, the next ones finding them set up, with another camera
    /// (a new table) in between, rasterizing ahead of the flush or not.
    #[test]
    fn sharing_the_set_up_changes_no_figure() {
        let scene = quads();
        let (camera, hidden) = view_and_hidden_box();
        let key = Keyframe {
            time: 0.0,
            position: Vec3::new(0.3, 0.2, 0.4),
            target: Vec3::new(0.1, 0.0, -2.0),
            fov_y_deg: 50.0,
        };
        let other = key.camera(4.0 / 3.0, 0.1, 100.0);
        let model = GpuModel { gpu_draw_call_us: 40.0, driver_queue_us: 60.0, ..GpuModel::modern() };
        let alone =
            |camera: &Camera| draws_and_queries(&mut SoftBackend::new(&scene, 97, 71, model.clone()), camera, hidden);
        let shared = SharedSetup::new();
        for camera in [&camera, &other, &camera] {
            let expected = alone(camera);
            for raster_triangles in [usize::MAX, 1, 5] {
                let mut backend = SoftBackend::new(&scene, 97, 71, model.clone());
                backend.share_setup(shared.clone());
                backend.raster_triangles = raster_triangles;
                assert_eq!(draws_and_queries(&mut backend, camera, hidden), expected, "ahead every {raster_triangles}");
                assert!(backend.frame_setup.as_ref().is_some_and(|s| s.get(12).is_some()), "set up in the table");
            }
        }
    }

    /// A frame of GPU-bound draws, then one query read at once: with an
    /// unbounded driver queue the read waits for every draw; with a queue
    /// of zero the draws' submissions block instead, and the read waits for
    /// the query alone. The GPU's time line, the frame time, the image and
    /// the count are the same either way.
    #[test]
    fn a_bounded_driver_queue_moves_the_wait_into_submission() {
        let scene = quads();
        let (camera, hidden) = view_and_hidden_box();
        let all: Vec<u32> = (0..scene.instances.len() as u32).collect();
        let frame = |driver_queue_us: f64| {
            let model = GpuModel {
                gpu_draw_call_us: 100.0,
                gpu_state_change_us: 0.0,
                gpu_query_fragment_ns: 0.0,
                driver_queue_us,
                ..GpuModel::modern()
            };
            let mut backend = SoftBackend::new(&scene, 97, 71, model);
            backend.begin_frame(&camera);
            backend.draw(&all);
            let query = backend.issue_query(&[hidden]);
            let pixels = backend.result(query);
            let mut depth = Vec::new();
            backend.depth_image(&mut depth);
            (backend.end_frame(), pixels, depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>())
        };
        let (free, free_pixels, free_depth) = frame(f64::INFINITY);
        let (bounded, bounded_pixels, bounded_depth) = frame(0.0);
        assert_eq!((bounded_pixels, &bounded_depth), (free_pixels, &free_depth));
        assert_eq!(free.submit_wait_ms, 0.0);
        assert!(free.wait_ms > 1.0, "the read waits for 13 draws of 100 µs: {free:?}");
        let m = GpuModel::modern();
        let query_round_trip_ms = (m.gpu_query_box_us + m.query_latency_us) * 1e-3;
        assert!((bounded.wait_ms - query_round_trip_ms).abs() < 1e-9, "{bounded:?}");
        assert!((bounded.wait_ms + bounded.submit_wait_ms - free.wait_ms).abs() < 1e-9);
        assert_eq!((bounded.frame_ms, bounded.gpu_ms, bounded.cpu_ms), (free.frame_ms, free.gpu_ms, free.cpu_ms));
    }

    /// A batched (`Hib`) query costs the CPU `cpu_hib_query_us` where the
    /// model has it and `cpu_query_us` where not; a hardware query
    /// `cpu_query_us` either way.
    #[test]
    fn a_batched_query_costs_the_cpu_the_item_buffers_cost() {
        let scene = quads();
        let (camera, hidden) = view_and_hidden_box();
        let cpu_ms = |mode: QueryMode, cpu_hib_query_us: Option<f64>| {
            let model = GpuModel { cpu_query_us: 2.0, cpu_hib_query_us, ..GpuModel::modern() };
            let mut backend = SoftBackend::new(&scene, 97, 71, model);
            backend.set_query_mode(mode);
            backend.begin_frame(&camera);
            let queries: Vec<QueryHandle> = (0..10).map(|_| backend.issue_query(&[hidden])).collect();
            queries.into_iter().for_each(|q| assert!(backend.result(q) > 0, "the box is in view"));
            backend.end_frame().cpu_ms
        };
        let unmeasured = cpu_ms(QueryMode::Hib, None);
        let measured = cpu_ms(QueryMode::Hib, Some(0.5));
        assert!((unmeasured - measured - 10.0 * 1.5e-3).abs() < 1e-9, "{unmeasured} ms, {measured} ms");
        assert_eq!(cpu_ms(QueryMode::Hardware, Some(0.5)), cpu_ms(QueryMode::Hardware, None));
    }

    /// A batch (`Hib`) costs the GPU `gpu_hib_batch_us` where the model
    /// has it, else a draw call and a dispatch: two batches read at once
    /// move the GPU's busy time, and the frame (each read waits for its
    /// batch), by twice the difference; the CPU's time not at all.
    #[test]
    fn a_batch_costs_the_gpu_the_item_buffers_batch_cost() {
        let scene = quads();
        let (camera, hidden) = view_and_hidden_box();
        let frame = |gpu_hib_batch_us: Option<f64>| {
            let model = GpuModel { gpu_hib_batch_us, ..GpuModel::modern() };
            let mut backend = SoftBackend::new(&scene, 97, 71, model);
            backend.set_query_mode(QueryMode::Hib);
            backend.begin_frame(&camera);
            for _ in 0..2 {
                let queries: Vec<QueryHandle> = (0..5).map(|_| backend.issue_query(&[hidden])).collect();
                queries.into_iter().for_each(|q| assert!(backend.result(q) > 0, "the box is in view"));
            }
            backend.end_frame()
        };
        let m = GpuModel::modern();
        let (old, new) = (frame(None), frame(Some(22.0)));
        let more_ms = 2.0 * (22.0 - m.gpu_draw_call_us - m.gpu_dispatch_us) * 1e-3;
        assert!((new.gpu_ms - old.gpu_ms - more_ms).abs() < 1e-9, "{old:?}\n{new:?}");
        assert!((new.frame_ms - old.frame_ms - more_ms).abs() < 1e-9, "{old:?}\n{new:?}");
        assert_eq!(new.cpu_ms, old.cpu_ms);
    }

    /// A query's result is readable 30 µs after it runs; two draws of
    /// 100 µs recorded after it, with a queue of zero, block the CPU past
    /// that before it checks again: the check sees the result, as it would
    /// not if the draws could queue.
    #[test]
    fn a_check_counts_the_blocks_of_submissions_recorded_before_it() {
        let scene = quads();
        let (camera, hidden) = view_and_hidden_box();
        let second_check = |driver_queue_us: f64| {
            let model = GpuModel { gpu_draw_call_us: 100.0, driver_queue_us, ..GpuModel::modern() };
            let mut backend = SoftBackend::new(&scene, 97, 71, model);
            backend.begin_frame(&camera);
            let query = backend.issue_query(&[hidden]);
            assert!(!backend.is_available(query), "30 µs of latency");
            backend.draw(&[0, 1]);
            let available = backend.is_available(query);
            let stats = backend.end_frame();
            (available, stats.submit_wait_ms)
        };
        let (queued, queued_blocked) = second_check(f64::INFINITY);
        let (blocked, blocked_ms) = second_check(0.0);
        assert!(!queued && queued_blocked == 0.0);
        assert!(blocked && blocked_ms > 0.09, "the second draw waits for the first: {blocked_ms} ms");
    }

    /// The oracle in calls of one candidate each, or of a few, culled or
    /// not, gives the image and every count of the unculled oracle in one
    /// call per pass.
    #[test]
    fn the_oracle_in_parts_gives_the_image_and_counts_of_one_call() {
        let scene = quads();
        let key = Keyframe { time: 0.0, position: Vec3::ZERO, target: -Vec3::Z, fov_y_deg: 60.0 };
        let camera = key.camera(4.0 / 3.0, 0.1, 100.0);
        let candidates: Vec<u32> = (0..scene.instances.len() as u32).rev().collect();
        let view = |part: usize, cull: bool| {
            let mut backend = SoftBackend::new(&scene, 97, 71, GpuModel::modern());
            let v = backend.oracle_in_parts(&camera, &candidates, part, cull);
            (v.pixels, v.visible, v.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>())
        };
        let whole = view(usize::MAX, false);
        // Some seen, some hidden (the small quad behind the first among them).
        assert!(whole.1.len() >= 5 && whole.1.len() < candidates.len() && whole.0[0] == 0, "{:?}", whole.0);
        for part in [1, 5, 13, usize::MAX] {
            for cull in [false, true] {
                assert_eq!(view(part, cull), whole, "parts of {part} triangles, culled: {cull}");
            }
        }
    }
}
