//! The rasterizer benchmark workloads, in one place so that every benchmark (the
//! criterion bench, `occlude raster-bench`, and other backends' rows) renders the
//! same triangles.
//!
//! - Fill rate, the field's workload: random right triangles with legs of `N`
//!   pixels at random positions and rotations, submitted back to front so that every
//!   fragment passes the depth test and writes ([`right_triangles`]).
//! - Occlusion queries: axis-aligned boxes whose front faces cover a given fraction
//!   of the screen, in front of or behind a screen-filling occluder
//!   ([`query_boxes`], [`screen_quad`]).
//!
//! Triangles are in clip space with `w = 1` (wgpu conventions: NDC `y` up, depth in
//! `[0, 1]`), as `Rasterizer::execute` takes them.

use glam::{Vec2, Vec3, Vec4};
use occlude_core::rng::Rng;

/// Clip-space vertex (`w = 1`) of the screen position `p` (pixels, `y` down) of a
/// `width` x `height` screen, at NDC depth `z`.
fn at_pixel(p: Vec2, z: f32, width: u32, height: u32) -> Vec4 {
    Vec4::new(p.x * 2.0 / width as f32 - 1.0, 1.0 - p.y * 2.0 / height as f32, z, 1.0)
}

/// `count` right triangles with legs of `leg` pixels on a `width` x `height` screen,
/// centred at uniformly random pixel positions, rotated by uniformly random angles,
/// each nearer than the previous one (depth from 1 towards 0), so that drawn in order
/// every covered pixel passes the depth test. Deterministic: the same arguments give
/// the same triangles.
pub fn right_triangles(width: u32, height: u32, leg: f32, count: usize) -> Vec<[Vec4; 3]> {
    let mut rng = Rng::new(0x5EED ^ u64::from(leg.to_bits()), 0);
    let (w, h) = (width as f32, height as f32);
    (0..count)
        .map(|i| {
            let centre = Vec2::new(rng.unit() * w, rng.unit() * h);
            let angle = rng.unit() * std::f32::consts::TAU;
            let u = Vec2::from_angle(angle) * leg;
            let v = Vec2::from_angle(angle + std::f32::consts::FRAC_PI_2) * leg;
            let z = 1.0 - (i + 1) as f32 / (count + 1) as f32;
            let o = centre - (u + v) / 3.0;
            [o, o + u, o + v].map(|p| at_pixel(p, z, width, height))
        })
        .collect()
}

/// Pixels covered by one triangle of [`right_triangles`] with legs of `leg` pixels:
/// `leg² / 2`, the unit the field reports fill rate in.
pub fn pixels_per_triangle(leg: u32) -> f64 {
    f64::from(leg) * f64::from(leg) / 2.0
}

/// How many [`right_triangles`] of legs `leg` cover about `screens` times the
/// `width` x `height` screen, at least 64.
pub fn triangles_for_screens(width: u32, height: u32, leg: u32, screens: f64) -> usize {
    ((screens * f64::from(width) * f64::from(height) / pixels_per_triangle(leg)) as usize).max(64)
}

/// Two counter-clockwise triangles covering the whole screen at NDC depth `z`: the
/// occluder the query workload tests against.
pub fn screen_quad(z: f32) -> [[Vec4; 3]; 2] {
    let v = |x: f32, y: f32| Vec4::new(x, y, z, 1.0);
    [[v(-1.0, -1.0), v(1.0, -1.0), v(1.0, 1.0)], [v(-1.0, -1.0), v(1.0, 1.0), v(-1.0, 1.0)]]
}

/// Depth of the screen-filling occluder ([`screen_quad`]) the query workload tests
/// against.
pub const OCCLUDER_DEPTH: f32 = 0.5;

/// Query boxes per submission in the query workload: a culling method issues many
/// between read-backs.
pub const QUERIES_PER_SUBMISSION: usize = 64;

/// The query workload: [`QUERIES_PER_SUBMISSION`] boxes ([`query_box`]) covering
/// `coverage` (0 to 1) of the screen each, spread over it, in front of the occluder
/// at [`OCCLUDER_DEPTH`] (`visible`) or behind it.
pub fn query_boxes(coverage: f32, visible: bool) -> Vec<[[Vec4; 3]; 12]> {
    let z = if visible { OCCLUDER_DEPTH / 2.0 } else { (OCCLUDER_DEPTH + 1.0) / 2.0 };
    (0..QUERIES_PER_SUBMISSION)
        .map(|i| {
            // An 8x8 lattice of positions, visited in a scrambled order.
            let (u, v) = ((i * 5) % 8, (i * 3 + i / 8) % 8);
            query_box(coverage, z, Vec2::new(u as f32 / 7.0, v as f32 / 7.0))
        })
        .collect()
}

/// The 12 triangles of an axis-aligned box, orthographically projected, whose front
/// face is a square-ish rectangle covering `coverage` (0 to 1) of the screen area at
/// NDC depth `z` and whose back face is 0.01 deeper. `offset` (each coordinate in
/// `[0, 1]`) places the rectangle from the top-left to the bottom-right of the
/// screen. Faces are counter-clockwise seen from outside, as the soft backend's query
/// boxes: with back-face culling, only the front face is rasterized (the side faces
/// are seen edge-on).
pub fn query_box(coverage: f32, z: f32, offset: Vec2) -> [[Vec4; 3]; 12] {
    // The front face spans `side` of NDC width and height: (side / 2)² of the area.
    let side = 2.0 * coverage.clamp(0.0, 1.0).sqrt();
    let lo = Vec2::splat(-1.0) + (2.0 - side) * Vec2::new(offset.x, 1.0 - offset.y);
    let (min, max) = (lo.extend(z), (lo + side).extend(z + 0.01));
    let corner = |i: usize| {
        let p = Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), max, min);
        p.extend(1.0)
    };
    // Corner `i` takes max x, y, z where bit 0, 1, 2 of `i` is set. Quads by outward
    // normal: -x, +x, -y, +y, -z (the front, facing the viewer), +z; NDC is
    // left-handed (z into the screen), so seen from outside each is counter-clockwise.
    const FACES: [[usize; 4]; 6] = [[0, 2, 6, 4], [1, 5, 7, 3], [0, 4, 5, 1], [2, 3, 7, 6], [0, 1, 3, 2], [4, 6, 7, 5]];
    let mut tris = [[Vec4::ZERO; 3]; 12];
    for (f, [a, b, c, d]) in FACES.into_iter().enumerate() {
        tris[2 * f] = [corner(a), corner(b), corner(c)];
        tris[2 * f + 1] = [corner(a), corner(c), corner(d)];
    }
    tris
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{execute, Command, CommandKind, DepthBuffer};

    fn draw(depth: &mut DepthBuffer, tris: &[[Vec4; 3]], cull_back: bool) -> crate::raster::CommandResult {
        let commands: Vec<Command> = (0..tris.len() as u32)
            .map(|i| Command { kind: CommandKind::Draw, triangles: i..i + 1, cull_back })
            .collect();
        let results = execute(depth, tris, &commands);
        results.iter().fold(Default::default(), |mut a, r| {
            a.fragments += r.fragments;
            a.passed += r.passed;
            a
        })
    }

    #[test]
    fn right_triangles_cover_half_a_leg_squared_and_come_nearer() {
        let tris = right_triangles(640, 480, 20.0, 200);
        assert_eq!(tris, right_triangles(640, 480, 20.0, 200), "deterministic");
        assert!(tris.windows(2).all(|w| w[1][0].z < w[0][0].z), "each nearer than the previous");
        // Away from the screen's edges a triangle covers about 20^2 / 2 = 200 pixels,
        // and back to front, every fragment passes.
        let mut depth = DepthBuffer::new(640, 480);
        let r = draw(&mut depth, &tris, false);
        assert_eq!(r.passed, r.fragments);
        let per_triangle = r.fragments as f64 / 200.0;
        assert!((170.0..=205.0).contains(&per_triangle), "{per_triangle} pixels per triangle");
        assert_eq!(pixels_per_triangle(20), 200.0);
        assert_eq!(triangles_for_screens(640, 480, 20, 2.0), 3072);
        assert_eq!(triangles_for_screens(64, 64, 500, 2.0), 64);
    }

    #[test]
    fn query_box_shows_its_front_face_only() {
        let (w, h) = (200u32, 100u32);
        for (coverage, offset) in [(0.25, Vec2::ZERO), (0.04, Vec2::new(0.3, 0.9)), (1.0, Vec2::splat(0.5))] {
            let tris = query_box(coverage, 0.4, offset);
            let mut depth = DepthBuffer::new(w, h);
            let front = draw(&mut depth, &tris, true).fragments;
            let expected = f64::from(coverage) * f64::from(w * h);
            assert!(
                (front as f64 - expected).abs() <= 0.05 * expected + 2.0 * f64::from(w + h),
                "{front} vs {expected}"
            );
            // Two-sided, the back face covers the same pixels again.
            let both = draw(&mut DepthBuffer::new(w, h), &tris, false).fragments;
            assert_eq!(both, 2 * front);
            // The front face is at the requested depth.
            assert!(depth.to_vec().iter().all(|&d| d == 1.0 || (d - 0.4).abs() < 1e-6));
        }
        let occluder = screen_quad(0.5);
        let mut depth = DepthBuffer::new(w, h);
        assert_eq!(draw(&mut depth, &occluder, true).fragments, u64::from(w * h));
    }
}
