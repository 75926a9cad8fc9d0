//! Rasterization of set-up triangles inside one screen tile.

use super::setup::SetupTri;
use super::{CommandKind, CommandResult, DepthTest};

/// Tile edge length in pixels. Tiles are the unit of parallel work.
pub(super) const TILE: u32 = 64;

/// One tile's part of the depth buffer: its rows, each a slice of up to `TILE`
/// pixels, starting at pixel `(x0, y0)`.
pub(super) struct TileView<'a> {
    /// Leftmost pixel column of the tile.
    pub x0: i32,
    /// Top pixel row of the tile.
    pub y0: i32,
    /// The tile's rows, top to bottom.
    pub rows: Vec<&'a mut [f32]>,
}

/// How many triangles ahead of the current one `raster_tile` prefetches.
const PREFETCH_AHEAD: usize = 8;

/// Hints the CPU to load `t` into the cache; a no-op where unsupported.
#[inline(always)]
fn prefetch(t: &SetupTri) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = (t as *const SetupTri).cast::<i8>();
        // SAFETY: prefetching has no observable effect besides timing and cannot
        // fault; SSE is part of the x86_64 baseline. The second line may lie past `t`
        // (`wrapping_add` keeps the pointer arithmetic defined), which a prefetch
        // also tolerates.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = t;
}

/// Rasterizes the triangles `tris` (already in command order) into `tile`, running
/// each one as its command's `kinds[cmd]` says and adding its fragment counts to
/// `acc[cmd]`.
pub(super) fn raster_tile<'t>(
    tile: &mut TileView<'_>,
    tris: impl Iterator<Item = &'t SetupTri> + Clone,
    kinds: &[CommandKind],
    acc: &mut [CommandResult],
) {
    let width = tile.rows.first().map_or(0, |r| r.len()) as i32;
    let tile_x1 = tile.x0 + width - 1;
    let tile_y1 = tile.y0 + tile.rows.len() as i32 - 1;
    // Set-up triangles are scattered through memory (each tile reads a sparse subset
    // of them in order), so fetch a few ahead to hide the cache misses.
    let mut ahead = tris.clone().skip(PREFETCH_AHEAD);
    for t in tris {
        if let Some(next) = ahead.next() {
            prefetch(next);
        }
        let x0 = t.x0.max(tile.x0);
        let x1 = t.x1.min(tile_x1);
        let y0 = t.y0.max(tile.y0);
        let y1 = t.y1.min(tile_y1);
        if x0 > x1 || y0 > y1 {
            continue;
        }
        let (kx, ky) = (i64::from(x0 - t.x0), i64::from(y0 - t.y0));
        let mut e = t.edges.map(|e| e.origin + e.step_x * kx + e.step_y * ky);
        let span_max = i64::from(x1 - x0);
        let mut counts = CommandResult::default();
        let kind = kinds[t.cmd as usize];
        for py in y0..=y1 {
            let span = row_span(t, &e, span_max);
            for (ei, edge) in e.iter_mut().zip(&t.edges) {
                *ei += edge.step_y;
            }
            let Some((lo, hi)) = span else { continue };
            let xs = x0 + lo;
            let row = &mut tile.rows[(py - tile.y0) as usize];
            let row = &mut row[(xs - tile.x0) as usize..=(x0 + hi - tile.x0) as usize];
            counts.fragments += row.len() as u64;
            counts.passed += shade_span(t, kind, row, t.row_depth(py - t.y0), xs - t.x0);
        }
        let a = &mut acc[t.cmd as usize];
        a.fragments += counts.fragments;
        a.passed += counts.passed;
    }
}

/// The covered pixels of one row, as offsets `lo..=hi` from the row's first
/// candidate pixel, given the edge values `e` at that pixel and the last candidate
/// offset `span_max`. Exact: the same as testing every pixel's edge functions.
#[inline(always)]
fn row_span(t: &SetupTri, e: &[i64; 3], span_max: i64) -> Option<(i32, i32)> {
    let (mut lo, mut hi) = (0i64, span_max);
    for (&g, edge) in e.iter().zip(&t.edges) {
        // Covered offsets k satisfy g + a * k >= 0.
        let a = edge.step_x;
        if a > 0 {
            if g < 0 {
                lo = lo.max((-g + a - 1) / a);
            }
        } else if a < 0 {
            if g < 0 {
                return None;
            }
            if g + a * span_max < 0 {
                hi = hi.min(g / -a);
            }
        } else if g < 0 {
            return None;
        }
    }
    (lo <= hi).then_some((lo as i32, hi as i32))
}

/// Depth-tests (and for draws, writes) the pixels of `row`, whose first pixel is
/// `dx` columns right of the triangle's bounding-box origin and whose depth at the
/// bounding-box column is `z_row`. Returns how many passed.
#[inline(always)]
fn shade_span(t: &SetupTri, kind: CommandKind, row: &mut [f32], z_row: f32, dx: i32) -> u64 {
    // A span is at most one tile row, so a u32 count cannot overflow.
    let mut passed = 0u32;
    match kind {
        CommandKind::Draw => {
            for (i, d) in row.iter_mut().enumerate() {
                let z = t.depth(z_row, dx + i as i32);
                let pass = z < *d;
                *d = if pass { z } else { *d };
                passed += u32::from(pass);
            }
        }
        CommandKind::Query(DepthTest::Less) => {
            for (i, d) in row.iter().enumerate() {
                passed += u32::from(t.depth(z_row, dx + i as i32) < *d);
            }
        }
        CommandKind::Query(DepthTest::Equal) => {
            for (i, d) in row.iter().enumerate() {
                passed += u32::from(t.depth(z_row, dx + i as i32) == *d);
            }
        }
    }
    u64::from(passed)
}
