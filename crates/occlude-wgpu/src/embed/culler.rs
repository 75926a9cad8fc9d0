//! [`Culler`]: a query-driven method, its hierarchy over the renderer's
//! instance boxes and a [`QueryBackend`], behind one call per frame.
//!
//! Each frame the method walks a BVH over the boxes front to back. Where it
//! draws, occlude calls the renderer's draw callback inside a render pass
//! on its views; where it needs to know whether a node is hidden, it draws
//! the node's box into the same pass inside a hardware occlusion query,
//! with a pipeline matching the renderer's depth state and no writes.
//! Results are resolved and mapped with `map_async`: "is it available?"
//! polls, "give me the result" waits (CHC paper, section 3; CHC++ paper,
//! sections 3-4, for how `chcpp` hides the wait).

use super::{Attachments, EmbedError, FrameTarget, QueryBackend};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::Method;
use occlude_core::{
    render_frame, Aabb, Camera, CullingMethod, DrawnSet, FrameStats, Hierarchy, HierarchyKind, InstanceChange, Scene,
    UpdatePolicy, Upkeep,
};

/// The methods that run embedded: those that draw and query through the
/// [`occlude_core::Backend`] interface alone. `vfc` (frustum culling)
/// issues no query and is the baseline the others are checked against.
/// The GPU-driven methods do not run here: `hiz`, `roc` and `ioc` run in
/// a [`GpuCuller`](super::GpuCuller); nor do
/// `opt` (an oracle pass) and `moc` (the meshes' triangles).
pub const QUERY_METHODS: [&str; 6] = ["vfc", "sw", "chc", "chcpp", "om", "auto"];

/// A query-driven culling method running in a renderer's own passes: give
/// it the renderer's device, attachments and per-instance boxes once, then
/// each frame the camera, the frame's views and a callback drawing a list
/// of instances.
///
/// # Example
///
/// ```no_run
/// use occlude_wgpu::embed::{Attachments, Culler, FrameTarget};
/// use glam::{Mat4, Vec3};
/// use occlude_core::{Aabb, Camera};
///
/// # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, color: &wgpu::TextureView,
/// #          depth: &wgpu::TextureView, pipeline: &wgpu::RenderPipeline) -> Result<(), Box<dyn std::error::Error>> {
/// // Once: your attachments and one box per instance you draw.
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
/// let mut culler = Culler::new(device, queue, attachments, &bounds, "chcpp".parse()?)?;
///
/// // Each frame: your camera, your views, your draws.
/// let view = Mat4::look_at_rh(Vec3::new(40.0, 2.0, 10.0), Vec3::new(40.0, 0.0, 0.0), Vec3::Y);
/// let projection = Mat4::perspective_rh(1.0, 1.0, 0.1, 200.0);
/// let camera = Camera::from_matrices(view, projection, false)?;
/// let target = FrameTarget::new(Some(color), wgpu::Color::BLACK, depth);
/// let stats = culler.render(&camera, target, |pass, instances| {
///     pass.set_pipeline(pipeline);
///     for &i in instances {
///         pass.draw(0..36, i..i + 1); // instance i, with your own buffers
///     }
/// })?;
/// println!("drew {} of {} instances", stats.visible_objects, bounds.len());
/// # Ok(())
/// # }
/// ```
pub struct Culler {
    backend: QueryBackend,
    scene: Scene,
    hierarchy: Hierarchy,
    method: Box<dyn CullingMethod>,
    drawn: DrawnSet,
}

impl Culler {
    /// Culls instances whose world-space boxes are `bounds` (instance `i`
    /// is `bounds[i]`; its draws must stay inside that box) with `method`
    /// (one of [`QUERY_METHODS`], with any parameters) on
    /// the renderer's `device` and `queue`, whose passes draw into
    /// `attachments`. Builds a BVH over the boxes once. A method that does
    /// not run embedded, bad boxes or attachments are an error. Each
    /// instance counts 12 triangles; [`Culler::for_scene`] takes their real
    /// counts.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        attachments: Attachments,
        bounds: &[Aabb],
        method: Method,
    ) -> Result<Self, EmbedError> {
        Self::for_scene(device, queue, attachments, Scene::from_bounds("embedded", bounds)?, method)
    }

    /// [`Culler::new`] over `scene`'s instances (their
    /// [`Instance::bounds`](occlude_core::Instance::bounds), triangle counts
    /// and materials; the renderer still draws its own geometry): for a
    /// renderer that gives each instance's real triangle count, made with
    /// [`Scene::from_bounds`] and [`Scene::with_triangle_counts`], so that
    /// frame statistics and the methods' cost decisions (`chcpp`'s tight
    /// bounds) see its geometry rather than 12 triangles a box.
    pub fn for_scene(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        attachments: Attachments,
        scene: Scene,
        method: Method,
    ) -> Result<Self, EmbedError> {
        if !QUERY_METHODS.contains(&method.name()) {
            return Err(EmbedError::Unsupported(method.name().to_string()));
        }
        let method = method.build()?;
        scene.validate()?;
        let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
        let backend = QueryBackend::new(device, queue, attachments, &scene)?;
        Ok(Self { backend, scene, hierarchy, method, drawn: DrawnSet::default() })
    }

    /// Renders a frame seen by `camera` (made with [`Camera::from_matrices`]
    /// from the renderer's own view and projection, `reverse_z` as its
    /// depth test says) into `target`: the method decides what to draw,
    /// `draw(pass, instances)` draws it with the renderer's pipelines (see
    /// [`QueryBackend::frame`]). Returns what the frame drew and queried.
    /// Views that are not what the attachments say are an error, and
    /// nothing is drawn. A camera whose depth order differs from the
    /// attachments', or a read-back that failed, is an error too, but that
    /// frame's image is complete (every query counted as visible).
    pub fn render<F>(&mut self, camera: &Camera, target: FrameTarget<'_>, draw: F) -> Result<FrameStats, EmbedError>
    where
        F: FnMut(&mut wgpu::RenderPass<'_>, &[u32]),
    {
        let mut frame = self.backend.frame(target, draw)?;
        let stats =
            render_frame(self.method.as_mut(), &mut frame, &self.scene, &self.hierarchy, camera, &mut self.drawn);
        match occlude_core::Backend::failure(&frame) {
            Some(reason) => Err(EmbedError::Device(reason)),
            None => Ok(stats),
        }
    }

    /// Moves, hides and shows instances before the next frame
    /// ([`occlude_core::motion`]): the scene's boxes change, the BVH is
    /// refitted (rebuilt when refits have degraded it), and the method keeps
    /// what it learnt about the nodes. For a culler made from boxes
    /// ([`Culler::new`]), [`InstanceChange::to_box`] moves an instance to a
    /// new box. A change naming an unknown instance or a non-finite
    /// transform is an error, and nothing changes.
    pub fn update(&mut self, changes: &[InstanceChange]) -> Result<Upkeep, EmbedError> {
        let changed = self.scene.apply(changes)?;
        let upkeep = self.hierarchy.update(&self.scene, &changed, UpdatePolicy::default());
        self.backend.update_instances(&self.scene, &changed);
        Ok(upkeep)
    }

    /// The scene the method culls ([`Scene::from_bounds`] for
    /// [`Culler::new`]).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
}
