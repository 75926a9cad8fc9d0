//! Occlusion tests against the buffer: screen rectangles and boxes.
//!
//! A rectangle's pixels are rounded outward, and it is visible when its nearest
//! depth is strictly less than any bound it overlaps. If an exact buffer shows
//! a pixel, `nearest < E(p) <= B(p)`, so the test says visible.
//!
//! A rectangle is read a tile row (two subtile rows) at a time straight from
//! the tile storage, eight subtiles (one [`Tile`]) per step, compared in lanes
//! (in AVX2 where the CPU has it, detected at run time: the `avx2` module), and
//! the test stops at the first tile holding a subtile of the rectangle that may
//! show it. The count of subtiles read is what a test's cost follows
//! (`*_counted`).

mod avx2;

use crate::buffer::{MaskedBuffer, Tile};
use crate::raster::Avx2;
use glam::{Mat4, Vec2, Vec3, Vec4};

/// A test's answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility {
    /// Some part may be seen (always the answer when in doubt).
    Visible,
    /// Hidden behind occluders.
    Occluded,
    /// Entirely outside the view frustum.
    ViewCulled,
}

/// How the eight subtiles of a tile are compared with a rectangle's depth:
/// [`Portable`], or [`Avx2`] where the CPU has it (the same answers).
trait TileTest: Copy {
    /// The lanes of `tile` (bit `l` for lane `l`) whose bound on their
    /// pixels' depth lies beyond `nearest`, where something at `nearest` may
    /// be seen. The bound is the reference depth, or the larger layer where
    /// the mask has pixels on the working layer, so a lane is beyond when
    /// `nearest < reference`, or the mask is not empty and `nearest <
    /// working` (the same as `nearest < reference.max(working)` with
    /// `f32::max`, NaN layers included: a NaN compares false).
    fn lanes_beyond(self, tile: &Tile, nearest: f32) -> u32;
}

/// The tile test in plain Rust.
#[derive(Clone, Copy, Debug)]
struct Portable;

impl TileTest for Portable {
    #[inline(always)]
    fn lanes_beyond(self, tile: &Tile, nearest: f32) -> u32 {
        let mut bits = 0;
        for l in 0..8 {
            let beyond = nearest < tile.reference[l] || (tile.mask[l] != 0 && nearest < tile.working[l]);
            bits |= u32::from(beyond) << l;
        }
        bits
    }
}

/// The subtiles a screen rectangle touches: columns `sx0..=sx1` of rows
/// `sy0..=sy1`.
#[derive(Clone, Copy, Debug)]
struct SubtileRect {
    sx0: u32,
    sx1: u32,
    sy0: u32,
    sy1: u32,
}

impl SubtileRect {
    /// Reads the rectangle tile row by tile row, a tile of eight subtiles at
    /// a time, until a tile has a subtile of the rectangle beyond `nearest`:
    /// whether one was found, and the rectangle's subtiles in the tiles read.
    #[inline(always)]
    fn scan(self, buffer: &MaskedBuffer, nearest: f32, test: impl TileTest) -> (Visibility, u64) {
        let (t0, t1) = (self.sx0 / 4, self.sx1 / 4);
        // The rectangle's columns in the first and last tile, as lanes of
        // either subtile row.
        let (first, last) = (0xf << (self.sx0 % 4) & 0xf, 0xf >> (3 - self.sx1 % 4));
        let per_row = u64::from(self.sx1 - self.sx0 + 1);
        let tiles_per_row = (buffer.cols / 4) as usize;
        let mut read = 0;
        for ty in self.sy0 / 2..=self.sy1 / 2 {
            // The tile row's subtile rows in the rectangle: the upper one
            // (lanes 0-3) unless the rectangle starts below it, the lower one
            // (lanes 4-7) unless it ends above it.
            let (upper, lower) = (2 * ty >= self.sy0, 2 * ty < self.sy1);
            let rows = u64::from(upper) + u64::from(lower);
            let halves = if upper { 0x0f } else { 0 } | if lower { 0xf0 } else { 0 };
            let row = &buffer.tiles[ty as usize * tiles_per_row..][t0 as usize..=t1 as usize];
            for (t, tile) in (t0..=t1).zip(row) {
                let mut columns = 0xf;
                if t == t0 {
                    columns &= first;
                }
                if t == t1 {
                    columns &= last;
                }
                if test.lanes_beyond(tile, nearest) & (columns | columns << 4) & halves != 0 {
                    let in_row = u64::from((4 * (t + 1)).min(self.sx1 + 1) - self.sx0);
                    return (Visibility::Visible, read + rows * in_row);
                }
            }
            read += rows * per_row;
        }
        (Visibility::Occluded, read)
    }
}

impl MaskedBuffer {
    /// Tests the screen rectangle from `min_px` to `max_px` (pixels, y down) whose
    /// nearest point has NDC depth `nearest_depth`. Every pixel the rectangle
    /// touches is tested (rounded outward). Cost: the subtiles it overlaps.
    pub fn test_rect(&self, min_px: Vec2, max_px: Vec2, nearest_depth: f32) -> Visibility {
        self.test_rect_counted(min_px, max_px, nearest_depth).0
    }

    /// [`test_rect`](Self::test_rect), with the number of subtiles it read:
    /// the rectangle's subtiles in the tiles of eight read before the answer
    /// (all of them when occluded; up to the first tile with a subtile that
    /// may show it when visible; none when the rectangle is off screen or its
    /// input is not finite). The time of a test follows this count.
    pub fn test_rect_counted(&self, min_px: Vec2, max_px: Vec2, nearest_depth: f32) -> (Visibility, u64) {
        if !(min_px.is_finite() && max_px.is_finite()) || nearest_depth.is_nan() {
            return (Visibility::Visible, 0);
        }
        let x0 = min_px.x.floor().max(0.0) as u32;
        let y0 = min_px.y.floor().max(0.0) as u32;
        let x1 = (max_px.x.floor().max(-1.0) as i64).min(self.width as i64 - 1);
        let y1 = (max_px.y.floor().max(-1.0) as i64).min(self.height as i64 - 1);
        if x1 < x0 as i64 || y1 < y0 as i64 {
            return (Visibility::ViewCulled, 0);
        }
        let rect = SubtileRect { sx0: x0 / 8, sx1: x1 as u32 / 8, sy0: y0 / 4, sy1: y1 as u32 / 4 };
        match Avx2::detect() {
            Some(avx2) => avx2.scan(rect, self, nearest_depth),
            None => rect.scan(self, nearest_depth, Portable),
        }
    }

    /// Tests the box from `min` to `max` seen through `view_proj` (to wgpu clip
    /// space). A box reaching the near plane is visible; one wholly outside a
    /// frustum plane is [`ViewCulled`](Visibility::ViewCulled).
    pub fn test_aabb(&self, min: Vec3, max: Vec3, view_proj: Mat4) -> Visibility {
        self.test_aabb_counted(min, max, view_proj).0
    }

    /// [`test_aabb`](Self::test_aabb), with the number of subtiles it read
    /// ([`test_rect_counted`](Self::test_rect_counted) of the box's screen
    /// rectangle; none when it is answered from its corners alone).
    pub fn test_aabb_counted(&self, min: Vec3, max: Vec3, view_proj: Mat4) -> (Visibility, u64) {
        let mut c = [Vec4::ZERO; 8];
        for (i, v) in c.iter_mut().enumerate() {
            let p = Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            );
            *v = view_proj * p.extend(1.0);
        }
        if c.iter().any(|v| !v.is_finite()) {
            return (Visibility::Visible, 0);
        }
        let out = |f: fn(&Vec4) -> bool| c.iter().all(f);
        if out(|v| v.x < -v.w) || out(|v| v.x > v.w) || out(|v| v.y < -v.w) || out(|v| v.y > v.w) || out(|v| v.z > v.w)
        {
            return (Visibility::ViewCulled, 0);
        }
        if c.iter().any(|v| v.z <= 0.0 || v.w <= 0.0) {
            return (Visibility::Visible, 0);
        }
        let (w, h) = (self.width as f32, self.height as f32);
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        let mut nearest = f32::INFINITY;
        for v in &c {
            let s = Vec2::new((v.x / v.w + 1.0) * 0.5 * w, (1.0 - v.y / v.w) * 0.5 * h);
            lo = lo.min(s);
            hi = hi.max(s);
            nearest = nearest.min(v.z / v.w);
        }
        // Outward by a pixel against rounding in the projection.
        let nearest = nearest - nearest.abs() * 1e-6;
        self.test_rect_counted(lo - 1.0, hi + 1.0, nearest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::buffer::Subtile;
    use proptest::prelude::*;

    /// The rectangle test read subtile by subtile (the definition the tile
    /// reads must answer as).
    fn scalar_test_rect(b: &MaskedBuffer, min_px: Vec2, max_px: Vec2, nearest: f32) -> Visibility {
        if !(min_px.is_finite() && max_px.is_finite()) || nearest.is_nan() {
            return Visibility::Visible;
        }
        let x0 = min_px.x.floor().max(0.0) as u32;
        let y0 = min_px.y.floor().max(0.0) as u32;
        let x1 = (max_px.x.floor().max(-1.0) as i64).min(b.width as i64 - 1);
        let y1 = (max_px.y.floor().max(-1.0) as i64).min(b.height as i64 - 1);
        if x1 < x0 as i64 || y1 < y0 as i64 {
            return Visibility::ViewCulled;
        }
        for sy in y0 / 4..=(y1 as u32) / 4 {
            for sx in x0 / 8..=(x1 as u32) / 8 {
                let s = b.subtile(sx, sy);
                let bound = if s.mask == 0 { s.reference } else { s.reference.max(s.working) };
                if nearest < bound {
                    return Visibility::Visible;
                }
            }
        }
        Visibility::Occluded
    }

    /// A buffer of `width` x `height` whose subtiles hold the given states
    /// (mask, working, reference; cycled). Renders keep the working layer no
    /// farther than the reference; these need not, so that every term of the
    /// bound is tested.
    fn filled(width: u32, height: u32, states: &[(u32, f32, f32)]) -> MaskedBuffer {
        let mut b = MaskedBuffer::new(width, height).unwrap();
        let mut k = 0;
        for sy in 0..b.rows {
            for sx in 0..b.cols {
                let (mask, working, reference) = states[k % states.len()];
                k += 1;
                let s = Subtile { mask, working, reference };
                let t = b.tile_index(sx, sy);
                b.tiles[t].set(Tile::lane(sx, sy), s);
            }
        }
        b
    }

    #[test]
    fn counts_the_subtiles_of_the_rectangle_it_reads() {
        // 200 x 40 pixels: 28 subtile columns (7 tiles, padded), 10 rows (5
        // tile rows).
        let mut b = MaskedBuffer::new(200, 40).unwrap();
        for t in &mut b.tiles {
            t.reference = [0.5; 8];
        }
        // Pixels 10..=69 x 5..=14: subtile columns 1..=8 (three tiles: 3 + 4
        // + 1 columns), rows 1..=3 (the lower row of tile row 0, both of tile
        // row 1), all read when occluded.
        let rect = (Vec2::new(10.0, 5.0), Vec2::new(69.5, 14.5));
        assert_eq!(b.test_rect_counted(rect.0, rect.1, 0.7), (Visibility::Occluded, 24));
        // In front: the first tile answers after its 3 subtiles of row 1.
        assert_eq!(b.test_rect_counted(rect.0, rect.1, 0.3), (Visibility::Visible, 3));
        // Visible only through subtile (4, 1): tile row 0's first tile (3)
        // clean and its second (4) seen; the subtile beside it in the upper
        // row, outside the rectangle, does not count.
        let (t, l) = (b.tile_index(4, 1), Tile::lane(4, 1));
        b.tiles[t].reference[l - 4] = 0.9;
        assert_eq!(b.test_rect_counted(rect.0, rect.1, 0.7), (Visibility::Occluded, 24));
        b.tiles[t].reference[l] = 0.9;
        assert_eq!(b.test_rect_counted(rect.0, rect.1, 0.7), (Visibility::Visible, 7));
        // Visible only through subtile (8, 2): tile row 0 (8 reads), then
        // tile row 1's tiles, two rows each: 3 and 4 clean, 1 seen.
        b.tiles[t].reference[l] = 0.5;
        let (t, l) = (b.tile_index(8, 2), Tile::lane(8, 2));
        b.tiles[t].reference[l] = 0.9;
        assert_eq!(b.test_rect_counted(rect.0, rect.1, 0.7), (Visibility::Visible, 24));
        // Clipped to the screen: columns 24..=24, rows 9..=9.
        let r = b.test_rect_counted(Vec2::new(195.0, 38.0), Vec2::new(400.0, 90.0), 0.7);
        assert_eq!(r, (Visibility::Occluded, 1));
        // Off screen and not finite: nothing read.
        assert_eq!(b.test_rect_counted(Vec2::new(300.0, 0.0), Vec2::new(400.0, 9.0), 0.7).1, 0);
        assert_eq!(b.test_rect_counted(Vec2::new(f32::NAN, 0.0), Vec2::new(4.0, 9.0), 0.7), (Visibility::Visible, 0));
    }

    #[test]
    fn a_box_counts_the_reads_of_its_rectangle() {
        let mut b = MaskedBuffer::new(64, 48).unwrap();
        for t in &mut b.tiles {
            t.reference = [0.5; 8];
        }
        // The whole screen at depth 0.7..0.8: its rectangle, a pixel wider on
        // each side, is clipped to all 8 x 12 subtiles.
        let whole = b.test_aabb_counted(Vec3::new(-1.0, -1.0, 0.7), Vec3::new(1.0, 1.0, 0.8), Mat4::IDENTITY);
        assert_eq!(whole, (Visibility::Occluded, 96));
        let culled = b.test_aabb_counted(Vec3::new(2.0, 2.0, 0.7), Vec3::new(3.0, 3.0, 0.8), Mat4::IDENTITY);
        assert_eq!(culled, (Visibility::ViewCulled, 0));
    }

    fn state() -> impl Strategy<Value = (u32, f32, f32)> {
        let depth = prop_oneof![Just(0.0f32), Just(0.5), Just(1.0), Just(f32::NAN), 0.0f32..1.0];
        (prop_oneof![Just(0u32), Just(u32::MAX >> 1), any::<u32>()], depth.clone(), depth)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn tile_reads_answer_as_subtile_reads(
            width in 1u32..300,
            height in 1u32..100,
            states in proptest::collection::vec(state(), 1..40),
            rects in proptest::collection::vec((-20.0f32..320.0, -20.0f32..120.0, 0.0f32..200.0, 0.0f32..80.0, -0.1f32..1.1), 1..20),
        ) {
            let b = filled(width, height, &states);
            for (x, y, w, h, z) in rects {
                let (lo, hi) = (Vec2::new(x, y), Vec2::new(x + w, y + h));
                let scalar = scalar_test_rect(&b, lo, hi, z);
                prop_assert_eq!(b.test_rect(lo, hi, z), scalar);
                // Both tile compares, whichever the CPU runs.
                if scalar != Visibility::ViewCulled {
                    let rect = SubtileRect {
                        sx0: lo.x.floor().max(0.0) as u32 / 8,
                        sx1: (hi.x.floor() as u32).min(b.width - 1) / 8,
                        sy0: lo.y.floor().max(0.0) as u32 / 4,
                        sy1: (hi.y.floor() as u32).min(b.height - 1) / 4,
                    };
                    let portable = rect.scan(&b, z, Portable);
                    prop_assert_eq!(portable.0, scalar);
                    prop_assert_eq!(portable, b.test_rect_counted(lo, hi, z));
                    if let Some(avx2) = Avx2::detect() {
                        prop_assert_eq!(avx2.scan(rect, &b, z), portable);
                    }
                }
            }
        }
    }
}
