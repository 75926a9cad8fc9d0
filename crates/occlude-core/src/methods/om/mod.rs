//! Occupancy maps and multiple occlusion queries (Staneker, Bartz, Straßer,
//! "Occupancy Maps and Multiple Occlusion Queries for Scene Graph Systems"),
//! the two-stage traversal of their section 4.2.
//!
//! **Stage 1** walks the hierarchy front to back. A node whose screen
//! rectangle still reaches a clear cell of the occupancy map (section 3.1)
//! has nothing drawn in front of it there, so it is taken as visible without a
//! query: a leaf is drawn and its footprint marked, an interior node opened.
//! A node whose rectangle is all covered goes to the pending list.
//!
//! **Stage 2** queries the pending nodes in rounds of multiple occlusion
//! queries (section 3.2): each round clears the map and walks the pending
//! nodes front to back, taking a node into the round's test list when its
//! rectangle reaches a cell no box in the list covers (`om.overlap=off`:
//! only when it overlaps none of them) and deferring it otherwise; all of a
//! round's queries are issued before the first result is read.
//! Visible leaves are drawn, visible interior nodes' children become pending.
//! After `n` such grouped rounds the remaining nodes are queried by brute
//! force, every pending node in one round, and `n` for the next frame is
//! `7/10` of the rounds this frame needed (`n_{frame+1} = 7/10 · m_frame`).
//!
//! # Why the occupancy map cannot make the image wrong
//!
//! A node is left undrawn only when its own query, issued against the depth
//! buffer of geometry really drawn, finds no pixel. Depth only moves nearer as
//! the frame goes on, so such a box is hidden in the final image too. The map
//! never culls: in stage 1 it chooses between "draw without asking" and "ask
//! the GPU", and in stage 2 it only chooses which queries share a round. Any
//! error in the map therefore costs time (a needless query, a needless draw,
//! a redundant query result), never a pixel. The correctness rule of
//! `docs/design.md` holds by this argument, and
//! `crates/occlude-bench/tests/om.rs` checks it on every frame of every small
//! scene.
//!
//! # Marking rule (stage 1)
//!
//! The paper marks a drawn geometry node's screen-space bounding box. The
//! geometry's true footprint is unknown without reading the depth buffer, so a
//! box footprint is the only one available, and it over-claims: cells inside
//! the rectangle but outside the geometry are marked covered. Over-claiming
//! sends later nodes there to a query (exact) instead of drawing them
//! blindly, the direction in which every decision is still made by the GPU's
//! exact answer. To over-claim as little as boxes allow, a drawn leaf marks
//! the rectangle of each of its instances' boxes, not the leaf's own box,
//! which also covers the gaps between its instances; for a leaf of one
//! instance, as in the paper's scene graphs, the two agree.
//!
//! # Deviations, stated
//!
//! - The paper does not state the map's resolution (section 3.1 promises it
//!   "below" and never gives it). The default is one 64-bit word per row, 64
//!   columns, with rows following the camera's aspect ratio (48 at 4:3).
//! - `n` on the first frame is 5, the fixed number of occupancy maps of the
//!   authors' earlier paper (SBM03), which the adaptive `n` replaces.
//!
//! # Alternatives to two of the paper's choices
//!
//! `om.overlap=off` takes a node into a round only when its rectangle
//! overlaps *no* marked cell, so no query of a round can be answered
//! "visible" merely because a box in front of it was not drawn yet.
//! `om.corner=off` sorts by the distance to a box's nearest point rather
//! than its nearest corner, which puts a box around the eye first.
//! `--paper om` compares them; the paper's choices measured faster.

pub mod occupancy;

use super::{
    CullingMethod, DebugView, FrameContext, FrontToBack, MethodParams, NdcRect, NodeClass, OptionError, ParamVisitor,
    SortKey,
};
use crate::backend::{Backend, QueryHandle};
use crate::geometry::Aabb;
use crate::hierarchy::NodeId;
use glam::Mat4;
use occupancy::{screen_bounds, CellRect, OccupancyBits};

/// Most columns (and rows) an occupancy map may have.
pub const MAX_MAP_CELLS: u32 = 1024;

/// The parameters of `om`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OmParams {
    /// `map`: columns of the occupancy map, 1 to [`MAX_MAP_CELLS`]; rows
    /// follow the camera's aspect ratio. The map covers the screen in
    /// normalized coordinates, so this is a size relative to the screen,
    /// checked here before any frame, and not tied to the frame's pixels: a
    /// map finer than the frame stays correct (rectangles are rounded outward
    /// to whole cells) but cannot skip more queries than one cell per pixel.
    pub map_columns: u32,
    /// `grouping`: stage 2 groups queries into rounds of non-overlapping
    /// boxes with the occupancy map (section 3.2); off, every stage-2 round
    /// queries all pending nodes at once ("multiple queries without
    /// occupancy-map grouping", for the paper's comparison).
    pub grouping: bool,
    /// `rounds`: grouped rounds allowed on the first frame, before any frame
    /// has measured how many rounds it needs.
    pub first_rounds: u32,
    /// `decay`: the factor of `n_{frame+1} = decay · m_frame` (section 4.2;
    /// the paper's 7/10).
    pub decay: f32,
    /// `overlap`: a grouped round admits a box that reaches any cell no box
    /// of the round covers, as the paper does (section 4.2); off, only a
    /// box overlapping none of them, so a round's boxes never overlap.
    pub overlap: bool,
    /// `corner`: queues sort nodes by their box's nearest corner to the
    /// eye, as the paper does (section 4.2); off, by the box's nearest
    /// point.
    pub corner: bool,
}

/// The paper's values.
impl Default for OmParams {
    fn default() -> Self {
        Self { map_columns: 64, grouping: true, first_rounds: 5, decay: 0.7, overlap: true, corner: true }
    }
}

impl MethodParams for OmParams {
    const METHOD: &'static str = "om";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        let columns = "an integer from 1 to 1024 (columns of cells)";
        v.value("map", &mut self.map_columns, columns, |c| (1..=MAX_MAP_CELLS).contains(c))?;
        v.flag("grouping", &mut self.grouping)?;
        v.value("rounds", &mut self.first_rounds, "an integer from 0 to 10000 (rounds)", |&r| r <= 10_000)?;
        v.value("decay", &mut self.decay, "a number from 0 to 1", |d| (0.0..=1.0).contains(d))?;
        v.flag("overlap", &mut self.overlap)?;
        v.flag("corner", &mut self.corner)
    }
}

/// `om`: hierarchical occlusion culling with an occupancy map and multiple
/// occlusion queries (see the module documentation).
#[derive(Clone, Debug)]
pub struct OccupancyMap {
    params: OmParams,
    map: OccupancyBits,
    /// Grouped rounds allowed in the coming frame (`n`).
    grouped_rounds: u32,
    /// Queries of the current round, with their nodes, in issue order.
    round: Vec<(NodeId, QueryHandle)>,
    /// Whether frames record a [`DebugView`].
    debug: bool,
    /// The view of the last frame, when it was recorded.
    view: Option<DebugView>,
    /// What the last frame's two stages did.
    last: StageCounts,
}

/// How one frame's work split between the stages.
#[derive(Clone, Copy, Debug, Default)]
struct StageCounts {
    /// Nodes drawn or opened in stage 1 without a query.
    stage1_no_query: u64,
    /// Stage-2 rounds, grouped and brute force.
    rounds: u32,
    /// Of those, rounds grouped by the occupancy map.
    grouped_rounds: u32,
}

impl OccupancyMap {
    /// The method with `params`, before its first frame.
    pub fn new(params: OmParams) -> Self {
        Self {
            params,
            map: OccupancyBits::default(),
            grouped_rounds: params.first_rounds,
            round: Vec::new(),
            debug: false,
            view: None,
            last: StageCounts::default(),
        }
    }

    /// Gives the map `map_columns` columns and as many rows as keep its cells
    /// square at `aspect` (at least 1, at most [`MAX_MAP_CELLS`]), and clears it.
    fn reset_map(&mut self, aspect: f32) {
        let width = self.params.map_columns;
        let height = (width as f32 / aspect).round().clamp(1.0, MAX_MAP_CELLS as f32) as u32;
        if (self.map.width(), self.map.height()) == (width, height) {
            self.map.clear();
        } else {
            self.map = OccupancyBits::new(width, height);
        }
    }
}

/// Adds the screen rectangle of box `b` as a node of `class` to `view`, when
/// a view is being recorded and some of the box lies in front of the eye.
fn note(view: &mut Option<DebugView>, class: NodeClass, view_projection: &Mat4, b: &Aabb) {
    if let Some(v) = view {
        if let Some((min, max)) = screen_bounds(view_projection, b) {
            v.nodes.push((class, NdcRect { min, max }));
        }
    }
}

/// The covered cells of `map`, row by row (see [`DebugView::occupancy`]).
fn covered_cells(map: &OccupancyBits) -> Vec<bool> {
    (0..map.height())
        .flat_map(|y| (0..map.width()).map(move |x| map.is_any_set(CellRect { x0: x, y0: y, x1: x + 1, y1: y + 1 })))
        .collect()
}

impl CullingMethod for OccupancyMap {
    fn name(&self) -> &'static str {
        "om"
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let h = ctx.hierarchy;
        let vp = ctx.camera.view_projection();
        self.reset_map(ctx.camera.aspect);
        let mut view = self.debug.then(DebugView::default);

        // Stage 1: draw what reaches uncovered screen space, without queries.
        let key = if self.params.corner { SortKey::NearestCorner } else { SortKey::NearestPoint };
        let mut queue = FrontToBack::by(key);
        let mut pending = FrontToBack::by(key);
        ctx.push_in_frustum(&[h.root()], &mut queue);
        let mut stage1_no_query = 0u64;
        while let Some(node) = queue.pop() {
            backend.traverse(1);
            if !self.map.is_any_clear(self.map.rect_of(&vp, h.bounds(node))) {
                pending.push_node(h, node, ctx.camera.position);
                continue;
            }
            stage1_no_query += 1;
            if h.is_leaf(node) {
                ctx.draw_leaf(backend, node);
                note(&mut view, NodeClass::DrawnWithoutQuery, &vp, h.bounds(node));
                for &i in h.instances(node).iter().filter(|&&i| ctx.scene.instances[i as usize].enabled) {
                    self.map.mark(self.map.rect_of(&vp, &ctx.scene.instances[i as usize].bounds));
                }
            } else {
                ctx.push_in_frustum(h.children(node), &mut queue);
            }
        }

        if let Some(v) = &mut view {
            (v.map_width, v.map_height, v.occupancy) = (self.map.width(), self.map.height(), covered_cells(&self.map));
        }

        // Stage 2: rounds of multiple queries, grouped by the map for the
        // first `n` rounds, then brute force.
        let allowed = if self.params.grouping { self.grouped_rounds } else { 0 };
        let mut rounds = 0u32;
        let mut next = FrontToBack::by(key);
        while !pending.is_empty() {
            let grouped = rounds < allowed;
            if grouped {
                self.map.clear();
            }
            while let Some(node) = pending.pop() {
                backend.traverse(1);
                if grouped {
                    let rect = self.map.rect_of(&vp, h.bounds(node));
                    // A rectangle of no cells (nothing on screen) is admitted
                    // by either rule: no box of the round can overlap it.
                    let admitted = if self.params.overlap {
                        rect.is_empty() || self.map.is_any_clear(rect)
                    } else {
                        !self.map.is_any_set(rect)
                    };
                    if !admitted {
                        next.push_node(h, node, ctx.camera.position);
                        continue;
                    }
                    self.map.mark(rect);
                }
                self.round.push((node, backend.issue_query(std::slice::from_ref(h.bounds(node)))));
            }
            for (node, query) in self.round.drain(..) {
                if backend.result(query) == 0 {
                    note(&mut view, NodeClass::FoundHidden, &vp, h.bounds(node));
                    continue;
                }
                if h.is_leaf(node) {
                    ctx.draw_leaf(backend, node);
                    note(&mut view, NodeClass::DrawnAfterQuery, &vp, h.bounds(node));
                } else {
                    ctx.push_in_frustum(h.children(node), &mut next);
                }
            }
            std::mem::swap(&mut pending, &mut next);
            rounds += 1;
        }
        self.last = StageCounts { stage1_no_query, rounds, grouped_rounds: rounds.min(allowed) };
        self.grouped_rounds = (self.params.decay * rounds as f32).round() as u32;
        self.view = view;
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        let c = &self.last;
        vec![
            ("stage1_no_query_nodes", c.stage1_no_query as f64),
            ("stage2_rounds", c.rounds as f64),
            ("stage2_grouped_rounds", c.grouped_rounds as f64),
        ]
    }

    fn set_debug(&mut self, on: bool) {
        self.debug = on;
    }

    fn debug_view(&self) -> Option<DebugView> {
        self.view.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, method, queries, Rig, BEHIND, SIDE, WALL};
    use super::*;
    use crate::methods::{create, MethodOptions};
    use crate::mock::Call;
    use glam::Vec3;

    fn read(opts: &[&str]) -> Result<OmParams, OptionError> {
        let opts = MethodOptions::parse(opts).unwrap();
        OmParams::from_options(&opts)
    }

    #[test]
    fn parameters_have_the_paper_defaults_and_checked_ranges() {
        let defaults =
            OmParams { map_columns: 64, grouping: true, first_rounds: 5, decay: 0.7, overlap: true, corner: true };
        assert_eq!(read(&[]), Ok(defaults));
        let p =
            read(&["om.map=128", "om.grouping=off", "om.rounds=0", "om.decay=0.5", "om.overlap=off", "om.corner=off"]);
        let p = p.unwrap();
        assert_eq!(
            p,
            OmParams { map_columns: 128, grouping: false, first_rounds: 0, decay: 0.5, overlap: false, corner: false }
        );
        for (bad, range) in [
            ("om.map=0", "om.map = 0: expected an integer from 1 to 1024"),
            ("om.map=1025", "om.map = 1025: expected an integer from 1 to 1024"),
            ("om.decay=1.5", "om.decay = 1.5: expected a number from 0 to 1"),
            ("om.grouping=maybe", "om.grouping = maybe: expected true or false"),
        ] {
            let err = read(&[bad]).unwrap_err().to_string();
            assert!(err.contains(range), "{bad}: {err}");
        }
        let built = create("om", &MethodOptions::parse(&["om.map=32"]).unwrap()).unwrap();
        assert_eq!(built.method.name(), "om");
        assert!(built.params.contains(&("map".to_string(), "32".to_string())));
        assert!(create("om", &MethodOptions::parse(&["om.size=3"]).unwrap()).is_err());
    }

    #[test]
    fn map_rows_follow_the_aspect_ratio_within_bounds() {
        let mut om = OccupancyMap::new(read(&[]).unwrap());
        om.reset_map(4.0 / 3.0);
        assert_eq!((om.map.width(), om.map.height()), (64, 48));
        om.reset_map(1000.0);
        assert_eq!(om.map.height(), 1);
        om.reset_map(0.001);
        assert_eq!(om.map.height(), MAX_MAP_CELLS);
    }

    /// Frame one, map empty: the wall in front and the cube beside it reach
    /// clear cells and are drawn without a query; the cube behind the wall
    /// is covered, so it is queried (stage 2), and not drawn when the
    /// query finds it hidden.
    #[test]
    fn draws_uncovered_nodes_without_queries_and_queries_covered_ones() {
        let rig = Rig::wall();
        let mut mock = rig.mock();
        mock.set_visible(BEHIND, false);
        let calls = &rig.run(&mut method("om", &[]), &mut mock, 1)[0];
        assert_draws_exactly(calls, &[WALL, SIDE]);
        let behind = *rig.hierarchy.bounds(rig.leaf_of(BEHIND));
        assert_eq!(queries(calls), [&[behind][..]]);
        let first_query = calls.iter().position(|c| matches!(c, Call::IssueQuery { .. })).unwrap();
        let wall_drawn = calls.iter().position(|c| matches!(c, Call::Draw(i) if i.contains(&WALL))).unwrap();
        assert!(wall_drawn < first_query, "the wall is drawn before the query behind it");
    }

    /// Two cubes behind a wall, overlapping on screen by half, the nearer
    /// one visible through a hole: their parent is queried first (one
    /// round), then `om.overlap=off` queries them in two rounds (the second
    /// overlaps the first), the paper's rule in one (the second reaches
    /// cells the first leaves clear). Both draw the same.
    #[test]
    fn the_papers_rule_admits_partly_overlapping_boxes_to_one_round() {
        let wall = Aabb::new(Vec3::new(-3.0, -3.0, 1.5), Vec3::new(3.0, 3.0, 2.5));
        let a = Aabb::new(Vec3::new(-1.0, -0.5, -3.5), Vec3::new(0.0, 0.5, -2.5));
        let b = Aabb::new(Vec3::new(-0.5, -0.5, -6.5), Vec3::new(0.5, 0.5, -5.5));
        let rig = Rig::new(&[wall, a, b], 1);
        let rounds = |options: &[&str]| {
            let mut mock = rig.mock();
            mock.set_visible(2, false);
            let mut om = method("om", options);
            let calls = &rig.run(&mut om, &mut mock, 1)[0];
            assert_draws_exactly(calls, &[0, 1]);
            let counters = om.method.counters();
            counters.iter().find(|(k, _)| *k == "stage2_rounds").map(|&(_, v)| v).unwrap()
        };
        assert_eq!(rounds(&["om.overlap=off"]), 3.0);
        assert_eq!(rounds(&[]), 2.0);
    }
}
