//! An object's screen silhouette (section 3.1.2, "Difficulties and
//! Optimizations"): the projection of its bounding box, which the paper
//! looks at to tell the three overlap configurations apart where two
//! objects' screen rectangles overlap and no colour channel is free
//! ("overlap conflict": both silhouettes meet the overlap region; "overlap
//! no conflict": only one does; "empty overlap": neither does).
//!
//! The silhouette of a box in front of the camera is the convex hull of its
//! 8 projected corners, whose edges are projections of box edges. A pixel
//! the object covers has its centre inside one of its triangles, so (the
//! rasterizer snapping vertices by less than
//! [`PIXEL_MARGIN`](crate::depth_pyramid::PIXEL_MARGIN)) within that margin
//! of the hull. [`Silhouette::meets`] says no for a pixel rectangle only
//! when an axis (x, y or the normal of a projected box edge) separates the
//! hull from every pixel centre of the rectangle by more than the margin,
//! so the object has no pixel there; separating axes of two convex shapes
//! are among those normals. A box reaching the near plane has no bounded
//! projection and meets every rectangle.

use super::rect::PixelRect;
use crate::depth_pyramid::{project_corner, PIXEL_MARGIN};
use crate::geometry::Aabb;
use glam::{DVec2, Mat4};

/// An object's screen rectangle and, when its box is in front of the
/// camera, its box's projected corners (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Silhouette {
    /// The pixels the object may cover ([`PixelRect::of_box`]).
    pub rect: PixelRect,
    /// The box's corners in pixels, in [`Aabb::corners`] order; `None` when
    /// the outline is unknown (the box reaches the near plane).
    corners: Option<[DVec2; 8]>,
}

impl Silhouette {
    /// The silhouette of box `b` on a `width` x `height` image through
    /// `view_projection`; `None` when it covers no pixel
    /// ([`PixelRect::of_box`]).
    pub fn of_box(view_projection: &Mat4, width: u32, height: u32, b: &Aabb) -> Option<Self> {
        let rect = PixelRect::of_box(view_projection, width, height, b)?;
        let mut corners = [DVec2::ZERO; 8];
        let projected = b
            .corners()
            .into_iter()
            .zip(&mut corners)
            .all(|(p, c)| project_corner(view_projection, width, height, p).map(|(s, _)| *c = s).is_some());
        Some(Self { rect, corners: projected.then_some(corners) })
    }

    /// A silhouette known only by its rectangle: it meets every rectangle
    /// overlapping `rect` (the paper's plain overlap test).
    pub fn rectangle(rect: PixelRect) -> Self {
        Self { rect, corners: None }
    }

    /// A silhouette with outline `corners` (in [`Aabb::corners`] order):
    /// tests draw the shapes they need.
    #[cfg(test)]
    pub(crate) fn outlined(rect: PixelRect, corners: [DVec2; 8]) -> Self {
        Self { rect, corners: Some(corners) }
    }

    /// Whether the object may cover a pixel of `r` (module documentation):
    /// false only when it certainly covers none.
    pub fn meets(&self, r: &PixelRect) -> bool {
        let Some(inside) = self.rect.intersect(r) else { return false };
        let Some(corners) = &self.corners else { return true };
        // The pixel centres of `inside` span [x0 + 0.5, x1 - 0.5] x [y0 + 0.5, y1 - 0.5].
        let lo = DVec2::new(f64::from(inside.x0), f64::from(inside.y0)) + 0.5;
        let hi = DVec2::new(f64::from(inside.x1), f64::from(inside.y1)) - 0.5;
        let centres = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        let separated = |axis: DVec2| {
            let length = axis.length();
            if length == 0.0 || !length.is_finite() {
                return false;
            }
            let span = |points: &mut dyn Iterator<Item = f64>| {
                points.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| (a.min(d), b.max(d)))
            };
            let (h0, h1) = span(&mut corners.iter().map(|c| c.dot(axis) / length));
            let (r0, r1) = span(&mut centres.iter().map(|c| c.dot(axis) / length));
            h1 + PIXEL_MARGIN < r0 || r1 + PIXEL_MARGIN < h0
        };
        let edges =
            (0..8usize).flat_map(|i| [1, 2, 4].into_iter().filter(move |b| i & b == 0).map(move |b| (i, i | b)));
        let mut axes = [DVec2::X, DVec2::Y].into_iter().chain(edges.map(|(i, j)| (corners[j] - corners[i]).perp()));
        !axes.any(separated)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use glam::{Mat4, Vec3};
    use proptest::prelude::*;

    /// An orthographic view of a 64 x 64 image turned 45 degrees about the
    /// view axis: the unit cube at the origin is a diamond, its corners
    /// on the image's edge centres.
    pub(crate) fn diamond_view() -> Mat4 {
        let s = std::f32::consts::FRAC_1_SQRT_2;
        Mat4::orthographic_rh(-s, s, -s, s, -10.0, 10.0)
            * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4)
            * Mat4::from_translation(Vec3::new(-0.5, -0.5, 0.0))
    }

    #[test]
    fn a_diamond_misses_the_corners_of_its_rectangle() {
        let cube = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let s = Silhouette::of_box(&diamond_view(), 64, 64, &cube).unwrap();
        assert_eq!(s.rect, PixelRect::new(0, 0, 64, 64));
        assert!(s.meets(&PixelRect::new(28, 28, 36, 36)));
        assert!(!s.meets(&PixelRect::new(0, 0, 12, 12)));
        assert!(!s.meets(&PixelRect::new(52, 52, 64, 64)));
        // The pixel just inside the diamond's edge is met.
        assert!(s.meets(&PixelRect::new(0, 31, 1, 33)));
        assert!(!s.meets(&PixelRect::new(70, 0, 80, 10)));
        assert!(Silhouette::rectangle(s.rect).meets(&PixelRect::new(0, 0, 12, 12)));
    }

    proptest! {
        /// Where the silhouette does not meet a rectangle, no point of the
        /// box projects onto the span of its pixel centres.
        #[test]
        fn a_missed_rectangle_holds_no_projected_point_of_the_box(
            min in (-2.0f32..2.0, -2.0f32..2.0, -9.0f32..-3.0),
            size in (0.1f32..2.0, 0.1f32..2.0, 0.1f32..2.0),
            (x0, y0, w, h) in (0u32..64, 0u32..64, 1u32..24, 1u32..24),
            turn in 0.0f32..6.3,
        ) {
            let view = Mat4::perspective_rh(1.2, 1.0, 0.1, 100.0)
                * Mat4::from_rotation_z(turn)
                * Mat4::from_rotation_x(turn * 0.3);
            let b = Aabb::new(Vec3::from(min), Vec3::from(min) + Vec3::from(size));
            let Some(s) = Silhouette::of_box(&view, 64, 64, &b) else { return Ok(()) };
            let r = PixelRect::new(x0, y0, x0 + w, y0 + h);
            if s.meets(&r) {
                return Ok(());
            }
            let Some(inside) = s.rect.intersect(&r) else { return Ok(()) };
            let steps = 6;
            for i in 0..=steps {
                for j in 0..=steps {
                    for k in 0..=steps {
                        let t = Vec3::new(i as f32, j as f32, k as f32) / steps as f32;
                        let p = b.min + (b.max - b.min) * t;
                        let (at, _) = project_corner(&view, 64, 64, p).expect("in front of the camera");
                        let held = at.x >= f64::from(inside.x0) + 0.5 && at.x <= f64::from(inside.x1) - 0.5
                            && at.y >= f64::from(inside.y0) + 0.5 && at.y <= f64::from(inside.y1) - 0.5;
                        prop_assert!(!held, "{:?} misses {:?}, but {:?} projects to {:?}", s, inside, p, at);
                    }
                }
            }
        }
    }
}
