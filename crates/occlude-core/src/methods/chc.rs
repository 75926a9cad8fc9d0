//! Coherent hierarchical culling (Bittner, Wimmer, Piringer, Purgathofer,
//! Eurographics 2004), Figure 2 of the paper, with its section 5 options.
//!
//! Visibility from the previous frame schedules this frame's queries: the
//! traversal runs front to back (a priority queue, section 4.4, so any
//! hierarchy works), skips queries on previously opened interior nodes,
//! renders previously visible leaves at once while their queries are in
//! flight, and consumes query results from a queue as soon as they are
//! available, interleaved with the traversal (section 4.1). Visibility is
//! pulled up the hierarchy when a node turns out visible.

use super::tracked::Tracked;
use super::{
    pull_up_visibility, subtree_triangles, Classified, CullingMethod, FrameContext, FrontToBack, MethodParams,
    OptionError, ParamVisitor,
};
use crate::backend::{Backend, QueryHandle};
use crate::hierarchy::{NodeId, Since};
use std::collections::VecDeque;

/// The section 5 options of CHC.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChcParams {
    /// `tav`: frames a node found visible is assumed visible without a query
    /// (section 5.1, conservative visibility testing); 0 turns it off.
    pub assumed_visible_frames: u32,
    /// `nvp`: a node is visible only if more than this many pixels pass
    /// (section 5.2, approximate visibility); 0 is exact.
    pub visible_pixel_threshold: u64,
    /// `spec`: when the CPU would stall, render the cheapest node waiting in
    /// the query queue if it has at most this many triangles (section 5.3,
    /// conservative speculative rendering); 0 turns it off.
    pub speculation_triangles: u64,
}

/// Every option off: the paper's basic algorithm (section 4).
impl Default for ChcParams {
    fn default() -> Self {
        Self { assumed_visible_frames: 0, visible_pixel_threshold: 0, speculation_triangles: 0 }
    }
}

impl MethodParams for ChcParams {
    const METHOD: &'static str = "chc";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        v.value("tav", &mut self.assumed_visible_frames, "an integer from 0 to 1000", |&f| f <= 1000)?;
        v.value("nvp", &mut self.visible_pixel_threshold, "an integer >= 0 (pixels)", |_| true)?;
        v.value("spec", &mut self.speculation_triangles, "an integer >= 0 (triangles)", |_| true)
    }
}

/// What CHC remembers about a node between frames.
#[derive(Clone, Copy, Debug, Default)]
struct NodeState {
    visible: bool,
    last_visited: u32,
    /// Last frame of the `tav` window in which no query is needed.
    assumed_until: u32,
    /// Frame in which the node's subtree was rendered speculatively.
    speculated: u32,
}

impl Classified for NodeState {
    fn visible_mut(&mut self) -> &mut bool {
        &mut self.visible
    }
}

/// `chc`: coherent hierarchical culling.
#[derive(Clone, Debug)]
pub struct Chc {
    params: ChcParams,
    frame: u32,
    /// The hierarchy the node states are for.
    tracked: Tracked,
    nodes: Vec<NodeState>,
    /// Triangles under each node, for the speculation cost estimate.
    subtree_triangles: Vec<u64>,
}

impl Chc {
    /// CHC with the given options.
    pub fn new(params: ChcParams) -> Self {
        Self { params, frame: 0, tracked: Tracked::default(), nodes: Vec::new(), subtree_triangles: Vec::new() }
    }

    /// Figure 2, `TraverseNode`: render a leaf or queue the children.
    fn traverse_node(
        &self,
        ctx: &mut FrameContext<'_>,
        backend: &mut dyn Backend,
        queue: &mut FrontToBack,
        node: NodeId,
    ) {
        let h = ctx.hierarchy;
        if h.is_leaf(node) {
            ctx.draw_leaf(backend, node);
        } else {
            for &c in h.children(node) {
                queue.push_node(h, c, ctx.camera.position);
            }
        }
    }

    /// Section 5.3: picks the cheapest queued node not yet speculated on,
    /// if it is cheap enough, and renders it; true when something was drawn.
    fn speculate(
        &mut self,
        ctx: &mut FrameContext<'_>,
        backend: &mut dyn Backend,
        queries: &VecDeque<(NodeId, QueryHandle)>,
    ) -> bool {
        let frame = self.frame;
        let candidate = queries
            .iter()
            .map(|&(n, _)| n)
            .filter(|&n| self.nodes[n as usize].speculated != frame)
            .min_by_key(|&n| (self.subtree_triangles[n as usize], n));
        match candidate {
            Some(n) if self.subtree_triangles[n as usize] <= self.params.speculation_triangles => {
                self.nodes[n as usize].speculated = frame;
                let mut leaves = Vec::new();
                ctx.leaves_in_view(n, &mut leaves);
                ctx.draw_leaves(backend, &leaves, false);
                true
            }
            _ => false,
        }
    }

    /// Sizes the per-node state for `h` (first frame, or a new hierarchy).
    fn prepare_state(&mut self, ctx: &FrameContext<'_>) {
        let h = ctx.hierarchy;
        if self.tracked.since(h) == Since::New {
            self.nodes = vec![NodeState::default(); h.node_count()];
            self.subtree_triangles = subtree_triangles(ctx.scene, h);
        }
    }
}

impl CullingMethod for Chc {
    fn name(&self) -> &'static str {
        "chc"
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        self.prepare_state(ctx);
        self.frame += 1;
        let frame = self.frame;
        let h = ctx.hierarchy;
        let mut traversal = FrontToBack::new();
        let mut queries: VecDeque<(NodeId, QueryHandle)> = VecDeque::new();
        traversal.push_node(h, h.root(), ctx.camera.position);

        while !traversal.is_empty() || !queries.is_empty() {
            // Part 1: consume finished queries (wait only with nothing else to do).
            while let Some(&(node, query)) = queries.front() {
                if !backend.is_available(query) {
                    if !traversal.is_empty() {
                        break;
                    }
                    if self.params.speculation_triangles > 0 && self.speculate(ctx, backend, &queries) {
                        continue;
                    }
                }
                queries.pop_front();
                if backend.result(query) > self.params.visible_pixel_threshold {
                    pull_up_visibility(h, &mut self.nodes, node);
                    let state = &mut self.nodes[node as usize];
                    state.assumed_until = frame + self.params.assumed_visible_frames;
                    self.traverse_node(ctx, backend, &mut traversal, node);
                }
            }
            // Part 2: hierarchy traversal.
            let Some(node) = traversal.pop() else { continue };
            backend.traverse(1);
            if !ctx.in_frustum(node) {
                continue;
            }
            let state = &mut self.nodes[node as usize];
            let was_visible = state.visible && state.last_visited + 1 == frame;
            let opened = was_visible && !h.is_leaf(node);
            let assumed = was_visible && frame <= state.assumed_until;
            state.visible = false;
            state.last_visited = frame;
            if assumed {
                // Section 5.1: still within the tav window, no query.
                pull_up_visibility(h, &mut self.nodes, node);
            } else if !opened {
                queries.push_back((node, backend.issue_query(std::slice::from_ref(h.bounds(node)))));
            }
            if was_visible {
                self.traverse_node(ctx, backend, &mut traversal, node);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, drawn, method, queried_alone, Rig};
    use crate::mock::Call;

    /// A hidden object is not drawn, its leaf is queried again in every
    /// following frame (the interval of an invisible node), and it is drawn
    /// in the frame it turns visible.
    #[test]
    fn a_hidden_object_is_requeried_each_frame_and_drawn_once_visible() {
        let rig = Rig::row(4);
        let mut mock = rig.mock();
        mock.set_visible(1, false);
        let mut chc = method("chc", &[]);
        let leaf = *rig.hierarchy.bounds(rig.leaf_of(1));
        for (f, calls) in rig.run(&mut chc, &mut mock, 4).iter().enumerate() {
            assert_draws_exactly(calls, &[0, 2, 3]);
            assert!(queried_alone(calls, &leaf), "frame {f}: the hidden leaf was not queried");
        }
        mock.set_visible(1, true);
        let calls = &rig.run(&mut chc, &mut mock, 1)[0];
        assert_draws_exactly(calls, &[0, 1, 2, 3]);
    }

    /// With `tav` = 2 a visible leaf is queried, then assumed visible for
    /// two frames without a query, then queried again; with `tav` = 0 it
    /// is queried every frame.
    #[test]
    fn a_visible_leaf_is_requeried_after_tav_frames() {
        let rig = Rig::row(4);
        let leaf = *rig.hierarchy.bounds(rig.leaf_of(0));
        let queried_frames = |options: &[&str]| -> Vec<usize> {
            let mut mock = rig.mock();
            let frames = rig.run(&mut method("chc", options), &mut mock, 7);
            frames.iter().enumerate().filter(|(_, c)| queried_alone(c, &leaf)).map(|(f, _)| f + 1).collect()
        };
        assert_eq!(queried_frames(&["chc.tav=2"]), [1, 4, 7]);
        assert_eq!(queried_frames(&[]), [1, 2, 3, 4, 5, 6, 7]);
    }

    /// A leaf visible in the last frame is drawn at once, before its query's
    /// result comes back (section 4.1: no wait for previously visible leaves).
    #[test]
    fn previously_visible_leaves_are_drawn_before_their_results_are_read() {
        let rig = Rig::row(4);
        let mut mock = rig.mock().with_latency(1000);
        let frames = rig.run(&mut method("chc", &[]), &mut mock, 2);
        let calls = &frames[1];
        let leaf = *rig.hierarchy.bounds(rig.leaf_of(0));
        let query = calls
            .iter()
            .find_map(|c| match c {
                Call::IssueQuery { query, boxes } if boxes[..] == [leaf] => Some(*query),
                _ => None,
            })
            .expect("the leaf is queried");
        let drawn_at = calls.iter().position(|c| matches!(c, Call::Draw(i) if i.contains(&0))).expect("drawn");
        let read_at = calls.iter().position(|c| matches!(c, Call::Result { query: q, .. } if *q == query)).unwrap();
        assert!(drawn_at < read_at, "drawn at call {drawn_at}, its result read at {read_at}");
        assert_eq!(drawn(calls).len(), 4);
    }
}
