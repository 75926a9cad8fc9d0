//! The buffer's coverage against the soft backend's rasterizer (8 sub-pixel
//! bits, top-left rule): a triangle in front of the near plane covers exactly
//! the pixels the rasterizer covers with it, any other at most those, and
//! where the buffer counts a pixel covered its bound is at least the
//! rasterizer's depth.

use glam::Vec4;
use occlude_moc::{CullMode, MaskedBuffer};
use occlude_soft::raster::{execute, Command, CommandKind, DepthBuffer};
use proptest::prelude::*;

/// Allowance for the rasterizer's `f32` depth interpolation, as the tests of
/// boxes allow (a relative `1e-6`).
const DEPTH_ROUNDING: f32 = 1e-6;

/// The buffer's depth image of `tris` (clip space, back faces culled) and the
/// soft rasterizer's.
fn images(width: u32, height: u32, tris: &[[Vec4; 3]]) -> (Vec<f32>, Vec<f32>) {
    let mut buffer = MaskedBuffer::new(width, height).unwrap();
    buffer.render_clip_triangles(tris, CullMode::Back);
    let mut bound = Vec::new();
    buffer.depth_image(&mut bound);
    let mut depth = DepthBuffer::new(width, height);
    let draw = Command { kind: CommandKind::Draw, triangles: 0..tris.len() as u32, cull_back: true };
    execute(&mut depth, tris, &[draw]);
    (bound, depth.to_vec())
}

/// The first pixel whose rasterized depth is beyond the buffer's bound, if any
/// (an uncovered pixel has depth 1, so this also finds a pixel the buffer
/// counts covered and the rasterizer does not).
fn beyond_bound(width: u32, bound: &[f32], depth: &[f32]) -> Option<String> {
    let i = bound.iter().zip(depth).position(|(&b, &d)| d > b + DEPTH_ROUNDING)?;
    Some(format!("pixel ({}, {}): bound {} below depth {}", i as u32 % width, i as u32 / width, bound[i], depth[i]))
}

/// The occluder triangle behind the one pixel `moc` missed on plant (medium)
/// at frame 20 (instance 818, triangle 480-481-485; 1024x768), as `f32` bits.
/// A sliver 21 pixels long and 0.05 high whose unsnapped edges pass just
/// below the centre of pixel (277, 365) and whose snapped ones just above it:
/// the buffer counted the pixel covered when it decided coverage from
/// unsnapped vertices, the rasterizer does not.
#[test]
fn the_sliver_that_hid_a_pixel_of_plant_leaves_it_uncovered() {
    let bits = [
        [3258602090u32, 1083353672, 1119707704, 1119734656],
        [3258605225, 1083357848, 1119733903, 1119760842],
        [3257618721, 1083360638, 1119751411, 1119778341],
    ];
    let tri = bits.map(|v| Vec4::from_array(v.map(f32::from_bits)));
    let (bound, depth) = images(1024, 768, &[tri]);
    let pixel = 365 * 1024 + 277;
    assert_eq!(depth[pixel], 1.0, "the rasterizer covers the pixel");
    assert_eq!(bound[pixel], 1.0, "the buffer counts the pixel covered");
    assert_eq!(beyond_bound(1024, &bound, &depth), None);
}

/// A screen coordinate: a whole pixel plus a fraction anywhere, on the 1/256
/// grid, or within 1/64 pixel of the pixel centre (where snapping decides).
fn coordinate(size: u32) -> impl Strategy<Value = f64> {
    let fraction = prop_oneof![
        0.0..1.0f64,
        (0..256u32).prop_map(|k| f64::from(k) / 256.0),
        (-64..=64i32).prop_map(|k| 0.5 + f64::from(k) / 4096.0),
    ];
    (-4..size as i32 + 4, fraction).prop_map(|(i, f)| f64::from(i) + f)
}

/// A clip-space vertex at screen position (`x`, `y`) of a `width` x `height`
/// screen, NDC depth `z`, clip `w`.
fn clip_vertex(width: u32, height: u32, x: f64, y: f64, z: f64, w: f64) -> Vec4 {
    let (nx, ny) = (2.0 * x / f64::from(width) - 1.0, 1.0 - 2.0 * y / f64::from(height));
    Vec4::new((nx * w) as f32, (ny * w) as f32, (z * w) as f32, w as f32)
}

/// Screen sizes, odd ones included.
const SCREENS: [(u32, u32); 3] = [(67, 45), (40, 24), (9, 7)];

/// `count` triangles of a screen, vertices in front of the near plane (NDC
/// depth up to 0.9) or, with `behind`, possibly behind it.
fn triangles(count: usize, behind: bool) -> impl Strategy<Value = (u32, u32, Vec<[Vec4; 3]>)> {
    (0..SCREENS.len()).prop_flat_map(move |s| {
        let (width, height) = SCREENS[s];
        let vertex = move || {
            let z = if behind { -0.6..0.9f64 } else { 0.0..0.9f64 };
            (coordinate(width), coordinate(height), z, 0.25..4.0f64)
                .prop_map(move |(x, y, z, w)| clip_vertex(width, height, x, y, z, w))
        };
        let tri = [vertex(), vertex(), vertex()];
        proptest::collection::vec(tri, count).prop_map(move |t| (width, height, t))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// In front of the near plane, the buffer covers exactly the pixels the
    /// rasterizer covers, with a bound at least its depth.
    #[test]
    fn a_triangle_in_front_covers_exactly_the_rasterizers_pixels((width, height, tris) in triangles(1, false)) {
        let (bound, depth) = images(width, height, &tris);
        for (i, (&b, &d)) in bound.iter().zip(&depth).enumerate() {
            prop_assert_eq!(b < 1.0, d < 1.0, "pixel ({}, {}): bound {} depth {}", i as u32 % width, i as u32 / width, b, d);
        }
        prop_assert_eq!(beyond_bound(width, &bound, &depth), None);
    }

    /// Several triangles, some crossing the near plane (drawn unsnapped, edges
    /// moved inward): the bound is never below the rasterizer's depth.
    #[test]
    fn triangles_never_bound_a_pixel_below_the_rasterizer((width, height, tris) in triangles(3, true)) {
        let (bound, depth) = images(width, height, &tris);
        prop_assert_eq!(beyond_bound(width, &bound, &depth), None);
    }
}

#[test]
fn sub_pixel_bits_beyond_the_exact_range_are_refused() {
    let mut buffer = MaskedBuffer::new(8, 8).unwrap();
    assert_eq!(buffer.subpixel_bits(), occlude_moc::SUBPIXEL_BITS);
    let err = buffer.set_subpixel_bits(occlude_moc::MAX_SUBPIXEL_BITS + 1).unwrap_err();
    assert_eq!(err, occlude_moc::Error::SubpixelBits(9));
    assert!(err.to_string().contains("at most 8"), "{err}");
    assert_eq!(buffer.subpixel_bits(), 8);
    buffer.set_subpixel_bits(4).unwrap();
    assert_eq!(buffer.subpixel_bits(), 4);
}
