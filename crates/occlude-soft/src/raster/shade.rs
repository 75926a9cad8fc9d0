//! Depth test (and write) of the pixels of a row span, one at a time: the portable
//! path, and the path of windows the AVX2 rasterizer declines.

use super::setup::RowPlane;

/// Depth test LESS with depth write (a draw): a const-generic parameter of the
/// rasterizers, so that each operation gets its own loop.
pub(super) const DRAW: u8 = 0;
/// Depth test LESS, no write (a query).
pub(super) const LESS: u8 = 1;
/// Depth test EQUAL, no write (a query).
pub(super) const EQUAL: u8 = 2;

/// Pixels per group: one AVX2 register, and the width of a hierarchical-depth block.
pub(super) const GROUP: usize = 8;

/// Depth-tests the pixel `d` against the fragment depth `z` with operation `OP`,
/// writing `z` when it passes a draw; returns whether it passed.
#[inline(always)]
pub(super) fn test_pixel<const OP: u8>(z: f32, d: &mut f32) -> bool {
    let pass = if OP == EQUAL { z == *d } else { z < *d };
    if OP == DRAW && pass {
        *d = z;
    }
    pass
}

/// Depth-tests the columns `lo..=hi` of `row` (a tile's row) with operation `OP`,
/// skipping the 8-column groups whose bit is set in `skip`; column 0 is `dx0` pixels
/// right of `plane`'s origin. Returns how many passed.
#[inline(always)]
pub(super) fn shade_span<const OP: u8>(
    row: &mut [f32],
    lo: usize,
    hi: usize,
    skip: u8,
    plane: RowPlane,
    dx0: i32,
) -> u32 {
    let mut passed = 0;
    for (c, d) in row.iter_mut().enumerate().take(hi + 1).skip(lo) {
        if skip & (1 << (c / GROUP)) == 0 {
            passed += u32::from(test_pixel::<OP>(plane.depth(dx0 + c as i32), d));
        }
    }
    passed
}
