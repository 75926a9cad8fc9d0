//! The rasterizer's two inner steps in lanes, for one subtile row (four pixel
//! rows) of a triangle, after HPG 2016 section 4 (coverage from the edges'
//! x-intercepts per scanline, then shifts, no per-pixel work):
//!
//! - [`edge_spans`]: each edge's x-intercept on the four pixel rows at once
//!   (stepped from the subtile row above, "Stepped intercepts" below),
//!   giving each row's covered pixels `lo..hi`;
//! - [`subtile_lanes`]: from those spans, the coverage masks and depth bounds of
//!   eight neighbouring subtiles at once.
//!
//! Each has this portable version and an AVX2 one ([`super::avx2`]) that does the
//! same `f64` and integer operations in the same order (never a fused
//! multiply-add), so both give bit-identical results; the tests check it on
//! random triangles.
//!
//! # Exactness
//! An edge's intercept `t = slope py + offset + 0.5` on row `y` (the edge
//! crosses the row at `x = t - 0.5`, so pixel `x`'s centre `x + 0.5` lies on
//! its right exactly when `x >= t`) decides its covered pixels without testing
//! them when `t`'s distance to the nearest whole number exceeds the edge's
//! proven error band ([`Edge::band`](super::Edge)): then the pixels up to
//! `floor(t) - 1` lie on one side and those from `floor(t)` on the other, exactly
//! as [`Edge::covers`](super::Edge) decides them. The floor itself is then the
//! end of the row's span the edge sets. When any of the four rows is
//! within the band (rare), or the edge is horizontal (band infinite), the edge is
//! reported in [`Spans::exact`] and the caller decides its rows with the scalar,
//! pixel-exact [`Edge::span`](super::Edge). A row's span is the intersection of
//! its edges' half-lines with the triangle's pixel window, so the order in which
//! edges are applied does not matter. Masks are therefore exactly the per-pixel
//! definition.
//!
//! # Rows outside the triangle
//! A subtile row may hold pixel rows of the screen above or below the
//! triangle's rows `y0..y1` (the pixel centres within its vertices' `y`
//! range). They are not emptied by a test of their own: a pixel centre there
//! lies outside the closed triangle, so one of its edge functions is negative
//! there (exactly, in `f64`), and the edges' half-lines, decided exactly as
//! above, leave the row empty. The intercepts' bands hold on every row of the
//! screen, inside the triangle or not (the band bounds the intercept over
//! `0..y_max`). Only the padding rows below the screen, where the band is not
//! proven and pixels are not the triangle's, are emptied by the traversal.
//!
//! # Stepped intercepts
//! An edge's intercepts `t = slope py + offset + 0.5` are evaluated so on the
//! first subtile row a triangle draws ([`first_intercepts`]), then carried to
//! each next subtile row by one rounded addition of `4 slope` (exact: a
//! product by a power of two) in [`edge_spans`]. In exact arithmetic the sum
//! after `j` steps is the evaluated intercept of the first row plus `4 j
//! slope`, which is the same function of the row as the evaluation there and
//! errs as little; each rounded addition adds at most `2^-53` of its result.
//! The rows that matter lie within `0..y_max` (and those before them in the
//! same lane too), where `|t| <= |slope| y_max + |offset| + 0.5`, below the
//! band's intercept term `|slope| y_max + |offset| + x_max + 1`; there are at
//! most `y_max / 4 + 1` steps, so the steps together err by at most
//! `(y_max / 4 + 1) 2^-53` of that term (to first order; the band allows
//! twice as much, [`band_scale`](super::band_scale)). A step's error only
//! moves `t` within the band, and the band is what decides a row without
//! testing pixels, so masks stay exactly the per-pixel definition. A test
//! checks the steps' error against this allowance on random triangles on
//! screens up to 30,000 rows tall.

use super::{floor_in, ScreenTriangle};
use crate::buffer::{outside_mask, Group, MergeMode};

/// Subtiles handled by one [`subtile_lanes`] call.
pub(crate) const LANES: usize = 8;

/// The covered pixels `lo[r]..hi[r]` of the four pixel rows of a subtile row
/// (`lo >= hi`: none), from the edges the lanes decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Spans {
    pub lo: [i32; 4],
    pub hi: [i32; 4],
    /// Bit `i` set: edge `i` is not yet applied and must be decided row by row
    /// with the exact scalar rule.
    pub exact: u8,
}

impl Spans {
    /// Pixels `left..right` that hold every row's covered pixels, `None` where
    /// that is empty (then so is every row): the smallest `lo` to the largest
    /// `hi`. An empty row may widen it (its `lo` and `hi` are ends of the
    /// triangle's window or edge bounds, within `0..=width`); the groups it
    /// adds have no cover and are left as they are.
    pub(crate) fn reach(&self) -> Option<(i32, i32)> {
        let left = self.lo.iter().fold(i32::MAX, |m, &v| m.min(v));
        let right = self.hi.iter().fold(i32::MIN, |m, &v| m.max(v));
        (left < right).then_some((left, right))
    }
}

/// Each edge's intercepts `slope py + offset + 0.5` (one past the pixel index
/// whose centre the edge crosses: the floor is the span's end it sets) on the
/// four pixel rows of a subtile row: evaluated on the first subtile row drawn
/// ([`first_intercepts`]), then stepped down by `4 slope` per subtile row
/// ([`edge_spans`]).
pub(crate) type Intercepts = [[f64; 4]; 3];

/// Portable [`Intercepts`] of the four pixel rows from `y`, evaluated.
pub(crate) fn first_intercepts(tri: &ScreenTriangle, y: i32) -> Intercepts {
    std::array::from_fn(|i| {
        let edge = &tri.edges[i];
        std::array::from_fn(|r| edge.slope * (f64::from(y + r as i32) + 0.5) + edge.offset + 0.5)
    })
}

/// Portable [`Spans`] of four pixel rows of `tri`, each row starting as the
/// triangle's window `x0..x1`, from the edges' `intercepts` on these rows,
/// which it then steps to the next subtile row's. A row of the screen outside
/// the triangle's rows `y0..y1` needs no test of its own: no pixel centre of
/// it is inside the triangle, so its edges leave it empty ("Rows outside the
/// triangle" above); rows below the screen are the caller's.
pub(crate) fn edge_spans(tri: &ScreenTriangle, intercepts: &mut Intercepts) -> Spans {
    let mut spans = Spans { lo: [tri.x0; 4], hi: [tri.x1; 4], exact: 0 };
    let rows = *intercepts;
    for (t, edge) in intercepts.iter_mut().zip(&tri.edges) {
        *t = t.map(|t| t + edge.slope * 4.0);
    }
    'edges: for (i, ((edge, &band), rows)) in tri.edges.iter().zip(&tri.bands).zip(rows).enumerate() {
        let mut bound = [0i32; 4];
        for (b, t) in bound.iter_mut().zip(rows) {
            // Clamped as the AVX2 `min` and `max` clamp (a NaN intercept
            // becomes `t_max`; see there why its band then fails).
            let t = t.min(tri.t_max).max(tri.t_min);
            let k = floor_in(t, tri.t_min, tri.t_max);
            let fraction = t - f64::from(k);
            if !(fraction > band && 1.0 - fraction > band) {
                spans.exact |= 1 << i;
                continue 'edges;
            }
            *b = k;
        }
        let right = edge.a > 0.0;
        let ends = if right { &mut spans.lo } else { &mut spans.hi };
        for (end, b) in ends.iter_mut().zip(bound) {
            *end = if right { (*end).max(b) } else { (*end).min(b) };
        }
    }
    spans
}

/// Portable coverage masks and depth bounds of the [`LANES`] subtiles from
/// column `sx` of subtile row `sy`: lane `l` is subtile `sx + l`, its mask bit
/// `x + 8 y` set for the pixels of row `y` inside `spans` (a row's bits by
/// shifts of its span's ends), its depth [`DepthPlane::subtile_bound`](super::DepthPlane)
/// (the group's first subtile at column `sx`, which the AVX2 version's lanes
/// share).
pub(crate) fn subtile_lanes(tri: &ScreenTriangle, spans: &Spans, sx: u32, sy: u32) -> ([u32; LANES], [f32; LANES]) {
    let (mut cover, mut depth) = ([0u32; LANES], [0f32; LANES]);
    let (gx, by) = (f64::from(sx * 8), f64::from(sy * 4));
    for l in 0..LANES {
        let bx = (sx as i32 + l as i32) * 8;
        for r in 0..4 {
            let (lo, hi) = ((spans.lo[r] - bx).clamp(0, 8), (spans.hi[r] - bx).clamp(0, 8));
            cover[l] |= ((1u32 << hi.max(lo)) - (1u32 << lo)) << (8 * r);
        }
        depth[l] = tri.plane.subtile_bound(gx, by, l);
    }
    (cover, depth)
}

/// One group's step of a subtile row: what [`subtile_lanes`] reads, and
/// whether the group has padding pixels.
pub(crate) struct GroupStep<'a> {
    pub tri: &'a ScreenTriangle,
    pub spans: &'a Spans,
    /// The group's first subtile.
    pub sx: u32,
    pub sy: u32,
    /// The screen's width and height where the group reaches beyond it (its
    /// lanes' padding pixels are [`outside`]); `None` where it lies wholly on
    /// screen.
    pub outside: Option<(u32, u32)>,
}

/// Per lane of the group from subtile column `sx` of row `sy`, its subtile's
/// pixels beyond a `width` x `height` screen.
#[inline]
pub(crate) fn outside((width, height): (u32, u32), sx: u32, sy: u32) -> [u32; LANES] {
    std::array::from_fn(|l| outside_mask(width, height, sx + l as u32, sy))
}

/// Adds the padding pixels `outside` (per lane: the pixels of its subtile
/// beyond the screen) to the lanes of `cover` that cover something: padding
/// counts as covered by every triangle touching its subtile (the crate doc).
#[inline]
pub(crate) fn add_outside(cover: &mut [u32; LANES], outside: &[u32; LANES]) {
    for (c, &o) in cover.iter_mut().zip(outside) {
        if *c != 0 {
            *c |= o;
        }
    }
}

/// The rasterizer's two per-row steps, portable ([`Portable`]) or in AVX2
/// ([`Avx2`](super::avx2::Avx2)), so that one traversal
/// (`Band::draw_with`) serves both.
pub(crate) trait Lanes: Copy {
    /// The edges' [`Intercepts`] in the lanes' layout.
    type Intercepts: Copy;
    /// The [`Intercepts`] of the four pixel rows from `y`
    /// ([`first_intercepts`]).
    fn first_intercepts(self, tri: &ScreenTriangle, y: i32) -> Self::Intercepts;
    /// The [`Spans`] of the four pixel rows of `intercepts`, which it steps
    /// to the next subtile row's ([`edge_spans`]).
    fn edge_spans(self, tri: &ScreenTriangle, intercepts: &mut Self::Intercepts) -> Spans;
    /// [`Spans::reach`].
    fn reach(self, spans: &Spans) -> Option<(i32, i32)> {
        spans.reach()
    }
    /// One group's masks and depth bounds ([`subtile_lanes`]), its padding
    /// added ([`add_outside`]), merged into `group` ([`Group::merge`]).
    fn draw_group(self, group: &mut Group, step: &GroupStep<'_>, mode: MergeMode);
}

/// The portable [`Lanes`]: this module's functions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

impl Lanes for Portable {
    type Intercepts = Intercepts;

    #[inline]
    fn first_intercepts(self, tri: &ScreenTriangle, y: i32) -> Intercepts {
        first_intercepts(tri, y)
    }

    #[inline]
    fn edge_spans(self, tri: &ScreenTriangle, intercepts: &mut Intercepts) -> Spans {
        edge_spans(tri, intercepts)
    }

    #[inline]
    fn draw_group(self, group: &mut Group, step: &GroupStep<'_>, mode: MergeMode) {
        let (mut cover, depth) = subtile_lanes(step.tri, step.spans, step.sx, step.sy);
        if let Some(screen) = step.outside {
            add_outside(&mut cover, &outside(screen, step.sx, step.sy));
        }
        group.merge(&cover, &depth, mode);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::buffer::Subtile;
    use crate::raster::CullMode;
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
                let mut group = Group { mask: [0; LANES], working: [0.0; LANES], reference: [1.0; LANES] };
                let (mut cover, mut depth) = ([0u32; LANES], [0f32; LANES]);
                for l in 0..LANES {
                    let (w, r) = (depths[pick(5)], depths[pick(5)]);
                    let (w, r) = (w.min(r), w.max(r));
                    group.set(l, Subtile { mask: masks[pick(4)], working: w, reference: r });
                    (cover[l], depth[l]) = (masks[pick(5)], depths[pick(6)]);
                }
                let before = group;
                let mut portable = group;
                portable.merge(&cover, &depth, mode);
                avx2.merge(&mut group, &cover, &depth, mode);
                for (l, &c) in cover.iter().enumerate() {
                    let (a, p) = (group.get(l), portable.get(l));
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
        let mut subtiles = 0;
        for (_, _, tri) in triangles(11, 4000) {
            let (r0, r1) = tri.subtile_rows();
            let (mut stepped, mut avx2_stepped) =
                (first_intercepts(&tri, r0 as i32 * 4), avx2.first_intercepts(&tri, r0 as i32 * 4));
            for sy in r0..r1 {
                let spans = edge_spans(&tri, &mut stepped);
                assert_eq!(avx2.edge_spans(&tri, &mut avx2_stepped), spans, "{:?} row {sy}", tri.edges);
                for sx in (tri.x0 / 8) as u32..=((tri.x1 - 1) / 8) as u32 {
                    let (c, d) = subtile_lanes(&tri, &spans, sx, sy);
                    let (ac, ad) = avx2.subtile_lanes(&tri, &spans, sx, sy);
                    assert_eq!(ac, c);
                    assert_eq!(ad.map(f32::to_bits), d.map(f32::to_bits));
                    subtiles += c.iter().filter(|&&m| m != 0).count();
                }
            }
        }
        assert!(subtiles > 10_000, "{subtiles}");
    }

    /// The crate doc's "Stepped intercepts": on random triangles up to 30,000
    /// rows tall, an intercept stepped from the first subtile row lies within
    /// `STEP_SCALE (y_max / 4 + 1)` of the band's intercept term of the one
    /// evaluated on its row, the part of the band ([`super::super::band_scale`])
    /// that allows for the steps.
    #[test]
    fn stepped_intercepts_stay_within_the_step_allowance() {
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
            let (r0, r1) = tri.subtile_rows();
            let mut stepped = first_intercepts(&tri, r0 as i32 * 4);
            for sy in r0..r1 {
                let y = (sy * 4) as i32;
                let evaluated = first_intercepts(&tri, y);
                for (i, edge) in tri.edges.iter().enumerate() {
                    let term = edge.slope.abs() * hf + edge.offset.abs() + wf + 1.0;
                    let allowance = super::super::STEP_SCALE * (hf * 0.25 + 1.0) * term;
                    for r in 0..4 {
                        if !(tri.y0..tri.y1).contains(&(y + r as i32)) || !evaluated[i][r].is_finite() {
                            continue;
                        }
                        let error = (stepped[i][r] - evaluated[i][r]).abs();
                        assert!(error <= allowance, "{t:?} edge {i} row {}: {error} > {allowance}", y + r as i32);
                        worst = worst.max(error / allowance);
                        rounded += usize::from(error > 0.0);
                        rows += 1;
                    }
                }
                let _ = edge_spans(&tri, &mut stepped);
            }
        }
        // Stepping does round (the test is not vacuous), well within the allowance.
        assert!(rows > 100_000 && rounded > rows / 10, "{rounded} of {rows}");
        eprintln!("stepped intercepts: {rounded} of {rows} rows rounded, worst {worst:.3} of the allowance");
    }
}
