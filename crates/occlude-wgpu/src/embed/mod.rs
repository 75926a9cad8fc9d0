//! Occlusion culling inside your own wgpu renderer. You keep your device,
//! pipelines, buffers and passes; occlude needs one world-space box per
//! instance and your depth buffer, and tells you which instances to draw.
//! The image is the one you would draw without culling, bit for bit.
//!
//! # Which culler
//!
//! - [`Culler`] runs the query-driven methods: `auto` (the one to start
//!   with: `chcpp` or `vfc`, whichever its frames measure faster), `chcpp`,
//!   `chc`, `om`, `sw`, and `vfc` (frustum culling only). It walks a BVH
//!   over your boxes on the CPU, tests node boxes with hardware occlusion
//!   queries in your passes, and calls your draw code with the instances
//!   to draw.
//! - [`GpuCuller`] runs the GPU-driven methods: `hiz` (two-phase Hi-Z),
//!   `roc` (every box rasterized against your depth), `ioc` (`roc` down
//!   a BVH), and `auto` (the one to start with: `roc`, `hiz` or frustum
//!   culling, whichever its GPU timestamps, read back a few frames late,
//!   measure faster). It writes two lists of visible instances on the GPU,
//!   with a draw command per mesh and draw group; you draw them with
//!   multi-draws. Only `auto`'s timestamps come back to the CPU.
//! - [`AnyCuller`] is either, as the [`Method`](occlude_core::methods::Method)
//!   says (`auto`: a [`GpuCuller`] where the device runs one): give it both
//!   ways of drawing and switch methods freely.
//!
//! # What you give
//!
//! - [`Attachments`]: your colour and depth formats (any with a depth
//!   aspect), your depth test (forward or reverse Z) and your MSAA samples.
//! - One box per instance. Every draw of instance `i` stays inside
//!   `bounds[i]` ([`Aabb::transformed`](occlude_core::Aabb::transformed)
//!   of its mesh's box gives it).
//! - A [`Method`](occlude_core::methods::Method), typed
//!   (`Method::Hiz(HizParams { texels: 4, ..Default::default() })`) or
//!   parsed (`"chcpp".parse()?`).
//! - For a [`GpuCuller`], each instance's mesh and draw group ([`Draws`]),
//!   or one [`IndirectDraw`] that every instance shares; and a vertex shader
//!   that reads the instance id from the list ([`VisibleList`]).
//! - Each frame, a camera ([`Camera::from_matrices`](occlude_core::Camera::from_matrices)
//!   of your view and projection) and a [`FrameTarget`]: your views, the
//!   MSAA resolve view, the viewport.
//! - When instances move, hide or show: `update` with the frame's
//!   [`InstanceChange`](occlude_core::InstanceChange)s before the frame.
//!   The BVH is refitted and only the changed boxes are uploaded.
//!
//! # What you get
//!
//! - [`Culler::render`] calls `draw(pass, instances)` inside render passes
//!   on your views, and returns the frame's [`FrameStats`].
//! - [`GpuCuller::encode_early`] and [`GpuCuller::encode_late`] record the
//!   two phases into your encoder. Draw [`GpuCuller::lists`]`[0]` after the
//!   first and `[1]` after the second ([`VisibleList::draw_group`]); your own
//!   passes (shadows, motion vectors) may sit between them and reuse the
//!   lists. [`GpuCuller::render`] does all of it in an encoder of its own.
//!
//! # Costs
//!
//! - [`Culler`]: each wait for a query result ends the current pass and
//!   submits it, since a result comes back only after its pass is
//!   submitted. So occlude begins and submits the frame's passes itself
//!   and cannot record into your encoder. `chcpp` waits rarely; `sw` on
//!   every query. [`FrameStats::wait_ms`] is the time spent blocked.
//! - [`GpuCuller`]: one submission, no read-back. Per frame six compute
//!   dispatches over the instances and (with count draws) two over the
//!   (group, mesh) pairs;
//!   for `hiz` one per pyramid level; for `roc` a render pass of the boxes
//!   in the frustum; for `ioc` such a pass per level of its walk. The
//!   dispatches do not grow with the number of meshes. After a camera cut
//!   it draws everything in the frustum for two frames.
//!
//! # Requirements
//!
//! - [`GpuCuller`]: compute shaders with 64-thread workgroups and six
//!   storage buffers per stage. `roc` and `ioc` need [`RASTER_FEATURES`]
//!   (forced early depth tests); several meshes or groups need
//!   `INDIRECT_FIRST_INSTANCE` ([`DRAW_FEATURES`], which also names the
//!   count draws used where present). `hiz` reads your depth texture, so it
//!   needs `TEXTURE_BINDING` usage. A device without what is needed is an
//!   [`EmbedError::Adapter`] naming it.
//! - [`Culler`]: your draw callback sets its own pipeline, bind groups and
//!   buffers on every call: occlude's query boxes are drawn between calls.
//!
//! # Limits
//!
//! - One colour attachment. A viewport is one rectangle of whole pixels;
//!   no scissor. The frame's first pass clears the whole views, not only
//!   the viewport: draw other viewports of the same target after it. With MSAA a [`Culler`]'s frame may resolve several times
//!   (each pass resolves when it ends).
//! - [`GpuCuller`] runs the settings [`GpuCuller::check_method`] accepts,
//!   and gives no statistics ([`GpuCuller::read_counts`] reads the lists'
//!   lengths back, for tests; [`GpuCuller::pass_counts`] counts the passes
//!   and dispatches it recorded).
//! - A [`Culler`] counts 12 triangles per instance in its statistics and
//!   cost estimates unless given real counts ([`Culler::for_scene`]).
//! - Errors of your device go to your handlers; [`Backend::failure`](occlude_core::Backend::failure)
//!   reports only what occlude found itself.
//!
//! Examples are on [`Culler`] and [`GpuCuller`]; `examples/own-renderer`
//! is a whole renderer that uses both.
//!
//! [`FrameStats`]: occlude_core::FrameStats
//! [`FrameStats::wait_ms`]: occlude_core::FrameStats::wait_ms

mod any_culler;
mod backend;
mod box_tests;
mod culler;
mod draws;
mod gpu_auto;
mod gpu_culler;
mod node_levels;
mod passes;

pub use any_culler::AnyCuller;
pub use backend::{Attachments, EmbeddedFrame, FrameTarget, QueryBackend, Viewport};
pub use culler::{Culler, QUERY_METHODS};
pub use draws::{Draws, IndirectDraw, InstanceDraw, VisibleList, DRAW_FEATURES};
pub use gpu_culler::{GpuCuller, GPU_METHODS, RASTER_FEATURES};
pub use passes::PassCounts;

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
        "{0} does not run in a GpuCuller: it runs hiz at instance granularity, roc.mode=exact, ioc without ioc.auto, \
         auto with auto.gpu on"
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
