//! View-frustum culling over the hierarchy: the baseline every table compares
//! against (CHC paper, section 6.2). Draws every leaf in view, no queries.

use super::{CullingMethod, FrameContext};
use crate::backend::Backend;
use crate::camera::Visibility;

/// `vfc`: hierarchical view-frustum culling.
#[derive(Clone, Copy, Debug, Default)]
pub struct ViewFrustumCulling;

impl CullingMethod for ViewFrustumCulling {
    fn name(&self) -> &'static str {
        "vfc"
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let h = ctx.hierarchy;
        // Depth-first, nearer child first; a node wholly inside the frustum
        // passes its children without further plane tests.
        let mut stack = vec![(h.root(), false)];
        let mut visited = 0u64;
        while let Some((node, inside)) = stack.pop() {
            visited += 1;
            let bounds = h.bounds(node);
            if bounds.is_empty() {
                continue;
            }
            let inside = inside
                || match ctx.frustum.classify(bounds) {
                    Visibility::Outside => continue,
                    Visibility::Inside => true,
                    Visibility::Intersecting => false,
                };
            if h.is_leaf(node) {
                ctx.draw_leaf(backend, node);
                continue;
            }
            let mut children = [0; 2];
            children.copy_from_slice(h.children(node));
            let eye = ctx.camera.position;
            children.sort_by(|&a, &b| h.bounds(a).distance_squared(eye).total_cmp(&h.bounds(b).distance_squared(eye)));
            stack.extend(children.iter().rev().map(|&c| (c, inside)));
        }
        backend.traverse(visited);
    }
}
