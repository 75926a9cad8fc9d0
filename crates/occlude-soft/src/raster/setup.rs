//! Triangle setup: projection to fixed-point screen coordinates, culling, and the
//! integer edge functions and depth plane the tile rasterizer evaluates.

use glam::{DVec4, Vec4};

use super::clip::{clip_triangle, Clipped, GuardBand, Polygon};

/// Sub-pixel bits of the fixed-point screen coordinates.
pub const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed-point units.
pub(super) const ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half a pixel in fixed-point units: the offset of a pixel centre.
pub(super) const HALF: i64 = ONE / 2;
/// Largest absolute screen coordinate (pixels) a vertex may have. The guard band
/// keeps vertices well inside it; it bounds the edge-function products far below
/// `i64` overflow (coordinates < 2^24 fixed-point units, products < 2^50).
pub(super) const COORD_LIMIT: f64 = 32768.0;

/// The viewport a triangle is set up for.
#[derive(Clone, Copy, Debug)]
pub(super) struct Viewport {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The guard band clipped to.
    pub guard: GuardBand,
}

impl Viewport {
    /// The viewport of a `width` x `height` depth buffer.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, guard: GuardBand::new(width, height) }
    }
}

/// A vertex snapped to fixed point, `[x, y]` with [`SUBPIXEL_BITS`] fractional bits,
/// `y` down. Vertices lie within `COORD_LIMIT` pixels, so `i32` holds them.
pub(super) type Fixed = [i32; 2];

/// One edge function, evaluated as `origin + step_x * dx + step_y * dy` at the centre
/// of the pixel `dx` columns right of and `dy` rows below the pixel it is set up at. A
/// pixel is covered when this is `>= 0` for all three edges (the top-left fill-rule
/// bias is already subtracted from `origin`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Edge {
    /// Change per pixel to the right.
    pub step_x: i64,
    /// Change per pixel down.
    pub step_y: i64,
    /// Value (minus the fill-rule bias) at the centre of the pixel it is set up at.
    pub origin: i64,
}

/// The edge functions of the triangle `v` (in the order of positive area: clockwise
/// on the screen) set up at the centre of the pixel `(x, y)`. The one definition of
/// coverage: every path evaluates these, at whatever pixel it starts from (the
/// functions are linear, so the values are the same).
#[inline(always)]
pub(super) fn edges_at(v: &[Fixed; 3], x: i32, y: i32) -> [Edge; 3] {
    let (ref_x, ref_y) = (i64::from(x) * ONE + HALF, i64::from(y) * ONE + HALF);
    let edge = |a: Fixed, b: Fixed| {
        let [ax, ay] = a.map(i64::from);
        let (dx, dy) = (i64::from(b[0]) - ax, i64::from(b[1]) - ay);
        // Top-left rule (y down, positive area): an edge is top when horizontal with
        // the interior below it, left when it goes up. Pixel centres exactly on other
        // edges are not covered.
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        Edge {
            step_x: -dy * ONE,
            step_y: dx * ONE,
            origin: dx * (ref_y - ay) - dy * (ref_x - ax) - i64::from(!top_left),
        }
    };
    [edge(v[0], v[1]), edge(v[1], v[2]), edge(v[2], v[0])]
}

/// A triangle ready to rasterize: screen-space pixel bounding box (inclusive,
/// clipped to the viewport), vertices and depth plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct SetupTri {
    /// Index of the command the triangle belongs to.
    pub cmd: u32,
    /// Leftmost pixel column whose centre may be covered.
    pub x0: i32,
    /// Topmost pixel row whose centre may be covered.
    pub y0: i32,
    /// Rightmost pixel column (inclusive).
    pub x1: i32,
    /// Bottom pixel row (inclusive).
    pub y1: i32,
    /// The vertices, in the order of positive area.
    pub verts: [Fixed; 3],
    /// Depth at the centre of pixel `(x0, y0)`.
    pub z_origin: f32,
    /// Depth change per pixel to the right.
    pub z_dx: f32,
    /// Depth change per pixel down.
    pub z_dy: f32,
}

impl SetupTri {
    /// The edge functions, set up at the bounding box's top-left pixel.
    pub fn edges(&self) -> [Edge; 3] {
        edges_at(&self.verts, self.x0, self.y0)
    }

    /// The depth plane along the pixel row `y0 + dy`.
    pub fn row_plane(&self, dy: i32) -> RowPlane {
        RowPlane::of(self.z_origin, self.z_dx, self.z_dy, dy)
    }
}

/// A triangle's depth plane along one pixel row: the one formula for a pixel's depth
/// that every path (scalar, SIMD, the tests' reference) evaluates.
#[derive(Clone, Copy, Debug)]
pub(super) struct RowPlane {
    /// Depth at the centre of the row's pixel in the bounding box's first column.
    pub z_row: f32,
    /// Depth change per pixel to the right.
    pub z_dx: f32,
}

impl RowPlane {
    /// The plane `z_origin + z_dx * dx + z_dy * dy` along the row `dy` below its
    /// origin.
    #[inline(always)]
    pub fn of(z_origin: f32, z_dx: f32, z_dy: f32, dy: i32) -> Self {
        Self { z_row: z_origin + z_dy * dy as f32, z_dx }
    }

    /// Depth at the centre of the pixel `dx` columns right of the bounding box's
    /// first column. A pure function of the triangle and the pixel, so every tile and
    /// thread computes the same bits. Negative values (rounding just past the near
    /// plane) and NaN become `+0.0`, so that depth values that compare equal are also
    /// bit-identical.
    #[inline(always)]
    pub fn depth(&self, dx: i32) -> f32 {
        let z = self.z_row + self.z_dx * dx as f32;
        if z > 0.0 {
            z
        } else {
            0.0
        }
    }
}

/// A vertex projected to the screen: fixed-point position and NDC depth.
#[derive(Clone, Copy, Debug)]
struct ScreenVertex {
    x: i64,
    y: i64,
    z: f64,
}

/// Clips `tri` (clip space) and passes its rasterizable pieces (0 to 6 triangles)
/// to `emit`. Degenerate, non-finite, back-facing (when `cull_back`) and off-screen
/// pieces are dropped.
#[inline(always)]
pub(super) fn setup_triangle(
    tri: &[Vec4; 3],
    cull_back: bool,
    cmd: u32,
    viewport: Viewport,
    poly: &mut Polygon,
    mut emit: impl FnMut(SetupTri),
) {
    match clip_triangle(tri, viewport.guard, poly) {
        Clipped::Outside => {}
        Clipped::Inside(verts) => setup_polygon(&verts, cull_back, cmd, viewport, &mut emit),
        Clipped::Polygon => setup_polygon(poly.as_slice(), cull_back, cmd, viewport, &mut emit),
    }
}

/// Projects the convex polygon `verts` (clip space, inside the clipping planes) and
/// passes the triangles of its fan that cover some pixel centre to `emit`.
#[inline(always)]
fn setup_polygon(verts: &[DVec4], cull_back: bool, cmd: u32, viewport: Viewport, emit: &mut impl FnMut(SetupTri)) {
    let mut screen = [ScreenVertex { x: 0, y: 0, z: 0.0 }; super::clip::MAX_POLY];
    for (s, v) in screen.iter_mut().zip(verts) {
        match project(*v, viewport) {
            Some(p) => *s = p,
            None => return,
        }
    }
    let screen = &screen[..verts.len()];
    for i in 1..screen.len() - 1 {
        if let Some(t) = setup_screen([screen[0], screen[i], screen[i + 1]], cull_back, cmd, viewport) {
            emit(t);
        }
    }
}

/// Projects a clip-space vertex to fixed-point screen coordinates (x right, y down,
/// row 0 at the top). `None` when the result is not finite or out of range.
fn project(v: DVec4, viewport: Viewport) -> Option<ScreenVertex> {
    let sx = (v.x / v.w + 1.0) * 0.5 * f64::from(viewport.width);
    let sy = (1.0 - v.y / v.w) * 0.5 * f64::from(viewport.height);
    let z = v.z / v.w;
    // Written so that NaN fails the test.
    if !(sx.abs() <= COORD_LIMIT && sy.abs() <= COORD_LIMIT && z.is_finite()) {
        return None;
    }
    Some(ScreenVertex { x: round(sx * ONE as f64), y: round(sy * ONE as f64), z })
}

/// `x.round() as i64` (halves away from zero) for `|x| < 2^52`, without the libm call
/// that `f64::round` costs where SSE4.1 is not assumed.
#[inline(always)]
pub(super) fn round(x: f64) -> i64 {
    let t = x as i64;
    // Exact: x and t have the same sign and differ by less than 1.
    let frac = x - t as f64;
    t + i64::from(frac >= 0.5) - i64::from(frac <= -0.5)
}

/// Sets up one screen-space triangle. `None` when it is degenerate, culled, covers no
/// pixel centre inside the viewport, or has a non-finite depth plane.
fn setup_screen(mut v: [ScreenVertex; 3], cull_back: bool, cmd: u32, viewport: Viewport) -> Option<SetupTri> {
    let area = (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x);
    // With y pointing down, counter-clockwise in NDC (front-facing) is negative area.
    if area == 0 || (cull_back && area > 0) {
        return None;
    }
    if area < 0 {
        v.swap(1, 2);
    }

    // Pixels whose centres `p * ONE + HALF` lie within the vertices' bounds.
    let min_x = v.iter().map(|p| p.x).min()?;
    let max_x = v.iter().map(|p| p.x).max()?;
    let min_y = v.iter().map(|p| p.y).min()?;
    let max_y = v.iter().map(|p| p.y).max()?;
    let x0 = ceil_div(min_x - HALF, ONE).max(0);
    let y0 = ceil_div(min_y - HALF, ONE).max(0);
    let x1 = (max_x - HALF).div_euclid(ONE).min(i64::from(viewport.width) - 1);
    let y1 = (max_y - HALF).div_euclid(ONE).min(i64::from(viewport.height) - 1);
    if x0 > x1 || y0 > y1 {
        return None;
    }

    // Depth plane z = z0 + a * (x - x0) + b * (y - y0) in pixel units; z/w is affine
    // in screen space.
    let px = |p: ScreenVertex| p.x as f64 / ONE as f64;
    let py = |p: ScreenVertex| p.y as f64 / ONE as f64;
    let (dx1, dy1, dz1) = (px(v[1]) - px(v[0]), py(v[1]) - py(v[0]), v[1].z - v[0].z);
    let (dx2, dy2, dz2) = (px(v[2]) - px(v[0]), py(v[2]) - py(v[0]), v[2].z - v[0].z);
    let det = dx1 * dy2 - dx2 * dy1;
    let a = (dz1 * dy2 - dz2 * dy1) / det;
    let b = (dx1 * dz2 - dx2 * dz1) / det;
    let c = v[0].z + a * (x0 as f64 + 0.5 - px(v[0])) + b * (y0 as f64 + 0.5 - py(v[0]));
    let (z_origin, z_dx, z_dy) = (c as f32, a as f32, b as f32);
    if !(z_origin.is_finite() && z_dx.is_finite() && z_dy.is_finite()) {
        return None;
    }

    let verts = v.map(|p| [p.x as i32, p.y as i32]);
    Some(SetupTri { cmd, x0: x0 as i32, y0: y0 as i32, x1: x1 as i32, y1: y1 as i32, verts, z_origin, z_dx, z_dy })
}

/// `ceil(n / d)` for `d > 0`.
fn ceil_div(n: i64, d: i64) -> i64 {
    -(-n).div_euclid(d)
}
