//! Two-phase Hi-Z occlusion culling (`hiz`), as GPU-driven renderers ship
//! it: zeux's niagara (early and late passes against a depth pyramid),
//! nvpro's `gl_occlusion_culling` in its HiZ mode and Bevy's
//! `OcclusionCulling` (issue 18, item 1). Where `roc` rasterizes every
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
//!    fits (default 2, the field's 2x2; boxes outside the frustum set
//!    nothing, boxes at the eye are visible untested), setting this frame's
//!    visibility;
//! 4. draw the instances visible now that were not drawn in step 1, and keep
//!    the visible set for the next frame.
//!
//! Exact: an instance with a pixel in the final image has there a depth no
//! farther than the early pass's depth (which draws a subset of the scene),
//! so its box, which contains it and is pulled towards the eye, passes the
//! full-resolution box test at that pixel; the pyramid test never hides a
//! box that test finds visible (the proof is `depth_pyramid`'s), so the
//! instance is drawn in step 1 or 4.

use super::roc::{AllInstances, TemporalSet};
use super::vfc::ViewFrustumCulling;
use super::{CullingMethod, FrameContext, OptionError, OptionReader};
use crate::backend::Backend;
use crate::gpu_culling::Pyramid;

/// Parameters of `hiz`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HizParams {
    /// `hiz.texels`: most texels per axis a box test reads, 1 to 16
    /// (default 2).
    pub texels: u32,
}

impl HizParams {
    /// Reads `hiz.texels`.
    pub fn read(r: &mut OptionReader) -> Result<Self, OptionError> {
        Ok(Self { texels: r.get("texels", 2, "an integer from 1 to 16", |t| (1..=16).contains(&t))? })
    }
}

/// The device resources of `hiz`, made on its first frame.
#[derive(Clone, Copy, Debug)]
struct Resources {
    all: AllInstances,
    pyramid: Pyramid,
    temporal: TemporalSet,
}

/// `hiz`: two-phase occlusion culling against a depth pyramid (module
/// documentation).
#[derive(Clone, Debug)]
pub struct TwoPhaseHiZ {
    params: HizParams,
    resources: Option<Resources>,
}

impl TwoPhaseHiZ {
    /// A fresh `hiz` (nothing visible yet).
    pub fn new(params: HizParams) -> Self {
        Self { params, resources: None }
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
        if self.resources.is_some() {
            return;
        }
        let Ok(gpu) = backend.gpu_culling() else { return };
        if gpu.pyramid_support().is_err() {
            return;
        }
        self.resources = Some(Resources {
            all: AllInstances::new(gpu, ctx.scene),
            pyramid: gpu.create_pyramid(),
            temporal: TemporalSet::new(gpu, ctx.scene.instances.len() as u32),
        });
    }

    /// A backend without [`GpuCulling`](crate::GpuCulling) or depth pyramids (which the runner
    /// refuses first) gets view-frustum culling.
    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let (Some(r), Ok(gpu)) = (self.resources.as_mut(), backend.gpu_culling()) else {
            return ViewFrustumCulling.render(ctx, backend);
        };
        let visible = r.temporal.begin(gpu, Some(r.all.boxes));
        gpu.build_pyramid(r.pyramid);
        gpu.test_boxes_pyramid(r.all.boxes, r.all.ids, r.pyramid, self.params.texels, visible);
        r.temporal.finish(gpu, true);
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
    fn texels_default_to_two_and_stay_in_range() {
        let read = |opts: &[&str]| HizParams::read(&mut MethodOptions::parse(opts).unwrap().for_method("hiz"));
        assert_eq!(read(&[]), Ok(HizParams { texels: 2 }));
        assert_eq!(read(&["hiz.texels=8"]), Ok(HizParams { texels: 8 }));
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
}
