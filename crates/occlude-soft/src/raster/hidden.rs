//! Triangles hidden behind the hierarchical depth as they are binned (small
//! ones one by one, a prepared command's all at once): counted there, neither
//! binned nor rasterized.
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
//! A command whose triangles were set up beforehand (a [`super::Prepared`]
//! instance, drawn by several lanes in a frame) is first tested whole, by its
//! [`Extent`]: the union of its triangles' boxes at the least of their depth
//! bounds. Hidden so, it adds the count of its triangles' pixels
//! ([`RasterTri::covered`], counted once per set-up and shared by the calls
//! that need it) and none of its triangles is binned; a view-frustum culling
//! lane draws most of a large scene's instances behind nearer ones. Not
//! hidden, its triangles are tested the same way in runs of a few
//! consecutive ones (`GROUP`), each run's count also shared, before one by
//! one: the lanes then count a partly hidden instance's hidden runs once
//! between them, not each of their triangles once per lane.
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
//! nothing. An extent's rectangle holds each of its triangles' boxes and its
//! bound is at most each triangle's bound over its box, so a command (or a
//! run of its triangles) hidden whole has every triangle hidden.

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

/// Where a set of set-up triangles may cover pixels, and how near: the union
/// of their rows and columns, and a lower bound of their depths there. A
/// command whose triangles' extent is hidden is hidden whole
/// ([`HiddenTest::command_fragments`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Extent {
    /// Columns `x0..=x1` and rows `y0..=y1`: `[x0, x1, y0, y1]`.
    rect: [i32; 4],
    /// At most every fragment's depth.
    min: f32,
}

impl Extent {
    /// The extent of `triangles`; `None` when there are none, or when a depth
    /// plane is too steep to bound ([`min_depth`]).
    pub fn of(triangles: &[RasterTri]) -> Option<Self> {
        if triangles.is_empty() {
            return None;
        }
        let mut extent = Self { rect: [i32::MAX, i32::MIN, i32::MAX, i32::MIN], min: f32::INFINITY };
        for t in triangles {
            let [x0, x1, y0, y1] = &mut extent.rect;
            (*x0, *x1, *y0, *y1) = ((*x0).min(t.x0), (*x1).max(t.x1), (*y0).min(t.y0), (*y1).max(t.y1));
            extent.min = extent.min.min(min_depth(t, t.x0, t.x1, t.y0, t.y1)?);
        }
        Some(extent)
    }

    /// The extent of the triangles of `self` and `other` together.
    pub fn union(&self, other: &Self) -> Self {
        let ([a0, a1, a2, a3], [b0, b1, b2, b3]) = (self.rect, other.rect);
        Self { rect: [a0.min(b0), a1.max(b1), a2.min(b2), a3.max(b3)], min: self.min.min(other.min) }
    }
}

/// Whether a command of `kind` passes fragments at equal depth (EQUAL), and
/// whether it counts them (not an any-pass query).
fn test_of(kind: CommandKind) -> (bool, bool) {
    match kind {
        CommandKind::Draw => (false, true),
        CommandKind::Query(test) => (test == DepthTest::Equal, true),
        CommandKind::QueryAny(test) => (test == DepthTest::Equal, false),
    }
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
        let (equal, counted) = test_of(self.kinds[t.cmd as usize]);
        // The box's minimum bounds the minimum of every window inside it.
        let min = min_depth(t, t.x0, t.x1, t.y0, t.y1)?;
        self.hidden_windows([t.x0, t.x1, t.y0, t.y1], min, equal, |window| {
            if counted {
                window_fragments(t, window)
            } else {
                Some(0)
            }
        })
    }

    /// The fragments of triangles of command `cmd` that lie within `extent`,
    /// if that is hidden: every triangle then is (the argument of the module
    /// documentation, for the extent's bound), and `fragments()` gives the
    /// count of their pixels. `None` if it is not hidden.
    #[inline(always)]
    pub fn command_fragments(&self, extent: &Extent, cmd: u32, fragments: impl FnOnce() -> u64) -> Option<u64> {
        let (equal, counted) = test_of(self.kinds[cmd as usize]);
        self.hidden_windows(extent.rect, extent.min, equal, |_| Some(0))?;
        Some(if counted { fragments() } else { 0 })
    }

    /// The sum of `count` over the windows of the rectangle `[x0, x1, y0, y1]` in
    /// the tiles it touches, if every block of every window rejects fragments at
    /// depth `min` (`equal`: for an EQUAL test) and `count` gives a number for
    /// each; `None` otherwise.
    #[inline(always)]
    fn hidden_windows(
        &self,
        [x0, x1, y0, y1]: [i32; 4],
        min: f32,
        equal: bool,
        mut count: impl FnMut([i32; 4]) -> Option<u64>,
    ) -> Option<u64> {
        let tile = TILE as i32;
        let mut sum = 0;
        for ty in y0 / tile..=y1 / tile {
            for tx in x0 / tile..=x1 / tile {
                let (left, top) = (tx * tile, ty * tile);
                let window = [x0.max(left), x1.min(left + tile - 1), y0.max(top), y1.min(top + tile - 1)];
                let [wx0, wx1, wy0, wy1] = window.map(|v| v as usize);
                let (left, top) = (left as usize, top as usize);
                let blocks = rect_mask(wx0 - left, wy0 - top, wx1 - left, wy1 - top);
                let hiz = &self.hiz[ty as usize * self.grid.tiles_x + tx as usize];
                if hiz.rejected(blocks, min, equal) != blocks {
                    return None;
                }
                sum += count(window)?;
            }
        }
        Some(sum)
    }
}

/// Windows of more pixels are left to the tiles, whose rasterizers count them
/// faster (8 pixels at a time) than a pixel-by-pixel walk here.
const MAX_COUNTED: i32 = 64;

/// The pixels `t` covers in `window` (columns `x0..=x1`, rows `y0..=y1`, inside one
/// tile and inside `t`'s box), if the window holds at most [`MAX_COUNTED`].
#[inline(always)]
fn window_fragments(t: &RasterTri, window: [i32; 4]) -> Option<u64> {
    if t.x0 == t.x1 && t.y0 == t.y1 {
        return Some(1);
    }
    let [x0, x1, y0, y1] = window;
    ((x1 - x0 + 1) * (y1 - y0 + 1) <= MAX_COUNTED).then(|| t.covered_in(window))
}
