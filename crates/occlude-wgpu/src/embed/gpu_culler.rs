//! [`GpuCuller`]: two-phase GPU-driven culling in a renderer's own passes,
//! its visibility never leaving the GPU: Hi-Z (`hiz`,
//! [`occlude_core::methods::hiz`]), raster occlusion culling (`roc`,
//! [`occlude_core::methods::roc`]; IOC poster, section 1) or its
//! hierarchical form (`ioc`, [`occlude_core::methods::ioc`]; IOC poster,
//! section 2), or `auto`'s choice among them (`gpu_auto.rs`). Each frame
//! occlude writes two lists of visible instance ids
//! (the early pass's and the late pass's), each with one indirect command
//! per draw group and mesh (`draws.rs`), and the renderer draws each list
//! with a multi-draw per group of its own. The compute
//! shaders are `cull.wgsl`'s, as the wgpu backend's GPU-resident culling
//! runs them (frustum drop, compaction, pyramid reduction and pyramid box
//! test), plus `cs_pyramid_base`, which reads level 0 from the renderer's
//! depth texture; `roc`'s and `ioc`'s box tests are the backend's too
//! (`box_tests.rs`), `ioc`'s walk is `node_levels.rs`.

//!
//! A frame, in the renderer's encoder: `encode_early` drops last frame's
//! visible instances whose boxes left the frustum and compacts the rest
//! into the early list; the renderer draws it; `encode_late` tests every
//! box against the depth that draw left (`hiz`: a pyramid of the depth
//! texture, each level the 2x2 maximum of the one before; `roc`: the boxes
//! rasterized in a read-only depth pass, each fragment that passes its
//! forced early depth test setting a flag; `ioc`: so, the BVH's node boxes
//! level by level, a hidden node ending the descent) and compacts the
//! instances visible now and not drawn early into the late list; the
//! renderer draws it. After each compaction `draws.rs` sorts the list by
//! (group, mesh) and writes the draw commands.
//!
//! Why the image is the image without culling: an instance with a pixel in
//! the final image is at that pixel no farther than the early pass's
//! depth. So its box (which holds it, padded and pulled towards the eye)
//! passes `roc`'s depth test there (as does every node box above it, for
//! `ioc`), and is not hidden by `hiz`'s pyramid, whose texels are at least
//! the farthest depth of the pixels they cover
//! ([`occlude_core::depth_pyramid`] has the proof). Level 0 reads the depth
//! texture with two changes: reverse Z turned into depth 0 nearest
//! (`1 - d`), and each texel taken 2^-22 farther, which covers a 24-bit
//! depth buffer's rounding and that of `1 - d`. With MSAA a texel is the
//! farthest of its pixel's samples and footprints cover every pixel a box
//! touches, since a sample off the centre may show an instance; box tests
//! and their fragments count samples.
use super::backend::{begin_pass, PassStart};
use super::box_tests::{BoxTest, BoxTests, TestInputs};
use super::draws::{DrawTables, Draws, VisibleList};
use super::gpu_auto::GpuAuto;
use super::node_levels::{NodeLevels, WalkInputs};
use super::passes::{PassCounts, Tally};
use super::{Attachments, EmbedError, FrameTarget};
use crate::context::GpuContext;
use crate::culling::{
    bind_group, box_set_buffer, cull_camera_buffer, cull_module, param_buffer, storage_init, write_boxes,
    write_cull_camera, PyramidBuffers,
};
use crate::pipelines::compute_pipeline;
use crate::readback::{take_bytes, Mapping};
use occlude_core::depth_pyramid::PIXEL_MARGIN;
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::auto::cold_frames;
use occlude_core::methods::hiz::{Granularity, HizParams};
use occlude_core::methods::ioc::IocWalk;
use occlude_core::methods::roc::RocMode;
use occlude_core::methods::{Method, MethodError};
use occlude_core::{
    Aabb, Camera, Hierarchy, HierarchyKind, InstanceChange, NodeId, Scene, Since, UpdatePolicy, Upkeep,
};

/// The methods [`GpuCuller`] runs: `hiz`, whose every step is a compute
/// pass over the renderer's depth, and `roc` and `ioc` (`roc` over a BVH
/// of the boxes, level by level), whose box tests rasterize the boxes
/// against the renderer's depth texture with a fragment stage writing
/// flags (their device needs [`RASTER_FEATURES`]); and `auto`, which runs
/// `roc`'s test (where the device has those features), `hiz`'s or only the
/// frustum's each frame, whichever its GPU time says is fastest.
pub const GPU_METHODS: [&str; 4] = ["hiz", "roc", "ioc", "auto"];

/// The device features `roc` and `ioc` need in a [`GpuCuller`] (checked
/// only for them): forced early depth tests, so that a box's fragments set
/// its flag only where they passed the depth test.
pub const RASTER_FEATURES: wgpu::Features = wgpu::Features::SHADER_EARLY_DEPTH_TEST;

/// The storage buffers `cs_test_boxes_pyramid`, the culling shader using
/// most, binds in one stage.
const STORAGE_BUFFERS_NEEDED: u32 = 6;

/// Threads per workgroup of `cull.wgsl`'s compute shaders.
const WORKGROUP_THREADS: u32 = 64;

/// The pyramid of one depth-texture size and the bind groups naming it.
struct PyramidState {
    size: (u32, u32),
    buffers: PyramidBuffers,
    /// The reductions' groups, level 1 first.
    reductions: Vec<wgpu::BindGroup>,
    /// The pyramid test's group writing flag buffer 0 or 1.
    tests: [wgpu::BindGroup; 2],
}

/// `hiz`'s late test: a depth pyramid of the early pass's depth, every
/// instance's box tested against it.
struct PyramidTest {
    base: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    test: wgpu::ComputePipeline,
    /// `param` uniforms: the pyramid test's reach, and for level 0 whether
    /// depth is reverse Z and the viewport's corner, written each frame
    /// (each reduction's level is made with the pyramid).
    reach: wgpu::Buffer,
    base_param: wgpu::Buffer,
    /// The depth texture's binding: 17 single-sample, 18 multisampled.
    depth_binding: u32,
    /// Made for the first frame's depth size, and again when it changes.
    state: Option<PyramidState>,
}

/// How the late phase finds this frame's visible instances.
enum LateTest {
    /// `hiz`: against a depth pyramid, in compute passes.
    Pyramid(PyramidTest),
    /// `roc`: every instance's box rasterized against the depth texture,
    /// its test's groups for flag parity 0 and 1.
    Every(BoxTests, [BoxTest; 2]),
    /// `ioc`: the BVH's node boxes rasterized level by level, then the
    /// instances marked visible outside the frustum dropped.
    Nodes(BoxTests, NodeLevels, Box<Hierarchy>),
    /// `vfc` (one of `auto`'s choices): every instance marked visible from
    /// this buffer of ones, then those outside the frustum dropped.
    Frustum(wgpu::Buffer),
}

impl LateTest {
    /// The method the test is.
    fn name(&self) -> &'static str {
        match self {
            LateTest::Pyramid(_) => "hiz",
            LateTest::Every(..) => "roc",
            LateTest::Nodes(..) => "ioc",
            LateTest::Frustum(_) => "vfc",
        }
    }
}

/// Two-phase GPU-driven culling (`hiz`, `roc`, `ioc`, `auto`) in a
/// renderer's own passes: give it the renderer's device, attachments,
/// per-instance boxes and how each instance is drawn once; each frame, the
/// camera and the frame's views, and draw its two [`VisibleList`]s.
///
/// **`auto`**, the method to start with, runs one late test a frame:
/// `roc`'s (where the device has [`RASTER_FEATURES`]), `hiz`'s, or none
/// beyond the frustum, whichever measured fastest, probing the others
/// within 1 % of the time ([`occlude_core::methods::auto`]). *Cost:* its
/// first frames try each test; two timestamps and a 16-byte read-back a
/// frame; the buffers of all three tests. *Requirements:* a depth texture
/// with `TEXTURE_BINDING` (for `hiz`); each frame's commands submitted
/// before the next frame's [`GpuCuller::encode_early`]; `TIMESTAMP_QUERY`
/// on the device for GPU times, else it times frames by the wall clock
/// between early phases (which a frame-rate cap makes all alike: then it
/// keeps what it runs). *Limits:* it does not choose `ioc`.
///
/// # Example
///
/// ```no_run
/// use occlude_wgpu::embed::{Attachments, FrameTarget, GpuCuller, IndirectDraw};
/// use glam::{Mat4, Vec3};
/// use occlude_core::methods::{hiz::HizParams, Method};
/// use occlude_core::{Aabb, Camera};
///
/// # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, color: &wgpu::TextureView,
/// #          depth: &wgpu::TextureView, pipeline: &wgpu::RenderPipeline,
/// #          instances: &wgpu::BindGroup) -> Result<(), Box<dyn std::error::Error>> {
/// // Once: your attachments, one box per instance, how an instance is drawn,
/// // and where your vertex shader reads the list: group 1, binding 0.
/// let attachments = Attachments {
///     color: Some(wgpu::TextureFormat::Rgba8Unorm),
///     depth: wgpu::TextureFormat::Depth32Float,
///     compare: wgpu::CompareFunction::Less,
///     samples: 1,
/// };
/// let bounds: Vec<Aabb> = (0..1000).map(|i| {
///     let at = Vec3::new((i % 40) as f32 * 2.0, 0.0, -((i / 40) as f32) * 2.0);
///     Aabb::new(at, at + Vec3::ONE)
/// }).collect();
/// let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
/// let method = Method::Hiz(HizParams { texels: 4, ..Default::default() });
/// let mut culler = GpuCuller::new(device, queue, attachments, &bounds, &method, draw)?
///     .with_list_pipeline(pipeline, 1, 0)?;
///
/// // Each frame: your camera, your views, your other bind groups and buffers;
/// // occlude sets your pipeline and the list and draws it indirectly.
/// let view = Mat4::look_at_rh(Vec3::new(40.0, 2.0, 10.0), Vec3::new(40.0, 0.0, 0.0), Vec3::Y);
/// let projection = Mat4::perspective_rh(1.0, 1.0, 0.1, 200.0);
/// let camera = Camera::from_matrices(view, projection, false)?;
/// let target = FrameTarget::new(Some(color), wgpu::Color::BLACK, depth);
/// culler.render_lists(&camera, target, |pass| pass.set_bind_group(0, instances, &[]))?;
/// # Ok(())
/// # }
/// ```
pub struct GpuCuller {
    ctx: GpuContext,
    attachments: Attachments,
    /// The instances' boxes as they stand ([`GpuCuller::update`]).
    scene: Scene,
    camera: wgpu::Buffer,
    boxes: wgpu::Buffer,
    all: wgpu::Buffer,
    stats: wgpu::Buffer,
    /// Per-instance visibility: this frame's is `flags[parity]`, last
    /// frame's the other.
    flags: [wgpu::Buffer; 2],
    parity: usize,
    /// The early and the late list as the compaction writes them.
    compacted: [wgpu::Buffer; 2],
    /// The renderer's lists: the compacted ones sorted by draw bucket,
    /// with their draw commands.
    lists: [VisibleList; 2],
    draws: DrawTables,
    /// The renderer's pipeline drawing the lists
    /// ([`GpuCuller::with_list_pipeline`]).
    pipeline: Option<wgpu::RenderPipeline>,
    /// Drop outside the frustum, compact into the early list, compact the
    /// newly visible into the late list; each for flag parity 0 and 1.
    drop_outside: (wgpu::ComputePipeline, [wgpu::BindGroup; 2]),
    compact_early: (wgpu::ComputePipeline, [wgpu::BindGroup; 2]),
    compact_late: (wgpu::ComputePipeline, [wgpu::BindGroup; 2]),
    /// The late tests it may run: one, or `auto`'s choices.
    late: Vec<LateTest>,
    /// The late test this frame runs.
    running: usize,
    /// `auto`'s choice among `late`.
    auto: Option<GpuAuto>,
    counts_staging: wgpu::Buffer,
    /// The camera of a frame whose early phase is recorded and late phase
    /// not yet.
    frame_camera: Option<Camera>,
    /// The passes and dispatches recorded since the last early phase.
    tally: Tally,
}

impl GpuCuller {
    /// Whether `method` runs in a [`GpuCuller`]: `hiz` with any
    /// `hiz.texels` at instance granularity, `roc` in its exact mode, `ioc`
    /// with any start and bottom levels, its frustum test on and no
    /// `ioc.auto`. Anything else is an error naming the method or the
    /// setting.
    pub fn check_method(method: &Method) -> Result<(), EmbedError> {
        method.params().map_err(MethodError::from)?;
        let setting = match method {
            Method::Hiz(p) if p.granularity != Granularity::Instance => "hiz.granularity=node",
            Method::Roc(p) if p.mode != RocMode::Exact => "roc.mode=last",
            Method::Ioc(p) if !p.frustum => "ioc.frustum=off",
            Method::Ioc(p) if p.auto => "ioc.auto=on",
            Method::Auto(p) if !p.gpu => "auto.gpu=off",
            Method::Hiz(_) | Method::Roc(_) | Method::Ioc(_) | Method::Auto(_) => return Ok(()),
            other => return Err(EmbedError::Unsupported(other.name().to_string())),
        };
        Err(EmbedError::UnsupportedSetting(setting.to_string()))
    }

    /// Culls instances whose world-space boxes are `bounds` (instance `i`
    /// is `bounds[i]`; its draws must stay inside that box) with the
    /// GPU-driven method `method` (one of [`GPU_METHODS`]; the parameters
    /// [`GpuCuller::check_method`] accepts) on the renderer's `device` and
    /// `queue`, whose passes draw into `attachments`, each instance drawn
    /// as `draws` says (an [`IndirectDraw`](super::IndirectDraw) when all
    /// draw one mesh). A method that does not run here, bad boxes,
    /// attachments or draws, or a device without what the method and the
    /// draws need (compute passes; for `roc` and `ioc` also
    /// `SHADER_EARLY_DEPTH_TEST`; for several meshes or groups
    /// `INDIRECT_FIRST_INSTANCE`) are an error.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        attachments: Attachments,
        bounds: &[Aabb],
        method: &Method,
        draws: impl Into<Draws>,
    ) -> Result<Self, EmbedError> {
        Self::for_scene(device, queue, attachments, Scene::from_bounds("embedded", bounds)?, method, draws)
    }

    /// [`GpuCuller::new`] over `scene`'s instances, as they stand (their
    /// culling boxes; hidden ones hidden): for a renderer that keeps its
    /// scene as an occlude [`Scene`], whose frames' changes
    /// ([`GpuCuller::update`]) then move instances by their transforms.
    pub fn for_scene(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        attachments: Attachments,
        scene: Scene,
        method: &Method,
        draws: impl Into<Draws>,
    ) -> Result<Self, EmbedError> {
        Self::check_method(method)?;
        // `auto` chooses among `roc` (where the device rasterizes box
        // tests), `hiz` and `vfc`.
        let methods = match method {
            Method::Auto(_) => {
                let roc = device.features().contains(RASTER_FEATURES).then(|| Method::Roc(Default::default()));
                roc.into_iter().chain([Method::Hiz(HizParams::default()), Method::Vfc]).collect()
            }
            one => vec![one.clone()],
        };
        let raster = methods.iter().any(|m| matches!(m, Method::Roc(_) | Method::Ioc(_)));
        attachments.check()?;
        check_device(device, raster)?;
        scene.validate()?;
        let ctx = GpuContext::from_device(device, queue);
        // Where the device lacks what the box tests need after all (storage
        // written by fragment shaders, on some GL drivers), making their
        // pipelines fails validation: that is the device's refusal.
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = cull_module(device, raster);
        let compute = |entry: &str| compute_pipeline(device, &module, entry);
        let n = scene.instances.len() as u32;
        let boxes: Vec<Aabb> = scene.instances.iter().map(|i| i.culling_bounds()).collect();
        let list_usage = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let list = |ids: &[u32]| {
            let mut words = vec![ids.len() as u32, n];
            words.extend(ids);
            words.resize(2 + n as usize, 0);
            storage_init(&ctx, "visible instances", bytemuck::cast_slice(&words), list_usage)
        };
        let all = list(&(0..n).collect::<Vec<_>>());
        let flag_usage = wgpu::BufferUsages::COPY_DST;
        let flags = [0, 1].map(|_| storage_init(&ctx, "visibility", &vec![0; 4 * n as usize], flag_usage));
        let compacted = [0, 1].map(|_| list(&[]));
        let draws = DrawTables::new(&ctx, &draws.into(), n)?;
        let lists = [0, 1].map(|index| draws.list(&ctx, &compacted[index], n, index));
        let boxes = box_set_buffer(&ctx, &boxes);
        let camera = cull_camera_buffer(device);
        let stats = storage_init(&ctx, "culling statistics", &[], wgpu::BufferUsages::empty());
        // Flag parity p: this frame's flags are flags[p], last frame's
        // flags[1 - p].
        let drop_outside = compute("cs_drop_outside");
        let drop_groups = parity_groups(&ctx, &drop_outside, |p| vec![(0, &camera), (1, &boxes), (3, &flags[1 - p])]);
        let compact_early = compute("cs_compact");
        let early_groups = parity_groups(&ctx, &compact_early, |p| vec![(6, &flags[1 - p]), (8, &compacted[0])]);
        let compact_late = compute("cs_compact_unless");
        let late_groups =
            parity_groups(&ctx, &compact_late, |p| vec![(6, &flags[p]), (7, &flags[1 - p]), (8, &compacted[1])]);
        let late_test = |method: &Method| match method {
            Method::Ioc(params) => {
                let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
                let tests = BoxTests::new(&ctx, &attachments, &module, hierarchy.node_count() as u32);
                // Depths past the tree's are clamped to it, as `ioc` does
                // (IocWalk::warnings say so; the embedding runs the defaults).
                let walk = IocWalk::new(params, &hierarchy);
                let inputs = WalkInputs { cull_camera: &camera, instance_flags: &flags, stats: &stats };
                let levels = NodeLevels::new(&ctx, &module, &tests, &hierarchy, &walk, inputs);
                LateTest::Nodes(tests, levels, Box::new(hierarchy))
            }
            Method::Roc(_) => {
                let tests = BoxTests::new(&ctx, &attachments, &module, n);
                let every = [0, 1].map(|p| {
                    let inputs = TestInputs {
                        cull_camera: &camera,
                        boxes: &boxes,
                        ids: (&all, n),
                        flags: &flags[p],
                        stats: &stats,
                    };
                    tests.test(&ctx, inputs)
                });
                LateTest::Every(tests, every)
            }
            Method::Hiz(params) => {
                let samples = attachments.samples > 1;
                LateTest::Pyramid(PyramidTest {
                    base: compute(if samples { "cs_pyramid_base_samples" } else { "cs_pyramid_base" }),
                    reduce: compute("cs_pyramid_level"),
                    test: compute("cs_test_boxes_pyramid"),
                    reach: param_buffer(device, params.texels),
                    base_param: device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("pyramid base parameters"),
                        size: 16,
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                    depth_binding: if samples { 18 } else { 17 },
                    state: None,
                })
            }
            Method::Vfc => LateTest::Frustum(storage_init(
                &ctx,
                "all visible",
                bytemuck::cast_slice(&vec![1u32; n as usize]),
                wgpu::BufferUsages::COPY_SRC,
            )),
            other => unreachable!("check_method admits no late test for {other}"),
        };
        let late: Vec<LateTest> = methods.iter().map(late_test).collect();
        let auto = match method {
            Method::Auto(params) => {
                let cold: Vec<u64> = methods.iter().map(cold_frames).collect();
                let frustum_only = methods.iter().position(|m| matches!(m, Method::Vfc));
                Some(GpuAuto::new(&ctx, *params, &cold, frustum_only))
            }
            _ => None,
        };
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(EmbedError::Adapter(format!("the device cannot run {method}'s culling passes: {error}")));
        }
        Ok(Self {
            attachments,
            scene,
            stats,
            drop_outside: (drop_outside, drop_groups),
            compact_early: (compact_early, early_groups),
            compact_late: (compact_late, late_groups),
            camera,
            boxes,
            all,
            flags,
            parity: 0,
            compacted,
            lists,
            draws,
            pipeline: None,
            late,
            running: 0,
            auto,
            counts_staging: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("visible counts read-back"),
                size: 8,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
            ctx,
            frame_camera: None,
            tally: Tally::default(),
        })
    }

    /// Moves, hides and shows instances before the next frame
    /// ([`occlude_core::motion`]; for boxes, [`InstanceChange::to_box`]):
    /// their boxes are rewritten on the device, one queue write each. For
    /// `ioc` the BVH is refitted and its changed node boxes rewritten; its
    /// shape is kept (never rebuilt here, as its levels are made for it),
    /// so a tree loosened by motion tests more boxes, never misses a pixel.
    /// A change naming an unknown instance or a non-finite transform is an
    /// error, and nothing changes.
    pub fn update(&mut self, changes: &[InstanceChange]) -> Result<Upkeep, EmbedError> {
        let changed = self.scene.apply(changes)?;
        let boxes: Vec<(u32, Aabb)> =
            changed.iter().map(|&i| (i, self.scene.instances[i as usize].culling_bounds())).collect();
        write_boxes(&self.ctx.queue, &self.boxes, &boxes);
        let nodes = self.late.iter_mut().find_map(|late| match late {
            LateTest::Nodes(_, levels, hierarchy) => Some((levels, hierarchy)),
            _ => None,
        });
        let Some((levels, hierarchy)) = nodes else {
            return Ok(Upkeep { instances: changed.len(), ..Upkeep::default() });
        };
        let before = hierarchy.version();
        let keep_shape = UpdatePolicy { max_cost_ratio: f32::INFINITY };
        let upkeep = hierarchy.update(&self.scene, &changed, keep_shape);
        match hierarchy.since(Some(before)) {
            Since::Unchanged => {}
            Since::Refit(Some(changes)) => levels.update_boxes(&self.ctx.queue, hierarchy, &changes.nodes),
            // Not after one refit of a tree that is never rebuilt; were it
            // to happen, every box is rewritten.
            Since::Refit(None) | Since::New => {
                let all: Vec<NodeId> = (0..hierarchy.node_count() as NodeId).collect();
                levels.update_boxes(&self.ctx.queue, hierarchy, &all);
            }
        }
        Ok(upkeep)
    }

    /// The culler drawing its lists with the renderer's `pipeline`, whose
    /// vertex shader reads the list at `@group(group) @binding(binding)`
    /// (`var<storage, read> visible: VisibleList;`, see [`VisibleList`]):
    /// each list's bind group is made from the pipeline's own layout of
    /// that group, holding the list alone, so group and pipeline always
    /// fit; [`GpuCuller::render_lists`] sets the pipeline, and
    /// [`VisibleList::draw`] the list's group, before each indirect draw.
    /// The pipeline's other groups stay the renderer's. This saves the
    /// renderer a bind group per list of its own making (wgpu binds buffers
    /// only through bind groups). A group the pipeline does not have, or
    /// one whose entries are not one storage buffer at `binding`, are an
    /// [`EmbedError::Binding`].
    pub fn with_list_pipeline(
        mut self,
        pipeline: &wgpu::RenderPipeline,
        group: u32,
        binding: u32,
    ) -> Result<Self, EmbedError> {
        let device = &self.ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let layout = pipeline.get_bind_group_layout(group);
        let made =
            self.lists.each_ref().map(|list| bind_group(&self.ctx, "visible list", &layout, &[(binding, list.ids())]));
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(EmbedError::Binding(format!(
                "the pipeline cannot read a visible list at group {group}, binding {binding}: {error}"
            )));
        }
        for (list, made) in self.lists.iter_mut().zip(made) {
            list.group = Some((group, made));
        }
        self.pipeline = Some(pipeline.clone());
        Ok(self)
    }

    /// The two lists the frame's draws read: index 0 the early pass's,
    /// 1 the late pass's. Their buffers live as long as the culler.
    pub fn lists(&self) -> &[VisibleList; 2] {
        &self.lists
    }

    /// Renders a frame seen by `camera` (made with
    /// [`Camera::from_matrices`] from the renderer's own view and
    /// projection, `reverse_z` as its depth test says) into `target`, in
    /// one submission of occlude's own: [`GpuCuller::encode_early`], then
    /// `draw(pass, list)` draws the early list in a pass that clears the
    /// views, [`GpuCuller::encode_late`], then `draw` draws the late list
    /// in a pass that loads them. Nothing comes back to the CPU. Errors as
    /// the two phases say; nothing is drawn then.
    pub fn render<F>(&mut self, camera: &Camera, target: FrameTarget<'_>, mut draw: F) -> Result<(), EmbedError>
    where
        F: FnMut(&mut wgpu::RenderPass<'_>, &VisibleList),
    {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.encode_early(&mut encoder, camera, &target)?;
        draw(&mut begin_pass(&mut encoder, &target, &self.attachments, PassStart::Clear, None), &self.lists[0]);
        self.encode_late(&mut encoder, &target)?;
        draw(&mut begin_pass(&mut encoder, &target, &self.attachments, PassStart::Load, None), &self.lists[1]);
        self.ctx.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The frame's first phase, recorded into the renderer's `encoder`:
    /// the early list ([`GpuCuller::lists`]`[0]`) is written with last
    /// frame's visible instances still in view of `camera` (made with
    /// [`Camera::from_matrices`] from the renderer's view and projection,
    /// `reverse_z` as its depth test says). Record the early list's draws
    /// into `target`'s views after it (and any pass of your own that
    /// should use the list, a shadow pass say), then
    /// [`GpuCuller::encode_late`]. Views that are not what the attachments
    /// say, for `hiz` a depth texture without `TEXTURE_BINDING` usage, or a
    /// camera whose depth order is not the depth test's are an error, and
    /// nothing is recorded.
    pub fn encode_early(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        target: &FrameTarget<'_>,
    ) -> Result<(), EmbedError> {
        target.check(&self.attachments)?;
        let depth = target.depth.texture();
        let pyramid = self.late.iter().any(|late| matches!(late, LateTest::Pyramid(_)));
        if pyramid && !depth.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
            return Err(EmbedError::Attachments(
                "the depth texture needs TEXTURE_BINDING usage: hiz builds its depth pyramid from it".into(),
            ));
        }
        let reverse_z = camera.matrices.is_some_and(|m| m.reverse_z);
        if reverse_z != self.attachments.reverse_z() {
            return Err(EmbedError::Device(format!(
                "the camera's reverse_z is {reverse_z} but the depth test {:?} is {}",
                self.attachments.compare,
                if self.attachments.reverse_z() { "reverse Z" } else { "forward Z" }
            )));
        }
        // With MSAA a sample off a pixel's centre may show an instance whose
        // footprint holds no centre: footprints grow by half a pixel more.
        let samples_margin = if self.attachments.samples > 1 { 0.5 } else { 0.0 };
        write_cull_camera(&self.ctx.queue, &self.camera, camera, PIXEL_MARGIN as f32 + samples_margin);
        if let Some(auto) = &mut self.auto {
            self.running = auto.begin(&self.ctx).map_err(EmbedError::Device)?;
        }
        let now = self.parity;
        for (compacted, list) in self.compacted.iter().zip(&self.lists) {
            encoder.clear_buffer(compacted, 0, Some(4));
            self.draws.reset(encoder, list);
        }
        encoder.clear_buffer(&self.flags[now], 0, None);
        self.tally.reset();
        let n = self.instance_count();
        let writes = self.auto.as_ref().and_then(GpuAuto::first_pass_writes);
        let mut pass = self.tally.timed_compute_pass(encoder, writes);
        pass.dispatch(&self.drop_outside.0, &self.drop_outside.1[now], n);
        pass.dispatch(&self.compact_early.0, &self.compact_early.1[now], n);
        self.draws.dispatch(&mut pass, &self.lists[0], n);
        drop(pass);
        if let Some(auto) = &mut self.auto {
            auto.resolve(encoder);
        }
        self.frame_camera = Some(*camera);
        Ok(())
    }

    /// The frame's second phase, recorded into the renderer's `encoder`
    /// after the early list's draws: every instance's box is tested against
    /// the depth those draws left in `target` (`hiz`: a depth pyramid built
    /// from the depth texture; `roc`: the boxes rasterized in a pass of
    /// their own; `ioc`: the BVH's node boxes so, level by level, then the
    /// instances outside the frustum dropped), and the late list
    /// ([`GpuCuller::lists`]`[1]`) is written with those found visible and
    /// not drawn early. Record its draws after it, in passes that load the
    /// views. Without [`GpuCuller::encode_early`] first in this frame it is
    /// an error ([`EmbedError::Sequence`]), and nothing is recorded.
    pub fn encode_late(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &FrameTarget<'_>,
    ) -> Result<(), EmbedError> {
        let camera = self.frame_camera.take().ok_or(EmbedError::Sequence("encode_late without encode_early first"))?;
        target.check(&self.attachments)?;
        let (now, before) = (self.parity, 1 - self.parity);
        let n = self.instance_count();
        match &self.late[self.running] {
            LateTest::Pyramid(_) => self.encode_pyramid_test(encoder, target, now),
            LateTest::Frustum(ones) => encoder.copy_buffer_to_buffer(ones, 0, &self.flags[now], 0, 4 * u64::from(n)),
            LateTest::Every(tests, every) => {
                tests.set_camera(&self.ctx.queue, &camera, &self.attachments);
                tests.encode(encoder, &self.tally, target, &self.attachments, &every[now]);
            }
            LateTest::Nodes(tests, levels, _) => {
                tests.set_camera(&self.ctx.queue, &camera, &self.attachments);
                levels.encode(encoder, &self.tally, tests, target, &self.attachments, now);
            }
        }
        let mut pass = self.tally.compute_pass(encoder);
        if matches!(self.late[self.running], LateTest::Nodes(..) | LateTest::Frustum(_)) {
            // `ioc.frustum`, and `vfc`: the instances marked visible that
            // lie outside the frustum (the drop's groups of parity `before`
            // clear this frame's flags).
            pass.dispatch(&self.drop_outside.0, &self.drop_outside.1[before], n);
        }
        pass.dispatch(&self.compact_late.0, &self.compact_late.1[now], n);
        self.draws.dispatch(&mut pass, &self.lists[1], n);
        drop(pass);
        self.parity = before;
        Ok(())
    }

    /// Renders a frame as [`GpuCuller::render`] does, drawing each list
    /// itself: at the start of each of the two passes it sets the
    /// pipeline given to [`GpuCuller::with_list_pipeline`] (if any),
    /// `setup(pass)` sets the renderer's other bind groups and its buffers
    /// (and the pipeline, if none was given), then [`VisibleList::draw`]
    /// records the list's indirect draw. For a renderer whose lists draw
    /// alike; one that draws them differently uses [`GpuCuller::render`].
    pub fn render_lists<F>(&mut self, camera: &Camera, target: FrameTarget<'_>, mut setup: F) -> Result<(), EmbedError>
    where
        F: FnMut(&mut wgpu::RenderPass<'_>),
    {
        let pipeline = self.pipeline.clone();
        self.render(camera, target, |pass, list| {
            if let Some(pipeline) = &pipeline {
                pass.set_pipeline(pipeline);
            }
            setup(pass);
            list.draw(pass);
        })
    }

    /// How many instances the last frame's early and late lists held,
    /// read back (blocking until the GPU finished the frame). An
    /// instrument, for tests and printouts: the frame itself never reads
    /// anything back.
    pub fn read_counts(&self) -> Result<[u32; 2], EmbedError> {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for (k, list) in self.compacted.iter().enumerate() {
            encoder.copy_buffer_to_buffer(list, 0, &self.counts_staging, 4 * k as u64, 4);
        }
        self.ctx.queue.submit([encoder.finish()]);
        Mapping::start(&self.counts_staging, 8).wait(&self.ctx).map_err(EmbedError::Device)?;
        let bytes = take_bytes(&self.counts_staging, 8).map_err(EmbedError::Device)?;
        let word = |k: usize| u32::from_le_bytes([bytes[4 * k], bytes[4 * k + 1], bytes[4 * k + 2], bytes[4 * k + 3]]);
        Ok([word(0), word(1)])
    }

    /// The compute passes, render passes and dispatches the last frame
    /// recorded (counted from [`GpuCuller::encode_early`] on). An
    /// instrument, for tests and printouts. They do not grow with the
    /// number of meshes or draw groups; `hiz`'s grow with the pyramid's
    /// levels, `ioc`'s with the levels of its BVH.
    pub fn pass_counts(&self) -> PassCounts {
        self.tally.counts()
    }

    /// The late test running this frame (`hiz`, `roc`, `ioc`, or for
    /// `auto` also `vfc`: the frustum alone), and whether `auto` is probing
    /// it rather than running its current choice. An instrument, for tests
    /// and printouts.
    pub fn late_test(&self) -> (&'static str, bool) {
        (self.late[self.running].name(), self.auto.as_ref().is_some_and(GpuAuto::probing))
    }

    /// Instances culled: one per box given.
    fn instance_count(&self) -> u32 {
        self.scene.instances.len() as u32
    }

    /// Records `hiz`'s test into `encoder`: the pyramid built from the
    /// viewport of `target`'s depth texture (made, with its bind groups,
    /// for the viewport's size unless it is of that size already), every
    /// box tested against it, setting flag buffer `now`.
    fn encode_pyramid_test(&mut self, encoder: &mut wgpu::CommandEncoder, target: &FrameTarget<'_>, now: usize) {
        let n = self.instance_count();
        let reverse = u32::from(self.attachments.reverse_z());
        let Some(LateTest::Pyramid(p)) = self.late.get_mut(self.running) else { return };
        let (ctx, device) = (&self.ctx, &self.ctx.device);
        let depth = target.depth.texture();
        let size = target.size();
        let corner = target.area();
        ctx.queue.write_buffer(&p.base_param, 0, bytemuck::cast_slice(&[reverse, corner.x, corner.y, 0]));
        if p.state.as_ref().is_none_or(|state| state.size != size) {
            let buffers = PyramidBuffers::new(ctx, size.0, size.1, size.0);
            let layout = p.reduce.get_bind_group_layout(0);
            let reductions = (1..buffers.counts.len() as u32)
                .map(|level| {
                    let param = param_buffer(device, level);
                    let entries = [(14, &buffers.texels), (15, &buffers.levels), (16, &param)];
                    bind_group(ctx, "hiz reduction", &layout, &entries)
                })
                .collect();
            let layout = p.test.get_bind_group_layout(0);
            let tests = [0, 1].map(|f| {
                let entries = [
                    (0, &self.camera),
                    (1, &self.boxes),
                    (2, &self.all),
                    (3, &self.flags[f]),
                    (13, &self.stats),
                    (14, &buffers.texels),
                    (15, &buffers.levels),
                    (16, &p.reach),
                ];
                bind_group(ctx, "hiz test", &layout, &entries)
            });
            p.state = Some(PyramidState { size, buffers, reductions, tests });
        }
        let pyramid = p.state.as_ref().expect("made above");
        let depth_view = depth
            .create_view(&wgpu::TextureViewDescriptor { aspect: wgpu::TextureAspect::DepthOnly, ..Default::default() });
        let base = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hiz pyramid base"),
            layout: &p.base.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry { binding: 14, resource: pyramid.buffers.texels.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 15, resource: pyramid.buffers.levels.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 16, resource: p.base_param.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: p.depth_binding,
                    resource: wgpu::BindingResource::TextureView(&depth_view),
                },
            ],
        });
        let mut pass = self.tally.compute_pass(encoder);
        pass.dispatch(&p.base, &base, pyramid.buffers.counts[0]);
        for (group, &texels) in pyramid.reductions.iter().zip(&pyramid.buffers.counts[1..]) {
            pass.dispatch(&p.reduce, group, texels);
        }
        pass.dispatch(&p.test, &pyramid.tests[now], n);
    }
}

/// `pipeline`'s bind groups for flag parity 0 and 1, of the buffers
/// `entries(parity)` names.
fn parity_groups<'a>(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    entries: impl Fn(usize) -> Vec<(u32, &'a wgpu::Buffer)>,
) -> [wgpu::BindGroup; 2] {
    [0, 1].map(|p| bind_group(ctx, "hiz", &pipeline.get_bind_group_layout(0), &entries(p)))
}

/// Whether `device` can run the culling passes: compute shaders with
/// workgroups of 64 and six storage buffers in a stage; for box tests
/// (`raster`) also forced early depth tests in fragment shaders.
fn check_device(device: &wgpu::Device, raster: bool) -> Result<(), EmbedError> {
    let limits = device.limits();
    let mut lacks = Vec::new();
    if limits.max_compute_invocations_per_workgroup < WORKGROUP_THREADS
        || limits.max_compute_workgroup_size_x < WORKGROUP_THREADS
    {
        lacks.push(format!("compute workgroups of {WORKGROUP_THREADS} threads"));
    }
    if limits.max_storage_buffers_per_shader_stage < STORAGE_BUFFERS_NEEDED {
        lacks.push(format!(
            "{STORAGE_BUFFERS_NEEDED} storage buffers per shader stage (it has {})",
            limits.max_storage_buffers_per_shader_stage
        ));
    }
    if raster && !device.features().contains(RASTER_FEATURES) {
        lacks.push(
            "the feature SHADER_EARLY_DEPTH_TEST (forced early depth tests: a box's fragments set its flag only \
             where they passed the depth test; request it when creating the device)"
                .to_string(),
        );
    }
    if lacks.is_empty() {
        Ok(())
    } else {
        let which = if raster { "GPU-driven culling with box tests (roc, ioc)" } else { "GPU-driven culling" };
        Err(EmbedError::Adapter(format!("the device lacks {}, which {which} needs", lacks.join(" and "))))
    }
}
