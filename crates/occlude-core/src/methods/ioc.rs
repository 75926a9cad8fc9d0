//! Iterative hierarchical raster occlusion culling (IOC poster, section 2,
//! Figure 2): raster occlusion culling (`roc`) applied to the nodes of the
//! hierarchy level by level instead of to every object.
//!
//! Per frame, on [`GpuCulling`](crate::GpuCulling): last frame's potentially visible objects are
//! drawn (the occluders). Then, from the start depth to the bottom depth, one
//! batch tests the boxes of the level's nodes against that depth. A culled
//! node ends the descent: nothing below it is marked, so its whole subtree
//! stays occluded. A visible leaf marks its objects potentially visible; a
//! visible interior node puts its children into the next level's list. At
//! the bottom depth every object below a visible node is potentially
//! visible. The potentially visible objects outside the view frustum are
//! dropped (`ioc.frustum`, default on: the objects of a visible bottom node
//! reach beyond the frustum, and drawing them costs without adding a pixel);
//! the rest not drawn as occluders are then drawn, and all of them are the
//! next frame's occluders. The start list
//! holds the nodes at the start depth and the leaves above it.
//!
//! `ioc.auto` chooses the start per frame (the poster's stated open
//! limitation is the manual choice of the depth range): the shallowest depth,
//! no deeper than the bottom, at which no node in the frustum spans more than
//! half the screen's height, judged on the CPU from the nodes' bounding
//! spheres by a walk down through the large nodes only (charged as traversal
//! of the nodes looked at). The bottom stays
//! `ioc.bottom`: how deep to go is what trades box tests against drawing
//! hidden objects, and nothing known before the frame's test measures that.
//!
//! The poster reads each level's list length back to the CPU to size the next
//! level's draw; here the length stays on the device and the next level's
//! dispatch and indirect draw read it there, so a frame reads nothing back.
//!
//! Exact for the same reason as `roc`: a node's box holds everything its
//! subtree draws inside it, so the box of every node above a visible pixel
//! passes the test at that pixel, and the object owning it is reached; and
//! the frustum test that drops objects is the conservative one box tests
//! use, so a dropped object has no pixel.

use super::node_walk::{walk_tables, NodeTest, NodeWalk};
use super::roc::TemporalSet;
use super::tracked::{update_instance_boxes, update_node_boxes, Tracked};
use super::vfc::ViewFrustumCulling;
use super::{CullingMethod, FrameContext, MethodParams, OptionError, ParamVisitor};
use crate::backend::Backend;
use crate::gpu_culling::{BoxSet, ExpandInto, IdList, ItemRange, RangeTable, TableData};
use crate::hierarchy::{Hierarchy, NodeId};
use std::fmt;
use std::str::FromStr;

/// A level of the hierarchy (depth 0 is the root), counted from the root or
/// up from the deepest level, so that one setting fits trees of any depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// `N`: depth N.
    FromRoot(u32),
    /// `deepest` or `deepest-K`: K levels above the deepest leaf.
    AboveDeepest(u32),
}

impl Level {
    /// The depth this level names in a tree whose deepest node has depth
    /// `deepest`, and whether a depth past the tree's had to be clamped.
    pub fn resolve(self, deepest: u32) -> (u32, bool) {
        match self {
            Level::FromRoot(d) => (d.min(deepest), d > deepest),
            Level::AboveDeepest(k) => (deepest.saturating_sub(k), k > deepest),
        }
    }
}

impl fmt::Display for Level {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Level::FromRoot(d) => write!(f, "{d}"),
            Level::AboveDeepest(0) => f.write_str("deepest"),
            Level::AboveDeepest(k) => write!(f, "deepest-{k}"),
        }
    }
}

impl FromStr for Level {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        match s.strip_prefix("deepest") {
            Some("") => Ok(Level::AboveDeepest(0)),
            Some(rest) => rest.strip_prefix('-').and_then(|k| k.parse().ok()).map(Level::AboveDeepest).ok_or(()),
            None => s.parse().map(Level::FromRoot).map_err(|_| ()),
        }
    }
}

/// Parameters of `ioc`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IocParams {
    /// `ioc.frustum`: whether the potentially visible objects are
    /// frustum-culled before they are drawn (default on; off draws every
    /// object below a visible bottom node, as the poster's text reads).
    pub frustum: bool,
    /// `ioc.start`: the first level tested (default 4).
    pub start: Level,
    /// `ioc.bottom`: the last level tested; below it nothing is tested
    /// (default `deepest-2`).
    pub bottom: Level,
    /// `ioc.auto`: choose the start per frame instead of `ioc.start` (the
    /// module documentation; default off).
    pub auto: bool,
}

/// The largest share of the screen's height a node's bounding sphere may
/// span for `ioc.auto` to start at its depth. Boxes larger than that almost
/// always pass (something in so large a box is in front of the occluders)
/// and each costs a good part of a screen of fragments, which is what ioc's
/// upper levels spend (docs/benchmarks.md); fixed at one half, not fitted to
/// any scene.
const AUTO_SPAN: f32 = 0.5;

const LEVEL: &str = "a depth N >= 0, 'deepest' or 'deepest-K'";

impl Default for IocParams {
    fn default() -> Self {
        Self { start: Level::FromRoot(4), bottom: Level::AboveDeepest(2), frustum: true, auto: false }
    }
}

impl MethodParams for IocParams {
    const METHOD: &'static str = "ioc";
    /// `ioc.start` and `ioc.bottom`; a start below the bottom, when both
    /// count from the same end, is an error naming both (not with
    /// `ioc.auto`, which chooses the start itself, so `ioc.start` is unused).
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        let start_given = v.is_set("start");
        v.value("start", &mut self.start, LEVEL, |_| true)?;
        v.value("bottom", &mut self.bottom, LEVEL, |_| true)?;
        v.flag("frustum", &mut self.frustum)?;
        v.flag("auto", &mut self.auto)?;
        let (start, bottom) = (self.start, self.bottom);
        let inverted = match (start, bottom) {
            (Level::FromRoot(s), Level::FromRoot(b)) => s > b,
            (Level::AboveDeepest(s), Level::AboveDeepest(b)) => s < b,
            _ => false,
        };
        if inverted && !self.auto {
            // Blame the one the user set: a default is nobody's mistake.
            return Err(if start_given {
                v.bad_value("start", start, format!("a level no deeper than ioc.bottom = {bottom}"))
            } else {
                v.bad_value("bottom", bottom, format!("a level no shallower than ioc.start = {start} (its default)"))
            });
        }
        Ok(())
    }
}

/// The device resources of `ioc`, made on its first frame.
#[derive(Clone, Debug)]
struct Resources {
    /// The node boxes, flags, lists and tables of the level-by-level test.
    walk: NodeWalk,
    /// Every instance's box, for the frustum test of what is drawn.
    instance_boxes: BoxSet,
    /// Per depth down to the bottom, the nodes at that depth and the leaves
    /// above it: the start list of a frame starting there (made for the
    /// start depth only, unless `ioc.auto`).
    starts: Vec<Option<IdList>>,
    /// Per node, every instance in its subtree.
    subtree_instances: RangeTable,
    temporal: TemporalSet,
    /// The start and bottom depths in this hierarchy.
    depths: (u32, u32),
}

/// `ioc`: iterative hierarchical raster occlusion culling (module
/// documentation).
#[derive(Clone, Debug)]
pub struct IterativeOcclusion {
    params: IocParams,
    /// The hierarchy (and instance boxes) the resources are for.
    tracked: Tracked,
    resources: Option<Resources>,
    warnings: Vec<String>,
}

impl IterativeOcclusion {
    /// A fresh `ioc` (nothing visible yet).
    pub fn new(params: IocParams) -> Self {
        Self { params, tracked: Tracked::default(), resources: None, warnings: Vec::new() }
    }
}

/// The start and bottom depths of `params` in `h`, clamped to its depth,
/// and a warning for each depth clamped (none for the start with
/// `ioc.auto`, which does not use it).
fn resolve_depths(params: &IocParams, h: &Hierarchy) -> ((u32, u32), Vec<String>) {
    let mut warnings = Vec::new();
    let deepest = h.max_depth();
    let (mut start, start_clamped) = params.start.resolve(deepest);
    let (bottom, bottom_clamped) = params.bottom.resolve(deepest);
    for (key, level, clamped) in [("start", params.start, start_clamped), ("bottom", params.bottom, bottom_clamped)] {
        if clamped && !(key == "start" && params.auto) {
            warnings.push(format!(
                "ioc.{key} = {level} is past the hierarchy's depth {deepest}: using {}",
                if key == "start" { start } else { bottom }
            ));
        }
    }
    if start > bottom {
        if !params.auto {
            warnings.push(format!(
                "ioc.start = {} (depth {start}) lies below ioc.bottom = {} (depth {bottom}) in this hierarchy: starting at {bottom}",
                params.start, params.bottom
            ));
        }
        start = bottom;
    }
    ((start, bottom), warnings)
}

/// The start list of a walk starting at `depth`: the nodes at that depth
/// and the leaves above it.
fn start_list(h: &Hierarchy, depth: u32) -> Vec<NodeId> {
    (0..h.node_count() as NodeId)
        .filter(|&n| h.node(n).depth == depth || (h.is_leaf(n) && h.node(n).depth < depth))
        .collect()
}

/// `ioc`'s walk of one hierarchy as plain data, before upload: what
/// [`IterativeOcclusion`] puts on the device on its first frame (without
/// `ioc.auto`), for a renderer that records the walk itself
/// (`occlude_wgpu::embed::GpuCuller`). Per frame: the start list's node
/// boxes are tested, the instances of the visible leaves marked and the
/// children of the visible nodes listed for the next depth, down to the
/// bottom, whose visible nodes mark every instance of their subtrees.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IocWalk {
    /// The start and bottom depths of the parameters in the hierarchy,
    /// clamped to its depth.
    pub depths: (u32, u32),
    /// Why a depth was clamped (empty when none was).
    pub warnings: Vec<String>,
    /// The nodes at the start depth and the leaves above it.
    pub start: Vec<NodeId>,
    /// Per node, its children (none for a leaf).
    pub children: TableData,
    /// Per node, a leaf's instances (none for an interior node).
    pub leaf_instances: TableData,
    /// Per node, every instance of its subtree.
    pub subtree_instances: TableData,
}

impl IocWalk {
    /// The walk of `h` with `params`' start and bottom (`ioc.auto` and
    /// `ioc.frustum` are the walker's to apply).
    pub fn new(params: &IocParams, h: &Hierarchy) -> Self {
        let (depths, warnings) = resolve_depths(params, h);
        let (children, leaf_instances) = walk_tables(h);
        Self {
            depths,
            warnings,
            start: start_list(h, depths.0),
            children,
            leaf_instances,
            subtree_instances: subtree_table(h),
        }
    }
}

impl CullingMethod for IterativeOcclusion {
    fn name(&self) -> &'static str {
        "ioc"
    }

    fn needs_gpu_culling(&self) -> bool {
        true
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn prepare(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let (scene, h) = (ctx.scene, ctx.hierarchy);
        self.tracked.keep_up(h, &mut self.resources, backend, |r, gpu, changes| {
            update_instance_boxes(gpu, r.instance_boxes, scene, changes);
            update_node_boxes(gpu, r.walk.boxes, h, changes);
        });
        if self.resources.is_some() {
            return;
        }
        let h = ctx.hierarchy;
        let (depths, warnings) = resolve_depths(&self.params, h);
        self.warnings.extend(warnings);
        let Ok(gpu) = backend.gpu_culling() else { return };
        let nodes = h.node_count() as u32;
        let instance_boxes: Vec<_> = ctx.scene.instances.iter().map(|i| i.culling_bounds()).collect();
        let auto = self.params.auto;
        let starts = (0..=depths.1)
            .map(|d| (auto || d == depths.0).then(|| gpu.create_list(nodes, &start_list(h, d))))
            .collect();
        let subtree = subtree_table(h);
        self.resources = Some(Resources {
            walk: NodeWalk::new(gpu, h),
            instance_boxes: gpu.create_boxes(&instance_boxes),
            starts,
            subtree_instances: gpu.create_table(&subtree.ranges, &subtree.items),
            temporal: TemporalSet::new(gpu, ctx.scene.instances.len() as u32),
            depths,
        });
    }

    /// A backend without [`GpuCulling`](crate::GpuCulling) (which the runner refuses first)
    /// gets view-frustum culling.
    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let Some(r) = self.resources.as_mut().filter(|_| backend.gpu_culling().is_ok()) else {
            return ViewFrustumCulling.render(ctx, backend);
        };
        let (mut start, bottom) = r.depths;
        if self.params.auto {
            let (depth, visited) = auto_start(ctx, bottom);
            start = depth;
            backend.traverse(visited);
        }
        let gpu = backend.gpu_culling().expect("checked above");
        let visible = r.temporal.begin(gpu, None);
        let first = r.starts[start as usize].expect("a start list for every depth ioc.auto may choose");
        let test: NodeTest<'_> = &mut |gpu, boxes, list, flags| gpu.test_boxes(boxes, list, flags);
        let bottom_list = r.walk.walk(gpu, first, bottom - start + 1, test, visible);
        gpu.expand(bottom_list, r.walk.visible, r.subtree_instances, ExpandInto::Flags(visible));
        if self.params.frustum {
            gpu.drop_outside_frustum(r.instance_boxes, visible);
        }
        r.temporal.finish(gpu, true);
    }
}

/// `ioc.auto`'s start for this frame: one below the deepest node in the
/// frustum that spans more than [`AUTO_SPAN`] of the screen's height
/// (judged from its bounding sphere), at most `bottom`; and how many nodes
/// it looked at (charged as traversal). The walk goes down only through
/// such large nodes: a node inside a small one is small too (its box lies
/// inside), up to the sphere's rounding, which only moves the start.
fn auto_start(ctx: &FrameContext<'_>, bottom: u32) -> (u32, u64) {
    let h = ctx.hierarchy;
    let eye = ctx.camera.position;
    let limit = AUTO_SPAN * (ctx.camera.fov_y_deg.to_radians() * 0.5).tan();
    let large = |n: NodeId| {
        let b = &h.node(n).bounds;
        let r = 0.5 * b.extent().length();
        let d = b.center().distance(eye);
        // The sphere's half-angle is asin(r / d); its tangent over the
        // view's half-angle tangent is the share of the screen's height.
        d <= r || r / (d * d - r * r).sqrt() > limit
    };
    let (mut start, mut visited) = (0, 0u64);
    let mut stack = vec![h.root()];
    while let Some(n) = stack.pop() {
        visited += 1;
        let depth = h.node(n).depth;
        if depth >= bottom || !ctx.frustum.intersects(&h.node(n).bounds) || !large(n) {
            continue;
        }
        start = start.max(depth + 1);
        stack.extend_from_slice(h.children(n));
    }
    (start.min(bottom), visited)
}

/// Per node, every instance of its subtree: the leaves' instances in
/// depth-first order, in which every subtree's instances are one range.
fn subtree_table(h: &Hierarchy) -> TableData {
    let mut subtree_ranges = vec![ItemRange::default(); h.node_count()];
    let mut in_order = Vec::with_capacity(h.items.len());
    // Depth first; a node is seen on the way down (`false`) and again once
    // its subtree is done (`true`).
    let mut stack = vec![(h.root(), false)];
    while let Some((id, done)) = stack.pop() {
        let range = &mut subtree_ranges[id as usize];
        if done {
            range.count = in_order.len() as u32 - range.first;
            continue;
        }
        range.first = in_order.len() as u32;
        in_order.extend_from_slice(h.instances(id));
        stack.push((id, true));
        stack.extend(h.children(id).iter().rev().map(|&c| (c, false)));
    }
    TableData { ranges: subtree_ranges, items: in_order }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::test_rig::{
        assert_refused_without_gpu_culling_and_falls_back_to_frustum_culling, assert_walks_top_down, Rig,
    };
    use crate::methods::MethodOptions;

    fn read(opts: &[&str]) -> Result<IocParams, OptionError> {
        IocParams::from_options(&MethodOptions::parse(opts).unwrap())
    }

    #[test]
    fn levels_parse_from_either_end_and_resolve_with_clamping() {
        assert_eq!(
            read(&[]),
            Ok(IocParams { start: Level::FromRoot(4), bottom: Level::AboveDeepest(2), frustum: true, auto: false })
        );
        assert!(!read(&["ioc.frustum=off"]).unwrap().frustum);
        let p = read(&["ioc.start=deepest-5", "ioc.bottom=deepest"]).unwrap();
        assert_eq!((p.start, p.bottom), (Level::AboveDeepest(5), Level::AboveDeepest(0)));
        assert_eq!(Level::FromRoot(3).resolve(10), (3, false));
        assert_eq!(Level::FromRoot(12).resolve(10), (10, true));
        assert_eq!(Level::AboveDeepest(2).resolve(10), (8, false));
        assert_eq!(Level::AboveDeepest(12).resolve(10), (0, true));
        for text in ["3", "deepest", "deepest-2"] {
            assert_eq!(text.parse::<Level>().unwrap().to_string(), text);
        }
        for bad in ["ioc.start=-1", "ioc.bottom=deep", "ioc.bottom=deepest-", "ioc.start=deepest+1"] {
            assert!(read(&[bad]).is_err(), "{bad} accepted");
        }
    }

    /// The walk as data describes the hierarchy: the start list is the
    /// nodes at the start depth and the leaves above it; each node's
    /// children, a leaf's instances and every instance below each node are
    /// its ranges of the tables; depths past the tree's are clamped, with
    /// a warning.
    #[test]
    fn the_walk_as_data_lists_the_start_and_each_nodes_children_leaf_and_subtree() {
        let rig = Rig::row(16);
        let h = &rig.hierarchy;
        let walk = IocWalk::new(&read(&["ioc.start=2", "ioc.bottom=deepest"]).unwrap(), h);
        assert_eq!(walk.depths, (2, h.max_depth()));
        assert!(walk.warnings.is_empty(), "{:?}", walk.warnings);
        let items = |t: &TableData, n: NodeId| {
            let r = t.ranges[n as usize];
            let mut items = t.items[r.first as usize..(r.first + r.count) as usize].to_vec();
            items.sort_unstable();
            items
        };
        for n in 0..h.node_count() as NodeId {
            let depth = h.node(n).depth;
            assert_eq!(walk.start.contains(&n), depth == 2 || (h.is_leaf(n) && depth < 2), "node {n}");
            assert_eq!(items(&walk.children, n), h.children(n), "node {n}");
            assert_eq!(items(&walk.leaf_instances, n), h.instances(n), "node {n}");
            let (mut below, mut stack) = (Vec::new(), vec![n]);
            while let Some(m) = stack.pop() {
                below.extend_from_slice(h.instances(m));
                stack.extend_from_slice(h.children(m));
            }
            below.sort_unstable();
            assert_eq!(items(&walk.subtree_instances, n), below, "node {n}");
        }
        assert_eq!(items(&walk.subtree_instances, h.root()).len(), rig.scene.instances.len());
        let clamped = IocWalk::new(&read(&["ioc.start=40"]).unwrap(), h);
        assert_eq!(clamped.depths, (h.max_depth() - 2, h.max_depth() - 2));
        assert_eq!(clamped.warnings.len(), 2, "{:?}", clamped.warnings);
    }

    #[test]
    fn a_start_below_the_bottom_names_both() {
        let err = read(&["ioc.start=7", "ioc.bottom=5"]).unwrap_err().to_string();
        assert!(err.contains("ioc.start = 7") && err.contains("ioc.bottom = 5"), "{err}");
        let err = read(&["ioc.bottom=0"]).unwrap_err().to_string();
        assert!(err.contains("ioc.bottom = 0") && err.contains("ioc.start = 4 (its default)"), "{err}");
        let err = read(&["ioc.start=deepest-1", "ioc.bottom=deepest-3"]).unwrap_err().to_string();
        assert!(err.contains("ioc.start = deepest-1") && err.contains("ioc.bottom = deepest-3"), "{err}");
        assert!(read(&["ioc.auto=on", "ioc.bottom=0"]).is_ok(), "with ioc.auto the start is not ioc.start");
    }

    #[test]
    fn is_refused_without_gpu_culling_and_falls_back_to_frustum_culling() {
        assert_refused_without_gpu_culling_and_falls_back_to_frustum_culling("ioc");
    }

    /// From the root to the deepest level, one box test per level, each of
    /// the children of the nodes the last level found visible, and no other
    /// test: a hidden subtree is not opened, and exactly the visible objects
    /// in view are drawn.
    #[test]
    fn tests_level_by_level_the_children_of_visible_nodes() {
        let (_, frames) = assert_walks_top_down("ioc", &["ioc.start=0", "ioc.bottom=deepest"], "test");
        assert!(frames.iter().all(|(_, rest)| rest.is_empty()));
    }
}
