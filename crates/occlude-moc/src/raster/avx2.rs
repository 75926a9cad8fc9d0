//! The AVX2 versions of [`super::lanes`]' two steps and of the group merge
//! ([`Group::merge`]): the four rows' intercepts of an edge in one `f64 x 4`
//! register, eight subtiles' masks (`i32 x 8`) and depth bounds (`f32 x 8`
//! from one `f64` base) at once, and a group's eight subtiles merged by
//! compares and blends. Same operations in the same order as the portable
//! versions (products and sums rounded separately, never fused; `min` taking
//! the second operand on NaN as `f64::min` and `f32::min` take the non-NaN
//! one; `max` of the working depth and the new one in the portable merge's
//! order), so the results are bit-identical.

use std::arch::x86_64::*;

use super::lanes::{add_outside, outside, GroupStep, Lanes, Spans, LANES};
use super::setup::{Batch, SETUP_LANES};
use super::{Band, CullMode, DepthPlane, ScreenTriangle};
use crate::buffer::{Group, MergeMode};
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

    /// [`lanes::subtile_lanes`](super::lanes::subtile_lanes), in AVX2 (on its
    /// own for the tests; the rasterizer runs it in [`Lanes::draw_group`]).
    #[cfg(test)]
    pub(crate) fn subtile_lanes(
        self,
        tri: &ScreenTriangle,
        spans: &Spans,
        sx: u32,
        sy: u32,
    ) -> ([u32; LANES], [f32; LANES]) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { subtile_lanes(tri, spans, sx, sy) }
    }

    /// [`Band::draw`](super::Band) of one triangle in one AVX2 function, so
    /// that this module's steps ([`Lanes`]) inline into its loop.
    pub(crate) fn draw(self, band: &mut Band<'_>, tri: &ScreenTriangle) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { draw(self, band, tri) }
    }

    /// Four triangles set up at once ([`setup::setup4`](super::setup::setup4)).
    pub(crate) fn setup4(
        self,
        clip: &[[Vec4; 3]; SETUP_LANES],
        cull: CullMode,
        width: u32,
        height: u32,
        subpixel_bits: u32,
    ) -> Batch {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { super::setup::setup4(clip, cull, width, height, subpixel_bits) }
    }

    /// [`Group::merge`], in AVX2 (on its own for the tests; the rasterizer
    /// runs it in [`Lanes::draw_group`]).
    #[cfg(test)]
    pub(crate) fn merge(self, group: &mut Group, cover: &[u32; LANES], depth: &[f32; LANES], mode: MergeMode) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { merge(group, cover, depth, mode) }
    }
}

impl Lanes for Avx2 {
    type Intercepts = [__m256d; 3];

    #[inline(always)]
    fn first_intercepts(self, tri: &ScreenTriangle, y: i32) -> [__m256d; 3] {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { first_intercepts(tri, y) }
    }

    #[inline(always)]
    fn edge_spans(self, tri: &ScreenTriangle, intercepts: &mut [__m256d; 3]) -> Spans {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { edge_spans(tri, intercepts) }
    }

    #[inline(always)]
    fn reach(self, spans: &Spans) -> Option<(i32, i32)> {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { reach(spans) }
    }

    /// The group's masks and depth bounds ([`subtile_lanes`]), the padding
    /// pixels added to the lanes that cover something
    /// ([`add_outside`]), then [`merge`], with the
    /// masks and depth bounds kept in registers.
    #[inline(always)]
    fn draw_group(self, group: &mut Group, step: &GroupStep<'_>, mode: MergeMode) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { draw_group(group, step, mode) }
    }
}

#[target_feature(enable = "avx2")]
unsafe fn draw(avx2: Avx2, band: &mut Band<'_>, tri: &ScreenTriangle) {
    band.draw_with(tri, avx2);
}

/// [`Spans::reach`] in lanes: the smallest `lo` and the largest `hi`, by two
/// shuffles each.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn reach(spans: &Spans) -> Option<(i32, i32)> {
    let (lo, hi) = (_mm_loadu_si128(spans.lo.as_ptr().cast()), _mm_loadu_si128(spans.hi.as_ptr().cast()));
    let lo = _mm_min_epi32(lo, _mm_shuffle_epi32::<0b01_00_11_10>(lo));
    let hi = _mm_max_epi32(hi, _mm_shuffle_epi32::<0b01_00_11_10>(hi));
    let left = _mm_cvtsi128_si32(_mm_min_epi32(lo, _mm_shuffle_epi32::<0b10_11_00_01>(lo)));
    let right = _mm_cvtsi128_si32(_mm_max_epi32(hi, _mm_shuffle_epi32::<0b10_11_00_01>(hi)));
    (left < right).then_some((left, right))
}

#[inline]
#[target_feature(enable = "avx2")]
unsafe fn draw_group(group: &mut Group, step: &GroupStep<'_>, mode: MergeMode) {
    let (mut cover, depth) = subtile_lanes(step.tri, step.spans, step.sx, step.sy);
    if let Some(screen) = step.outside {
        add_outside(&mut cover, &outside(screen, step.sx, step.sy));
    }
    merge(group, &cover, &depth, mode);
}

/// [`lanes::first_intercepts`](super::lanes::first_intercepts) in AVX2: an
/// edge's four rows in one register.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn first_intercepts(tri: &ScreenTriangle, y: i32) -> [__m256d; 3] {
    let rows = _mm_add_epi32(_mm_set1_epi32(y), _mm_setr_epi32(0, 1, 2, 3));
    let py = _mm256_add_pd(_mm256_cvtepi32_pd(rows), _mm256_set1_pd(0.5));
    std::array::from_fn(|i| {
        let edge = &tri.edges[i];
        let t = _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(edge.slope), py), _mm256_set1_pd(edge.offset));
        _mm256_add_pd(t, _mm256_set1_pd(0.5))
    })
}

/// [`lanes::edge_spans`](super::lanes::edge_spans) in AVX2: the three edges
/// side by side (unrolled), their intercepts stepped by an addition each, one
/// test of all twelve rows against their bands, and only where one fails
/// (rare) the per-edge [`Spans::exact`] bits.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn edge_spans(tri: &ScreenTriangle, intercepts: &mut [__m256d; 3]) -> Spans {
    let (t_min, t_max) = (_mm256_set1_pd(tri.t_min), _mm256_set1_pd(tri.t_max));
    let one = _mm256_set1_pd(1.0);
    let (mut lo, mut hi) = (_mm_set1_epi32(tri.x0), _mm_set1_epi32(tri.x1));
    // Per edge: the floor of its four intercepts, and which of them lie
    // farther than the band from a pixel boundary.
    let mut intercept = |i: usize| {
        let (edge, band) = (&tri.edges[i], _mm256_set1_pd(tri.bands[i]));
        let t = intercepts[i];
        intercepts[i] = _mm256_add_pd(t, _mm256_set1_pd(edge.slope * 4.0));
        // A NaN intercept becomes `t_max` (as in the portable clamp). On a
        // row of the screen that leaves the edge to the exact rule all the
        // same: an intercept there is NaN or infinite only where the slope, the
        // offset or their terms' sum bounded by `|slope| y_max + |offset|` is,
        // so the band ([`Edge::band`](super::Edge)) is infinite or NaN too,
        // and no fraction exceeds it.
        let t = _mm256_max_pd(_mm256_min_pd(t, t_max), t_min);
        let k = _mm256_floor_pd(t);
        let fraction = _mm256_sub_pd(t, k);
        let safe = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_GT_OQ>(fraction, band),
            _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_sub_pd(one, fraction), band),
        );
        (k, safe)
    };
    let edges = [intercept(0), intercept(1), intercept(2)];
    let all_safe = _mm256_and_pd(_mm256_and_pd(edges[0].1, edges[1].1), edges[2].1);
    let mut exact = 0u8;
    if _mm256_movemask_pd(all_safe) != 0xF {
        for (i, (_, safe)) in edges.iter().enumerate() {
            if _mm256_movemask_pd(*safe) != 0xF {
                exact |= 1 << i;
            }
        }
    }
    // Each edge bounds `lo` (inside to its right) or `hi`, chosen by a blend
    // rather than a branch: which it is changes from triangle to triangle, so
    // a branch would be mispredicted on about every subtile row.
    let (none_lo, none_hi) = (_mm_set1_epi32(i32::MIN), _mm_set1_epi32(i32::MAX));
    for (i, (k, _)) in edges.iter().enumerate() {
        if exact >> i & 1 == 0 {
            let bound = _mm256_cvttpd_epi32(*k);
            let right = _mm_set1_epi32(-i32::from(tri.edges[i].a > 0.0));
            lo = _mm_max_epi32(lo, _mm_blendv_epi8(none_lo, bound, right));
            hi = _mm_min_epi32(hi, _mm_blendv_epi8(bound, none_hi, right));
        }
    }
    let mut spans = Spans { lo: [0; 4], hi: [0; 4], exact };
    _mm_storeu_si128(spans.lo.as_mut_ptr().cast(), lo);
    _mm_storeu_si128(spans.hi.as_mut_ptr().cast(), hi);
    spans
}

#[inline]
#[target_feature(enable = "avx2")]
unsafe fn subtile_lanes(tri: &ScreenTriangle, spans: &Spans, sx: u32, sy: u32) -> ([u32; LANES], [f32; LANES]) {
    let cover = group_cover(spans, sx);
    let mut out = ([0u32; LANES], [0f32; LANES]);
    _mm256_storeu_si256(out.0.as_mut_ptr().cast(), cover);
    _mm256_storeu_ps(out.1.as_mut_ptr(), depth_bounds(&tri.plane, sx, sy));
    out
}

/// [`DepthPlane::subtile_bound`](super::DepthPlane) of the eight subtiles of
/// the group from subtile column `sx` of row `sy`: the group's base in `f64`
/// (scalar), then its lanes' steps added and the cap taken in `f32` lanes,
/// with the portable version's operations in its order.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn depth_bounds(plane: &DepthPlane, sx: u32, sy: u32) -> __m256 {
    let base = plane.far_at(plane.corner_x(f64::from(sx * 8)), plane.row_term(f64::from(sy * 4)));
    let steps =
        _mm256_mul_ps(_mm256_set1_ps(plane.lane_step()), _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0));
    // `far_sum` on eight lanes.
    let sum = _mm256_add_ps(_mm256_set1_ps(base), steps);
    let nudge = _mm256_mul_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0), sum), _mm256_set1_ps(super::FAR_NUDGE_F32));
    _mm256_min_ps(_mm256_add_ps(sum, nudge), _mm256_set1_ps(plane.far_max()))
}

/// The coverage masks of the eight subtiles of the group from subtile column
/// `sx` (64 pixels wide): each pixel row's span as one 64-bit row of the
/// group (ones from `lo` on, less ones from `hi` on: variable shifts, which
/// give 0 from 64 on), then the 4 x 8 bytes transposed so that subtile `l`
/// takes byte `l` of each row.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn group_cover(spans: &Spans, sx: u32) -> __m256i {
    let (gx, zero) = (_mm_set1_epi32(sx as i32 * 8), _mm_setzero_si128());
    let column = |x: &[i32; 4]| {
        _mm256_cvtepu32_epi64(_mm_max_epi32(_mm_sub_epi32(_mm_loadu_si128(x.as_ptr().cast()), gx), zero))
    };
    let ones = _mm256_set1_epi64x(-1);
    let rows =
        _mm256_andnot_si256(_mm256_sllv_epi64(ones, column(&spans.hi)), _mm256_sllv_epi64(ones, column(&spans.lo)));
    // Per 128-bit half (rows 0, 1 and rows 2, 3): byte l of the two rows side
    // by side, for l = 0..8.
    let pairs = _mm256_shuffle_epi8(
        rows,
        _mm256_setr_epi8(
            0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15, 0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15,
        ),
    );
    // Subtiles 0-3 in the low half, 4-7 in the high half, each half's rows
    // 0, 1 pairs then rows 2, 3 pairs; then each subtile's two pairs joined.
    let halves = _mm256_permute4x64_epi64::<0b11_01_10_00>(pairs);
    _mm256_shuffle_epi8(
        halves,
        _mm256_setr_epi8(
            0, 1, 8, 9, 2, 3, 10, 11, 4, 5, 12, 13, 6, 7, 14, 15, 0, 1, 8, 9, 2, 3, 10, 11, 4, 5, 12, 13, 6, 7, 14, 15,
        ),
    )
}

/// [`Subtile::merge`](crate::buffer::Subtile::merge) on eight lanes, each
/// step a comparison and a blend; lanes whose cover is empty, or whose depth is
/// NaN or not nearer than the reference, keep their subtile.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn merge(group: &mut Group, cover: &[u32; LANES], depth: &[f32; LANES], mode: MergeMode) {
    let zero = _mm256_setzero_si256();
    let c = _mm256_loadu_si256(cover.as_ptr().cast());
    let d = _mm256_loadu_ps(depth.as_ptr());
    let mask = _mm256_load_si256(group.mask.as_ptr().cast());
    let working = _mm256_load_ps(group.working.as_ptr());
    let reference = _mm256_load_ps(group.reference.as_ptr());
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
    _mm256_store_si256(group.mask.as_mut_ptr().cast(), _mm256_blendv_epi8(mask, m, taken));
    _mm256_store_ps(group.working.as_mut_ptr(), _mm256_blendv_ps(working, w, taken_ps));
    _mm256_store_ps(group.reference.as_mut_ptr(), _mm256_blendv_ps(reference, r, taken_ps));
}
