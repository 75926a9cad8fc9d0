use glam::{Mat4, Vec3, Vec4};

use super::*;

use occlude_core::rng::Rng;

mod properties;
mod reference;

/// Clip-space vertex of screen position `(sx, sy)` (pixels, y down), NDC depth `z`,
/// scaled by `w`.
fn at_pixel(sx: f32, sy: f32, z: f32, w: f32, width: u32, height: u32) -> Vec4 {
    let x = sx * 2.0 / width as f32 - 1.0;
    let y = 1.0 - sy * 2.0 / height as f32;
    Vec4::new(x, y, z, 1.0) * w
}

fn cmd(kind: CommandKind, triangles: Range<u32>, cull_back: bool) -> Command {
    Command { kind, triangles, cull_back }
}

fn draw_all(depth: &mut DepthBuffer, tris: &[[Vec4; 3]]) -> CommandResult {
    execute(depth, tris, &[cmd(CommandKind::Draw, 0..tris.len() as u32, false)])[0]
}

/// Two CCW triangles covering NDC `[-s, s]^2` at depth `z`.
fn quad(s: f32, z: f32) -> [[Vec4; 3]; 2] {
    let v = |x: f32, y: f32| Vec4::new(x, y, z, 1.0);
    [[v(-s, -s), v(s, -s), v(s, s)], [v(-s, -s), v(s, s), v(-s, s)]]
}

/// Number of pixel centres `p + 0.5` with `lo <= p + 0.5 < hi` (top-left rule for a
/// rectangle: left and top edges included).
fn centres_in(lo: f32, hi: f32) -> u64 {
    (0..10_000).filter(|&p| lo <= p as f32 + 0.5 && (p as f32 + 0.5) < hi).count() as u64
}

#[test]
fn screen_quad_covers_every_pixel_once() {
    // Sizes that are not tile multiples.
    let mut depth = DepthBuffer::new(200, 150);
    let r = draw_all(&mut depth, &quad(1.0, 0.5));
    assert_eq!(r.fragments, 200 * 150);
    assert_eq!(r.passed, 200 * 150);
    assert!(depth.to_vec().iter().all(|&d| d == 0.5));
}

#[test]
fn copy_to_replaces_what_the_buffer_held_with_the_rows() {
    // 130x70: tiles cut on both sides, so the tile layout differs from the rows.
    let mut depth = DepthBuffer::new(130, 70);
    for (x, y) in [(0, 0), (129, 0), (64, 1), (0, 69), (129, 69), (70, 64)] {
        depth.set(x, y, (x * 100 + y) as f32 * 1e-5);
    }
    let mut out = vec![7.0; 3];
    depth.copy_to(&mut out);
    assert_eq!(out.len(), 130 * 70);
    for (i, &d) in out.iter().enumerate() {
        let (x, y) = ((i % 130) as u32, (i / 130) as u32);
        assert_eq!(d.to_bits(), depth.get(x, y).to_bits(), "pixel {x},{y}");
    }
    // A second copy into the same, now full, buffer replaces it rather than appending.
    depth.set(5, 5, 0.25);
    depth.copy_to(&mut out);
    assert_eq!(out, depth.to_vec());
    assert_eq!(out[5 * 130 + 5], 0.25);
}

/// A jittered-grid triangulation of the screen rectangle `[x0, x1) x [y0, y1)`
/// (pixels), every triangle's winding randomly flipped when `flip` is set.
fn triangulated_rect(
    rect: [f32; 4],
    cells: usize,
    w: f32,
    flip: bool,
    rng: &mut Rng,
    size: (u32, u32),
) -> Vec<[Vec4; 3]> {
    let [x0, y0, x1, y1] = rect;
    let n = cells + 1;
    let mut pts = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let mut x = x0 + (x1 - x0) * i as f32 / cells as f32;
            let mut y = y0 + (y1 - y0) * j as f32 / cells as f32;
            if i > 0 && i < cells {
                x += rng.range(-0.3, 0.3) * (x1 - x0) / cells as f32;
            }
            if j > 0 && j < cells {
                y += rng.range(-0.3, 0.3) * (y1 - y0) / cells as f32;
            }
            let z = rng.range(0.1, 0.9);
            pts.push(at_pixel(x, y, z, w, size.0, size.1));
        }
    }
    let mut tris = Vec::new();
    for j in 0..cells {
        for i in 0..cells {
            let (a, b, c, d) = (j * n + i, j * n + i + 1, (j + 1) * n + i, (j + 1) * n + i + 1);
            // Screen y goes down, so (a, c, d) is counter-clockwise in NDC.
            let pick = if rng.next_u64() & 1 == 0 { [[a, c, d], [a, d, b]] } else { [[a, c, b], [b, c, d]] };
            for [p, q, r] in pick {
                if flip && rng.next_u64() & 1 == 0 {
                    tris.push([pts[p], pts[r], pts[q]]);
                } else {
                    tris.push([pts[p], pts[q], pts[r]]);
                }
            }
        }
    }
    tris
}

#[test]
fn triangulated_rectangle_covers_each_pixel_once() {
    let size = (256u32, 128u32);
    let mut rng = Rng::new(7, 0);
    let rects = [
        [10.0, 20.0, 200.0, 100.0],       // pixel-aligned corners
        [10.5, 20.5, 130.5, 90.5],        // edges through pixel centres
        [3.25, 7.75, 250.125, 127.5],     // fractional (dyadic) corners
        [-40.0, -30.0, 300.0, 200.0],     // beyond the viewport
        [100.375, 60.625, 101.0, 61.125], // smaller than a pixel
    ];
    for rect in rects {
        for (w, flip, cells) in [(1.0, false, 7), (2.0, true, 13), (0.5, true, 1)] {
            let tris = triangulated_rect(rect, cells, w, flip, &mut rng, size);
            let mut depth = DepthBuffer::new(size.0, size.1);
            let r = draw_all(&mut depth, &tris);
            let clamp = |v: f32, max: u32| v.clamp(0.0, max as f32);
            let expected = centres_in(clamp(rect[0], size.0), clamp(rect[2], size.0))
                * centres_in(clamp(rect[1], size.1), clamp(rect[3], size.1));
            assert_eq!(r.fragments, expected, "rect {rect:?} w {w}");
            assert_eq!(r.passed, expected, "rect {rect:?} w {w}");
            let written = depth.to_vec().iter().filter(|&&d| d < 1.0).count() as u64;
            assert_eq!(written, expected, "rect {rect:?} w {w}");
            for (i, &d) in depth.to_vec().iter().enumerate() {
                let (px, py) = ((i as u32 % size.0) as f32 + 0.5, (i as u32 / size.0) as f32 + 0.5);
                let inside = rect[0] <= px && px < rect[2] && rect[1] <= py && py < rect[3];
                assert_eq!(inside, d < 1.0, "pixel {px},{py} of rect {rect:?}");
            }
        }
    }
}

#[test]
fn huge_quad_is_clipped_to_the_guard_band_without_gaps() {
    let mut depth = DepthBuffer::new(300, 200);
    let r = draw_all(&mut depth, &quad(1.0e5, 0.25));
    assert_eq!(r.fragments, 300 * 200);
    assert!(depth.to_vec().iter().all(|&d| d == 0.25));
}

/// The 12 triangles of the axis-aligned cube `center +- 0.5`, each face
/// counter-clockwise seen from outside in a right-handed space.
fn cube(center: Vec3) -> Vec<[Vec3; 3]> {
    let mut tris = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let v = n.cross(u);
            let c = center + n * 0.5;
            let p = [c - u * 0.5 - v * 0.5, c + u * 0.5 - v * 0.5, c + u * 0.5 + v * 0.5];
            let q = c - u * 0.5 + v * 0.5;
            tris.push(p);
            tris.push([p[0], p[2], q]);
        }
    }
    for t in &tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        assert!(n.dot(t[0] - center) > 0.0, "outward CCW winding");
    }
    tris
}

#[test]
fn cube_covers_its_front_face() {
    // Orthographic, w = 1: x, y map directly to NDC and the camera looks down -z, so
    // NDC depth is 0.5 - z and the face at z = +0.5 is the front (depth 0).
    let to_clip = |p: Vec3| Vec4::new(p.x, p.y, 0.5 - p.z, 1.0);
    let tris: Vec<[Vec4; 3]> = cube(Vec3::new(0.25, -0.125, 0.0)).into_iter().map(|t| t.map(to_clip)).collect();
    // 128x128: NDC x in [-0.25, 0.75] -> pixels [48, 112), y in [-0.625, 0.375] ->
    // rows [40, 104): a 64x64 face.
    let mut depth = DepthBuffer::new(128, 128);
    let n = tris.len() as u32;
    let r = execute(
        &mut depth,
        &tris,
        &[
            cmd(CommandKind::Query(DepthTest::Less), 0..n, true),
            cmd(CommandKind::Query(DepthTest::Less), 0..n, false),
            cmd(CommandKind::Draw, 0..n, true),
        ],
    );
    assert_eq!(r[0], CommandResult { fragments: 4096, passed: 4096 });
    // Two-sided: the back face (depth 1.0) is covered too but fails LESS vs 1.0.
    assert_eq!(r[1], CommandResult { fragments: 8192, passed: 4096 });
    assert_eq!(r[2], CommandResult { fragments: 4096, passed: 4096 });
    for (i, &d) in depth.to_vec().iter().enumerate() {
        let (x, y) = (i % 128, i / 128);
        let inside = (48..112).contains(&x) && (40..104).contains(&y);
        assert_eq!(d, if inside { 0.0 } else { 1.0 }, "pixel {x},{y}");
    }
}

#[test]
fn near_plane_clips_affine_depth() {
    // w = 1 and z = x: the left half of the screen is behind the near plane.
    let v = |x: f32, y: f32| Vec4::new(x, y, x, 1.0);
    let tris = [[v(-1.0, -1.0), v(1.0, -1.0), v(1.0, 1.0)], [v(-1.0, -1.0), v(1.0, 1.0), v(-1.0, 1.0)]];
    let mut depth = DepthBuffer::new(64, 32);
    let r = draw_all(&mut depth, &tris);
    assert_eq!(r.fragments, 32 * 32);
    for (i, &d) in depth.to_vec().iter().enumerate() {
        let x = i % 64;
        if x < 32 {
            assert_eq!(d, 1.0);
        } else {
            let expected = (x as f32 + 0.5) / 32.0 - 1.0;
            assert!((d - expected).abs() < 1e-6, "pixel {x}: {d} vs {expected}");
        }
    }
}

#[test]
fn near_plane_clips_a_ground_triangle_reaching_behind_the_eye() {
    let (w, h) = (128u32, 96u32);
    let proj = Mat4::perspective_rh(90f32.to_radians(), w as f32 / h as f32, 0.1, 10_000.0);
    // Counter-clockwise seen from above.
    let tri = [
        Vec3::new(-1.0e4, -1.0, -1000.0),
        Vec3::new(0.0, -1.0, 1000.0), // behind the eye
        Vec3::new(1.0e4, -1.0, -1000.0),
    ]
    .map(|p| proj * p.extend(1.0));
    assert!(tri[1].w < 0.0);
    for cull_back in [false, true] {
        let mut depth = DepthBuffer::new(w, h);
        let r = execute(&mut depth, &[tri], &[cmd(CommandKind::Draw, 0..1, cull_back)])[0];
        // The floor seen from above is front-facing and fills exactly the rows below
        // the horizon; nothing wraps around above it.
        assert_eq!(r.fragments, u64::from(w * h / 2), "cull_back {cull_back}");
        assert_eq!(r.passed, r.fragments);
        for (i, &d) in depth.to_vec().iter().enumerate() {
            if i < (w * h / 2) as usize {
                assert_eq!(d, 1.0);
            } else {
                assert!((0.0..1.0).contains(&d), "depth {d}");
            }
        }
    }
    // Seen from below (winding reversed), it is back-facing.
    let mut depth = DepthBuffer::new(w, h);
    let reversed = [tri[0], tri[2], tri[1]];
    let r = execute(&mut depth, &[reversed], &[cmd(CommandKind::Draw, 0..1, true)]);
    assert_eq!(r[0].fragments, 0);
}

#[test]
fn near_clipped_mesh_is_watertight() {
    // A jittered grid on the ground plane y = -1, reaching behind the eye and far past
    // the guard band at the sides: its triangles share near- and guard-clipped edges.
    let (w, h) = (160u32, 120u32);
    let proj = Mat4::perspective_rh(90f32.to_radians(), w as f32 / h as f32, 0.1, 10_000.0);
    let mut rng = Rng::new(21, 0);
    let (nx, nz) = (41usize, 41usize);
    let mut pts = Vec::new();
    for j in 0..nz {
        for i in 0..nx {
            let mut x = -4000.0 + 8000.0 * i as f32 / (nx - 1) as f32;
            let mut z = 200.0 - 1400.0 * j as f32 / (nz - 1) as f32;
            if i > 0 && i < nx - 1 && j > 0 && j < nz - 1 {
                x += rng.range(-50.0, 50.0);
                z += rng.range(-10.0, 10.0);
            }
            pts.push(proj * Vec4::new(x, -1.0, z, 1.0));
        }
    }
    let mut tris = Vec::new();
    for j in 0..nz - 1 {
        for i in 0..nx - 1 {
            let (a, b, c, d) = (j * nx + i, j * nx + i + 1, (j + 1) * nx + i, (j + 1) * nx + i + 1);
            // Rows go away from the eye (-z): (a, b, d) is counter-clockwise from above.
            tris.push([pts[a], pts[b], pts[d]]);
            tris.push([pts[a], pts[d], pts[c]]);
        }
    }
    let mut depth = DepthBuffer::new(w, h);
    let n = tris.len() as u32;
    let r = execute(&mut depth, &tris, &[cmd(CommandKind::Draw, 0..n, true)])[0];
    assert_eq!(r.fragments, u64::from(w * h / 2));
    assert_eq!(r.passed, r.fragments);
    let written = depth.to_vec().iter().filter(|&&d| d < 1.0).count() as u64;
    assert_eq!(written, r.fragments);
}

#[test]
fn degenerate_and_non_finite_triangles_are_dropped() {
    let v = |x: f32, y: f32| Vec4::new(x, y, 0.5, 1.0);
    let tris = [
        [v(-1.0, -1.0), v(0.0, 0.0), v(1.0, 1.0)],   // collinear
        [v(-1.0, -1.0), v(-1.0, -1.0), v(1.0, 1.0)], // repeated vertex
        [v(f32::NAN, -1.0), v(1.0, -1.0), v(1.0, 1.0)],
        [v(-1.0, -1.0), v(f32::INFINITY, -1.0), v(1.0, 1.0)],
        [v(-1.0, -1.0), v(1.0, -1.0), Vec4::new(1.0, 1.0, f32::NEG_INFINITY, 1.0)],
        [Vec4::ZERO, Vec4::ZERO, Vec4::ZERO],
        [Vec4::new(0.0, 0.0, 0.5, 0.0), v(1.0, -1.0), v(1.0, 1.0)], // w = 0, z > 0
        [v(-0.5, -0.5), v(-0.5 + 1e-7, -0.5), v(-0.5, -0.5 + 1e-7)], // below a sub-pixel
    ];
    let mut depth = DepthBuffer::new(64, 64);
    for cull_back in [false, true] {
        let commands: Vec<Command> =
            (0..tris.len() as u32).map(|i| cmd(CommandKind::Draw, i..i + 1, cull_back)).collect();
        let r = execute(&mut depth, &tris, &commands);
        assert!(r.iter().all(|r| *r == CommandResult::default()), "{r:?}");
    }
    assert!(depth.to_vec().iter().all(|&d| d == 1.0));
}

#[test]
fn query_less_counts_unoccluded_fragments() {
    let (w, h) = (160u32, 100u32);
    // Occluder: the left 40% of the screen at depth 0.5.
    let o = |x: f32, y: f32| Vec4::new(x, y, 0.5, 1.0);
    let occluder = [[o(-1.0, -1.0), o(-0.2, -1.0), o(-0.2, 1.0)], [o(-1.0, -1.0), o(-0.2, 1.0), o(-1.0, 1.0)]];
    let mut tris = occluder.to_vec();
    tris.extend(quad(1.0, 0.7)); // behind the occluder
    tris.extend(quad(1.0, 0.3)); // in front of it
    let mut depth = DepthBuffer::new(w, h);
    let q = CommandKind::Query(DepthTest::Less);
    let r = execute(
        &mut depth,
        &tris,
        &[cmd(CommandKind::Draw, 0..2, false), cmd(q, 2..4, true), cmd(q, 4..6, true), cmd(q, 0..2, true)],
    );
    let all = u64::from(w * h);
    let left = u64::from(64 * h);
    assert_eq!(r[0], CommandResult { fragments: left, passed: left });
    assert_eq!(r[1], CommandResult { fragments: all, passed: all - left });
    assert_eq!(r[2], CommandResult { fragments: all, passed: all });
    assert_eq!(r[3], CommandResult { fragments: left, passed: 0 });
    // Queries do not write depth.
    let written = depth.to_vec().iter().filter(|&&d| d == 0.5).count() as u64;
    assert_eq!(written, left);
    assert_eq!(depth.to_vec().iter().filter(|&&d| d == 1.0).count() as u64, all - left);
}

/// A random scene of `n` triangles in clip space: on and off screen, crossing the
/// near plane, some behind the eye, some tiny.
fn random_scene(n: usize, seed: u64) -> Vec<[Vec4; 3]> {
    let mut rng = Rng::new(seed, 0);
    (0..n)
        .map(|i| {
            let w = rng.range(0.5, 4.0);
            let (cx, cy) = (rng.range(-1.3, 1.3), rng.range(-1.3, 1.3));
            let size = match i % 4 {
                0 => 0.01,
                1 => 0.1,
                2 => 0.5,
                _ => 3.0,
            };
            let mut vert = || {
                let w = if i % 17 == 0 { rng.range(-1.0, 1.0) } else { w * rng.range(0.8, 1.2) };
                Vec4::new(
                    (cx + rng.range(-size, size)) * w,
                    (cy + rng.range(-size, size)) * w,
                    rng.range(-0.1, 1.05) * w,
                    w,
                )
            };
            [vert(), vert(), vert()]
        })
        .collect()
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool").install(f)
}

#[test]
fn query_equal_passes_redrawn_geometry() {
    let tris = random_scene(300, 11);
    let (w, h) = (240u32, 180u32);
    let n = tris.len() as u32;
    // Redrawing a single triangle with EQUAL passes all of its fragments.
    for i in 0..n {
        let mut depth = DepthBuffer::new(w, h);
        let r = execute(
            &mut depth,
            &tris,
            &[cmd(CommandKind::Draw, i..i + 1, false), cmd(CommandKind::Query(DepthTest::Equal), i..i + 1, false)],
        );
        assert_eq!(r[1].fragments, r[0].fragments);
        assert_eq!(r[1].passed, r[0].passed, "triangle {i}");
    }
    // After the whole scene, every written pixel equals some triangle's depth.
    let mut depth = DepthBuffer::new(w, h);
    let mut commands = vec![cmd(CommandKind::Draw, 0..n, false)];
    commands.extend((0..n).map(|i| cmd(CommandKind::Query(DepthTest::Equal), i..i + 1, false)));
    let before = {
        let mut d = DepthBuffer::new(w, h);
        draw_all(&mut d, &tris);
        d
    };
    let r = execute(&mut depth, &tris, &commands);
    assert_eq!(depth, before, "queries do not write depth");
    let written = depth.to_vec().iter().filter(|&&d| d < 1.0).count() as u64;
    let equal: u64 = r[1..].iter().map(|r| r.passed).sum();
    assert!(written > 1000);
    assert!(equal >= written, "{equal} < {written}");
}

#[test]
fn thread_count_does_not_change_results() {
    let tris = random_scene(400, 3);
    let commands = mixed_commands(tris.len() as u32);
    let run = |threads| {
        in_pool(threads, || {
            let mut depth = DepthBuffer::new(333, 251);
            let r = Rasterizer::new().execute(&mut depth, &tris, &commands);
            (depth, r)
        })
    };
    let (d1, r1) = run(1);
    let (d2, r2) = run(2);
    let (d4, r4) = run(4);
    assert!(r1.iter().any(|r| r.passed > 0));
    assert_eq!(r1, r2);
    assert_eq!(r1, r4);
    assert_eq!(bits(&d1), bits(&d2));
    assert_eq!(bits(&d1), bits(&d4));
}

#[test]
fn draw_order_does_not_change_depth() {
    let tris = random_scene(400, 5);
    let mut rev = tris.clone();
    rev.reverse();
    let mut a = DepthBuffer::new(301, 207);
    let mut b = DepthBuffer::new(301, 207);
    let mut raster = Rasterizer::new();
    let ra = raster.execute(&mut a, &tris, &[cmd(CommandKind::Draw, 0..400, false)]);
    // One command per triangle, reversed, reusing the rasterizer's buffers.
    let commands: Vec<Command> = (0..400).map(|i| cmd(CommandKind::Draw, i..i + 1, false)).collect();
    let rb = raster.execute(&mut b, &rev, &commands);
    let frags: u64 = rb.iter().map(|r| r.fragments).sum();
    assert_eq!(ra[0].fragments, frags);
    assert_eq!(bits(&a), bits(&b));
}

/// The depth image's bits, to compare buffers exactly (NaN and signed zeros
/// included).
fn bits(d: &DepthBuffer) -> Vec<u32> {
    float_bits(&d.to_vec())
}

/// The bits of `values`.
fn float_bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|v| v.to_bits()).collect()
}

/// Runs `calls` (command lists, one `execute` each, on the same buffer) with
/// `raster` and with the reference, and checks that every result and the final depth
/// image agree bit for bit. Returns the results.
fn check_against_reference(
    raster: &mut Rasterizer,
    size: (u32, u32),
    tris: &[[Vec4; 3]],
    calls: &[Vec<Command>],
) -> Vec<CommandResult> {
    let mut depth = DepthBuffer::new(size.0, size.1);
    let mut expected = vec![1.0; size.0 as usize * size.1 as usize];
    let mut all = Vec::new();
    for commands in calls {
        let r = raster.execute(&mut depth, tris, commands);
        let e = reference::execute(&mut expected, size.0, size.1, tris, commands);
        assert_eq!(r, e, "results of {commands:?}");
        assert!(bits(&depth) == float_bits(&expected), "depth images differ after {commands:?}");
        all.extend(r);
    }
    all
}

/// Draws, then LESS, EQUAL and any-pass queries of every few triangles of `tris`,
/// then the rest of the draws: every kind of command against a partly drawn buffer.
fn mixed_commands(n: u32) -> Vec<Command> {
    let mut commands = vec![cmd(CommandKind::Draw, 0..n / 2, false)];
    for i in (0..n).step_by(7) {
        let end = (i + 7).min(n);
        commands.push(cmd(CommandKind::Query(DepthTest::Less), i..end, true));
        commands.push(cmd(CommandKind::Query(DepthTest::Equal), i..end, false));
        commands.push(cmd(CommandKind::QueryAny(DepthTest::Less), i..end, false));
        commands.push(cmd(CommandKind::QueryAny(DepthTest::Equal), i..end, true));
    }
    commands.push(cmd(CommandKind::Draw, n / 2..n, true));
    commands
}

/// Commands whose triangles were set up beforehand ([`Rasterizer::prepare`],
/// every other command, by another rasterizer) give the results and image of
/// setting them up in the call, with either kernel, in one call or several.
#[test]
fn prepared_commands_give_the_results_of_commands_set_up_in_the_call() {
    let tris = random_scene(400, 13);
    let commands = mixed_commands(tris.len() as u32);
    let size = (333, 251);
    for raster in [Rasterizer::new, Rasterizer::scalar] {
        let mut expected_depth = DepthBuffer::new(size.0, size.1);
        let expected = raster().execute(&mut expected_depth, &tris, &commands);
        let preparer = raster();
        let prepared: Vec<Option<Prepared>> = commands
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let range = c.triangles.start as usize..c.triangles.end as usize;
                (i % 2 == 0).then(|| preparer.prepare(size.0, size.1, &tris[range], c.cull_back))
            })
            .collect();
        assert!(prepared.iter().flatten().any(|p| !p.is_empty()) && prepared.iter().flatten().any(Prepared::is_empty));
        // The prepared commands' own ranges are not read: empty them.
        let emptied: Vec<Command> = commands
            .iter()
            .zip(&prepared)
            .map(|(c, p)| if p.is_some() { cmd(c.kind, 0..0, c.cull_back) } else { c.clone() })
            .collect();
        let refs: Vec<Option<&Prepared>> = prepared.iter().map(Option::as_ref).collect();
        for split in [emptied.len(), 5] {
            let mut depth = DepthBuffer::new(size.0, size.1);
            let mut rasterizer = raster();
            let mut results = Vec::new();
            for (commands, prepared) in emptied.chunks(split).zip(refs.chunks(split)) {
                results.extend(rasterizer.execute_prepared(&mut depth, &tris, commands, prepared));
            }
            assert_eq!(results, expected, "in calls of {split} commands");
            assert_eq!(bits(&depth), bits(&expected_depth), "in calls of {split} commands");
        }
    }
}

#[test]
fn simd_and_scalar_match_the_per_pixel_reference() {
    // Odd sizes, several tiles, a few execute calls on the same buffer so that the
    // hierarchical depth of one call serves the next.
    let tris = random_scene(300, 9);
    let n = tris.len() as u32;
    let calls = vec![mixed_commands(n), mixed_commands(n), vec![cmd(CommandKind::Query(DepthTest::Less), 0..n, true)]];
    for size in [(190, 140), (333, 251), (64, 64), (65, 1)] {
        let simd = check_against_reference(&mut Rasterizer::new(), size, &tris, &calls);
        let scalar = check_against_reference(&mut Rasterizer::scalar(), size, &tris, &calls);
        assert_eq!(simd, scalar);
        if size.0 > 100 {
            assert!(simd[0].fragments > 10_000);
            assert!(simd.iter().any(|r| r.passed == 0) && simd.iter().any(|r| r.passed > 1));
        }
    }
}

/// Small triangles behind what an earlier call drew are counted as they are
/// binned (`hidden`), with the results and image of rasterizing them, on both
/// kernels and with every kind of command.
#[test]
fn small_hidden_triangles_counted_at_binning_match_the_reference() {
    // The first call draws an occluder over the left half at depth 0.3; the
    // second draws and queries random triangles, tiny to large, in front of it
    // and behind, and small ones behind it whose edges run through pixel centres
    // (where the fill rule decides).
    let v = |x: f32, y: f32| Vec4::new(x, y, 0.3, 1.0);
    for mut raster in [Rasterizer::new(), Rasterizer::scalar()] {
        for (w, h) in [(190, 140), (333, 251)] {
            let mut tris = vec![[v(-1.0, -1.0), v(0.0, -1.0), v(0.0, 1.0)], [v(-1.0, -1.0), v(0.0, 1.0), v(-1.0, 1.0)]];
            tris.extend(random_scene(600, 21));
            for k in 0..40 {
                let (x, y) = ((k % 8 * 9) as f32 + 3.5, (k / 8 * 11) as f32 + 5.5);
                let p = |dx: f32, dy: f32| at_pixel(x + dx, y + dy, 0.6, 1.5, w, h);
                let (a, b, c) = (p(0.0, 0.0), p(3.0 + (k % 3) as f32, 0.0), p(0.0, 3.0 + (k % 4) as f32));
                tris.push(if k % 2 == 0 { [a, c, b] } else { [a, b, c] });
            }
            let calls = vec![vec![cmd(CommandKind::Draw, 0..2, false)], mixed_commands(tris.len() as u32)];
            let size = (w, h);
            check_against_reference(&mut raster, size, &tris, &calls);
            let counted: u64 = raster.chunks.iter().flat_map(Chunk::hidden).map(|&(_, f)| f).sum();
            assert!(counted > 100, "{counted} fragments counted at binning at {size:?}");
        }
    }
}

/// A new rasterizer of `raster` that has run the call `first` and then
/// `commands` (with their `prepared` set-ups; empty for none) on a `w` x `h`
/// buffer; with the second call's results and the image.
fn after_first_call(
    raster: fn() -> Rasterizer,
    (w, h): (u32, u32),
    tris: &[[Vec4; 3]],
    first: &[Command],
    commands: &[Command],
    prepared: &[Option<&Prepared>],
) -> (Rasterizer, Vec<CommandResult>, DepthBuffer) {
    let mut depth = DepthBuffer::new(w, h);
    let mut rasterizer = raster();
    rasterizer.execute(&mut depth, tris, first);
    let results = rasterizer.execute_prepared(&mut depth, tris, commands, prepared);
    (rasterizer, results, depth)
}

/// A prepared command whose triangles are all behind what an earlier call drew
/// is counted whole (`hidden::Extent`), with the results and image of
/// rasterizing it, on both kernels and with every kind of command; clusters in
/// front of the occluder or reaching past it are rasterized.
#[test]
fn prepared_commands_hidden_whole_match_the_commands_set_up_in_the_call() {
    let v = |x: f32, y: f32| Vec4::new(x, y, 0.3, 1.0);
    let occluder = [[v(-1.0, -1.0), v(0.0, -1.0), v(0.0, 1.0)], [v(-1.0, -1.0), v(0.0, 1.0), v(-1.0, 1.0)]];
    for (w, h) in [(190, 140), (333, 251)] {
        // Clusters of triangles from under a pixel to 80 pixels across (so that
        // every way of counting a triangle's pixels is used), behind the
        // occluder, behind it but for one triangle, or straddling its edge.
        let mut tris = occluder.to_vec();
        let mut clusters = Vec::new();
        let mut rng = Rng::new(5, 0);
        for k in 0..24 {
            let (cx, z) = match k % 3 {
                0 => (0.35 * w as f32 * rng.range(0.2, 1.0), 0.6),
                1 => (0.35 * w as f32 * rng.range(0.2, 1.0), 0.1),
                _ => (0.5 * w as f32, 0.6),
            };
            let cy = h as f32 * rng.range(0.2, 0.8);
            let size = [0.7f32, 3.0, 12.0, 80.0][k % 4].min(cx - 1.0);
            let start = tris.len() as u32;
            for j in 0..12 {
                // The clusters in front have one triangle in front, the others behind.
                let z = if k % 3 == 1 && j != 7 { 0.6 } else { z };
                let mut p = || {
                    let (x, y) = (cx + rng.range(-size, size) / 2.0, cy + rng.range(-size, size) / 2.0);
                    at_pixel(x, y, z * rng.range(0.95, 1.05), rng.range(0.5, 2.0), w, h)
                };
                tris.push([p(), p(), p()]);
            }
            clusters.push(start..tris.len() as u32);
        }
        let mut commands = Vec::new();
        for c in &clusters {
            commands.push(cmd(CommandKind::Query(DepthTest::Less), c.clone(), false));
            commands.push(cmd(CommandKind::Query(DepthTest::Equal), c.clone(), false));
            commands.push(cmd(CommandKind::QueryAny(DepthTest::Less), c.clone(), false));
            commands.push(cmd(CommandKind::Draw, c.clone(), false));
        }
        let first = [cmd(CommandKind::Draw, 0..2, false)];
        for raster in [Rasterizer::new, Rasterizer::scalar] {
            let (_, expected, expected_depth) = after_first_call(raster, (w, h), &tris, &first, &commands, &[]);
            let prepared: Vec<Prepared> = commands
                .iter()
                .map(|c| raster().prepare(w, h, &tris[c.triangles.start as usize..c.triangles.end as usize], false))
                .collect();
            let refs: Vec<Option<&Prepared>> = prepared.iter().map(Some).collect();
            let emptied: Vec<Command> = commands.iter().map(|c| cmd(c.kind, 0..0, false)).collect();
            let (rasterizer, results, depth) = after_first_call(raster, (w, h), &tris, &first, &emptied, &refs);
            assert_eq!(results, expected, "at {w}x{h}");
            assert_eq!(bits(&depth), bits(&expected_depth), "at {w}x{h}");
            let whole = rasterizer.hidden_whole.iter().filter(|&&h| h).count();
            assert!(whole >= 16 && whole < commands.len(), "{whole} of {} commands hidden whole", commands.len());
            assert!(results.iter().zip(&rasterizer.hidden_whole).any(|(r, &h)| h && r.fragments > 1000));
        }
    }
}

/// A prepared command partly in front of what an earlier call drew has its
/// runs of [`GROUP`] triangles behind it counted whole (`Group`), with the
/// results and image of setting it up in the call, on both kernels, where the
/// set-up chunks split its groups.
#[test]
fn prepared_groups_hidden_whole_match_the_commands_set_up_in_the_call() {
    let v = |x: f32, y: f32| Vec4::new(x, y, 0.3, 1.0);
    let (w, h) = (333, 251);
    let mut tris = vec![[v(-1.0, -1.0), v(0.0, -1.0), v(0.0, 1.0)], [v(-1.0, -1.0), v(0.0, 1.0), v(-1.0, 1.0)]];
    // A command of 100 triangles anywhere, so that the chunks' bounds (every
    // `MIN_SETUP_CHUNK` triangles) fall inside the next command's groups.
    tris.extend(random_scene(100, 3));
    let first = tris.len() as u32;
    // Then runs of 128 triangles (many groups) 2 to 12 pixels across: behind
    // the occluder, beside it, or in front of it.
    let mut rng = Rng::new(8, 0);
    for k in 0..12 {
        let (cx, z) = match k % 3 {
            0 => (0.4 * w as f32 * rng.range(0.2, 1.0), 0.6),
            1 => (w as f32 * rng.range(0.6, 0.9), 0.6),
            _ => (0.4 * w as f32 * rng.range(0.2, 1.0), 0.1),
        };
        let cy = h as f32 * rng.range(0.2, 0.8);
        for j in 0..128 {
            let size = [2.0f32, 4.0, 12.0][j % 3];
            let mut p = || {
                let (x, y) = (cx + rng.range(-size, size) / 2.0, cy + rng.range(-size, size) / 2.0);
                at_pixel(x, y, z * rng.range(0.95, 1.05), rng.range(0.5, 2.0), w, h)
            };
            tris.push([p(), p(), p()]);
        }
    }
    let n = tris.len() as u32;
    let commands = [cmd(CommandKind::Draw, 2..first, false), cmd(CommandKind::Query(DepthTest::Less), first..n, false)];
    let occluder = [cmd(CommandKind::Draw, 0..2, false)];
    for raster in [Rasterizer::new, Rasterizer::scalar] {
        let (_, expected, expected_depth) = after_first_call(raster, (w, h), &tris, &occluder, &commands, &[]);
        let prepared = raster().prepare(w, h, &tris[first as usize..], false);
        let emptied = [commands[0].clone(), cmd(commands[1].kind, 0..0, false)];
        let refs = [None, Some(&prepared)];
        let (rasterizer, results, depth) = after_first_call(raster, (w, h), &tris, &occluder, &emptied, &refs);
        assert_eq!(results, expected);
        assert_eq!(bits(&depth), bits(&expected_depth));
        assert!(!rasterizer.hidden_whole[1] && rasterizer.chunks.len() > 2, "{} chunks", rasterizer.chunks.len());
        // A group is counted only where it was hidden whole.
        let counted = prepared.groups.iter().filter(|g| g.covered.get().is_some()).count();
        assert!(counted >= 2 && counted < prepared.groups.len() - 4, "{counted} of {} groups", prepared.groups.len());
    }
}

#[test]
fn hidden_and_visible_queries_after_external_writes_and_clears() {
    // A full occluder at 0.5, then queries behind it (hidden: the hierarchical depth
    // rejects them) and in front of it; then writes from outside and a clear, after
    // which a stale hierarchical depth would hide pixels that are visible.
    let (w, h) = (150u32, 90u32);
    let all = u64::from(w * h);
    let mut tris = quad(1.0, 0.5).to_vec();
    tris.extend(quad(1.0, 0.7));
    tris.extend(quad(1.0, 0.3));
    let q = |kind, range| cmd(kind, range, true);
    let (less, any) = (CommandKind::Query(DepthTest::Less), CommandKind::QueryAny(DepthTest::Less));
    for mut raster in [Rasterizer::new(), Rasterizer::scalar()] {
        let mut depth = DepthBuffer::new(w, h);
        raster.execute(&mut depth, &tris, &[cmd(CommandKind::Draw, 0..2, false)]);
        for _ in 0..2 {
            let r = raster.execute(&mut depth, &tris, &[q(less, 2..4), q(less, 4..6), q(any, 2..4), q(any, 4..6)]);
            assert_eq!(r[0], CommandResult { fragments: all, passed: 0 });
            assert_eq!(r[1], CommandResult { fragments: all, passed: all });
            assert_eq!(r[2], CommandResult { fragments: 0, passed: 0 });
            assert_eq!(r[3], CommandResult { fragments: 0, passed: 1 });
        }
        depth.set(120, 70, 0.9);
        let r = raster.execute(&mut depth, &tris, &[q(less, 2..4), q(any, 2..4)]);
        assert_eq!(r[0].passed, 1);
        assert_eq!(r[1].passed, 1);
        depth.clear();
        let r = raster.execute(&mut depth, &tris, &[q(less, 2..4), cmd(CommandKind::Draw, 0..2, false)]);
        assert_eq!(r[0].passed, all);
        assert_eq!(r[1].passed, all);
    }
}

/// Rasterizes `t` with operation `OP` over the whole of `rows` (a tile at the
/// origin), with the AVX2 window rasterizer and with the span walk, and checks that
/// they agree bit for bit; returns how many pixels changed.
#[cfg(target_arch = "x86_64")]
fn check_window_rasterizers<const OP: u8>(
    avx2: avx2::Avx2,
    t: &span::RasterTri,
    rows: &[Vec<f32>],
    rejected: u64,
) -> usize {
    let window = [0, rows[0].len() as i32 - 1, 0, rows.len() as i32 - 1];
    let (width, height) = (rows[0].len(), rows.len());
    let run = |simd: bool| {
        let mut data: Vec<f32> = rows.concat();
        let mut hiz = hiz::TileHiZ::cleared();
        let rows = split::TileRows::new(&mut data, width, height, width);
        let mut tile = split::TileView { x0: 0, y0: 0, rows, hiz: &mut hiz };
        let r = if simd {
            avx2.window::<OP>(&mut tile, t, window, rejected, false)
        } else {
            tile::raster_spans::<OP>(&mut tile, t, window, rejected, false)
        };
        (r, data)
    };
    let ((ra, a), (rb, b)) = (run(true), run(false));
    assert_eq!(ra, rb, "{t:?}");
    let bits = |data: &[f32]| data.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b), "{t:?}");
    bits(&a).iter().zip(bits(&rows.concat())).filter(|(x, y)| *x != y).count()
}

/// [`check_window_rasterizers`] for a draw and both queries; returns how many
/// pixels the draw changed.
#[cfg(target_arch = "x86_64")]
fn check_window_operations(avx2: avx2::Avx2, t: &span::RasterTri, rows: &[Vec<f32>], rejected: u64) -> usize {
    check_window_rasterizers::<{ shade::LESS }>(avx2, t, rows, rejected);
    check_window_rasterizers::<{ shade::EQUAL }>(avx2, t, rows, rejected);
    check_window_rasterizers::<{ shade::DRAW }>(avx2, t, rows, rejected)
}

#[test]
#[cfg(target_arch = "x86_64")]
fn window_rasterizers_agree_on_special_values() {
    // Signed zeros, infinities, NaN, subnormals in the plane and in the buffer: the
    // AVX2 rasterizer must round, clamp and compare exactly as the scalar one, in
    // whole groups and in a group cut by the end of the row.
    let Some(avx2) = avx2::Avx2::detect() else {
        eprintln!("no AVX2 on this CPU: nothing to compare");
        return;
    };
    let specials = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        0.5,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::MAX,
        -f32::MAX,
        1e-40,
        -1e-40,
        f32::MIN_POSITIVE,
    ];
    // 21 pixels wide: two whole groups and a cut one; 16 wide: two whole groups
    // (the unrolled loop of windows without a cut group). A triangle covering it
    // all, and one covering all but a corner (one edge crosses the window).
    for (w, corner) in [(21u32, 3.0), (21, 1.8), (16, 3.0), (16, 1.8)] {
        let h = 3u32;
        let v = |x: f32, y: f32| Vec4::new(x, y, 0.5, 1.0);
        let mut setups = Vec::new();
        let big = [v(-1.0, -1.0), v(corner, -1.0), v(-1.0, corner)];
        setup::setup_triangle(&big, false, 0, setup::Viewport::new(w, h), &mut clip::Polygon::new(), |t| {
            setups.push(t)
        });
        let base = span::RasterTri::new(&setups[0]).expect("covers rows");
        let rows: Vec<Vec<f32>> =
            (0..h as usize).map(|y| (0..w as usize).map(|x| specials[(x + 5 * y) % 13]).collect()).collect();
        let mut writes = 0;
        for &z_origin in &specials {
            for &z_dx in &specials {
                for z_dy in [0.0, -0.0, 1.0, f32::NAN, f32::INFINITY] {
                    let mut t = base;
                    (t.z_origin, t.z_dx, t.z_dy) = (z_origin, z_dx, z_dy);
                    for rejected in [0, 0b010, 0b101] {
                        writes += check_window_operations(avx2, &t, &rows, rejected);
                    }
                }
            }
        }
        assert!(writes > 1000, "the special values must exercise the writes ({w} wide): {writes}");
    }
}

#[test]
#[cfg(target_arch = "x86_64")]
fn window_rasterizers_agree_for_every_number_of_crossing_edges() {
    // The AVX2 rasterizer has one loop per number of edges crossing the window (none,
    // one, two, three), with and without rejected blocks: each must match the span
    // walker bit for bit, in whole groups and in the group cut by the end of the row
    // (61 columns: seven whole groups and five pixels), and in windows of one to
    // eight whole groups without rejected blocks (the unrolled loops).
    let Some(avx2) = avx2::Avx2::detect() else {
        eprintln!("no AVX2 on this CPU: nothing to compare");
        return;
    };
    for w in [61, 8, 16, 24, 32, 40, 48, 56, 64] {
        check_windows_crossed_by_every_number_of_edges(avx2, w);
    }
}

/// [`window_rasterizers_agree_for_every_number_of_crossing_edges`] in a tile `w`
/// pixels wide.
#[cfg(target_arch = "x86_64")]
fn check_windows_crossed_by_every_number_of_edges(avx2: avx2::Avx2, w: u32) {
    let h = 64u32;
    let v = |x: f32, y: f32, z: f32| Vec4::new(x, y, z, 1.0);
    let triangles = [
        // Covers the whole window.
        [v(-9.0, -9.0, 0.2), v(30.0, -9.0, 0.5), v(-9.0, 30.0, 0.8)],
        // One edge, the diagonal, crosses the window.
        [v(-5.0, -5.0, 0.2), v(5.0, -5.0, 0.5), v(-5.0, 5.0, 0.8)],
        // Two edges meet inside it.
        [v(0.1, -0.1, 0.3), v(5.0, 5.0, 0.6), v(-5.0, 5.0, 0.9)],
        // All three edges inside it.
        [v(-0.5, -0.5, 0.3), v(0.6, -0.4, 0.6), v(0.1, 0.7, 0.9)],
    ];
    let rows: Vec<Vec<f32>> =
        (0..h as usize).map(|y| (0..w as usize).map(|x| ((x * 7 + y * 13) % 10) as f32 / 10.0).collect()).collect();
    let mut writes = Vec::new();
    for tri in &triangles {
        let mut setups = Vec::new();
        setup::setup_triangle(tri, false, 0, setup::Viewport::new(w, h), &mut clip::Polygon::new(), |t| setups.push(t));
        let t = span::RasterTri::new(&setups[0]).expect("covers rows");
        let mut changed = 0;
        for rejected in [0, 0x0F0F_0000_00FF_0012, !0 >> 1] {
            changed += check_window_operations(avx2, &t, &rows, rejected);
        }
        writes.push(changed);
    }
    assert!(writes.iter().all(|&n| n > 0), "every triangle must write pixels: {writes:?}");
}

#[test]
fn empty_inputs() {
    let mut depth = DepthBuffer::new(0, 10);
    let tris = quad(1.0, 0.5);
    assert_eq!(execute(&mut depth, &tris, &[cmd(CommandKind::Draw, 0..2, false)]), vec![CommandResult::default()]);
    let mut depth = DepthBuffer::new(10, 10);
    assert!(execute(&mut depth, &tris, &[]).is_empty());
    let r = execute(&mut depth, &tris, &[cmd(CommandKind::Draw, 1..1, false)]);
    assert_eq!(r, vec![CommandResult::default()]);
    depth.set(3, 0, 0.0);
    depth.clear();
    assert!(depth.to_vec().iter().all(|&d| d == 1.0));
}
