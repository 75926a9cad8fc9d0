//! Set-up triangles in the form the tiles read ([`RasterTri`]), and their exact row
//! spans by incremental edge functions ([`walk`]).
//!
//! A pixel is covered when all three edge functions are `>= 0` at its centre. Along a
//! row an edge function is `g + a * k` at the `k`-th pixel (`a` its `step_x`), so each
//! edge bounds the covered pixels on one side: from the left where `a > 0`
//! (`k >= ceil(-g / a)`), from the right where `a < 0` (`k <= floor(g / -a)`), and
//! where `a == 0` it covers whole rows, a range of them. From one row to the next `g`
//! grows by the edge's `step_y`, and a bound moves by `floor(step_y / |a|)` plus a
//! carry of at most one pixel, tracked exactly with the remainder (a digital
//! differential analyser): two divisions per edge and window, none per row. The
//! result is the same pixel set as testing every pixel's edge functions.
//!
//! Both steps are multiples of `2^SUBPIXEL_BITS` (`a = -dy * 256`, `step_y =
//! dx * 256` for the edge's fixed-point vector `(dx, dy)`), and for positive `c`,
//! `floor(g / (256 * c)) == floor(floor(g / 256) / c)`: edges are used reduced to
//! `(g >> 8, -dy, dx)`, whose remainders fit a `u32`.

use super::setup::{edges_at, Fixed, RowPlane, SetupTri, SUBPIXEL_BITS};

/// A set-up triangle in the form the tiles read: the rows it may cover, its vertices
/// (the edge functions are set up from them where a window starts) and depth plane.
/// One cache line, the vertices first (the AVX2 rasterizer loads them as one
/// vector).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct RasterTri {
    /// The vertices, in the order of positive area.
    pub verts: [Fixed; 3],
    /// Index of the command the triangle belongs to.
    pub cmd: u32,
    /// Leftmost pixel column whose centre may be covered (the bounding box's), the
    /// column origin of the depth plane.
    pub x0: i32,
    /// Rightmost pixel column (inclusive).
    pub x1: i32,
    /// First row that may be covered: the bounding box's top, or lower where a
    /// horizontal edge excludes rows.
    pub y0: i32,
    /// Last row that may be covered (inclusive).
    pub y1: i32,
    /// The bounding box's top row, the row origin of the depth plane.
    pub plane_y: i32,
    /// Depth at the centre of pixel `(x0, plane_y)`.
    pub z_origin: f32,
    /// Depth change per pixel to the right.
    pub z_dx: f32,
    /// Depth change per pixel down.
    pub z_dy: f32,
}

const _: () = assert!(std::mem::size_of::<RasterTri>() == 64 && std::mem::offset_of!(RasterTri, verts) == 0);

impl RasterTri {
    /// A value to fill memory with before the triangles are copied in.
    pub const PLACEHOLDER: Self = Self {
        verts: [[0; 2]; 3],
        cmd: 0,
        x0: 0,
        x1: 0,
        y0: 0,
        y1: 0,
        plane_y: 0,
        z_origin: 0.0,
        z_dx: 0.0,
        z_dy: 0.0,
    };

    /// The raster form of `t`, or `None` when a horizontal edge excludes every row.
    pub fn new(t: &SetupTri) -> Option<Self> {
        Self {
            verts: t.verts,
            cmd: t.cmd,
            x0: t.x0,
            x1: t.x1,
            y0: t.y0,
            y1: t.y1,
            plane_y: t.y0,
            z_origin: t.z_origin,
            z_dx: t.z_dx,
            z_dy: t.z_dy,
        }
        .covered_rows()
    }

    /// `self`, whose rows are its bounding box's (`y0 == plane_y`), with the rows
    /// that a horizontal edge excludes removed; `None` when it excludes every row,
    /// or when the rows left hold at most 2 x 2 pixel centres and the triangle
    /// covers none of them. Most triangles of a large scene are that small, and
    /// most of those cover no centre; dropped here, they are neither binned nor
    /// rasterized.
    #[inline(always)]
    pub fn covered_rows(mut self) -> Option<Self> {
        let (mut y0, mut y1) = (i64::from(self.y0), i64::from(self.y1));
        // A horizontal edge (two vertices on one row) covers the rows k (from the
        // box's top) where g + dx * k >= 0.
        let [[_, ya], [_, yb], [_, yc]] = self.verts;
        if ya == yb || yb == yc || yc == ya {
            for (g, _, dx) in self.edges_at(self.x0, self.plane_y).into_iter().filter(|e| e.1 == 0) {
                match dx.signum() {
                    1 => y0 = y0.max(i64::from(self.plane_y) - g.div_euclid(dx)),
                    -1 => y1 = y1.min(i64::from(self.plane_y) + g.div_euclid(-dx)),
                    _ if g < 0 => return None,
                    _ => {}
                }
            }
        }
        (self.y0, self.y1) = (y0 as i32, y1 as i32);
        if y0 > y1 {
            return None;
        }
        if self.x1 - self.x0 < 2 && y1 - y0 < 2 {
            let [(g0, a0, b0), (g1, a1, b1), (g2, a2, b2)] = self.edges_at(self.x0, self.plane_y);
            let first = y0 - i64::from(self.plane_y);
            let mut covers = false;
            for j in first..=first + (y1 - y0) {
                for i in 0..=i64::from(self.x1 - self.x0) {
                    covers |= (g0 + a0 * i + b0 * j >= 0) & (g1 + a1 * i + b1 * j >= 0) & (g2 + a2 * i + b2 * j >= 0);
                }
            }
            if !covers {
                return None;
            }
        }
        Some(self)
    }

    /// The pixel centres the triangle covers in `window` (columns `x0..=x1`,
    /// rows `y0..=y1`, within its rows and columns), each centre's edge
    /// functions tested as [`Self::covered_rows`] tests them, stepped along
    /// the rows: for small windows (the walk and the tiles count large ones
    /// faster).
    #[inline(always)]
    pub fn covered_in(&self, [x0, x1, y0, y1]: [i32; 4]) -> u64 {
        let [(mut g0, a0, b0), (mut g1, a1, b1), (mut g2, a2, b2)] = self.edges_at(x0, y0);
        let mut covered = 0;
        for _ in y0..=y1 {
            let (mut e0, mut e1, mut e2) = (g0, g1, g2);
            for _ in x0..=x1 {
                covered += u64::from((e0 >= 0) & (e1 >= 0) & (e2 >= 0));
                (e0, e1, e2) = (e0 + a0, e1 + a1, e2 + a2);
            }
            (g0, g1, g2) = (g0 + b0, g1 + b1, g2 + b2);
        }
        covered
    }

    /// The pixel centres the triangle covers: its fragments, as every
    /// rasterizer path counts them. A triangle whose rows and columns hold
    /// one centre covers it ([`Self::covered_rows`] keeps no triangle of at
    /// most 2 x 2 centres that covers none); up to 64 centres (`STEPPED`) are
    /// tested one by one ([`Self::covered_in`]), more are walked by spans
    /// ([`walk`]) window by window.
    pub fn covered(&self) -> u64 {
        const STEPPED: i32 = 64;
        let [x0, x1, y0, y1] = [self.x0, self.x1, self.y0, self.y1];
        if x0 == x1 && y0 == y1 {
            return 1;
        }
        if (x1 - x0 + 1) * (y1 - y0 + 1) <= STEPPED {
            return self.covered_in([x0, x1, y0, y1]);
        }
        let mut spans = [Span::default(); MAX_WINDOW];
        let mut covered = 0;
        for x in (x0..=x1).step_by(MAX_WINDOW) {
            let (end, mut y) = ((x + MAX_WINDOW as i32 - 1).min(x1), y0);
            while y <= y1 {
                let rows = ((y1 - y + 1) as usize).min(MAX_WINDOW);
                covered += walk(self, x, end, y, &mut spans[..rows]) as u64;
                y += rows as i32;
            }
        }
        covered
    }

    /// The reduced edge functions `(g, a, b)` set up at pixel `(x, y)`: the pixel `i`
    /// columns right and `j` rows below is covered when `g + a * i + b * j >= 0` for
    /// every edge.
    #[inline(always)]
    pub fn edges_at(&self, x: i32, y: i32) -> [(i64, i64, i64); 3] {
        reduce(edges_at(&self.verts, x, y))
    }

    /// The depth plane along the pixel row `y` (absolute).
    #[inline(always)]
    pub fn row_plane(&self, y: i32) -> RowPlane {
        RowPlane::of(self.z_origin, self.z_dx, self.z_dy, y - self.plane_y)
    }
}

/// Edge functions reduced by `2^SUBPIXEL_BITS` (see the module documentation).
#[inline(always)]
fn reduce(edges: [super::setup::Edge; 3]) -> [(i64, i64, i64); 3] {
    edges.map(|e| (e.origin >> SUBPIXEL_BITS, e.step_x >> SUBPIXEL_BITS, e.step_y >> SUBPIXEL_BITS))
}

/// `(floor(n / d), n mod d)` for `d > 0` and `|n| < 2^53`: an `f64` estimate (two
/// roundings away from the quotient) corrected to the exact result, which costs less
/// than an `i64` division.
#[inline(always)]
pub(super) fn floor_divmod(n: i64, d: u32) -> (i64, u32) {
    let d64 = i64::from(d);
    let mut q = (n as f64 / f64::from(d)) as i64;
    let mut r = n - q * d64;
    while r < 0 {
        q -= 1;
        r += d64;
    }
    while r >= d64 {
        q += 1;
        r -= d64;
    }
    (q, r as u32)
}

/// One edge's bound on the covered pixels of the current row, stepped row by row.
#[derive(Clone, Copy, Debug)]
struct Bound {
    /// The bound as a pixel offset from the first column of the window walked: the
    /// first covered pixel of a left bound, the last of a right bound.
    k: i64,
    /// The reduced edge function at pixel `k`, `g + a * k`: in `[0, c)`.
    r: u32,
    /// `|a|` (the edge's `|dy|`), at most `2^24`.
    c: u32,
    /// `k`'s change per row before the carry: `floor(b / c)`, negated for a left
    /// bound.
    dk: i32,
    /// `b mod c`: the remainder's growth per row.
    m: u32,
}

impl Bound {
    /// The bound of the reduced edge `(g, a, b)` (`a != 0`) at the walk's first pixel;
    /// a left bound where `a > 0`.
    fn new((g, a, b): (i64, i64, i64)) -> Self {
        // |a|, |b| <= 2^24 (vertices lie within COORD_LIMIT).
        let c = a.unsigned_abs() as u32;
        let ((floor, r), (dk, m)) = (floor_divmod(g, c), floor_divmod(b, c));
        // Left: k = ceil(-g / a) = -floor(g / c); right: k = floor(g / -a).
        let (k, dk) = if a > 0 { (-floor, -dk) } else { (floor, dk) };
        Self { k, r, c, dk: dk as i32, m }
    }

    /// A left bound that never moves and never binds.
    const FIXED: Self = Self { k: i64::MIN / 2, r: 0, c: 1, dk: 0, m: 0 };

    /// Moves the bound to the next row; `dir` is where `k` moves on a carry: -1 for a
    /// left bound, +1 for a right one.
    #[inline(always)]
    fn step(&mut self, dir: i64) {
        // r, m < c <= 2^24: no overflow.
        let r = self.r + self.m;
        let carry = r >= self.c;
        self.r = if carry { r - self.c } else { r };
        self.k += i64::from(self.dk) + if carry { dir } else { 0 };
    }
}

/// The covered pixels of one row of a window: columns `lo..end` from the window's
/// first column; empty when `lo >= end`.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Span {
    /// First covered column.
    pub lo: u8,
    /// One past the last covered column.
    pub end: u8,
}

/// Widest window walked: a tile.
pub(super) const MAX_WINDOW: usize = 64;

/// Writes the spans of the columns `x0..=x1` (at most [`MAX_WINDOW`]) of `t`'s rows
/// `y..y + out.len()` (within `t.y0..=t.y1`) to `out`, and returns how many pixels
/// they cover.
pub(super) fn walk(t: &RasterTri, x0: i32, x1: i32, y: i32, out: &mut [Span]) -> usize {
    debug_assert!(x1 - x0 < MAX_WINDOW as i32);
    // A left bound, a right bound and a third of either side: a triangle's edges' dy
    // sum to zero, so at least one is on each side. A horizontal edge is left out (the
    // rows are already limited to those it covers) and a fixed bound takes its place.
    let (mut left, mut right, mut third, mut third_dir) = (None, None, Bound::FIXED, -1);
    for e in t.edges_at(x0, y).into_iter().filter(|e| e.1 != 0) {
        let side = if e.1 > 0 { &mut left } else { &mut right };
        if side.is_none() {
            *side = Some(Bound::new(e));
        } else {
            (third, third_dir) = (Bound::new(e), if e.1 > 0 { -1 } else { 1 });
        }
    }
    let (Some(mut l), Some(mut r)) = (left, right) else {
        unreachable!("a triangle has an edge on each side");
    };
    // Clamping to the window keeps every value within a u8.
    let end_max = i64::from(x1 - x0) + 1;
    let mut covered = 0;
    for span in out {
        let (mut lo, mut end) = (l.k.max(0), (r.k + 1).min(end_max));
        if third_dir < 0 {
            lo = lo.max(third.k);
        } else {
            end = end.min(third.k + 1);
        }
        let lo = lo.min(end_max);
        let end = end.max(lo);
        *span = Span { lo: lo as u8, end: end as u8 };
        covered += (end - lo) as usize;
        l.step(-1);
        r.step(1);
        third.step(third_dir);
    }
    covered
}
