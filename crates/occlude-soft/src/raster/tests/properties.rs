//! Property tests: on random scenes at random sizes, the optimized rasterizer (AVX2
//! where the CPU has it, and the scalar fallback) agrees with the per-pixel reference
//! bit for bit, and the hierarchical depth's bound is below every depth it bounds.

use glam::Vec4;
use proptest::prelude::*;

use super::super::clip::Polygon;
use super::super::hiz::min_depth;
use super::super::setup::{round, setup_triangle, Viewport};
use super::super::span::{floor_divmod, RasterTri};
use super::super::{Command, CommandKind, DepthTest, Rasterizer};
use super::{bits, check_against_reference, cmd, float_bits, DepthBuffer};

/// A clip-space vertex at NDC `(x, y, z)` scaled by `w`.
fn clip(x: f32, y: f32, z: f32, w: f32) -> Vec4 {
    Vec4::new(x, y, z, 1.0) * w
}

/// Triangles of every kind the rasterizer must handle.
fn triangle() -> impl Strategy<Value = [Vec4; 3]> {
    let ndc = || -1.6f32..1.6;
    let vertex =
        move |w: std::ops::Range<f32>| (ndc(), ndc(), -0.2f32..1.1, w).prop_map(|(x, y, z, w)| clip(x, y, z, w));
    prop_oneof![
        // Anywhere, any size: crossing tiles, the near plane, the viewport's sides.
        4 => [vertex(0.2..3.0), vertex(0.2..3.0), vertex(0.2..3.0)],
        // Small: around a pixel or below.
        3 => (ndc(), ndc(), 0.0f32..1.0, prop::array::uniform3((-0.03f32..0.03, -0.03f32..0.03)))
            .prop_map(|(x, y, z, d)| d.map(|(dx, dy)| clip(x + dx, y + dy, z, 1.0))),
        // Degenerate: the third vertex on the line through the first two.
        1 => (vertex(1.0..1.0001), vertex(1.0..1.0001), -1.0f32..2.0).prop_map(|(a, b, t)| [a, b, a.lerp(b, t)]),
        // Reaching behind the eye (w <= 0).
        1 => [vertex(-1.0..1.0), vertex(0.2..2.0), vertex(-1.0..1.0)],
        // Far past the guard band.
        1 => [vertex(0.5..1.0), vertex(0.5..1.0), vertex(0.5..1.0)].prop_map(|t| t.map(|v| clip(v.x * 1e4, v.y, v.z, v.w))),
        // Depths up to f32::MAX: planes so steep that depths overflow to infinity and
        // NaN (clamped to 0) inside the triangle.
        1 => prop::array::uniform3((ndc(), ndc(), 0.0f32..3.4e38)).prop_map(|v| v.map(|(x, y, z)| clip(x, y, z, 1.0))),
        // On a coarse grid: vertices and edges through pixel centres and corners, edges
        // shared between triangles (ties of the fill rule).
        2 => prop::array::uniform3((0i32..=16, 0i32..=16, 0.0f32..1.0))
            .prop_map(|v| v.map(|(x, y, z)| clip(x as f32 / 8.0 - 1.0, y as f32 / 8.0 - 1.0, z, 1.0))),
    ]
}

/// A command over `triangles` (a range taken modulo their count): any kind, culling
/// on or off. Ranges overlap, so the same triangles are drawn and queried again
/// (EQUAL queries then pass).
fn command(n: u32) -> impl Strategy<Value = Command> {
    (0..5u8, 0..n, 0..n, any::<bool>()).prop_map(|(kind, a, b, cull_back)| {
        let kind = match kind {
            0 => CommandKind::Draw,
            1 => CommandKind::Query(DepthTest::Less),
            2 => CommandKind::Query(DepthTest::Equal),
            3 => CommandKind::QueryAny(DepthTest::Less),
            _ => CommandKind::QueryAny(DepthTest::Equal),
        };
        cmd(kind, a.min(b)..a.max(b) + 1, cull_back)
    })
}

/// A raster form's fields, bit for bit, to compare set-ups.
fn fields(t: &RasterTri) -> (u32, [i32; 5], [[i32; 2]; 3], [u32; 3]) {
    (t.cmd, [t.x0, t.x1, t.y0, t.y1, t.plane_y], t.verts, [t.z_origin, t.z_dx, t.z_dy].map(f32::to_bits))
}

/// The four-at-a-time set-up of `tris` against the scalar one, lane by lane: a set-up
/// triangle's raster form must be the scalar set-up's only one, field for field and
/// bit for bit; a dropped one must have none (the scalar set-up may keep a
/// triangle that `RasterTri::new` then drops); a triangle inside the viewport (`w` =
/// 1) must not be handed back to the scalar set-up.
#[cfg(target_arch = "x86_64")]
fn check_four_at_a_time_setup(tris: &[[Vec4; 3]; 4], size: (u32, u32), cull_back: bool) -> Result<(), TestCaseError> {
    use super::super::setup_avx2::setup4;
    if !is_x86_feature_detected!("avx2") {
        return Ok(());
    }
    let viewport = Viewport::new(size.0, size.1);
    let mut four = [RasterTri::PLACEHOLDER; 4];
    // SAFETY: the CPU supports AVX2 (checked above).
    let lanes = unsafe { setup4(tris, cull_back, 7, viewport, &mut four) };
    for (i, (tri, fast)) in tris.iter().zip(&four).enumerate() {
        let mut scalar = Vec::new();
        setup_triangle(tri, cull_back, 7, viewport, &mut Polygon::new(), |t| scalar.push(t));
        if lanes.ready & (1 << i) != 0 {
            prop_assert_eq!(scalar.len(), 1, "{:?}", tri);
            let expected = RasterTri::new(&scalar[0]);
            prop_assert_eq!(fast.covered_rows().map(|t| fields(&t)), expected.map(|t| fields(&t)), "{:?}", tri);
        } else if lanes.scalar & (1 << i) != 0 {
            let on_screen = tri.iter().all(|v| v.is_finite() && v.w == 1.0 && v.truncate().abs().max_element() <= 1.0);
            prop_assert!(!on_screen, "{:?} is inside the viewport, handed to the scalar set-up", tri);
        } else {
            let kept = scalar.iter().filter_map(RasterTri::new).count();
            prop_assert_eq!(kept, 0, "{:?} dropped, the scalar set-up kept it", tri);
        }
    }
    Ok(())
}

/// Triangles whose box holds one pixel centre, lying on one of their edges
/// (vertical or horizontal, on either side, either winding): the four-at-a-time
/// set-up keeps exactly those the top-left rule lets cover it.
#[test]
#[cfg(target_arch = "x86_64")]
fn one_centre_triangles_with_the_centre_on_an_edge() {
    // Pixel (5, 5) of a 16 x 16 image, its centre at (5.5, 5.5).
    let at = |x: f32, y: f32| clip(x / 8.0 - 1.0, 1.0 - y / 8.0, 0.5, 1.0);
    let mut tris = Vec::new();
    for side in [-0.7, 0.7] {
        let vertical = [at(5.5, 5.0), at(5.5, 6.0), at(5.5 + side, 5.5)];
        let horizontal = [at(5.0, 5.5), at(6.0, 5.5), at(5.5, 5.5 + side)];
        for [a, b, c] in [vertical, horizontal] {
            tris.extend([[a, b, c], [a, c, b]]);
        }
    }
    for four in tris.chunks_exact(4) {
        for cull_back in [false, true] {
            check_four_at_a_time_setup(four.try_into().expect("four"), (16, 16), cull_back).unwrap();
        }
    }
    // Half of them cover the centre.
    let covering =
        tris.iter().filter(|t| super::draw_all(&mut DepthBuffer::new(16, 16), std::slice::from_ref(*t)).fragments == 1);
    assert_eq!(covering.count(), tris.len() / 2);
}

/// The pre-test of the four-at-a-time set-up against the full set-up, lane by lane:
/// a lane it reports (no pixel centre in its box) must be one that `setup4` does
/// not set up and the scalar set-up drops; and a triangle inside every clipping
/// plane whose snapped vertices' box misses every pixel centre of the viewport by
/// more than two fixed-point units on one axis must be reported (the pre-test is
/// that tight).
#[cfg(target_arch = "x86_64")]
fn check_uncovered_lanes(tris: &[[Vec4; 3]; 4], size: (u32, u32), cull_back: bool) -> Result<(), TestCaseError> {
    use super::super::clip::{clip_triangle, Clipped};
    use super::super::setup::ONE;
    use super::super::setup_avx2::{setup4, uncovered4};
    if !is_x86_feature_detected!("avx2") {
        return Ok(());
    }
    let viewport = Viewport::new(size.0, size.1);
    let mut four = [RasterTri::PLACEHOLDER; 4];
    // SAFETY: the CPU supports AVX2 (checked above).
    let (uncovered, lanes) = unsafe { (uncovered4(tris, viewport), setup4(tris, cull_back, 7, viewport, &mut four)) };
    for (i, tri) in tris.iter().enumerate() {
        let mut scalar = Vec::new();
        setup_triangle(tri, cull_back, 7, viewport, &mut Polygon::new(), |t| scalar.push(t));
        if uncovered & (1 << i) != 0 {
            prop_assert!(lanes.ready & (1 << i) == 0 && scalar.is_empty(), "{:?} reported, but set up", tri);
            continue;
        }
        let Clipped::Inside(v) = clip_triangle(tri, viewport.guard, &mut Polygon::new()) else { continue };
        // The snapped coordinates, as `setup::project` computes them.
        let snap = |s: f64| round(s * ONE as f64);
        let xs = v.map(|p| snap((p.x / p.w + 1.0) * 0.5 * f64::from(size.0)));
        let ys = v.map(|p| snap((1.0 - p.y / p.w) * 0.5 * f64::from(size.1)));
        if !v.iter().all(|p| (p.z / p.w).is_finite()) {
            continue;
        }
        // Whether the centres `k * ONE + ONE / 2` of `0..n` all miss `[lo - 2, hi + 2]`.
        let misses = |c: [i64; 3], n: u32| {
            let (lo, hi) = (c.iter().min().unwrap() - 2 - ONE / 2, c.iter().max().unwrap() + 2 - ONE / 2);
            let first = (-(-lo).div_euclid(ONE)).max(0);
            let last = hi.div_euclid(ONE).min(i64::from(n) - 1);
            first > last
        };
        prop_assert!(!misses(xs, size.0) && !misses(ys, size.1), "{:?} covers no centre, not reported", tri);
    }
    Ok(())
}

/// A buffer size, triangles, and the commands of a few `execute` calls.
type Scene = ((u32, u32), Vec<[Vec4; 3]>, Vec<Vec<Command>>);

/// A random scene: a size (odd ones included, rarely a multiple of the tile), its
/// triangles, and a few `execute` calls' commands.
fn scene() -> impl Strategy<Value = Scene> {
    let size = (1u32..200, 1u32..150);
    (size, prop::collection::vec(triangle(), 1..40)).prop_flat_map(|(size, tris)| {
        let n = tris.len() as u32;
        let calls = prop::collection::vec(prop::collection::vec(command(n), 1..12), 1..4);
        (Just(size), Just(tris), calls)
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn optimized_paths_match_the_reference((size, tris, calls) in scene()) {
        let simd = check_against_reference(&mut Rasterizer::new(), size, &tris, &calls);
        let scalar = check_against_reference(&mut Rasterizer::scalar(), size, &tris, &calls);
        prop_assert_eq!(simd, scalar);
    }

    #[test]
    fn results_survive_external_writes(
        (size, tris, calls) in scene(),
        at in any::<prop::sample::Index>(),
        value in 0.0f32..1.0,
    ) {
        // Like `optimized_paths_match_the_reference`, with one pixel overwritten from
        // outside between the calls: the hierarchical depth must not go stale.
        let mut raster = Rasterizer::new();
        let mut depth = DepthBuffer::new(size.0, size.1);
        let mut expected = vec![1.0; size.0 as usize * size.1 as usize];
        for commands in &calls {
            let r = raster.execute(&mut depth, &tris, commands);
            let e = super::reference::execute(&mut expected, size.0, size.1, &tris, commands);
            prop_assert_eq!(r, e);
            prop_assert!(bits(&depth) == float_bits(&expected));
            let i = at.index(expected.len());
            depth.set(i as u32 % size.0, i as u32 / size.0, value);
            expected[i] = value;
        }
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn four_at_a_time_setup_matches_the_scalar_setup(
        tris in prop::array::uniform4(prop_oneof![
            8 => triangle(),
            1 => (triangle(), 0..12usize, prop_oneof![Just(f32::NAN), Just(f32::INFINITY), Just(-0.0), Just(0.0)])
                .prop_map(|(mut t, at, v)| { t[at / 4][at % 4] = v; t }),
        ]),
        size in (1u32..300, 1u32..300),
        cull_back in any::<bool>(),
    ) {
        check_four_at_a_time_setup(&tris, size, cull_back)?;
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn uncovered_lanes_are_those_the_setup_drops(
        tris in prop::array::uniform4(prop_oneof![
            4 => triangle(),
            // Below a pixel at these sizes: mostly between the centres.
            4 => (-1.1f32..1.1, -1.1f32..1.1, 0.0f32..1.0, 0.3f32..3.0, prop::array::uniform3((-0.004f32..0.004, -0.004f32..0.004)))
                .prop_map(|(x, y, z, w, d)| d.map(|(dx, dy)| clip(x + dx, y + dy, z, w))),
            1 => (triangle(), 0..12usize, prop_oneof![Just(f32::NAN), Just(f32::INFINITY), Just(-0.0), Just(0.0)])
                .prop_map(|(mut t, at, v)| { t[at / 4][at % 4] = v; t }),
        ]),
        size in (1u32..1100, 1u32..800),
        cull_back in any::<bool>(),
    ) {
        check_uncovered_lanes(&tris, size, cull_back)?;
    }

    #[test]
    fn indexed_setup_matches_the_setup_of_its_triangles(
        vertices in prop::collection::vec(prop_oneof![
            8 => triangle(),
            1 => (triangle(), 0..12usize, prop_oneof![Just(f32::NAN), Just(f32::INFINITY), Just(-0.0), Just(0.0)])
                .prop_map(|(mut t, at, v)| { t[at / 4][at % 4] = v; t }),
        ], 1..12).prop_map(|t| t.concat()),
        picks in prop::collection::vec(any::<prop::sample::Index>(), 0..100),
        size in (1u32..300, 1u32..300),
        cull_back in any::<bool>(),
    ) {
        // Triangles sharing vertices in any pattern, a last one incomplete.
        let indices: Vec<u32> = picks.iter().map(|i| i.index(vertices.len()) as u32).collect();
        let triangles: Vec<[Vec4; 3]> =
            indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| vertices[t[k] as usize])).collect();
        for raster in [Rasterizer::new(), Rasterizer::scalar()] {
            let indexed = raster.prepare_indexed(size.0, size.1, &vertices, &indices, cull_back);
            let expected = raster.prepare(size.0, size.1, &triangles, cull_back);
            let all = |p: &super::super::Prepared| p.triangles.iter().map(fields).collect::<Vec<_>>();
            prop_assert_eq!(all(&indexed), all(&expected));
        }
    }

    #[test]
    fn arithmetic_shortcuts_are_exact(
        x in prop_oneof![-1e15f64..1e15, (-1000i64..1000).prop_map(|h| h as f64 * 0.5), -2.0f64..2.0],
        n in prop_oneof![-(1i64 << 52)..(1i64 << 52), -1000i64..1000],
        d in prop_oneof![1u32..=(1 << 24), 1u32..10],
    ) {
        prop_assert_eq!(round(x), x.round() as i64);
        let (q, r) = floor_divmod(n, d);
        prop_assert_eq!((q, i64::from(r)), (n.div_euclid(i64::from(d)), n.rem_euclid(i64::from(d))));
    }

    #[test]
    fn hierarchical_bound_is_below_every_depth(
        tri in triangle(),
        size in (1u32..300, 1u32..300),
        corners in prop::array::uniform4(0.0f64..1.0),
    ) {
        let mut setups = Vec::new();
        setup_triangle(&tri, false, 0, Viewport::new(size.0, size.1), &mut Polygon::new(), |t| setups.push(t));
        for t in setups.iter().filter_map(RasterTri::new) {
            // A random sub-rectangle of the bounding box, as a tile would clip it.
            let (w, h) = (f64::from(t.x1 - t.x0), f64::from(t.y1 - t.plane_y));
            let (xa, xb) = (t.x0 + (corners[0] * w) as i32, t.x0 + (corners[1] * w) as i32);
            let (ya, yb) = (t.plane_y + (corners[2] * h) as i32, t.plane_y + (corners[3] * h) as i32);
            let (x0, x1, y0, y1) = (xa.min(xb), xa.max(xb), ya.min(yb), ya.max(yb));
            let Some(min) = min_depth(&t, x0, x1, y0, y1) else { continue };
            for y in y0..=y1 {
                let plane = t.row_plane(y);
                for x in x0..=x1 {
                    let z = plane.depth(x - t.x0);
                    prop_assert!(min <= z, "bound {} above the depth {} at {},{}", min, z, x, y);
                }
            }
        }
    }
}
