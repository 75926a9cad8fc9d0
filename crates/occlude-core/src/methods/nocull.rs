//! No culling: every leaf of the hierarchy drawn each frame, the view
//! frustum untested. The IOC poster's NOCULL baseline (section 3, Figures 1
//! and 4): what culling of any kind saves is measured against it. The GPU
//! clips what lies outside the view, so its image is `vfc`'s.

use super::{CullingMethod, FrameContext};
use crate::backend::Backend;

/// `nocull`: every shown instance drawn, leaf by leaf, depth first.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoCulling;

impl CullingMethod for NoCulling {
    fn name(&self) -> &'static str {
        "nocull"
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let h = ctx.hierarchy;
        let mut stack = vec![h.root()];
        let mut visited = 0u64;
        while let Some(node) = stack.pop() {
            visited += 1;
            if h.is_leaf(node) {
                ctx.draw_leaf(backend, node);
            } else {
                stack.extend(h.children(node).iter().rev());
            }
        }
        backend.traverse(visited);
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, method, queries, Rig};

    /// Every instance drawn once, the one behind the camera too, and no
    /// query.
    #[test]
    fn draws_every_instance_once_and_queries_nothing() {
        let rig = Rig::row(6);
        let mut mock = rig.mock();
        mock.set_visible(2, false);
        for calls in &rig.run(&mut method("nocull", &[]), &mut mock, 2) {
            assert_draws_exactly(calls, &[0, 1, 2, 3, 4, 5, 6]);
            assert!(queries(calls).is_empty());
        }
    }
}
