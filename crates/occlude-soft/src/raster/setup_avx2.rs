//! Triangle set-up of four triangles at once in AVX2 `f64` lanes, for the usual
//! case: finite vertices inside the guard band that project within range. It
//! computes what [`setup_triangle`](super::setup::setup_triangle) computes for such
//! a triangle, bit for bit: the same `f64` operations in the same order (IEEE
//! arithmetic is exact per lane, and no multiply-add is fused), the fixed-point
//! coordinates as `f64` integers (below 2^23 in magnitude, so their differences,
//! products and the doubled area are exact in `f64` as they are in `i64`), and
//! writes their raster forms ([`RasterTri`]) with one 4x4 transpose per four
//! fields. Any other triangle is handed back to the scalar set-up.
//!
//! Projecting a vertex depends on that vertex alone, so an indexed mesh's
//! vertices can be projected once each ([`project4`], four at a time, kept as
//! [`VertexRecord`]s) and its triangles set up from them ([`gather4`],
//! [`uncovered4_projected`], [`setup4_projected`]) with the results of
//! [`setup4`] on the same triangles given vertex by vertex: a closed mesh has
//! about half as many vertices as triangles, each shared by some six.

use std::arch::x86_64::*;

use glam::Vec4;

use super::setup::{Viewport, COORD_LIMIT, HALF, ONE};
use super::span::RasterTri;

// The field order `setup4` writes the raster forms in.
const _: () = {
    use std::mem::offset_of;
    assert!(offset_of!(RasterTri, verts) == 0 && offset_of!(RasterTri, cmd) == 24);
    assert!(offset_of!(RasterTri, x0) == 28 && offset_of!(RasterTri, x1) == 32);
    assert!(offset_of!(RasterTri, y0) == 36 && offset_of!(RasterTri, y1) == 40);
    assert!(offset_of!(RasterTri, plane_y) == 44 && offset_of!(RasterTri, z_origin) == 48);
    assert!(offset_of!(RasterTri, z_dx) == 52 && offset_of!(RasterTri, z_dy) == 56);
    assert!(std::mem::size_of::<RasterTri>() == 64);
};

/// What the set-up of a group of four triangles made of each: bit `i` for the
/// triangle `i`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Lanes {
    /// Set up: the raster form is written, its rows still its bounding box's
    /// ([`RasterTri::covered_rows`] is left to do).
    pub ready: u8,
    /// Not the usual case (clipped, non-finite, out of range): for the scalar
    /// set-up. The others cover no pixel centre (degenerate, culled, off the
    /// viewport, or a non-finite depth plane): nothing to rasterize.
    pub scalar: u8,
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
    lanes(&[tris[0][k], tris[1][k], tris[2][k], tris[3][k]])
}

/// The four vertices `v` as `f64` lanes.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn lanes(v: &[Vec4; 4]) -> Vertices {
    let v = |t: usize| _mm_loadu_ps(v[t].as_ref().as_ptr());
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
#[derive(Clone, Copy)]
pub(super) struct Projected {
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
unsafe fn ints(v: __m256d) -> __m128i {
    _mm256_cvtpd_epi32(v)
}

/// Margin, in fixed-point units, by which [`uncovered4`] widens its estimate of
/// the vertices' bounds: the snapped coordinate is within half a unit of the
/// unrounded one, and the estimate within far less than that of the unrounded
/// one (see [`uncovered4`]).
const UNCOVERED_MARGIN: f64 = 1.0;

/// The lanes of the four triangles `tris` that [`setup4`] and the scalar set-up
/// are sure to drop because their bounding box holds no pixel centre of the
/// viewport (sub-pixel triangles between the centres, triangles off the
/// screen), found at a fraction of [`setup4`]'s cost: one division per vertex
/// instead of three and no edges, depth plane or raster form. Bit `i` for
/// triangle `i`.
///
/// A lane is reported only when its vertices are inside every clipping plane
/// (`setup4`'s test, exactly) or one of its coordinates is not finite (which
/// `clip_triangle` drops), so that a finite one is handed whole to the
/// projection; if that projection fails
/// (out of range, non-finite depth) the triangle is dropped whatever its box. Else
/// `setup4` snaps each vertex to `round(s * ONE)` for its screen coordinate `s =
/// (x / w + 1) * W / 2` (and `(1 - y / w) * H / 2`); this estimates `s` as `(x *
/// (1 / w) + 1) * W / 2`, which differs from it by a few rounding errors of
/// numbers below `2^15` pixels (the guard band's reach), under `10^-7` units, so every
/// snapped coordinate lies within [`UNCOVERED_MARGIN`] of the estimate. The
/// pixel columns whose centres lie within the estimated bounds widened by the
/// margin therefore include the set-up's `x0..=x1`, and likewise for rows: none
/// (within the viewport) means the set-up finds none.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn uncovered4(tris: &[[Vec4; 3]; 4], viewport: Viewport) -> u8 {
    let verts = [load(tris, 0), load(tris, 1), load(tris, 2)];
    let zero = _mm256_setzero_pd();
    let mut usual = _mm256_cmp_pd::<_CMP_TRUE_UQ>(zero, zero);
    for v in &verts {
        usual = _mm256_and_pd(usual, inside(v, viewport));
    }
    let (one, half, fixed) = (_mm256_set1_pd(1.0), _mm256_set1_pd(0.5), _mm256_set1_pd(ONE as f64));
    let (width, height) = (_mm256_set1_pd(f64::from(viewport.width)), _mm256_set1_pd(f64::from(viewport.height)));
    // The estimated fixed-point coordinates of each vertex.
    let screen = |v: &Vertices| {
        let r = _mm256_div_pd(one, v.w);
        let sx = _mm256_mul_pd(_mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(v.x, r), one), half), width);
        let sy = _mm256_mul_pd(_mm256_mul_pd(_mm256_sub_pd(one, _mm256_mul_pd(v.y, r)), half), height);
        (_mm256_mul_pd(sx, fixed), _mm256_mul_pd(sy, fixed))
    };
    let [(x0, y0), (x1, y1), (x2, y2)] = [screen(&verts[0]), screen(&verts[1]), screen(&verts[2])];
    let (margin, inv_one) = (_mm256_set1_pd(UNCOVERED_MARGIN + HALF as f64), _mm256_set1_pd(1.0 / ONE as f64));
    // No centre `p * ONE + HALF` within `[lo - margin, hi + margin]` inside the
    // viewport's `0..size`; with NaN the comparison is false (not reported).
    let empty = |a, b, c, size: __m256d| {
        let lo = _mm256_sub_pd(_mm256_min_pd(_mm256_min_pd(a, b), c), margin);
        let hi = _mm256_sub_pd(_mm256_max_pd(_mm256_max_pd(a, b), c), _mm256_set1_pd(HALF as f64 - UNCOVERED_MARGIN));
        let first = _mm256_max_pd(_mm256_ceil_pd(_mm256_mul_pd(lo, inv_one)), zero);
        let last = _mm256_min_pd(_mm256_floor_pd(_mm256_mul_pd(hi, inv_one)), _mm256_sub_pd(size, one));
        _mm256_cmp_pd::<_CMP_GT_OQ>(first, last)
    };
    let none = _mm256_or_pd(empty(x0, x1, x2, width), empty(y0, y1, y2, height));
    bits(_mm256_and_pd(usual, none)) as u8
}

/// Sets up the four triangles `tris` of command `cmd` as `setup::setup_triangle`
/// and [`RasterTri::new`] would, for the triangles of the usual case, writing the
/// raster forms of the [`Lanes::ready`] ones to `out`; the others come back as
/// [`Lanes::scalar`] or are dropped.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn setup4(
    tris: &[[Vec4; 3]; 4],
    cull_back: bool,
    cmd: u32,
    viewport: Viewport,
    out: &mut [RasterTri; 4],
) -> Lanes {
    let p0 = project_usual(&load(tris, 0), viewport);
    let p1 = project_usual(&load(tris, 1), viewport);
    let p2 = project_usual(&load(tris, 2), viewport);
    setup4_projected([p0, p1, p2], cull_back, cmd, viewport, out)
}

/// [`project`], with `ok` the lanes of the usual case: finite inputs (all four
/// coordinates, as `clip_triangle` checks), inside the guard band, projected
/// within range.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn project_usual(v: &Vertices, viewport: Viewport) -> Projected {
    let mut usual = inside(v, viewport);
    for c in [v.x, v.y, v.z, v.w] {
        usual = _mm256_and_pd(usual, abs_below::<_CMP_LT_OQ>(c, f64::INFINITY));
    }
    let p = project(v, viewport);
    Projected { ok: _mm256_and_pd(usual, p.ok), ..p }
}

/// A vertex projected for [`gather4`]: fixed-point `x`, `y`, depth `z`
/// (as [`project`] gives them), and all bits set where it is of the usual case
/// ([`project_usual`]), else zero.
pub(super) type VertexRecord = [f64; 4];

/// Projects the four vertices `v` into `out`, as [`setup4`] projects each
/// vertex of its triangles: a vertex shared by several triangles is projected
/// once.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn project4(v: &[Vec4; 4], viewport: Viewport, out: &mut [VertexRecord; 4]) {
    let p = project_usual(&lanes(v), viewport);
    // The 4x4 transpose of the x, y, z, ok rows into one record per vertex.
    let (xy_lo, xy_hi) = (_mm256_unpacklo_pd(p.x, p.y), _mm256_unpackhi_pd(p.x, p.y));
    let (zo_lo, zo_hi) = (_mm256_unpacklo_pd(p.z, p.ok), _mm256_unpackhi_pd(p.z, p.ok));
    let records = [
        _mm256_permute2f128_pd::<0x20>(xy_lo, zo_lo),
        _mm256_permute2f128_pd::<0x20>(xy_hi, zo_hi),
        _mm256_permute2f128_pd::<0x31>(xy_lo, zo_lo),
        _mm256_permute2f128_pd::<0x31>(xy_hi, zo_hi),
    ];
    for (o, r) in out.iter_mut().zip(records) {
        _mm256_storeu_pd(o.as_mut_ptr(), r);
    }
}

/// Vertex `k` of the four triangles `i` (indices into `records`), one per lane.
///
/// # Safety
/// The CPU must support AVX2, and every index must be within `records`.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn gather(records: &[VertexRecord], i: &[[u32; 3]; 4], k: usize) -> Projected {
    let r = |t: usize| _mm256_loadu_pd(records.get_unchecked(i[t][k] as usize).as_ptr());
    let (a, b, c, d) = (r(0), r(1), r(2), r(3));
    // The 4x4 transpose of four records into x, y, z, ok lanes.
    let (ab_lo, ab_hi) = (_mm256_unpacklo_pd(a, b), _mm256_unpackhi_pd(a, b));
    let (cd_lo, cd_hi) = (_mm256_unpacklo_pd(c, d), _mm256_unpackhi_pd(c, d));
    Projected {
        x: _mm256_permute2f128_pd::<0x20>(ab_lo, cd_lo),
        y: _mm256_permute2f128_pd::<0x20>(ab_hi, cd_hi),
        z: _mm256_permute2f128_pd::<0x31>(ab_lo, cd_lo),
        ok: _mm256_permute2f128_pd::<0x31>(ab_hi, cd_hi),
    }
}

/// The vertices of the four triangles `i` (indices into `records`), projected
/// by [`project4`], as lanes for [`uncovered4_projected`] and [`setup4_projected`].
///
/// # Safety
/// The CPU must support AVX2, and every index must be within `records`.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn gather4(records: &[VertexRecord], i: &[[u32; 3]; 4]) -> [Projected; 3] {
    [gather(records, i, 0), gather(records, i, 1), gather(records, i, 2)]
}

/// The pixel columns `x0..=x1` and rows `y0..=y1` whose centres lie within the
/// vertices' bounds (`setup_screen`), as `[x0, y0, x1, y1]`: exact, as the
/// divisions are by a power of two.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn pixel_box([p0, p1, p2]: &[Projected; 3], viewport: Viewport) -> [__m256d; 4] {
    let (zero, half, inv_one) = (_mm256_setzero_pd(), _mm256_set1_pd(HALF as f64), _mm256_set1_pd(1.0 / ONE as f64));
    let min3 = |a, b, c| _mm256_min_pd(_mm256_min_pd(a, b), c);
    let max3 = |a, b, c| _mm256_max_pd(_mm256_max_pd(a, b), c);
    let first = |lo| _mm256_max_pd(_mm256_ceil_pd(_mm256_mul_pd(_mm256_sub_pd(lo, half), inv_one)), zero);
    let last = |hi, size: u32| {
        _mm256_min_pd(
            _mm256_floor_pd(_mm256_mul_pd(_mm256_sub_pd(hi, half), inv_one)),
            _mm256_set1_pd(f64::from(size) - 1.0),
        )
    };
    [
        first(min3(p0.x, p1.x, p2.x)),
        first(min3(p0.y, p1.y, p2.y)),
        last(max3(p0.x, p1.x, p2.x), viewport.width),
        last(max3(p0.y, p1.y, p2.y), viewport.height),
    ]
}

/// The lanes of the usual case among the triangles of the projected vertices `p`
/// whose bounding box holds no pixel centre of the viewport: those
/// [`setup4_projected`] drops for that reason (exactly, from the snapped
/// vertices, where [`uncovered4`] estimates). Bit `i` for triangle `i`.
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn uncovered4_projected(p: &[Projected; 3], viewport: Viewport) -> u8 {
    let usual = _mm256_and_pd(_mm256_and_pd(p[0].ok, p[1].ok), p[2].ok);
    let [x0, y0, x1, y1] = pixel_box(p, viewport);
    let empty = _mm256_or_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(x0, x1), _mm256_cmp_pd::<_CMP_GT_OQ>(y0, y1));
    bits(_mm256_and_pd(usual, empty)) as u8
}

/// Lanes where the triangle `p` (vertices in the order of positive area)
/// covers the centre of pixel `(x, y)`: its edge functions as
/// `setup::edges_at` defines them, top-left rule included, exact in `f64`
/// (coordinates below 2^23 in magnitude, so each product is below 2^48).
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn centre_covered(p: &[Projected; 3], x: __m256d, y: __m256d) -> __m256d {
    let (zero, one, half) = (_mm256_setzero_pd(), _mm256_set1_pd(ONE as f64), _mm256_set1_pd(HALF as f64));
    let (cx, cy) = (_mm256_add_pd(_mm256_mul_pd(x, one), half), _mm256_add_pd(_mm256_mul_pd(y, one), half));
    let edge = |a: &Projected, b: &Projected| {
        let (dx, dy) = (_mm256_sub_pd(b.x, a.x), _mm256_sub_pd(b.y, a.y));
        let value = _mm256_sub_pd(_mm256_mul_pd(dx, _mm256_sub_pd(cy, a.y)), _mm256_mul_pd(dy, _mm256_sub_pd(cx, a.x)));
        // A top or left edge covers centres on it (`>= 0`), another does not
        // (`>= 1`: `> 0`, the value being an integer).
        let top_left = _mm256_or_pd(
            _mm256_cmp_pd::<_CMP_LT_OQ>(dy, zero),
            _mm256_and_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(dy, zero), _mm256_cmp_pd::<_CMP_GT_OQ>(dx, zero)),
        );
        _mm256_blendv_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(value, zero), _mm256_cmp_pd::<_CMP_GE_OQ>(value, zero), top_left)
    };
    _mm256_and_pd(_mm256_and_pd(edge(&p[0], &p[1]), edge(&p[1], &p[2])), edge(&p[2], &p[0]))
}

/// [`setup4`] from its triangles' projected vertices `p` ([`project_usual`]).
///
/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn setup4_projected(
    [p0, mut p1, mut p2]: [Projected; 3],
    cull_back: bool,
    cmd: u32,
    viewport: Viewport,
    out: &mut [RasterTri; 4],
) -> Lanes {
    let zero = _mm256_setzero_pd();
    let usual = _mm256_and_pd(_mm256_and_pd(p0.ok, p1.ok), p2.ok);

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

    let [x0, y0, x1, y1] = pixel_box(&[p0, p1, p2], viewport);
    let inv_one = _mm256_set1_pd(1.0 / ONE as f64);
    keep = _mm256_and_pd(keep, _mm256_and_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(x0, x1), _mm256_cmp_pd::<_CMP_LE_OQ>(y0, y1)));
    // A triangle whose box holds one pixel centre and that does not cover it
    // covers nothing: most of a large scene's set-up triangles (dropped here,
    // not by `RasterTri::covered_rows` after the set-up).
    let single = _mm256_and_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(x0, x1), _mm256_cmp_pd::<_CMP_EQ_OQ>(y0, y1));
    if bits(_mm256_and_pd(single, keep)) != 0 {
        keep = _mm256_andnot_pd(_mm256_andnot_pd(centre_covered(&[p0, p1, p2], x0, y0), single), keep);
    }

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
    // The raster forms, field by field in memory order (a 4x4 transpose per four
    // fields): the vertices, the command, the bounding box (columns, then rows,
    // then the plane's row origin, its top), the depth plane, and padding.
    let plane = [_mm_castps_si128(plane[0]), _mm_castps_si128(plane[1]), _mm_castps_si128(plane[2])];
    let fields = [
        [ints(p0.x), ints(p0.y), ints(p1.x), ints(p1.y)],
        [ints(p2.x), ints(p2.y), _mm_set1_epi32(cmd as i32), ints(x0)],
        [ints(x1), ints(y0), ints(y1), ints(y0)],
        [plane[0], plane[1], plane[2], _mm_setzero_si128()],
    ];
    for (k, [a, b, c, d]) in fields.into_iter().enumerate() {
        let (ab_lo, ab_hi) = (_mm_unpacklo_epi32(a, b), _mm_unpackhi_epi32(a, b));
        let (cd_lo, cd_hi) = (_mm_unpacklo_epi32(c, d), _mm_unpackhi_epi32(c, d));
        let rows = [
            _mm_unpacklo_epi64(ab_lo, cd_lo),
            _mm_unpackhi_epi64(ab_lo, cd_lo),
            _mm_unpacklo_epi64(ab_hi, cd_hi),
            _mm_unpackhi_epi64(ab_hi, cd_hi),
        ];
        for (t, row) in out.iter_mut().zip(rows) {
            // SAFETY: bytes 16k..16k + 16 of the 64-byte `RasterTri` (the layout is
            // checked at the top of the module); every bit pattern is a valid value of its fields.
            unsafe { _mm_storeu_si128(std::ptr::from_mut(t).cast::<__m128i>().add(k), row) };
        }
    }
    Lanes { ready: (usual & keep) as u8, scalar: (!usual & 0b1111) as u8 }
}
