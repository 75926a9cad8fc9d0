//! The screen-space occupancy map of Staneker, Bartz and Straßer (section 3):
//! a coarse bit mask over the screen, one bit per cell, rows of `u64` words
//! (the "cache-optimized bit-field" of their earlier paper), with the
//! conservative screen rectangle of a box as its only way in.
//!
//! The map lives in normalized screen coordinates, so its resolution is
//! independent of the frame's pixel size: a cell may span many pixels or, for
//! a map finer than the frame, less than one. Both are sound because every
//! rectangle is rounded outward to whole cells.

use crate::geometry::Aabb;
use glam::{Mat4, Vec2, Vec4};

/// A rectangle of map cells, half-open: columns `x0..x1`, rows `y0..y1`,
/// row 0 at the top of the screen. Empty when `x0 >= x1` or `y0 >= y1`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CellRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl CellRect {
    /// True when the rectangle holds no cell.
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }
}

/// Normalized-device-coordinate bounds (`x`, `y` in `[-1, 1]` on screen, `y`
/// up) of the part of `b` in front of the near plane, or `None` when all of
/// `b` lies behind it.
///
/// The projection of a convex body is the convex hull of its projected
/// vertices, so the box is clipped to the near plane (`z >= 0` in clip space,
/// where `w >= near > 0`) first: its vertices are the corners in front plus
/// the points where its twelve edges cross the plane. The result is the exact
/// bounding rectangle (up to `f32` rounding), also for a box that reaches
/// behind the eye, where projecting the eight corners alone would be wrong.
pub fn screen_bounds(view_projection: &Mat4, b: &Aabb) -> Option<(Vec2, Vec2)> {
    let clip = b.corners().map(|c| *view_projection * c.extend(1.0));
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    let mut add = |c: Vec4| {
        let p = Vec2::new(c.x, c.y) / c.w;
        lo = lo.min(p);
        hi = hi.max(p);
    };
    for (i, &c) in clip.iter().enumerate() {
        if c.z >= 0.0 {
            add(c);
        }
        // Corners `i` and `i | axis` differ on one axis: each edge once.
        for axis in [1, 2, 4] {
            let d = clip[i | axis];
            if i & axis == 0 && (c.z >= 0.0) != (d.z >= 0.0) {
                add(c + (d - c) * (c.z / (c.z - d.z)));
            }
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// A bit per screen cell; a set bit means "covered" (stage 1: by drawn
/// geometry; stage 2: by a box already in this round's query list).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccupancyBits {
    width: u32,
    height: u32,
    words_per_row: usize,
    bits: Vec<u64>,
}

impl OccupancyBits {
    /// An all-clear map of `width` x `height` cells (both at least 1).
    pub fn new(width: u32, height: u32) -> Self {
        assert!(width >= 1 && height >= 1, "an occupancy map needs at least one cell");
        let words_per_row = width.div_ceil(64) as usize;
        Self { width, height, words_per_row, bits: vec![0; words_per_row * height as usize] }
    }

    /// Columns of cells.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Rows of cells.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Clears every bit.
    pub fn clear(&mut self) {
        self.bits.fill(0);
    }

    /// The cells touched by the normalized-device-coordinate rectangle
    /// `ndc` (as from [`screen_bounds`]), rounded outward and clipped to the
    /// screen; a degenerate rectangle still covers the cell it lies in.
    pub fn cells(&self, (lo, hi): (Vec2, Vec2)) -> CellRect {
        let (w, h) = (self.width as f32, self.height as f32);
        // Columns grow with x; rows grow downwards, so y flips.
        let span = |a: f32, b: f32, n: f32| {
            let (a, b) = ((a + 1.0) * 0.5 * n, (b + 1.0) * 0.5 * n);
            let first = a.floor().clamp(0.0, n);
            let last = b.ceil().max(a.floor() + 1.0).clamp(0.0, n);
            (first as u32, last as u32)
        };
        let (x0, x1) = span(lo.x, hi.x, w);
        let (y0, y1) = span(-hi.y, -lo.y, h);
        CellRect { x0, y0, x1, y1 }
    }

    /// The cells of box `b` seen through `view_projection`: the whole part
    /// of the box in front of the near plane (empty if there is none).
    pub fn rect_of(&self, view_projection: &Mat4, b: &Aabb) -> CellRect {
        screen_bounds(view_projection, b).map_or(CellRect::default(), |ndc| self.cells(ndc))
    }

    /// Sets every bit under `r`.
    pub fn mark(&mut self, r: CellRect) {
        for (word, mask) in self.spans(r) {
            self.bits[word] |= mask;
        }
    }

    /// True when some bit under `r` is clear: the rectangle reaches screen
    /// space that nothing has covered yet. False for an empty rectangle.
    pub fn is_any_clear(&self, r: CellRect) -> bool {
        self.spans(r).any(|(word, mask)| self.bits[word] & mask != mask)
    }

    /// True when some bit under `r` is set: the rectangle overlaps what is
    /// already covered. False for an empty rectangle.
    pub fn is_any_set(&self, r: CellRect) -> bool {
        self.spans(r).any(|(word, mask)| self.bits[word] & mask != 0)
    }

    /// The words under `r` with the mask of their bits inside it, row by
    /// row: a row costs one step per 64 columns, never one per cell.
    fn spans(&self, r: CellRect) -> impl Iterator<Item = (usize, u64)> {
        let (x0, x1) = (r.x0.min(self.width), r.x1.min(self.width));
        let (y0, y1) = (r.y0.min(self.height), r.y1.min(self.height));
        let words = if x0 < x1 { x0 / 64..(x1 - 1) / 64 + 1 } else { 0..0 };
        let stride = self.words_per_row;
        (y0..y1).flat_map(move |y| {
            words.clone().map(move |w| {
                let lo = x0.max(w * 64) - w * 64;
                let hi = x1.min(w * 64 + 64) - w * 64;
                (y as usize * stride + w as usize, (u64::MAX >> (64 - (hi - lo))) << lo)
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use glam::Vec3;
    use proptest::prelude::*;

    /// The map with one `bool` per cell: the per-bit reference.
    struct Naive {
        width: u32,
        cells: Vec<bool>,
    }

    impl Naive {
        fn cells_of(&self, r: CellRect) -> impl Iterator<Item = usize> + '_ {
            (r.y0..r.y1).flat_map(move |y| (r.x0..r.x1).map(move |x| (y * self.width + x) as usize))
        }
    }

    fn rect(w: u32, h: u32) -> impl Strategy<Value = CellRect> {
        (0..=w, 0..=w, 0..=h, 0..=h).prop_map(|(a, b, c, d)| CellRect {
            x0: a.min(b),
            x1: a.max(b),
            y0: c.min(d),
            y1: c.max(d),
        })
    }

    proptest! {
        /// After any sequence of marks, both tests agree with the per-bit
        /// reference on any rectangle, for widths across word boundaries.
        #[test]
        fn matches_the_per_bit_reference(
            (w, h, marks, probes) in (1u32..200, 1u32..40).prop_flat_map(|(w, h)| {
                (Just(w), Just(h), prop::collection::vec(rect(w, h), 0..8), prop::collection::vec(rect(w, h), 1..16))
            })
        ) {
            let mut map = OccupancyBits::new(w, h);
            let mut naive = Naive { width: w, cells: vec![false; (w * h) as usize] };
            for &m in &marks {
                map.mark(m);
                for i in naive.cells_of(m).collect::<Vec<_>>() {
                    naive.cells[i] = true;
                }
            }
            for &p in &probes {
                prop_assert_eq!(map.is_any_clear(p), naive.cells_of(p).any(|i| !naive.cells[i]), "{:?}", p);
                prop_assert_eq!(map.is_any_set(p), naive.cells_of(p).any(|i| naive.cells[i]), "{:?}", p);
            }
        }

        /// The cell rectangle of a box holds the cell of every point of the
        /// box that projects onto the screen in front of the near plane.
        #[test]
        fn box_rect_holds_every_projected_point(
            x in -20.0f32..20.0, y in -5.0f32..5.0, z in -30.0f32..8.0,
            sx in 0.01f32..12.0, sy in 0.01f32..6.0, sz in 0.01f32..12.0,
        ) {
            let cam = camera();
            let vp = cam.view_projection();
            let b = Aabb::new(Vec3::new(x, y, z), Vec3::new(x + sx, y + sy, z + sz));
            let map = OccupancyBits::new(64, 48);
            let r = map.rect_of(&vp, &b);
            for i in 0..125 {
                let t = Vec3::new((i % 5) as f32, ((i / 5) % 5) as f32, (i / 25) as f32) * 0.25;
                let c = vp * (b.min + (b.max - b.min) * t).extend(1.0);
                if c.z < 0.0 || c.x.abs() > c.w || c.y.abs() > c.w {
                    continue;
                }
                let cell = map.cells((Vec2::new(c.x, c.y) / c.w, Vec2::new(c.x, c.y) / c.w));
                prop_assert!(
                    r.x0 <= cell.x0 && cell.x1 <= r.x1 && r.y0 <= cell.y0 && cell.y1 <= r.y1,
                    "{:?} outside {:?}", cell, r
                );
            }
        }
    }

    fn camera() -> Camera {
        Camera {
            position: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::Y,
            fov_y_deg: 60.0,
            aspect: 4.0 / 3.0,
            near: 0.1,
            far: 100.0,
            matrices: None,
        }
    }

    #[test]
    fn marks_and_tests_across_words() {
        let mut map = OccupancyBits::new(130, 3);
        let r = CellRect { x0: 60, x1: 129, y0: 1, y1: 2 };
        assert!(map.is_any_clear(r) && !map.is_any_set(r));
        map.mark(r);
        assert!(!map.is_any_clear(r) && map.is_any_set(r));
        assert!(map.is_any_clear(CellRect { x0: 59, x1: 61, y0: 1, y1: 2 }));
        assert!(map.is_any_clear(CellRect { x0: 60, x1: 130, y0: 1, y1: 2 }));
        assert!(!map.is_any_set(CellRect { x0: 0, x1: 130, y0: 0, y1: 1 }));
        assert!(!map.is_any_clear(CellRect::default()) && !map.is_any_set(CellRect::default()));
        map.clear();
        assert!(!map.is_any_set(r));
    }

    #[test]
    fn box_rects_are_placed_and_clipped() {
        let cam = camera();
        let vp = cam.view_projection();
        let map = OccupancyBits::new(64, 48);
        // Straight ahead: a small box around the view axis covers the centre.
        let centre = map.rect_of(&vp, &Aabb::new(Vec3::new(-0.1, 0.9, -5.0), Vec3::new(0.1, 1.1, -4.9)));
        assert!(centre.x0 <= 32 && 32 < centre.x1 && centre.y0 <= 24 && 24 < centre.y1, "{centre:?}");
        assert!(centre.x1 - centre.x0 < 8, "{centre:?}");
        // A box right of the view axis lands in the right half.
        let right = map.rect_of(&vp, &Aabb::new(Vec3::new(1.0, 0.9, -5.0), Vec3::new(1.5, 1.1, -4.9)));
        assert!(right.x0 >= 32, "{right:?}");
        // Entirely behind the eye: nothing.
        assert!(map.rect_of(&vp, &Aabb::new(Vec3::new(-1.0, 0.0, 6.0), Vec3::new(1.0, 2.0, 7.0))).is_empty());
        // Around the eye: the whole screen.
        let around = map.rect_of(&vp, &Aabb::new(Vec3::new(-1.0, 0.0, 4.0), Vec3::new(1.0, 2.0, 6.0)));
        assert_eq!(around, CellRect { x0: 0, y0: 0, x1: 64, y1: 48 });
        // A floor reaching behind the eye covers the bottom rows, not the top.
        let floor = map.rect_of(&vp, &Aabb::new(Vec3::new(-50.0, -0.1, -50.0), Vec3::new(50.0, 0.0, 50.0)));
        assert_eq!((floor.y1, floor.x0, floor.x1), (48, 0, 64));
        assert!(floor.y0 >= 24, "{floor:?}");
    }
}
