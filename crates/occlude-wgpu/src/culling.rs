//! GPU-resident culling on wgpu ([`occlude_core::GpuCulling`]): the
//! visibility buffer of the IOC poster and the "raster" technique of nvpro's
//! `gl_occlusion_culling` sample. Boxes are tested in one batch per command:
//! a compute pass flags the boxes near the eye, drops those outside the view
//! frustum and appends the rest to a raster list, and one indirect draw of
//! that list rasterizes them as query boxes (the same proxies, bias and
//! depth state as [`Backend::issue_query`](occlude_core::Backend::issue_query)),
//! each fragment that passes the depth test setting its box's flag. Compute
//! passes turn flags into id lists, and a list into indirect draw arguments
//! drawn by one multi-draw (`multi_draw_indexed_indirect_count` where the
//! device has it). The shaders are in `cull.wgsl`, the box tests' fragment stages in
//! `cull_fragments.wgsl` (appended to it here).
//!
//! [`CullingScene`] is the part shared by every backend on a scene (pipelines,
//! per-instance draw data); [`Culling`] one backend's resources, which live as
//! long as the backend. The backend records [`CullOp`]s among its draws and
//! queries and encodes each as a compute pass ([`Culling::encode_compute`])
//! and, for box tests and list draws, a draw in the render pass that follows
//! ([`Culling::encode_draw`]).
//!
//! Depth pyramids (two-phase Hi-Z, [`occlude_core::depth_pyramid`]) live in
//! one storage buffer each, level after level: a build copies the depth
//! texture into level 0 and reduces each further level in a dispatch of its
//! own; a pyramid box test is one dispatch applying the rules of box tests
//! and then `DepthPyramid::test` to each box, without drawing.

use crate::backend::frame_group;
use crate::context::GpuContext;
use crate::pipelines::{self, compute_pipeline, CullingPipelines};
use crate::queries::{PassKind, PassTimer};
use crate::query_boxes::{BOX_BYTES, BOX_INDEX_COUNT};
use crate::readback::{take_bytes, Mapping};
use crate::scene_buffers::{material_color, GpuScene};
use occlude_core::depth_pyramid::{level_sizes, DEPTH_SLACK, PIXEL_MARGIN};
use occlude_core::query_box::{QUERY_BOX_PAD, QUERY_DEPTH_BIAS};
use occlude_core::{Aabb, BoxSet, Camera, ExpandInto, Flags, IdList, ItemRange, Pyramid, RangeTable, Scene};
use std::collections::HashMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// Threads per workgroup of every culling compute shader.
const GROUP_SIZE: u32 = 64;

/// Workgroups per dispatch dimension that every device accepts.
const MAX_GROUPS_PER_DIMENSION: u32 = 65535;

/// Bytes of a list's header (count, capacity) before its ids.
const LIST_HEADER: u64 = 8;

/// Bytes of one `DrawIndexedIndirectArgs`.
const DRAW_ARGS_BYTES: u64 = 20;

/// Bytes of the statistics' header (list draws' draws, their triangles low
/// and high, boxes rasterized) before the drawn-instance bits.
const STATS_HEADER: u64 = 16;

/// Bytes of the culling camera uniform, `Cull` of `cull.wgsl`.
const CAMERA_BYTES: u64 = 4 * 48;

/// A GPU-resident culling command, recorded among the backend's draws.
#[derive(Clone, Copy, Debug)]
pub(crate) enum CullOp {
    TestBoxes { boxes: BoxSet, ids: IdList, flags: Flags },
    BuildPyramid(Pyramid),
    TestPyramid { boxes: BoxSet, ids: IdList, pyramid: Pyramid, reach: u32, flags: Flags },
    Expand { src: IdList, filter: Flags, table: RangeTable, into: ExpandInto },
    Compact { flags: Flags, unless: Option<Flags>, dst: IdList },
    DropOutside { boxes: BoxSet, flags: Flags },
    ClearFlags(Flags),
    CopyFlags { src: Flags, dst: Flags },
    DrawList(IdList),
}

impl CullOp {
    /// Whether the command draws in the render pass after its compute pass.
    pub fn draws(&self) -> bool {
        matches!(self, Self::TestBoxes { .. } | Self::DrawList(_))
    }

    /// The command's resources, naming its compute bind group (a pyramid
    /// build has one per level, named by [`level_key`]).
    fn key(&self) -> [u32; 6] {
        match *self {
            Self::TestBoxes { boxes, ids, flags } => [0, boxes.0, ids.0, flags.0, 0, 0],
            Self::Expand { src, filter, table, into: ExpandInto::List(dst) } => [1, src.0, filter.0, table.0, dst.0, 0],
            Self::Expand { src, filter, table, into: ExpandInto::Flags(f) } => [2, src.0, filter.0, table.0, f.0, 0],
            Self::Compact { flags, unless, dst } => [3, flags.0, unless.map_or(u32::MAX, |u| u.0), dst.0, 0, 0],
            Self::ClearFlags(flags) => [4, flags.0, 0, 0, 0, 0],
            Self::CopyFlags { src, dst } => [9, src.0, dst.0, 0, 0, 0],
            Self::DrawList(list) => [5, list.0, 0, 0, 0, 0],
            Self::DropOutside { boxes, flags } => [6, boxes.0, flags.0, 0, 0, 0],
            Self::BuildPyramid(pyramid) => level_key(pyramid, 0),
            Self::TestPyramid { boxes, ids, pyramid, reach, flags } => [8, boxes.0, ids.0, pyramid.0, reach, flags.0],
        }
    }
}

/// Culling's part of a [`GpuScene`]: its pipelines, and per instance the
/// mesh range and triangle count that list draws need and its colour.
pub(crate) struct CullingScene {
    render: CullingPipelines,
    test_boxes: wgpu::ComputePipeline,
    expand_list: wgpu::ComputePipeline,
    expand_flags: wgpu::ComputePipeline,
    compact: wgpu::ComputePipeline,
    compact_unless: wgpu::ComputePipeline,
    drop_outside: wgpu::ComputePipeline,
    draw_args: wgpu::ComputePipeline,
    pyramid_level: wgpu::ComputePipeline,
    test_boxes_pyramid: wgpu::ComputePipeline,
    /// `InstanceDraw` of `cull.wgsl` per instance.
    instances: wgpu::Buffer,
    /// Group 1 of list draws: every instance's colour.
    colors: wgpu::BindGroup,
}

/// The compute bind group key of the reduction of `pyramid`'s `level`.
fn level_key(pyramid: Pyramid, level: u32) -> [u32; 6] {
    [7, pyramid.0, level, 0, 0, 0]
}

impl CullingScene {
    /// Builds the pipelines and uploads the per-instance data of `scene`.
    pub fn new(gpu: &GpuScene, scene: &Scene) -> Self {
        let device = &gpu.ctx.device;
        let module = cull_module(device, true);
        let compute = |entry: &str| compute_pipeline(device, &module, entry);
        let draws: Vec<[u32; 4]> = scene
            .instances
            .iter()
            .enumerate()
            .map(|(k, i)| {
                let m = gpu.meshes[i.mesh as usize];
                let triangles = scene.instance_triangles(k) as u32;
                [m.index_count, m.first_index, m.base_vertex as u32, triangles]
            })
            .collect();
        let colors: Vec<[f32; 4]> = scene.instances.iter().map(|i| material_color(i.material)).collect();
        let instances =
            storage_init(&gpu.ctx, "instance draws", bytemuck::cast_slice(&draws), wgpu::BufferUsages::empty());
        let colors =
            storage_init(&gpu.ctx, "instance colours", bytemuck::cast_slice(&colors), wgpu::BufferUsages::empty());
        let render = gpu.pipelines.culling(device, &module);
        let colors = bind_group(&gpu.ctx, "instance colours", &render.colors_layout, &[(1, &colors)]);
        Self {
            test_boxes: compute("cs_test_boxes"),
            expand_list: compute("cs_expand_list"),
            expand_flags: compute("cs_expand_flags"),
            compact: compute("cs_compact"),
            compact_unless: compute("cs_compact_unless"),
            drop_outside: compute("cs_drop_outside"),
            draw_args: compute("cs_draw_args"),
            pyramid_level: compute("cs_pyramid_level"),
            test_boxes_pyramid: compute("cs_test_boxes_pyramid"),
            render,
            instances,
            colors,
        }
    }

    /// The box-test render pipeline (vertex stage of the query boxes).
    pub fn test_pipeline(&self) -> &wgpu::RenderPipeline {
        &self.render.test
    }

    /// The list-draw render pipeline (vertex stage of the draws).
    pub fn list_pipeline(&self) -> &wgpu::RenderPipeline {
        &self.render.list
    }

    /// The counted-query render pipeline (vertex stage of the query boxes).
    pub fn count_pipeline(&self) -> &wgpu::RenderPipeline {
        &self.render.count
    }

    /// A bind group of `counts` as counted queries' group 1.
    pub fn counts_group(&self, ctx: &GpuContext, counts: &wgpu::Buffer) -> wgpu::BindGroup {
        bind_group(ctx, "query counts", &self.render.counts_layout, &[(2, counts)])
    }
}

/// A flag buffer and the bind group through which box-test fragments set it.
struct FlagBuffer {
    buffer: wgpu::Buffer,
    /// Slots (the buffer holds at least one, for an empty set).
    len: u32,
    fragment_group: wgpu::BindGroup,
}

/// An id list: count, capacity and ids in one buffer (the count doubles as
/// the draw count of list draws).
struct ListBuffer {
    buffer: wgpu::Buffer,
    capacity: u32,
}

/// A range table: ranges as `(first, count)` pairs, and the items.
pub(crate) struct TableBuffers {
    pub ranges: wgpu::Buffer,
    pub items: wgpu::Buffer,
}

impl TableBuffers {
    /// The table giving id `k` the items `items[ranges[k]]`, uploaded.
    pub fn new(ctx: &GpuContext, ranges: &[ItemRange], items: &[u32]) -> Self {
        let pairs: Vec<[u32; 2]> = ranges.iter().map(|r| [r.first, r.count]).collect();
        let empty = wgpu::BufferUsages::empty();
        let ranges = storage_init(ctx, "table ranges", bytemuck::cast_slice(&pairs), empty);
        let items = storage_init(ctx, "table items", bytemuck::cast_slice(items), empty);
        Self { ranges, items }
    }
}

/// A depth pyramid: its levels one after the other in `texels` (level 0 with
/// rows padded as texture copies need), and their places (`Level` of
/// `cull.wgsl`) in `levels`.
pub(crate) struct PyramidBuffers {
    pub texels: wgpu::Buffer,
    pub levels: wgpu::Buffer,
    /// Texels per level, level 0 first.
    pub counts: Vec<u32>,
    /// Bytes per row of level 0.
    row_bytes: u32,
}

impl PyramidBuffers {
    /// A pyramid over a `width` x `height` depth image, level 0's rows
    /// `pitch` texels apart (at least `width`), every texel at the far
    /// plane.
    pub fn new(ctx: &GpuContext, width: u32, height: u32, pitch: u32) -> Self {
        let mut table = Vec::new();
        let mut offset = 0;
        for (k, (w, h)) in level_sizes(width, height).into_iter().enumerate() {
            let pitch = if k == 0 { pitch } else { w };
            table.push([offset, w, h, pitch]);
            offset += pitch * h;
        }
        let far = vec![1f32; offset as usize];
        let texels = storage_init(ctx, "depth pyramid", bytemuck::cast_slice(&far), wgpu::BufferUsages::COPY_DST);
        let levels = storage_init(ctx, "pyramid levels", bytemuck::cast_slice(&table), wgpu::BufferUsages::empty());
        let counts = table.iter().map(|l| l[1] * l[2]).collect();
        Self { texels, levels, counts, row_bytes: 4 * pitch }
    }
}

/// What the box tests and list draws of a frame did, counted on the GPU.
pub(crate) struct CullStats {
    /// Draws inside list draws.
    pub draws: u64,
    /// Triangles of those draws.
    pub triangles: u64,
    /// Boxes the box tests rasterized (not those flagged near the eye or
    /// dropped outside the frustum).
    pub boxes: u64,
    /// One bit per instance drawn (bit `i % 32` of word `i / 32`).
    pub drawn: Vec<u32>,
}

/// One backend's culling resources, created outside frames and kept for the
/// backend's life.
pub(crate) struct Culling {
    gpu: Arc<GpuScene>,
    scene: Arc<CullingScene>,
    /// The backend's camera uniform, which box tests draw with.
    frame_camera: wgpu::Buffer,
    /// The backend's depth texture, which pyramids are built from.
    depth: wgpu::Texture,
    /// `Cull` of `cull.wgsl`: frustum planes and near region of the frame.
    camera: wgpu::Buffer,
    boxes: Vec<wgpu::Buffer>,
    flags: Vec<FlagBuffer>,
    lists: Vec<ListBuffer>,
    tables: Vec<TableBuffers>,
    pyramids: Vec<PyramidBuffers>,
    /// Uniforms holding one number (`param` of `cull.wgsl`: a level to
    /// reduce, a reach), by that number.
    params: HashMap<u32, wgpu::Buffer>,
    /// Scratch shared by the commands, which run one after the other: the
    /// raster list of box tests, its draw arguments, and list draws' draw
    /// arguments, for the largest list capacity.
    raster: wgpu::Buffer,
    box_draw: wgpu::Buffer,
    draw_args: wgpu::Buffer,
    scratch_capacity: u32,
    /// The frame group drawing `raster` as query boxes, made when needed.
    test_frame: Option<wgpu::BindGroup>,
    /// Compute bind groups by [`CullOp::key`].
    groups: HashMap<[u32; 6], wgpu::BindGroup>,
    stats: wgpu::Buffer,
    stats_staging: wgpu::Buffer,
    count_staging: wgpu::Buffer,
    /// Whether list draws take their count from the list (else the fallback:
    /// a multi-draw over the list's whole capacity).
    multi_draw_count: bool,
    /// Whether a box test or list draw was recorded since the statistics
    /// were last read.
    stats_pending: bool,
}

impl Culling {
    /// Resources for a backend on `gpu`, drawing box tests with the camera
    /// uniform `frame_camera` and building pyramids from `depth`.
    pub fn new(gpu: &Arc<GpuScene>, scene: &Scene, frame_camera: &wgpu::Buffer, depth: &wgpu::Texture) -> Self {
        let ctx = &gpu.ctx;
        let stats_bytes = STATS_HEADER + 4 * (scene.instances.len() as u64).div_ceil(32).max(1);
        let buffer = |label, size, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let staging = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ;
        let box_draw = [BOX_INDEX_COUNT, 0, 0, 0, 0];
        let indirect = wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST;
        Self {
            scene: gpu.culling(scene),
            gpu: Arc::clone(gpu),
            frame_camera: frame_camera.clone(),
            depth: depth.clone(),
            camera: cull_camera_buffer(&ctx.device),
            boxes: Vec::new(),
            flags: Vec::new(),
            lists: Vec::new(),
            tables: Vec::new(),
            pyramids: Vec::new(),
            params: HashMap::new(),
            raster: buffer("raster boxes", BOX_BYTES, wgpu::BufferUsages::STORAGE),
            box_draw: storage_init(ctx, "box-test draw", bytemuck::cast_slice(&box_draw), indirect),
            draw_args: buffer(
                "list draws",
                DRAW_ARGS_BYTES,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            ),
            scratch_capacity: 1,
            test_frame: None,
            groups: HashMap::new(),
            stats: buffer(
                "list-draw statistics",
                stats_bytes,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
            stats_staging: buffer("list-draw statistics read-back", stats_bytes, staging),
            count_staging: buffer("list count read-back", LIST_HEADER, staging),
            multi_draw_count: ctx.multi_draw_indirect_count(),
            stats_pending: false,
        }
    }

    fn ctx(&self) -> &GpuContext {
        &self.gpu.ctx
    }

    /// Sets the frame's camera for box tests (frustum planes, near region,
    /// view-projection matrix and the constants of pyramid footprints).
    pub fn set_camera(&self, camera: &Camera) {
        write_cull_camera(&self.ctx().queue, &self.camera, camera, PIXEL_MARGIN as f32);
    }

    /// Uploads `boxes` padded as query boxes, each with its slot; empty boxes
    /// stay empty (min > max), which tests skip.
    pub fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet {
        self.boxes.push(box_set_buffer(self.ctx(), boxes));
        BoxSet(self.boxes.len() as u32 - 1)
    }

    /// Rewrites the `changed` slots of `boxes` (one queue write each).
    pub fn update_boxes(&mut self, boxes: BoxSet, changed: &[(u32, Aabb)]) {
        write_boxes(&self.gpu.ctx.queue, &self.boxes[boxes.0 as usize], changed);
    }

    /// Drops every box set, flag buffer, list, table and pyramid, and the
    /// bind groups that name them.
    pub fn release_all(&mut self) {
        self.boxes.clear();
        self.flags.clear();
        self.lists.clear();
        self.tables.clear();
        self.pyramids.clear();
        self.groups.clear();
        self.test_frame = None;
    }

    /// A flag buffer of `len` slots, all 0.
    pub fn create_flags(&mut self, len: u32) -> Flags {
        let buffer = self.ctx().device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("flags"),
            size: 4 * u64::from(len.max(1)),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let layout = &self.scene.render.flags_layout;
        let fragment_group = bind_group(self.ctx(), "box-test flags", layout, &[(0, &buffer)]);
        self.flags.push(FlagBuffer { buffer, len, fragment_group });
        Flags(self.flags.len() as u32 - 1)
    }

    /// Sets the flags of `flags` to `set`, those past its end to 0 (a queue
    /// write, before the next submission's commands).
    pub fn write_flags(&self, flags: Flags, set: &[bool]) {
        let f = &self.flags[flags.0 as usize];
        let words: Vec<u32> = (0..f.len as usize).map(|k| u32::from(set.get(k).copied().unwrap_or(false))).collect();
        self.ctx().queue.write_buffer(&f.buffer, 0, bytemuck::cast_slice(&words));
    }

    /// A list of up to `capacity` ids holding `ids`; grows the scratch
    /// buffers to the capacity.
    pub fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList {
        assert!(ids.len() <= capacity as usize, "a list of capacity {capacity} cannot hold {} ids", ids.len());
        let mut words = vec![0u32; 2 + capacity.max(1) as usize];
        words[0] = ids.len() as u32;
        words[1] = capacity;
        words[2..2 + ids.len()].copy_from_slice(ids);
        let usage = wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let buffer = storage_init(self.ctx(), "id list", bytemuck::cast_slice(&words), usage);
        self.lists.push(ListBuffer { buffer, capacity });
        if capacity > self.scratch_capacity {
            self.grow_scratch(capacity);
        }
        IdList(self.lists.len() as u32 - 1)
    }

    /// A table giving id `k` the items `items[ranges[k]]`.
    pub fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable {
        let table = TableBuffers::new(self.ctx(), ranges, items);
        self.tables.push(table);
        RangeTable(self.tables.len() as u32 - 1)
    }

    /// A depth pyramid over the depth texture, every texel at the far plane.
    pub fn create_pyramid(&mut self) -> Pyramid {
        let (width, height) = (self.depth.width(), self.depth.height());
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let row_bytes = (4 * width).div_ceil(align) * align;
        let pyramid = PyramidBuffers::new(self.ctx(), width, height, row_bytes / 4);
        self.pyramids.push(pyramid);
        Pyramid(self.pyramids.len() as u32 - 1)
    }

    /// The levels of `pyramid` past level 0: the dispatches of its build.
    pub fn reductions(&self, pyramid: Pyramid) -> u64 {
        self.pyramids[pyramid.0 as usize].counts.len() as u64 - 1
    }

    /// The uniform holding `value` in its first word, made on first use.
    fn param(&mut self, value: u32) -> wgpu::Buffer {
        let ctx = Arc::clone(&self.gpu.ctx);
        self.params.entry(value).or_insert_with(|| param_buffer(&ctx.device, value)).clone()
    }

    /// Encodes the build of `pyramid`: the depth texture copied into level
    /// 0, then one dispatch per further level, in one compute pass.
    fn encode_pyramid_build(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        pyramid: Pyramid,
        timer: Option<&mut PassTimer>,
    ) {
        let p = &self.pyramids[pyramid.0 as usize];
        let (width, height) = (self.depth.width(), self.depth.height());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.depth,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::DepthOnly,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &p.texels,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(p.row_bytes),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        let counts = p.counts.clone();
        let scene = Arc::clone(&self.scene);
        let groups: Vec<wgpu::BindGroup> = (1..counts.len() as u32)
            .map(|level| {
                let param = self.param(level);
                let p = &self.pyramids[pyramid.0 as usize];
                let (texels, levels) = (p.texels.clone(), p.levels.clone());
                let entries = [(14, &texels), (15, &levels), (16, &param)];
                self.cached_group(level_key(pyramid, level), &scene.pyramid_level, &entries)
            })
            .collect();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("depth pyramid"),
            timestamp_writes: timer.and_then(|t| t.compute_pass_doing(PassKind::Pyramid)),
        });
        dispatch_reductions(&mut pass, &scene.pyramid_level, &groups, &counts);
    }

    /// The compute bind group `key` of `entries` for `pipeline`, made on
    /// first use.
    fn cached_group(
        &mut self,
        key: [u32; 6],
        pipeline: &wgpu::ComputePipeline,
        entries: &[(u32, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        let ctx = &self.gpu.ctx;
        self.groups
            .entry(key)
            .or_insert_with(|| bind_group(ctx, "culling", &pipeline.get_bind_group_layout(0), entries))
            .clone()
    }

    /// Replaces the scratch buffers by ones for lists of `capacity` ids; the
    /// bind groups naming the old ones go.
    fn grow_scratch(&mut self, capacity: u32) {
        let device = &self.gpu.ctx.device;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let cap = u64::from(capacity);
        self.raster = buffer("raster boxes", cap * BOX_BYTES, wgpu::BufferUsages::STORAGE);
        self.draw_args =
            buffer("list draws", cap * DRAW_ARGS_BYTES, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT);
        self.scratch_capacity = capacity;
        self.test_frame = None;
        self.groups.clear();
    }

    /// Notes a box test or list draw: the statistics are to be read after
    /// the frame.
    pub fn note_counted(&mut self) {
        self.stats_pending = true;
    }

    /// Encodes `op`'s compute work: the buffer clears it starts with, then
    /// its dispatch in a compute pass of its own (timed when `timer` is
    /// given). Clearing flags is a buffer clear alone, copying them a
    /// buffer copy.
    pub fn encode_compute(&mut self, encoder: &mut wgpu::CommandEncoder, op: &CullOp, timer: Option<&mut PassTimer>) {
        let scene = Arc::clone(&self.scene);
        let (pipeline, threads) = match *op {
            CullOp::ClearFlags(flags) => {
                encoder.clear_buffer(&self.flags[flags.0 as usize].buffer, 0, None);
                return;
            }
            CullOp::CopyFlags { src, dst } => {
                let (src, dst) = (&self.flags[src.0 as usize], &self.flags[dst.0 as usize]);
                let bytes = 4 * u64::from(src.len.min(dst.len));
                if src.len < dst.len {
                    encoder.clear_buffer(&dst.buffer, bytes, None);
                }
                if bytes > 0 {
                    encoder.copy_buffer_to_buffer(&src.buffer, 0, &dst.buffer, 0, bytes);
                }
                return;
            }
            CullOp::BuildPyramid(pyramid) => return self.encode_pyramid_build(encoder, pyramid, timer),
            CullOp::TestPyramid { ids, .. } => (&scene.test_boxes_pyramid, self.lists[ids.0 as usize].capacity),
            CullOp::TestBoxes { ids, .. } => {
                // Zero the box draw's instance count (the appended boxes).
                encoder.clear_buffer(&self.box_draw, 4, Some(4));
                (&scene.test_boxes, self.lists[ids.0 as usize].capacity)
            }
            CullOp::Expand { src, into, .. } => {
                let pipeline = match into {
                    ExpandInto::List(dst) => {
                        encoder.clear_buffer(&self.lists[dst.0 as usize].buffer, 0, Some(4));
                        &scene.expand_list
                    }
                    ExpandInto::Flags(_) => &scene.expand_flags,
                };
                (pipeline, self.lists[src.0 as usize].capacity)
            }
            CullOp::Compact { flags, unless, dst } => {
                encoder.clear_buffer(&self.lists[dst.0 as usize].buffer, 0, Some(4));
                let pipeline = if unless.is_some() { &scene.compact_unless } else { &scene.compact };
                (pipeline, (self.flags[flags.0 as usize].buffer.size() / 4) as u32)
            }
            CullOp::DrawList(list) => (&scene.draw_args, self.lists[list.0 as usize].capacity),
            CullOp::DropOutside { flags, .. } => {
                (&scene.drop_outside, (self.flags[flags.0 as usize].buffer.size() / 4) as u32)
            }
        };
        let group = self.compute_group(op, pipeline);
        if matches!(op, CullOp::TestBoxes { .. }) && self.test_frame.is_none() {
            self.test_frame = Some(frame_group(&self.gpu, &self.frame_camera, &self.raster));
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("culling"),
            timestamp_writes: timer.and_then(PassTimer::compute_pass),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        let (x, y) = workgroups(threads);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Encodes the draw of a box test or a list draw into `pass`, whose
    /// pipeline ([`CullingScene::test_pipeline`] or
    /// [`CullingScene::list_pipeline`]), index buffer, vertex buffer and (for
    /// list draws) frame group are bound; after a box test, group 0 holds
    /// the raster list's frame group.
    pub fn encode_draw(&self, pass: &mut wgpu::RenderPass<'_>, op: &CullOp) {
        match *op {
            CullOp::TestBoxes { flags, .. } => {
                let Some(test_frame) = &self.test_frame else { return };
                pass.set_bind_group(0, test_frame, &[]);
                pass.set_bind_group(1, &self.flags[flags.0 as usize].fragment_group, &[]);
                pass.draw_indexed_indirect(&self.box_draw, 0);
            }
            CullOp::DrawList(list) => {
                let list = &self.lists[list.0 as usize];
                pass.set_bind_group(1, &self.scene.colors, &[]);
                if self.multi_draw_count {
                    pass.multi_draw_indexed_indirect_count(&self.draw_args, 0, &list.buffer, 0, list.capacity);
                } else {
                    pass.multi_draw_indexed_indirect(&self.draw_args, 0, list.capacity);
                }
            }
            _ => {}
        }
    }

    /// The shared part: the box-test and list-draw pipelines.
    pub fn scene(&self) -> &CullingScene {
        &self.scene
    }

    /// The compute bind group of `op` for `pipeline`, made on first use.
    fn compute_group(&mut self, op: &CullOp, pipeline: &wgpu::ComputePipeline) -> wgpu::BindGroup {
        if let Some(group) = self.groups.get(&op.key()) {
            return group.clone();
        }
        let reach = match *op {
            CullOp::TestPyramid { reach, .. } => Some(self.param(reach)),
            _ => None,
        };
        let list = |l: IdList| &self.lists[l.0 as usize].buffer;
        let flags = |f: Flags| &self.flags[f.0 as usize].buffer;
        let table = |t: RangeTable| &self.tables[t.0 as usize];
        let entries: Vec<(u32, &wgpu::Buffer)> = match *op {
            CullOp::TestBoxes { boxes, ids, flags: f } => vec![
                (0, &self.camera),
                (1, &self.boxes[boxes.0 as usize]),
                (2, list(ids)),
                (3, flags(f)),
                (4, &self.raster),
                (5, &self.box_draw),
                (13, &self.stats),
            ],
            CullOp::Expand { src, filter, table: t, into } => {
                let out = match into {
                    ExpandInto::List(dst) => (8, list(dst)),
                    ExpandInto::Flags(f) => (3, flags(f)),
                };
                vec![(2, list(src)), (6, flags(filter)), out, (9, &table(t).ranges), (10, &table(t).items)]
            }
            CullOp::Compact { flags: f, unless, dst } => {
                let mut entries = vec![(6, flags(f)), (8, list(dst))];
                entries.extend(unless.map(|u| (7, flags(u))));
                entries
            }
            CullOp::DrawList(l) => {
                vec![(2, list(l)), (11, &self.scene.instances), (12, &self.draw_args), (13, &self.stats)]
            }
            CullOp::DropOutside { boxes, flags: f } => {
                vec![(0, &self.camera), (1, &self.boxes[boxes.0 as usize]), (3, flags(f))]
            }
            CullOp::TestPyramid { boxes, ids, pyramid, flags: f, .. } => {
                let p = &self.pyramids[pyramid.0 as usize];
                let mut entries = vec![(0, &self.camera), (1, &self.boxes[boxes.0 as usize]), (2, list(ids))];
                entries.extend([(3, flags(f)), (13, &self.stats), (14, &p.texels), (15, &p.levels)]);
                entries.extend(reach.as_ref().map(|r| (16, r)));
                entries
            }
            CullOp::ClearFlags(_) | CullOp::CopyFlags { .. } | CullOp::BuildPyramid(_) => Vec::new(),
        };
        let group = bind_group(self.ctx(), "culling", &pipeline.get_bind_group_layout(0), &entries);
        self.groups.insert(op.key(), group.clone());
        group
    }

    /// The length of `list` after all submitted work, read back (blocking).
    pub fn read_count(&self, list: IdList) -> Result<u32, String> {
        let list = &self.lists[list.0 as usize];
        let header = self.read_words(&list.buffer, LIST_HEADER, &self.count_staging)?;
        Ok(header[0].min(list.capacity))
    }

    /// The ids of `list` after all submitted work, read back (blocking).
    pub fn read_list(&self, list: IdList) -> Result<Vec<u32>, String> {
        let list = &self.lists[list.0 as usize];
        let size = list.buffer.size();
        let mut words = self.read_words(&list.buffer, size, &self.staging(size))?;
        let count = words[0].min(list.capacity) as usize;
        Ok(words.drain(2..2 + count).collect())
    }

    /// The flags of `flags` after all submitted work, read back (blocking).
    pub fn read_flags(&self, flags: Flags) -> Result<Vec<bool>, String> {
        let flags = &self.flags[flags.0 as usize];
        let size = flags.buffer.size();
        let words = self.read_words(&flags.buffer, size, &self.staging(size))?;
        Ok(words[..flags.len as usize].iter().map(|&w| w != 0).collect())
    }

    /// A read-back buffer of `size` bytes, for the instruments' reads.
    fn staging(&self, size: u64) -> wgpu::Buffer {
        self.ctx().device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("culling read-back"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        })
    }

    /// The first `size` bytes of `source` after all submitted work, copied
    /// through `staging` and read back (blocking), as words.
    fn read_words(&self, source: &wgpu::Buffer, size: u64, staging: &wgpu::Buffer) -> Result<Vec<u32>, String> {
        let ctx = self.ctx();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(source, 0, staging, 0, size);
        ctx.queue.submit([encoder.finish()]);
        Mapping::start(staging, size).wait(ctx)?;
        Ok(bytemuck::pod_collect_to_vec(&take_bytes(staging, size)?))
    }

    /// What the box tests and list draws since the last call did (`None`
    /// when there were none), read back after all submitted work (blocking), and the
    /// counters zeroed for the next frame.
    pub fn take_stats(&mut self) -> Result<Option<CullStats>, String> {
        if !std::mem::take(&mut self.stats_pending) {
            return Ok(None);
        }
        let ctx = &self.gpu.ctx;
        let size = self.stats.size();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.stats, 0, &self.stats_staging, 0, size);
        encoder.clear_buffer(&self.stats, 0, None);
        ctx.queue.submit([encoder.finish()]);
        Mapping::start(&self.stats_staging, size).wait(ctx)?;
        let bytes = take_bytes(&self.stats_staging, size)?;
        let words: Vec<u32> = bytes.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        Ok(Some(CullStats {
            draws: u64::from(words[0]),
            triangles: u64::from(words[1]) | u64::from(words[2]) << 32,
            boxes: u64::from(words[3]),
            drawn: words[4..].to_vec(),
        }))
    }
}

/// The culling shaders: `cull.wgsl`, with `cull_fragments.wgsl` appended
/// when `fragments` (box tests and counted queries rasterize; the device
/// must have `SHADER_EARLY_DEPTH_TEST`); the compute passes alone need only
/// `cull.wgsl`.
pub(crate) fn cull_module(device: &wgpu::Device, fragments: bool) -> wgpu::ShaderModule {
    let source = if fragments {
        concat!(include_str!("cull.wgsl"), include_str!("cull_fragments.wgsl"))
    } else {
        include_str!("cull.wgsl")
    };
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("occlude culling shaders"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// Writes the culling camera uniform `buffer` (`Cull` of `cull.wgsl`) for
/// `camera`: frustum planes, near region, the view-projection matrix the
/// backends rasterize (depth 0 nearest) and the constants of pyramid
/// footprints, which are grown by `pixel_margin` pixels
/// ([`PIXEL_MARGIN`]; with MSAA half a pixel more, for samples off the
/// pixels' centres).
pub(crate) fn write_cull_camera(queue: &wgpu::Queue, buffer: &wgpu::Buffer, camera: &Camera, pixel_margin: f32) {
    let mut uniform = [0f32; CAMERA_BYTES as usize / 4];
    for (k, plane) in camera.frustum().planes.iter().enumerate() {
        uniform[4 * k..4 * k + 4].copy_from_slice(&plane.to_array());
    }
    let near = camera.near_region();
    uniform[24..28].copy_from_slice(&near.center.extend(near.radius * near.radius).to_array());
    uniform[28..44].copy_from_slice(&camera.view_projection().to_cols_array());
    uniform[44..47].copy_from_slice(&[QUERY_DEPTH_BIAS, DEPTH_SLACK, pixel_margin]);
    queue.write_buffer(buffer, 0, bytemuck::cast_slice(&uniform));
}

/// A uniform buffer for [`write_cull_camera`].
pub(crate) fn cull_camera_buffer(device: &wgpu::Device) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("culling camera"),
        size: CAMERA_BYTES,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A `param` uniform of `cull.wgsl` holding `value` in its first word.
pub(crate) fn param_buffer(device: &wgpu::Device, value: u32) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("culling parameter"),
        contents: bytemuck::cast_slice(&[value, 0, 0, 0]),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// A box set's storage buffer: `boxes` padded as query boxes, each with its
/// slot; empty boxes stay empty (min > max), which tests skip.
pub(crate) fn box_set_buffer(ctx: &GpuContext, boxes: &[Aabb]) -> wgpu::Buffer {
    let data: Vec<[u32; 8]> = boxes.iter().zip(0u32..).map(|(b, slot)| box_words(b, slot)).collect();
    storage_init(ctx, "box set", bytemuck::cast_slice(&data), wgpu::BufferUsages::COPY_DST)
}

/// Writes each `(slot, box)` of `changed` into the box set `buffer` (made
/// by [`box_set_buffer`]), one queue write per box.
pub(crate) fn write_boxes(queue: &wgpu::Queue, buffer: &wgpu::Buffer, changed: &[(u32, Aabb)]) {
    for (slot, b) in changed {
        let words = box_words(b, *slot);
        queue.write_buffer(buffer, u64::from(*slot) * BOX_SLOT_BYTES, bytemuck::cast_slice(&words));
    }
}

/// Bytes of one box of a box set.
const BOX_SLOT_BYTES: u64 = 32;

/// Box `b` in slot `slot` of a box set, padded as a query box; an empty box
/// stays empty (min > max), which tests skip.
fn box_words(b: &Aabb, slot: u32) -> [u32; 8] {
    let (lo, hi) = if b.is_empty() {
        (glam::Vec3::ONE, glam::Vec3::ZERO)
    } else {
        let p = b.expanded(QUERY_BOX_PAD, QUERY_BOX_PAD * b.min.abs().max(b.max.abs()).max_element());
        (p.min, p.max)
    };
    let [lx, ly, lz] = lo.to_array().map(f32::to_bits);
    let [hx, hy, hz] = hi.to_array().map(f32::to_bits);
    [lx, ly, lz, slot, hx, hy, hz, 0]
}

/// Records a pyramid's reductions into `pass`: `pipeline`
/// (`cs_pyramid_level`) once per level past level 0 with that level's bind
/// group, over `counts` (texels per level, level 0 first).
pub(crate) fn dispatch_reductions(
    pass: &mut wgpu::ComputePass<'_>,
    pipeline: &wgpu::ComputePipeline,
    groups: &[wgpu::BindGroup],
    counts: &[u32],
) {
    pass.set_pipeline(pipeline);
    for (group, &texels) in groups.iter().zip(&counts[1..]) {
        pass.set_bind_group(0, group, &[]);
        let (x, y) = workgroups(texels);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// Workgroups `(x, y)` covering `threads` threads, `x` within the limit.
pub(crate) fn workgroups(threads: u32) -> (u32, u32) {
    let groups = threads.div_ceil(GROUP_SIZE).max(1);
    let x = groups.min(MAX_GROUPS_PER_DIMENSION);
    (x, groups.div_ceil(x))
}

/// A storage buffer holding `contents`, with `usage` besides; zeros follow up
/// to 32 bytes, so that even an empty array binds one element of any type
/// here.
pub(crate) fn storage_init(ctx: &GpuContext, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let mut bytes = contents.to_vec();
    bytes.resize(contents.len().max(BOX_BYTES as usize), 0);
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &bytes,
        usage: wgpu::BufferUsages::STORAGE | usage,
    })
}

/// A bind group of whole buffers at the given bindings.
pub(crate) fn bind_group(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let resources: Vec<_> = buffers.iter().map(|&(binding, buffer)| (binding, buffer.as_entire_binding())).collect();
    pipelines::bind_group(&ctx.device, label, layout, &resources)
}

#[cfg(test)]
mod tests;
