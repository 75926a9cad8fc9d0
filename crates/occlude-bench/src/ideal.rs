//! The papers' ideal methods, which draw the nodes stop-and-wait finds
//! visible without any query:
//!
//! - `ideal`: the CHC paper's "ideal" algorithm (Bittner et al. 2004,
//!   section 6.2): "the visible objects found by the S&W algorithm" rendered
//!   "without performing any visibility tests", in `sw`'s own order.
//! - `ideal-sorted`: the CHC++ paper's OPT (Mattausch et al. 2008, section
//!   8): "only the visible nodes (recorded by S&W) without any occlusion
//!   queries", here drawn in one batch through the material-sorted render
//!   queue `chcpp` uses (`FrameContext::draw_instances` after a stable sort
//!   by material), so that CHC++'s sorting gains nothing over it.
//!
//! The runner records the draw calls `sw` makes in a frame ([`DrawLog`], a
//! backend that forwards everything and keeps the draws) and [`Ideal`]
//! draws them in the same frame on its own backend, with no query and no
//! traversal: the same objects, and for `ideal` the same calls in the same
//! order. Neither is the per-instance lower bound `opt`, which is kept
//! beside them. On the soft backend, `ideal`'s backend takes the counts and
//! image of `sw`'s instead of rasterizing the same draws again
//! ([`occlude_soft::DrawReplay`], wired by the runner); `ideal-sorted`'s,
//! drawing in another order, rasterizes its own.

use occlude_core::{
    Aabb, Backend, Camera, CostModel, CpuCullingWork, CullingMethod, FrameContext, FrameStats, GpuCulling,
    GpuCullingUnsupported, Instruments, QueryHandle, Scene,
};
use std::sync::{Arc, Mutex, PoisonError};

/// The CHC paper's ideal, as `--methods` lists it.
pub const IDEAL: &str = "ideal";

/// The CHC++ paper's OPT, as `--methods` lists it.
pub const IDEAL_SORTED: &str = "ideal-sorted";

/// The methods that draw [`SOURCE`]'s visible set, each listed after it.
pub const IDEALS: [&str; 2] = [IDEAL, IDEAL_SORTED];

/// The method whose visible set [`Ideal`] renders, listed before it.
pub const SOURCE: &str = "sw";

/// The draw calls of one frame, shared by the [`DrawLog`] that records them
/// and the [`Ideal`] that replays them (the runner renders both lanes on
/// one thread, the log's first, but possibly another thread than the other
/// lanes').
pub type DrawCalls = Arc<Mutex<Vec<Vec<u32>>>>;

/// The calls recorded in `calls` (a panic while they were held leaves them
/// usable: each is a whole draw call).
fn lock(calls: &DrawCalls) -> std::sync::MutexGuard<'_, Vec<Vec<u32>>> {
    calls.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A backend that forwards every call to `inner` and keeps the frame's draw
/// calls in `calls` (cleared when a frame begins). `B` is the wrapped
/// backend's type, a trait object in the runner.
pub struct DrawLog<B: ?Sized> {
    inner: Box<B>,
    calls: DrawCalls,
}

impl<B: Backend + ?Sized> DrawLog<B> {
    /// Records the draws made on `inner` into `calls`.
    pub fn new(inner: Box<B>, calls: DrawCalls) -> Self {
        Self { inner, calls }
    }
}

impl<B: Backend + ?Sized> Backend for DrawLog<B> {
    fn begin_frame(&mut self, camera: &Camera) {
        lock(&self.calls).clear();
        self.inner.begin_frame(camera);
    }

    fn update_instances(&mut self, scene: &Scene, changed: &[u32]) {
        self.inner.update_instances(scene, changed);
    }
    fn draw(&mut self, instances: &[u32]) {
        lock(&self.calls).push(instances.to_vec());
        self.inner.draw(instances);
    }
    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
        self.inner.issue_query(boxes)
    }
    fn is_available(&mut self, query: QueryHandle) -> bool {
        self.inner.is_available(query)
    }
    fn result(&mut self, query: QueryHandle) -> u64 {
        self.inner.result(query)
    }
    fn traverse(&mut self, nodes: u64) {
        self.inner.traverse(nodes);
    }
    fn resolution(&self) -> (u32, u32) {
        self.inner.resolution()
    }
    fn cpu_culling(&mut self, work: CpuCullingWork) {
        self.inner.cpu_culling(work);
    }
    fn end_frame(&mut self) -> FrameStats {
        self.inner.end_frame()
    }
    fn failure(&self) -> Option<String> {
        self.inner.failure()
    }
    fn gpu_culling(&mut self) -> Result<&mut dyn GpuCulling, GpuCullingUnsupported> {
        self.inner.gpu_culling()
    }
    fn instruments(&mut self) -> Option<&mut dyn Instruments> {
        self.inner.instruments()
    }
    fn cost_model(&self) -> Option<CostModel> {
        self.inner.cost_model()
    }
}

/// `ideal` and `ideal-sorted`: draw the instances [`SOURCE`] drew in this
/// frame, without queries.
pub struct Ideal {
    calls: DrawCalls,
    sorted: bool,
}

impl Ideal {
    /// `ideal`: replays what a [`DrawLog`] sharing `calls` recorded, call by
    /// call.
    pub fn new(calls: DrawCalls) -> Self {
        Self { calls, sorted: false }
    }

    /// `ideal-sorted`: draws the instances a [`DrawLog`] sharing `calls`
    /// recorded in one batch ordered by material (stable, so `sw`'s order
    /// within a material).
    pub fn sorted(calls: DrawCalls) -> Self {
        Self { calls, sorted: true }
    }

    /// The method called `name` (one of [`IDEALS`]) drawing what a
    /// [`DrawLog`] sharing `calls` recorded.
    pub fn named(name: &str, calls: DrawCalls) -> Self {
        assert!(IDEALS.contains(&name), "not an ideal method: {name}");
        if name == IDEAL_SORTED {
            Self::sorted(calls)
        } else {
            Self::new(calls)
        }
    }
}

impl CullingMethod for Ideal {
    fn name(&self) -> &'static str {
        if self.sorted {
            IDEAL_SORTED
        } else {
            IDEAL
        }
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let calls = lock(&self.calls);
        if !self.sorted {
            for instances in calls.iter() {
                backend.draw(instances);
            }
            return;
        }
        let mut queue: Vec<u32> = calls.iter().flatten().copied().collect();
        let instances = &ctx.scene.instances;
        queue.sort_by_key(|&i| instances[i as usize].material);
        ctx.draw_instances(backend, &queue);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use occlude_core::mock::assert_forwards_every_call;

    /// The draw log forwards every call of the backend interface.
    #[test]
    fn forwards_every_call() {
        assert_forwards_every_call(|mock| DrawLog::new(Box::new(mock), DrawCalls::default()));
    }
}
