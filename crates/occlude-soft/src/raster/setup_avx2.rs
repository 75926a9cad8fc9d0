//! Triangle set-up of four triangles at once in AVX2 `f64` lanes, for the usual
//! case: finite vertices inside the guard band that project within range. It
//! computes what [`setup_triangle`](super::setup::setup_triangle) computes for such
//! a triangle, bit for bit: the same `f64` operations in the same order (IEEE
//! arithmetic is exact per lane, and no multiply-add is fused), the fixed-point
//! coordinates as `f64` integers (below 2^23 in magnitude, so their differences,
//! products and the doubled area are exact in `f64` as they are in `i64`). Any other
//! triangle is handed back to the scalar set-up.

use std::arch::x86_64::*;

use glam::Vec4;

use super::setup::{SetupTri, Viewport, COORD_LIMIT, HALF, ONE};

/// What the set-up of a group of four triangles made of each.
#[derive(Clone, Copy, Debug)]
pub(super) enum Lane {
    /// Set up.
    Ready(SetupTri),
    /// Covers no pixel centre (degenerate, culled, off the viewport, or a
    /// non-finite depth plane): nothing to rasterize.
    Dropped,
    /// Not the usual case (clipped, non-finite, out of range): for the scalar
    /// set-up.
    Scalar,
}

/// The vertex `k` of four triangles, one per lane: clip-space `x, y, z, w`.
struct Vertices {
    x: __m256d,
    y: __m256d,
    z: __m256d,
    w: __m256d,
}

/// Loads vertex `k` of each of the four triangles `tris` as `f64` lanes.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn load(tris: &[[Vec4; 3]; 4], k: usize) -> Vertices {
    let v = |t: usize| _mm_loadu_ps(tris[t][k].as_ref().as_ptr());
    let (a, b, c, d) = (v(0), v(1), v(2), v(3));
    // Transposes the four (x, y, z, w) rows into four columns.
    let (ab_lo, ab_hi) = (_mm_unpacklo_ps(a, b), _mm_unpackhi_ps(a, b));
    let (cd_lo, cd_hi) = (_mm_unpacklo_ps(c, d), _mm_unpackhi_ps(c, d));
    Vertices {
        x: _mm256_cvtps_pd(_mm_movelh_ps(ab_lo, cd_lo)),
        y: _mm256_cvtps_pd(_mm_movehl_ps(cd_lo, ab_lo)),
        z: _mm256_cvtps_pd(_mm_movelh_ps(ab_hi, cd_hi)),
        w: _mm256_cvtps_pd(_mm_movehl_ps(cd_hi, ab_hi)),
    }
}

/// A vertex projected to the screen, as `setup::project` does: fixed-point `x, y`
/// (integers in `f64`) and NDC depth; `ok` lanes are finite and within range.
struct Projected {
    x: __m256d,
    y: __m256d,
    z: __m256d,
    ok: __m256d,
}

/// `setup::round` per lane: to the nearest integer, halves away from zero.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn round(x: __m256d) -> __m256d {
    let t = _mm256_round_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(x);
    let frac = _mm256_sub_pd(x, t);
    let one = _mm256_set1_pd(1.0);
    let up = _mm256_and_pd(_mm256_cmp_pd::<_CMP_GE_OQ>(frac, _mm256_set1_pd(0.5)), one);
    let down = _mm256_and_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(frac, _mm256_set1_pd(-0.5)), one);
    _mm256_sub_pd(_mm256_add_pd(t, up), down)
}

/// Lanes where `|v| < limit` (false for NaN).
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn abs_below<const CMP: i32>(v: __m256d, limit: f64) -> __m256d {
    let abs = _mm256_andnot_pd(_mm256_set1_pd(-0.0), v);
    _mm256_cmp_pd::<CMP>(abs, _mm256_set1_pd(limit))
}

/// Lanes whose vertex lies inside every clipping plane of `clip::clip_triangle`
/// (near and guard band): no distance below zero, as its mask tests them.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn inside(v: &Vertices, viewport: Viewport) -> __m256d {
    let zero = _mm256_setzero_pd();
    let (gxw, gyw) =
        (_mm256_mul_pd(_mm256_set1_pd(viewport.guard.gx), v.w), _mm256_mul_pd(_mm256_set1_pd(viewport.guard.gy), v.w));
    let distances =
        [v.z, _mm256_sub_pd(gxw, v.x), _mm256_add_pd(gxw, v.x), _mm256_sub_pd(gyw, v.y), _mm256_add_pd(gyw, v.y)];
    distances.iter().fold(_mm256_cmp_pd::<_CMP_TRUE_UQ>(zero, zero), |ok, &d| {
        _mm256_andnot_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(d, zero), ok)
    })
}

/// `setup::project` per lane.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn project(v: &Vertices, viewport: Viewport) -> Projected {
    let (one, half) = (_mm256_set1_pd(1.0), _mm256_set1_pd(0.5));
    let sx = _mm256_mul_pd(
        _mm256_mul_pd(_mm256_add_pd(_mm256_div_pd(v.x, v.w), one), half),
        _mm256_set1_pd(f64::from(viewport.width)),
    );
    let sy = _mm256_mul_pd(
        _mm256_mul_pd(_mm256_sub_pd(one, _mm256_div_pd(v.y, v.w)), half),
        _mm256_set1_pd(f64::from(viewport.height)),
    );
    let z = _mm256_div_pd(v.z, v.w);
    let ok = _mm256_and_pd(
        _mm256_and_pd(abs_below::<_CMP_LE_OQ>(sx, COORD_LIMIT), abs_below::<_CMP_LE_OQ>(sy, COORD_LIMIT)),
        abs_below::<_CMP_LT_OQ>(z, f64::INFINITY),
    );
    let fixed = _mm256_set1_pd(ONE as f64);
    Projected { x: round(_mm256_mul_pd(sx, fixed)), y: round(_mm256_mul_pd(sy, fixed)), z, ok }
}

/// Lanes of `mask` as bits.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn bits(mask: __m256d) -> u32 {
    _mm256_movemask_pd(mask) as u32
}

/// `f64` lanes (integers below 2^31) as `i32`s.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn ints(v: __m256d) -> [i32; 4] {
    let mut out = [0i32; 4];
    _mm_storeu_si128(out.as_mut_ptr().cast(), _mm256_cvtpd_epi32(v));
    out
}

/// Sets up the four triangles `tris` of command `cmd` as `setup::setup_triangle`
/// would, for the triangles of the usual case; the others come back as
/// [`Lane::Scalar`].
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn setup4(tris: &[[Vec4; 3]; 4], cull_back: bool, cmd: u32, viewport: Viewport) -> [Lane; 4] {
    let verts = [load(tris, 0), load(tris, 1), load(tris, 2)];
    let zero = _mm256_setzero_pd();
    // Finite inputs (all four coordinates, as `clip_triangle` checks), inside the
    // guard band, projected within range: the usual case.
    let mut usual = _mm256_cmp_pd::<_CMP_TRUE_UQ>(zero, zero);
    for v in &verts {
        for c in [v.x, v.y, v.z, v.w] {
            usual = _mm256_and_pd(usual, abs_below::<_CMP_LT_OQ>(c, f64::INFINITY));
        }
        usual = _mm256_and_pd(usual, inside(v, viewport));
    }
    let [p0, p1, mut p2] = verts.map(|v| project(&v, viewport));
    let mut p1 = p1;
    for p in [&p0, &p1, &p2] {
        usual = _mm256_and_pd(usual, p.ok);
    }

    // Twice the signed area, exact (see the module documentation); with y down,
    // front faces have negative area, and positive-area order swaps vertices 1, 2.
    let area = _mm256_sub_pd(
        _mm256_mul_pd(_mm256_sub_pd(p1.x, p0.x), _mm256_sub_pd(p2.y, p0.y)),
        _mm256_mul_pd(_mm256_sub_pd(p1.y, p0.y), _mm256_sub_pd(p2.x, p0.x)),
    );
    let mut keep = _mm256_cmp_pd::<_CMP_NEQ_OQ>(area, zero);
    if cull_back {
        keep = _mm256_and_pd(keep, _mm256_cmp_pd::<_CMP_LT_OQ>(area, zero));
    }
    let swap = _mm256_cmp_pd::<_CMP_LT_OQ>(area, zero);
    for (a, b) in [(&mut p1.x, &mut p2.x), (&mut p1.y, &mut p2.y), (&mut p1.z, &mut p2.z)] {
        let (old_a, old_b) = (*a, *b);
        *a = _mm256_blendv_pd(old_a, old_b, swap);
        *b = _mm256_blendv_pd(old_b, old_a, swap);
    }

    // The pixels whose centres lie within the vertices' bounds (`setup_screen`):
    // exact, as the divisions are by a power of two.
    let (half, inv_one) = (_mm256_set1_pd(HALF as f64), _mm256_set1_pd(1.0 / ONE as f64));
    let min3 = |a, b, c| _mm256_min_pd(_mm256_min_pd(a, b), c);
    let max3 = |a, b, c| _mm256_max_pd(_mm256_max_pd(a, b), c);
    let first = |lo| _mm256_max_pd(_mm256_ceil_pd(_mm256_mul_pd(_mm256_sub_pd(lo, half), inv_one)), zero);
    let last = |hi, size: u32| {
        _mm256_min_pd(
            _mm256_floor_pd(_mm256_mul_pd(_mm256_sub_pd(hi, half), inv_one)),
            _mm256_set1_pd(f64::from(size) - 1.0),
        )
    };
    let x0 = first(min3(p0.x, p1.x, p2.x));
    let y0 = first(min3(p0.y, p1.y, p2.y));
    let x1 = last(max3(p0.x, p1.x, p2.x), viewport.width);
    let y1 = last(max3(p0.y, p1.y, p2.y), viewport.height);
    keep = _mm256_and_pd(keep, _mm256_and_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(x0, x1), _mm256_cmp_pd::<_CMP_LE_OQ>(y0, y1)));

    // The depth plane, in `setup_screen`'s order of operations.
    let (px0, py0) = (_mm256_mul_pd(p0.x, inv_one), _mm256_mul_pd(p0.y, inv_one));
    let (dx1, dy1, dz1) = (
        _mm256_sub_pd(_mm256_mul_pd(p1.x, inv_one), px0),
        _mm256_sub_pd(_mm256_mul_pd(p1.y, inv_one), py0),
        _mm256_sub_pd(p1.z, p0.z),
    );
    let (dx2, dy2, dz2) = (
        _mm256_sub_pd(_mm256_mul_pd(p2.x, inv_one), px0),
        _mm256_sub_pd(_mm256_mul_pd(p2.y, inv_one), py0),
        _mm256_sub_pd(p2.z, p0.z),
    );
    let det = _mm256_sub_pd(_mm256_mul_pd(dx1, dy2), _mm256_mul_pd(dx2, dy1));
    let a = _mm256_div_pd(_mm256_sub_pd(_mm256_mul_pd(dz1, dy2), _mm256_mul_pd(dz2, dy1)), det);
    let b = _mm256_div_pd(_mm256_sub_pd(_mm256_mul_pd(dx1, dz2), _mm256_mul_pd(dx2, dz1)), det);
    let pixel_half = _mm256_set1_pd(0.5);
    let c = _mm256_add_pd(
        _mm256_add_pd(p0.z, _mm256_mul_pd(a, _mm256_sub_pd(_mm256_add_pd(x0, pixel_half), px0))),
        _mm256_mul_pd(b, _mm256_sub_pd(_mm256_add_pd(y0, pixel_half), py0)),
    );
    let plane = [_mm256_cvtpd_ps(c), _mm256_cvtpd_ps(a), _mm256_cvtpd_ps(b)];
    let finite = |v: __m128| {
        let abs = _mm_andnot_ps(_mm_set1_ps(-0.0), v);
        _mm256_cvtps_pd(_mm_cmplt_ps(abs, _mm_set1_ps(f32::INFINITY)))
    };
    for p in &plane {
        keep = _mm256_and_pd(keep, finite(*p));
    }

    let (usual, keep) = (bits(usual), bits(keep));
    let [z_origin, z_dx, z_dy] = plane.map(|p| {
        let mut out = [0f32; 4];
        _mm_storeu_ps(out.as_mut_ptr(), p);
        out
    });
    let (x0, y0, x1, y1) = (ints(x0), ints(y0), ints(x1), ints(y1));
    let vx = [ints(p0.x), ints(p1.x), ints(p2.x)];
    let vy = [ints(p0.y), ints(p1.y), ints(p2.y)];
    std::array::from_fn(|i| {
        if usual & (1 << i) == 0 {
            Lane::Scalar
        } else if keep & (1 << i) == 0 {
            Lane::Dropped
        } else {
            Lane::Ready(SetupTri {
                cmd,
                x0: x0[i],
                y0: y0[i],
                x1: x1[i],
                y1: y1[i],
                verts: [[vx[0][i], vy[0][i]], [vx[1][i], vy[1][i]], [vx[2][i], vy[2][i]]],
                z_origin: z_origin[i],
                z_dx: z_dx[i],
                z_dy: z_dy[i],
            })
        }
    })
}
