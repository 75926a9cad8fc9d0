//! The rasterizer's two inner steps in lanes, after HPG 2016 section 4
//! (coverage from the edges' x-intercepts per scanline, then shifts, no
//! per-pixel work):
//!
//! - [`edge_spans`]: each edge's x-intercept on [`STEP_ROWS`] pixel rows (two
//!   subtile rows) at once, one `f32` lane a row ("Intercepts in `f32`"
//!   below), giving each row's covered pixels `lo..hi`;
//! - [`tile_lanes`]: from a tile row's spans, the coverage masks and depth
//!   bounds of the eight subtiles of a 32x8-pixel tile (four across, two
//!   down, MOC's tile) at once.
//!
//! Each has this portable version and an AVX2 one ([`super::avx2`]) that does the
//! same `f32`, `f64` and integer operations in the same order (never a fused
//! multiply-add), so both give bit-identical results; the tests check it on
//! random triangles.
//!
//! # Exactness
//! An edge's intercept `t = slope py + offset + 0.5` on row `y` (`py = y +
//! 0.5`: the edge crosses the row at `x = t - 0.5`, so pixel `x`'s centre `x +
//! 0.5` lies on its right exactly when `x >= t`) decides its covered pixels
//! without testing them when the computed `t`'s distance to the nearest whole
//! number exceeds a proven error band: then the pixels up to `floor(t) - 1` lie
//! on one side and those from `floor(t)` on the other, exactly as
//! [`Edge::covers`](super::Edge) decides them. The floor itself is then the end
//! of the row's span the edge sets. When any of the eight rows is within the
//! band (rare), the edge is reported in [`Spans::exact`] and the caller
//! decides its rows with the scalar, pixel-exact [`Edge::span`](super::Edge).
//! A horizontal edge covers whole rows on one side of it: the set-up keeps
//! only those rows in the triangle's window, and the lanes leave the edge out
//! ([`Intercepts::new`]). A row's span is the intersection of
//! its edges' half-lines with the triangle's pixel window, so the order in which
//! edges are applied does not matter. Masks are therefore exactly the per-pixel
//! definition.
//!
//! # Rows outside the triangle
//! A tile row may hold pixel rows of the screen above or below the
//! triangle's rows `y0..y1` (the pixel centres within its vertices' `y`
//! range). They are not emptied by a test of their own: a pixel centre there
//! lies outside the closed triangle, so one of its edge functions is negative
//! there (exactly, in `f64`), and the edges' half-lines, decided exactly as
//! above, leave the row empty. The bands hold on every row of the screen that
//! a draw's steps reach, inside the triangle or not. Where the edge that
//! leaves a row out is horizontal, which the lanes leave out, the traversal
//! empties the rows outside `y0..y1` itself (`Intercepts::flat`); it also
//! empties the padding rows below the screen, where the band is not proven
//! and pixels are not the triangle's.
//!
//! # Intercepts in `f32`
//! At set-up ([`Intercepts::new`], or `raster::setup` for four triangles at
//! once), each edge's intercept on the top pixel row of the triangle's first
//! tile row, `y_f`, is evaluated in `f64` as above, less the
//! window's left column `x0` (`u`, then rounded to `f32`: `base`), and its
//! slope is rounded to `f32`. Row `y_f + r` takes `t' = base + slope r` in
//! `f32` (`r` a small whole number, exact), and the span's end is
//! `floor(t') + x0`. Against the exact intercept `T` of the edge's `f64`
//! coefficients, `t' + x0 - T(y_f + r)` is the `f64` evaluation's error on row
//! `y_f` (which the edge's `f64` band, [`Edge::band`](super::Edge), allows for,
//! with the edge function's rounding), plus `u`'s rounding in `f64` and the
//! `f64` slope's error times `r` (each `2^-53` of `|u|` or `|slope| r`), plus
//! four `f32` roundings of at most `2^-24` each: of `base` (of `|u|`), of the
//! slope (times `r`: of `|slope| r`), of the product (of `|slope| r (1 +
//! 2^-24)`) and of the sum (of `|t'|`, at most `|u| + |slope| r` to first
//! order). Together less than `2^-24 (2 |u| + 3 |slope| R) (1 + 2^-20)` over
//! the `R` rows of the triangle's tile rows. The band used is the `f64` band
//! plus `2^-22 (2 |u| + 3 |slope| R + 1)`, rounded up to `f32`: four times
//! that, with `2^-22` more for the
//! rounding of the fraction `t' - floor(t')` and of `1 - fraction` (under
//! `2^-24` each, the fraction being below 1). Where `t'` is farther than that
//! band from every whole number, so is the exact intercept from every pixel
//! boundary by more than the `f64` edge function's rounding, and the floor
//! decides as [`Edge::covers`](super::Edge) does. A non-finite `u`, slope or
//! band (horizontal edges) fails the band test on every row. A test checks the
//! `f32` error against its allowance on random triangles on screens up to
//! 30,000 rows tall.
//!
//! Intercepts beyond the window are clamped to `-1.5 ..= x1 - x0 + 3.5`
//! (exact in `f32`: the screen is under `2^15` pixels wide): half a pixel from
//! a whole number, so a clamped intercept passes the band test wherever the
//! band is under half a pixel, and the window's pixels keep their side.

use super::{round_far, Exact, Raster};
use crate::buffer::{outside_mask, MergeMode, Tile};

/// Subtiles handled by one [`tile_lanes`] call: a tile's.
pub(crate) const LANES: usize = 8;

/// Pixel rows whose spans one [`edge_spans`] call gives: a tile row, two
/// subtile rows.
pub(crate) const STEP_ROWS: u32 = 8;

/// Pixels across a tile: four subtiles, as in MOC (32x8 pixels, eight
/// subtiles in lanes).
pub(crate) const TILE_W: u32 = 32;

/// The covered pixels `lo[r]..hi[r]` of the eight pixel rows of a tile row
/// (two subtile rows; `lo >= hi`: none), from the edges the lanes decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(32))]
pub(crate) struct Spans {
    pub lo: [i32; STEP_ROWS as usize],
    pub hi: [i32; STEP_ROWS as usize],
    /// Bit `i` set: edge `i` is not yet applied and must be decided row by row
    /// with the exact scalar rule.
    pub exact: u8,
}

impl Spans {
    /// Pixels `left..right` that hold every row's covered pixels, `None` where
    /// that is empty (then so is every row): the smallest `lo` to the largest
    /// `hi`. An empty row may widen it (its `lo` and `hi` are ends of the
    /// triangle's window or edge bounds, within `0..=width`); the tiles it
    /// adds have no cover and are left as they are.
    pub(crate) fn reach(&self) -> Option<(i32, i32)> {
        let left = self.lo.iter().fold(i32::MAX, |m, &v| m.min(v));
        let right = self.hi.iter().fold(i32::MIN, |m, &v| m.max(v));
        (left < right).then_some((left, right))
    }
}

/// Relative allowance of the `f32` intercepts' error ("Intercepts in `f32`"
/// above): `2^-22`, four times the error bound's `2^-24 (1 + 2^-20)`.
pub(crate) const F32_SCALE: f64 = 1.0 / (1u32 << 22) as f64;

/// The lower end of the clamped intercepts, relative to the window's left
/// column.
pub(crate) const T_MIN: f32 = -1.5;

/// Each edge's intercepts in `f32` for one draw of a triangle ("Intercepts in
/// `f32`" above), relative to the window's left column `x0`: row `r` of the
/// draw (from its first pixel row) has intercept `base + slope r`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Intercepts {
    /// Per edge, its intercept on row 0 less `x0`, rounded to `f32`.
    pub base: [f32; 3],
    /// Per edge, its slope `dx/dy` rounded to `f32`.
    pub slope: [f32; 3],
    /// The `f32` band: a fraction farther than this from 0 and 1 decides.
    pub band: [f32; 3],
    /// All ones where the edge bounds a row's span on the left (inside to
    /// its right, `a > 0`: its floor is the span's `lo`), else zero.
    pub right: [i32; 3],
    /// The upper end of the clamped intercepts, `x1 - x0 + 3.5`.
    pub t_max: f32,
    /// Whether an edge is horizontal: left out of the lanes (its intercept
    /// `t_max` on every row, which bounds nothing), its rows kept by the
    /// window, and the rows beyond it emptied by the traversal.
    pub flat: bool,
}

impl Intercepts {
    /// Placeholder of a triangle under construction.
    pub(crate) const EMPTY: Self =
        Intercepts { base: [0.0; 3], slope: [0.0; 3], band: [0.0; 3], right: [0; 3], t_max: 0.0, flat: false };

    /// The intercepts of the triangle with window `tri` and edges `exact`
    /// from the top pixel row of its first tile row, over every row a draw
    /// of it steps through: those of its tile rows.
    #[inline]
    pub(crate) fn new(tri: &Raster, exact: &Exact) -> Self {
        let (r0, r1) = tri.subtile_rows();
        let top = r0 & !1;
        let py = f64::from(top * 4) + 0.5;
        let (x0, rows) = (f64::from(tri.x0), f64::from((r1 - top + 1) * 4));
        let mut out = Self::EMPTY;
        out.t_max = (tri.x1 - tri.x0) as f32 + 3.5;
        for (i, edge) in exact.edges.iter().enumerate() {
            out.right[i] = -i32::from(edge.a > 0.0);
            if edge.a == 0.0 {
                // Horizontal: `t_max` bounds `hi` (`a` is not positive)
                // beyond the window, half a pixel from a whole number.
                (out.base[i], out.flat) = (out.t_max, true);
                continue;
            }
            let u = edge.slope * py + edge.offset + 0.5 - x0;
            out.base[i] = u as f32;
            out.slope[i] = edge.slope as f32;
            out.band[i] = round_far(exact.bands[i] + F32_SCALE * (2.0 * u.abs() + 3.0 * edge.slope.abs() * rows + 1.0));
        }
        out
    }
}

/// `floor(v)` of a clamped intercept, without a library call.
#[inline]
fn floor_f32(v: f32) -> i32 {
    let i = v as i32;
    i - i32::from(i as f32 > v)
}

/// Portable [`Spans`] of the tile row from row `row` of the triangle's
/// [`Intercepts`] (a multiple of 8), each row starting as the triangle's
/// window `x0..x1`. A row of the screen outside the triangle's rows `y0..y1`
/// needs no test of its own: no pixel centre of it is inside the triangle,
/// so its edges leave it empty ("Rows outside the triangle" above); the rows
/// beyond a horizontal edge and below the screen are the caller's.
pub(crate) fn edge_spans(tri: &Raster, row: f32) -> Spans {
    const ROWS: usize = STEP_ROWS as usize;
    let intercepts = &tri.lanes;
    let (mut lo, mut hi) = ([0i32; ROWS], [tri.x1 - tri.x0; ROWS]);
    let mut exact = 0u8;
    'edges: for i in 0..3 {
        let mut bound = [0i32; ROWS];
        for (r, b) in bound.iter_mut().enumerate() {
            let t = intercepts.base[i] + intercepts.slope[i] * (row + r as f32);
            // Clamped as the AVX2 `min` and `max` clamp (a NaN intercept
            // becomes `t_max`, and its band is NaN: see there).
            let t = t.min(intercepts.t_max).max(T_MIN);
            let k = floor_f32(t);
            let fraction = t - k as f32;
            let band = intercepts.band[i];
            if !(fraction > band && 1.0 - fraction > band) {
                exact |= 1 << i;
                continue 'edges;
            }
            *b = k;
        }
        let right = intercepts.right[i] != 0;
        let ends = if right { &mut lo } else { &mut hi };
        for (end, b) in ends.iter_mut().zip(bound) {
            *end = if right { (*end).max(b) } else { (*end).min(b) };
        }
    }
    Spans { lo: lo.map(|v| v + tri.x0), hi: hi.map(|v| v + tri.x0), exact }
}

/// Portable coverage masks and depth bounds of the [`LANES`] subtiles of
/// tile `tx` (32 pixels wide) of tile row `ty` (subtile rows `2 ty` and
/// `2 ty + 1`): lane `l` is subtile column `4 tx + l % 4` of subtile row
/// `2 ty + l / 4`, its mask bit `x + 8 y` set for the pixels of its row `y`
/// inside `spans` (a row's bits by shifts of its span's ends), its depth
/// [`DepthPlane::subtile_bound`](super::DepthPlane) from the first tile of
/// the triangle's window (the AVX2 version steps to it from there tile by
/// tile, with the same exact sums).
pub(crate) fn tile_lanes(tri: &Raster, spans: &Spans, tx: u32, ty: u32) -> ([u32; LANES], [f32; LANES]) {
    let (mut cover, mut depth) = ([0u32; LANES], [0f32; LANES]);
    let anchor = tri.tile_columns().0;
    for l in 0..LANES {
        let (column, half) = (l % 4, l / 4);
        let bx = (tx * TILE_W) as i32 + column as i32 * 8;
        for r in 0..4 {
            let row = 4 * half + r;
            let (lo, hi) = ((spans.lo[row] - bx).clamp(0, 8), (spans.hi[row] - bx).clamp(0, 8));
            cover[l] |= ((1u32 << hi.max(lo)) - (1u32 << lo)) << (8 * r);
        }
        depth[l] = tri.plane.subtile_bound(anchor, tx, f64::from(ty * 8 + half as u32 * 4), column);
    }
    (cover, depth)
}

/// The tiles of one tile row of a triangle in the reach of its spans: what
/// [`Lanes::draw_tiles`] reads.
pub(crate) struct TileRow<'a> {
    pub raster: &'a Raster,
    pub spans: &'a Spans,
    /// The tile row: subtile rows `2 ty` and `2 ty + 1`.
    pub ty: u32,
    /// The tile columns `first..=last` in the spans' reach.
    pub first: u32,
    pub last: u32,
    /// The first tile column whose tiles have padding pixels (beyond the
    /// screen's right side; every column on a tile row reaching below the
    /// screen): from it on, a tile's lanes that cover something take their
    /// padding ([`outside`], [`add_outside`]).
    pub padded_from: u32,
    /// The screen's width and height.
    pub screen: (u32, u32),
}

/// Per lane of tile `tx` of tile row `ty`, its subtile's pixels beyond a
/// `width` x `height` screen.
#[inline]
pub(crate) fn outside((width, height): (u32, u32), tx: u32, ty: u32) -> [u32; LANES] {
    std::array::from_fn(|l| outside_mask(width, height, 4 * tx + (l % 4) as u32, 2 * ty + (l / 4) as u32))
}

/// Adds the padding pixels `outside` (per lane: the pixels of its subtile
/// beyond the screen) to the lanes of `cover` that cover something: padding
/// counts as covered by every triangle touching its subtile (`crate::buffer`).
#[inline]
pub(crate) fn add_outside(cover: &mut [u32; LANES], outside: &[u32; LANES]) {
    for (c, &o) in cover.iter_mut().zip(outside) {
        if *c != 0 {
            *c |= o;
        }
    }
}

/// The rasterizer's two per-tile-row steps, portable ([`Portable`]) or in
/// AVX2 ([`Avx2`](super::avx2::Avx2)), so that one traversal
/// (`Band::draw_with`) serves both.
pub(crate) trait Lanes: Copy {
    /// The [`Spans`] of the tile row from row `row` of the triangle's
    /// [`Intercepts`] ([`edge_spans`]).
    fn edge_spans(self, tri: &Raster, row: f32) -> Spans;
    /// [`Spans::reach`].
    fn reach(self, spans: &Spans) -> Option<(i32, i32)> {
        spans.reach()
    }
    /// The tiles of `row`, each one's masks and depth bounds ([`tile_lanes`]),
    /// its padding added ([`add_outside`]), merged ([`Tile::merge`]) into
    /// its subtiles: tile `tx` of `tiles` (the tile row).
    fn draw_tiles(self, tiles: &mut [Tile], row: &TileRow<'_>, mode: MergeMode);
}

/// The portable [`Lanes`]: this module's functions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

impl Lanes for Portable {
    #[inline]
    fn edge_spans(self, tri: &Raster, row: f32) -> Spans {
        edge_spans(tri, row)
    }

    #[inline]
    fn draw_tiles(self, tiles: &mut [Tile], row: &TileRow<'_>, mode: MergeMode) {
        for tx in row.first..=row.last {
            let (mut cover, depth) = tile_lanes(row.raster, row.spans, tx, row.ty);
            if tx >= row.padded_from {
                add_outside(&mut cover, &outside(row.screen, tx, row.ty));
            }
            tiles[tx as usize].merge(&cover, &depth, mode);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::buffer::Subtile;
    use crate::raster::{CullMode, ScreenTriangle};
    use glam::DVec3;

    struct Lcg(u64);
    impl Lcg {
        fn unit(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Random triangles of sizes 1 to 500 pixels on odd screen sizes, snapped to
    /// half pixels in some (centres on edges, horizontal and vertical edges).
    fn triangles(seed: u64, count: usize) -> Vec<(u32, u32, ScreenTriangle)> {
        let mut rng = Lcg(seed);
        let sizes = [1.0, 3.0, 10.0, 25.0, 50.0, 100.0, 250.0, 500.0];
        let screens = [(1, 1), (7, 5), (83, 45), (641, 479), (1023, 767)];
        let mut out = Vec::new();
        while out.len() < count {
            let (w, h) = screens[out.len() % screens.len()];
            let size = sizes[out.len() % sizes.len()];
            let c = DVec3::new(rng.unit() * f64::from(w + 20) - 10.0, rng.unit() * f64::from(h + 20) - 10.0, 0.0);
            let mut t = [0; 3].map(|_| c + DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, 0.0) * size);
            for p in &mut t {
                p.z = rng.unit();
                if out.len() % 3 == 0 {
                    (p.x, p.y) = ((p.x * 2.0).round() / 2.0, (p.y * 2.0).round() / 2.0);
                }
            }
            if out.len() % 5 == 0 {
                t[1].y = t[0].y;
            }
            if out.len() % 7 == 0 {
                t[2].x = t[0].x;
            }
            if let Some(tri) = ScreenTriangle::new(t, CullMode::None, w, h, super::super::Tolerance::NONE) {
                out.push((w, h, tri));
            }
        }
        out
    }

    #[test]
    fn avx2_merge_equals_the_portable_merge() {
        let Some(avx2) = super::super::avx2::Avx2::detect() else {
            eprintln!("skipped: no AVX2 on this CPU");
            return;
        };
        let mut rng = Lcg(5);
        // Few distinct values, so that ties, full masks and discards happen.
        let depths = [0.1f32, 0.25, 0.5, 0.75, 1.0, f32::NAN];
        let masks = [0u32, 0xFF, 0xFFFF_0000, 0x0F0F_0F0F, u32::MAX];
        let mut pick = |n: usize| (rng.unit() * n as f64) as usize % n;
        let (mut full, mut discarded) = (0, 0);
        for mode in [MergeMode::LayerMerge, MergeMode::QuickMask] {
            for _ in 0..20_000 {
                let mut tile = Tile { mask: [0; LANES], working: [0.0; LANES], reference: [1.0; LANES] };
                let (mut cover, mut depth) = ([0u32; LANES], [0f32; LANES]);
                for l in 0..LANES {
                    let (w, r) = (depths[pick(5)], depths[pick(5)]);
                    let (w, r) = (w.min(r), w.max(r));
                    tile.set(l, Subtile { mask: masks[pick(4)], working: w, reference: r });
                    (cover[l], depth[l]) = (masks[pick(5)], depths[pick(6)]);
                }
                let before = tile;
                let mut portable = tile;
                portable.merge(&cover, &depth, mode);
                avx2.merge(&mut tile, &cover, &depth, mode);
                for (l, &c) in cover.iter().enumerate() {
                    let (a, p) = (tile.get(l), portable.get(l));
                    assert!(
                        a.mask == p.mask
                            && a.working.to_bits() == p.working.to_bits()
                            && a.reference.to_bits() == p.reference.to_bits(),
                        "{mode:?} lane {l}: {a:?} vs {p:?}"
                    );
                    let b = before.get(l);
                    // A full mask moved the working depth into the reference; a
                    // discarded working layer left only the new cover.
                    full += usize::from(p.reference.to_bits() != b.reference.to_bits());
                    discarded += usize::from(b.mask & !c != 0 && p.mask == c);
                }
            }
        }
        assert!(full > 1000 && discarded > 1000, "{full} {discarded}");
    }

    #[test]
    fn avx2_lanes_equal_the_portable_lanes() {
        let Some(avx2) = super::super::avx2::Avx2::detect() else {
            eprintln!("skipped: no AVX2 on this CPU");
            return;
        };
        let (mut subtiles, mut exact) = (0, 0);
        for (_, _, tri) in triangles(11, 4000) {
            let (r0, r1) = tri.raster.subtile_rows();
            let top = r0 & !1;
            for sy in (top..r1).step_by(2) {
                let row = ((sy - top) * 4) as f32;
                let spans = edge_spans(&tri.raster, row);
                assert_eq!(avx2.edge_spans(&tri.raster, row), spans, "{:?} row {sy}", tri.exact.edges);
                assert_eq!(avx2.reach(&spans), spans.reach());
                exact += usize::from(spans.exact != 0);
                let (first, last) = tri.raster.tile_columns();
                for tx in first..=last {
                    let (c, d) = tile_lanes(&tri.raster, &spans, tx, sy / 2);
                    let (ac, ad) = avx2.tile_lanes(&tri.raster, &spans, tx, sy / 2);
                    assert_eq!(ac, c);
                    assert_eq!(ad.map(f32::to_bits), d.map(f32::to_bits));
                    subtiles += c.iter().filter(|&&m| m != 0).count();
                }
            }
        }
        // The exact rule is taken (near-horizontal edges, centres on edges), and
        // the lanes decide most steps.
        assert!(subtiles > 10_000 && exact > 100, "{subtiles} {exact}");
    }

    /// The module doc's "Intercepts in `f32`": on random triangles on screens
    /// up to 30,000 rows tall, every row's `f32` intercept (plus `x0`) lies
    /// within the `f32` allowance `2^-22 (2 |u| + 3 |slope| R + 1)` of the
    /// intercept evaluated in `f64` on its row, the allowance the `f32` band
    /// adds to the edge's `f64` band.
    #[test]
    fn f32_intercepts_stay_within_their_allowance() {
        let mut rng = Lcg(23);
        let screens = [(1920u32, 1080u32), (640, 8000), (4000, 30000), (83, 45)];
        let (mut rounded, mut rows) = (0usize, 0usize);
        let mut worst = 0f64;
        for round in 0..3000 {
            let (w, h) = screens[round % screens.len()];
            let (wf, hf) = (f64::from(w), f64::from(h));
            let mut t = [0; 3].map(|_| DVec3::new(rng.unit() * wf, rng.unit() * hf, rng.unit()));
            if round % 3 == 0 {
                // A near-horizontal edge: a steep intercept.
                t[1].y = t[0].y + (rng.unit() - 0.5) * 1e-3;
            }
            for p in &mut t {
                (p.x, p.y) = ((p.x * 256.0).round() / 256.0, (p.y * 256.0).round() / 256.0);
            }
            let Some(tri) = ScreenTriangle::new(t, CullMode::None, w, h, super::super::Tolerance::NONE) else {
                continue;
            };
            let (r0, r1) = tri.raster.subtile_rows();
            let (top, count) = ((r0 & !1) as i32 * 4, (r1 - (r0 & !1) + 1) * 4);
            let intercepts = &tri.raster.lanes;
            for (i, edge) in tri.exact.edges.iter().enumerate() {
                let u = edge.slope * (f64::from(top) + 0.5) + edge.offset + 0.5 - f64::from(tri.raster.x0);
                let allowance = super::F32_SCALE * (2.0 * u.abs() + 3.0 * edge.slope.abs() * f64::from(count) + 1.0);
                for r in 0..count as i32 {
                    let y = f64::from(top + r) + 0.5;
                    let evaluated = edge.slope * y + edge.offset + 0.5;
                    let lane = intercepts.base[i] + intercepts.slope[i] * r as f32;
                    if !evaluated.is_finite() || !allowance.is_finite() {
                        continue;
                    }
                    let error = (f64::from(lane) + f64::from(tri.raster.x0) - evaluated).abs();
                    assert!(error <= allowance, "{t:?} edge {i} row {}: {error} > {allowance}", top + r);
                    worst = worst.max(error / allowance);
                    rounded += usize::from(error > 0.0);
                    rows += 1;
                }
            }
        }
        // The lanes do round (the test is not vacuous), within the allowance.
        assert!(rows > 100_000 && rounded > rows / 2, "{rounded} of {rows}");
        eprintln!("f32 intercepts: {rounded} of {rows} rows rounded, worst {worst:.3} of the allowance");
    }
}
