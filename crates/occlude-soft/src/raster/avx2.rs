//! The AVX2 window rasterizer: a triangle's edge functions and depth plane evaluated
//! 8 pixels at a time over its window in a tile, with results identical to the span
//! walker's and the scalar depth test's.
//!
//! Coverage uses the reduced edge functions of [`RasterTri::edges_at`] in `i32`
//! lanes.
//! Per window, an edge that holds at the four corners of the window (widened to whole
//! 8-pixel groups) holds everywhere in it and is dropped; one that fails at all four
//! fails everywhere, and the window is empty; an edge that crosses the window takes
//! values within its slopes times the window's size, which the coordinate limit of
//! the set-up keeps inside `i32` (slopes of at most 2^24, windows of at most 64
//! pixels a side: below 2^24 * 126 < 2^31). Coverage is then a
//! sign test of the crossing edges' values or-ed together, in one loop per number
//! of crossing edges (none to three).
//!
//! Depth is [`RowPlane::depth`](super::setup::RowPlane::depth) per lane: the same
//! `f32` product and sum (never a fused multiply-add; the product does not depend
//! on the row, so it is computed once per group of the window), and `max(z, 0)` in
//! the operand order that, like `depth`, turns NaN and `-0.0` into `+0.0`.

use std::arch::x86_64::*;
use std::mem::MaybeUninit;

use super::hiz::BLOCKS;
use super::setup::{HALF, ONE, SUBPIXEL_BITS};
use super::shade::{test_pixel, DRAW, EQUAL, GROUP};
use super::span::RasterTri;
use super::split::TileView;
use super::CommandResult;

/// Proof that the running CPU supports AVX2 and POPCNT: a value exists only where it
/// does, which makes calling this module's `target_feature` functions sound.
#[derive(Clone, Copy, Debug)]
pub(super) struct Avx2(());

impl Avx2 {
    /// `Some` when the running CPU supports AVX2 and POPCNT.
    pub fn detect() -> Option<Self> {
        (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("popcnt")).then_some(Self(()))
    }

    /// Rasterizes `t` with operation `OP` over `window` (its columns `x0..=x1` and rows
    /// `y0..=y1` in `tile`, absolute, not empty), skipping the depth tests of the
    /// hierarchical-depth blocks set in `rejected`; with `stop_at_pass`, stops after
    /// the first row with a passing fragment.
    pub fn window<const OP: u8>(
        self,
        tile: &mut TileView<'_>,
        t: &RasterTri,
        window: [i32; 4],
        rejected: u64,
        stop_at_pass: bool,
    ) -> CommandResult {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2 and POPCNT.
        unsafe { raster_window::<OP>(tile, t, window, rejected, stop_at_pass) }
    }
}

/// Edge functions per lane: the value at the window's first row for each lane of its
/// first group, and the steps per group to the right and per row down. The edges
/// that do not hold on the whole window come first; the others are zero.
struct Edges {
    row: [__m256i; 3],
    per_group: [__m256i; 3],
    per_row: [__m256i; 3],
    /// How many edges do not hold on the whole window.
    live: usize,
}

/// Sets up `t`'s edges over the columns `c0..=c1` and rows `y0..=y1` (absolute;
/// `c0..c0 + 8` the first group's lanes); `None` when an edge excludes the whole
/// window.
///
/// The three edges are computed side by side in `i64` lanes, as
/// [`setup::edges_at`](super::setup::edges_at) and the reduction of
/// [`RasterTri::edges_at`] compute each (the products of `i32` differences are
/// exact in `i64`), without a branch on their values but for an empty window. The
/// vertices lie within the set-up's coordinate limit (2^23 fixed-point units), so
/// their differences fit `i32` lanes.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn edges(t: &RasterTri, c0: i32, c1: i32, y0: i32, y1: i32) -> Option<Edges> {
    // The vertices as i32 lanes x0 y0 x1 y1 x2 y2 (then `cmd` and `x0`, unused):
    // `verts` is the first field of the 64-byte `RasterTri`.
    // SAFETY: the 32 bytes lie inside `*t`.
    let v = unsafe { _mm256_loadu_si256(std::ptr::from_ref(t).cast()) };
    // Edge k runs from vertex k to vertex k + 1 (mod 3); lane 3 repeats edge 0.
    let from = _mm256_permutevar8x32_epi32(v, _mm256_setr_epi32(0, 2, 4, 0, 1, 3, 5, 1));
    let to = _mm256_permutevar8x32_epi32(v, _mm256_setr_epi32(2, 4, 0, 2, 3, 5, 1, 3));
    // The edge vectors (dx | dy) and the set-up pixel's centre relative to each
    // edge's first vertex (x | y), all within 2^25 in magnitude.
    let d = _mm256_sub_epi32(to, from);
    let (cx, cy) = (c0 * ONE as i32 + HALF as i32, y0 * ONE as i32 + HALF as i32);
    let centre = _mm256_setr_epi32(cx, cx, cx, cx, cy, cy, cy, cy);
    let r = _mm256_sub_epi32(centre, from);
    let wide = |v: __m256i, high: bool| {
        _mm256_cvtepi32_epi64(if high { _mm256_extracti128_si256::<1>(v) } else { _mm256_castsi256_si128(v) })
    };
    let (dx, dy, rx, ry) = (wide(d, false), wide(d, true), wide(r, false), wide(r, true));
    let zero = _mm256_setzero_si256();
    // Top-left rule (`edges_at`): a top or left edge has no bias, others 1.
    let top_left = _mm256_or_si256(
        _mm256_cmpgt_epi64(zero, dy),
        _mm256_and_si256(_mm256_cmpeq_epi64(dy, zero), _mm256_cmpgt_epi64(dx, zero)),
    );
    let origin = _mm256_sub_epi64(
        _mm256_sub_epi64(_mm256_sub_epi64(_mm256_mul_epi32(dx, ry), _mm256_mul_epi32(dy, rx)), top_left),
        _mm256_set1_epi64x(1),
    );
    // Reduced: g = origin >> 8 (arithmetic: the logical shift, sign bits filled in),
    // a = -dy, b = dx.
    let negative = _mm256_cmpgt_epi64(zero, origin);
    let g = _mm256_or_si256(
        _mm256_srli_epi64::<{ SUBPIXEL_BITS as i32 }>(origin),
        _mm256_slli_epi64::<{ 64 - SUBPIXEL_BITS as i32 }>(negative),
    );
    let (a, b) = (_mm256_sub_epi64(zero, dy), dx);
    // The extremes of g + a * i + b * j over the window, at its corners.
    let (ai, bj) = (
        _mm256_mul_epi32(a, _mm256_set1_epi64x(i64::from(c1 - c0))),
        _mm256_mul_epi32(b, _mm256_set1_epi64x(i64::from(y1 - y0))),
    );
    let below = |v: __m256i| _mm256_and_si256(v, _mm256_cmpgt_epi64(zero, v));
    let above = |v: __m256i| _mm256_andnot_si256(_mm256_cmpgt_epi64(zero, v), v);
    let lo = _mm256_add_epi64(_mm256_add_epi64(g, below(ai)), below(bj));
    let hi = _mm256_add_epi64(_mm256_add_epi64(g, above(ai)), above(bj));
    let lanes = |m: __m256i| (_mm256_movemask_pd(_mm256_castsi256_pd(m)) & 0b111) as usize;
    if lanes(_mm256_cmpgt_epi64(zero, hi)) != 0 {
        return None;
    }
    // Edges that hold everywhere (lo >= 0) are left out.
    let live = lanes(_mm256_cmpgt_epi64(zero, lo));
    debug_assert!(
        lanes(_mm256_or_si256(
            _mm256_cmpgt_epi64(_mm256_set1_epi64x(i64::from(i32::MIN)), lo),
            _mm256_cmpgt_epi64(hi, _mm256_set1_epi64x(i64::from(i32::MAX))),
        )) & live
            == 0,
        "a crossing edge's values fit i32 lanes"
    );
    // All values of a live edge fit an i32, and so do its slopes (|a|, |b| are at
    // most 2^24, so 8 * a fits too): the low halves of the i64 lanes.
    let low = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
    let (g, a, b) =
        (_mm256_permutevar8x32_epi32(g, low), _mm256_permutevar8x32_epi32(a, low), _mm256_permutevar8x32_epi32(b, low));
    // The live edges first, in order: slot s takes edge ORDER[live][s].
    const ORDER: [[i32; 3]; 8] =
        [[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [0, 2, 0], [1, 2, 0], [0, 1, 2]];
    let count = live.count_ones() as usize;
    let steps = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let mut out = Edges { row: [zero; 3], per_group: [zero; 3], per_row: [zero; 3], live: count };
    for (s, &k) in ORDER[live].iter().enumerate() {
        // Slots past the live edges stay zero: an edge function that never changes.
        let keep = _mm256_set1_epi32(-i32::from(s < count));
        let pick = |v: __m256i| _mm256_and_si256(_mm256_permutevar8x32_epi32(v, _mm256_set1_epi32(k)), keep);
        let (gs, as_, bs) = (pick(g), pick(a), pick(b));
        out.row[s] = _mm256_add_epi32(gs, _mm256_mullo_epi32(as_, steps));
        out.per_group[s] = _mm256_slli_epi32::<3>(as_);
        out.per_row[s] = bs;
    }
    Some(out)
}

/// [`Avx2::window`].
///
/// # Safety
/// The CPU must support AVX2 and POPCNT.
#[target_feature(enable = "avx2,popcnt")]
#[inline(never)]
unsafe fn raster_window<const OP: u8>(
    tile: &mut TileView<'_>,
    t: &RasterTri,
    window: [i32; 4],
    rejected: u64,
    stop_at_pass: bool,
) -> CommandResult {
    let [x0, x1, y0, y1] = window;
    let row_len = tile.rows.width();
    // Groups before `whole` lie wholly inside the tile's rows; a last group cut by
    // the end of the row is done pixel by pixel.
    let whole = row_len / GROUP;
    let (first, last) = ((x0 - tile.x0) as usize / GROUP, (x1 - tile.x0) as usize / GROUP);
    let c0 = tile.x0 + (first * GROUP) as i32;
    let Some(edges) = self::edges(t, c0, tile.x0 + (last * GROUP + GROUP - 1) as i32, y0, y1) else {
        return CommandResult::default();
    };
    let window = Window { first, end: (last + 1).min(whole), cut: last >= whole, c0, y0, y1 };
    // A window wholly inside the triangle needs no coverage test. Its groups lie
    // wholly in the window: the pixels of a group outside the window are outside
    // the bounding box (or the viewport), so not covered.
    debug_assert!(
        edges.live > 0 || (x0 == c0 && (last >= whole || x1 == c0 + ((last - first + 1) * GROUP) as i32 - 1))
    );
    // Windows without rejected blocks or a cut group (a draw's usual window) have
    // their groups unrolled.
    if rejected == 0 && !stop_at_pass && !window.cut {
        let plain = match window.end - window.first {
            1 => plain_rows_for::<OP, 1>(edges.live),
            2 => plain_rows_for::<OP, 2>(edges.live),
            3 => plain_rows_for::<OP, 3>(edges.live),
            4 => plain_rows_for::<OP, 4>(edges.live),
            5 => plain_rows_for::<OP, 5>(edges.live),
            6 => plain_rows_for::<OP, 6>(edges.live),
            7 => plain_rows_for::<OP, 7>(edges.live),
            _ => plain_rows_for::<OP, 8>(edges.live),
        };
        return plain(tile, t, &window, &edges);
    }
    // One loop per number of live edges, so that each tests only those.
    match (edges.live, stop_at_pass) {
        (0, false) => rows::<OP, 0, false>(tile, t, &window, &edges, rejected),
        (0, true) => rows::<OP, 0, true>(tile, t, &window, &edges, rejected),
        (1, false) => rows::<OP, 1, false>(tile, t, &window, &edges, rejected),
        (1, true) => rows::<OP, 1, true>(tile, t, &window, &edges, rejected),
        (2, false) => rows::<OP, 2, false>(tile, t, &window, &edges, rejected),
        (2, true) => rows::<OP, 2, true>(tile, t, &window, &edges, rejected),
        (_, false) => rows::<OP, 3, false>(tile, t, &window, &edges, rejected),
        (_, true) => rows::<OP, 3, true>(tile, t, &window, &edges, rejected),
    }
}

/// The whole groups `first..end` (and group `end` if `cut`) of the rows `y0..=y1`
/// of a window; `c0` is the first group's first column.
struct Window {
    first: usize,
    end: usize,
    cut: bool,
    c0: i32,
    y0: i32,
    y1: i32,
}

/// Per-lane sums of a window's groups: minus the lanes outside the triangle and
/// minus the lanes that passed (a lane's mask is -1 where it is set).
struct Sums {
    minus_outside: __m256i,
    minus_passed: __m256i,
}

/// The rows of [`raster_window`], finding the covered lanes by testing the first
/// `LIVE` edge functions (none: the window lies wholly inside the triangle); with
/// `STOP` (an any-pass query, which counts no fragments), stops after the first row
/// with a passing fragment and reports no fragments.
///
/// # Safety
/// The CPU must support AVX2 and POPCNT.
#[target_feature(enable = "avx2,popcnt")]
#[inline]
unsafe fn rows<const OP: u8, const LIVE: usize, const STOP: bool>(
    tile: &mut TileView<'_>,
    t: &RasterTri,
    window: &Window,
    edges: &Edges,
    rejected: u64,
) -> CommandResult {
    let &Window { first, end, cut, c0, y0, y1 } = window;
    let whole = tile.rows.width() / GROUP;
    // The groups `first..end` as bits (end <= 8).
    let groups = ((1u16 << end) - (1u16 << first)) as u8;
    let mut e_row = edges.row;
    // Only the groups `first..end` are written, and only those are read.
    let mut products = [const { MaybeUninit::<__m256>::uninit() }; BLOCKS];
    for (k, p) in products[first..end].iter_mut().enumerate() {
        p.write(depth_product(t, c0, k));
    }
    let dx0 = tile.x0 - t.x0;
    let cut_lanes = (1u32 << (tile.rows.width() - whole * GROUP)) - 1;
    let (mut rows_done, mut cut_fragments, mut scalar_passed) = (0u32, 0u32, 0u32);
    let zero = _mm256_setzero_si256();
    let mut sums = Sums { minus_outside: zero, minus_passed: zero };
    // The row's blocks, the cut one included.
    let row_blocks = groups | if cut { 1 << whole } else { 0 };
    for ly in (y0 - tile.y0) as usize..=(y1 - tile.y0) as usize {
        let skip = (rejected >> (BLOCKS * (ly / GROUP))) as u8;
        if LIVE == 0 && skip & row_blocks == row_blocks {
            // Every pixel of the row is covered and none can pass (a hidden query
            // box's usual row): only the count of its lanes is left.
            rows_done += 1;
            cut_fragments += if cut { cut_lanes.count_ones() } else { 0 };
            continue;
        }
        let row = tile.rows.row_mut(ly);
        let plane = t.row_plane(tile.y0 + ly as i32);
        let group_row =
            GroupRow { pixels: row.as_mut_ptr(), z_row: _mm256_set1_ps(plane.z_row), products: &products, first, end };
        // Rows that no rejected block crosses, the usual case for draws, run a loop
        // without the per-group test of the rejection bits.
        let e = if skip & groups == 0 {
            group_row.run::<OP, LIVE, false>(e_row, &edges.per_group, 0, &mut sums)
        } else {
            group_row.run::<OP, LIVE, true>(e_row, &edges.per_group, skip, &mut sums)
        };
        rows_done += 1;
        if cut {
            // `e` is now at group `whole`, cut by the end of the row.
            let outside = outside::<LIVE>(&e);
            let mut covered = !(_mm256_movemask_ps(_mm256_castsi256_ps(outside)) as u32) & cut_lanes;
            cut_fragments += covered.count_ones();
            if skip & (1 << whole) == 0 {
                while covered != 0 {
                    let c = whole * GROUP + covered.trailing_zeros() as usize;
                    covered &= covered - 1;
                    scalar_passed += u32::from(test_pixel::<OP>(plane.depth(dx0 + c as i32), &mut row[c]));
                }
            }
        }
        for (ek, step) in e_row.iter_mut().zip(&edges.per_row).take(LIVE) {
            *ek = _mm256_add_epi32(*ek, *step);
        }
        if STOP && (scalar_passed > 0 || _mm256_testz_si256(sums.minus_passed, sums.minus_passed) == 0) {
            break;
        }
    }
    let passed = scalar_passed + hsum(sums.minus_passed).wrapping_neg();
    let fragments = if STOP {
        0
    } else {
        let lanes = rows_done * (end - first) as u32 * GROUP as u32;
        lanes.wrapping_add(hsum(sums.minus_outside)) + cut_fragments
    };
    CommandResult { fragments: u64::from(fragments), passed: u64::from(passed) }
}

/// A [`plain_rows`] instance.
type PlainRows = unsafe fn(&mut TileView<'_>, &RasterTri, &Window, &Edges) -> CommandResult;

/// The [`plain_rows`] of `G` groups for `live` live edges.
fn plain_rows_for<const OP: u8, const G: usize>(live: usize) -> PlainRows {
    match live {
        0 => plain_rows::<OP, 0, G>,
        1 => plain_rows::<OP, 1, G>,
        2 => plain_rows::<OP, 2, G>,
        _ => plain_rows::<OP, 3, G>,
    }
}

/// The rows of [`raster_window`] for a window of `G` (1 to 8) whole groups with no
/// rejected block, no cut group and not stopping at a pass, testing the first
/// `LIVE` edge functions: [`rows`] with the groups unrolled and no per-row
/// bookkeeping (the depth plane's row value is stepped in a register, by the same
/// `f32` operations as [`RowPlane::of`](super::setup::RowPlane::of)).
///
/// # Safety
/// The CPU must support AVX2 and POPCNT.
#[target_feature(enable = "avx2,popcnt")]
#[inline]
unsafe fn plain_rows<const OP: u8, const LIVE: usize, const G: usize>(
    tile: &mut TileView<'_>,
    t: &RasterTri,
    window: &Window,
    edges: &Edges,
) -> CommandResult {
    let &Window { first, c0, y0, y1, .. } = window;
    let (ly0, ly1) = ((y0 - tile.y0) as usize, (y1 - tile.y0) as usize);
    // Checks that the window's last row lies in the tile; the groups lie in its rows.
    tile.rows.row_mut(ly1);
    debug_assert!(first + G <= tile.rows.width() / GROUP);
    let stride = tile.rows.stride();
    let mut pixels = tile.rows.row_mut(ly0).as_mut_ptr().add(first * GROUP);
    let mut products = [_mm256_setzero_ps(); G];
    for (k, p) in products.iter_mut().enumerate() {
        *p = depth_product(t, c0, k);
    }
    let (z_origin, z_dy) = (_mm256_set1_ps(t.z_origin), _mm256_set1_ps(t.z_dy));
    // The row's offset from the plane's origin row: an integer below 2^24, exact.
    let mut dy = _mm256_set1_ps((y0 - t.plane_y) as f32);
    let zero = _mm256_setzero_si256();
    let (mut minus_outside, mut minus_passed) = (zero, zero);
    let mut e_row = edges.row;
    for _ in ly0..=ly1 {
        let z_row = _mm256_add_ps(z_origin, _mm256_mul_ps(z_dy, dy));
        let mut e = e_row;
        for (g, &product) in products.iter().enumerate() {
            let outside = outside::<LIVE>(&e);
            minus_outside = _mm256_add_epi32(minus_outside, outside);
            // SAFETY: the group's 8 pixels lie inside the row (checked above).
            let pass = unsafe { depth_group::<OP>(pixels.add(g * GROUP), z_row, product, outside) };
            minus_passed = _mm256_add_epi32(minus_passed, pass);
            if g + 1 < G {
                for (ek, step) in e.iter_mut().zip(&edges.per_group).take(LIVE) {
                    *ek = _mm256_add_epi32(*ek, *step);
                }
            }
        }
        for (ek, step) in e_row.iter_mut().zip(&edges.per_row).take(LIVE) {
            *ek = _mm256_add_epi32(*ek, *step);
        }
        dy = _mm256_add_ps(dy, _mm256_set1_ps(1.0));
        // SAFETY: stays inside the tile's rows until the last row is done (the
        // pointer is not read after it).
        pixels = pixels.wrapping_add(stride);
    }
    let lanes = (ly1 - ly0 + 1) as u32 * (G * GROUP) as u32;
    CommandResult {
        fragments: u64::from(lanes.wrapping_add(hsum(minus_outside))),
        passed: u64::from(hsum(minus_passed).wrapping_neg()),
    }
}

/// The product `z_dx * dx` of [`RowPlane::depth`](super::setup::RowPlane::depth)
/// for the lanes of the group `k` groups right of the column `c0`: the same in
/// every row, so computed once per group of a window. The plane's pixel offsets
/// `dx` of the lanes are integers below 2^24, so exact in `f32`.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn depth_product(t: &RasterTri, c0: i32, k: usize) -> __m256 {
    let first = _mm256_set1_ps((c0 - t.x0 + (k * GROUP) as i32) as f32);
    let dx = _mm256_add_ps(first, _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0));
    _mm256_mul_ps(_mm256_set1_ps(t.z_dx), dx)
}

/// The lanes of a group outside the triangle by the first `LIVE` edge functions
/// `e`: -1 where one of them is negative (its sign bit set), else 0. A group wholly
/// outside the triangle is tested all the same (nothing passes): cheaper than the
/// mispredicted branches that skipping it costs.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn outside<const LIVE: usize>(e: &[__m256i; 3]) -> __m256i {
    match LIVE {
        0 => _mm256_setzero_si256(),
        1 => _mm256_srai_epi32::<31>(e[0]),
        2 => _mm256_srai_epi32::<31>(_mm256_or_si256(e[0], e[1])),
        _ => _mm256_srai_epi32::<31>(_mm256_or_si256(_mm256_or_si256(e[0], e[1]), e[2])),
    }
}

/// Depth-tests with operation `OP` (and for a draw, writes) the 8 pixels at `p`,
/// whose fragment depths are `max(z_row + product, 0)`, skipping the lanes set in
/// `outside`; returns the passing lanes as -1. The depth is
/// [`RowPlane::depth`](super::setup::RowPlane::depth)'s: `max` returns its second
/// operand, +0.0, unless the sum is > 0.
///
/// # Safety
/// The CPU must support AVX2; the 8 pixels at `p` must be the caller's to write.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn depth_group<const OP: u8>(p: *mut f32, z_row: __m256, product: __m256, outside: __m256i) -> __m256i {
    let z = _mm256_max_ps(_mm256_add_ps(z_row, product), _mm256_setzero_ps());
    // SAFETY: the caller promises the pixels.
    let mut d = unsafe { _mm256_loadu_ps(p) };
    // An empty statement that hides where `d` came from: LLVM would otherwise fuse
    // the load, blend and store below into a masked store (vmaskmovps), which is
    // microcoded and many times slower on AMD Zen.
    // SAFETY: the statement does nothing; `d` keeps its value.
    unsafe { std::arch::asm!("/* {0} */", inout(ymm_reg) d, options(pure, nomem, nostack, preserves_flags)) };
    let test = if OP == EQUAL { _mm256_cmp_ps::<_CMP_EQ_OQ>(z, d) } else { _mm256_cmp_ps::<_CMP_LT_OQ>(z, d) };
    let pass = _mm256_andnot_ps(_mm256_castsi256_ps(outside), test);
    if OP == DRAW {
        // SAFETY: as above.
        unsafe { _mm256_storeu_ps(p, _mm256_blendv_ps(d, z, pass)) };
    }
    _mm256_castps_si256(pass)
}

/// The sum of the eight `i32` lanes of `v`, as a `u32` (wrapping).
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn hsum(v: __m256i) -> u32 {
    let halves = _mm_add_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256::<1>(v));
    let pairs = _mm_add_epi32(halves, _mm_unpackhi_epi64(halves, halves));
    _mm_cvtsi128_si32(_mm_add_epi32(pairs, _mm_shuffle_epi32::<1>(pairs))) as u32
}

/// The whole groups `first..end` of one row of a window.
struct GroupRow<'a> {
    /// The tile row's first pixel.
    pixels: *mut f32,
    /// The depth plane along the row (`RowPlane::z_row`), in every lane.
    z_row: __m256,
    /// Per group of the tile row, `z_dx * dx` of its lanes (`RowPlane::depth`):
    /// written for the groups `first..end`.
    products: &'a [MaybeUninit<__m256>; BLOCKS],
    first: usize,
    end: usize,
}

impl GroupRow<'_> {
    /// Tests (and for a draw, writes) the row's groups with operation `OP`, the first
    /// `LIVE` edge functions `e` at group `first` stepping by `per_group`, and adds
    /// to `sums`; with `SKIPS`, the depth tests of the groups set in `skip` are
    /// skipped (their lanes are still counted). Returns the edge functions at group
    /// `end`.
    ///
    /// # Safety
    /// The CPU must support AVX2; the row must hold the groups' pixels.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn run<const OP: u8, const LIVE: usize, const SKIPS: bool>(
        &self,
        mut e: [__m256i; 3],
        per_group: &[__m256i; 3],
        skip: u8,
        sums: &mut Sums,
    ) -> [__m256i; 3] {
        for g in self.first..self.end {
            let outside = outside::<LIVE>(&e);
            sums.minus_outside = _mm256_add_epi32(sums.minus_outside, outside);
            if !(SKIPS && skip & (1 << g) != 0) {
                // SAFETY: the products of the groups `first..end` are written.
                let product = unsafe { self.products[g].assume_init() };
                // SAFETY: the caller promises the group's 8 pixels lie inside the row.
                let pass = unsafe { depth_group::<OP>(self.pixels.add(g * GROUP), self.z_row, product, outside) };
                sums.minus_passed = _mm256_add_epi32(sums.minus_passed, pass);
            }
            for (ek, step) in e.iter_mut().zip(per_group).take(LIVE) {
                *ek = _mm256_add_epi32(*ek, *step);
            }
        }
        e
    }
}
