//! Hierarchical depth: per 8x8-pixel block of a tile, an upper bound of the depth
//! stored there, so that a triangle whose every fragment lies at or behind it skips
//! the block's per-pixel tests (its fragments are still counted, from the spans).
//!
//! A bound is exact when computed, and stays a valid bound while only draws write the
//! block, since a draw only ever lowers depths; it is then merely loose, and the block
//! is marked dirty. Dirty blocks are recomputed for queries (which write nothing, so
//! the refresh pays off for every later query and draw) and at the start of every
//! rasterizer call, for its binning (`hidden`); within a call draws test the bounds
//! as they are, as recomputing on every draw would cost a fill-rate-bound workload
//! more than the rejection saves. Writes from outside the rasterizer, which may raise
//! depths, reset the bounds to infinity.
//!
//! Rejection never changes a result: it skips only pixels whose test would fail,
//! using a lower bound of the triangle's depth that accounts for `f32` rounding.

use super::shade::GROUP;
use super::span::RasterTri;
use super::split::TileRows;

/// Blocks per tile side (`TILE / GROUP`): 8, so that a tile's blocks fit a `u64`.
pub(super) const BLOCKS: usize = 8;

/// The hierarchical depth of one tile: block `8 * row + column` is bit
/// `8 * row + column` of the masks.
#[derive(Clone, Debug)]
pub(super) struct TileHiZ {
    /// Per block, an upper bound of the depths stored in it (NaN pixels aside: they
    /// fail every test).
    max: [f32; BLOCKS * BLOCKS],
    /// Blocks whose bound may be loose: written since it was computed.
    dirty: u64,
    /// The smallest of `max`: no block rejects a fragment in front of it.
    lowest: f32,
}

impl TileHiZ {
    /// The hierarchical depth of a tile cleared to the far plane (1.0).
    pub fn cleared() -> Self {
        Self { max: [1.0; BLOCKS * BLOCKS], dirty: 0, lowest: 1.0 }
    }

    /// Forgets the bounds (the depths were written from outside, perhaps raised).
    pub fn invalidate(&mut self) {
        self.max = [f32::INFINITY; BLOCKS * BLOCKS];
        self.dirty = !0;
        self.lowest = f32::INFINITY;
    }

    /// The smallest of the blocks' bounds.
    pub fn lowest(&self) -> f32 {
        self.lowest
    }

    /// Whether some block's bound may be loose.
    pub fn is_dirty(&self) -> bool {
        self.dirty != 0
    }

    /// Marks the blocks of `mask` as written by a draw.
    #[inline(always)]
    pub fn mark_written(&mut self, mask: u64) {
        self.dirty |= mask;
    }

    /// Recomputes the dirty blocks of `mask` from the tile's `rows`.
    pub fn refresh(&mut self, rows: &TileRows<'_>, mask: u64) {
        let todo = mask & self.dirty;
        if todo == 0 {
            return;
        }
        const WIDTH: usize = BLOCKS * GROUP;
        for by in 0..BLOCKS {
            let row_blocks = (todo >> (BLOCKS * by)) as u8;
            if row_blocks == 0 {
                continue;
            }
            // Per column of the block row, the largest depth, a pixel row at a time
            // (vector maxes; a tile cut by the buffer's edge has padding columns of
            // -inf): the row's eight blocks at once. `>` ignores NaN pixels, as
            // `f32::max` does.
            let mut columns = [f32::NEG_INFINITY; WIDTH];
            for y in by * GROUP..(by * GROUP + GROUP).min(rows.height()) {
                let row = rows.row(y);
                for (m, &d) in columns.iter_mut().zip(row) {
                    *m = if d > *m { d } else { *m };
                }
            }
            for (bx, block) in columns.chunks_exact(GROUP).enumerate() {
                if row_blocks & (1 << bx) != 0 {
                    self.max[by * BLOCKS + bx] = block.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v));
                }
            }
        }
        self.dirty &= !mask;
        self.lowest = self.max.iter().fold(f32::INFINITY, |m, &v| m.min(v));
    }

    /// The blocks of `mask` where no fragment at depth `>= min` can pass: LESS
    /// (`equal` false) fails where `min >= max`, EQUAL where `min > max`.
    #[inline(always)]
    pub fn rejected(&self, mask: u64, min: f32, equal: bool) -> u64 {
        if mask == 0 || min < self.lowest {
            return 0;
        }
        let (first, last) = (mask.trailing_zeros() as usize / BLOCKS, (63 - mask.leading_zeros()) as usize / BLOCKS);
        let mut out = 0;
        for by in first..=last {
            // One block row at a time, in a form the compiler turns into one vector
            // compare.
            let maxes: &[f32; BLOCKS] = self.max[by * BLOCKS..][..BLOCKS].try_into().expect("a block row");
            let mut bits = 0u8;
            for (bx, &max) in maxes.iter().enumerate() {
                let hit = if equal { min > max } else { min >= max };
                bits |= u8::from(hit) << bx;
            }
            out |= u64::from(bits) << (8 * by);
        }
        out & mask
    }
}

/// The blocks touched by the tile-local pixel rectangle `x0..=x1`, `y0..=y1`.
#[inline(always)]
pub(super) fn rect_mask(x0: usize, y0: usize, x1: usize, y1: usize) -> u64 {
    let (bx0, bx1) = (x0 / GROUP, x1 / GROUP);
    let (by0, by1) = (y0 / GROUP, y1 / GROUP);
    let columns = (0xFFu64 >> (BLOCKS - 1 - bx1)) & (0xFFu64 << bx0);
    let rows = (!0u64 >> (8 * (BLOCKS - 1 - by1))) & (!0u64 << (8 * by0));
    (columns * 0x0101_0101_0101_0101) & rows
}

/// The groups (block columns) of the tile-local columns `lo..=hi`, as bits.
#[inline(always)]
pub(super) fn group_bits(lo: usize, hi: usize) -> u8 {
    (0xFFu8 >> (BLOCKS - 1 - hi / GROUP)) & (0xFFu8 << (lo / GROUP))
}

/// A lower bound of the depth [`RowPlane::depth`](super::setup::RowPlane::depth)
/// gives any pixel of `t` in the columns `x0..=x1` and rows `y0..=y1` (inside its
/// bounding box), or `None` where the plane is too steep for `f32` to stay finite.
///
/// The plane's exact minimum is at a corner; the computed depth is within
/// `3 * 2^-24 * M` of the exact one (three roundings of terms bounded by
/// `M = |z_origin| + |z_dy| * dy + |z_dx| * dx`), and clamping at 0 only raises it,
/// so `min - M * 2^-20` is a safe bound even after rounding it to `f32`.
#[inline(always)]
pub(super) fn min_depth(t: &RasterTri, x0: i32, x1: i32, y0: i32, y1: i32) -> Option<f32> {
    let (dx0, dx1) = (f64::from(x0 - t.x0), f64::from(x1 - t.x0));
    let (dy0, dy1) = (f64::from(y0 - t.plane_y), f64::from(y1 - t.plane_y));
    let (z0, zx, zy) = (f64::from(t.z_origin), f64::from(t.z_dx), f64::from(t.z_dy));
    let corner = |slope: f64, lo: f64, hi: f64| slope * if slope >= 0.0 { lo } else { hi };
    let min = z0 + corner(zx, dx0, dx1) + corner(zy, dy0, dy1);
    let magnitude = z0.abs() + zx.abs() * dx1 + zy.abs() * dy1;
    const LIMIT: f64 = 1e30;
    (magnitude < LIMIT).then(|| (min - magnitude * (1.0 / (1u64 << 20) as f64) - 1e-30) as f32)
}
