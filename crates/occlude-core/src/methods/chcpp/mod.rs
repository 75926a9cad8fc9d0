//! CHC++: coherent hierarchical culling revisited (Mattausch, Bittner,
//! Wimmer, Eurographics 2008), Figure 6 of the paper.
//!
//! On top of CHC's front-to-back traversal and temporal coherence:
//! previously invisible nodes wait in an i-queue and are queried in batches
//! of `b`, grouped into multiqueries (section 4.1, 5.1); queries of
//! previously visible leaves wait in a v-queue and fill the time the CPU
//! would otherwise wait (section 4.2); rendering goes through a render queue
//! sorted by material before each query batch (section 4.3); visible leaves
//! are re-queried every `nav` frames, the first time after a random delay
//! (section 5.2); queries use tight bounding volumes and traversal stops at
//! virtual leaves (section 6). Every component can be switched off.
//!
//! Query handles do not outlive a frame, so the v-queue left at the end of
//! a frame is issued and read then. That read costs the last query's
//! latency, which shows as wait time.

pub mod multiquery;
pub mod tight;

use super::tracked::Tracked;
use super::{
    pull_up_visibility, subtree_triangles, Carried, Classified, CullingMethod, FrameContext, FrontToBack, MethodParams,
    OptionError, ParamVisitor, VisibleSet,
};
use crate::backend::{Backend, QueryHandle};
use crate::cost_model::CostModel;
use crate::geometry::Aabb;
use crate::hierarchy::{Hierarchy, NodeId, Since};
use crate::rng::mix64;
use multiquery::{KeepCounts, KeepEstimate};
use std::collections::VecDeque;

/// The CHC++ parameters; the switches exist for ablation studies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChcppParams {
    /// `b`: previously invisible nodes per query batch (section 4.1).
    pub batch: u32,
    /// `nav`: frames a visible leaf goes untested between queries (section 5.2).
    pub nav: u32,
    /// `dmax`: deepest level of descendants used as tight bounds (section 6).
    pub dmax: u32,
    /// `smax`: most surface-area growth allowed when refining tight bounds.
    pub smax: f32,
    /// `vleaf`: interior nodes with fewer triangles become virtual leaves (0: off).
    pub virtual_leaf_triangles: u64,
    /// `multiquery`: group i-queue nodes into multiqueries (section 5.1).
    pub multiquery: bool,
    /// `pkeep`: the multiqueries' estimate of a node keeping its
    /// classification, `fit` (Eq. 2) or `measured` (Eq. 1).
    pub pkeep: KeepEstimate,
    /// `vqueue`: delay visible-leaf queries to fill wait time (section 4.2).
    pub vqueue: bool,
    /// `sort`: render through a material-sorted render queue (section 4.3).
    pub sort: bool,
    /// `random`: randomize the first re-query of a newly visible leaf (section 5.2).
    pub random: bool,
    /// `tight`: query tight bounding volumes (section 6).
    pub tight: bool,
}

/// The paper's values (section 8) with every component on.
impl Default for ChcppParams {
    fn default() -> Self {
        Self {
            batch: 50,
            nav: 10,
            dmax: 3,
            smax: 1.4,
            virtual_leaf_triangles: 0,
            multiquery: true,
            pkeep: KeepEstimate::Fit,
            vqueue: true,
            sort: true,
            random: true,
            tight: true,
        }
    }
}

impl MethodParams for ChcppParams {
    const METHOD: &'static str = "chcpp";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        v.value("b", &mut self.batch, "an integer from 1 to 100000", |b| (1..=100_000).contains(b))?;
        v.value("nav", &mut self.nav, "an integer from 0 to 1000", |&n| n <= 1000)?;
        v.value("dmax", &mut self.dmax, "an integer from 0 to 16", |&d| d <= 16)?;
        v.value("smax", &mut self.smax, "a number from 1 to 100", |s| (1.0..=100.0).contains(s))?;
        v.value("vleaf", &mut self.virtual_leaf_triangles, "an integer >= 0 (triangles)", |_| true)?;
        v.flag("multiquery", &mut self.multiquery)?;
        v.value("pkeep", &mut self.pkeep, "fit or measured", |_| true)?;
        v.flag("vqueue", &mut self.vqueue)?;
        v.flag("sort", &mut self.sort)?;
        v.flag("random", &mut self.random)?;
        v.flag("tight", &mut self.tight)
    }
}

/// What CHC++ remembers about a node between frames.
#[derive(Clone, Copy, Debug, Default)]
struct NodeState {
    visible: bool,
    last_visited: u32,
    /// Frame the visibility classification last changed (persistence).
    changed_at: u32,
    /// First frame in which a visible leaf is queried again.
    next_test: u32,
}

impl Classified for NodeState {
    fn visible_mut(&mut self) -> &mut bool {
        &mut self.visible
    }
}

/// An issued query and what it was for.
enum Pending {
    /// One node; `was_visible` tells a v-queue query from an i-queue one.
    Node { node: NodeId, query: QueryHandle, was_visible: bool },
    /// Several previously invisible nodes in one multiquery.
    Multi { nodes: Vec<NodeId>, query: QueryHandle },
}

impl Pending {
    fn query(&self) -> QueryHandle {
        match self {
            Pending::Node { query, .. } | Pending::Multi { query, .. } => *query,
        }
    }
}

/// The queues of one frame (the paper's Figure 3).
#[derive(Default)]
struct Queues {
    distance: FrontToBack,
    queries: VecDeque<Pending>,
    invisible: Vec<NodeId>,
    visible: VecDeque<NodeId>,
    render: Vec<NodeId>,
}

/// `chcpp`: CHC++.
#[derive(Clone, Debug)]
pub struct Chcpp {
    params: ChcppParams,
    frame: u32,
    /// The hierarchy the node states and boxes are for.
    tracked: Tracked,
    nodes: Vec<NodeState>,
    is_leaf: Vec<bool>,
    boxes: Vec<Option<Vec<Aabb>>>,
    /// Eq. 1's counts over the walkthrough, kept with `pkeep=measured`.
    keep: KeepCounts,
}

/// A deterministic pseudo-random integer in `1..=n` for (node, frame).
fn jitter(node: NodeId, frame: u32, n: u32) -> u32 {
    let z = mix64(u64::from(node) << 32 | u64::from(frame));
    1 + (z % u64::from(n.max(1))) as u32
}

/// The first frame after `frame` in which `node`, found visible then, is
/// queried again: after `nav` frames, or a random delay of up to `nav`
/// (section 5.2).
fn first_retest(params: ChcppParams, node: NodeId, frame: u32) -> u32 {
    frame + if params.random { jitter(node, frame, params.nav) } else { params.nav + 1 }
}

/// Calls `f` with every instance of the leaves in `node`'s subtree.
fn for_each_instance_under(h: &Hierarchy, node: NodeId, f: &mut impl FnMut(u32)) {
    if h.is_leaf(node) {
        h.instances(node).iter().for_each(|&i| f(i));
    } else {
        h.children(node).iter().for_each(|&c| for_each_instance_under(h, c, f));
    }
}

impl Chcpp {
    /// CHC++ with the given parameters.
    pub fn new(params: ChcppParams) -> Self {
        Self {
            params,
            frame: 0,
            tracked: Tracked::default(),
            nodes: Vec::new(),
            is_leaf: Vec::new(),
            boxes: Vec::new(),
            keep: KeepCounts::default(),
        }
    }

    /// Makes the per-node state for a new tree; after a refit, forgets the
    /// query boxes of the nodes whose box changed and of their ancestors
    /// (a tight box is made of descendants' boxes), keeping the rest.
    fn prepare_state(&mut self, ctx: &FrameContext<'_>) {
        let h = ctx.hierarchy;
        match self.tracked.since(h) {
            Since::Unchanged => {}
            Since::Refit(Some(changes)) => {
                for &changed in &changes.nodes {
                    let mut n = Some(changed);
                    while let Some(node) = n {
                        self.boxes[node as usize] = None;
                        n = h.parent(node);
                    }
                }
            }
            Since::Refit(None) => self.boxes.fill(None),
            Since::New => {
                self.nodes = vec![NodeState::default(); h.node_count()];
                let tris = subtree_triangles(ctx.scene, h);
                self.is_leaf = tight::virtual_leaves(h, &tris, self.params.virtual_leaf_triangles);
                self.boxes = vec![None; h.node_count()];
            }
        }
    }

    /// The boxes a query of `node` rasterizes (tight bounds when on).
    fn boxes(&mut self, ctx: &FrameContext<'_>, node: NodeId) -> &[Aabb] {
        let (h, p) = (ctx.hierarchy, self.params);
        self.boxes[node as usize].get_or_insert_with(|| {
            if p.tight {
                tight::tight_boxes(h, node, p.dmax, p.smax)
            } else {
                vec![*h.bounds(node)]
            }
        })
    }

    /// Draws everything in the render queue (sorted by material when on).
    fn flush_render_queue(&self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend, q: &mut Queues) {
        if !q.render.is_empty() {
            ctx.draw_leaves(backend, &q.render, self.params.sort);
            q.render.clear();
        }
    }

    /// Figure 6, `TraverseNode`: a (virtual) leaf goes to rendering, an
    /// interior node's children to the distance queue.
    fn traverse_node(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend, q: &mut Queues, node: NodeId) {
        if self.is_leaf[node as usize] {
            let first = q.render.len();
            ctx.leaves_in_view(node, &mut q.render);
            if !self.params.sort {
                ctx.draw_leaves(backend, &q.render[first..], false);
                q.render.truncate(first);
            }
        } else {
            for &c in ctx.hierarchy.children(node) {
                q.distance.push_node(ctx.hierarchy, c, ctx.camera.position);
            }
        }
    }

    /// Issues one query for `node` after rendering what is queued.
    fn issue_single(
        &mut self,
        ctx: &mut FrameContext<'_>,
        backend: &mut dyn Backend,
        q: &mut Queues,
        node: NodeId,
        was_visible: bool,
    ) {
        self.flush_render_queue(ctx, backend, q);
        let query = backend.issue_query(self.boxes(ctx, node));
        q.queries.push_back(Pending::Node { node, query, was_visible });
    }

    /// Figure 6, `IssueMultiQueries`: the i-queue as one batch, grouped into
    /// multiqueries by the cost/benefit model when on.
    fn issue_batch(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend, q: &mut Queues) {
        if q.invisible.is_empty() {
            return;
        }
        self.flush_render_queue(ctx, backend, q);
        let mut nodes = std::mem::take(&mut q.invisible);
        let frame = self.frame;
        let persistence = |n: NodeId| frame - self.nodes[n as usize].changed_at;
        let sizes = if self.params.multiquery {
            let keep = |n: NodeId| match self.params.pkeep {
                KeepEstimate::Fit => multiquery::p_keep(persistence(n)),
                KeepEstimate::Measured => self.keep.p_keep(persistence(n)),
            };
            // Likeliest to stay invisible first (section 5.1); the fit
            // grows with persistence, so for it this is persistence order.
            let mut keyed: Vec<(f64, u32, NodeId)> = nodes.iter().map(|&n| (keep(n), persistence(n), n)).collect();
            keyed.sort_by(|a, b| b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)).then(a.2.cmp(&b.2)));
            nodes = keyed.iter().map(|&(_, _, n)| n).collect();
            multiquery::group_sizes(&keyed.iter().map(|&(p, _, _)| p).collect::<Vec<_>>())
        } else {
            vec![1; nodes.len()]
        };
        let mut rest = &nodes[..];
        for size in sizes {
            let (group, tail) = rest.split_at(size);
            rest = tail;
            if let [node] = group {
                let query = backend.issue_query(self.boxes(ctx, *node));
                q.queries.push_back(Pending::Node { node: *node, query, was_visible: false });
            } else {
                let boxes: Vec<Aabb> = group.iter().flat_map(|&n| self.boxes(ctx, n).to_vec()).collect();
                let query = backend.issue_query(&boxes);
                q.queries.push_back(Pending::Multi { nodes: group.to_vec(), query });
            }
        }
    }

    /// Eq. 1's counts of a returned query: a single node kept its
    /// classification if the result says what it was; a multiquery that
    /// found nothing kept every node's (one that found something is
    /// counted through its nodes' own queries).
    fn count_kept(&mut self, done: &Pending, visible: bool) {
        let persistence = |n: NodeId| self.frame - self.nodes[n as usize].changed_at;
        match done {
            Pending::Node { node, was_visible, .. } => self.keep.record(persistence(*node), visible == *was_visible),
            Pending::Multi { nodes, .. } if !visible => {
                for &n in nodes {
                    self.keep.record(persistence(n), true);
                }
            }
            Pending::Multi { .. } => {}
        }
    }

    /// Figure 6, `HandleReturnedQuery`.
    fn handle(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend, q: &mut Queues, done: Pending) {
        let visible = backend.result(done.query()) > 0;
        let frame = self.frame;
        if self.params.pkeep == KeepEstimate::Measured {
            self.count_kept(&done, visible);
        }
        match done {
            Pending::Multi { nodes, .. } => {
                if visible {
                    // The group broke coherence: test each node on its own.
                    for n in nodes {
                        self.issue_single(ctx, backend, q, n, false);
                    }
                }
            }
            Pending::Node { node, was_visible, .. } => {
                let nav = self.params.nav;
                let state = &mut self.nodes[node as usize];
                if visible {
                    if was_visible {
                        state.next_test = frame + nav + 1;
                    } else {
                        state.changed_at = frame;
                        state.next_test = first_retest(self.params, node, frame);
                        self.traverse_node(ctx, backend, q, node);
                    }
                    pull_up_visibility(ctx.hierarchy, &mut self.nodes, node);
                } else {
                    if was_visible {
                        state.changed_at = frame;
                    }
                    state.visible = false;
                }
            }
        }
    }
}

impl CullingMethod for Chcpp {
    fn name(&self) -> &'static str {
        "chcpp"
    }

    /// From nothing, every node counts as invisible: the root, if in view,
    /// is queried and its result awaited before anything else.
    fn floor_ms(&self, ctx: &FrameContext<'_>, model: &CostModel, _: (u32, u32), cold: bool) -> f64 {
        if cold && ctx.in_frustum(ctx.hierarchy.root()) {
            model.query_round_trip_ms()
        } else {
            0.0
        }
    }

    fn carried_visibility(&self) -> Carried {
        Carried::Leaves
    }

    /// The instances of the (virtual) leaves classified visible in its
    /// last frame.
    fn visible_set(&self, ctx: &FrameContext<'_>) -> Option<VisibleSet> {
        let h = ctx.hierarchy;
        // A tree rebuilt since (other node ids) leaves nothing to give.
        if self.frame == 0 || self.nodes.len() != h.node_count() {
            return None;
        }
        let mut visible = vec![false; ctx.scene.instances.len()];
        for (node, state) in (0..).zip(&self.nodes) {
            if self.is_leaf[node as usize] && state.visible && state.last_visited == self.frame {
                for_each_instance_under(h, node, &mut |i| visible[i as usize] = true);
            }
        }
        Some(VisibleSet::Host(visible))
    }

    /// Classifies every node visible where its subtree holds an instance of
    /// `visible`, as seen in the frame before the next (persistence
    /// restarts; a visible leaf's first re-query is drawn as for a newly
    /// visible one). One visit of each node, charged as traversal; a set
    /// on the device is read back first.
    fn seed(&mut self, ctx: &FrameContext<'_>, backend: &mut dyn Backend, visible: &VisibleSet) {
        let Some(visible) = visible.to_host(backend) else { return };
        self.prepare_state(ctx);
        let (h, frame) = (ctx.hierarchy, self.frame);
        backend.traverse(h.node_count() as u64);
        // Children have higher ids than their parent: one backward sweep.
        for node in (0..h.node_count() as NodeId).rev() {
            let seen = if h.is_leaf(node) {
                h.instances(node).iter().any(|&i| visible.get(i as usize).copied().unwrap_or(false))
            } else {
                h.children(node).iter().any(|&c| self.nodes[c as usize].visible)
            };
            let next_test = if seen { first_retest(self.params, node, frame) } else { 0 };
            self.nodes[node as usize] = NodeState { visible: seen, last_visited: frame, changed_at: frame, next_test };
        }
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        self.prepare_state(ctx);
        self.frame += 1;
        let frame = self.frame;
        let mut q = Queues::default();
        q.distance.push_node(ctx.hierarchy, ctx.hierarchy.root(), ctx.camera.position);

        while !q.distance.is_empty() || !q.queries.is_empty() {
            while let Some(front) = q.queries.front() {
                if backend.is_available(front.query()) {
                    let done = q.queries.pop_front().expect("front exists");
                    self.handle(ctx, backend, &mut q, done);
                } else if !q.distance.is_empty() {
                    break;
                } else if let Some(n) = q.visible.pop_front() {
                    // Fill the wait with a previously visible leaf's query.
                    self.issue_single(ctx, backend, &mut q, n, true);
                } else {
                    let done = q.queries.pop_front().expect("front exists");
                    self.handle(ctx, backend, &mut q, done);
                }
            }
            if let Some(node) = q.distance.pop() {
                backend.traverse(1);
                if ctx.in_frustum(node) {
                    let state = &mut self.nodes[node as usize];
                    let seen_last_frame = state.last_visited + 1 == frame;
                    let was_visible = state.visible && seen_last_frame;
                    let test_due = frame >= state.next_test;
                    if !seen_last_frame {
                        // A stale classification says nothing: persistence restarts.
                        state.changed_at = frame;
                    }
                    state.last_visited = frame;
                    state.visible = false;
                    if !was_visible {
                        q.invisible.push(node);
                        if q.invisible.len() >= self.params.batch as usize {
                            self.issue_batch(ctx, backend, &mut q);
                        }
                    } else {
                        if self.is_leaf[node as usize] {
                            if !test_due {
                                pull_up_visibility(ctx.hierarchy, &mut self.nodes, node);
                            } else if self.params.vqueue {
                                q.visible.push_back(node);
                            } else {
                                self.issue_single(ctx, backend, &mut q, node, true);
                            }
                        }
                        self.traverse_node(ctx, backend, &mut q, node);
                    }
                }
            }
            if q.distance.is_empty() {
                self.issue_batch(ctx, backend, &mut q);
            }
        }
        // The remaining previously-visible queries go out as one batch after
        // the last rendering; their results classify the nodes for the next frame.
        self.flush_render_queue(ctx, backend, &mut q);
        while let Some(n) = q.visible.pop_front() {
            self.issue_single(ctx, backend, &mut q, n, true);
        }
        while let Some(done) = q.queries.pop_front() {
            self.handle(ctx, backend, &mut q, done);
        }
        self.flush_render_queue(ctx, backend, &mut q);
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, drawn, method, queried_alone, queries, Rig};
    use super::*;
    use crate::mock::Call;
    use crate::DrawnSet;
    use glam::Vec3;

    /// Without the random delay, a visible leaf goes `nav` frames without a
    /// query between two queries.
    #[test]
    fn a_visible_leaf_is_requeried_every_nav_plus_one_frames() {
        let rig = Rig::row(4);
        let leaf = *rig.hierarchy.bounds(rig.leaf_of(0));
        let mut mock = rig.mock();
        let mut chcpp = method("chcpp", &["chcpp.nav=3", "chcpp.random=off", "chcpp.tight=off"]);
        let frames = rig.run(&mut chcpp, &mut mock, 10);
        let queried: Vec<usize> =
            frames.iter().enumerate().skip(1).filter(|(_, c)| queried_alone(c, &leaf)).map(|(f, _)| f + 1).collect();
        assert_eq!(queried, [5, 9]);
        for calls in &frames {
            assert_draws_exactly(calls, &[0, 1, 2, 3]);
        }
    }

    /// Nodes that stay hidden frame after frame are grouped into
    /// multiqueries (several boxes, one query) that come back empty, and
    /// never drawn.
    #[test]
    fn persistently_hidden_nodes_share_multiqueries() {
        let rig = Rig::row(8);
        let mut mock = rig.mock();
        for hidden in [1, 3, 5, 7] {
            mock.set_visible(hidden, false);
        }
        let frames = rig.run(&mut method("chcpp", &["chcpp.tight=off"]), &mut mock, 6);
        let mut grouped_and_empty = 0;
        for calls in &frames {
            assert_draws_exactly(calls, &[0, 2, 4, 6]);
            for call in calls {
                if let Call::IssueQuery { query, boxes } = call {
                    let empty =
                        calls.iter().any(|c| matches!(c, Call::Result { query: q, value: 0, .. } if q == query));
                    grouped_and_empty += usize::from(boxes.len() > 1 && empty);
                }
            }
        }
        assert!(grouped_and_empty > 0, "no multiquery of hidden nodes");
    }

    /// A grid of 64 cubes, every other one hidden, seen for 12 frames: the
    /// fit's p_keep (0.99 at most) caps a multiquery near 10 nodes; Eq. 1's
    /// measured estimate learns that every hidden node stayed hidden
    /// (p_keep 1) and puts each batch of them into one query.
    #[test]
    fn measured_keep_estimates_learn_that_hidden_nodes_stay_hidden() {
        let boxes: Vec<Aabb> = (0..64)
            .map(|k| {
                let at = Vec3::new((k % 8) as f32 - 3.5, (k / 8) as f32 - 3.5, 0.0);
                Aabb::new(at - 0.3, at + 0.3)
            })
            .collect();
        let rig = Rig::new(&boxes, 1);
        // The last frame's multiqueries: how many, and the most boxes in one.
        let multiqueries = |options: &[&str]| {
            let mut mock = rig.mock();
            for hidden in (1..64).step_by(2) {
                mock.set_visible(hidden, false);
            }
            let frames = rig.run(&mut method("chcpp", options), &mut mock, 12);
            let sizes: Vec<usize> = frames[11]
                .iter()
                .filter_map(|c| if let Call::IssueQuery { boxes, .. } = c { Some(boxes.len()) } else { None })
                .filter(|&n| n > 1)
                .collect();
            (sizes.len(), sizes.iter().copied().max().unwrap_or(0))
        };
        let (fit_count, fit_largest) = multiqueries(&["chcpp.tight=off"]);
        let (measured_count, measured_largest) = multiqueries(&["chcpp.tight=off", "chcpp.pkeep=measured"]);
        assert!((2..=12).contains(&fit_largest), "{fit_largest}");
        assert!(measured_largest > fit_largest, "measured {measured_largest}, fit {fit_largest}");
        assert!(measured_count < fit_count, "measured {measured_count}, fit {fit_count}");
    }

    /// Seeded with what is visible, CHC++'s first frame runs as a warm
    /// one: it draws the visible instances and queries fewer nodes than
    /// from nothing, where every node on the way to a leaf is queried. It
    /// gives the set back. A wrong seed costs time, never an instance: the
    /// seeded frame still draws every visible one.
    #[test]
    fn a_seeded_first_frame_starts_from_the_seed() {
        let rig = Rig::row(8);
        let mut mock = rig.mock();
        for hidden in [1, 3, 5, 7] {
            mock.set_visible(hidden, false);
        }
        let options = ["chcpp.tight=off"];
        let cold = rig.run(&mut method("chcpp", &options), &mut mock, 1).remove(0);
        let truth: Vec<bool> = (0..9).map(|i| i < 8 && i % 2 == 0).collect();
        for (seed, exact) in [(truth.clone(), true), (truth.iter().map(|v| !v).collect(), false)] {
            let mut chcpp = method("chcpp", &options);
            let mut drawn_set = DrawnSet::default();
            let ctx = FrameContext::new(&rig.scene, &rig.hierarchy, rig.camera, &mut drawn_set);
            chcpp.method.seed(&ctx, &mut mock, &VisibleSet::Host(seed));
            let first = rig.run(&mut chcpp, &mut mock, 1).remove(0);
            if exact {
                assert_draws_exactly(&first, &[0, 2, 4, 6]);
                assert!(queries(&first).len() < queries(&cold).len(), "{} queries", queries(&first).len());
                assert_eq!(chcpp.method.visible_set(&ctx), Some(VisibleSet::Host(truth.clone())));
            } else {
                let got = drawn(&first);
                assert!([0, 2, 4, 6].iter().all(|i| got.contains(i)), "drew {got:?}");
            }
        }
    }
}
