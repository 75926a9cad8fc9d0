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
//! it.

use occlude_core::{
    Aabb, Backend, Camera, CostModel, CpuCullingWork, CullingMethod, FrameContext, FrameStats, GpuCulling,
    GpuCullingUnsupported, Instruments, QueryHandle,
};
use std::cell::RefCell;
use std::rc::Rc;

/// The method's name, as `--methods` lists it.
pub const IDEAL: &str = "ideal";

/// The method whose visible set [`Ideal`] renders, listed before it.
pub const SOURCE: &str = "sw";

/// The draw calls of one frame, shared by the [`DrawLog`] that records them
/// and the [`Ideal`] that replays them.
pub type DrawCalls = Rc<RefCell<Vec<Vec<u32>>>>;

/// A backend that forwards every call to `inner` and keeps the frame's draw
/// calls in `calls` (cleared when a frame begins).
pub struct DrawLog<'s> {
    inner: Box<dyn Backend + 's>,
    calls: DrawCalls,
}

impl<'s> DrawLog<'s> {
    /// Records the draws made on `inner` into `calls`.
    pub fn new(inner: Box<dyn Backend + 's>, calls: DrawCalls) -> Self {
        Self { inner, calls }
    }
}

impl Backend for DrawLog<'_> {
    fn begin_frame(&mut self, camera: &Camera) {
        self.calls.borrow_mut().clear();
        self.inner.begin_frame(camera);
    }
    fn draw(&mut self, instances: &[u32]) {
        self.calls.borrow_mut().push(instances.to_vec());
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
        for instances in self.calls.borrow().iter() {
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
