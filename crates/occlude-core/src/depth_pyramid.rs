//! The depth pyramid of two-phase Hi-Z culling and the test of a box against
//! it: the construction and level selection every backend mirrors (the CPU
//! here is the soft backend's device and the reference of the wgpu shaders).
//! The issue it follows is the field's recurring false culling at sizes that
//! are not powers of two and at levels too fine for a box's footprint (Bevy
//! issues #14062 and #14042; niagara's fix: a level from the footprint's size
//! and a check of the finer level). Here neither can happen, by construction:
//!
//! **Construction.** Level 0 is the depth image itself (`W` x `H`). Level
//! `k + 1` has `ceil(w_k / 2)` x `ceil(h_k / 2)` texels, and its texel
//! `(x, y)` is the maximum of the level-`k` texels `(2x + i, 2y + j)`,
//! `i, j` in `{0, 1}`, that exist (a 2x2 reduction whose last row or column
//! may have a single texel). The levels stop at 1x1. By induction on `k`,
//! texel `(x, y)` of level `k` is the maximum depth of the pixels `(px, py)`
//! with `px >> k == x` and `py >> k == y`: true at level 0; a level-`k + 1`
//! texel reduces the level-`k` texels `x'` with `x' >> 1 == x`, whose pixels
//! are those with `px >> (k + 1) == x`; and every level-`k` texel `x' <
//! w_k` has its parent `x' >> 1 < ceil(w_k / 2)`, so no pixel is left out,
//! whatever the parity of the size.
//!
//! **Footprint.** A box (the padded query proxy, `query_box::padded`) is
//! projected from its 8 corners exactly as the rasterizer projects a query
//! box's vertices: clip coordinates in `f32` from the view-projection matrix,
//! depth pulled towards the eye by
//! [`QUERY_DEPTH_BIAS`], then divided in `f64`. A box with a corner on or
//! behind the near plane (clip `z <= 0` or `w <= 0`) is visible untested (the
//! rasterizer would clip it, and its projection is unbounded). Otherwise the
//! box's front faces cover only pixel centres inside the bounding rectangle of
//! the projected corners; the rasterizer snaps vertices to 1/256 pixel, so the
//! rectangle is grown by [`PIXEL_MARGIN`] (more than the snap) before its
//! pixel range `[x0, x1] x [y0, y1]` (centres inside, clamped to the image)
//! is taken. The box's depth at any covered pixel is an interpolation of its
//! corners' depths, so no less than their minimum; the rasterizer evaluates
//! that interpolation in `f32`, and [`DEPTH_SLACK`] below the minimum covers
//! its rounding. A box whose range is empty covers no pixel centre.
//!
//! **Selection.** Any level `k` works if the test fetches every texel from
//! `(x0 >> k, y0 >> k)` to `(x1 >> k, y1 >> k)`: by the construction their
//! pixels include the whole range, so their maximum is at least the depth of
//! every pixel the box covers. The level chosen is the finest at which that
//! is at most `reach` x `reach` texels (`(x1 >> k) - (x0 >> k) < reach`, the
//! same in `y`; `reach` 2 is the field's usual 2x2, larger ones read more
//! texels of a finer level and cull more); it exists because the last level
//! is 1x1. Fetching by index rather than
//! by a sampler's footprint is what makes a too-fine level impossible: a
//! finer level only costs more texels, never a missed one.
//!
//! **Test.** The box is visible when its nearest depth (less the slack) is in
//! front of the maximum it fetched (`<`, the depth test of query boxes).
//! Whenever the full-resolution box test finds a pixel where the box passes,
//! that pixel lies in the range and its depth is at most the fetched maximum,
//! while the box's depth there is at least the nearest depth: the pyramid
//! test says visible. `occlude-soft`'s property tests check this against its
//! exact rasterizer on random depth images at odd sizes.
//!
//! [`tested_levels`] names the level each box of a pyramid test reads, by
//! the same footprint and selection, for views of the test (`occlude
//! view`'s pyramid-level colours, through `recording::RecordingBackend`).

use crate::camera::Camera;
use crate::geometry::Aabb;
use crate::query_box::{padded, QUERY_DEPTH_BIAS};
use glam::{DVec2, Mat4, Vec3};

/// How far beyond its projected corners a box's pixel range reaches, in
/// pixels: more than the rasterizer's 1/512-pixel vertex snapping.
pub const PIXEL_MARGIN: f64 = 1.0 / 64.0;

/// How far below its corners' minimum the nearest depth of a box is taken,
/// in normalized depth: the `f32` rounding of the rasterizer's depth plane.
pub const DEPTH_SLACK: f32 = QUERY_DEPTH_BIAS;

/// The sizes of a pyramid's levels over a `width` x `height` image, level 0
/// first, down to 1x1 (each level the previous one halved, rounded up).
pub fn level_sizes(width: u32, height: u32) -> Vec<(u32, u32)> {
    let mut sizes = vec![(width.max(1), height.max(1))];
    while let Some(&(w, h)) = sizes.last().filter(|&&(w, h)| w > 1 || h > 1) {
        sizes.push((w.div_ceil(2), h.div_ceil(2)));
    }
    sizes
}

/// What a box covers on the screen, for a pyramid test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Footprint {
    /// A corner is on or behind the near plane: visible without a test.
    Near,
    /// No pixel centre inside the image: hidden.
    Empty,
    /// The pixels the box may cover and its nearest depth.
    Rect(ScreenRect),
}

/// An inclusive pixel range and the nearest depth a box has in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenRect {
    /// First column.
    pub x0: u32,
    /// First row (row 0 at the top).
    pub y0: u32,
    /// Last column.
    pub x1: u32,
    /// Last row.
    pub y1: u32,
    /// Nearest normalized depth of the box, biased and less [`DEPTH_SLACK`].
    pub depth: f32,
}

/// Point `p` seen through `view_projection` on a `width` x `height` image,
/// as the module documentation projects a box corner: its pixel position
/// (row 0 at the top) and biased normalized depth, or `None` when it is on
/// or behind the near plane (or not a number).
pub fn project_corner(view_projection: &Mat4, width: u32, height: u32, p: Vec3) -> Option<(DVec2, f64)> {
    let v = *view_projection * p.extend(1.0);
    let z = v.z - QUERY_DEPTH_BIAS * v.w;
    // Written so that NaN counts as reaching the near plane.
    if !(z > 0.0 && v.w > 0.0) {
        return None;
    }
    let (cw, cz) = (f64::from(v.w), f64::from(z));
    let (w, h) = (f64::from(width), f64::from(height));
    let s = DVec2::new((f64::from(v.x) / cw + 1.0) * 0.5 * w, (1.0 - f64::from(v.y) / cw) * 0.5 * h);
    Some((s, cz / cw))
}

/// The footprint of `b` (already padded as a query box) seen through
/// `view_projection` on a `width` x `height` image (module documentation).
pub fn box_footprint(view_projection: &Mat4, width: u32, height: u32, b: &Aabb) -> Footprint {
    let (w, h) = (f64::from(width), f64::from(height));
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    let mut depth = f64::INFINITY;
    for p in b.corners() {
        let Some((s, d)) = project_corner(view_projection, width, height, p) else { return Footprint::Near };
        lo = lo.min(s);
        hi = hi.max(s);
        depth = depth.min(d);
    }
    // Pixel `p` is covered only if its centre `p + 0.5` is in [lo, hi].
    let first = (lo - 0.5 - PIXEL_MARGIN).ceil().max(DVec2::ZERO);
    let last = (hi - 0.5 + PIXEL_MARGIN).floor().min(DVec2::new(w - 1.0, h - 1.0));
    if !(first.x <= last.x && first.y <= last.y) {
        return Footprint::Empty;
    }
    Footprint::Rect(ScreenRect {
        x0: first.x as u32,
        y0: first.y as u32,
        x1: last.x as u32,
        y1: last.y as u32,
        depth: depth as f32 - DEPTH_SLACK,
    })
}

/// The finest level at which `rect` spans at most `reach` x `reach` texels
/// (`reach` >= 1).
pub fn select_level(rect: &ScreenRect, reach: u32) -> u32 {
    let mut k = 0;
    while (rect.x1 >> k) - (rect.x0 >> k) >= reach || (rect.y1 >> k) - (rect.y0 >> k) >= reach {
        k += 1;
    }
    k
}

impl Footprint {
    /// The pyramid level a test of this footprint reads at most `reach` x
    /// `reach` texels of ([`select_level`]); `None` for `Near` and `Empty`,
    /// which the test answers without reading any.
    pub fn level(&self, reach: u32) -> Option<u32> {
        match self {
            Footprint::Rect(rect) => Some(select_level(rect, reach)),
            Footprint::Near | Footprint::Empty => None,
        }
    }
}

/// Per box of `boxes` (unpadded, as a method gives them to
/// `GpuCulling::create_boxes`), the level a pyramid box test
/// (`GpuCulling::test_boxes_pyramid`, reading at most `reach` x `reach`
/// texels) of `camera`'s view on a `width` x `height` image reads: the
/// level of [`DepthPyramid::test`] for the padded box's [`box_footprint`].
/// `None` where the test reads no level: an empty box, and a padded box
/// (the test's rules, as the backends apply them) touching the near region
/// (visible untested), outside the frustum (not tested), with a corner at
/// the near plane or covering no pixel centre.
pub fn tested_levels(camera: &Camera, width: u32, height: u32, boxes: &[Aabb], reach: u32) -> Vec<Option<u32>> {
    let (frustum, view_projection) = (camera.frustum(), camera.view_projection());
    let level = |b: &Aabb| {
        let b = (!b.is_empty()).then(|| padded(b))?;
        if camera.box_touches_near_region(&b) || !frustum.intersects(&b) {
            return None;
        }
        box_footprint(&view_projection, width, height, &b).level(reach)
    };
    boxes.iter().map(level).collect()
}

/// The outcome of one pyramid test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PyramidTest {
    /// The box may have a visible pixel.
    pub visible: bool,
    /// Texels read (1 to `reach` squared).
    pub fetched: u32,
}

/// A depth pyramid on the CPU (module documentation): level 0 is the depth
/// image, each further level a 2x2 maximum of the one before.
#[derive(Clone, Debug)]
pub struct DepthPyramid {
    sizes: Vec<(u32, u32)>,
    levels: Vec<Vec<f32>>,
}

impl DepthPyramid {
    /// A pyramid over a `width` x `height` image, every texel at the far
    /// plane (1.0).
    pub fn new(width: u32, height: u32) -> Self {
        let sizes = level_sizes(width, height);
        let levels = sizes.iter().map(|&(w, h)| vec![1.0; w as usize * h as usize]).collect();
        Self { sizes, levels }
    }

    /// The levels' sizes, level 0 first.
    pub fn sizes(&self) -> &[(u32, u32)] {
        &self.sizes
    }

    /// Level `k`'s texels, row by row from the top.
    pub fn level(&self, k: usize) -> &[f32] {
        &self.levels[k]
    }

    /// Rebuilds every level from `depth` (`width * height` values, row by
    /// row from the top, as `Instruments::depth_image` gives them).
    ///
    /// # Panics
    /// If `depth` has not the pyramid's size.
    pub fn build(&mut self, depth: &[f32]) {
        assert_eq!(depth.len(), self.levels[0].len(), "a depth image of another size than the pyramid");
        self.levels[0].copy_from_slice(depth);
        for k in 1..self.levels.len() {
            let ((sw, sh), (w, h)) = (self.sizes[k - 1], self.sizes[k]);
            let (done, rest) = self.levels.split_at_mut(k);
            let (src, dst) = (&done[k - 1], &mut rest[0]);
            for y in 0..h {
                for x in 0..w {
                    let (xs, ys) = (2 * x..(2 * x + 2).min(sw), 2 * y..(2 * y + 2).min(sh));
                    let texels = ys.flat_map(|sy| xs.clone().map(move |sx| src[(sy * sw + sx) as usize]));
                    dst[(y * w + x) as usize] = texels.fold(0.0, f32::max);
                }
            }
        }
    }

    /// Texels written by the reductions of [`Self::build`] (level 0, the
    /// depth image itself, is not reduced).
    pub fn reduced_texels(&self) -> u64 {
        self.sizes[1..].iter().map(|&(w, h)| u64::from(w) * u64::from(h)).sum()
    }

    /// Tests a box's footprint against the pyramid, reading at most `reach`
    /// x `reach` texels (module documentation). An `Empty` footprint is
    /// hidden and a `Near` one visible, untested.
    pub fn test(&self, footprint: &Footprint, reach: u32) -> PyramidTest {
        let (rect, k) = match (footprint, footprint.level(reach)) {
            (Footprint::Rect(r), Some(k)) => (r, k),
            (Footprint::Near, _) => return PyramidTest { visible: true, fetched: 0 },
            _ => return PyramidTest { visible: false, fetched: 0 },
        };
        let (w, texels) = (self.sizes[k as usize].0, &self.levels[k as usize]);
        let (mut farthest, mut fetched) = (0.0f32, 0);
        for y in rect.y0 >> k..=rect.y1 >> k {
            for x in rect.x0 >> k..=rect.x1 >> k {
                farthest = farthest.max(texels[(y * w + x) as usize]);
                fetched += 1;
            }
        }
        PyramidTest { visible: rect.depth < farthest, fetched }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn levels_halve_rounding_up_down_to_one_texel() {
        assert_eq!(level_sizes(1, 1), [(1, 1)]);
        assert_eq!(level_sizes(5, 2), [(5, 2), (3, 1), (2, 1), (1, 1)]);
        assert_eq!(level_sizes(1023, 767).len(), 11);
        assert_eq!(level_sizes(1024, 768).len(), 11);
        assert_eq!(level_sizes(641, 479)[1], (321, 240));
    }

    proptest! {
        /// Every texel is the maximum of the pixels it stands for, at odd
        /// sizes too (the construction's invariant).
        #[test]
        fn texels_are_maxima_of_their_pixels(w in 1u32..40, h in 1u32..40, seed in any::<u64>()) {
            let mut rng = crate::rng::Rng::new(seed, 0);
            let depth: Vec<f32> = (0..w * h).map(|_| rng.unit()).collect();
            let mut p = DepthPyramid::new(w, h);
            p.build(&depth);
            for (k, &(lw, lh)) in p.sizes().iter().enumerate() {
                for y in 0..lh {
                    for x in 0..lw {
                        let pixels = (0..h).filter(|py| py >> k == y)
                            .flat_map(|py| (0..w).filter(move |px| px >> k == x).map(move |px| (px, py)));
                        let max = pixels.map(|(px, py)| depth[(py * w + px) as usize]).fold(0.0, f32::max);
                        prop_assert_eq!(p.level(k)[(y * lw + x) as usize], max, "level {} texel {},{}", k, x, y);
                    }
                }
            }
        }

        /// The selected level spans at most `reach` x `reach` texels, and
        /// the level above it more (it is the finest such level).
        #[test]
        fn the_selected_level_is_the_finest_within_reach(
            x0 in 0u32..2000, y0 in 0u32..2000, dx in 0u32..2000, dy in 0u32..2000, reach in 1u32..9,
        ) {
            let r = ScreenRect { x0, y0, x1: x0 + dx, y1: y0 + dy, depth: 0.5 };
            let k = select_level(&r, reach);
            let span = |k: u32| ((r.x1 >> k) - (r.x0 >> k), (r.y1 >> k) - (r.y0 >> k));
            prop_assert!(span(k).0 < reach && span(k).1 < reach);
            if k > 0 {
                prop_assert!(span(k - 1).0 >= reach || span(k - 1).1 >= reach);
            }
        }
    }

    #[test]
    fn boxes_at_or_behind_the_near_plane_are_visible() {
        let camera = crate::Camera {
            position: glam::Vec3::ZERO,
            target: glam::Vec3::NEG_Z,
            up: glam::Vec3::Y,
            fov_y_deg: 60.0,
            aspect: 1.0,
            near: 0.25,
            far: 100.0,
            matrices: None,
        };
        let vp = camera.view_projection();
        let through_eye_plane = Aabb::new(glam::Vec3::new(5.0, -1.0, -10.0), glam::Vec3::new(6.0, 1.0, 10.0));
        assert_eq!(box_footprint(&vp, 64, 64, &through_eye_plane), Footprint::Near);
        let ahead = Aabb::new(glam::Vec3::new(-1.0, -1.0, -11.0), glam::Vec3::new(1.0, 1.0, -10.0));
        let Footprint::Rect(r) = box_footprint(&vp, 64, 64, &ahead) else { panic!("a box ahead has a rectangle") };
        assert!(r.x0 > 0 && r.x1 < 63 && r.x0 < r.x1 && r.depth > 0.9 && r.depth < 1.0, "{r:?}");
        let mut p = DepthPyramid::new(64, 64);
        assert!(p.test(&Footprint::Rect(r), 2).visible, "nothing in front of it");
        p.build(&vec![0.5; 64 * 64]);
        assert!(!p.test(&Footprint::Rect(r), 2).visible, "a wall in front of it");
        assert!(p.test(&Footprint::Near, 2).visible && !p.test(&Footprint::Empty, 2).visible);
    }
}
