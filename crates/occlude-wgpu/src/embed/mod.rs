//! Occlusion culling inside your own wgpu renderer: your device and queue,
//! your depth buffer (`Depth32Float`, `Depth24Plus`, reverse Z with
//! `GreaterEqual`), your pipelines and draws. Occlude needs only each
//! instance's world-space box. Two shapes:
//!
//! - [`Culler`], the query-driven methods (`chc`, `chcpp`, `om`, `sw`;
//!   `vfc` as the baseline; `auto`, the one to start with, runs `chcpp` or
//!   `vfc`, whichever its frames' times measure faster, so culling never
//!   costs you much): occlude calls your draw code with lists of
//!   instances decided on the CPU from occlusion queries (below).
//! - [`GpuCuller`], the GPU-driven methods `hiz`, `roc` and `ioc`: occlude writes
//!   lists of visible instance ids into buffers on the GPU and you draw
//!   with one multi-draw per draw group, whatever the number of meshes
//!   (section "GPU-driven culling" below).
//!
//! [`AnyCuller`] is either, as the [`Method`](occlude_core::methods::Method)
//! says: give it both ways of drawing and switch methods freely.
//!
//! # Query-driven culling
//!
//! Each frame the method walks a BVH over the boxes front to back; where it
//! would draw, occlude calls your draw callback with the instances to draw,
//! inside a render pass on your attachments; where it needs to know whether
//! a node is hidden, it draws the node's box into the same pass with a
//! pipeline matching your depth state (depth test on, no depth or colour
//! writes) inside a hardware occlusion query. Query results are resolved
//! and mapped with `map_async`: "is it available?" polls without blocking,
//! "give me the result" waits (CHC paper, section 3; CHC++ paper, sections
//! 3-4 for how `chcpp` hides that wait).
//!
//! ## Costs
//!
//! - **A submission per wait.** A query's result can only come back after
//!   its pass is submitted, so the frame is split there: each wait ends the
//!   current render pass and submits it, and the next pass loads your
//!   attachments (the frame's first pass clears them). `sw` waits on every
//!   query, `chc` and `chcpp` on far fewer; [`FrameStats::wait_ms`] is the
//!   time spent blocked, the rest of a wait is GPU latency.
//! - **Latency.** A read-back takes at least one round trip through the
//!   queue. The frame's end waits for read-backs still in flight (not for
//!   your draws).
//! - **Your passes are ours.** Occlude begins the frame's render passes on
//!   your views, and submits them itself (a query's result comes back only
//!   after its pass is submitted), so it cannot record into your encoder;
//!   draws you need outside them (sky, UI, post-processing) go in passes
//!   of your own before or after.
//!
//! ## Requirements
//!
//! - Every draw of instance `i` stays inside `bounds[i]`; an instance that
//!   moves gets its new box before the frame ([`Culler::update`] with
//!   [`InstanceChange::to_box`](occlude_core::InstanceChange::to_box), or
//!   [`GpuCuller::update`]). A mesh's local box and
//!   its instance's transform give the world box with
//!   [`Aabb::transformed`](occlude_core::Aabb::transformed).
//! - The camera is [`occlude_core::Camera::from_matrices`] of the view and
//!   projection you draw with, `reverse_z` matching the depth test.
//! - Your draw callback sets its own pipeline, bind groups and buffers on
//!   every call: occlude's query boxes are drawn between calls in the same
//!   pass.
//!
//! ## Known limits
//!
//! - One colour attachment at most. With MSAA ([`Attachments::samples`])
//!   occlude's passes resolve into [`FrameTarget::resolve`] each time
//!   they end (a query's wait ends one), so a frame may resolve several
//!   times. A viewport ([`FrameTarget::viewport`]) is one rectangle of
//!   whole pixels; no scissor.
//! - Each instance counts 12 triangles in [`FrameStats`] and in `chcpp`'s
//!   cost estimates, unless you give the real counts
//!   ([`Culler::for_scene`] with
//!   [`Scene::with_triangle_counts`](occlude_core::Scene::with_triangle_counts)).
//! - Errors of your device (loss, validation) go to your handlers, not to
//!   [`Backend::failure`](occlude_core::Backend::failure), which reports
//!   only what occlude found itself (a failed read-back, a camera of the
//!   wrong depth order). A failure stays: every later frame reports it,
//!   and its queries count as visible, so frames stay complete.
//!
//! ## Example
//!
//! ```no_run
//! use occlude_wgpu::embed::{Attachments, Culler, FrameTarget};
//! use glam::{Mat4, Vec3};
//! use occlude_core::{Aabb, Camera};
//!
//! # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, color: &wgpu::TextureView,
//! #          depth: &wgpu::TextureView, pipeline: &wgpu::RenderPipeline) -> Result<(), Box<dyn std::error::Error>> {
//! // Once: your attachments and one box per instance you draw.
//! let attachments = Attachments {
//!     color: Some(wgpu::TextureFormat::Rgba8Unorm),
//!     depth: wgpu::TextureFormat::Depth32Float,
//!     compare: wgpu::CompareFunction::Less,
//!     samples: 1,
//! };
//! let bounds: Vec<Aabb> = (0..1000).map(|i| {
//!     let at = Vec3::new((i % 40) as f32 * 2.0, 0.0, -((i / 40) as f32) * 2.0);
//!     Aabb::new(at, at + Vec3::ONE)
//! }).collect();
//! let mut culler = Culler::new(device, queue, attachments, &bounds, "chcpp".parse()?)?;
//!
//! // Each frame: your camera, your views, your draws.
//! let view = Mat4::look_at_rh(Vec3::new(40.0, 2.0, 10.0), Vec3::new(40.0, 0.0, 0.0), Vec3::Y);
//! let projection = Mat4::perspective_rh(1.0, 1.0, 0.1, 200.0);
//! let camera = Camera::from_matrices(view, projection, false)?;
//! let target = FrameTarget::new(Some(color), wgpu::Color::BLACK, depth);
//! let stats = culler.render(&camera, target, |pass, instances| {
//!     pass.set_pipeline(pipeline);
//!     for &i in instances {
//!         pass.draw(0..36, i..i + 1); // instance i, with your own buffers
//!     }
//! })?;
//! println!("drew {} of {} instances", stats.visible_objects, bounds.len());
//! # Ok(())
//! # }
//! ```
//!
//! # GPU-driven culling
//!
//! [`GpuCuller`] runs two-phase Hi-Z culling (`hiz`,
//! [`occlude_core::methods::hiz`]; zeux's niagara, nvpro's
//! `gl_occlusion_culling`, Bevy's occlusion culling) or raster occlusion
//! culling (`roc`, [`occlude_core::methods::roc`]; IOC poster, section 1;
//! nvpro's "raster" technique) or its hierarchical form (`ioc`,
//! [`occlude_core::methods::ioc`]; IOC poster, section 2) with every
//! decision on the GPU. Each frame, in one submission:
//!
//! 1. a compute pass drops last frame's visible instances whose boxes left
//!    the view frustum and compacts the rest into the early
//!    [`VisibleList`];
//! 2. your callback draws the early list in a pass that clears your views;
//! 3. a compute pass builds a depth pyramid from your depth texture
//!    ([`occlude_core::depth_pyramid`]: level 0 your depth, each level the
//!    2x2 maximum of the one before) and tests every instance's box
//!    against it (at most 8 x 8 texels of the finest level that fits, as
//!    `hiz` does by default), setting this frame's visibility; `roc`
//!    instead rasterizes every instance's box against your depth texture
//!    (a pass of occlude's holding your depth view alone, read-only,
//!    tested with your compare function, no depth or colour writes), each
//!    fragment that passes the depth test (forced early, before the
//!    fragment shader writes) setting its instance's flag; `ioc` tests so
//!    the node boxes of a BVH over your boxes (built once), level by level
//!    from depth 4 to two above the deepest (`ioc`'s defaults): a hidden
//!    node ends the descent, a visible leaf marks its instances, a visible
//!    node at the bottom level all instances below it, and those outside
//!    the frustum are dropped; a compute pass compacts the instances
//!    visible now that the early pass did not draw into the late list;
//! 4. your callback draws the late list in a pass that loads your views.
//!
//! A list is one buffer: its length, its capacity and the ids, which your
//! vertex shader reads as `ids[instance_index]` (the WGSL is at
//! [`VisibleList`]). You give each instance a mesh (an [`IndirectDraw`]:
//! index range and base vertex) and a draw group (your pipeline or
//! material; [`Draws`]). After each compaction a compute pass sorts the
//! list by (group, mesh) and writes one indirect command per pair, its
//! instance count the pair's visible instances and its first instance the
//! pair's place in the list; [`VisibleList::draw_group`] draws a group with
//! one multi-draw (counted on the GPU with `MULTI_DRAW_INDIRECT_COUNT`;
//! without it, over all the group's commands, the empty ones drawing
//! nothing). One mesh needs no feature; several need
//! `INDIRECT_FIRST_INSTANCE` ([`DRAW_FEATURES`]). Your shader declares the list in a bind group of its own, which
//! [`GpuCuller::with_list_pipeline`] makes from your pipeline's layout,
//! and [`GpuCuller::render_lists`] sets your pipeline and, after your
//! callback has set your other bind groups and buffers, the list's group
//! and its indirect draw (or bind the list in a group of yours and draw it
//! yourself in [`GpuCuller::render`]'s callback).
//!
//! **In your own frame.** [`GpuCuller::render`] records and submits the
//! frame in an encoder of occlude's. To place the frame in yours (a render
//! graph), record its phases: [`GpuCuller::encode_early`] (step 1), your
//! passes drawing the early list (step 2), [`GpuCuller::encode_late`] (step 3),
//! your passes drawing the late list. Between them the lists are yours to
//! reuse: draw the same visible instances into a shadow or motion-vector
//! pass. A [`Culler`] cannot do this: each wait for a query result must
//! submit the work before it, so it submits its own encoders.
//!
//! The image is the image without culling: an instance with a pixel in the
//! final image is at that pixel no farther than the early pass's depth,
//! so its box (which holds it, padded and pulled towards the eye as query
//! boxes are) passes `roc`'s depth test there (as does the box of every
//! node above it, for `ioc`), and is not hidden by `hiz`'s pyramid, whose
//! texels are at least the farthest depth of the pixels they cover (the
//! proof is [`occlude_core::depth_pyramid`]'s). Your depth texture is read into
//! level 0 with two changes: reverse Z is turned into depth 0 nearest
//! (`1 - d`), and each texel is taken 2^-22 farther, which covers both a
//! 24-bit depth buffer's rounding of the fragments' depth and the rounding
//! of `1 - d`; the box's depth comes from
//! [`Camera::view_projection`](occlude_core::Camera::view_projection),
//! whose reverse-Z flip only negates and adds rows of your projection.
//!
//! ## Costs
//!
//! - **Per frame:** six compute dispatches over the instances, two over
//!   the (group, mesh) pairs, buffer copies of the commands and your
//!   multi-draws (one per list and group); for `hiz` one dispatch per
//!   pyramid level (level 0 over your depth's pixels, each further level
//!   over its texels); for `roc` a render pass of its own drawing every
//!   box in the frustum (12 triangles each, their fragments tested against
//!   your depth: fill rate grows with the boxes' screen area); for `ioc`
//!   per level of the walk a dispatch over the nodes and such a pass
//!   drawing the level's node boxes in the frustum, two dispatches over
//!   the nodes between levels and one after the last. One submission;
//!   nothing is read back, so the CPU never waits for the GPU.
//! - **Memory:** per instance a 32-byte box, two flag words and three list
//!   entries; `hiz`'s pyramid is about 4/3 of a 32-bit depth image, `roc`
//!   keeps a second 32-byte box per instance (the boxes to draw); `ioc`
//!   per node (about two per instance) two boxes, a flag, three list
//!   entries and table entries.
//! - **Latency of visibility:** an instance hidden last frame and visible
//!   now is drawn in the late pass of this frame, after the late test:
//!   never missing, but its draw waits for the test.
//! - **Warm-up:** the first frame has no visible set from a frame before,
//!   so its pyramid (or for `roc` and `ioc` its depth) is empty and it
//!   draws every instance in the frustum; the second frame draws those
//!   again in its early pass. Occlusion
//!   shows from the third frame on, and again two frames after a camera
//!   cut (in the example, 2,717 of 3,603 instances in frames 0 and 1,
//!   then for `hiz` about 70 to 180 a frame, `roc` 50 to 160, `ioc` 210
//!   to 540: docs/benchmarks.md).
//!
//! ## Requirements
//!
//! - As for [`Culler`]: draws of instance `i` stay inside `bounds[i]`, the
//!   camera is [`occlude_core::Camera::from_matrices`] of your matrices
//!   with `reverse_z` matching the depth test.
//! - `hiz`: your depth texture has `TEXTURE_BINDING` usage (the pyramid
//!   reads it in a compute shader); otherwise [`GpuCuller::render`]
//!   refuses the frame. `roc` and `ioc` only render into it.
//! - Your device has compute shaders with workgroups of 64 threads and 6
//!   storage buffers per shader stage (checked by [`GpuCuller::new`]); your
//!   vertex shader reads a storage buffer (the list).
//! - `roc` and `ioc`: your device was created with [`RASTER_FEATURES`]
//!   (`SHADER_EARLY_DEPTH_TEST`: a fragment shader with side effects runs
//!   only for fragments that passed the depth test) and writes storage
//!   buffers from fragment shaders (Vulkan, Metal and DX12 do; some GL
//!   drivers not). [`GpuCuller::new`] checks the feature for them only and
//!   refuses a device without it ([`EmbedError::Adapter`], naming it), and
//!   refuses likewise a device on which occlude's pipelines fail to build.
//! - Your callback binds its own pipeline (with
//!   [`GpuCuller::render_lists`], occlude sets the pipeline given to
//!   [`GpuCuller::with_list_pipeline`]), bind groups and buffers: it is
//!   called once per list, at the start of each of the frame's two passes.
//! - With [`GpuCuller::with_list_pipeline`], your pipeline has a bind
//!   group holding the list alone (one storage buffer), which your
//!   callback leaves to occlude.
//!
//! ## Known limits
//!
//! - `hiz`, `roc` and `ioc` ([`GPU_METHODS`]) with the settings
//!   [`GpuCuller::check_method`] accepts: `hiz` at instance granularity,
//!   `roc.mode=exact`, `ioc` with its frustum test and without
//!   `ioc.auto` (its levels clamped to the BVH's depth).
//! - `roc`'s box test has a render pass of its own between your two
//!   passes (three passes a frame; `hiz` has two), `ioc` one per level of
//!   its walk.
//! - No statistics from the frame: [`GpuCuller::read_counts`] reads the
//!   lists' lengths back (blocking), for tests and printouts.
//! - The attachment rules of [`Culler`]. With MSAA, `hiz`'s pyramid holds
//!   the farthest sample of each pixel and footprints cover every pixel a
//!   box touches (not only those whose centre it holds); `roc`'s and
//!   `ioc`'s box tests and the queries count samples.
//!
//! ## Example
//!
//! ```no_run
//! use occlude_wgpu::embed::{Attachments, FrameTarget, GpuCuller, IndirectDraw};
//! use glam::{Mat4, Vec3};
//! use occlude_core::methods::{hiz::HizParams, Method};
//! use occlude_core::{Aabb, Camera};
//!
//! # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, color: &wgpu::TextureView,
//! #          depth: &wgpu::TextureView, pipeline: &wgpu::RenderPipeline,
//! #          instances: &wgpu::BindGroup) -> Result<(), Box<dyn std::error::Error>> {
//! // Once: your attachments, one box per instance, how an instance is drawn,
//! // and where your vertex shader reads the list: group 1, binding 0.
//! let attachments = Attachments {
//!     color: Some(wgpu::TextureFormat::Rgba8Unorm),
//!     depth: wgpu::TextureFormat::Depth32Float,
//!     compare: wgpu::CompareFunction::Less,
//!     samples: 1,
//! };
//! let bounds: Vec<Aabb> = (0..1000).map(|i| {
//!     let at = Vec3::new((i % 40) as f32 * 2.0, 0.0, -((i / 40) as f32) * 2.0);
//!     Aabb::new(at, at + Vec3::ONE)
//! }).collect();
//! let draw = IndirectDraw::NonIndexed { vertex_count: 36, first_vertex: 0 };
//! let method = Method::Hiz(HizParams { texels: 4, ..Default::default() });
//! let mut culler = GpuCuller::new(device, queue, attachments, &bounds, &method, draw)?
//!     .with_list_pipeline(pipeline, 1, 0)?;
//!
//! // Each frame: your camera, your views, your other bind groups and buffers;
//! // occlude sets your pipeline and the list and draws it indirectly.
//! let view = Mat4::look_at_rh(Vec3::new(40.0, 2.0, 10.0), Vec3::new(40.0, 0.0, 0.0), Vec3::Y);
//! let projection = Mat4::perspective_rh(1.0, 1.0, 0.1, 200.0);
//! let camera = Camera::from_matrices(view, projection, false)?;
//! let target = FrameTarget::new(Some(color), wgpu::Color::BLACK, depth);
//! culler.render_lists(&camera, target, |pass| pass.set_bind_group(0, instances, &[]))?;
//! # Ok(())
//! # }
//! ```
//!
//! [`FrameStats`]: occlude_core::FrameStats
//! [`FrameStats::wait_ms`]: occlude_core::FrameStats::wait_ms

mod any_culler;
mod backend;
mod box_tests;
mod culler;
mod draws;
mod gpu_culler;
mod node_levels;

pub use any_culler::AnyCuller;
pub use backend::{Attachments, EmbeddedFrame, FrameTarget, QueryBackend, Viewport};
pub use culler::{Culler, QUERY_METHODS};
pub use draws::{Draws, IndirectDraw, InstanceDraw, VisibleList, DRAW_FEATURES};
pub use gpu_culler::{GpuCuller, GPU_METHODS, RASTER_FEATURES};

use occlude_core::methods::MethodError;
use occlude_core::SceneError;

/// Why culling cannot run in a renderer as asked.
#[derive(Debug, thiserror::Error)]
pub enum EmbedError {
    /// The method does not run embedded.
    #[error(
        "method '{0}' cannot run in your renderer: the embedding runs the query-driven methods ({names}) with a \
         Culler and the GPU-driven ones ({gpu}) with a GpuCuller",
        names = QUERY_METHODS.join(", "),
        gpu = GPU_METHODS.join(", ")
    )]
    Unsupported(String),
    /// A parameter value the method does not run with here
    /// ([`GpuCuller::check_method`]).
    #[error(
        "{0} does not run in a GpuCuller: it runs hiz at instance granularity, roc.mode=exact, ioc without ioc.auto"
    )]
    UnsupportedSetting(String),
    /// The method's name or parameters are wrong.
    #[error(transparent)]
    Method(#[from] MethodError),
    /// The instance boxes are not a scene ([`occlude_core::Scene::from_bounds`]).
    #[error("bad instance bounds: {0}")]
    Scene(#[from] SceneError),
    /// A frame's changes name an unknown instance or a transform that is
    /// not finite ([`Culler::update`]); nothing changed.
    #[error("bad instance change: {0}")]
    Motion(#[from] occlude_core::MotionError),
    /// The attachments' depth format or test cannot be culled against.
    #[error("unsupported attachments: {0}")]
    Attachments(String),
    /// The renderer's device lacks what GPU-driven culling needs: compute
    /// limits, or for `roc` and `ioc` the feature `SHADER_EARLY_DEPTH_TEST`
    /// ([`RASTER_FEATURES`]), named in the message.
    #[error("{0}")]
    Adapter(String),
    /// The per-instance draws do not fit the instances ([`Draws`]): not one
    /// per box, an unknown mesh, indexed and non-indexed meshes mixed.
    #[error("bad draws: {0}")]
    Draws(String),
    /// A visible list cannot be bound as the renderer's pipeline asks
    /// ([`GpuCuller::with_list_pipeline`]).
    #[error("cannot bind the visible lists: {0}")]
    Binding(String),
    /// The frame's phases were recorded out of order
    /// ([`GpuCuller::encode_late`] before [`GpuCuller::encode_early`]).
    #[error("{0}")]
    Sequence(&'static str),
    /// Occlude's work on the device failed, or the camera's depth order is
    /// not the depth test's ([`occlude_core::Backend::failure`]).
    #[error("culling failed: {0}")]
    Device(String),
}
