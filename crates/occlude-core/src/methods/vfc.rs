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

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, method, queries, Rig};
    use crate::mock::Call;

    /// Everything in the frustum drawn once, nothing behind the camera, no
    /// query, and the nodes visited charged.
    #[test]
    fn draws_everything_in_view_once_and_queries_nothing() {
        let rig = Rig::row(6);
        let mut mock = rig.mock();
        mock.set_visible(2, false);
        let frames = rig.run(&mut method("vfc", &[]), &mut mock, 2);
        for calls in &frames {
            assert_draws_exactly(calls, &[0, 1, 2, 3, 4, 5]);
            assert!(queries(calls).is_empty());
            assert!(calls.iter().any(|c| matches!(c, Call::Traverse(n) if *n > 0)));
        }
    }
}
