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
        let eye = ctx.camera.position;
        let mut queue = FrontToBack::new();
        if ctx.in_frustum(h.root()) {
            queue.push_node(h, h.root(), eye);
        }
        while let Some(node) = queue.pop() {
            backend.traverse(1);
            let query = backend.issue_query(std::slice::from_ref(h.bounds(node)));
            if backend.result(query) == 0 {
                continue;
            }
            if h.is_leaf(node) {
                ctx.draw_leaf(backend, node);
            } else {
                for &c in h.children(node) {
                    if ctx.in_frustum(c) {
                        queue.push_node(h, c, eye);
                    }
                }
            }
        }
    }
}
