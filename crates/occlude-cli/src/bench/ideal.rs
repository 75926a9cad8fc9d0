//! `ideal`: the CHC paper's "ideal" algorithm (Bittner et al. 2004, section
//! 6.2), also the CHC++ paper's OPT (Mattausch et al. 2008, section 8): "the
//! visible objects found by the S&W algorithm" rendered "without performing
//! any visibility tests", the fastest any method can be on the same
//! hierarchy.
//!
//! The runner records the draw calls `sw` makes in a frame ([`DrawLog`], a
//! backend that forwards everything and keeps the draws) and [`Ideal`]
//! replays them in the same frame on its own backend: the same objects, in
//! the same order and the same calls, with no query and no traversal. It is
//! the paper's ideal, not the pixel-exact set of `opt`, which is kept beside
//! it. On the soft backend, `ideal`'s backend takes the counts and image of
//! `sw`'s instead of rasterizing the same draws again
//! ([`occlude_soft::DrawReplay`], wired by the runner).

use occlude_core::{
    Aabb, Backend, Camera, CostModel, CpuCullingWork, CullingMethod, FrameContext, FrameStats, GpuCulling,
    GpuCullingUnsupported, Instruments, QueryHandle, Scene,
};
use std::sync::{Arc, Mutex, PoisonError};

/// The method's name, as `--methods` lists it.
pub const IDEAL: &str = "ideal";

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

/// `ideal`: replays the draw calls [`SOURCE`] made in this frame.
pub struct Ideal {
    calls: DrawCalls,
}

impl Ideal {
    /// Replays what a [`DrawLog`] sharing `calls` recorded.
    pub fn new(calls: DrawCalls) -> Self {
        Self { calls }
    }
}

impl CullingMethod for Ideal {
    fn name(&self) -> &'static str {
        IDEAL
    }

    fn render(&mut self, _ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        for instances in lock(&self.calls).iter() {
            backend.draw(instances);
        }
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
