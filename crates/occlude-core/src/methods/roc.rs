//! Raster occlusion culling (ROC), the baseline of the IOC poster (section 1,
//! its references [1, 2]: nvpro's `gl_occlusion_culling`, "raster" technique,
//! temporal mode): every object's box is tested against the depth of last
//! frame's visible objects in one batch on the GPU, a fragment that passes
//! the depth test marks its object visible in a buffer on the device, and
//! the visible objects are drawn by an indirect multi-draw. No result comes
//! back to the CPU.
//!
//! Per frame, on [`GpuCulling`]:
//!
//! 1. draw last frame's visible objects (the occluders);
//! 2. clear this frame's flags and test every object's box against that
//!    depth (objects outside the frustum set nothing, boxes at the eye are
//!    visible untested);
//! 3. draw the objects visible now that were not drawn in step 1 (`exact`
//!    mode; `roc.mode=last` leaves this out, so an object that comes into
//!    view appears a frame late and the missed pixels are reported);
//! 4. keep the visible objects for the next frame.
//!
//! Exact in the default mode: an object with a pixel in the final image has
//! that pixel at a depth no farther than the step-1 depth there, so its box,
//! which contains it and is pulled towards the eye, passes the test there,
//! and the object is drawn in step 1 or 3.

use super::tracked::{update_instance_boxes, Tracked};
use super::vfc::ViewFrustumCulling;
use super::{Carried, CullingMethod, FrameContext, MethodParams, OptionError, ParamVisitor, VisibleSet};
use crate::backend::Backend;
use crate::cost_model::CostModel;
use crate::gpu_culling::{BoxSet, Flags, GpuCulling, IdList};
use crate::scene::Scene;
use std::fmt;
use std::str::FromStr;

/// Whether a frame draws what its own test found (`exact`) or only what the
/// previous frame's test found (`last`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RocMode {
    /// Steps 1-4: exact for the current frame.
    Exact,
    /// Steps 1, 2 and 4: no second draw, objects may appear a frame late.
    Last,
}

impl fmt::Display for RocMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RocMode::Exact => "exact",
            RocMode::Last => "last",
        })
    }
}

impl FromStr for RocMode {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        match s {
            "exact" => Ok(RocMode::Exact),
            "last" => Ok(RocMode::Last),
            _ => Err(()),
        }
    }
}

/// Parameters of `roc`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RocParams {
    /// `roc.mode`: `exact` (default) or `last`.
    pub mode: RocMode,
}

impl Default for RocParams {
    fn default() -> Self {
        Self { mode: RocMode::Exact }
    }
}

impl MethodParams for RocParams {
    const METHOD: &'static str = "roc";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        v.value("mode", &mut self.mode, "exact or last", |_| true)
    }
}

/// The temporal half of ROC, shared with `ioc` (the poster: "we first
/// pre-render the depth buffer of the occluders, which are visible at the
/// previous frame"): per-instance flags of this frame and the last, and the
/// lists drawn from them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TemporalSet {
    /// This frame's visibility flags, per instance.
    visible: Flags,
    /// Last frame's (the two are swapped at the end of each frame).
    previous: Flags,
    /// Last frame's visible instances, drawn first.
    occluders: IdList,
    /// Instances visible now and not among the occluders.
    newly_visible: IdList,
}

impl TemporalSet {
    /// The resources for `instances` instances, nothing visible yet.
    pub(crate) fn new(gpu: &mut dyn GpuCulling, instances: u32) -> Self {
        Self {
            visible: gpu.create_flags(instances),
            previous: gpu.create_flags(instances),
            occluders: gpu.create_list(instances, &[]),
            newly_visible: gpu.create_list(instances, &[]),
        }
    }

    /// Step 1 and the start of step 2: draws the occluders (last frame's
    /// visible instances; with `in_frustum`, only those whose box in it lies
    /// in the view frustum, the others forgotten) and clears this frame's
    /// flags; returns them, for the frame's tests to set.
    pub(crate) fn begin(&self, gpu: &mut dyn GpuCulling, in_frustum: Option<BoxSet>) -> Flags {
        if let Some(boxes) = in_frustum {
            gpu.drop_outside_frustum(boxes, self.previous);
        }
        gpu.compact(self.previous, None, self.occluders);
        gpu.draw_list(self.occluders);
        gpu.clear_flags(self.visible);
        self.visible
    }

    /// The dispatches and indirect draws that [`TemporalSet::begin`] (with
    /// `in_frustum` or without) and [`TemporalSet::finish`] (with
    /// `draw_new` or without) record whatever the scene: a method's cost
    /// floor (`CullingMethod::floor_ms`).
    pub(crate) fn passes(in_frustum: bool, draw_new: bool) -> (u64, u64) {
        // Dropping (if in_frustum), compacting, listing's dispatch and
        // clearing; listing's draw. Then compacting and listing again.
        let (dispatches, draws) = (3 + u64::from(in_frustum), 1);
        if draw_new {
            (dispatches + 2, draws + 1)
        } else {
            (dispatches, draws)
        }
    }

    /// Last frame's visible instances, on the device.
    pub(crate) fn visible(&self) -> VisibleSet {
        VisibleSet::Device(self.previous)
    }

    /// Makes `visible` last frame's visible instances.
    pub(crate) fn seed(&self, gpu: &mut dyn GpuCulling, visible: &VisibleSet) {
        visible.write_to(gpu, self.previous);
    }

    /// Steps 3 (when `draw_new`) and 4.
    pub(crate) fn finish(&mut self, gpu: &mut dyn GpuCulling, draw_new: bool) {
        if draw_new {
            gpu.compact(self.visible, Some(self.previous), self.newly_visible);
            gpu.draw_list(self.newly_visible);
        }
        std::mem::swap(&mut self.visible, &mut self.previous);
    }
}

/// Every instance's box and the list of every instance id, on the device:
/// what the methods testing every object each frame (`roc`, `hiz`) test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AllInstances {
    /// Every instance's box.
    pub(crate) boxes: BoxSet,
    /// Every instance id.
    pub(crate) ids: IdList,
}

impl AllInstances {
    /// Uploads the boxes and the list of `scene`'s instances.
    pub(crate) fn new(gpu: &mut dyn GpuCulling, scene: &Scene) -> Self {
        let n = scene.instances.len() as u32;
        let boxes: Vec<_> = scene.instances.iter().map(|i| i.culling_bounds()).collect();
        let ids: Vec<u32> = (0..n).collect();
        Self { boxes: gpu.create_boxes(&boxes), ids: gpu.create_list(n, &ids) }
    }
}

/// The device resources of `roc`, made on its first frame.
#[derive(Clone, Copy, Debug)]
struct Resources {
    all: AllInstances,
    temporal: TemporalSet,
}

/// `roc`: raster occlusion culling of every object against last frame's
/// visible objects (module documentation).
#[derive(Clone, Debug)]
pub struct RasterOcclusion {
    params: RocParams,
    /// The hierarchy (and instance boxes) the resources are for.
    tracked: Tracked,
    resources: Option<Resources>,
}

impl RasterOcclusion {
    /// A fresh `roc` (nothing visible yet).
    pub fn new(params: RocParams) -> Self {
        Self { params, tracked: Tracked::default(), resources: None }
    }
}

impl CullingMethod for RasterOcclusion {
    fn name(&self) -> &'static str {
        "roc"
    }

    fn needs_gpu_culling(&self) -> bool {
        true
    }

    fn prepare(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let scene = ctx.scene;
        self.tracked.keep_up(ctx.hierarchy, &mut self.resources, backend, |r, gpu, changes| {
            update_instance_boxes(gpu, r.all.boxes, scene, changes);
        });
        if self.resources.is_some() {
            return;
        }
        let Ok(gpu) = backend.gpu_culling() else { return };
        let all = AllInstances::new(gpu, ctx.scene);
        self.resources = Some(Resources { all, temporal: TemporalSet::new(gpu, ctx.scene.instances.len() as u32) });
    }

    /// Every frame: the temporal set's passes (`TemporalSet::passes`;
    /// the new draws only when exact) and the box test, a dispatch and an
    /// indirect draw: six dispatches and three draws when exact.
    fn floor_ms(&self, _: &FrameContext<'_>, model: &CostModel, _: (u32, u32), _: bool) -> f64 {
        let (dispatches, draws) = TemporalSet::passes(false, self.params.mode == RocMode::Exact);
        model.passes_ms(dispatches + 1, draws + 1, 0)
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

    /// A backend without [`GpuCulling`] (which the runner refuses first)
    /// gets view-frustum culling.
    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let (Some(r), Ok(gpu)) = (self.resources.as_mut(), backend.gpu_culling()) else {
            return ViewFrustumCulling.render(ctx, backend);
        };
        let visible = r.temporal.begin(gpu, None);
        gpu.test_boxes(r.all.boxes, r.all.ids, visible);
        r.temporal.finish(gpu, self.params.mode == RocMode::Exact);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::test_rig::{
        assert_draws_exactly, assert_refused_without_gpu_culling_and_falls_back_to_frustum_culling, culling_steps,
        method, Rig,
    };
    use crate::methods::MethodOptions;

    #[test]
    fn mode_defaults_to_exact_and_rejects_others() {
        let read = |opts: &[&str]| RocParams::from_options(&MethodOptions::parse(opts).unwrap());
        assert_eq!(read(&[]), Ok(RocParams { mode: RocMode::Exact }));
        assert_eq!(read(&["roc.mode=last"]), Ok(RocParams { mode: RocMode::Last }));
        let err = read(&["roc.mode=fast"]).unwrap_err();
        assert!(err.to_string().contains("roc.mode = fast: expected exact or last"), "{err}");
    }

    #[test]
    fn is_refused_without_gpu_culling_and_falls_back_to_frustum_culling() {
        assert_refused_without_gpu_culling_and_falls_back_to_frustum_culling("roc");
    }

    /// Each frame draws last frame's visible objects, then tests every box,
    /// then draws the newly visible: an object turning visible is drawn in
    /// that frame (`exact`), or only in the next (`last`); a hidden one is
    /// never drawn.
    #[test]
    fn draws_last_frames_visible_then_tests_every_box_then_the_newly_visible() {
        let rig = Rig::row(4);
        let all: Vec<u32> = (0..rig.scene.instances.len() as u32).collect();
        for (options, drawn_late) in [(&[][..], false), (&["roc.mode=last"][..], true)] {
            let mut mock = rig.mock().with_gpu_culling();
            mock.set_visible(2, false);
            let mut roc = method("roc", options);
            let frames = rig.run(&mut roc, &mut mock, 2);
            let mut steps = vec![("draw", vec![0, 1, 3]), ("test", all.clone())];
            if !drawn_late {
                steps.push(("draw", vec![]));
            }
            assert_eq!(culling_steps(&frames[1]), steps, "{options:?}");
            mock.set_visible(2, true);
            let turned = &rig.run(&mut roc, &mut mock, 1)[0];
            assert_draws_exactly(turned, if drawn_late { &[0, 1, 3] } else { &[0, 1, 2, 3] });
            assert_draws_exactly(&rig.run(&mut roc, &mut mock, 1)[0], &[0, 1, 2, 3]);
        }
    }

    /// Seeded, `roc` and `hiz` draw the seed first, as last frame's
    /// visible set, and give what their frame found, on the device.
    #[test]
    fn a_seed_is_drawn_first_and_the_visible_set_read_back() {
        let rig = Rig::row(4);
        for name in ["roc", "hiz"] {
            let mut mock = rig.mock().with_gpu_culling();
            mock.set_visible(2, false);
            let mut m = method(name, &[]);
            let mut drawn = crate::DrawnSet::default();
            let mut ctx = FrameContext::new(&rig.scene, &rig.hierarchy, rig.camera, &mut drawn);
            m.method.prepare(&mut ctx, &mut mock);
            m.method.seed(&ctx, &mut mock, &VisibleSet::Host(vec![true, false, false, true, false]));
            let first = rig.run(&mut m, &mut mock, 1).remove(0);
            assert_eq!(culling_steps(&first)[0], ("draw", vec![0, 3]), "{name}");
            assert_draws_exactly(&first, &[0, 1, 3]);
            let visible = m.method.visible_set(&ctx).and_then(|v| v.to_host(&mut mock));
            assert_eq!(visible, Some(vec![true, true, false, true, false]), "{name}");
        }
    }
}
