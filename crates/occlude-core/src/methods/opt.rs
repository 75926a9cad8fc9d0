//! The ideal visible set (DESIGN.md, "opt"; the CHC++ paper's OPT): draw
//! exactly the hierarchy leaves that hold an instance with at least one pixel
//! in the final image, with no query. The set comes from an oracle pass run
//! before the frame's clock starts, so `opt` is the fastest any query-based
//! method can be on the same hierarchy.

use super::{CullingMethod, FrameContext};
use crate::backend::Backend;
use crate::hierarchy::NodeId;

/// `opt`: render the oracle's visible leaves only.
#[derive(Clone, Debug, Default)]
pub struct Optimal {
    leaves: Vec<NodeId>,
}

impl CullingMethod for Optimal {
    fn name(&self) -> &'static str {
        "opt"
    }

    fn prepare(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let h = ctx.hierarchy;
        let in_view: Vec<NodeId> =
            (0..h.node_count() as NodeId).filter(|&n| h.is_leaf(n) && ctx.in_frustum(n)).collect();
        let mut candidates: Vec<u32> = in_view.iter().flat_map(|&n| h.instances(n).iter().copied()).collect();
        candidates.sort_unstable();
        candidates.dedup();
        let mut visible = vec![false; ctx.scene.instances.len()];
        for i in backend.visible_instances(&ctx.camera, &candidates) {
            visible[i as usize] = true;
        }
        let eye = ctx.camera.position;
        self.leaves = in_view.into_iter().filter(|&n| h.instances(n).iter().any(|&i| visible[i as usize])).collect();
        self.leaves.sort_by(|&a, &b| h.bounds(a).distance_squared(eye).total_cmp(&h.bounds(b).distance_squared(eye)));
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        for &leaf in &self.leaves {
            ctx.draw_leaf(backend, leaf);
        }
    }
}
