//! The AVX2 versions of [`super::lanes`]' two steps and of the tile merge
//! ([`Tile::merge`]): the eight rows' intercepts of an edge in one `f32 x 8`
//! register, a 32x8-pixel tile's eight subtiles' masks (`i32 x 8`, a row's
//! 32 pixels a lane, then a byte transpose) and depth bounds (`f32 x 8` from
//! an `f64` base per subtile row) at once, and the eight subtiles merged by
//! compares and blends, loaded from and stored to the buffer's [`Tile`] as
//! three registers. Same operations in the same order as the portable
//! versions (products and sums rounded separately, never fused; `min` taking
//! the second operand on NaN as `f64::min` and `f32::min` take the non-NaN
//! one; `max` of the working depth and the new one in the portable merge's
//! order), so the results are bit-identical.

use std::arch::x86_64::*;

use super::lanes::{add_outside, outside, Lanes, Spans, TileRow, LANES, TILE_W, T_MIN};
use super::setup::{Batch, SETUP_LANES};
use super::{Band, CullMode, DepthPlane, Raster, ScreenTriangle};
use crate::buffer::{MergeMode, Tile};
use glam::Vec4;

/// Proof that the running CPU supports AVX2: a value exists only where it does,
/// which makes calling this module's `target_feature` functions sound.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(());

impl Avx2 {
    /// `Some` when the running CPU supports AVX2.
    pub(crate) fn detect() -> Option<Self> {
        is_x86_feature_detected!("avx2").then_some(Self(()))
    }

    /// [`lanes::tile_lanes`](super::lanes::tile_lanes), in AVX2 (on its own
    /// for the tests; the rasterizer runs it in [`Lanes::draw_tiles`]).
    #[cfg(test)]
    pub(crate) fn tile_lanes(self, tri: &Raster, spans: &Spans, tx: u32, ty: u32) -> ([u32; LANES], [f32; LANES]) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { tile_lanes(tri, spans, tx, ty) }
    }

    /// [`Band::draw`](super::Band) of one triangle in one AVX2 function, so
    /// that this module's steps ([`Lanes`]) inline into its loop.
    pub(crate) fn draw(self, band: &mut Band<'_>, tri: &ScreenTriangle) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { draw(self, band, tri) }
    }

    /// [`Band::draw`](super::Band) of lane `l` of `batch`, read in place.
    pub(crate) fn draw_lane(self, band: &mut Band<'_>, batch: &Batch, l: usize) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { draw_lane(self, band, batch, l) }
    }

    /// Four triangles set up at once ([`setup::setup4`](super::setup::setup4)).
    pub(crate) fn setup4(
        self,
        clip: &[[Vec4; 3]; SETUP_LANES],
        cull: CullMode,
        width: u32,
        height: u32,
        subpixel_bits: u32,
        batch: &mut Batch,
    ) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { super::setup::setup4(clip, cull, width, height, subpixel_bits, batch) }
    }

    /// [`Tile::merge`], in AVX2 (on its own for the tests; the rasterizer
    /// runs it in [`Lanes::draw_tiles`]).
    #[cfg(test)]
    pub(crate) fn merge(self, tile: &mut Tile, cover: &[u32; LANES], depth: &[f32; LANES], mode: MergeMode) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { merge(tile, cover, depth, mode) }
    }
}

impl Lanes for Avx2 {
    #[inline(always)]
    fn edge_spans(self, tri: &Raster, row: f32) -> Spans {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { edge_spans(tri, row) }
    }

    #[inline(always)]
    fn reach(self, spans: &Spans) -> Option<(i32, i32)> {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { reach(spans) }
    }

    /// Per tile, the masks and depth bounds
    /// ([`tile_lanes`](super::lanes::tile_lanes)), the padding pixels added
    /// to the lanes that cover something ([`add_outside`]), then
    /// [`merge_lanes`] on the tile's subtiles, with the spans, the plane's
    /// terms, masks and depth bounds kept in registers.
    #[inline(always)]
    fn draw_tiles(self, tiles: &mut [Tile], row: &TileRow<'_>, mode: MergeMode) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { draw_tiles(tiles, row, mode) }
    }
}

#[target_feature(enable = "avx2")]
unsafe fn draw(avx2: Avx2, band: &mut Band<'_>, tri: &ScreenTriangle) {
    band.draw_with(tri, avx2);
}

#[target_feature(enable = "avx2")]
unsafe fn draw_lane(avx2: Avx2, band: &mut Band<'_>, batch: &Batch, l: usize) {
    band.draw_with(&batch.drawn(l), avx2);
}

/// [`Spans::reach`] in lanes: the smallest `lo` and the largest `hi` of the
/// eight rows, by a fold of the halves and two shuffles each.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn reach(spans: &Spans) -> Option<(i32, i32)> {
    let (lo, hi) = (_mm256_load_si256(spans.lo.as_ptr().cast()), _mm256_load_si256(spans.hi.as_ptr().cast()));
    let lo = _mm_min_epi32(_mm256_castsi256_si128(lo), _mm256_extracti128_si256::<1>(lo));
    let hi = _mm_max_epi32(_mm256_castsi256_si128(hi), _mm256_extracti128_si256::<1>(hi));
    let lo = _mm_min_epi32(lo, _mm_shuffle_epi32::<0b01_00_11_10>(lo));
    let hi = _mm_max_epi32(hi, _mm_shuffle_epi32::<0b01_00_11_10>(hi));
    let left = _mm_cvtsi128_si32(_mm_min_epi32(lo, _mm_shuffle_epi32::<0b10_11_00_01>(lo)));
    let right = _mm_cvtsi128_si32(_mm_max_epi32(hi, _mm_shuffle_epi32::<0b10_11_00_01>(hi)));
    (left < right).then_some((left, right))
}

/// [`Lanes::draw_tiles`] in AVX2. Without a `target_feature` of its own so
/// that it can be inlined always (which Rust refuses for a `target_feature`
/// function): its intrinsics compile to AVX2 inside [`draw`] and
/// [`draw_lane`], the functions it is inlined into, which have the feature.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn draw_tiles(tiles: &mut [Tile], row: &TileRow<'_>, mode: MergeMode) {
    // One loop per merge rule, so that no tile tests it.
    match mode {
        MergeMode::LayerMerge => tile_loop(tiles, row, MergeMode::LayerMerge),
        MergeMode::QuickMask => tile_loop(tiles, row, MergeMode::QuickMask),
    }
}

/// [`draw_tiles`]' loop, for one merge rule.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn tile_loop(tiles: &mut [Tile], row: &TileRow<'_>, mode: MergeMode) {
    // Once for the row, so that the loop indexes unchecked.
    assert!((row.last as usize) < tiles.len(), "tiles beyond the band's tile row");
    let spans = row.spans;
    let (lo, hi) = (_mm256_load_si256(spans.lo.as_ptr().cast()), _mm256_load_si256(spans.hi.as_ptr().cast()));
    let mut depth = DepthLanes::new(&row.raster.plane, row.ty, row.raster.tile_columns().0, row.first);
    let mut x = _mm256_set1_epi32((row.first * TILE_W) as i32);
    let tiles = tiles.as_mut_ptr();
    for tx in row.first..row.last + 1 {
        let mut c = tile_cover(lo, hi, x);
        if tx >= row.padded_from {
            c = with_outside(c, row.screen, tx, row.ty);
        }
        let d = depth.next();
        // SAFETY: `tx <= last`, a tile of the row by the assertion above;
        // `Tile` is 32-byte aligned, its fields 32 bytes each.
        let tile = &mut *tiles.add(tx as usize);
        let mask = _mm256_load_si256(tile.mask.as_ptr().cast());
        let (working, reference) = (_mm256_load_ps(tile.working.as_ptr()), _mm256_load_ps(tile.reference.as_ptr()));
        let (mask, working, reference) = merge_lanes(mask, working, reference, c, d, mode);
        store(tile.mask.as_mut_ptr().cast(), mask);
        store(tile.working.as_mut_ptr().cast(), _mm256_castps_si256(working));
        store(tile.reference.as_mut_ptr().cast(), _mm256_castps_si256(reference));
        x = _mm256_add_epi32(x, _mm256_set1_epi32(TILE_W as i32));
    }
}

/// `v` stored to the 32 bytes at `p` (32-byte aligned), in assembly: LLVM
/// turns a blend of a loaded value stored back to the same place into a
/// masked store (`vmaskmovps`), which AMD's processors run slowly (the fill
/// rate fell by a fifth where it did).
///
/// # Safety
/// The CPU must support AVX2; `p` must be valid for writes of 32 bytes and
/// aligned to 32.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn store(p: *mut __m256i, v: __m256i) {
    std::arch::asm!(
        "vmovdqa ymmword ptr [{p}], {v}",
        p = in(reg) p,
        v = in(ymm_reg) v,
        options(nostack, preserves_flags),
    );
}

/// `cover` with the padding pixels of tile `tx` of tile row `ty` on a
/// `screen` added to its lanes that cover something ([`add_outside`]).
#[cold]
#[target_feature(enable = "avx2")]
unsafe fn with_outside(cover: __m256i, screen: (u32, u32), tx: u32, ty: u32) -> __m256i {
    let mut lanes = [0u32; LANES];
    _mm256_storeu_si256(lanes.as_mut_ptr().cast(), cover);
    add_outside(&mut lanes, &outside(screen, tx, ty));
    _mm256_loadu_si256(lanes.as_ptr().cast())
}

/// [`lanes::edge_spans`](super::lanes::edge_spans) in AVX2: an edge's
/// eight rows in one `f32` register, the three edges side by side
/// (unrolled), one test of all 24 rows against their bands, and only where
/// one fails (rare) the portable version ([`undecided_spans`]).
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn edge_spans(tri: &Raster, row: f32) -> Spans {
    let intercepts = &tri.lanes;
    let rows = _mm256_add_ps(_mm256_set1_ps(row), _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0));
    let (t_min, t_max) = (_mm256_set1_ps(T_MIN), _mm256_set1_ps(intercepts.t_max));
    let one = _mm256_set1_ps(1.0);
    // Per edge: the floor of its eight intercepts, and which of them lie
    // farther than the band from a pixel boundary.
    let intercept = |i: usize| {
        let slope = _mm256_set1_ps(intercepts.slope[i]);
        let t = _mm256_add_ps(_mm256_set1_ps(intercepts.base[i]), _mm256_mul_ps(slope, rows));
        // A NaN intercept becomes `t_max` (as in the portable clamp); its
        // band is then NaN or infinite too (it grows with `|u|` and `|slope|`,
        // and the `f64` band is infinite or NaN wherever the slope or offset
        // is), so no fraction passes and the edge goes to the exact rule.
        let t = _mm256_max_ps(_mm256_min_ps(t, t_max), t_min);
        let k = _mm256_floor_ps(t);
        let fraction = _mm256_sub_ps(t, k);
        let band = _mm256_set1_ps(intercepts.band[i]);
        let safe = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(fraction, band),
            _mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_sub_ps(one, fraction), band),
        );
        (k, safe)
    };
    let edges = [intercept(0), intercept(1), intercept(2)];
    let all_safe = _mm256_and_ps(_mm256_and_ps(edges[0].1, edges[1].1), edges[2].1);
    if _mm256_movemask_ps(all_safe) != 0xFF {
        return undecided_spans(*tri, row);
    }
    // Each edge bounds `lo` (inside to its right) or `hi`, chosen by a blend
    // rather than a branch: which it is changes from triangle to triangle, so
    // a branch would be mispredicted on about every step.
    let (mut lo, mut hi) = (_mm256_setzero_si256(), _mm256_set1_epi32(tri.x1 - tri.x0));
    let (none_lo, none_hi) = (_mm256_set1_epi32(i32::MIN), _mm256_set1_epi32(i32::MAX));
    for (i, (k, _)) in edges.iter().enumerate() {
        let bound = _mm256_cvttps_epi32(*k);
        let right = _mm256_set1_epi32(intercepts.right[i]);
        lo = _mm256_max_epi32(lo, _mm256_blendv_epi8(none_lo, bound, right));
        hi = _mm256_min_epi32(hi, _mm256_blendv_epi8(bound, none_hi, right));
    }
    let x0 = _mm256_set1_epi32(tri.x0);
    let mut spans = Spans { lo: [0; 8], hi: [0; 8], exact: 0 };
    _mm256_store_si256(spans.lo.as_mut_ptr().cast(), _mm256_add_epi32(lo, x0));
    _mm256_store_si256(spans.hi.as_mut_ptr().cast(), _mm256_add_epi32(hi, x0));
    spans
}

/// [`edge_spans`] of a tile row where an intercept lies within its band of
/// a pixel boundary (rare): the portable version's, which is the same but
/// for the edges it leaves to the exact rule ([`Spans::exact`]). The
/// triangle by value, so that the caller's stays out of memory.
#[cold]
fn undecided_spans(tri: Raster, row: f32) -> Spans {
    super::lanes::edge_spans(&tri, row)
}

#[cfg(test)]
#[target_feature(enable = "avx2")]
unsafe fn tile_lanes(tri: &Raster, spans: &Spans, tx: u32, ty: u32) -> ([u32; LANES], [f32; LANES]) {
    let (lo, hi) = (_mm256_load_si256(spans.lo.as_ptr().cast()), _mm256_load_si256(spans.hi.as_ptr().cast()));
    let mut out = ([0u32; LANES], [0f32; LANES]);
    _mm256_storeu_si256(out.0.as_mut_ptr().cast(), tile_cover(lo, hi, _mm256_set1_epi32((tx * TILE_W) as i32)));
    _mm256_storeu_ps(out.1.as_mut_ptr(), DepthLanes::new(&tri.plane, ty, tri.tile_columns().0, tx).next());
    out
}

/// [`DepthPlane::subtile_bound`](super::DepthPlane) of the eight subtiles of
/// each tile of a tile row, tile by tile: per subtile row the base at the
/// corner of the anchor (the first tile of the triangle's window) in `f64`
/// (the two rows in two lanes), rounded far to `f32`, once for the row; the
/// lanes' offsets `m` steps (exact), kept in a register and stepped by four
/// steps a tile (exact sums of exact multiples, so the same values); per tile
/// their sum with the base nudged far and capped in `f32` lanes: the portable
/// version's operations in its order.
struct DepthLanes {
    /// The base of the upper subtile row in lanes 0-3, of the lower in 4-7.
    base: __m256,
    /// The next tile's lanes' offsets from the base.
    offsets: __m256,
    /// Four steps: from a tile's offsets to the next one's.
    tile_step: __m256,
    cap: __m256,
}

impl DepthLanes {
    /// The bounds' terms for the tiles of tile row `ty` from tile `first`,
    /// anchored at tile `anchor` (at or left of `first`).
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn new(plane: &DepthPlane, ty: u32, anchor: u32, first: u32) -> Self {
        // `far_at` (the plane, then `round_far`) of both subtile rows in the
        // two lanes of one `f64 x 2`; the corner's column is a whole number,
        // so converted exactly.
        let x = _mm_set1_pd(plane.zx * plane.corner_x(f64::from(anchor * TILE_W)));
        let v = _mm_add_pd(x, row_terms(plane, ty));
        let nudge = _mm_mul_pd(_mm_andnot_pd(_mm_set1_pd(-0.0), v), _mm_set1_pd(super::FAR_NUDGE));
        let far = _mm_cvtpd_ps(_mm_add_pd(_mm_add_pd(v, nudge), _mm_set1_pd(1e-12)));
        let step = _mm256_set1_ps(plane.lane_step());
        // Whole numbers below 2^24: converted exactly, and products exact by
        // the step's zero bits.
        let m = _mm256_add_epi32(
            _mm256_set1_epi32((4 * (first - anchor)) as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 0, 1, 2, 3),
        );
        DepthLanes {
            base: _mm256_set_m128(_mm_shuffle_ps::<0b01_01_01_01>(far, far), _mm_shuffle_ps::<0>(far, far)),
            offsets: _mm256_mul_ps(step, _mm256_cvtepi32_ps(m)),
            tile_step: _mm256_mul_ps(step, _mm256_set1_ps(4.0)),
            cap: _mm256_set1_ps(plane.far_max()),
        }
    }

    /// The bounds of the next tile's eight subtiles (the first tile's, on
    /// the first call).
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn next(&mut self) -> __m256 {
        // `far_sum` on eight lanes.
        let sum = _mm256_add_ps(self.base, self.offsets);
        self.offsets = _mm256_add_ps(self.offsets, self.tile_step);
        let nudge = _mm256_mul_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0), sum), _mm256_set1_ps(super::FAR_NUDGE_F32));
        _mm256_min_ps(_mm256_add_ps(sum, nudge), self.cap)
    }
}

/// [`DepthPlane::row_term`](super::DepthPlane) of the two subtile rows of
/// tile row `ty` (the upper one in the low lane), in the lanes of one
/// `f64 x 2`: the same sum, product and sum.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn row_terms(plane: &DepthPlane, ty: u32) -> __m128d {
    let by = _mm_cvtepi32_pd(_mm_setr_epi32((ty * 8) as i32, (ty * 8 + 4) as i32, 0, 0));
    let y = _mm_add_pd(by, _mm_set1_pd(if plane.zy > 0.0 { 4.0 } else { 0.0 }));
    _mm_add_pd(_mm_mul_pd(_mm_set1_pd(plane.zy), y), _mm_set1_pd(plane.z0))
}

/// The coverage masks of the eight subtiles of the tile whose first column
/// is `x` (in every lane), from the eight rows' span ends `lo` and `hi`:
/// each pixel row's span as one 32-bit row of the tile, a lane a row (ones
/// from `lo` on, less ones from `hi` on: variable shifts, which give 0 from
/// 32 on), then each 128-bit half's 4 x 4 bytes transposed so that subtile
/// column `c` takes byte `c` of each of its four rows.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn tile_cover(lo: __m256i, hi: __m256i, x: __m256i) -> __m256i {
    let zero = _mm256_setzero_si256();
    let column = |v: __m256i| _mm256_max_epi32(_mm256_sub_epi32(v, x), zero);
    let ones = _mm256_set1_epi32(-1);
    let rows = _mm256_andnot_si256(shift_left(ones, column(hi)), shift_left(ones, column(lo)));
    _mm256_shuffle_epi8(
        rows,
        _mm256_setr_epi8(
            0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15, 0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15,
        ),
    )
}

/// `v << count` per lane, 0 where `count` is 32 or more: `vpsllvd` itself,
/// in assembly because LLVM adds a compare and a blend to the intrinsic for
/// the counts beyond 31, for which the instruction already gives 0.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn shift_left(v: __m256i, count: __m256i) -> __m256i {
    let out;
    std::arch::asm!(
        "vpsllvd {out}, {v}, {count}",
        out = lateout(ymm_reg) out,
        v = in(ymm_reg) v,
        count = in(ymm_reg) count,
        options(pure, nomem, nostack, preserves_flags),
    );
    out
}

/// [`Subtile::merge`](crate::buffer::Subtile::merge) on eight lanes, each
/// step a comparison and a blend; lanes whose cover `c` is empty, or whose
/// depth `d` is NaN or not nearer than the reference, keep their subtile.
/// Returns the new mask, working and reference layers.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn merge_lanes(
    mask: __m256i,
    working: __m256,
    reference: __m256,
    c: __m256i,
    d: __m256,
    mode: MergeMode,
) -> (__m256i, __m256, __m256) {
    let zero = _mm256_setzero_si256();
    // Taken: a cover, and a depth nearer than the reference (false on NaN).
    let nearer = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(d, reference));
    let taken = _mm256_andnot_si256(_mm256_cmpeq_epi32(c, zero), nearer);
    let mut m = mask;
    if mode == MergeMode::LayerMerge {
        let distance = _mm256_andnot_ps(_mm256_set1_ps(-0.0), _mm256_sub_ps(d, working));
        let discard = _mm256_andnot_si256(
            _mm256_cmpeq_epi32(mask, zero),
            _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OQ>(distance, _mm256_sub_ps(reference, working))),
        );
        m = _mm256_andnot_si256(discard, m);
    }
    let w = _mm256_blendv_ps(_mm256_max_ps(working, d), d, _mm256_castsi256_ps(_mm256_cmpeq_epi32(m, zero)));
    let m = _mm256_or_si256(m, c);
    let full = _mm256_cmpeq_epi32(m, _mm256_set1_epi32(-1));
    let r = _mm256_blendv_ps(reference, w, _mm256_castsi256_ps(full));
    let m = _mm256_andnot_si256(full, m);
    let taken_ps = _mm256_castsi256_ps(taken);
    (
        _mm256_blendv_epi8(mask, m, taken),
        _mm256_blendv_ps(working, w, taken_ps),
        _mm256_blendv_ps(reference, r, taken_ps),
    )
}

/// [`merge_lanes`] on a tile in memory (for the tests).
#[cfg(test)]
#[target_feature(enable = "avx2")]
unsafe fn merge(tile: &mut Tile, cover: &[u32; LANES], depth: &[f32; LANES], mode: MergeMode) {
    let (c, d) = (_mm256_loadu_si256(cover.as_ptr().cast()), _mm256_loadu_ps(depth.as_ptr()));
    let mask = _mm256_load_si256(tile.mask.as_ptr().cast());
    let (working, reference) = (_mm256_load_ps(tile.working.as_ptr()), _mm256_load_ps(tile.reference.as_ptr()));
    let (mask, working, reference) = merge_lanes(mask, working, reference, c, d, mode);
    _mm256_store_si256(tile.mask.as_mut_ptr().cast(), mask);
    _mm256_store_ps(tile.working.as_mut_ptr(), working);
    _mm256_store_ps(tile.reference.as_mut_ptr(), reference);
}
