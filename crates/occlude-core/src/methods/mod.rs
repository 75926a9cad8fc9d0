//! Culling methods, each written once against [`Backend`].
//!
//! A method decides, frame by frame, which hierarchy leaves to draw. A frame
//! is [`render_frame`](crate::frame::render_frame):
//! [`CullingMethod::prepare`] before the frame's clock starts, then
//! `Backend::begin_frame`, [`CullingMethod::render`] and
//! `Backend::end_frame`.

pub mod auto;
pub mod chc;
pub mod chcpp;
pub mod debug;
mod front_to_back;
pub mod hiz;
pub mod ioc;
mod method;
pub mod moc;
pub mod nocull;
mod node_walk;
pub mod nohc;
mod occluder_proxies;
pub mod om;
pub mod opt;
pub mod options;
pub mod roc;
pub mod sw;
#[cfg(test)]
mod test_rig;
mod tracked;
pub mod vfc;

pub use debug::{DebugView, NdcRect, NodeClass};
pub use front_to_back::{FrontToBack, SortKey};
pub use method::Method;
pub use options::{MethodOptions, MethodParams, OptionError, ParamVisitor};

use crate::backend::Backend;
use crate::camera::{Camera, Frustum};
use crate::cost_model::CostModel;
use crate::gpu_culling::{Flags, GpuCullingUnsupported};
use crate::hierarchy::{Hierarchy, NodeId};
use crate::scene::Scene;
use crate::stats::FrameStats;
use std::ops::ControlFlow;
use thiserror::Error;

/// Names accepted by [`create`], in the order tables list them.
pub const METHOD_NAMES: [&str; 14] =
    ["vfc", "sw", "chc", "chcpp", "om", "roc", "ioc", "hiz", "moc", "opt", "nohc", "nohc-opt", "auto", "nocull"];

/// Why [`create`] could not build a method.
#[derive(Debug, Error, PartialEq)]
pub enum MethodError {
    /// No method has this name.
    #[error("unknown method '{0}': expected one of {names}", names = METHOD_NAMES.join(", "))]
    Unknown(String),
    /// A parameter is wrong.
    #[error(transparent)]
    Option(#[from] OptionError),
}

/// A method ready to run, with the parameter values it uses (defaults
/// included) for the report.
pub struct BuiltMethod {
    /// The method; `Send`, so that a runner can render several methods'
    /// frames on threads of their own (every method is).
    pub method: Box<dyn CullingMethod + Send>,
    /// `(parameter, value)` pairs in the order the method reads them.
    pub params: Vec<(String, String)>,
}

/// What a backend lacks to run a method ([`check_support`]).
#[derive(Clone, Debug, Error, PartialEq, Eq)]
pub enum Unsupported {
    /// The method reads the oracle pass ([`Backend::instruments`]), which
    /// the backend does not have.
    #[error("this backend has no oracle pass (Backend::instruments)")]
    NoOracle,
    /// GPU-resident culling, or its depth pyramids, are missing.
    #[error(transparent)]
    GpuCulling(#[from] GpuCullingUnsupported),
}

/// Whether `backend` can run `method`: the oracle, GPU-resident culling
/// and depth pyramids it needs, or what the backend lacks. The bench runner
/// and the viewer ask before the first frame, so that a method never runs
/// on its fallback unseen.
pub fn check_support(method: &dyn CullingMethod, backend: &mut dyn Backend) -> Result<(), Unsupported> {
    if method.needs_oracle() && backend.instruments().is_none() {
        return Err(Unsupported::NoOracle);
    }
    if !method.needs_gpu_culling() {
        return Ok(());
    }
    let gpu = backend.gpu_culling()?;
    if method.needs_depth_pyramid() {
        gpu.pyramid_support()?;
    }
    Ok(())
}

/// The method called `name`, freshly constructed (no state from earlier
/// frames), with its parameters read from `options` ([`Method::parse`]).
pub fn create(name: &str, options: &MethodOptions) -> Result<BuiltMethod, MethodError> {
    let method = Method::parse(name, options)?;
    Ok(BuiltMethod { method: method.build()?, params: method.params()? })
}

/// A visibility-culling method. Implementations keep whatever they carry from
/// frame to frame (temporal coherence) in `self`.
pub trait CullingMethod {
    /// The method's name as used on the command line and in JSON.
    fn name(&self) -> &'static str;

    /// Work done before the frame's clock starts (an oracle pass); most
    /// methods need none.
    fn prepare(&mut self, _ctx: &mut FrameContext<'_>, _backend: &mut dyn Backend) {}

    /// Draws the frame: everything visible must reach `backend.draw` or
    /// [`GpuCulling::draw_list`](crate::GpuCulling::draw_list).
    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend);

    /// Whether the method runs on the backend's GPU-resident culling
    /// ([`Backend::gpu_culling`]); the runner refuses a backend without it
    /// before the first frame.
    fn needs_gpu_culling(&self) -> bool {
        false
    }

    /// Whether the method reads the backend's oracle pass
    /// ([`Instruments::oracle`](crate::Instruments::oracle), `opt`); the
    /// runner refuses a backend without it before the first frame.
    fn needs_oracle(&self) -> bool {
        false
    }

    /// Whether the method builds depth pyramids on the backend's
    /// GPU-resident culling ([`GpuCulling::pyramid_support`](crate::GpuCulling::pyramid_support));
    /// the runner refuses a backend without them before the first frame.
    fn needs_depth_pyramid(&self) -> bool {
        false
    }

    /// Warnings about the method's parameters that only the scene could
    /// reveal (a hierarchy depth past the tree's, clamped), each given once;
    /// the runner prints them.
    fn take_warnings(&mut self) -> Vec<String> {
        Vec::new()
    }

    /// Turns recording of a [`DebugView`] during the following frames on or
    /// off. Recording must change neither the method's decisions nor its
    /// statistics; methods without a view ignore it.
    fn set_debug(&mut self, _on: bool) {}

    /// The statistics of the frame just rendered, as the backend ended it:
    /// for a method that learns from what its frames cost (`auto`).
    fn finish_frame(&mut self, _stats: &FrameStats) {}

    /// A lower bound of the time of a frame of this method at `resolution`
    /// under `model`, ms: the passes it runs whatever the scene holds;
    /// `cold`, a frame that starts from nothing (its first, or the first
    /// after other methods ran), where that costs more. 0 where none is
    /// known. `auto` spares trying a method whose bound cannot beat the one
    /// it runs.
    fn floor_ms(&self, _ctx: &FrameContext<'_>, _model: &CostModel, _resolution: (u32, u32), _cold: bool) -> f64 {
        0.0
    }

    /// What [`CullingMethod::visible_set`] gives once the method has
    /// rendered a frame: `auto` seeds a method it switches to from it, if
    /// both carry visibility.
    fn carried_visibility(&self) -> Carried {
        Carried::Nothing
    }

    /// The instances this method found visible in the last frame it
    /// rendered, where it keeps them: for another method to start from
    /// ([`CullingMethod::seed`]). `None` where it keeps no visibility
    /// (`vfc`) or has rendered no frame.
    fn visible_set(&self, _ctx: &FrameContext<'_>) -> Option<VisibleSet> {
        None
    }

    /// Takes `visible` (what another method found visible last frame) as
    /// its own last frame's visibility, in place of what it kept. Any set
    /// keeps the method exact: it only changes what is drawn before
    /// testing. `auto` seeds a method it switches to, so that its first
    /// frame does not start from nothing. Moving the set costs the frame
    /// calling this: a GPU-driven method copies device flags or uploads a
    /// CPU set, `chcpp` reads device flags back (a wait for the GPU).
    /// Methods without temporal state ignore it.
    fn seed(&mut self, _ctx: &FrameContext<'_>, _backend: &mut dyn Backend, _visible: &VisibleSet) {}

    /// Method-specific figures of the last frame it rendered, by name (for
    /// example `om`'s nodes decided in stage 1 without a query and its
    /// stage-2 rounds); reported per frame beside the common statistics.
    fn counters(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }

    /// What the method decided in the last frame it rendered, if recording
    /// was on for that frame and the method has a view to give (only `om`).
    fn debug_view(&self) -> Option<DebugView> {
        None
    }
}

/// What a method carries from frame to frame and hands over
/// ([`CullingMethod::carried_visibility`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Carried {
    /// Nothing (`vfc`): it gives no set and takes none.
    Nothing,
    /// Every instance of the leaves it found visible (`chcpp`): a superset
    /// of the instances visible, as coarse as its leaves.
    Leaves,
    /// Exactly the instances whose own test found them visible (`roc`,
    /// `hiz`).
    Instances,
}

/// What a method found visible in its last frame, one flag per instance,
/// where it keeps them ([`CullingMethod::visible_set`]).
#[derive(Clone, Debug, PartialEq)]
pub enum VisibleSet {
    /// On the CPU (`chcpp`'s classification).
    Host(Vec<bool>),
    /// In a flag buffer of the backend's GPU-resident culling (`roc`'s and
    /// `hiz`'s), valid until that method's next frame.
    Device(Flags),
}

impl VisibleSet {
    /// The flags on the CPU: a device set is read back (the frame waits
    /// for the GPU); `None` where the backend has no GPU-resident culling.
    pub fn to_host(&self, backend: &mut dyn Backend) -> Option<Vec<bool>> {
        match self {
            VisibleSet::Host(set) => Some(set.clone()),
            VisibleSet::Device(flags) => Some(backend.gpu_culling().ok()?.read_flags(*flags)),
        }
    }

    /// Makes `dst`, a flag buffer on `gpu`, hold the set: a copy on the
    /// device, or an upload.
    pub fn write_to(&self, gpu: &mut dyn crate::GpuCulling, dst: Flags) {
        match self {
            VisibleSet::Host(set) => gpu.write_flags(dst, set),
            VisibleSet::Device(src) if *src != dst => gpu.copy_flags(*src, dst),
            VisibleSet::Device(_) => {}
        }
    }
}

/// Triangles drawn by each node's subtree, a rendering-cost estimate
/// (children have higher ids than their parent in both builders, so one
/// backward sweep suffices).
pub fn subtree_triangles(scene: &Scene, h: &Hierarchy) -> Vec<u64> {
    let mut tris = vec![0u64; h.node_count()];
    for n in (0..h.node_count() as NodeId).rev() {
        tris[n as usize] = if h.is_leaf(n) {
            h.instances(n).iter().map(|&i| scene.instance_triangles(i as usize)).sum()
        } else {
            h.children(n).iter().map(|&c| tris[c as usize]).sum()
        };
    }
    tris
}

/// Per-node state that carries a visibility classification from frame to
/// frame (CHC and CHC++).
pub(crate) trait Classified {
    /// The node's "visible" flag.
    fn visible_mut(&mut self) -> &mut bool;
}

/// Marks `node` and its ancestors visible, stopping at the first ancestor
/// already marked (CHC paper, Figure 2, `PullUpVisibility`; CHC++ Figure 6).
pub(crate) fn pull_up_visibility<S: Classified>(h: &Hierarchy, states: &mut [S], mut node: NodeId) {
    loop {
        let visible = states[node as usize].visible_mut();
        if *visible {
            return;
        }
        *visible = true;
        match h.parent(node) {
            Some(p) => node = p,
            None => return,
        }
    }
}

/// Remembers which instances were drawn in the current frame, so an instance
/// referenced by several kD-tree leaves is drawn once.
#[derive(Clone, Debug, Default)]
pub struct DrawnSet {
    stamp: Vec<u32>,
    frame: u32,
    batch: Vec<u32>,
}

impl DrawnSet {
    /// Forgets the previous frame's draws.
    pub fn next_frame(&mut self, instances: usize) {
        self.stamp.resize(instances, 0);
        self.frame = self.frame.wrapping_add(1);
        if self.frame == 0 {
            self.stamp.fill(0);
            self.frame = 1;
        }
    }

    /// True when `instance` was drawn this frame.
    pub fn contains(&self, instance: u32) -> bool {
        self.stamp[instance as usize] == self.frame
    }

    /// Replaces the batch with those of `instances` shown in `scene` and
    /// not drawn yet this frame (each once), marking them drawn.
    fn batch_new(&mut self, scene: &Scene, instances: impl Iterator<Item = u32>) {
        self.batch.clear();
        for i in instances {
            if self.stamp[i as usize] != self.frame && scene.instances[i as usize].enabled {
                self.stamp[i as usize] = self.frame;
                self.batch.push(i);
            }
        }
    }
}

/// Everything a method sees of one frame.
pub struct FrameContext<'a> {
    /// The scene being drawn.
    pub scene: &'a Scene,
    /// The hierarchy over its instances.
    pub hierarchy: &'a Hierarchy,
    /// This frame's camera.
    pub camera: Camera,
    /// This frame's view frustum.
    pub frustum: Frustum,
    drawn: &'a mut DrawnSet,
}

impl<'a> FrameContext<'a> {
    /// The context of a new frame seen by `camera`.
    pub fn new(scene: &'a Scene, hierarchy: &'a Hierarchy, camera: Camera, drawn: &'a mut DrawnSet) -> Self {
        drawn.next_frame(scene.instances.len());
        Self { scene, hierarchy, frustum: camera.frustum(), camera, drawn }
    }

    /// Draws the instances of leaf `node` not yet drawn this frame; returns
    /// how many were drawn.
    pub fn draw_leaf(&mut self, backend: &mut dyn Backend, node: NodeId) -> usize {
        self.draw_leaves(backend, &[node], false)
    }

    /// Draws those of `instances` shown and not yet drawn this frame, in
    /// one batch; returns them (valid until the next draw through this
    /// context).
    pub fn draw_instances(&mut self, backend: &mut dyn Backend, instances: &[u32]) -> &[u32] {
        let d = &mut *self.drawn;
        d.batch_new(self.scene, instances.iter().copied());
        if !d.batch.is_empty() {
            backend.draw(&d.batch);
        }
        &d.batch
    }

    /// Draws the shown instances of `leaves` not yet drawn this frame, in
    /// one batch; with `sort_by_material` the batch is ordered by material so
    /// that each material costs one state change (the CHC++ render queue,
    /// section 4.3). Returns how many instances were drawn.
    pub fn draw_leaves(&mut self, backend: &mut dyn Backend, leaves: &[NodeId], sort_by_material: bool) -> usize {
        let d = &mut *self.drawn;
        let h = self.hierarchy;
        d.batch_new(self.scene, leaves.iter().flat_map(|&leaf| h.instances(leaf).iter().copied()));
        if sort_by_material {
            let instances = &self.scene.instances;
            d.batch.sort_by_key(|&i| instances[i as usize].material);
        }
        if !d.batch.is_empty() {
            backend.draw(&d.batch);
        }
        d.batch.len()
    }

    /// Appends the leaves in view under `node` (itself if it is a leaf), in
    /// no particular order; returns the nodes visited.
    pub fn leaves_in_view(&self, node: NodeId, out: &mut Vec<NodeId>) -> u64 {
        self.walk_leaves_in_view(node, |leaf| {
            out.push(leaf);
            ControlFlow::Continue(())
        })
    }

    /// Calls `visit` with each leaf under `node` in the view frustum, depth
    /// first, until it breaks; returns the number of nodes visited.
    pub fn walk_leaves_in_view(&self, node: NodeId, mut visit: impl FnMut(NodeId) -> ControlFlow<()>) -> u64 {
        let h = self.hierarchy;
        let mut stack = vec![node];
        let mut visited = 0;
        while let Some(n) = stack.pop() {
            visited += 1;
            if !self.in_frustum(n) {
                continue;
            }
            if !h.is_leaf(n) {
                stack.extend_from_slice(h.children(n));
            } else if visit(n).is_break() {
                break;
            }
        }
        visited
    }

    /// True when `instance` was drawn this frame.
    pub fn was_drawn(&self, instance: u32) -> bool {
        self.drawn.contains(instance)
    }

    /// True when node `id` has something in view (non-empty and not outside
    /// the frustum).
    pub fn in_frustum(&self, id: NodeId) -> bool {
        let b = self.hierarchy.bounds(id);
        !b.is_empty() && self.frustum.intersects(b)
    }

    /// Adds those of `nodes` that are in the frustum to `queue`, ordered by
    /// their distance from the eye.
    pub fn push_in_frustum(&self, nodes: &[NodeId], queue: &mut FrontToBack) {
        for &n in nodes {
            if self.in_frustum(n) {
                queue.push_node(self.hierarchy, n, self.camera.position);
            }
        }
    }
}
