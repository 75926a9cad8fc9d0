//! Small triangles hidden behind the hierarchical depth as they are binned:
//! counted there, neither binned nor rasterized.
//!
//! A draw's or query's result needs every fragment's count, passing or not (the
//! clock charges a draw for the pixels it covers), so a triangle whose fragments
//! all fail the depth test is still visited in every tile it touches. Most of a
//! large scene's triangles are such, and small: behind what earlier calls drew
//! (with the bounds made exact before each call bins, 92 % of the tile visits of
//! view-frustum culling's draws on the power plant at paper size meet only
//! rejected blocks). Here a set-up triangle is tested against the bounds the depth
//! buffer holds when the call starts, before it is binned; one that no block of
//! any tile it touches lets pass, and whose window in each covers at most
//! [`MAX_COUNTED`] pixels (of any size for an any-pass query, which counts none),
//! is counted pixel by pixel and goes no further. Larger ones are binned:
//! the tiles count them faster, and skip their rejected blocks' depth tests.
//!
//! **Why the results are the same.** The bounds at the call's start are upper
//! bounds of the depths at any later point of the call: the call's draws only lower
//! depths, and its queries write none. A fragment at or behind such a bound (LESS;
//! strictly behind for EQUAL) fails against every depth the block holds later, so
//! the triangle writes nothing and passes nothing. Its fragment count is the number
//! of pixel centres its reduced edge functions hold, the definition of coverage
//! every rasterizer path follows (`RasterTri::covered_rows`, the span walk, the
//! AVX2 windows); a triangle whose bounding box holds one pixel centre covers it
//! (set-up keeps no triangle of at most 2 x 2 centres that covers none): one
//! fragment. An any-pass query counts no fragments, so its hidden triangles add
//! nothing.

use super::bin::TileGrid;
use super::hiz::{min_depth, rect_mask, TileHiZ};
use super::span::RasterTri;
use super::tile::TILE;
use super::{CommandKind, DepthTest};

/// The bounds and commands a call's triangles are tested against as they are binned.
#[derive(Clone, Copy)]
pub(super) struct HiddenTest<'a> {
    /// The depth buffer's hierarchical depth at the call's start, one per tile.
    hiz: &'a [TileHiZ],
    /// The buffer's tiles.
    grid: TileGrid,
    /// Each command's kind.
    kinds: &'a [CommandKind],
}

impl<'a> HiddenTest<'a> {
    /// The test for a call drawing into a buffer with the hierarchical depth `hiz`
    /// (tiles of `grid`), running commands of `kinds`; `None` when no bound is
    /// below the far plane (a cleared buffer), where nothing nearer can be hidden.
    pub fn new(hiz: &'a [TileHiZ], grid: TileGrid, kinds: &'a [CommandKind]) -> Option<Self> {
        hiz.iter().any(|h| h.lowest() < 1.0).then_some(Self { hiz, grid, kinds })
    }

    /// The number of fragments `t` counts for its command, if it is hidden in every
    /// tile it touches and small enough to count here (module documentation);
    /// `None` if it is to be binned.
    #[inline(always)]
    pub fn fragments_if_hidden(&self, t: &RasterTri) -> Option<u64> {
        let (equal, counted) = match self.kinds[t.cmd as usize] {
            CommandKind::Draw => (false, true),
            CommandKind::Query(test) => (test == DepthTest::Equal, true),
            CommandKind::QueryAny(test) => (test == DepthTest::Equal, false),
        };
        // The box's minimum bounds the minimum of every window inside it.
        let min = min_depth(t, t.x0, t.x1, t.y0, t.y1)?;
        let tile = TILE as i32;
        let mut fragments = 0;
        for ty in t.y0 / tile..=t.y1 / tile {
            for tx in t.x0 / tile..=t.x1 / tile {
                let (x0, y0) = (tx * tile, ty * tile);
                let [wx0, wx1, wy0, wy1] =
                    [t.x0.max(x0), t.x1.min(x0 + tile - 1), t.y0.max(y0), t.y1.min(y0 + tile - 1)];
                let blocks =
                    rect_mask((wx0 - x0) as usize, (wy0 - y0) as usize, (wx1 - x0) as usize, (wy1 - y0) as usize);
                let hiz = &self.hiz[ty as usize * self.grid.tiles_x + tx as usize];
                if hiz.rejected(blocks, min, equal) != blocks {
                    return None;
                }
                if counted {
                    fragments += window_fragments(t, [wx0, wx1, wy0, wy1])?;
                }
            }
        }
        Some(fragments)
    }
}

/// Windows of more pixels are left to the tiles, whose rasterizers count them
/// faster (8 pixels at a time) than a pixel-by-pixel walk here.
const MAX_COUNTED: i32 = 64;

/// The pixels `t` covers in `window` (columns `x0..=x1`, rows `y0..=y1`, inside one
/// tile and inside `t`'s box), if the window holds at most [`MAX_COUNTED`].
#[inline(always)]
fn window_fragments(t: &RasterTri, [x0, x1, y0, y1]: [i32; 4]) -> Option<u64> {
    if t.x0 == t.x1 && t.y0 == t.y1 {
        return Some(1);
    }
    if (x1 - x0 + 1) * (y1 - y0 + 1) > MAX_COUNTED {
        return None;
    }
    // Each centre's edge functions, `g + a * i + b * j` as
    // `RasterTri::covered_rows` tests them, stepped by `a` along a row.
    let [(mut g0, a0, b0), (mut g1, a1, b1), (mut g2, a2, b2)] = t.edges_at(x0, y0);
    let mut covered = 0;
    for _ in y0..=y1 {
        let (mut e0, mut e1, mut e2) = (g0, g1, g2);
        for _ in x0..=x1 {
            covered += u64::from((e0 >= 0) & (e1 >= 0) & (e2 >= 0));
            (e0, e1, e2) = (e0 + a0, e1 + a1, e2 + a2);
        }
        (g0, g1, g2) = (g0 + b0, g1 + b1, g2 + b2);
    }
    Some(covered)
}
