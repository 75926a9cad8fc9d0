//! From clip space to the screen: near-plane clipping, the perspective divide,
//! and the snapping of vertices to the rasterizer's sub-pixel grid that makes
//! the buffer's coverage the rasterizer's.
//!
//! # Coverage
//! A triangle's mask holds exactly the pixels the rasterizer covers with it,
//! whatever the scene. Its vertices are projected as the rasterizer projects
//! them (`f64` divide of the `f32` clip coordinates) and snapped to the same
//! grid, the nearest multiple of `1 / 2^bits` pixel (halves away from zero); a
//! pixel is covered when its centre passes the three edge functions of the
//! snapped vertices, with the top-left rule on an edge (exactly one of two
//! triangles sharing an edge takes a centre on it). With coordinates below
//! `2^15` pixels and at most [`crate::MAX_SUBPIXEL_BITS`] bits every such edge
//! function needs at most 49 significant bits, so `f64` evaluates it exactly:
//! the buffer's test is the rasterizer's, decided identically. This holds for
//! triangles in front of the near plane with their vertices within 8000 pixels
//! of the screen (inside the soft backend's guard band, so that it does not
//! clip them either). Any other triangle (crossing the near plane, or reaching
//! farther out) is drawn unsnapped with its edges moved inward by 1/32 pixel,
//! more than a rasterizer's own clipping and snapping move its edges on screen,
//! so its mask lies within the rasterizer's coverage of its clipped polygon; it
//! is rare (geometry at the camera) and its few cracks cost little culling.
//!
//! What a GPU must share for this: its vertices on the same grid points. A GPU
//! computes clip coordinates and the projection in its own `f32` arithmetic, a
//! few units in the last place (about `1e-4` pixel) from the buffer's; where
//! that straddles a rounding tie of the grid, it snaps the vertex to the
//! neighbouring point, and pixel centres within 1/256 pixel of that vertex's
//! outer edges can then differ. The depth bounds below allow for such a step;
//! coverage there is the one thing this argument assumes of a GPU rather than
//! proves.

use crate::clip::clip_near;
use crate::raster::{CullMode, ScreenTriangle, Tolerance};
use glam::{DVec2, DVec3, DVec4, Vec4};

/// Pixels beyond each side of the screen within which the vertices of a
/// triangle that does not cross the near plane are snapped: inside the soft
/// backend's guard band (8192 pixels), so that it does not clip such a
/// triangle either and both snap the same vertices.
pub(crate) const SNAP_RANGE: f64 = 8000.0;

/// Largest absolute coordinate (pixels) snapped. Below `2^15`, with at most 8
/// sub-pixel bits, the edge functions of snapped vertices at pixel centres
/// need at most 49 significant bits: `f64` evaluates them exactly.
pub(crate) const SNAP_LIMIT: f64 = 32000.0;

/// Largest absolute coordinate (pixels) of a vertex drawn at all; a polygon
/// with a vertex beyond it (or with `w <= 0`) is not drawn, which only makes
/// the buffer cull less. Far below it, the `f64` rounding of an edge function
/// is negligible against [`UNSNAPPED_MARGIN`].
pub(crate) const DRAW_LIMIT: f64 = 1e9;

/// Pixels by which the edges of a triangle that is not snapped (it crosses the
/// near plane, or a vertex lies outside the snapping range) are moved inward,
/// and by which its depth plane is raised ([`Tolerance`]): a bound on how far a
/// rasterizer's own clipped and snapped vertices can lie from the buffer's
/// (half a 1/256 grid step of snapping, plus the rounding of `f32` clipping
/// and projection, about `1e-7` of a coordinate: under 1/32 pixel for
/// coordinates up to 200,000 pixels).
pub(crate) const UNSNAPPED_MARGIN: f64 = 1.0 / 32.0;

/// Clips a clip-space triangle to the near plane, projects it to a `width` x
/// `height` screen and hands the drawable triangles of the resulting fan to
/// `out`; returns how many triangles the fan has (drawable or not).
///
/// A triangle in front of the near plane with its vertices within
/// [`SNAP_RANGE`] of the screen is projected as the soft backend projects it
/// (`f64` divide of the `f32` clip coordinates) and snapped to the grid of
/// `subpixel_bits` fractional bits (rounding halves away from zero): its edges
/// are then the rasterizer's, exactly. Any other is drawn unsnapped with
/// [`UNSNAPPED_MARGIN`].
pub(crate) fn screen_triangles(
    clip: [Vec4; 3],
    cull: CullMode,
    width: u32,
    height: u32,
    subpixel_bits: u32,
    out: &mut dyn FnMut(&ScreenTriangle),
) -> u64 {
    let mut poly = [Vec4::ZERO; 4];
    let n = clip_near(clip, &mut poly);
    if n < 3 {
        return 0;
    }
    let (w, h) = (f64::from(width), f64::from(height));
    let in_range = |v: f64, size: f64| (-SNAP_RANGE..=size + SNAP_RANGE).contains(&v) && v.abs() <= SNAP_LIMIT;
    let mut snap = clip.iter().all(|c| c.z >= 0.0);
    let mut screen = [DVec3::ZERO; 4];
    for (s, c) in screen.iter_mut().zip(&poly[..n]) {
        let c = c.as_dvec4();
        let DVec2 { x, y } = to_screen(c, w, h);
        // Written so that NaN fails.
        if !(c.w > 0.0 && x.abs() < DRAW_LIMIT && y.abs() < DRAW_LIMIT) {
            return n as u64 - 2;
        }
        snap &= in_range(x, w) && in_range(y, h);
        *s = DVec3::new(x, y, c.z / c.w);
    }
    let tolerance = if snap {
        let grid = f64::from(1u32 << subpixel_bits);
        for s in &mut screen[..n] {
            (s.x, s.y) = (round(s.x * grid) / grid, round(s.y * grid) / grid);
        }
        // The depth slack of one grid step covers a rasterizer whose own
        // rounding put a vertex at the neighbouring grid point.
        Tolerance { edge: 0.0, depth: 1.0 / grid }
    } else {
        Tolerance { edge: UNSNAPPED_MARGIN, depth: UNSNAPPED_MARGIN }
    };
    for k in 1..n - 1 {
        if let Some(tri) = ScreenTriangle::new([screen[0], screen[k], screen[k + 1]], cull, width, height, tolerance) {
            out(&tri);
        }
    }
    n as u64 - 2
}

/// Clip-space point `c` on a `width` x `height` screen (pixels, y down),
/// divided in `f64`: where the set-up puts a vertex before snapping it, and
/// where the parallel path's bins take it to be.
#[inline]
pub(crate) fn to_screen(c: DVec4, width: f64, height: f64) -> DVec2 {
    DVec2::new((c.x / c.w + 1.0) * 0.5 * width, (1.0 - c.y / c.w) * 0.5 * height)
}

/// `x.round()` (halves away from zero) for `|x| < 2^52`, as the soft
/// rasterizer rounds, without the library call `f64::round` costs where
/// SSE4.1 is not assumed.
#[inline]
fn round(x: f64) -> f64 {
    let t = x as i64;
    // Exact: x and t have the same sign and differ by less than 1.
    let fraction = x - t as f64;
    (t + i64::from(fraction >= 0.5) - i64::from(fraction <= -0.5)) as f64
}

#[cfg(test)]
mod tests {
    #[test]
    fn round_takes_halves_away_from_zero_as_f64_round_does() {
        for x in [0.0, 0.49999999999999994, 0.5, 1.5, 2.5, -0.5, -1.5, -2.4, 1e15 + 0.5, -7.75, 3.0] {
            assert_eq!(super::round(x), x.round(), "{x}");
        }
    }
}
