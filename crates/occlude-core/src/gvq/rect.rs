//! Pixel rectangles: an object's screen region and the pieces its region
//! set is split into (section 3.1.2).

use crate::camera::Frustum;
use crate::depth_pyramid::{box_footprint, Footprint};
use crate::geometry::Aabb;
use glam::Mat4;

/// A half-open rectangle of pixels: columns `x0..x1`, rows `y0..y1`, row 0
/// at the top of the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelRect {
    /// The rectangle `x0..x1` x `y0..y1`.
    pub fn new(x0: u32, y0: u32, x1: u32, y1: u32) -> Self {
        Self { x0, y0, x1, y1 }
    }

    /// The pixel rectangle of `b` on a `width` x `height` image through
    /// `view_projection`: every pixel whose centre a triangle inside `b`
    /// can cover lies in it (`depth_pyramid::box_footprint`'s margin is
    /// larger than the rasterizer's vertex snapping). A box in the view
    /// frustum reaching the near plane gets the whole image; `None` when
    /// the box is outside the frustum or no pixel centre can be covered.
    pub fn of_box(view_projection: &Mat4, width: u32, height: u32, b: &Aabb) -> Option<Self> {
        if !Frustum::from_view_projection(view_projection).intersects(b) {
            return None;
        }
        match box_footprint(view_projection, width, height, b) {
            Footprint::Near => (width > 0 && height > 0).then(|| Self::new(0, 0, width, height)),
            Footprint::Empty => None,
            Footprint::Rect(r) => Some(Self::new(r.x0, r.y0, r.x1 + 1, r.y1 + 1)),
        }
    }

    /// True when the rectangle holds no pixel.
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    /// Pixels in the rectangle.
    pub fn area(&self) -> u64 {
        if self.is_empty() {
            0
        } else {
            u64::from(self.x1 - self.x0) * u64::from(self.y1 - self.y0)
        }
    }

    /// Whether pixel `(x, y)` lies in the rectangle.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// The pixels both rectangles hold, `None` when there are none (the
    /// paper's overlap test: two objects conflict when this is `Some`).
    pub fn intersect(&self, o: &Self) -> Option<Self> {
        let r = Self::new(self.x0.max(o.x0), self.y0.max(o.y0), self.x1.min(o.x1), self.y1.min(o.y1));
        (!r.is_empty()).then_some(r)
    }

    /// The rest of `self` without `cut`, as up to four disjoint rectangles
    /// (the full-width bands above and below `cut`, then the parts left and
    /// right of it): figure 3's split.
    pub fn subtract(&self, cut: &Self) -> Vec<Self> {
        let Some(c) = self.intersect(cut) else { return vec![*self] };
        [
            Self::new(self.x0, self.y0, self.x1, c.y0),
            Self::new(self.x0, c.y1, self.x1, self.y1),
            Self::new(self.x0, c.y0, c.x0, c.y1),
            Self::new(c.x1, c.y0, self.x1, c.y1),
        ]
        .into_iter()
        .filter(|r| !r.is_empty())
        .collect()
    }

    /// The union of two rectangles sharing a whole edge (so that the union
    /// is a rectangle), else `None`: figure 3's merge.
    pub fn join(&self, o: &Self) -> Option<Self> {
        let side_by_side = self.y0 == o.y0 && self.y1 == o.y1 && (self.x1 == o.x0 || o.x1 == self.x0);
        let stacked = self.x0 == o.x0 && self.x1 == o.x1 && (self.y1 == o.y0 || o.y1 == self.y0);
        (side_by_side || stacked)
            .then(|| Self::new(self.x0.min(o.x0), self.y0.min(o.y0), self.x1.max(o.x1), self.y1.max(o.y1)))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use glam::Vec3;
    use proptest::prelude::*;

    /// A rectangle within about 80 x 80 pixels, or (one in ten) none.
    pub(crate) fn rect_strategy() -> impl Strategy<Value = Option<PixelRect>> {
        prop_oneof![
            1 => Just(None),
            9 => (0u32..50, 0u32..50, 1u32..30, 1u32..30).prop_map(|(x, y, w, h)| Some(PixelRect::new(x, y, x + w, y + h))),
        ]
    }

    #[test]
    fn subtract_partitions_the_rectangle() {
        let a = PixelRect::new(0, 0, 10, 8);
        let cut = PixelRect::new(3, 2, 6, 12);
        let rest = a.subtract(&cut);
        assert_eq!(rest.len(), 3);
        let inside = a.intersect(&cut).unwrap();
        assert_eq!(rest.iter().map(PixelRect::area).sum::<u64>() + inside.area(), a.area());
        for (i, r) in rest.iter().enumerate() {
            assert!(r.intersect(&cut).is_none());
            assert!(rest[i + 1..].iter().all(|s| s.intersect(r).is_none()));
        }
        assert_eq!(a.subtract(&PixelRect::new(20, 20, 30, 30)), vec![a]);
        assert!(a.subtract(&PixelRect::new(0, 0, 99, 99)).is_empty());
    }

    #[test]
    fn join_needs_a_whole_shared_edge() {
        let a = PixelRect::new(0, 0, 4, 4);
        assert_eq!(a.join(&PixelRect::new(4, 0, 9, 4)), Some(PixelRect::new(0, 0, 9, 4)));
        assert_eq!(a.join(&PixelRect::new(0, 4, 4, 5)), Some(PixelRect::new(0, 0, 4, 5)));
        assert_eq!(a.join(&PixelRect::new(4, 1, 9, 4)), None);
        assert_eq!(a.join(&PixelRect::new(5, 0, 9, 4)), None);
    }

    #[test]
    fn a_box_in_front_of_the_camera_gets_its_pixels_and_one_behind_none() {
        let vp = Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0) * Mat4::look_at_rh(Vec3::ZERO, -Vec3::Z, Vec3::Y);
        let front = Aabb::new(Vec3::new(-0.5, -0.5, -5.5), Vec3::new(0.5, 0.5, -4.5));
        let r = PixelRect::of_box(&vp, 64, 64, &front).unwrap();
        assert!(r.contains(32, 32) && !r.contains(0, 0));
        let behind = Aabb::new(Vec3::new(-0.5, -0.5, 4.5), Vec3::new(0.5, 0.5, 5.5));
        assert_eq!(PixelRect::of_box(&vp, 64, 64, &behind), None);
        let around = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        assert_eq!(PixelRect::of_box(&vp, 64, 64, &around), Some(PixelRect::new(0, 0, 64, 64)));
    }
}
