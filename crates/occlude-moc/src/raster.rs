//! Occluder rasterization, in MOC's 32x8-pixel tiles (HPG 2016 section 4): per
//! tile row (two subtile rows), each edge's x-intercepts on the eight pixel
//! rows, then per tile in reach the coverage masks of its eight subtiles by
//! shifts of the rows' spans and their depth bounds from the triangle's plane,
//! all eight at once ([`lanes`], in AVX2 where the CPU has it: [`avx2`]),
//! loaded from and stored to the buffer's [`Tile`] in one go. With AVX2,
//! triangles are set up four at a time ([`setup`]).
//!
//! Coverage is defined pixel by pixel by [`Edge::covers`] (the sign of an `f64`
//! edge function at the pixel centre, with the top-left rule on the edge; of
//! the snapped vertices, `crate::project`, exact). Along a row that function is
//! monotone in `x` (every rounded operation is), so an edge's covered pixels
//! are a half-line; its end is found from the intercept, and only the pixel
//! centres within the intercept's proven error band ([`Edge::band`]) are
//! decided by evaluating [`Edge::covers`] itself. Masks are therefore exactly
//! what the pixel-by-pixel definition gives.
//!
//! # Depth bounds
//! The depth plane is the one through the snapped vertices, raised by
//! `(|dz/dx| + |dz/dy|) s` for a vertex displacement `s` of one grid step
//! (1/32 pixel unsnapped). A rasterizer whose vertices lie within `s` of the buffer's
//! interpolates, at a pixel `p` inside its triangle, the buffer's plane at the
//! point whose barycentric weights in the buffer's triangle are `p`'s in its
//! own (a convex combination of the vertex displacements away from `p`, so
//! within `s` in x and in y): at most the raised plane at `p`. Over a subtile
//! that is bounded by the raised plane's largest value at the subtile's four
//! corners, capped by the farthest vertex (the depth is a convex combination of
//! the vertices'). The buffer takes that bound for every subtile of a
//! triangle's subtile row from one anchor, the first subtile of the triangle's
//! window: the plane at the anchor's corner in `f64`, nudged farther by `2^-22`
//! of itself (more than its rounding to the nearest `f32` can take back), plus,
//! for the subtile `m` places to the right, `m` steps of an `f32` step never
//! less than the plane's rise `8 dz/dx` from one corner to the next, with as
//! many low significand bits zero as make `m` steps exact for every `m` on the
//! screen (8 on a 1920-pixel-wide screen); that sum is rounded to `f32` and
//! nudged farther by `2^-22` of itself, more than the sum's rounding took, and
//! capped by the farthest vertex, itself rounded far.
//!
//! # Threads
//! Inside a rayon pool of several threads, large triangle sets are binned by
//! their vertices' rows to bands of tile rows (four bands a thread), in
//! parallel chunks keeping only triangle indices. The bands are then set up and
//! drawn in parallel, each taking its triangles in order; a triangle touching
//! two bands is set up in both. The buffer and the work counted are the same
//! whatever the threads.

use crate::buffer::{MaskedBuffer, MergeMode, Tile};
use crate::project::{screen_triangles, to_screen};
use crate::SUBTILE_H;
use glam::{DVec2, DVec3, Mat4, Vec3, Vec4};
use rayon::prelude::*;

mod avx2;
mod lanes;
mod setup;

pub(crate) use avx2::Avx2;
use lanes::{Intercepts, Lanes, Portable, Spans, TileRow, LANES, STEP_ROWS, TILE_W};
use setup::{Batch, SETUP_LANES};

/// What a [`MaskedBuffer::render_triangles`] call rasterized: the measure of
/// its cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderWork {
    /// Triangles set up after near-plane clipping (a clipped triangle may
    /// become two), before back-face and empty-area rejection.
    pub triangles: u64,
    /// 32x8-pixel tiles overlapped by the pixel-centre ranges of the
    /// triangles that were rasterized.
    pub tiles: u64,
}

impl std::ops::AddAssign for RenderWork {
    fn add_assign(&mut self, other: Self) {
        self.triangles += other.triangles;
        self.tiles += other.tiles;
    }
}

/// Which triangles are drawn, by winding on screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CullMode {
    /// Skip triangles whose vertices run clockwise in NDC (y up): wgpu's default
    /// front face is counter-clockwise.
    #[default]
    Back,
    /// Draw both windings.
    None,
}

/// Relative error allowance of the intercept bands ([`Edge::band`]): `2^-46`,
/// far above the few units in the last place (`2^-53`) the few rounded
/// operations of one evaluation can lose.
const BAND_SCALE: f64 = 1.0 / (1u64 << 46) as f64;

/// How far a rasterizer's vertices may lie from a [`ScreenTriangle`]'s, and
/// what the triangle gives up for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tolerance {
    /// Pixels by which the edges are moved inward (0: the edges themselves).
    pub edge: f64,
    /// Pixels of vertex displacement the depth bounds allow for.
    pub depth: f64,
}

impl Tolerance {
    /// The triangle as given: its own edges and depth plane.
    #[cfg(test)]
    pub(crate) const NONE: Tolerance = Tolerance { edge: 0.0, depth: 0.0 };
}

/// One edge of a screen-space triangle: `e(x, y) = a x + b y + c`, positive
/// inside.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Edge {
    a: f64,
    b: f64,
    c: f64,
    /// Whether a pixel centre exactly on the edge is covered: for one of the two
    /// directions of an edge only, so a shared edge leaves no hole and no pixel
    /// is taken twice.
    on: bool,
    /// The intercept `x = slope y + offset` where `e` is zero (`a != 0`).
    slope: f64,
    offset: f64,
}

impl Edge {
    /// The edge from `p` to `q` of a triangle whose edge functions are positive
    /// inside, moved inward by `margin` pixels (0: the edge itself, with the
    /// top-left rule on it; more: pixel centres on the moved edge are outside).
    fn new(p: DVec3, q: DVec3, margin: f64) -> Self {
        let (a, b) = (p.y - q.y, q.x - p.x);
        // `e > margin (|a| + |b|)` puts the centre farther than `margin` from the
        // edge, whose distance is `e / sqrt(a^2 + b^2)`.
        let c = -(a * p.x + b * p.y) - margin * (a.abs() + b.abs());
        let r = 1.0 / a;
        // The top-left rule (y down, edge functions positive inside): a centre
        // on the edge is covered when the edge goes up, or is horizontal with
        // the inside below it.
        let on = margin == 0.0 && (a > 0.0 || (a == 0.0 && b > 0.0));
        Edge { a, b, c, on, slope: -b * r, offset: -c * r }
    }

    /// Whether the pixel centre (`px`, `py`) is covered by this edge: the
    /// definition every mask follows.
    #[inline]
    pub(crate) fn covers(&self, px: f64, py: f64) -> bool {
        let e = self.a * px + self.b * py + self.c;
        e > 0.0 || (self.on && e == 0.0)
    }

    /// Half-width, in pixels, of the band around the computed intercept outside
    /// which [`covers`](Self::covers) is decided by the side of the intercept,
    /// for pixel centres within `x_max`, `y_max` of the origin: the intercept's
    /// own rounding plus the edge function's rounding divided by its slope
    /// ([`BAND_SCALE`]). Infinite or NaN when the intercept cannot be trusted.
    fn band(&self, x_max: f64, y_max: f64) -> f64 {
        let intercept = self.slope.abs() * y_max + self.offset.abs() + x_max + 1.0;
        let function = (self.a.abs() * x_max + self.b.abs() * y_max + self.c.abs()) * (1.0 / self.a).abs();
        BAND_SCALE * (intercept + function)
    }

    /// The pixels `lo..hi` of row `y` (centre `y + 0.5`), clipped to `x0..x1`,
    /// covered by this edge, given its `band`.
    #[inline]
    fn span(&self, y: i32, x0: i32, x1: i32, band: f64) -> (i32, i32) {
        let py = f64::from(y) + 0.5;
        if self.a == 0.0 {
            // Horizontal: the whole row is in or out.
            return if self.covers(0.5, py) { (x0, x1) } else { (x0, x0) };
        }
        let (min, max) = (f64::from(x0) - 2.0, f64::from(x1) + 2.0);
        // An intercept beyond the window x0..x1 moves to half a pixel beyond
        // min or max: the window's pixels keep their side, and no pixel index
        // falls in a band narrower than half a pixel around it.
        let t = (self.slope * py + self.offset - 0.5).clamp(min - 0.5, max + 0.5);
        // Pixels x <= below lie wholly on the side x < t; pixels x >= above on
        // the side x > t; those between are decided one by one. Usually no
        // pixel index is within the band of t (its fraction, exact, is farther
        // than the band from 0 and 1), and below and above are neighbours.
        let k = floor_in(t, min - 1.0, max + 1.0);
        let fraction = t - f64::from(k);
        let (lo, hi) = (t - band, t + band);
        let (below, above) = if fraction > band && 1.0 - fraction > band {
            (k, k + 1)
        } else if lo.is_finite() && hi.is_finite() {
            (-floor_in(-lo, -max, -min) - 1, floor_in(hi, min, max) + 1)
        } else {
            (x0 - 1, x1)
        };
        if self.a > 0.0 {
            // Covered to the right: from the first pixel that is.
            let first = (below + 1..above).find(|&x| self.covers(f64::from(x) + 0.5, py)).unwrap_or(above);
            (first.clamp(x0, x1), x1)
        } else {
            let end =
                (below + 1..above).rev().find(|&x| self.covers(f64::from(x) + 0.5, py)).map_or(below + 1, |x| x + 1);
            (x0, end.clamp(x0, x1))
        }
    }
}

/// `floor(v)` clamped to `min..=max` (small integers), without a library call.
#[inline]
fn floor_in(v: f64, min: f64, max: f64) -> i32 {
    let v = v.clamp(min, max);
    let i = v as i32;
    i - i32::from(f64::from(i) > v)
}

/// A triangle's depth plane `z = zx x + zy y + z0`, with the `f32` step of
/// its subtile bounds from one subtile to the next and their cap (its
/// farthest vertex depth), both set up with it for a screen of a given width.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthPlane {
    zx: f64,
    zy: f64,
    z0: f64,
    /// [`Self::lane_step`], set up with the plane.
    step: f32,
    /// [`Self::far_max`], set up with the plane.
    cap: f32,
}

impl DepthPlane {
    /// The plane through `t`, raised by `(|zx| + |zy|) slack`: at every point at
    /// least the plane's value anywhere within `slack` pixels (in x and in y),
    /// so also the depth a rasterizer interpolates from vertices it placed up to
    /// `slack` away from `t`'s (the module doc, "Depth bounds"), on a
    /// screen `width` pixels wide.
    fn new(t: &[DVec3; 3], slack: f64, width: u32) -> Self {
        let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
        let n = d1.cross(d2);
        let r = 1.0 / n.z;
        let (zx, zy) = (-n.x * r, -n.y * r);
        let z0 = t[0].z - zx * t[0].x - zy * t[0].y + (zx.abs() + zy.abs()) * slack;
        Self::from_terms(zx, zy, z0, t[0].z.max(t[1].z).max(t[2].z), width)
    }

    /// The plane `z = zx x + zy y + z0` capped at `zmax`, with its `f32`
    /// step and cap for a screen `width` pixels wide.
    pub(crate) fn from_terms(zx: f64, zy: f64, z0: f64, zmax: f64, width: u32) -> Self {
        let v = round_far(zx * 8.0);
        let (bits, low) = (v.to_bits(), (1u32 << step_zero_bits(width)) - 1);
        let step = f32::from_bits(if v >= 0.0 { (bits + low) & !low } else { bits & !low });
        DepthPlane { zx, zy, z0, step, cap: round_far(zmax) }
    }

    /// The row term `zy y + z0` of the subtile row whose top is `by`, at the
    /// row its corners' bound is taken on: the bottom one where the plane rises
    /// downward (a rounded product and sum are monotone in each coordinate, so
    /// that is where the rounded plane is largest too).
    #[inline]
    pub(crate) fn row_term(&self, by: f64) -> f64 {
        // A select of constants, not of sums, which compiles to a branch
        // that the plane's random orientation mispredicts.
        let y = by + if self.zy > 0.0 { 4.0 } else { 0.0 };
        self.zy * y + self.z0
    }

    /// The plane at column `x` of the row of `row` ([`Self::row_term`]),
    /// nudged farther and rounded to `f32` ([`round_far`]): never nearer than
    /// the plane there.
    #[inline]
    pub(crate) fn far_at(&self, x: f64, row: f64) -> f32 {
        round_far(self.zx * x + row)
    }

    /// The column of the corner whose bound a subtile from column `bx` takes:
    /// its right edge where the plane rises to the right.
    #[inline]
    pub(crate) fn corner_x(&self, bx: f64) -> f64 {
        if self.zx > 0.0 {
            bx + 8.0
        } else {
            bx
        }
    }

    /// An `f32` step from one subtile's corner to the next one's to the right,
    /// never less than the plane's rise `8 zx` and with its
    /// [`step_zero_bits`] lowest significand bits zero, so that its multiples
    /// by the subtile columns of the screen are exact in `f32`: `8 zx`
    /// rounded far ([`round_far`]), then its significand rounded up (positive)
    /// or cut (negative).
    #[inline]
    pub(crate) fn lane_step(&self) -> f32 {
        self.step
    }

    /// The farthest vertex depth rounded far ([`round_far`]): the cap of every
    /// bound.
    #[inline]
    pub(crate) fn far_max(&self) -> f32 {
        self.cap
    }

    /// An `f32` bound on the triangle's depth over subtile `l` (`0..4`) of
    /// tile `tx` in the subtile row whose top is `by`, from the first
    /// subtile of tile `anchor` (the first tile of the triangle's window, at
    /// or left of `tx`): the plane at the anchor subtile's corner
    /// ([`Self::corner_x`], [`Self::row_term`]) in `f64`, rounded far
    /// ([`Self::far_at`]), plus `m = 4 (tx - anchor) + l` [`Self::lane_step`]s
    /// (exact) in `f32` ([`far_sum`]), capped by [`Self::far_max`]. The
    /// subtile's corner lies `8 m` to the right of the anchor's, so this is
    /// never nearer than the plane's largest value at its corners, nor than the
    /// farthest vertex where that is nearer (the module doc, "Depth
    /// bounds"). The rasterizer keeps the anchor's value for a tile row and
    /// adds the steps tile by tile ([`lanes::tile_lanes`]).
    #[inline]
    pub(crate) fn subtile_bound(&self, anchor: u32, tx: u32, by: f64, l: usize) -> f32 {
        let base = self.far_at(self.corner_x(f64::from(anchor * TILE_W)), self.row_term(by));
        let m = 4 * (tx - anchor) + l as u32;
        far_sum(base, self.lane_step() * m as f32).min(self.far_max())
    }
}

/// The lowest significand bits that a depth plane's `f32` step
/// ([`DepthPlane::lane_step`]) keeps zero on a screen `width` pixels wide, so
/// that its product with every subtile column offset `m` of the screen (below
/// `4 ceil(width / 32)`) has at most 24 significant bits: exact. 8 bits on a
/// 1920-pixel-wide screen, leaving the step 16.
pub(crate) fn step_zero_bits(width: u32) -> u32 {
    let offsets = 4 * width.div_ceil(TILE_W).max(1);
    u32::BITS - (offsets - 1).leading_zeros()
}

/// Relative nudge of a depth bound before its rounding to `f32` ([`round_far`]):
/// `2^-22`, more than the `2^-24` relative error of rounding to the nearest `f32`.
pub(crate) const FAR_NUDGE: f64 = 1.0 / (1u32 << 22) as f64;

/// `depth` nudged farther, then rounded to the nearest `f32`, which is never
/// nearer than `depth`: the nudge `|depth| 2^-22 + 1e-12` exceeds the rounding's
/// error, at most `2^-24` of the nudged value (or `2^-150` below the normal
/// range), and the `f64` operations' own (`2^-53` of their operands). A single
/// conversion, where rounding up would take a comparison and a correction.
#[inline]
pub(crate) fn round_far(depth: f64) -> f32 {
    (depth + depth.abs() * FAR_NUDGE + 1e-12) as f32
}

/// [`FAR_NUDGE`] in `f32`.
pub(crate) const FAR_NUDGE_F32: f32 = 1.0 / (1u32 << 22) as f32;

/// `a + b` in `f32`, never less than the exact sum: the rounded sum `s`,
/// then `s + |s| 2^-22` rounded. Each rounding to nearest errs by at most
/// `2^-24` of its result (none where the sum is below the normal range, where
/// a sum of two `f32` is exact), so the second sum exceeds `s` by more than
/// `2^-23 |s|`, more than `s` can lie below `a + b`; where `|s| 2^-22` is
/// below the normal range its own rounding (`2^-150`) is less than the margin
/// for every normal `s`.
#[inline]
pub(crate) fn far_sum(a: f32, b: f32) -> f32 {
    let s = a + b;
    s + s.abs() * FAR_NUDGE_F32
}

/// What the traversal reads of a set-up triangle on every draw: its pixel
/// window, its edges' `f32` intercepts and its depth plane. The `f64` edges,
/// which decide the rare rows the intercepts leave undecided, are read
/// through [`SetUp::exact`] only then.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Raster {
    /// Columns `x0..x1` and rows `y0..y1` of pixels whose centres may be inside.
    pub(crate) x0: i32,
    pub(crate) x1: i32,
    pub(crate) y0: i32,
    pub(crate) y1: i32,
    pub(crate) plane: DepthPlane,
    /// The edges' `f32` intercepts from the triangle's first tile row
    /// ([`Intercepts::new`]).
    pub(crate) lanes: Intercepts,
}

impl Raster {
    /// How many 32x8-pixel tiles its pixel-centre ranges overlap.
    fn tiles(&self) -> u64 {
        // A tile is 4 x 2 subtiles; the window is on screen (`0 <= y0 < y1`),
        // so unsigned division is shifts.
        let ty = 2 * SUBTILE_H;
        let (first, last) = self.tile_columns();
        let (y0, y1) = (self.y0 as u32, self.y1 as u32);
        u64::from(last - first + 1) * u64::from((y1 - 1) / ty - y0 / ty + 1)
    }

    /// The first and last tile column of the window; the first is also the
    /// anchor of the depth bounds ([`DepthPlane::subtile_bound`]).
    fn tile_columns(&self) -> (u32, u32) {
        // The window is on screen (`0 <= x0 < x1`), so unsigned division is
        // shifts.
        (self.x0 as u32 / TILE_W, (self.x1 - 1) as u32 / TILE_W)
    }

    /// The first and one past the last subtile row the triangle touches.
    fn subtile_rows(&self) -> (u32, u32) {
        ((self.y0 / 4) as u32, ((self.y1 - 1) / 4 + 1) as u32)
    }
}

/// A triangle's edges in `f64` and their intercept bands ([`Edge::band`]):
/// what decides a row's span pixel by pixel where the `f32` intercepts cannot
/// ([`exact_spans`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Exact {
    pub(crate) edges: [Edge; 3],
    pub(crate) bands: [f64; 3],
}

/// A set-up triangle as the traversal ([`Band::draw`]) takes it: a
/// [`ScreenTriangle`], or a lane of the four triangles set up at once
/// ([`setup::Batch`]), read where the set-up wrote it rather than copied.
pub(crate) trait SetUp {
    /// What every draw reads.
    fn raster(&self) -> Raster;
    /// The exact edges, for the rows the intercepts leave undecided.
    fn exact(&self) -> Exact;
}

/// A triangle ready to rasterize: screen position (pixels, y down; z = NDC
/// depth) with edge functions positive inside, and the pixels whose centres it
/// may cover.
#[derive(Clone, Copy)]
pub(crate) struct ScreenTriangle {
    pub(crate) raster: Raster,
    pub(crate) exact: Exact,
}

#[cfg(test)]
impl ScreenTriangle {
    /// `tri`'s fields, copied.
    pub(crate) fn copy_of(tri: &impl SetUp) -> Self {
        ScreenTriangle { raster: tri.raster(), exact: tri.exact() }
    }
}

impl SetUp for ScreenTriangle {
    #[inline(always)]
    fn raster(&self) -> Raster {
        self.raster
    }

    fn exact(&self) -> Exact {
        self.exact
    }
}

impl ScreenTriangle {
    /// The triangle `t` on a `width` x `height` screen, its edges moved inward by
    /// `tolerance.edge` pixels and its depth plane raised by `tolerance.depth`
    /// ([`DepthPlane::new`]), or `None` when it is not drawn: a non-finite or
    /// negative depth coordinate, zero area, culled by winding, or no pixel
    /// centre on screen within its bounding box (on the inner side of a
    /// horizontal edge).
    #[inline]
    pub(crate) fn new(
        mut t: [DVec3; 3],
        cull: CullMode,
        width: u32,
        height: u32,
        tolerance: Tolerance,
    ) -> Option<Self> {
        if t.iter().any(|p| !p.is_finite() || p.z < 0.0) {
            return None;
        }
        // Signed area, positive for counter-clockwise in NDC (clockwise on screen).
        let area = (t[1].x - t[0].x) * (t[2].y - t[0].y) - (t[2].x - t[0].x) * (t[1].y - t[0].y);
        if area == 0.0 || (cull == CullMode::Back && area > 0.0) || area.abs() < 1e-12 {
            return None;
        }
        if area < 0.0 {
            t.swap(1, 2);
        }
        let (w, h) = (f64::from(width), f64::from(height));
        let lo_x = t[0].x.min(t[1].x).min(t[2].x).max(0.0);
        let hi_x = t[0].x.max(t[1].x).max(t[2].x).min(w);
        let lo_y = t[0].y.min(t[1].y).min(t[2].y).max(0.0);
        let hi_y = t[0].y.max(t[1].y).max(t[2].y).min(h);
        if lo_x >= hi_x || lo_y >= hi_y {
            return None;
        }
        // The first and one past the last pixel centre in lo..hi (both within
        // 0..=size): ceil(lo - 0.5) and floor(hi - 0.5) + 1.
        let centres =
            |lo: f64, hi: f64, size: f64| (-floor_in(0.5 - lo, -size, 1.0), floor_in(hi - 0.5, -1.0, size) + 1);
        let ((x0, x1), (y0, y1)) = (centres(lo_x, hi_x, w), centres(lo_y, hi_y, h));
        let (x0, x1, y0, y1) = (x0.max(0), x1.min(width as i32), y0.max(0), y1.min(height as i32));
        if x0 >= x1 || y0 >= y1 {
            return None;
        }
        let m = tolerance.edge;
        let edges = [Edge::new(t[0], t[1], m), Edge::new(t[1], t[2], m), Edge::new(t[2], t[0], m)];
        // A horizontal edge covers whole rows on one side of it: the window
        // keeps only the rows it covers (it may leave out the row whose
        // centres lie on it, or within the margin), and the lanes leave it
        // out ([`Intercepts::new`]).
        let (mut y0, mut y1) = (y0, y1);
        for edge in edges.iter().filter(|e| e.a == 0.0) {
            while y0 < y1 && !edge.covers(0.5, f64::from(y0) + 0.5) {
                y0 += 1;
            }
            while y1 > y0 && !edge.covers(0.5, f64::from(y1) - 0.5) {
                y1 -= 1;
            }
        }
        if y0 >= y1 {
            return None;
        }
        let bands = edges.map(|e| e.band(w, h));
        let plane = DepthPlane::new(&t, tolerance.depth, width);
        let raster = Raster { x0, x1, y0, y1, plane, lanes: Intercepts::EMPTY };
        let exact = Exact { edges, bands };
        let lanes = Intercepts::new(&raster, &exact);
        Some(ScreenTriangle { raster: Raster { lanes, ..raster }, exact })
    }
}

/// Subtile rows `first..first + tiles.len() * 8 / cols` of a buffer (whole
/// tile rows), which a thread rasterizes on its own.
pub(crate) struct Band<'a> {
    tiles: &'a mut [Tile],
    first: u32,
    /// One past the band's last subtile row.
    end: u32,
    cols: u32,
    width: u32,
    height: u32,
    merge: MergeMode,
    /// The AVX2 lanes, where the CPU has them; else the portable ones.
    avx2: Option<Avx2>,
}

impl Band<'_> {
    /// Rasterizes the triangle's tile rows (two subtile rows each; the band
    /// starts and ends on a tile row) within the band: per tile row, the
    /// eight pixel rows' spans ([`Lanes::edge_spans`] from the triangle's
    /// [`Intercepts`], [`exact_spans`]; the next tile row's taken before this
    /// one's tiles, so that the processor overlaps them), then per 32x8-pixel
    /// tile in their reach, the masks and depth bounds of its eight subtiles,
    /// merged. With AVX2 the whole triangle is one call, so that the steps
    /// inline into one loop.
    fn draw(&mut self, tri: &ScreenTriangle) {
        match self.avx2 {
            Some(avx2) => avx2.draw(self, tri),
            None => self.draw_with(tri, Portable),
        }
    }

    /// [`Self::draw`] of the lanes of `batch` whose bits `lanes` has, in
    /// lane order, read where the set-up stored them.
    fn draw_lanes(&mut self, batch: &Batch, lanes: u32) {
        for l in (0..SETUP_LANES).filter(|l| lanes >> l & 1 == 1) {
            self.draw_lane(batch, l);
        }
    }

    /// [`Self::draw`] of lane `l` of `batch`, read where the set-up stored it.
    #[inline(always)]
    fn draw_lane(&mut self, batch: &Batch, l: usize) {
        match self.avx2 {
            Some(avx2) => avx2.draw_lane(self, batch, l),
            None => self.draw_with(&batch.drawn(l), Portable),
        }
    }

    /// [`Self::draw`] with the steps of `lanes`.
    #[inline(always)]
    fn draw_with<L: Lanes, T: SetUp>(&mut self, tri: &T, lanes: L) {
        debug_assert!(self.first.is_multiple_of(2) && self.end.is_multiple_of(2), "bands of whole tile rows");
        let raster = tri.raster();
        let (r0, r1) = raster.subtile_rows();
        let top = r0 & !1;
        let (first, end) = (top.max(self.first), r1.min(self.end));
        if first >= end {
            return;
        }
        let mut spans = self.tile_row_spans(tri, &raster, lanes, top, first);
        let mut sy = first;
        // One test per tile row says whether another follows: the last row
        // costs one mispredicted branch, not one here and one in a loop test.
        while sy + 2 < end {
            let next = self.tile_row_spans(tri, &raster, lanes, top, sy + 2);
            self.draw_tile_row(&raster, lanes, sy, &spans);
            spans = next;
            sy += 2;
        }
        self.draw_tile_row(&raster, lanes, sy, &spans);
    }

    /// The spans of the tile row from subtile row `sy` of a triangle whose
    /// first tile row starts at subtile row `top`: the lanes'
    /// ([`Lanes::edge_spans`]), the edges they leave decided exactly
    /// ([`exact_spans`]), the rows beyond a horizontal edge and below the
    /// screen emptied ([`empty_outside_rows`]).
    #[inline(always)]
    fn tile_row_spans<L: Lanes, T: SetUp>(&self, tri: &T, raster: &Raster, lanes: L, top: u32, sy: u32) -> Spans {
        let y = sy * 4;
        let mut spans = lanes.edge_spans(raster, ((sy - top) * 4) as f32);
        if spans.exact != 0 {
            spans = exact_spans(&tri.exact(), (raster.x0, raster.x1), y as i32, spans);
        }
        let beyond_flat_edge = raster.lanes.flat && (y < raster.y0 as u32 || y + STEP_ROWS > raster.y1 as u32);
        if beyond_flat_edge || y + STEP_ROWS > self.height {
            spans = empty_outside_rows((raster.x0, raster.x1), (raster.y0, raster.y1), y, spans);
        }
        spans
    }

    /// The tiles of the tile row from subtile row `sy` (even) in the reach of
    /// its `spans`, or every tile column of a window at most [`NARROW_TILES`]
    /// wide: the loop's bounds then need not wait for the spans (a chain of
    /// dependent steps from the intercepts), and a tile the spans miss takes
    /// empty masks, which merge nothing.
    #[inline(always)]
    fn draw_tile_row<L: Lanes>(&mut self, raster: &Raster, lanes: L, sy: u32, spans: &Spans) {
        let (mut first, mut last) = raster.tile_columns();
        if last - first >= NARROW_TILES {
            let Some((left, right)) = lanes.reach(spans) else { return };
            // Spans lie within the window, so `0 <= left < right`: the tiles
            // by shifts of unsigned values.
            (first, last) = (left as u32 / TILE_W, (right - 1) as u32 / TILE_W);
        }
        let tiles_per_row = self.cols as usize / 4;
        let row = (sy - self.first) as usize / 2 * tiles_per_row;
        let tiles = &mut self.tiles[row..row + tiles_per_row];
        let padded_from = if sy * 4 + STEP_ROWS > self.height { 0 } else { self.width / TILE_W };
        let row = TileRow { raster, spans, ty: sy / 2, first, last, padded_from, screen: (self.width, self.height) };
        lanes.draw_tiles(tiles, &row, self.merge);
    }
}

/// `spans` with its rows from `y` outside the triangle's rows `y0..y1`
/// emptied (its window is `x0..x1` by `y0..y1`; the window and the spans
/// passed by value, so that the caller's stay out of memory), which lie within
/// the screen: the padding rows below the screen
/// (in the last tile row only), and the rows beyond a horizontal edge, which
/// the lanes leave out ([`Intercepts::new`]). Other rows outside `y0..y1`
/// are already empty (`raster::lanes`, "Rows outside the triangle").
#[cold]
fn empty_outside_rows((x0, x1): (i32, i32), (y0, y1): (i32, i32), y: u32, mut spans: Spans) -> Spans {
    for r in 0..STEP_ROWS as usize {
        if !(y0..y1).contains(&(y as i32 + r as i32)) {
            (spans.lo[r], spans.hi[r]) = (x1, x0);
        }
    }
    spans
}

/// `spans` with the edges it leaves to the exact scalar rule
/// ([`Spans::exact`]) applied to its eight rows from `y`, row by row, of a
/// triangle whose window's columns are `x0..x1` (rarely any).
#[cold]
fn exact_spans(exact: &Exact, (x0, x1): (i32, i32), y: i32, mut spans: Spans) -> Spans {
    for r in 0..STEP_ROWS as usize {
        for (i, (edge, &band)) in exact.edges.iter().zip(&exact.bands).enumerate() {
            if spans.exact >> i & 1 == 1 {
                let (lo, hi) = edge.span(y + r as i32, x0, x1, band);
                spans.lo[r] = spans.lo[r].max(lo);
                spans.hi[r] = spans.hi[r].min(hi);
            }
        }
    }
    spans
}

/// The widest window, in tile columns, whose tile rows walk all its tiles
/// rather than their spans' reach ([`Band::draw_tile_row`]): on the
/// fill-rate workload (one thread, the AMD EPYC of docs/benchmarks.md)
/// walking windows of up to two tiles so was 4-8 % faster at N = 10 and 25
/// and level at N = 50 and 100; up to three, 6 % slower at N = 50.
const NARROW_TILES: u32 = 2;

/// The bit of a render's item (a triangle index) that marks where the
/// triangle's work is counted: in the first band it is binned to, so that
/// it is counted once however many bands set it up (every item, on one
/// thread).
const COUNTED: u32 = 1 << 31;

/// Triangles per chunk of the parallel binning, and the most a call of
/// small triangles renders on one thread whatever the pool
/// ([`worth_threads`]).
const BIN_CHUNK: usize = 2048;

/// A triangle's set-up in the time of 32x8-pixel tiles drawn: the buffer's
/// cost per triangle over its cost per tile on one thread (76.4 and 4.4 ns
/// on the machine of docs/gpu-models.md), for [`worth_threads`]' estimate.
const SETUP_TILES: usize = 17;

/// The tiles of a small triangle's screen box for [`worth_threads`]: one
/// of a few pixels takes up to four where it straddles tile edges.
const SMALL_TILES: usize = 4;

/// Triangles of a call of at most [`BIN_CHUNK`] that [`worth_threads`]
/// looks at, evenly spaced.
const WORK_SAMPLES: usize = 32;

/// Whether `count` triangles (`clip(i)`) on a `width` x
/// `height` screen are worth the parallel path: more work than
/// [`BIN_CHUNK`] small triangles ([`SMALL_TILES`]), estimated from up to
/// [`WORK_SAMPLES`] of them as [`SETUP_TILES`] plus the tiles of their
/// vertices' screen box (the whole screen's for one reaching behind the
/// near plane). Less work is mostly one object, seldom spread over several
/// bands, and its binning, fork and join cost more than another thread
/// saves (docs/benchmarks.md: with every call of more than 512 triangles
/// parallel, the `moc` method's per-object calls took 40 % more time on the
/// teapots); a few large occluders are worth it.
fn worth_threads(count: usize, clip: impl Fn(usize) -> Option<[Vec4; 3]>, width: u32, height: u32) -> bool {
    if count > BIN_CHUNK {
        return true;
    }
    let (w, h) = (f64::from(width), f64::from(height));
    let tiles = |t: [Vec4; 3]| {
        if !in_front(&t) {
            return width.div_ceil(TILE_W) as usize * height.div_ceil(STEP_ROWS) as usize;
        }
        let s = t.map(|c| to_screen(c.as_dvec4(), w, h).clamp(DVec2::ZERO, DVec2::new(w, h)));
        let (x, y) = (s.map(|p| p.x as usize), s.map(|p| p.y as usize));
        let across = |v: [usize; 3], size: usize| v[0].max(v[1]).max(v[2]) / size - v[0].min(v[1]).min(v[2]) / size + 1;
        across(x, TILE_W as usize) * across(y, STEP_ROWS as usize)
    };
    let step = count.div_ceil(WORK_SAMPLES).max(1);
    let (samples, work) =
        (0..count).step_by(step).fold((0, 0), |(n, w), i| (n + 1, w + SETUP_TILES + clip(i).map_or(0, tiles)));
    work * count > BIN_CHUNK * (SETUP_TILES + SMALL_TILES) * samples
}

/// Bands per thread of the parallel rasterization: several, so that threads
/// even out bands of uneven work, and few, so that few triangles straddle
/// two (each band sets up its own triangles).
const BANDS_PER_THREAD: u32 = 4;

/// The set-up of one render call: turns its triangles into set-up
/// triangles and draws them in a band. On several threads each band runs
/// it on the triangles binned to it ([`Bins`]).
struct SetUpPass<'a, C> {
    /// Triangle `i` in clip space, `None` where it is not drawn.
    clip: &'a C,
    /// The index of item 0's triangle: items index a part of the call.
    offset: usize,
    cull: CullMode,
    width: u32,
    height: u32,
    subpixel_bits: u32,
    avx2: Option<Avx2>,
}

impl<C: Fn(usize) -> Option<[Vec4; 3]>> SetUpPass<'_, C> {
    /// The triangle of `item`, in clip space.
    #[inline]
    fn clip(&self, item: u32) -> Option<[Vec4; 3]> {
        (self.clip)(self.offset + (item & !COUNTED) as usize)
    }

    /// Sets up the triangles `items` (indices, in order, [`COUNTED`] set on
    /// those whose work is counted here) and draws them in `band`: with
    /// AVX2 four at a time ([`Self::four`]); returns the work counted.
    fn run(&self, mut items: impl Iterator<Item = u32>, band: &mut Band<'_>) -> RenderWork {
        let mut work = RenderWork::default();
        if let Some(avx2) = self.avx2 {
            let mut batch = Batch::EMPTY;
            loop {
                let (mut quad, mut taken) = ([0u32; SETUP_LANES], 0);
                while taken < SETUP_LANES {
                    let Some(item) = items.next() else { break };
                    (quad[taken], taken) = (item, taken + 1);
                }
                if taken < SETUP_LANES {
                    for &item in &quad[..taken] {
                        self.one(self.clip(item), item & COUNTED != 0, &mut work, band);
                    }
                    return work;
                }
                self.four(avx2, quad, &mut batch, &mut work, band);
            }
        }
        for item in items {
            self.one(self.clip(item), item & COUNTED != 0, &mut work, band);
        }
        work
    }

    /// The four triangles `quad` set up at once into `batch` where all four
    /// are in the common case of the batched set-up ([`setup`]), each lane
    /// that is not by the scalar set-up ([`Self::one`]), drawn in order.
    #[inline(always)]
    fn four(
        &self,
        avx2: Avx2,
        quad: [u32; SETUP_LANES],
        batch: &mut Batch,
        work: &mut RenderWork,
        band: &mut Band<'_>,
    ) {
        let [a, b, c, d] = quad;
        let Some(tris) = (|| Some([self.clip(a)?, self.clip(b)?, self.clip(c)?, self.clip(d)?]))() else {
            for item in quad {
                self.one(self.clip(item), item & COUNTED != 0, work, band);
            }
            return;
        };
        let counted = quad.iter().enumerate().fold(0, |m, (l, &item)| m | u32::from(item & COUNTED != 0) << l);
        avx2.setup4(&tris, self.cull, self.width, self.height, self.subpixel_bits, batch);
        let (drawn, scalar) = (batch.drawn_lanes(), batch.scalar_lanes());
        work.triangles += u64::from((counted & !scalar).count_ones());
        work.tiles += batch.tiles(drawn & counted);
        if scalar == 0 {
            band.draw_lanes(batch, drawn);
            return;
        }
        // In order: the scalar set-up's triangles between the batch's.
        for (l, c) in tris.into_iter().enumerate() {
            if scalar >> l & 1 == 1 {
                self.one(Some(c), counted >> l & 1 == 1, work, band);
            } else if drawn >> l & 1 == 1 {
                band.draw_lane(batch, l);
            }
        }
    }

    /// Triangle `clip` by the scalar set-up ([`screen_triangles`]), drawn in
    /// `band`, its work added to `work` where `counted`.
    fn one(&self, clip: Option<[Vec4; 3]>, counted: bool, work: &mut RenderWork, band: &mut Band<'_>) {
        let Some(clip) = clip else { return };
        let (width, height, bits) = (self.width, self.height, self.subpixel_bits);
        let triangles = screen_triangles(clip, self.cull, width, height, bits, &mut |tri| {
            if counted {
                work.tiles += tri.raster.tiles();
            }
            band.draw(tri);
        });
        if counted {
            work.triangles += triangles;
        }
    }
}

/// The bands of `rows` pixel rows each, `first..=last` of `0..bands`, that
/// triangle `clip` may touch: where it lies in front of the near plane, those
/// its vertices' rows reach and a pixel more either way (the set-up projects
/// them with the same [`to_screen`], then moves them by
/// half a grid step at most, and draws only the tile rows of pixel centres
/// between them); every band where it reaches behind the near plane
/// (clipping moves its vertices) or has a NaN depth or `w`. A row that is
/// NaN counts as band 0, and `last` is at least `first`, so that every
/// triangle is binned somewhere: the set-up counts even those it does not
/// draw.
#[inline]
fn bands_of(clip: &[Vec4; 3], height: u32, rows: u32, bands: u32) -> (u32, u32) {
    if !in_front(clip) {
        return (0, bands - 1);
    }
    // The screen's width does not move a vertex's row.
    let y = clip.map(|c| to_screen(c.as_dvec4(), 0.0, f64::from(height)).y);
    let (lo, hi) = (y[0].min(y[1]).min(y[2]) - 1.0, y[0].max(y[1]).max(y[2]) + 1.0);
    let (scale, last) = (1.0 / f64::from(rows), f64::from(bands - 1));
    let first = floor_in(lo * scale, 0.0, last);
    (first as u32, floor_in(hi * scale, 0.0, last).max(first) as u32)
}

/// Whether triangle `clip` lies in front of the near plane with a positive
/// `w` at every vertex (false where a depth or `w` is NaN): the set-up then
/// projects its vertices as they are, unclipped.
#[inline]
fn in_front(clip: &[Vec4; 3]) -> bool {
    clip.iter().all(|c| c.z >= 0.0 && c.w > 0.0)
}

/// A chunk of a render's triangles binned to the bands they may touch
/// ([`bands_of`]; a counting sort): a band reads only its own triangles, in
/// order, each marked [`COUNTED`] in its first band.
struct Bins {
    /// Band `b`'s items are `order[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    order: Vec<u32>,
}

impl Bins {
    /// Triangles `range`, binned to `bands` bands by `bands_of(i)` (first and
    /// last band; `None` where triangle `i` is not drawn).
    fn new(range: std::ops::Range<usize>, bands: usize, bands_of: impl Fn(usize) -> Option<(u32, u32)>) -> Self {
        // Triangles not drawn take the empty span (1, 0).
        let spans: Vec<(u32, u32)> = range.clone().map(|i| bands_of(i).unwrap_or((1, 0))).collect();
        let mut starts = vec![0u32; bands + 1];
        for &(first, last) in &spans {
            (first..last + 1).for_each(|b| starts[b as usize + 1] += 1);
        }
        for b in 0..bands {
            starts[b + 1] += starts[b];
        }
        let mut next = starts.clone();
        let mut order = vec![0u32; starts[bands] as usize];
        for (i, &(first, last)) in range.zip(&spans) {
            for b in first..last + 1 {
                order[next[b as usize] as usize] = i as u32 | if b == first { COUNTED } else { 0 };
                next[b as usize] += 1;
            }
        }
        Bins { starts, order }
    }

    /// The items of the triangles binned to band `b`, in order.
    fn in_band(&self, b: usize) -> &[u32] {
        &self.order[self.starts[b] as usize..self.starts[b + 1] as usize]
    }
}

impl MaskedBuffer {
    /// Renders indexed occluder triangles, `model_to_clip` taking `positions` to
    /// clip space (wgpu conventions). Vertices are snapped to the sub-pixel
    /// grid of [`set_subpixel_bits`](Self::set_subpixel_bits) (`crate::project`,
    /// "Coverage"); triangles crossing the near plane are clipped; index
    /// triples with an out-of-range index, NaN vertices and zero-area
    /// triangles are skipped. Cost: per triangle, its pixel rows and the
    /// subtiles its rows touch. Run inside a rayon pool of several threads,
    /// large sets are binned to bands of rows in parallel, then set up and
    /// rasterized in parallel bands (a triangle touching two bands is set up
    /// in both); the buffer is the same whatever the threads. Returns the
    /// work done, for callers that account for it (a simulated clock).
    pub fn render_triangles(
        &mut self,
        positions: &[Vec3],
        indices: &[u32],
        model_to_clip: Mat4,
        cull: CullMode,
    ) -> RenderWork {
        let clip = |i: usize| {
            let tri = &indices[3 * i..3 * i + 3];
            let v = [tri[0], tri[1], tri[2]].map(|k| positions.get(k as usize).copied());
            let [Some(a), Some(b), Some(c)] = v else { return None };
            Some([a, b, c].map(|p| model_to_clip * p.extend(1.0)))
        };
        self.render(indices.len() / 3, clip, cull)
    }

    /// Renders occluder triangles already in clip space (wgpu conventions), as
    /// [`render_triangles`](Self::render_triangles) does after its transform: for
    /// callers that transform their own vertices, and the fill-rate benchmark.
    pub fn render_clip_triangles(&mut self, triangles: &[[Vec4; 3]], cull: CullMode) -> RenderWork {
        self.render(triangles.len(), |i| Some(triangles[i]), cull)
    }

    /// Renders triangles `0..count`, `clip(i)` giving triangle `i` in clip
    /// space, in parts of at most [`COUNTED`] triangles (an item carries its
    /// index in the bits below it).
    fn render(&mut self, count: usize, clip: impl Fn(usize) -> Option<[Vec4; 3]> + Sync, cull: CullMode) -> RenderWork {
        let mut work = RenderWork::default();
        for offset in (0..count).step_by(COUNTED as usize) {
            work += self.render_part(offset, (count - offset).min(COUNTED as usize), &clip, cull);
        }
        work
    }

    /// Renders triangles `offset..offset + count`: one after the other on one
    /// thread, or, when the current rayon pool has several threads, binned to
    /// bands of tile rows in parallel chunks ([`Bins`]), then set up and drawn
    /// band by band in parallel.
    fn render_part(
        &mut self,
        offset: usize,
        count: usize,
        clip: &(impl Fn(usize) -> Option<[Vec4; 3]> + Sync),
        cull: CullMode,
    ) -> RenderWork {
        let (width, height, subpixel_bits) = (self.width, self.height, self.subpixel_bits);
        let pass = SetUpPass { clip, offset, cull, width, height, subpixel_bits, avx2: Avx2::detect() };
        let threads = rayon::current_num_threads();
        if threads < 2 || !worth_threads(count, |i| clip(offset + i), width, height) {
            return pass.run((0..count as u32).map(|i| i | COUNTED), &mut self.whole());
        }
        // Bands of whole tile rows (two subtile rows).
        let tile_rows = self.rows / 2;
        let band_rows = 2 * tile_rows.div_ceil(BANDS_PER_THREAD * threads as u32);
        let bands = self.rows.div_ceil(band_rows);
        let bins: Vec<Bins> = (0..count.div_ceil(BIN_CHUNK))
            .into_par_iter()
            .map(|c| {
                let range = c * BIN_CHUNK..((c + 1) * BIN_CHUNK).min(count);
                let bands_of = |i: usize| clip(offset + i).map(|t| bands_of(&t, height, band_rows * 4, bands));
                Bins::new(range, bands as usize, bands_of)
            })
            .collect();
        let (cols, merge, avx2) = (self.cols, self.merge, pass.avx2);
        self.tiles
            .par_chunks_mut((band_rows * cols) as usize / LANES)
            .enumerate()
            .map(|(b, tiles)| {
                let first = b as u32 * band_rows;
                let end = first + (tiles.len() * LANES) as u32 / cols;
                let mut band = Band { tiles, first, end, cols, width, height, merge, avx2 };
                pass.run(bins.iter().flat_map(|bin| bin.in_band(b).iter().copied()), &mut band)
            })
            .reduce(RenderWork::default, |mut a, b| {
                a += b;
                a
            })
    }

    /// The whole buffer as one band.
    fn whole(&mut self) -> Band<'_> {
        self.whole_with(Avx2::detect())
    }

    /// The whole buffer as one band, with the AVX2 lanes or the portable ones.
    fn whole_with(&mut self, avx2: Option<Avx2>) -> Band<'_> {
        Band {
            tiles: &mut self.tiles,
            first: 0,
            end: self.rows,
            cols: self.cols,
            width: self.width,
            height: self.height,
            merge: self.merge,
            avx2,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::buffer::{outside_mask, Subtile};

    /// The masks by definition: every pixel centre of the subtile tested against
    /// every edge; the depth bounds by [`DepthPlane::subtile_bound`] (whose own
    /// test checks them against the plane).
    fn reference_draw(buffer: &mut MaskedBuffer, tri: &ScreenTriangle) {
        let mode = buffer.merge;
        for sy in 0..buffer.rows {
            for sx in 0..buffer.cols {
                let mut cover = 0;
                for i in 0..32u32 {
                    let (x, y) = (sx * 8 + i % 8, sy * 4 + i / 8);
                    let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                    if x < buffer.width && y < buffer.height && tri.exact.edges.iter().all(|e| e.covers(px, py)) {
                        cover |= 1 << i;
                    }
                }
                if cover != 0 {
                    let anchor = tri.raster.tile_columns().0;
                    let far = tri.raster.plane.subtile_bound(anchor, sx / 4, f64::from(sy * 4), (sx % 4) as usize);
                    let outside = outside_mask(buffer.width, buffer.height, sx, sy);
                    let (t, l) = (buffer.tile_index(sx, sy), Tile::lane(sx, sy));
                    let mut s = buffer.tiles[t].get(l);
                    s.merge(cover | outside, far, mode);
                    buffer.tiles[t].set(l, s);
                }
            }
        }
    }

    struct Lcg(u64);
    impl Lcg {
        fn unit(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Every subtile of the buffer, padding included, tile by tile.
    fn subtiles(b: &MaskedBuffer) -> impl Iterator<Item = Subtile> + '_ {
        b.tiles.iter().flat_map(|t| (0..LANES).map(|l| t.get(l)))
    }

    fn assert_same(a: &MaskedBuffer, b: &MaskedBuffer, what: &str) {
        for (i, (s, r)) in subtiles(a).zip(subtiles(b)).enumerate() {
            assert!(
                s.mask == r.mask && s.working.to_bits() == r.working.to_bits() && s.reference == r.reference,
                "{what}: subtile {i}: {s:?} vs {r:?}"
            );
        }
    }

    #[test]
    fn spans_give_the_masks_of_the_per_pixel_definition() {
        let mut rng = Lcg(3);
        let (w, h) = (83u32, 45u32);
        let mut covered = 0;
        for round in 0..400 {
            let mut fast = MaskedBuffer::new(w, h).unwrap();
            let mut slow = fast.clone();
            let mut portable = fast.clone();
            for _ in 0..1 + round % 6 {
                let size = [2.0, 15.0, 120.0][round % 3];
                let c = DVec3::new(rng.unit() * 100.0 - 10.0, rng.unit() * 60.0 - 8.0, 0.0);
                let mut t = [0; 3].map(|_| c + DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, 0.0) * size);
                for p in &mut t {
                    p.z = rng.unit();
                    // Snapped to half pixels in some rounds: centres on edges, shared
                    // and horizontal edges.
                    if round % 4 == 0 {
                        (p.x, p.y) = ((p.x * 2.0).round() / 2.0, (p.y * 2.0).round() / 2.0);
                    }
                }
                if round % 5 == 0 {
                    t[1].y = t[0].y;
                }
                let tris = [t, [t[0], t[2], t[1]]].into_iter();
                for tri in tris.filter_map(|t| ScreenTriangle::new(t, CullMode::None, w, h, Tolerance::NONE)) {
                    fast.whole().draw(&tri);
                    portable.whole_with(None).draw(&tri);
                    reference_draw(&mut slow, &tri);
                }
            }
            assert_same(&portable, &slow, &format!("portable, round {round}"));
            covered += subtiles(&fast).filter(|s| s.mask != 0 || s.reference < 1.0).count();
            assert_same(&fast, &slow, &format!("round {round}"));
        }
        assert!(covered > 2000, "{covered}");
    }

    #[test]
    fn subtile_bounds_are_never_nearer_than_the_plane_and_close_to_it() {
        let mut rng = Lcg(17);
        let mut capped = 0;
        let widths = [1920u32, 7, 640, 4000, 33];
        for i in 0..200_000 {
            // Planes from flat to steep, depths around 0..1, some far out.
            let scale = [1e-9, 1e-5, 1e-3, 0.1, 1.0][i % 5];
            let (zmax, width) = (rng.unit() * 2.0, widths[i % widths.len()]);
            let plane = DepthPlane::from_terms(
                (rng.unit() - 0.5) * scale,
                (rng.unit() - 0.5) * scale,
                rng.unit() * [1.0, 1e-6, 10.0][i % 3],
                zmax,
                width,
            );
            // A tile of the screen and an anchor at or left of it.
            let tiles = width.div_ceil(TILE_W);
            let tx = ((rng.unit() * f64::from(tiles)) as u32).min(tiles - 1);
            let anchor = [0, tx, (rng.unit() * f64::from(tx + 1)) as u32][i % 3].min(tx);
            let (sy, l) = ((rng.unit() * 300.0) as u32, i % 4);
            let (bx, by) = (f64::from(tx * TILE_W + 8 * l as u32), f64::from(sy * 4));
            let corners = [(0.0, 0.0), (8.0, 0.0), (0.0, 4.0), (8.0, 4.0)];
            let exact = corners
                .iter()
                .map(|&(dx, dy)| plane.zx * (bx + dx) + plane.zy * (by + dy) + plane.z0)
                .fold(f64::MIN, f64::max)
                .min(zmax);
            let bound = f64::from(plane.subtile_bound(anchor, tx, by, l));
            assert!(bound >= exact, "{plane:?} tile {tx} from {anchor}, lane {l}: {bound} < {exact}");
            // Looser than the plane by a few f32 units of its terms at most: the
            // base's and the sum's nudges (`2^-22` each), and the step's
            // rounding (`2^-22` and `1e-12`, the latter times the `m` steps)
            // and cut to `24 - z` significant bits (less than a unit of its
            // last, `2^(z - 23)` of it), of the x term's rise from the anchor.
            let ax = f64::from(anchor * TILE_W);
            let terms = (plane.zx * (ax + 8.0)).abs() + (plane.zy * (by + 4.0)).abs() + plane.z0.abs();
            let rise = (plane.zx * (bx + 8.0 - ax)).abs();
            let cut = 2f64.powi(step_zero_bits(width) as i32 - 23) + 2f64.powi(-22);
            let m = f64::from(4 * (tx - anchor)) + l as f64;
            let slack = terms * 2e-6 + rise * cut + m * 2e-12 + 1e-11;
            assert!(bound - exact <= slack, "{plane:?} tile {tx} from {anchor}, lane {l}: {bound} vs {exact}");
            capped += usize::from(exact == zmax);
        }
        assert!(capped > 1000, "{capped}");
    }

    #[test]
    fn the_depth_step_leaves_its_products_by_every_column_offset_exact() {
        for (width, zero) in [(1, 2), (32, 2), (33, 3), (1920, 8), (2048, 8), (2049, 9)] {
            assert_eq!(step_zero_bits(width), zero, "width {width}");
            let steps = 4 * width.div_ceil(TILE_W);
            let plane = DepthPlane::from_terms(0.123_456_789, 0.0, 0.5, 1.0, width);
            let step = plane.lane_step();
            assert!(f64::from(step) >= 8.0 * 0.123_456_789);
            for m in 0..steps {
                assert_eq!(f64::from(step * m as f32), f64::from(step) * f64::from(m), "width {width}, {m} steps");
            }
        }
    }

    #[test]
    fn a_few_large_triangles_are_worth_threads_and_many_small_ones_only_beyond_a_chunk() {
        let (w, h) = (640u32, 480u32);
        // Right triangles of `size` NDC units with their corner at `x`, `y`.
        let at = |x: f32, y: f32, size: f32| {
            [Vec4::new(x, y, 0.5, 1.0), Vec4::new(x + size, y, 0.5, 1.0), Vec4::new(x, y + size, 0.5, 1.0)]
        };
        // Screen boxes of about 1,080 tiles each: 60 are more work than
        // 2,048 small triangles, 30 less.
        let walls: Vec<_> = (0..60).map(|i| at(-1.0, -1.0 + i as f32 * 0.01, 1.9)).collect();
        assert!(worth_threads(walls.len(), |i| Some(walls[i]), w, h));
        assert!(!worth_threads(30, |i| Some(walls[i]), w, h));
        let specks: Vec<_> = (0..BIN_CHUNK + 1).map(|i| at(-0.9 + (i % 97) as f32 * 0.018, 0.0, 0.002)).collect();
        assert!(!worth_threads(BIN_CHUNK, |i| Some(specks[i]), w, h));
        assert!(worth_threads(BIN_CHUNK + 1, |i| Some(specks[i]), w, h));
        // Behind the near plane: the whole screen, as the bins take it.
        let behind: Vec<_> = walls.iter().map(|t| t.map(|v| Vec4::new(v.x * 0.01, v.y * 0.01, -0.5, 1.0))).collect();
        assert!(worth_threads(behind.len(), |i| Some(behind[i]), w, h));
        assert!(!worth_threads(0, |_| None, w, h));
    }

    #[test]
    fn threads_give_the_buffer_and_work_of_one_thread() {
        let (w, h) = (300u32, 200u32);
        let mut rng = Lcg(9);
        let tris: Vec<[Vec4; 3]> = (0..3 * BIN_CHUNK + 17)
            .map(|i| {
                let c = Vec4::new(rng.unit() as f32 * 2.2 - 1.1, rng.unit() as f32 * 2.2 - 1.1, 0.0, 1.0);
                let mut t = [0; 3].map(|_| {
                    let d = Vec4::new(rng.unit() as f32 - 0.5, rng.unit() as f32 - 0.5, 0.0, 0.0) * 0.3;
                    // The same point at another `w`: the bins divide as the set-up does.
                    (c + d + Vec4::new(0.0, 0.0, rng.unit() as f32 * 1.1 - 0.1, 0.0)) * (0.5 + rng.unit() as f32 * 2.0)
                });
                // Now and then a vertex far above or below the screen, or a NaN.
                match i % 97 {
                    0 => t[1].y *= 100.0,
                    1 => t[2].y = f32::NAN,
                    _ => {}
                }
                t
            })
            .collect();
        let run = |threads: usize, mode: MergeMode| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut buffer = MaskedBuffer::new(w, h).unwrap();
            buffer.merge = mode;
            let work = pool.install(|| buffer.render_clip_triangles(&tris, CullMode::Back));
            (buffer, work)
        };
        for mode in [MergeMode::LayerMerge, MergeMode::QuickMask] {
            let (one, work) = run(1, mode);
            assert!(subtiles(&one).filter(|s| s.reference < 1.0).count() > 500);
            // Clipped triangles are counted as the fans they become.
            assert!(work.triangles > tris.len() as u64 && work.tiles > work.triangles, "{work:?}");
            for threads in [2, 3] {
                let (buffer, threads_work) = run(threads, mode);
                assert_same(&buffer, &one, &format!("{threads} threads, {mode:?}"));
                assert_eq!(threads_work, work, "{threads} threads, {mode:?}");
            }
        }
    }
}
