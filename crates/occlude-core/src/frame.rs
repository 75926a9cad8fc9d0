//! The frame protocol and the correctness rule, as every caller of a
//! method uses them: `occlude bench` and the viewer, the tests, and a
//! renderer of one's own.
//!
//! A frame of a method is [`render_frame`]: the method's preparation
//! (outside the frame's clock), `Backend::begin_frame`, the method's
//! rendering and `Backend::end_frame`. The correctness rule
//! (`docs/design.md`) compares a method's depth image with view-frustum
//! culling's, bit for bit: [`differing_pixels`] counts the pixels that
//! differ.

use crate::backend::Backend;
use crate::camera::Camera;
use crate::hierarchy::Hierarchy;
use crate::methods::{CullingMethod, DrawnSet, FrameContext};
use crate::scene::Scene;
use crate::stats::FrameStats;

/// Renders one frame of `method` on `backend` (prepare, `begin_frame`,
/// render, `end_frame`) and returns its statistics. `drawn` is the method's
/// per-frame draw bookkeeping, kept by the caller from frame to frame so
/// that its memory is reused.
pub fn render_frame(
    method: &mut dyn CullingMethod,
    backend: &mut dyn Backend,
    scene: &Scene,
    hierarchy: &Hierarchy,
    camera: &Camera,
    drawn: &mut DrawnSet,
) -> FrameStats {
    let mut ctx = FrameContext::new(scene, hierarchy, *camera, drawn);
    method.prepare(&mut ctx, backend);
    backend.begin_frame(camera);
    method.render(&mut ctx, backend);
    let stats = backend.end_frame();
    method.finish_frame(&stats);
    stats
}

/// Pixels whose depth bits differ between two depth images of the same
/// size (from [`Instruments::depth_image`](crate::Instruments::depth_image)):
/// 0 for every conservative method against view-frustum culling. Images of
/// different lengths differ in every pixel one has and the other lacks.
pub fn differing_pixels(a: &[f32], b: &[f32]) -> u64 {
    let common = a.iter().zip(b).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
    (common + a.len().abs_diff(b.len())) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differing_pixels_compares_bits_and_lengths() {
        assert_eq!(differing_pixels(&[0.5, 1.0], &[0.5, 1.0]), 0);
        // -0.0 == 0.0 and NaN != NaN as floats; as bits the first differ and
        // the same NaN does not.
        assert_eq!(differing_pixels(&[0.0, f32::NAN], &[-0.0, f32::NAN]), 1);
        assert_eq!(differing_pixels(&[0.5, 1.0, 1.0], &[0.5]), 2);
    }
}
