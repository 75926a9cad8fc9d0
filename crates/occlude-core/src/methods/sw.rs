//! Hierarchical stop-and-wait (CHC paper, section 3.3): front to back, every
//! node in the frustum is queried and the CPU waits for each result before
//! going on. Visible leaves are drawn, visible interior nodes opened.

use super::{CullingMethod, FrameContext, FrontToBack};
use crate::backend::Backend;

/// `sw`: hierarchical stop-and-wait occlusion culling.
#[derive(Clone, Copy, Debug, Default)]
pub struct StopAndWait;

impl CullingMethod for StopAndWait {
    fn name(&self) -> &'static str {
        "sw"
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let h = ctx.hierarchy;
        let mut queue = FrontToBack::new();
        ctx.push_in_frustum(&[h.root()], &mut queue);
        while let Some(node) = queue.pop() {
            backend.traverse(1);
            let query = backend.issue_query(std::slice::from_ref(h.bounds(node)));
            if backend.result(query) == 0 {
                continue;
            }
            if h.is_leaf(node) {
                ctx.draw_leaf(backend, node);
            } else {
                ctx.push_in_frustum(h.children(node), &mut queue);
            }
        }
    }
}
