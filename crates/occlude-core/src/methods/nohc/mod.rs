//! NOHC and NOHC-OPT: near optimal hierarchical culling (Guthe, Balázs,
//! Klein, EGSR 2006), as the CHC++ paper describes and compares it (section
//! 3.2, and section 8 with Figures 1, 7 and 10).
//!
//! **`nohc`.** The hierarchy is traversed front to back. At each node in
//! the frustum a cost model decides whether an occlusion query pays: the
//! node is occluded with probability `p` (screen coverage corrected by
//! temporal coherence, [`estimate`]), rendering its subtree costs `R` (its
//! draw calls, triangles and the pixels of its box) and the query costs `Q`
//! (one box of those pixels), both from the backend's model
//! ([`Backend::cost_model`]: the soft backend's `GpuModel`; a backend that
//! measures its time has none and [`CostModel::default`] is used). The
//! query is issued when `p R > Q`; the node then waits in a query queue,
//! while the traversal goes on, and is opened (a leaf drawn, an interior
//! node's children queued) only if the query finds it visible, as in CHC's
//! query queue. A node whose query does not pay is opened at once: a leaf
//! is drawn, an interior node's children decide for themselves. Nothing is
//! culled without a query, so the image is view-frustum culling's.
//!
//! **`nohc-opt`.** "The function defined as optimum by Guthe et al., which
//! issues queries for all invisible nodes but only if they are feasible
//! according to their cost model" (CHC++ paper, section 8): the same
//! traversal and costs, with `p` known rather than estimated. An oracle
//! pass before the frame's clock starts (as `opt`'s) tells which instances
//! have a visible pixel; a node holding one has `p = 0` (never queried,
//! opened), any other `p = 1` (queried when `R > Q`).
//!
//! **Our choices**, where the CHC++ paper does not give Guthe's details: the
//! coverage model and its temporal correction ([`estimate`]); `R` and `Q` as
//! CPU plus GPU time of the model's own terms (no calibration run of ours
//! beyond the model the backend has); `R` is the whole subtree's, although
//! the traversal may cull part of it later; the footprint of a box is the
//! pixel rectangle its corners span (`depth_pyramid::box_footprint`), the
//! whole image for a box reaching the near plane; Guthe's further
//! "reasonability" rules are not reproduced. `nohc-opt` takes a node to be
//! visible when it holds an instance with a visible pixel (for a kD-tree
//! leaf sharing a large instance, that can be a node whose own part is
//! hidden: its query then finds it occluded or visible, and either is
//! sound).

pub mod estimate;

use super::opt::{leaves_in_view, oracle_visible};
use super::tracked::Tracked;
use super::{subtree_triangles, CullingMethod, FrameContext, FrontToBack};
use crate::backend::{Backend, QueryHandle};
use crate::cost_model::CostModel;
use crate::depth_pyramid::{box_footprint, Footprint};
use crate::hierarchy::{Hierarchy, NodeId, Since};
use estimate::{occlusion_probability, query_pays, History};
use glam::Mat4;
use std::collections::VecDeque;

/// Where the probability of occlusion comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimate {
    /// Screen coverage and temporal coherence (`nohc`).
    Model,
    /// The oracle's visible set (`nohc-opt`).
    Oracle,
}

/// What NOHC remembers about a node between frames.
#[derive(Clone, Copy, Debug, Default)]
struct NodeState {
    last_visited: u32,
    /// Whether `occluded` holds a query's answer given since the node was
    /// last left out of the traversal.
    known: bool,
    occluded: bool,
    /// Frame the classification last changed (or was first known).
    changed_at: u32,
}

/// `nohc` and `nohc-opt` (module documentation).
#[derive(Clone, Debug)]
pub struct Nohc {
    estimate: Estimate,
    frame: u32,
    /// The hierarchy the node states are for.
    tracked: Tracked,
    nodes: Vec<NodeState>,
    triangles: Vec<u64>,
    /// Instance references under each node: the subtree's draw calls.
    draws: Vec<u64>,
    /// `nohc-opt`: per node, whether it holds an instance the oracle saw
    /// this frame (empty without an oracle: every node visible).
    truth: Vec<bool>,
    /// Nodes in the frustum opened without a query in the last frame.
    unqueried: u64,
}

/// The frame's view as the cost model needs it.
struct View {
    view_projection: Mat4,
    width: u32,
    height: u32,
    cost: CostModel,
    /// Pixels of the boxes of the leaves drawn so far.
    covered_px: f64,
}

impl View {
    /// Pixels of the rectangle `b`'s corners span (the whole image for a
    /// box reaching the near plane).
    fn pixels(&self, b: &crate::geometry::Aabb) -> f64 {
        match box_footprint(&self.view_projection, self.width, self.height, b) {
            Footprint::Near => f64::from(self.width) * f64::from(self.height),
            Footprint::Empty => 0.0,
            Footprint::Rect(r) => f64::from(r.x1 - r.x0 + 1) * f64::from(r.y1 - r.y0 + 1),
        }
    }

    /// Screens' worth of pixels covered by the boxes drawn so far.
    fn coverage(&self) -> f64 {
        self.covered_px / (f64::from(self.width) * f64::from(self.height)).max(1.0)
    }
}

impl Nohc {
    /// NOHC with its occlusion probability from `estimate`.
    pub fn new(estimate: Estimate) -> Self {
        Self {
            estimate,
            frame: 0,
            tracked: Tracked::default(),
            nodes: Vec::new(),
            triangles: Vec::new(),
            draws: Vec::new(),
            truth: Vec::new(),
            unqueried: 0,
        }
    }

    fn prepare_state(&mut self, ctx: &FrameContext<'_>) {
        let h = ctx.hierarchy;
        if self.tracked.since(h) == Since::New {
            self.nodes = vec![NodeState::default(); h.node_count()];
            self.triangles = subtree_triangles(ctx.scene, h);
            self.draws = vec![0; h.node_count()];
            for n in (0..h.node_count() as NodeId).rev() {
                self.draws[n as usize] = if h.is_leaf(n) {
                    h.instances(n).len() as u64
                } else {
                    h.children(n).iter().map(|&c| self.draws[c as usize]).sum()
                };
            }
        }
    }

    /// Marks `node` visited this frame and returns what its queries tell.
    fn visit(&mut self, node: NodeId) -> History {
        let frame = self.frame;
        let s = &mut self.nodes[node as usize];
        if s.last_visited + 1 != frame {
            s.known = false;
        }
        s.last_visited = frame;
        let frames = frame - s.changed_at;
        match (s.known, s.occluded) {
            (false, _) => History::Unknown,
            (true, true) => History::Occluded { frames },
            (true, false) => History::Visible { frames },
        }
    }

    /// Records a query's answer for `node`.
    fn record(&mut self, node: NodeId, occluded: bool) {
        let frame = self.frame;
        let s = &mut self.nodes[node as usize];
        if !s.known || s.occluded != occluded {
            s.changed_at = frame;
        }
        s.known = true;
        s.occluded = occluded;
    }

    /// The probability that `node` is occluded now.
    fn occluded(&mut self, node: NodeId, view: &View) -> f64 {
        let history = self.visit(node);
        match self.estimate {
            Estimate::Model => occlusion_probability(view.coverage(), history),
            Estimate::Oracle => f64::from(u8::from(self.truth.get(node as usize).is_some_and(|&seen| !seen))),
        }
    }

    /// Draws a leaf (its box's pixels counted as covered) or queues an
    /// interior node's children.
    fn open(
        &self,
        ctx: &mut FrameContext<'_>,
        backend: &mut dyn Backend,
        traversal: &mut FrontToBack,
        view: &mut View,
        node: NodeId,
    ) {
        let h = ctx.hierarchy;
        if h.is_leaf(node) {
            if ctx.draw_leaf(backend, node) > 0 {
                view.covered_px += view.pixels(h.bounds(node));
            }
        } else {
            for &c in h.children(node) {
                traversal.push_node(h, c, ctx.camera.position);
            }
        }
    }
}

impl CullingMethod for Nohc {
    fn name(&self) -> &'static str {
        match self.estimate {
            Estimate::Model => "nohc",
            Estimate::Oracle => "nohc-opt",
        }
    }

    fn needs_oracle(&self) -> bool {
        self.estimate == Estimate::Oracle
    }

    /// `nohc-opt`: the oracle pass, and which nodes hold a visible instance.
    fn prepare(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        if self.estimate != Estimate::Oracle {
            return;
        }
        self.truth.clear();
        let in_view = leaves_in_view(ctx);
        let Some((_, visible)) = oracle_visible(ctx, backend, &in_view) else {
            // Without an oracle (refused up front by `check_support`), every
            // node counts as visible: view-frustum culling, never a query.
            return;
        };
        self.truth = holds_visible(ctx.hierarchy, &visible);
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        self.prepare_state(ctx);
        self.frame += 1;
        self.unqueried = 0;
        let h = ctx.hierarchy;
        let (width, height) = backend.resolution();
        let cost = backend.cost_model().unwrap_or_default();
        let mut view = View { view_projection: ctx.camera.view_projection(), width, height, cost, covered_px: 0.0 };
        let mut traversal = FrontToBack::new();
        let mut queries: VecDeque<(NodeId, QueryHandle)> = VecDeque::new();
        traversal.push_node(h, h.root(), ctx.camera.position);

        while !traversal.is_empty() || !queries.is_empty() {
            // Finished queries first; wait only with nothing left to traverse.
            while let Some(&(node, query)) = queries.front() {
                if !traversal.is_empty() && !backend.is_available(query) {
                    break;
                }
                queries.pop_front();
                let visible = backend.result(query) > 0;
                self.record(node, !visible);
                if visible {
                    self.open(ctx, backend, &mut traversal, &mut view, node);
                }
            }
            let Some(node) = traversal.pop() else { continue };
            backend.traverse(1);
            if !ctx.in_frustum(node) {
                continue;
            }
            let b = h.bounds(node);
            let pixels = view.pixels(b);
            let render_us = view.cost.render_us(self.draws[node as usize], self.triangles[node as usize], pixels);
            let query_us = view.cost.query_us(1, pixels);
            if query_pays(self.occluded(node, &view), render_us, query_us) {
                queries.push_back((node, backend.issue_query(std::slice::from_ref(b))));
            } else {
                self.unqueried += 1;
                self.open(ctx, backend, &mut traversal, &mut view, node);
            }
        }
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        vec![("unqueried_nodes", self.unqueried as f64)]
    }
}

/// Per node, whether it holds one of the instances `visible` marks.
fn holds_visible(h: &Hierarchy, visible: &[bool]) -> Vec<bool> {
    let mut holds = vec![false; h.node_count()];
    for n in (0..h.node_count() as NodeId).rev() {
        holds[n as usize] = if h.is_leaf(n) {
            h.instances(n).iter().any(|&i| visible[i as usize])
        } else {
            h.children(n).iter().any(|&c| holds[c as usize])
        };
    }
    holds
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, drawn, method, queries, Rig, BEHIND, SIDE, WALL};
    use super::super::{check_support, Unsupported};
    use super::*;
    use crate::geometry::Aabb;
    use crate::mock::MockBackend;
    use glam::Vec3;

    /// A wall filling the whole view (instance 0) and a cube hidden behind
    /// it (instance 1).
    fn screen_wall() -> Rig {
        let wall = Aabb::new(Vec3::new(-20.0, -20.0, 1.5), Vec3::new(20.0, 20.0, 2.5));
        let behind = Aabb::new(Vec3::new(-0.5, -0.5, -3.5), Vec3::new(0.5, 0.5, -2.5));
        Rig::new(&[wall, behind], 1)
    }

    /// Behind a wall covering the screen, the hidden cube's query pays (p =
    /// 1 - 1/e by coverage in the first frame, p_keep after): it is queried
    /// and culled in every frame; the wall, drawn first with nothing in
    /// front of it, is never queried.
    #[test]
    fn a_node_behind_a_covering_wall_is_queried_and_culled() {
        let rig = screen_wall();
        let mut mock = rig.mock();
        mock.set_visible(1, false);
        let hidden = *rig.hierarchy.bounds(rig.leaf_of(1));
        for calls in rig.run(&mut method("nohc", &[]), &mut mock, 3) {
            assert_draws_exactly(&calls, &[0]);
            assert_eq!(queries(&calls), [&[hidden][..]]);
        }
    }

    /// With nothing in front of anything, no query pays: everything in view
    /// drawn, no query, every node in view opened unqueried.
    #[test]
    fn with_little_coverage_no_query_pays() {
        let rig = Rig::row(4);
        let mut mock = rig.mock();
        let mut nohc = method("nohc", &[]);
        for calls in rig.run(&mut nohc, &mut mock, 2) {
            assert_draws_exactly(&calls, &rig.in_view());
            assert!(queries(&calls).is_empty());
        }
        let unqueried = nohc.method.counters()[0];
        assert_eq!(unqueried.0, "unqueried_nodes");
        assert!(unqueried.1 >= 4.0, "{unqueried:?}");
    }

    /// The costs are the backend's: where a query costs more than drawing
    /// the hidden cube could save, it is drawn unqueried.
    #[test]
    fn the_backends_cost_model_decides() {
        let rig = screen_wall();
        let dear = CostModel { cpu_query_us: 100.0, ..CostModel::default() };
        let mut mock: MockBackend = rig.mock().with_cost_model(dear);
        mock.set_visible(1, false);
        for calls in rig.run(&mut method("nohc", &[]), &mut mock, 2) {
            assert!(queries(&calls).is_empty());
            assert_eq!(drawn(&calls).len(), 2, "both cubes drawn");
        }
    }

    /// `nohc-opt` queries exactly the nodes holding nothing visible (where
    /// the query is cheaper than the drawing), never a visible one.
    #[test]
    fn nohc_opt_queries_only_the_invisible_nodes() {
        let rig = Rig::wall();
        let mut mock = rig.mock();
        mock.set_visible(BEHIND, false);
        let mut nohc_opt = Nohc::new(Estimate::Oracle);
        let mut visible = vec![true; 3];
        visible[BEHIND as usize] = false;
        let mut drawn_set = crate::methods::DrawnSet::default();
        for _ in 0..2 {
            let mut ctx = FrameContext::new(&rig.scene, &rig.hierarchy, rig.camera, &mut drawn_set);
            nohc_opt.truth = holds_visible(&rig.hierarchy, &visible);
            mock.begin_frame(&rig.camera);
            nohc_opt.render(&mut ctx, &mut mock);
            mock.end_frame();
            let calls = mock.take_log();
            assert_draws_exactly(&calls, &[WALL, SIDE]);
            assert_eq!(queries(&calls), [&[*rig.hierarchy.bounds(rig.leaf_of(BEHIND))][..]]);
        }
    }

    /// `nohc-opt` needs the oracle: refused without one, and run anyway it
    /// counts every node visible: view-frustum culling, no query.
    #[test]
    fn nohc_opt_is_refused_without_an_oracle_and_falls_back_to_frustum_culling() {
        let rig = Rig::wall();
        let mut mock = rig.mock();
        let mut m = method("nohc-opt", &[]);
        assert_eq!(check_support(m.method.as_ref(), &mut mock), Err(Unsupported::NoOracle));
        assert!(check_support(method("nohc", &[]).method.as_ref(), &mut mock).is_ok());
        mock.set_visible(BEHIND, false);
        for calls in rig.run(&mut m, &mut mock, 2) {
            assert_draws_exactly(&calls, &rig.in_view());
            assert!(queries(&calls).is_empty());
        }
    }
}
