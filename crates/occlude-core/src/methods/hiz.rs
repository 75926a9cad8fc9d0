//! Two-phase Hi-Z occlusion culling (`hiz`), as GPU-driven renderers ship
//! it: zeux's niagara (early and late passes against a depth pyramid),
//! nvpro's `gl_occlusion_culling` in its HiZ mode and Bevy's
//! `OcclusionCulling`. Where `roc` rasterizes every
//! object's box against the depth buffer, `hiz` reads a few texels of a
//! depth pyramid per box in a compute pass, with no draw of the boxes.
//!
//! Per frame, on [`GpuCulling`](crate::GpuCulling):
//!
//! 1. early pass: draw last frame's visible instances that are still in the
//!    view frustum;
//! 2. build a depth pyramid from that depth ([`crate::depth_pyramid`]);
//! 3. late pass: test every instance's box against the pyramid, reading
//!    at most `hiz.texels` x `hiz.texels` texels of the finest level that
//!    fits (default 8; 2 is the field's 2x2, which draws 1.2-1.9x the
//!    triangles of 8 and is slower in the simulated clock, as measured in
//!    `docs/benchmarks.md`, "The default `hiz.texels`"; boxes outside the
//!    frustum set nothing, boxes at the eye are visible untested), setting
//!    this frame's visibility (`hiz.granularity=instance`, the default); or, with
//!    `hiz.granularity=node`, walk the hierarchy from the root down
//!    (`methods/node_walk.rs`), testing the node boxes of each level against
//!    the pyramid the same way and descending only into visible nodes, and
//!    test against it the boxes of the instances of the visible leaves
//!    (gathered as flags over the walk, compacted into one list, tested in
//!    one dispatch);
//! 4. draw the instances visible now that were not drawn in step 1, and keep
//!    the visible set for the next frame.
//!
//! Exact: an instance with a pixel in the final image has there a depth no
//! farther than the early pass's depth (which draws a subset of the scene),
//! so its box, which contains it and is pulled towards the eye, passes the
//! full-resolution box test at that pixel; the pyramid test never hides a
//! box that test finds visible (the proof is `depth_pyramid`'s), so the
//! instance is drawn in step 1 or 4. With node granularity every node
//! above such an instance holds its box, so the node's box passes the
//! full-resolution test at the same pixel and the pyramid test keeps it
//! (a node box is a box): the walk reaches the instance.
//!
//! What node granularity costs: three dispatches per level of the
//! hierarchy (box test, leaves, children; `methods/node_walk.rs`) plus five
//! (clearing the node flags; clearing, gathering from the last level and
//! compacting the leaves' instances; their test), against one dispatch
//! over every instance; what it saves is the box tests of the
//! instances under hidden nodes. On the soft backend each dispatch is
//! charged as the one it stands for (`GpuModel`'s per-dispatch, per-item,
//! per-box and per-texel costs; nothing new). On wgpu every culling
//! dispatch runs one thread per slot of its list's capacity (no indirect
//! dispatch), here the node count, on every level.

use super::node_walk::{NodeTest, NodeWalk};
use super::roc::{AllInstances, TemporalSet};
use super::tracked::{update_instance_boxes, update_node_boxes, Tracked};
use super::vfc::ViewFrustumCulling;
use super::{Carried, CullingMethod, FrameContext, MethodParams, OptionError, ParamVisitor, VisibleSet};
use crate::backend::Backend;
use crate::cost_model::CostModel;
use crate::depth_pyramid::level_sizes;
use crate::gpu_culling::{ExpandInto, Flags, IdList, Pyramid};
use std::fmt;
use std::str::FromStr;

/// What the late pass tests against the pyramid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Granularity {
    /// `instance`: every instance's box, in one dispatch.
    Instance,
    /// `node`: the hierarchy's node boxes top-down, then the instances of
    /// the visible leaves (module documentation).
    Node,
}

impl fmt::Display for Granularity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Granularity::Instance => "instance",
            Granularity::Node => "node",
        })
    }
}

impl FromStr for Granularity {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        match s {
            "instance" => Ok(Granularity::Instance),
            "node" => Ok(Granularity::Node),
            _ => Err(()),
        }
    }
}

/// Parameters of `hiz`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HizParams {
    /// `hiz.texels`: most texels per axis a box test reads, 1 to 16
    /// (default 8: fewer triangles than the field's 2x2 and, in the
    /// simulated clock, faster on every measured scene).
    pub texels: u32,
    /// `hiz.granularity`: `instance` (default) or `node`.
    pub granularity: Granularity,
}

impl Default for HizParams {
    fn default() -> Self {
        Self { texels: 8, granularity: Granularity::Instance }
    }
}

impl MethodParams for HizParams {
    const METHOD: &'static str = "hiz";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        v.value("texels", &mut self.texels, "an integer from 1 to 16", |t| (1..=16).contains(t))?;
        v.value("granularity", &mut self.granularity, "instance or node", |_| true)
    }
}

/// The device resources of `hiz.granularity=node`'s walk.
#[derive(Clone, Copy, Debug)]
struct NodeResources {
    walk: NodeWalk,
    /// The list holding the root, where the walk starts.
    root: IdList,
    /// The levels of the hierarchy (its deepest depth + 1).
    levels: u32,
    /// Per instance, whether it lies in a leaf the walk found visible.
    candidates: Flags,
    /// Those instances, compacted for their box test.
    candidate_list: IdList,
}

/// The device resources of `hiz`, made on its first frame.
#[derive(Clone, Copy, Debug)]
struct Resources {
    all: AllInstances,
    pyramid: Pyramid,
    temporal: TemporalSet,
    /// With `hiz.granularity=node`.
    nodes: Option<NodeResources>,
}

/// `hiz`: two-phase occlusion culling against a depth pyramid (module
/// documentation).
#[derive(Clone, Debug)]
pub struct TwoPhaseHiZ {
    params: HizParams,
    /// The hierarchy (and instance boxes) the resources are for.
    tracked: Tracked,
    resources: Option<Resources>,
}

impl TwoPhaseHiZ {
    /// A fresh `hiz` (nothing visible yet).
    pub fn new(params: HizParams) -> Self {
        Self { params, tracked: Tracked::default(), resources: None }
    }
}

impl CullingMethod for TwoPhaseHiZ {
    fn name(&self) -> &'static str {
        "hiz"
    }

    fn needs_gpu_culling(&self) -> bool {
        true
    }

    fn needs_depth_pyramid(&self) -> bool {
        true
    }

    fn prepare(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let (scene, h) = (ctx.scene, ctx.hierarchy);
        self.tracked.keep_up(h, &mut self.resources, backend, |r, gpu, changes| {
            update_instance_boxes(gpu, r.all.boxes, scene, changes);
            if let Some(n) = &r.nodes {
                update_node_boxes(gpu, n.walk.boxes, h, changes);
            }
        });
        if self.resources.is_some() {
            return;
        }
        let Ok(gpu) = backend.gpu_culling() else { return };
        if gpu.pyramid_support().is_err() {
            return;
        }
        let instances = ctx.scene.instances.len() as u32;
        let h = ctx.hierarchy;
        let nodes = (self.params.granularity == Granularity::Node).then(|| NodeResources {
            walk: NodeWalk::new(gpu, h),
            root: gpu.create_list(1, &[h.root()]),
            levels: h.max_depth() + 1,
            candidates: gpu.create_flags(instances),
            candidate_list: gpu.create_list(instances, &[]),
        });
        self.resources = Some(Resources {
            all: AllInstances::new(gpu, ctx.scene),
            pyramid: gpu.create_pyramid(),
            temporal: TemporalSet::new(gpu, instances),
            nodes,
        });
    }

    /// Every frame: the temporal set's passes (`TemporalSet::passes`,
    /// dropping what left the frustum, drawing the new), a reduction per
    /// pyramid level past the first (the pyramid's texels) and at least one
    /// box test: seven dispatches and a reduction per level, two indirect
    /// draws.
    fn floor_ms(&self, _: &FrameContext<'_>, model: &CostModel, (width, height): (u32, u32), _: bool) -> f64 {
        let levels = level_sizes(width, height);
        let texels = levels[1..].iter().map(|&(w, h)| u64::from(w) * u64::from(h)).sum();
        let (dispatches, draws) = TemporalSet::passes(true, true);
        let reductions = levels.len() as u64 - 1;
        model.passes_ms(dispatches + reductions + 1, draws, texels)
    }

    fn carried_visibility(&self) -> Carried {
        Carried::Instances
    }

    fn visible_set(&self, _: &FrameContext<'_>) -> Option<VisibleSet> {
        self.resources.as_ref().map(|r| r.temporal.visible())
    }

    fn seed(&mut self, _: &FrameContext<'_>, backend: &mut dyn Backend, visible: &VisibleSet) {
        let (Some(r), Ok(gpu)) = (self.resources.as_ref(), backend.gpu_culling()) else { return };
        r.temporal.seed(gpu, visible);
    }

    /// A backend without [`GpuCulling`](crate::GpuCulling) or depth pyramids (which the runner
    /// refuses first) gets view-frustum culling.
    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let (Some(r), Ok(gpu)) = (self.resources.as_mut(), backend.gpu_culling()) else {
            return ViewFrustumCulling.render(ctx, backend);
        };
        let visible = r.temporal.begin(gpu, Some(r.all.boxes));
        gpu.build_pyramid(r.pyramid);
        let (pyramid, reach) = (r.pyramid, self.params.texels);
        match r.nodes {
            None => gpu.test_boxes_pyramid(r.all.boxes, r.all.ids, pyramid, reach, visible),
            Some(n) => {
                gpu.clear_flags(n.candidates);
                let test: NodeTest<'_> =
                    &mut |gpu, boxes, list, flags| gpu.test_boxes_pyramid(boxes, list, pyramid, reach, flags);
                let deepest = n.walk.walk(gpu, n.root, n.levels, test, n.candidates);
                gpu.expand(deepest, n.walk.visible, n.walk.leaf_instances, ExpandInto::Flags(n.candidates));
                gpu.compact(n.candidates, None, n.candidate_list);
                gpu.test_boxes_pyramid(r.all.boxes, n.candidate_list, pyramid, reach, visible);
            }
        }
        r.temporal.finish(gpu, true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::methods::test_rig::{
        assert_draws_exactly, assert_refused_without_gpu_culling_and_falls_back_to_frustum_culling,
        assert_walks_top_down, culling_steps, method, Rig,
    };
    use crate::methods::MethodOptions;

    #[test]
    fn texels_default_to_eight_and_stay_in_range() {
        let read = |opts: &[&str]| HizParams::from_options(&MethodOptions::parse(opts).unwrap());
        let instance = Granularity::Instance;
        assert_eq!(read(&[]), Ok(HizParams { texels: 8, granularity: instance }));
        assert_eq!(read(&["hiz.texels=2"]), Ok(HizParams { texels: 2, granularity: instance }));
        assert_eq!(read(&["hiz.texels=16"]), Ok(HizParams { texels: 16, granularity: instance }));
        let err = read(&["hiz.texels=0"]).unwrap_err();
        assert!(err.to_string().contains("hiz.texels = 0: expected an integer from 1 to 16"), "{err}");
    }

    #[test]
    fn is_refused_without_gpu_culling_and_falls_back_to_frustum_culling() {
        assert_refused_without_gpu_culling_and_falls_back_to_frustum_culling("hiz");
    }

    /// The early pass draws last frame's visible objects (those in view),
    /// the pyramid is built from them, every box is tested against it, and
    /// the late pass draws the newly visible, in that order: an object
    /// turning visible is drawn in that frame, a hidden one never.
    #[test]
    fn early_pass_pyramid_test_late_pass() {
        let rig = Rig::row(4);
        let all: Vec<u32> = (0..rig.scene.instances.len() as u32).collect();
        let mut mock = rig.mock().with_gpu_culling();
        mock.set_visible(2, false);
        let mut hiz = method("hiz", &[]);
        let frames = rig.run(&mut hiz, &mut mock, 2);
        let steps = [("draw", vec![0, 1, 3]), ("build pyramid", vec![]), ("pyramid test", all), ("draw", vec![])];
        assert_eq!(culling_steps(&frames[1]), steps);
        mock.set_visible(2, true);
        let turned = &rig.run(&mut hiz, &mut mock, 1)[0];
        assert_eq!(culling_steps(turned).last(), Some(&("draw", vec![2])));
        assert_draws_exactly(turned, &[0, 1, 2, 3]);
    }

    /// `hiz.granularity=node`: after the early pass and the pyramid, one
    /// pyramid test per level from the root, each of the children of the
    /// nodes the last level found visible, then one of the instances of the
    /// visible leaves; a hidden subtree is not opened, and exactly the
    /// visible objects are drawn.
    #[test]
    fn node_granularity_tests_visible_nodes_top_down_then_their_instances() {
        let (rig, frames) = assert_walks_top_down("hiz", &["hiz.granularity=node"], "pyramid test");
        let h = &rig.hierarchy;
        let seen: Vec<Aabb> = (0..4).map(|i| rig.scene.instances[i].bounds).collect();
        let visible = |n: &u32| seen.iter().any(|b| b.overlaps(h.bounds(*n)));
        for (nodes, rest) in frames {
            let mut reached: Vec<u32> = nodes
                .iter()
                .flatten()
                .filter(|&n| h.is_leaf(*n) && visible(n))
                .flat_map(|&n| h.instances(n).to_vec())
                .collect();
            reached.sort_unstable();
            assert_eq!(rest, [reached]);
            assert!(rest[0].len() < rig.scene.instances.len(), "no hidden instance was left untested");
        }
    }

    #[test]
    fn granularity_reads_instance_or_node() {
        let read = |opts: &[&str]| HizParams::from_options(&MethodOptions::parse(opts).unwrap());
        assert_eq!(read(&["hiz.granularity=node"]).unwrap().granularity, Granularity::Node);
        assert_eq!(read(&["hiz.granularity=instance"]).unwrap().granularity, Granularity::Instance);
        let err = read(&["hiz.granularity=leaf"]).unwrap_err();
        assert!(err.to_string().contains("hiz.granularity = leaf: expected instance or node"), "{err}");
    }
}
