//! Occlusion culling inside your own wgpu renderer, for the query-driven
//! methods (`chc`, `chcpp`, `om`, `sw`; `vfc` as the baseline): your
//! device and queue, your depth buffer (`Depth32Float`, `Depth24Plus`,
//! reverse Z with `GreaterEqual`), your pipelines and draws. Occlude needs
//! only each instance's world-space box.
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
//! # Costs
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
//!   your views; draws you need outside them (sky, UI, post-processing) go
//!   in passes of your own before or after.
//!
//! # Requirements
//!
//! - Every draw of instance `i` stays inside `bounds[i]`; instances that
//!   move need new bounds (and a new [`Culler`]).
//! - The camera is [`occlude_core::Camera::from_matrices`] of the view and
//!   projection you draw with, `reverse_z` matching the depth test.
//! - Your draw callback sets its own pipeline, bind groups and buffers on
//!   every call: occlude's query boxes are drawn between calls in the same
//!   pass.
//!
//! # Known limits
//!
//! - One colour attachment at most, one sample (no MSAA), no viewport or
//!   scissor other than the whole target.
//! - Each instance counts 12 triangles in [`FrameStats`] and in `chcpp`'s
//!   cost estimates, whatever it draws.
//! - No GPU-resident culling (`roc`, `ioc`, `hiz`): that needs occlude's
//!   own scene on the GPU (see [`Culler`]'s [`QUERY_METHODS`]).
//! - Errors of your device (loss, validation) go to your handlers, not to
//!   [`Backend::failure`](occlude_core::Backend::failure), which reports
//!   only what occlude found itself (a failed read-back, a camera of the
//!   wrong depth order). A failure stays: every later frame reports it,
//!   and its queries count as visible, so frames stay complete.
//!
//! # Example
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
//! };
//! let bounds: Vec<Aabb> = (0..1000).map(|i| {
//!     let at = Vec3::new((i % 40) as f32 * 2.0, 0.0, -((i / 40) as f32) * 2.0);
//!     Aabb::new(at, at + Vec3::ONE)
//! }).collect();
//! let mut culler = Culler::new(device, queue, attachments, &bounds, "chcpp")?;
//!
//! // Each frame: your camera, your views, your draws.
//! let view = Mat4::look_at_rh(Vec3::new(40.0, 2.0, 10.0), Vec3::new(40.0, 0.0, 0.0), Vec3::Y);
//! let projection = Mat4::perspective_rh(1.0, 1.0, 0.1, 200.0);
//! let camera = Camera::from_matrices(view, projection, false)?;
//! let target = FrameTarget { color: Some(color), clear_color: wgpu::Color::BLACK, depth };
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
//! [`FrameStats`]: occlude_core::FrameStats
//! [`FrameStats::wait_ms`]: occlude_core::FrameStats::wait_ms

mod backend;
mod culler;

pub use backend::{Attachments, EmbeddedFrame, FrameTarget, QueryBackend};
pub use culler::{Culler, QUERY_METHODS};

use occlude_core::methods::MethodError;
use occlude_core::SceneError;

/// Why culling cannot run in a renderer as asked.
#[derive(Debug, thiserror::Error)]
pub enum EmbedError {
    /// The method does not run embedded.
    #[error(
        "method '{0}' cannot run in your renderer: the embedding runs the query-driven methods ({names})",
        names = QUERY_METHODS.join(", ")
    )]
    Unsupported(String),
    /// The method's name or parameters are wrong.
    #[error(transparent)]
    Method(#[from] MethodError),
    /// The instance boxes are not a scene ([`occlude_core::Scene::from_bounds`]).
    #[error("bad instance bounds: {0}")]
    Scene(#[from] SceneError),
    /// The attachments' depth format or test cannot be culled against.
    #[error("unsupported attachments: {0}")]
    Attachments(String),
    /// Occlude's work on the device failed, or the camera's depth order is
    /// not the depth test's ([`occlude_core::Backend::failure`]).
    #[error("culling failed: {0}")]
    Device(String),
}
