//! [`AnyCuller`]: either shape of the embedding behind one type, chosen by
//! the [`Method`], so that a renderer switches between query-driven and
//! GPU-driven culling without an enum of its own.

use super::{Attachments, Culler, Draws, EmbedError, FrameTarget, GpuCuller, VisibleList};
use occlude_core::methods::Method;
use occlude_core::{Aabb, Camera, FrameStats, InstanceChange, Scene, Upkeep};

/// A [`Culler`] for a query-driven method, a [`GpuCuller`] for a
/// GPU-driven one ([`Method::is_gpu_driven`]) and for `auto` where the
/// device runs GPU-driven culling. The renderer gives both ways
/// of drawing each frame: a list of instances decided on the CPU, and a
/// [`VisibleList`] drawn indirectly; the method in use calls one of them.
#[allow(clippy::large_enum_variant)] // one per renderer: the sizes do not matter
pub enum AnyCuller {
    /// A query-driven method.
    Queries(Culler),
    /// A GPU-driven method.
    Gpu(GpuCuller),
}

impl AnyCuller {
    /// The culler `method` runs in, over `bounds` (see [`Culler::new`] and
    /// [`GpuCuller::new`]; `draws` is how a [`GpuCuller`] draws each
    /// instance and is unused by a [`Culler`]). Errors as theirs.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        attachments: Attachments,
        bounds: &[Aabb],
        method: Method,
        draws: impl Into<Draws>,
    ) -> Result<Self, EmbedError> {
        Self::for_scene(device, queue, attachments, Scene::from_bounds("embedded", bounds)?, method, draws)
    }

    /// [`AnyCuller::new`] over `scene`'s instances ([`Culler::for_scene`],
    /// [`GpuCuller::for_scene`]).
    pub fn for_scene(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        attachments: Attachments,
        scene: Scene,
        method: Method,
        draws: impl Into<Draws>,
    ) -> Result<Self, EmbedError> {
        if method.is_gpu_driven() {
            return Ok(AnyCuller::Gpu(GpuCuller::for_scene(device, queue, attachments, scene, &method, draws)?));
        }
        if matches!(method, Method::Auto(p) if p.gpu) {
            // `auto` chooses among GPU-driven tests where the device runs
            // them, else among query-driven methods.
            match GpuCuller::for_scene(device, queue, attachments, scene.clone(), &method, draws) {
                Ok(culler) => return Ok(AnyCuller::Gpu(culler)),
                Err(EmbedError::Adapter(_)) => {}
                Err(e) => return Err(e),
            }
        }
        Ok(AnyCuller::Queries(Culler::for_scene(device, queue, attachments, scene, method)?))
    }

    /// For a [`GpuCuller`], [`GpuCuller::with_list_pipeline`]; a
    /// [`Culler`] is returned as it is.
    pub fn with_list_pipeline(
        self,
        pipeline: &wgpu::RenderPipeline,
        group: u32,
        binding: u32,
    ) -> Result<Self, EmbedError> {
        Ok(match self {
            AnyCuller::Gpu(culler) => AnyCuller::Gpu(culler.with_list_pipeline(pipeline, group, binding)?),
            queries => queries,
        })
    }

    /// Moves, hides and shows instances before the next frame
    /// ([`Culler::update`], [`GpuCuller::update`]).
    pub fn update(&mut self, changes: &[InstanceChange]) -> Result<Upkeep, EmbedError> {
        match self {
            AnyCuller::Queries(culler) => culler.update(changes),
            AnyCuller::Gpu(culler) => culler.update(changes),
        }
    }

    /// Renders a frame seen by `camera` into `target`: a [`Culler`] calls
    /// `draw_instances(pass, instances)` and returns the frame's statistics
    /// ([`Culler::render`]), a [`GpuCuller`] calls `draw_list(pass, list)`
    /// and returns none ([`GpuCuller::render`]: nothing is read back).
    pub fn render<I, L>(
        &mut self,
        camera: &Camera,
        target: FrameTarget<'_>,
        draw_instances: I,
        draw_list: L,
    ) -> Result<Option<FrameStats>, EmbedError>
    where
        I: FnMut(&mut wgpu::RenderPass<'_>, &[u32]),
        L: FnMut(&mut wgpu::RenderPass<'_>, &VisibleList),
    {
        match self {
            AnyCuller::Queries(culler) => culler.render(camera, target, draw_instances).map(Some),
            AnyCuller::Gpu(culler) => culler.render(camera, target, draw_list).map(|()| None),
        }
    }
}
