//! The set-up of four triangles at once in AVX2 (`f64 x 4` lanes, one
//! triangle a lane), after MOC's batched set-up (HPG 2016 section 4 sets up
//! several triangles per SIMD pass): projection, snapping to the sub-pixel
//! grid, winding and area rejection, the pixel window, the edges with their
//! intercept bands, and the depth plane.
//!
//! It covers the common case only: a triangle wholly in front of the near plane
//! with finite coordinates, `w > 0` and its vertices within the snapping range
//! (`crate::project`'s conditions for snapping). A lane outside it is left to
//! the scalar [`screen_triangles`](crate::project::screen_triangles). Every
//! lane does the scalar path's `f64` operations in the same order (products
//! and sums rounded separately, never fused; the same rounding of halves away
//! from zero), so a triangle set up here is bit for bit the scalar one; the
//! tests check it on random triangles.

use std::arch::x86_64::*;

use glam::Vec4;

use super::lanes::{Intercepts, F32_SCALE};
use super::{step_zero_bits, CullMode, DepthPlane, Edge, Exact, Raster, SetUp, BAND_SCALE, FAR_NUDGE};
use crate::project::{DRAW_LIMIT, SNAP_LIMIT, SNAP_RANGE};

/// Triangles set up by one [`setup4`] call.
pub(crate) const SETUP_LANES: usize = 4;

/// Four triangles set up by [`setup4`], lane by lane, in the registers'
/// layout, where the traversal reads them ([`Batch::drawn`]).
pub(crate) struct Batch {
    /// Bit `l` set: lane `l` was set up here (else it is for the scalar
    /// set-up).
    common: i32,
    /// Bit `l` set: lane `l`'s triangle is not drawn (culled, zero area, or no
    /// pixel centre on screen, as
    /// [`ScreenTriangle::new`](super::ScreenTriangle::new) rejects).
    rejected: i32,
    /// Per edge: `a`, `b`, `c`, `slope`, `offset`, `band`.
    edges: [[[f64; SETUP_LANES]; 6]; 3],
    /// Per edge, bit `l`: [`Edge`]'s `on` of lane `l`.
    on: [i32; 3],
    /// Per edge, bit `l`: whether lane `l`'s edge has `a > 0`
    /// ([`Intercepts`]' `right`).
    right: [i32; 3],
    /// `x0`, `x1`, `y0`, `y1`, converted in lanes.
    window: [[i32; SETUP_LANES]; 4],
    /// The plane's `zx`, `zy`, `z0`.
    plane: [[f64; SETUP_LANES]; 3],
    /// The plane's `f32` step and cap ([`DepthPlane::from_terms`]).
    plane_f32: [[f32; SETUP_LANES]; 2],
    /// Per edge: [`Intercepts`]' `base`, `slope` and `band`.
    lanes: [[[f32; SETUP_LANES]; 3]; 3],
    /// [`Intercepts`]' `t_max`.
    t_max: [f32; SETUP_LANES],
    /// Bit `l` set: lane `l`'s triangle has a horizontal edge
    /// ([`Intercepts`]' `flat`).
    flat: i32,
    /// Per lane, the 32x8-pixel tiles its window overlaps
    /// ([`Raster::tiles`](super::Raster)), where it is drawn.
    tiles: [i32; SETUP_LANES],
}

impl Batch {
    /// A batch of no triangles, for [`setup4`] to fill.
    pub(crate) const EMPTY: Batch = Batch {
        common: 0,
        rejected: 0,
        edges: [[[0.0; SETUP_LANES]; 6]; 3],
        on: [0; 3],
        right: [0; 3],
        window: [[0; SETUP_LANES]; 4],
        plane: [[0.0; SETUP_LANES]; 3],
        plane_f32: [[0.0; SETUP_LANES]; 2],
        lanes: [[[0.0; SETUP_LANES]; 3]; 3],
        t_max: [0.0; SETUP_LANES],
        flat: 0,
        tiles: [0; SETUP_LANES],
    };

    /// Bit `l` set: lane `l`'s triangle is drawn (set up here, and not
    /// rejected).
    #[inline]
    pub(crate) fn drawn_lanes(&self) -> u32 {
        (self.common & !self.rejected) as u32
    }

    /// Bit `l` set: lane `l`'s triangle is outside the common case, for the
    /// scalar set-up.
    #[inline]
    pub(crate) fn scalar_lanes(&self) -> u32 {
        !self.common as u32 & ((1 << SETUP_LANES) - 1)
    }

    /// The tiles the windows of the lanes whose bits `lanes` has overlap,
    /// where those lanes are drawn.
    #[inline]
    pub(crate) fn tiles(&self, lanes: u32) -> u64 {
        (0..SETUP_LANES).filter(|l| lanes >> l & 1 == 1).map(|l| self.tiles[l] as u64).sum()
    }

    /// Lane `l`'s triangle, where it is drawn ([`Self::drawn_lanes`]).
    #[inline]
    pub(crate) fn drawn(&self, l: usize) -> Lane<'_> {
        Lane { batch: self, l }
    }
}

/// A triangle of a [`Batch`], read in place: the traversal loads its fields
/// from the batch's lanes, where the set-up stored them.
pub(crate) struct Lane<'a> {
    batch: &'a Batch,
    l: usize,
}

impl SetUp for Lane<'_> {
    #[inline(always)]
    fn raster(&self) -> Raster {
        let (b, l) = (self.batch, self.l);
        let (v, p, f) = (&b.window, &b.plane, &b.plane_f32);
        let lanes = &b.lanes;
        Raster {
            x0: v[0][l],
            x1: v[1][l],
            y0: v[2][l],
            y1: v[3][l],
            plane: DepthPlane { zx: p[0][l], zy: p[1][l], z0: p[2][l], step: f[0][l], cap: f[1][l] },
            lanes: Intercepts {
                base: [lanes[0][0][l], lanes[1][0][l], lanes[2][0][l]],
                slope: [lanes[0][1][l], lanes[1][1][l], lanes[2][1][l]],
                band: [lanes[0][2][l], lanes[1][2][l], lanes[2][2][l]],
                right: b.right.map(|bits| -(bits >> l & 1)),
                t_max: b.t_max[l],
                flat: b.flat >> l & 1 == 1,
            },
        }
    }

    fn exact(&self) -> Exact {
        let (b, l) = (self.batch, self.l);
        let edge = |i: usize| {
            let e = &b.edges[i];
            Edge { a: e[0][l], b: e[1][l], c: e[2][l], on: b.on[i] >> l & 1 == 1, slope: e[3][l], offset: e[4][l] }
        };
        Exact { edges: [edge(0), edge(1), edge(2)], bands: [b.edges[0][5][l], b.edges[1][5][l], b.edges[2][5][l]] }
    }
}

/// The four clip-space triangles `clip` set up on a `width` x `height` screen
/// with vertices snapped to `1 / 2^subpixel_bits` pixel, as the scalar
/// [`screen_triangles`](crate::project::screen_triangles) sets up a triangle
/// that needs no clipping, into `batch` (written in place, not returned: a
/// batch is large, and a returned one may be copied). It writes every
/// field that the lanes it sets up are read from; the other lanes' fields
/// keep the last call's values, which nothing reads.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn setup4(
    clip: &[[Vec4; 3]; SETUP_LANES],
    cull: CullMode,
    width: u32,
    height: u32,
    subpixel_bits: u32,
    batch: &mut Batch,
) {
    let (w, h) = (f64::from(width), f64::from(height));
    let (wv, hv) = (_mm256_set1_pd(w), _mm256_set1_pd(h));
    let grid = _mm256_set1_pd(f64::from(1u32 << subpixel_bits));
    // One grid step: dividing by the grid, a power of two, is multiplying by it.
    let step = _mm256_set1_pd(1.0 / f64::from(1u32 << subpixel_bits));
    let (zero, half, one) = (_mm256_setzero_pd(), _mm256_set1_pd(0.5), _mm256_set1_pd(1.0));
    let sign = _mm256_set1_pd(-0.0);
    let abs = |v: __m256d| _mm256_andnot_pd(sign, v);
    let (draw_limit, snap_limit) = (_mm256_set1_pd(DRAW_LIMIT), _mm256_set1_pd(SNAP_LIMIT));
    // Lanes in the common case so far (all bits set).
    let mut common = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    let mut vx = [zero; 3];
    let mut vy = [zero; 3];
    let mut vz = [zero; 3];
    for k in 0..3 {
        // Vertex k of the four triangles, one triangle a lane.
        let [mut x, mut y, mut z, mut cw] = [0, 1, 2, 3].map(|l| _mm_loadu_ps(clip[l][k].as_ref().as_ptr()));
        _MM_TRANSPOSE4_PS(&mut x, &mut y, &mut z, &mut cw);
        let finite = |v: __m128| {
            let a = _mm_andnot_ps(_mm_set1_ps(-0.0), v);
            _mm256_cvtps_pd(_mm_cmplt_ps(a, _mm_set1_ps(f32::INFINITY)))
        };
        // A converted all-ones f32 is a NaN f64 (its sign set): the lane mask.
        let ok = _mm256_and_pd(_mm256_and_pd(finite(x), finite(y)), _mm256_and_pd(finite(z), finite(cw)));
        let ok = _mm256_and_pd(ok, _mm256_cvtps_pd(_mm_cmpge_ps(z, _mm_setzero_ps())));
        let (cx, cy, cz, cw) = (_mm256_cvtps_pd(x), _mm256_cvtps_pd(y), _mm256_cvtps_pd(z), _mm256_cvtps_pd(cw));
        let sx = _mm256_mul_pd(_mm256_mul_pd(_mm256_add_pd(_mm256_div_pd(cx, cw), one), half), wv);
        let sy = _mm256_mul_pd(_mm256_mul_pd(_mm256_sub_pd(one, _mm256_div_pd(cy, cw)), half), hv);
        let drawn = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_GT_OQ>(cw, zero),
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(abs(sx), draw_limit),
                _mm256_cmp_pd::<_CMP_LT_OQ>(abs(sy), draw_limit),
            ),
        );
        let in_range = |v: __m256d, size: __m256d| {
            let range = _mm256_set1_pd(SNAP_RANGE);
            _mm256_and_pd(
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_GE_OQ>(v, _mm256_sub_pd(zero, range)),
                    _mm256_cmp_pd::<_CMP_LE_OQ>(v, _mm256_add_pd(size, range)),
                ),
                _mm256_cmp_pd::<_CMP_LE_OQ>(abs(v), snap_limit),
            )
        };
        let snapped = _mm256_and_pd(in_range(sx, wv), in_range(sy, hv));
        common = _mm256_and_pd(common, _mm256_and_pd(_mm256_and_pd(ok, drawn), snapped));
        vx[k] = _mm256_mul_pd(round(_mm256_mul_pd(sx, grid)), step);
        vy[k] = _mm256_mul_pd(round(_mm256_mul_pd(sy, grid)), step);
        vz[k] = _mm256_div_pd(cz, cw);
        // A non-finite depth (a tiny w) is left to the scalar path.
        common = _mm256_and_pd(common, _mm256_cmp_pd::<_CMP_LT_OQ>(vz[k], _mm256_set1_pd(f64::INFINITY)));
    }
    let common = _mm256_movemask_pd(common);
    batch.common = common;
    if common == 0 {
        return;
    }
    // ScreenTriangle::new: signed area, rejection, winding.
    let area = _mm256_sub_pd(
        _mm256_mul_pd(_mm256_sub_pd(vx[1], vx[0]), _mm256_sub_pd(vy[2], vy[0])),
        _mm256_mul_pd(_mm256_sub_pd(vx[2], vx[0]), _mm256_sub_pd(vy[1], vy[0])),
    );
    let mut rejected = _mm256_or_pd(
        _mm256_cmp_pd::<_CMP_EQ_OQ>(area, zero),
        _mm256_cmp_pd::<_CMP_LT_OQ>(abs(area), _mm256_set1_pd(1e-12)),
    );
    if cull == CullMode::Back {
        rejected = _mm256_or_pd(rejected, _mm256_cmp_pd::<_CMP_GT_OQ>(area, zero));
    }
    let swap = _mm256_cmp_pd::<_CMP_LT_OQ>(area, zero);
    for v in [&mut vx, &mut vy, &mut vz] {
        (v[1], v[2]) = (_mm256_blendv_pd(v[1], v[2], swap), _mm256_blendv_pd(v[2], v[1], swap));
    }
    // The pixel window.
    let lo_x = _mm256_max_pd(_mm256_min_pd(_mm256_min_pd(vx[0], vx[1]), vx[2]), zero);
    let hi_x = _mm256_min_pd(_mm256_max_pd(_mm256_max_pd(vx[0], vx[1]), vx[2]), wv);
    let lo_y = _mm256_max_pd(_mm256_min_pd(_mm256_min_pd(vy[0], vy[1]), vy[2]), zero);
    let hi_y = _mm256_min_pd(_mm256_max_pd(_mm256_max_pd(vy[0], vy[1]), vy[2]), hv);
    rejected = _mm256_or_pd(
        rejected,
        _mm256_or_pd(_mm256_cmp_pd::<_CMP_GE_OQ>(lo_x, hi_x), _mm256_cmp_pd::<_CMP_GE_OQ>(lo_y, hi_y)),
    );
    let floor_in = |v: __m256d, min: __m256d, max: __m256d| _mm256_floor_pd(_mm256_max_pd(_mm256_min_pd(v, max), min));
    let minus_one = _mm256_set1_pd(-1.0);
    let first = |lo: __m256d, size: __m256d| {
        let c = _mm256_sub_pd(zero, floor_in(_mm256_sub_pd(half, lo), _mm256_sub_pd(zero, size), one));
        _mm256_max_pd(c, zero)
    };
    let end = |hi: __m256d, size: __m256d| {
        _mm256_min_pd(_mm256_add_pd(floor_in(_mm256_sub_pd(hi, half), minus_one, size), one), size)
    };
    let (x0, x1, y0, y1) = (first(lo_x, wv), end(hi_x, wv), first(lo_y, hv), end(hi_y, hv));
    rejected =
        _mm256_or_pd(rejected, _mm256_or_pd(_mm256_cmp_pd::<_CMP_GE_OQ>(x0, x1), _mm256_cmp_pd::<_CMP_GE_OQ>(y0, y1)));
    // The edge from vertex `i` to the next (Edge::new with no margin):
    // recomputed where needed rather than kept, which would take more
    // registers than there are.
    let edge = |i: usize| {
        let (p, q) = (i, (i + 1) % 3);
        let a = _mm256_sub_pd(vy[p], vy[q]);
        let b = _mm256_sub_pd(vx[q], vx[p]);
        let c = _mm256_xor_pd(_mm256_add_pd(_mm256_mul_pd(a, vx[p]), _mm256_mul_pd(b, vy[p])), sign);
        (a, b, c)
    };
    // A horizontal edge (ScreenTriangle::new): the window keeps only the rows
    // it covers. With no margin the edge lies on a row of the window's end
    // (a vertex's `y`), so at most that row, whose centres lie on the edge,
    // is left out, by one step of each end as the scalar loops take.
    let horizontal = [0, 1, 2].map(|i| _mm256_cmp_pd::<_CMP_EQ_OQ>(_mm256_sub_pd(vy[i], vy[(i + 1) % 3]), zero));
    let flat = _mm256_or_pd(_mm256_or_pd(horizontal[0], horizontal[1]), horizontal[2]);
    batch.flat = _mm256_movemask_pd(flat);
    let (mut y0, mut y1) = (y0, y1);
    if batch.flat != 0 {
        for (i, &horizontal) in horizontal.iter().enumerate() {
            let (a, b, c) = edge(i);
            // Edge::covers at (0.5, py); `on` is `b > 0` where `a` is zero.
            let covers = |py: __m256d| {
                let e = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(a, half), _mm256_mul_pd(b, py)), c);
                _mm256_or_pd(
                    _mm256_cmp_pd::<_CMP_GT_OQ>(e, zero),
                    _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(b, zero), _mm256_cmp_pd::<_CMP_EQ_OQ>(e, zero)),
                )
            };
            let (first, last) = (covers(_mm256_add_pd(y0, half)), covers(_mm256_sub_pd(y1, half)));
            y0 = _mm256_add_pd(y0, _mm256_and_pd(_mm256_andnot_pd(first, horizontal), one));
            y1 = _mm256_sub_pd(y1, _mm256_and_pd(_mm256_andnot_pd(last, horizontal), one));
        }
    }
    batch.rejected = _mm256_movemask_pd(_mm256_or_pd(rejected, _mm256_cmp_pd::<_CMP_GE_OQ>(y0, y1)));
    // Per edge: its coefficients, intercept and band (Edge::new, Edge::band),
    // and its lanes' intercepts (Intercepts::new), over the rows from the top
    // of the first tile row (subtile row `top`) through the last subtile row
    // `r1 - 1` and one more; a horizontal edge's are `t_max`, 0 and 0.
    let top = _mm256_mul_pd(_mm256_floor_pd(_mm256_mul_pd(y0, _mm256_set1_pd(0.125))), _mm256_set1_pd(2.0));
    let r1 = _mm256_add_pd(_mm256_floor_pd(_mm256_mul_pd(_mm256_sub_pd(y1, one), _mm256_set1_pd(0.25))), one);
    let four = _mm256_set1_pd(4.0);
    let py = _mm256_add_pd(_mm256_mul_pd(top, four), half);
    let rows = _mm256_mul_pd(_mm256_add_pd(_mm256_sub_pd(r1, top), one), four);
    // round_far before its rounding to `f32`: nudged farther.
    let nudge_far = |v: __m256d| {
        _mm256_add_pd(_mm256_add_pd(v, _mm256_mul_pd(abs(v), _mm256_set1_pd(FAR_NUDGE))), _mm256_set1_pd(1e-12))
    };
    // Exact: whole numbers below 2^15 and a half.
    let t_max = _mm256_add_pd(_mm256_sub_pd(x1, x0), _mm256_set1_pd(3.5));
    _mm_storeu_ps(batch.t_max.as_mut_ptr(), _mm256_cvtpd_ps(t_max));
    for (i, &horizontal) in horizontal.iter().enumerate() {
        let (a, b, c) = edge(i);
        let r = _mm256_div_pd(one, a);
        let right = _mm256_cmp_pd::<_CMP_GT_OQ>(a, zero);
        batch.right[i] = _mm256_movemask_pd(right);
        batch.on[i] = _mm256_movemask_pd(_mm256_or_pd(
            right,
            _mm256_and_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(a, zero), _mm256_cmp_pd::<_CMP_GT_OQ>(b, zero)),
        ));
        let slope = _mm256_mul_pd(_mm256_xor_pd(b, sign), r);
        let offset = _mm256_mul_pd(_mm256_xor_pd(c, sign), r);
        let intercept =
            _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(abs(slope), hv), abs(offset)), wv), one);
        let function = _mm256_mul_pd(
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(abs(a), wv), _mm256_mul_pd(abs(b), hv)), abs(c)),
            abs(r),
        );
        let band = _mm256_mul_pd(_mm256_set1_pd(BAND_SCALE), _mm256_add_pd(intercept, function));
        for (out, v) in batch.edges[i].iter_mut().zip([a, b, c, slope, offset, band]) {
            _mm256_storeu_pd(out.as_mut_ptr(), v);
        }
        let u = _mm256_sub_pd(_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(slope, py), offset), half), x0);
        let allowance = _mm256_add_pd(
            _mm256_add_pd(
                _mm256_mul_pd(_mm256_set1_pd(2.0), abs(u)),
                _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(3.0), abs(slope)), rows),
            ),
            one,
        );
        let lane_band = nudge_far(_mm256_add_pd(band, _mm256_mul_pd(_mm256_set1_pd(F32_SCALE), allowance)));
        let mut lanes = [u, slope, lane_band];
        if batch.flat != 0 {
            for (v, flat) in lanes.iter_mut().zip([t_max, zero, zero]) {
                *v = _mm256_blendv_pd(*v, flat, horizontal);
            }
        }
        for (out, v) in batch.lanes[i].iter_mut().zip(lanes) {
            _mm_storeu_ps(out.as_mut_ptr(), _mm256_cvtpd_ps(v));
        }
    }
    // The depth plane (DepthPlane::new), raised by one grid step.
    let (d1, d2) = (
        [_mm256_sub_pd(vx[1], vx[0]), _mm256_sub_pd(vy[1], vy[0]), _mm256_sub_pd(vz[1], vz[0])],
        [_mm256_sub_pd(vx[2], vx[0]), _mm256_sub_pd(vy[2], vy[0]), _mm256_sub_pd(vz[2], vz[0])],
    );
    let cross =
        |a: __m256d, b: __m256d, c: __m256d, d: __m256d| _mm256_sub_pd(_mm256_mul_pd(a, b), _mm256_mul_pd(c, d));
    let nx = cross(d1[1], d2[2], d2[1], d1[2]);
    let ny = cross(d1[2], d2[0], d2[2], d1[0]);
    let nz = cross(d1[0], d2[1], d2[0], d1[1]);
    let rz = _mm256_div_pd(one, nz);
    let zx = _mm256_mul_pd(_mm256_xor_pd(nx, sign), rz);
    let zy = _mm256_mul_pd(_mm256_xor_pd(ny, sign), rz);
    let z0 = _mm256_add_pd(
        _mm256_sub_pd(_mm256_sub_pd(vz[0], _mm256_mul_pd(zx, vx[0])), _mm256_mul_pd(zy, vy[0])),
        _mm256_mul_pd(_mm256_add_pd(abs(zx), abs(zy)), step),
    );
    let zmax = _mm256_max_pd(_mm256_max_pd(vz[0], vz[1]), vz[2]);
    // Whole numbers within the screen in drawn lanes, so converted exactly.
    for (out, v) in batch.window.iter_mut().zip([x0, x1, y0, y1]) {
        _mm_storeu_si128(out.as_mut_ptr().cast(), _mm256_cvttpd_epi32(v));
    }
    // Raster::tiles: the tile columns and rows from the first pixel's to the
    // last one's (divisions by powers of two, exact).
    let span = |lo: __m256d, end: __m256d, size: f64| {
        let of = |v: __m256d| _mm256_floor_pd(_mm256_mul_pd(v, _mm256_set1_pd(1.0 / size)));
        _mm256_add_pd(_mm256_sub_pd(of(_mm256_sub_pd(end, one)), of(lo)), one)
    };
    let tiles = _mm256_mul_pd(span(x0, x1, 32.0), span(y0, y1, 8.0));
    _mm_storeu_si128(batch.tiles.as_mut_ptr().cast(), _mm256_cvttpd_epi32(tiles));
    for (out, v) in batch.plane.iter_mut().zip([zx, zy, z0]) {
        _mm256_storeu_pd(out.as_mut_ptr(), v);
    }
    // DepthPlane::from_terms: the step `8 zx` and the cap `zmax`, rounded
    // far, the step's significand then rounded up (not negative) or cut to
    // leave its `step_zero_bits` lowest bits zero.
    let v = _mm256_cvtpd_ps(nudge_far(_mm256_mul_pd(zx, _mm256_set1_pd(8.0))));
    let low = _mm_set1_epi32(((1u32 << step_zero_bits(width)) - 1) as i32);
    let bits = _mm_castps_si128(v);
    let up = _mm_castps_si128(_mm_cmpge_ps(v, _mm_setzero_ps()));
    let bits = _mm_add_epi32(bits, _mm_and_si128(up, low));
    let step = _mm_castsi128_ps(_mm_andnot_si128(low, bits));
    _mm_storeu_ps(batch.plane_f32[0].as_mut_ptr(), step);
    _mm_storeu_ps(batch.plane_f32[1].as_mut_ptr(), _mm256_cvtpd_ps(nudge_far(zmax)));
}

/// `crate::project`'s rounding (halves away from zero) on four lanes of
/// magnitude below `2^52`: the truncation `t`, plus the truncation of twice
/// the fraction (exact: `x - t` by Sterbenz's lemma, doubling by the
/// exponent), which is `±1` exactly where the fraction is at least a half
/// away from zero; `+ 0` gives a zero result the scalar rounding's positive
/// sign.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn round(x: __m256d) -> __m256d {
    let t = _mm256_round_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(x);
    let fraction = _mm256_sub_pd(x, t);
    let away = _mm256_round_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(_mm256_add_pd(fraction, fraction));
    _mm256_add_pd(_mm256_add_pd(t, away), _mm256_setzero_pd())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::project::screen_triangles;
    use crate::raster::avx2::Avx2;
    use crate::raster::ScreenTriangle;

    struct Lcg(u64);
    impl Lcg {
        fn unit(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// Every field of a set-up triangle, as bits.
    fn fields(t: &ScreenTriangle) -> Vec<u64> {
        let (r, e) = (&t.raster, &t.exact);
        let mut out: Vec<u64> = e
            .edges
            .iter()
            .flat_map(|e| [e.a, e.b, e.c, e.slope, e.offset].map(f64::to_bits).into_iter().chain([u64::from(e.on)]))
            .collect();
        let p = &r.plane;
        out.extend([p.zx, p.zy, p.z0].map(f64::to_bits));
        out.extend([p.step, p.cap].map(|v| u64::from(v.to_bits())));
        out.extend(e.bands.map(f64::to_bits));
        let lanes = &r.lanes;
        out.extend(
            lanes
                .base
                .iter()
                .chain(&lanes.slope)
                .chain(&lanes.band)
                .chain([&lanes.t_max])
                .map(|v| u64::from(v.to_bits())),
        );
        out.extend(lanes.right.iter().map(|&v| v as u64).chain([u64::from(lanes.flat)]));
        out.extend([r.x0, r.x1, r.y0, r.y1].map(|v| v as u64));
        out
    }

    /// A clip-space vertex: mostly on screen (some snapped to half pixels,
    /// so that edges pass through pixel centres and areas vanish), some far
    /// out, behind the eye, at `w <= 0` or not finite.
    fn vertex(rng: &mut Lcg, case: usize) -> Vec4 {
        let mut v = Vec4::new(rng.unit() * 2.4 - 1.2, rng.unit() * 2.4 - 1.2, rng.unit(), 1.0);
        match case % 23 {
            0 => v.z = -0.1,
            1 => v.w = if case.is_multiple_of(2) { 0.0 } else { -1.0 },
            2 => v.x *= 40.0,
            3 => v.y = f32::NAN,
            4 => v.w = f32::INFINITY,
            5 => v.w = 1e-30,
            6..=12 => (v.x, v.y) = ((v.x * 8.0).round() / 8.0, (v.y * 8.0).round() / 8.0),
            _ => {}
        }
        v
    }

    #[test]
    fn batched_set_up_equals_the_scalar_set_up() {
        let Some(avx2) = Avx2::detect() else {
            eprintln!("skipped: no AVX2 on this CPU");
            return;
        };
        let mut rng = Lcg(17);
        let screens = [(64, 48), (83, 45), (1920, 1080), (7, 5)];
        let (mut batched, mut drawn, mut scalar, mut flats, mut on_centres) = (0, 0, 0, 0, 0);
        // One batch for all rounds: what a call leaves from the last one must
        // not show.
        let mut batch = Batch::EMPTY;
        for round in 0..20_000usize {
            let (width, height) = screens[round % screens.len()];
            let (cull, bits) = ([CullMode::Back, CullMode::None][round % 2], [8, 8, 4, 0][round / 2 % 4]);
            let mut centre = Vec4::new(rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0, 0.0, 0.0);
            if round.is_multiple_of(10) {
                // On a row of pixel centres: a horizontal edge through them.
                let row = (rng.unit() * height as f32).floor() + 0.5;
                centre.y = 1.0 - 2.0 * row / height as f32;
            }
            let size = [0.01, 0.1, 1.0][round % 3];
            let clip: [[Vec4; 3]; SETUP_LANES] = std::array::from_fn(|l| {
                std::array::from_fn(|k| {
                    let v = vertex(&mut rng, round * 7 + l * 3 + k);
                    let v = centre + v * Vec4::new(size, size, 1.0, 1.0);
                    if round.is_multiple_of(5) && k < 2 && v.w == 1.0 {
                        // A horizontal edge.
                        Vec4::new(v.x, centre.y, v.z, v.w)
                    } else {
                        v
                    }
                })
            });
            avx2.setup4(&clip, cull, width, height, bits, &mut batch);
            for (l, c) in clip.iter().enumerate() {
                if batch.scalar_lanes() >> l & 1 == 1 {
                    scalar += 1;
                    continue;
                }
                let tri = (batch.drawn_lanes() >> l & 1 == 1).then(|| ScreenTriangle::copy_of(&batch.drawn(l)));
                let tiles = tri.as_ref().map_or(0, |t| t.raster.tiles());
                assert_eq!(batch.tiles(1 << l & batch.drawn_lanes()), tiles, "round {round} lane {l}: {c:?}");
                batched += 1;
                let mut expected = Vec::new();
                let count = screen_triangles(*c, cull, width, height, bits, &mut |t| expected.push(fields(t)));
                assert_eq!(count, 1, "round {round} lane {l}: {c:?}");
                let got: Vec<_> = tri.iter().map(fields).collect();
                assert_eq!(got, expected, "round {round} lane {l}: {c:?}");
                drawn += got.len();
                if let Some(t) = &tri {
                    // A horizontal edge, and one through pixel centres.
                    let flat = t.exact.edges.iter().filter(|e| e.a == 0.0);
                    flats += usize::from(t.raster.lanes.flat);
                    on_centres += flat.filter(|e| (-e.c / e.b - 0.5).fract() == 0.0).count();
                }
            }
        }
        assert!(batched > 40_000 && drawn > 10_000 && scalar > 10_000, "{batched} {drawn} {scalar}");
        assert!(flats > 500 && on_centres > 100, "{flats} horizontal, {on_centres} on pixel centres");
    }
}
