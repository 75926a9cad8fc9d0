//! Rasterization of set-up triangles inside one screen tile: per triangle, the
//! hierarchical-depth rejection of its blocks, then its pixels: 8 at a time with
//! AVX2, else along its exact row spans one at a time.

use std::sync::atomic::{AtomicBool, Ordering};

#[cfg(target_arch = "x86_64")]
use super::avx2::Avx2;
use super::hiz::{group_bits, min_depth, rect_mask, BLOCKS};
use super::shade::{shade_span, DRAW, EQUAL, GROUP, LESS};
use super::span::{walk, RasterTri, Span, MAX_WINDOW};
use super::split::TileView;
use super::{CommandKind, CommandResult, DepthTest};

/// Tile edge length in pixels. Tiles are the unit of parallel work; a tile holds
/// 8x8 hierarchical-depth blocks of 8x8 pixels.
pub(super) const TILE: u32 = 64;
const _: () = assert!(TILE as usize == BLOCKS * GROUP && TILE as usize == MAX_WINDOW);

/// What the tile's triangles do, by command.
pub(super) struct Commands<'a> {
    /// Each command's kind.
    pub kinds: &'a [CommandKind],
    /// Per command, whether some tile has found a passing fragment of a
    /// [`CommandKind::QueryAny`] (the other tiles then stop testing it).
    pub found: &'a [AtomicBool],
}

/// The instruction set the tiles run on.
#[derive(Clone, Copy, Debug)]
pub(super) enum Kernel {
    /// Portable code: triangles' spans walked and shaded one pixel at a time.
    Scalar,
    /// Triangles' windows rasterized 8 pixels at a time ([`Avx2`]).
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
}

impl Kernel {
    /// The fastest kernel the running CPU supports.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = Avx2::detect() {
            return Kernel::Avx2(avx2);
        }
        Kernel::Scalar
    }
}

/// A faster way than walking spans to rasterize a triangle's window, where the CPU
/// has one: see [`Avx2::window`] for the arguments.
trait WindowRaster: Copy {
    fn window<const OP: u8>(
        self,
        tile: &mut TileView<'_>,
        t: &RasterTri,
        window: [i32; 4],
        rejected: u64,
        stop_at_pass: bool,
    ) -> Option<CommandResult>;
}

/// No faster way: every window's spans are walked.
#[derive(Clone, Copy, Debug)]
struct Spans;

impl WindowRaster for Spans {
    #[inline(always)]
    fn window<const OP: u8>(
        self,
        _: &mut TileView<'_>,
        _: &RasterTri,
        _: [i32; 4],
        _: u64,
        _: bool,
    ) -> Option<CommandResult> {
        None
    }
}

#[cfg(target_arch = "x86_64")]
impl WindowRaster for Avx2 {
    #[inline(always)]
    fn window<const OP: u8>(
        self,
        tile: &mut TileView<'_>,
        t: &RasterTri,
        window: [i32; 4],
        rejected: u64,
        stop_at_pass: bool,
    ) -> Option<CommandResult> {
        Some(Avx2::window::<OP>(self, tile, t, window, rejected, stop_at_pass))
    }
}

/// Rasterizes the triangles `tris` (already in command order) into `tile` with
/// `kernel`, running each one as its command says and adding its fragment counts to
/// `acc[cmd]`.
pub(super) fn raster_tile<'t>(
    kernel: Kernel,
    tile: &mut TileView<'_>,
    tris: impl Iterator<Item = &'t RasterTri>,
    commands: &Commands<'_>,
    acc: &mut [CommandResult],
) {
    match kernel {
        Kernel::Scalar => raster_tile_with(Spans, tile, tris, commands, acc),
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2 and POPCNT.
        Kernel::Avx2(avx2) => unsafe { raster_tile_avx2(avx2, tile, tris, commands, acc) },
    }
}

/// [`raster_tile_with`] compiled for AVX2, so that the hierarchical-depth loops
/// vectorize.
///
/// # Safety
/// The CPU must support AVX2 and POPCNT.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt")]
unsafe fn raster_tile_avx2<'t>(
    avx2: Avx2,
    tile: &mut TileView<'_>,
    tris: impl Iterator<Item = &'t RasterTri>,
    commands: &Commands<'_>,
    acc: &mut [CommandResult],
) {
    raster_tile_with(avx2, tile, tris, commands, acc);
}

#[inline(always)]
fn raster_tile_with<'t, W: WindowRaster>(
    fast: W,
    tile: &mut TileView<'_>,
    tris: impl Iterator<Item = &'t RasterTri>,
    commands: &Commands<'_>,
    acc: &mut [CommandResult],
) {
    for t in tris {
        let cmd = t.cmd as usize;
        let a = &mut acc[cmd];
        match commands.kinds[cmd] {
            CommandKind::Draw => add(a, raster_triangle::<W, DRAW>(fast, tile, t, false)),
            CommandKind::Query(DepthTest::Less) => add(a, raster_triangle::<W, LESS>(fast, tile, t, false)),
            CommandKind::Query(DepthTest::Equal) => add(a, raster_triangle::<W, EQUAL>(fast, tile, t, false)),
            CommandKind::QueryAny(test) => {
                let found = &commands.found[cmd];
                if a.passed > 0 || found.load(Ordering::Relaxed) {
                    continue;
                }
                let r = match test {
                    DepthTest::Less => raster_triangle::<W, LESS>(fast, tile, t, true),
                    DepthTest::Equal => raster_triangle::<W, EQUAL>(fast, tile, t, true),
                };
                if r.passed > 0 {
                    a.passed = 1;
                    found.store(true, Ordering::Relaxed);
                }
            }
        }
    }
}

/// Adds `r` to `acc`.
#[inline(always)]
fn add(acc: &mut CommandResult, r: CommandResult) {
    acc.fragments += r.fragments;
    acc.passed += r.passed;
}

/// Rasterizes `t` into `tile` with operation `OP`; with `stop_at_pass` (an any-pass
/// query, which needs no fragment count), returns as soon as a row has a passing
/// fragment (the counts are then partial).
#[inline(always)]
fn raster_triangle<W: WindowRaster, const OP: u8>(
    fast: W,
    tile: &mut TileView<'_>,
    t: &RasterTri,
    stop_at_pass: bool,
) -> CommandResult {
    let x0 = t.x0.max(tile.x0);
    let x1 = t.x1.min(tile.x0 + tile.rows.width() as i32 - 1);
    let y0 = t.y0.max(tile.y0);
    let y1 = t.y1.min(tile.y0 + tile.rows.height() as i32 - 1);
    if x0 > x1 || y0 > y1 {
        return CommandResult::default();
    }
    let window = [x0, x1, y0, y1];

    // Hierarchical depth: the blocks whose stored depths this triangle cannot pass.
    let blocks =
        rect_mask((x0 - tile.x0) as usize, (y0 - tile.y0) as usize, (x1 - tile.x0) as usize, (y1 - tile.y0) as usize);
    if OP != DRAW {
        tile.hiz.refresh(&tile.rows, blocks);
    }
    let rejected = min_depth(t, x0, x1, y0, y1).map_or(0, |min| tile.hiz.rejected(blocks, min, OP == EQUAL));
    if stop_at_pass && blocks & !rejected == 0 {
        // Nothing can pass, and an any-pass query counts no fragments.
        return CommandResult::default();
    }

    let counts = fast
        .window::<OP>(tile, t, window, rejected, stop_at_pass)
        .unwrap_or_else(|| raster_spans::<OP>(tile, t, window, rejected, stop_at_pass));
    if OP == DRAW {
        // The blocks written, or at least covered: their bounds may be loose now.
        tile.hiz.mark_written(blocks & !rejected);
    }
    counts
}

/// [`raster_triangle`] over `window` (see [`Avx2::window`]) by walking the
/// triangle's spans and testing their pixels one at a time.
pub(super) fn raster_spans<const OP: u8>(
    tile: &mut TileView<'_>,
    t: &RasterTri,
    window: [i32; 4],
    rejected: u64,
    stop_at_pass: bool,
) -> CommandResult {
    let [x0, x1, y0, y1] = window;
    let lx0 = (x0 - tile.x0) as usize;
    let (ly0, ly1) = ((y0 - tile.y0) as usize, (y1 - tile.y0) as usize);
    let mut spans = [Span::default(); MAX_WINDOW];
    let spans = &mut spans[..=ly1 - ly0];
    let fragments = walk(t, x0, x1, y0, spans);
    let dx0 = tile.x0 - t.x0;
    let mut passed = 0;
    for (ly, span) in (ly0..).zip(&*spans) {
        if span.lo >= span.end {
            continue;
        }
        let (lo, hi) = (lx0 + usize::from(span.lo), lx0 + usize::from(span.end) - 1);
        let skip = (rejected >> (BLOCKS * (ly / GROUP))) as u8;
        if group_bits(lo, hi) & !skip == 0 {
            continue;
        }
        passed += shade_span::<OP>(tile.rows.row_mut(ly), lo, hi, skip, t.row_plane(tile.y0 + ly as i32), dx0);
        if stop_at_pass && passed > 0 {
            break;
        }
    }
    CommandResult { fragments: fragments as u64, passed: u64::from(passed) }
}
