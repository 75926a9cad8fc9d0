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

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, method, Rig};
    use crate::mock::Call;

    /// Each query is waited for before the next is issued (a stall every
    /// time, with a latency), and the script is honoured: hidden instances
    /// are not drawn, visible ones in view are.
    #[test]
    fn waits_for_each_query_before_the_next() {
        let rig = Rig::row(6);
        let mut mock = rig.mock().with_latency(3);
        mock.set_visible(1, false);
        mock.set_visible(4, false);
        let frames = rig.run(&mut method("sw", &[]), &mut mock, 2);
        for calls in &frames {
            assert_draws_exactly(calls, &[0, 2, 3, 5]);
            let mut open = None;
            for call in calls {
                match call {
                    Call::IssueQuery { query, .. } => {
                        assert_eq!(open, None, "a query issued before the previous one's result was read");
                        open = Some(*query);
                    }
                    Call::Result { query, waited, .. } => {
                        assert_eq!(open.take(), Some(*query));
                        assert!(waited, "with a latency, every result is a stall");
                    }
                    _ => {}
                }
            }
            assert_eq!(open, None);
        }
    }
}
